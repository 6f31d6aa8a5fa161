//! The extension module `eopnp._eopnp` of the `eopnp` Python package (PyO3, abi3): the Rust
//! crate's solver, cameras, RANSAC and COLMAP reader for numpy arrays, and the package's
//! exceptions (`errors`). `eopnp/__init__.py` re-exports it; `eopnp/__init__.pyi` has the
//! types, its docstrings generated from the ones here (`python/gen_stub_docs.py`).
//!
//! Every function that solves takes `options=` (an `eopnp.SolverOptions`) or the same options
//! as keyword arguments; `options::solver_arg` turns either into the `eopnp::Solver`.
//!
//! Every entry point converts its arrays to `f64` points (copies, made with the GIL held:
//! another Python thread may modify the arrays while the GIL is released), runs the library
//! with the GIL released, and maps each error to the exception class of its `PnpError`
//! family.
//!
//! `solve_batch`, `solve_ransac_batch` and `solve_batch_arrays` (`batch`) copy every problem
//! first, then solve one problem per rayon task (feature `rayon`) with the GIL released for the
//! whole batch; `solve_batch_arrays` writes the poses into stacked arrays from the tasks.

use pyo3::prelude::*;

mod batch;
mod camera;
mod colmap;
mod convert;
mod errors;
mod frames;
mod gravity;
mod model_rigs;
mod options;
mod pose;
mod ransac;
mod rig;
mod solution;
mod solve;

#[pymodule]
fn _eopnp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::add_to_module(m)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve_all, m)?)?;
    m.add_function(wrap_pyfunction!(solve::refine, m)?)?;
    m.add_function(wrap_pyfunction!(solve::_time_solve, m)?)?;
    m.add_function(wrap_pyfunction!(ransac::solve_ransac, m)?)?;
    m.add_function(wrap_pyfunction!(batch::solve_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::solve_ransac_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::solve_batch_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(batch::problem_seed, m)?)?;
    m.add_function(wrap_pyfunction!(rig::solve_generalized, m)?)?;
    m.add_function(wrap_pyfunction!(rig::solve_generalized_ransac, m)?)?;
    m.add_function(wrap_pyfunction!(rig::refine_generalized, m)?)?;
    m.add_function(wrap_pyfunction!(batch::solve_generalized_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::solve_generalized_ransac_batch, m)?)?;
    m.add_function(wrap_pyfunction!(rig::_rig_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::read_colmap_model, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::register_image, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::register_images, m)?)?;
    m.add_function(wrap_pyfunction!(frames::register_frame, m)?)?;
    m.add_function(wrap_pyfunction!(frames::register_frames, m)?)?;
    m.add_function(wrap_pyfunction!(frames::_frame_registration_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(colmap::_registration_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(solution::_solution_from_state, m)?)?;
    m.add_class::<solution::PySolution>()?;
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<gravity::PyGravity>()?;
    m.add_class::<rig::PyRig>()?;
    m.add_class::<ransac::PyRansacOptions>()?;
    m.add_class::<options::PySolverOptions>()?;
    m.add_class::<colmap::PyModel>()?;
    m.add_class::<colmap::PyImage>()?;
    m.add_class::<colmap::PyRegistration>()?;
    m.add_class::<model_rigs::PyFrame>()?;
    m.add_class::<model_rigs::PySensorRig>()?;
    m.add_class::<frames::PyFrameRegistration>()?;
    Ok(())
}
