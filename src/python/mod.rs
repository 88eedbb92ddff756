//! The Python extension module `implicit_psdr._native` (feature `python`; built by maturin, see
//! `pyproject.toml`), re-exported by the pure-Python package `implicit_psdr` (`python/`).
//!
//! Every function here makes the calls the command-line tool makes, with its defaults: the scene's
//! `spp`, seed 0, the differentiable pixel normalisation and the default boundary budgets. Arrays are
//! numpy `float32`: images `H × W × 3` (row 0 the top row), grids `[nz, ny, nx]`. The GIL is released
//! while rendering. Library errors become `SceneError` (a `ValueError`) with the library's one-line
//! message; malformed arguments (shapes, dtypes, non-finite values) become `ValueError`; a panic (a
//! bug) becomes `RuntimeError` rather than crossing into Python.

mod args;
mod arrays;
mod cli;
mod grad;
mod mesh;
mod optimize;
mod render;
mod scene;
mod tools;

use crate::integrator::RenderStats;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyRuntimeWarning, PyValueError};
use pyo3::prelude::*;

// Named after the package that re-exports it, so that its repr and tracebacks read
// `implicit_psdr.SceneError`.
create_exception!(
    implicit_psdr,
    SceneError,
    PyValueError,
    "An invalid scene, parameter, grid or request, with the library's one-line message naming the \
     field (`shapes[0].sdf.radius: must be > 0, got -1`)."
);

/// The Python exception for a library error: its one-line message, whose fields are the keyword
/// arguments of the same names (`params`, `grids`, `grid_directions`, `target`), and where to find the
/// parameter names when one is unknown.
pub(crate) fn scene_error(e: crate::Error) -> PyErr {
    match e {
        crate::Error::Field { field, message }
            if field == "params" && message.starts_with("no parameter") =>
        {
            SceneError::new_err(format!("{field}: {message} (Scene.params() lists them)"))
        }
        e => SceneError::new_err(e.to_string()),
    }
}

/// Runs `work` without the GIL, on at most `threads` threads (all of rayon's global pool when
/// `None`), catching a panic so that it reaches Python as a `RuntimeError`. Results do not depend on
/// the thread count (the driver merges work in a fixed order); capping it lets several renders share
/// the cores (one per Ray task).
pub(crate) fn run_detached<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let pool = match threads {
        None => None,
        Some(0) => return Err(PyValueError::new_err("threads: must be >= 1, got 0")),
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("threads: {e}")))?,
        ),
    };
    let outcome = py.detach(move || {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || match pool {
            Some(pool) => pool.install(work),
            None => work(),
        }))
    });
    outcome.map_err(|panic| {
        let message = (panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic".to_string());
        PyRuntimeError::new_err(format!("internal error (please report): {message}"))
    })
}

/// Issues what went wrong during a render (rays out of steps, non-finite samples) as Python
/// warnings, the lines the command-line tool prints.
pub(crate) fn warn(py: Python<'_>, stats: &RenderStats) -> PyResult<()> {
    warn_lines(py, stats.warnings())
}

/// Issues each line as a Python `RuntimeWarning`.
pub(crate) fn warn_lines(py: Python<'_>, lines: Vec<String>) -> PyResult<()> {
    for line in lines {
        let message = std::ffi::CString::new(line.replace('\0', " "))
            .expect("no interior NUL after replacing them");
        PyErr::warn(py, &py.get_type::<PyRuntimeWarning>(), &message, 1)?;
    }
    Ok(())
}

/// The extension module: the `Scene` class, `render`, `diff`, `fd`, `grad`, `bake`, `optimize`,
/// `read_exr`, `write_exr`, `extract_mesh`, `mesh_to_grid`, and `cli` (the command-line tool).
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_class::<scene::PyScene>()?;
    m.add_function(wrap_pyfunction!(scene::scene_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::diff, m)?)?;
    m.add_function(wrap_pyfunction!(grad::grad, m)?)?;
    m.add_function(wrap_pyfunction!(optimize::optimize, m)?)?;
    m.add_function(wrap_pyfunction!(arrays::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(arrays::write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(tools::fd, m)?)?;
    m.add_function(wrap_pyfunction!(tools::bake, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::extract_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::mesh_to_grid, m)?)?;
    m.add_function(wrap_pyfunction!(cli::cli, m)?)?;
    m.add("DEFAULT_SEED", 0u64)?;
    Ok(())
}
