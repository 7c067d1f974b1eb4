//! Shared by the integration tests: running the `loops` binary, a fresh temp folder per test,
//! and the checks of its output.
#![allow(dead_code)] // each test crate uses a different part

#[path = "../../../loops-io/tests/support/python.rs"]
mod python;
#[allow(unused_imports)] // each test crate uses a different part
pub use python::{python, skip, skipped};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `loops` with `args`.
pub fn loops(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loops")).args(args).output().expect("the loops binary runs")
}

/// An empty folder `name` of the test crate in the temp folder (emptied first when it exists),
/// removed when the returned guard is dropped.
pub fn temp_dir(name: &str) -> TempDir {
    let crate_name = env!("CARGO_CRATE_NAME");
    TempDir::at(std::env::temp_dir().join(format!("loops-cli-{crate_name}-{name}-{}", std::process::id())))
}

/// A test's folder, removed with what it holds when dropped; kept, and its path printed, when
/// the test fails, so that what the test left can be read.
pub struct TempDir(PathBuf);

impl TempDir {
    /// Makes `dir` empty (removing what it held) and guards it.
    pub fn at(dir: PathBuf) -> Self {
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Self(dir)
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TempDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept the failed test's folder {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Writes `contents` as the file `name` of `dir`, and returns its path.
pub fn write_in(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, contents).expect("a file in the temp dir");
    path
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The error of a command that failed with exit code 2 and one line on stderr.
pub fn one_line_error(output: &Output) -> String {
    assert_eq!(output.status.code(), Some(2), "stderr: {}", stderr(output));
    let err = stderr(output);
    assert_eq!(err.trim_end().lines().count(), 1, "one line expected: {err}");
    err
}

/// What an error must mention: one text, or several.
pub trait Needles {
    fn each(&self) -> Vec<&str>;
}

impl Needles for &str {
    fn each(&self) -> Vec<&str> {
        vec![self]
    }
}

impl<S: AsRef<str> + ?Sized> Needles for &[&S] {
    fn each(&self) -> Vec<&str> {
        self.iter().map(|s| s.as_ref()).collect()
    }
}

impl<S: AsRef<str> + ?Sized, const N: usize> Needles for &[&S; N] {
    fn each(&self) -> Vec<&str> {
        self.iter().map(|s| s.as_ref()).collect()
    }
}

/// A failure as the CLI reports one: exit code 2, one line `loops: error: ...` on stderr that
/// mentions each of `needles`.
pub fn assert_one_line_error(output: &Output, needles: impl Needles) {
    let err = one_line_error(output);
    assert!(err.starts_with("loops: error: "), "{err}");
    for needle in needles.each() {
        assert!(err.contains(needle), "{err:?} should mention {needle:?}");
    }
}

/// The names in a folder, sorted.
pub fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// Where laps of a 40 m square (10 m a side) are at step `k`, a quarter metre a step: `(x, y)`.
pub fn square_lap(k: u32) -> (f64, f64) {
    let s = f64::from(k % 160) * 0.25;
    match k % 160 / 40 {
        0 => (s, 0.0),
        1 => (10.0, s - 10.0),
        2 => (30.0 - s, 10.0),
        _ => (0.0, 40.0 - s),
    }
}

/// Two laps of a 40 m square at 1 m/s, shifted by `dx`, as TUM at `path`, starting at `t0`.
pub fn laps_tum(path: &Path, t0: u32, dx: f64) {
    let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
    for k in 0..320 {
        let (x, y) = square_lap(k);
        text += &format!("{}.0 {} {y} 0 0 0 0 1\n", t0 + k, x + dx);
    }
    std::fs::write(path, text).unwrap();
}
