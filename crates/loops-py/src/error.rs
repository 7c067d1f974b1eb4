//! The Python exception hierarchy and the one place core errors become Python exceptions.

use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIndexError, PyIsADirectoryError, PyKeyboardInterrupt, PyMemoryError,
    PyNotADirectoryError, PyOSError, PyPermissionError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;
use pyo3::{PyErr, import_exception};

// The hierarchy lives in Python (`inexact_loops/errors.py`) so that classes can also be
// `ValueError` or `OSError`; Rust raises those classes.
import_exception!(inexact_loops.errors, InvalidTrajectoryError);
import_exception!(inexact_loops.errors, InvalidParameterError);
import_exception!(inexact_loops.errors, LoopsIOError);
import_exception!(inexact_loops.errors, InternalError);
import_exception!(inexact_loops.errors, OutOfMemoryError);

/// Any error of the Rust layers, on its way to Python. Reader errors are boxed: they carry a
/// path, a line and the core's error, and errors travel through every `Result` of the bindings.
pub(crate) enum Failure {
    Core(loops_core::Error),
    Io(Box<loops_io::IoError>),
    Write(loops_io::WriteError),
    OutDir(loops_io::out_dir::OutDirError),
    OutputOnInput(loops_io::out_dir::OutputOnInput),
    Timing(loops_io::TimingConflict),
    Store(loops_io::store::StoreError),
    Panic(String),
}

impl From<loops_io::store::StoreError> for Failure {
    fn from(error: loops_io::store::StoreError) -> Self {
        match error {
            loops_io::store::StoreError::Core(error) => Self::Core(error),
            loops_io::store::StoreError::OutDir(error) => Self::OutDir(error),
            error => Self::Store(error),
        }
    }
}

impl From<loops_io::out_dir::OutDirError> for Failure {
    fn from(error: loops_io::out_dir::OutDirError) -> Self {
        Self::OutDir(error)
    }
}

impl From<loops_io::out_dir::OutputOnInput> for Failure {
    fn from(error: loops_io::out_dir::OutputOnInput) -> Self {
        Self::OutputOnInput(error)
    }
}

impl From<loops_io::TimingConflict> for Failure {
    fn from(error: loops_io::TimingConflict) -> Self {
        Self::Timing(error)
    }
}

impl From<loops_core::Error> for Failure {
    fn from(error: loops_core::Error) -> Self {
        Self::Core(error)
    }
}

impl From<loops_io::IoError> for Failure {
    fn from(error: loops_io::IoError) -> Self {
        Self::Io(Box::new(error))
    }
}

impl From<loops_io::WriteError> for Failure {
    fn from(error: loops_io::WriteError) -> Self {
        Self::Write(error)
    }
}

/// `OSError` with the operating system's errno (Python then raises its subclass:
/// `FileNotFoundError`, `PermissionError`, ...), or the subclass of the error's kind when a
/// library error carries no errno.
fn os_error(error: &std::io::Error, message: String) -> PyErr {
    use std::io::ErrorKind;
    if let Some(errno) = error.raw_os_error() {
        return PyOSError::new_err((errno, message));
    }
    match error.kind() {
        ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        ErrorKind::AlreadyExists => PyFileExistsError::new_err(message),
        ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
        ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

impl From<Failure> for PyErr {
    fn from(failure: Failure) -> Self {
        match failure {
            Failure::Core(error) => core_error(&error, error.to_string()),
            Failure::Io(error) => {
                let message = error.to_string();
                match *error {
                    loops_io::IoError::Open { error, .. } => os_error(&error, message),
                    loops_io::IoError::Trajectory { error, .. } => core_error(&error, message),
                    _ => LoopsIOError::new_err(message),
                }
            }
            // A refused output folder or entry is a wrong argument (the user's choice of folder);
            // the operating system's refusals are OSError.
            Failure::OutDir(error) => {
                let message = error.to_string();
                match error {
                    loops_io::out_dir::OutDirError::Io { error, .. } => os_error(&error, message),
                    _ => InvalidParameterError::new_err(message),
                }
            }
            Failure::OutputOnInput(error) => InvalidParameterError::new_err(error.to_string()),
            Failure::Timing(error) => InvalidParameterError::new_err(error.to_string()),
            Failure::Write(error) => {
                let message = error.to_string();
                match error {
                    loops_io::WriteError::Exists { .. } => PyFileExistsError::new_err(message),
                    loops_io::WriteError::Write { error, .. } => os_error(&error, message),
                    _ => LoopsIOError::new_err(message),
                }
            }
            // A store's settings other than those given are a wrong argument; its files, an
            // I/O error naming the file.
            Failure::Store(error) => {
                let message = error.to_string();
                match error {
                    loops_io::store::StoreError::Io { error, .. } => os_error(&error, message),
                    loops_io::store::StoreError::Settings { .. } => InvalidParameterError::new_err(message),
                    loops_io::store::StoreError::NotAStore { .. } => PyFileNotFoundError::new_err(message),
                    _ => LoopsIOError::new_err(message),
                }
            }
            Failure::Panic(message) => InternalError::new_err(format!("internal error (please report): {message}")),
        }
    }
}

/// The Python class of a core error ([`loops_core::Error::class`]): bad trajectories apart from
/// bad parameters; memory that could not be had as `MemoryError`.
fn core_error(error: &loops_core::Error, message: String) -> PyErr {
    use loops_core::ErrorClass as C;
    match error.class() {
        C::InvalidTrajectory => InvalidTrajectoryError::new_err(message),
        C::IndexOutOfRange => PyIndexError::new_err(message),
        C::OutOfMemory => OutOfMemoryError::new_err(message),
        // Only when Python did not raise first (see `detached`): an interrupt without a signal.
        C::Interrupted => PyKeyboardInterrupt::new_err(message),
        _ => InvalidParameterError::new_err(message),
    }
}

/// An `InvalidParameterError` about how arguments combine (a check no single core call makes).
pub(crate) fn invalid_parameter(message: String) -> PyErr {
    InvalidParameterError::new_err(message)
}

static UNPICKLING_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `pickle.UnpicklingError("cannot unpickle {class}: {reason}")`.
pub(crate) fn unpickling_error(py: Python<'_>, class: &str, reason: impl std::fmt::Display) -> PyErr {
    match UNPICKLING_ERROR.import(py, "pickle", "UnpicklingError") {
        Ok(unpickling) => PyErr::from_type(unpickling.clone(), format!("cannot unpickle {class}: {reason}")),
        Err(error) => error,
    }
}

/// Any exception raised while unpickling a `class` as the `pickle.UnpicklingError` that
/// pickling documents, naming the class and carrying the message of the check that refused the
/// state (a core error's class would say "invalid parameter" of a file's bytes); the original
/// is its `__cause__`. An `UnpicklingError` already, `KeyboardInterrupt` and `MemoryError` pass
/// unchanged: they say nothing about the state.
pub(crate) fn unpickling(py: Python<'_>, class: &str, error: PyErr) -> PyErr {
    let passes = |class: Option<&Bound<'_, PyType>>| class.is_some_and(|class| error.is_instance(py, class));
    let unpickling = UNPICKLING_ERROR.import(py, "pickle", "UnpicklingError").ok();
    if passes(unpickling)
        || error.is_instance_of::<PyKeyboardInterrupt>(py)
        || error.is_instance_of::<PyMemoryError>(py)
    {
        return error;
    }
    let converted = unpickling_error(py, class, error.value(py));
    converted.set_cause(py, Some(error));
    converted
}

/// A `ValueError` about an argument's shape or value that Python itself should have caught.
pub(crate) fn value_error(message: String) -> PyErr {
    PyValueError::new_err(message)
}
