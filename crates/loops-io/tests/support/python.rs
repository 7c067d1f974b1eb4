//! The Python that writes the test fixtures (the official `mcap` writers, `rosbags`), and what a
//! test does when it cannot run: one file, included by the test support of loops-io and of
//! loops-cli.
//!
//! - The interpreter is `$PYTHON` when set (the Makefile passes the one its Python tests run in,
//!   so an inactive virtual environment is still the one used), else `python3`.
//! - A test that cannot run here is **skipped out loud**: libtest has no "skipped", and what a
//!   passing test prints is hidden, so [`skip`] appends a line to the file `$LOOPS_SKIPPED_LOG`
//!   (the Makefile prints the count and the reasons after `cargo test`) as well as to stderr.
//! - **Under CI** (`CI` set) a missing fixture writer is a failure, not a skip: CI installs every
//!   one, so a skip there would be a test that tests nothing.

use std::ffi::OsString;
use std::io::Write;

/// The Python interpreter of the fixture writers: `$PYTHON`, else `python3`.
pub fn python() -> OsString {
    std::env::var_os("PYTHON").filter(|p| !p.is_empty()).unwrap_or_else(|| "python3".into())
}

/// Says that the test part `what` cannot run here, because `why`: a failure under CI, else a
/// line on stderr and in `$LOOPS_SKIPPED_LOG`.
///
/// # Panics
/// Under CI (`CI` set), always.
pub fn skip(what: &str, why: &str) {
    if std::env::var_os("CI").is_some_and(|v| !v.is_empty() && v != "false") {
        panic!("{what} cannot run in CI, where every fixture writer is installed: {}", why.trim());
    }
    skipped(what, why);
}

/// Says that the test part `what` is skipped, because `why` (real data absent from a user's
/// clone, a device the system lacks): a line on stderr and in `$LOOPS_SKIPPED_LOG`, never a
/// failure.
pub fn skipped(what: &str, why: &str) {
    let why = why.trim();
    eprintln!("SKIPPED {what}: {why}");
    if let Some(log) = std::env::var_os("LOOPS_SKIPPED_LOG") {
        let line = format!("{} {what}: {}\n", env!("CARGO_PKG_NAME"), why.replace('\n', " "));
        if let Ok(mut file) = std::fs::OpenOptions::new().create(true).append(true).open(log) {
            let _ = file.write_all(line.as_bytes());
        }
    }
}
