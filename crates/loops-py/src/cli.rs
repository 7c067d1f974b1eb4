//! `run_cli`: the `loops` command in the Python process, behind the wheel's `loops` console
//! script (`inexact_loops/_cli.py`). The command is `loops_cli::main`, the binary's own code.

use std::ffi::OsString;

use pyo3::prelude::*;

/// Exit code of a panic, as the Rust runtime gives the binary.
const PANIC_EXIT_CODE: u8 = 101;

/// Runs the ``loops`` command in this process with ``args`` (the arguments after the program
/// name) and returns its exit code; the wheel's ``loops`` console script is this call.
///
/// The command is the one ``cargo install --path crates/loops-cli`` builds, compiled into this
/// module: the same output on stdout and stderr, ``--help`` and ``--version`` included, and the
/// same exit codes (0; 1 when a log of ``loops run`` failed; 2 on an error; 0 when stdout closes
/// early). It runs without the GIL. It installs a SIGINT/SIGTERM handler that stays for the
/// rest of the process (an interrupt removes unfinished output and exits with 130), so call it
/// from a process that runs the command and nothing else.
///
/// Args:
///     args: the command's arguments, e.g. ``["demo", "--limit", "5"]``.
///
/// Returns:
///     The exit code.
#[pyfunction]
pub(crate) fn run_cli(py: Python<'_>, args: Vec<OsString>) -> u8 {
    let argv: Vec<OsString> = std::iter::once(OsString::from("loops")).chain(args).collect();
    py.detach(|| {
        // Not `detached`: the command reports its own errors on stderr and answers with an exit
        // code, as the binary does, and handles SIGINT itself; a panic becomes the binary's
        // exit code 101 (its message printed by the hook, as in the binary), not an exception.
        std::panic::catch_unwind(|| loops_cli::main(argv)).unwrap_or(PANIC_EXIT_CODE)
    })
}
