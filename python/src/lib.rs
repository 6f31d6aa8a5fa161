//! The extension module `eopnp._eopnp` of the `eopnp` Python package (PyO3, abi3): the Rust
//! crate's solver, cameras, RANSAC and COLMAP reader for numpy arrays. `eopnp/__init__.py`
//! re-exports it with the exceptions of `eopnp/_errors.py`; `eopnp/__init__.pyi` has the
//! types and the documentation.
//!
//! Every entry point converts its arrays to `f64` points (copies: the arrays may be mutated
//! while the GIL is released), runs the library with the GIL released, and maps each error
//! to the exception class of its `PnpError` family.
//!
//! Room for what issue 16 adds later: a `solve_batch` is one more function over lists of the
//! same inputs (`convert`), one `detach` around the crate's batch call, returning
//! `Solution`s (plain data, picklable, so they cross process boundaries); a `covariance=`
//! keyword is one more field of `options::SolverOptions` and an optional field of
//! `solution::PySolution` (None when not asked for).

use pyo3::prelude::*;

mod camera;
mod colmap;
mod convert;
mod errors;
mod options;
mod ransac;
mod solution;
mod solve;

#[pymodule]
fn _eopnp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve_all, m)?)?;
    m.add_function(wrap_pyfunction!(solve::_time_solve, m)?)?;
    m.add_function(wrap_pyfunction!(ransac::solve_ransac, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::read_colmap_model, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::register_image, m)?)?;
    m.add_function(wrap_pyfunction!(solution::_solution_from_state, m)?)?;
    m.add_class::<solution::PySolution>()?;
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<ransac::PyRansacOptions>()?;
    m.add_class::<colmap::PyModel>()?;
    m.add_class::<colmap::PyImage>()?;
    m.add_class::<colmap::PyRegistration>()?;
    Ok(())
}
