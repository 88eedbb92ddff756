//! The command-line tool from Python: the package's `implicit-psdr` console script
//! (`implicit_psdr.cli:main`) runs the same code as the Rust binary ([`crate::cli::main`]).

use pyo3::prelude::*;

/// Runs the command line `argv` (the program's name first) as the `implicit-psdr` tool does and
/// returns its exit code; prints to the process's stdout and stderr. The GIL is released meanwhile.
#[pyfunction]
pub(crate) fn cli(py: Python<'_>, argv: Vec<String>) -> u8 {
    py.detach(move || crate::cli::main(argv))
}
