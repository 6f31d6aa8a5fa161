//! The tests of the public root finders are integration tests: `tests/roots.rs`.
