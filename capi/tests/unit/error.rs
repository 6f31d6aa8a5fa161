//! The guard of every exported function: a panic inside it becomes `EOPNP_PANIC` with its
//! message as the thread's last error, and does not cross the boundary.

use super::*;
use std::ffi::CStr;

fn message() -> String {
    // SAFETY: `last_message` is a NUL-terminated string owned by this thread's slot.
    unsafe { CStr::from_ptr(last_message()) }
        .to_str()
        .unwrap()
        .to_owned()
}

#[test]
fn a_panic_is_caught_and_reported() {
    let status = guard(|| panic!("boom {}", 42));
    assert_eq!(status, EopnpStatus::EOPNP_PANIC);
    assert_eq!(last_info().status, EopnpStatus::EOPNP_PANIC);
    assert!(message().contains("boom 42"), "{}", message());
    // A `&'static str` payload too.
    assert_eq!(guard(|| panic!("static")), EopnpStatus::EOPNP_PANIC);
    assert!(message().ends_with("static"), "{}", message());
}

#[test]
fn a_message_with_a_nul_is_cut_there() {
    let status = guard(|| Err(Failure::invalid("before\0after")));
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_ARGUMENT);
    assert_eq!(message(), "before");
}

#[test]
fn success_keeps_the_last_failure() {
    assert_eq!(
        guard(|| Err(Failure::null("x"))),
        EopnpStatus::EOPNP_NULL_POINTER
    );
    assert_eq!(guard(|| Ok(())), EopnpStatus::EOPNP_OK);
    assert_eq!(message(), "`x` is NULL");
}
