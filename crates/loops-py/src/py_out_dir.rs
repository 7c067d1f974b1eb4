//! `OutDir`: loops-io's output folder (one run at a time, a marker of what the command wrote, a
//! scratch folder, `force` replacing only the command's own entries) for `inexact_loops.dask`,
//! and `refuse_output_on_input`. The rules are loops-io's; this module only converts.

use std::path::PathBuf;

use loops_io::out_dir::{self, OutDirError, Tool};
use pyo3::prelude::*;

use crate::error::{Failure, InvalidParameterError};

/// An output folder a command fills with its results, held by this process: the rules of
/// ``loops run --out`` (one run at a time, an exclusive lock on the folder; every entry written
/// is listed in the command's marker before it is moved into place; ``force`` replaces only
/// listed entries, never a file of yours named like one of ours; work in progress is filled in
/// the command's scratch folder, and only that folder, as the marker lists it, is removed after
/// a killed run). Used by :func:`inexact_loops.dask.run_fleet_dask`.
///
/// Args:
///     path: the folder; created (with its parents) when missing.
///     force: replace the results of an earlier run of the command.
///     tool: the command: ``"loops-dask"``, ``"loops run"`` or ``"loops fleet"``.
///
/// Raises:
///     InvalidParameterError: the folder is in use, not empty without ``force``, or holds an
///         entry of the command's name that it did not write; an unknown ``tool``.
///     OSError: the folder cannot be created, read, locked or written.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct OutDir {
    inner: std::sync::Mutex<Option<out_dir::OutDir>>,
    path: PathBuf,
}

impl OutDir {
    fn with<T>(&self, f: impl FnOnce(&out_dir::OutDir) -> Result<T, Failure>) -> PyResult<T> {
        let held = self.inner.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let dir = held.as_ref().ok_or_else(|| {
            Failure::from(OutDirError::Io {
                what: "using the closed output folder".to_owned(),
                path: self.path.clone(),
                error: std::io::ErrorKind::NotConnected.into(),
            })
        })?;
        Ok(f(dir)?)
    }
}

#[pymethods]
impl OutDir {
    #[new]
    #[pyo3(signature = (path, *, force=false, tool="loops-dask"))]
    fn new(path: PathBuf, force: bool, tool: &str) -> PyResult<Self> {
        let tool = Tool::named(tool).ok_or_else(|| {
            InvalidParameterError::new_err(format!(
                "tool {tool:?} is not a command with an output folder: \"loops-dask\", \"loops run\" or \"loops fleet\""
            ))
        })?;
        std::fs::create_dir_all(&path).map_err(|error| {
            Failure::from(OutDirError::Io { what: "creating".to_owned(), path: path.clone(), error })
        })?;
        let dir = out_dir::OutDir::take(&path, force, tool).map_err(Failure::from)?;
        Ok(Self { inner: std::sync::Mutex::new(Some(dir)), path })
    }

    /// The folder, as given.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The scratch folder, where entries are filled before :meth:`place` moves them.
    #[getter]
    fn scratch(&self) -> PyResult<PathBuf> {
        self.with(|dir| Ok(dir.scratch()))
    }

    /// The entries the command's marker lists (it wrote them), sorted.
    #[getter]
    fn entries(&self) -> PyResult<Vec<String>> {
        self.with(|dir| Ok(dir.entries()))
    }

    /// Whether the entry ``name`` is listed in the marker: the command wrote it.
    fn owns(&self, name: &str) -> PyResult<bool> {
        self.with(|dir| Ok(dir.owns(name)))
    }

    /// Lists ``name`` in the marker, before it is written.
    fn claim(&self, name: &str) -> PyResult<()> {
        self.with(|dir| Ok(dir.claim(name)?))
    }

    /// A new path in the scratch folder for one file or folder to fill, then :meth:`place`.
    /// Nothing is created.
    fn staging_path(&self) -> PyResult<PathBuf> {
        self.with(|dir| Ok(dir.staging_path()))
    }

    /// Moves the filled file or folder ``staged`` into place as the entry ``name``, listing it
    /// first. An existing entry is replaced only with ``force`` and only when the marker lists
    /// it and it is of the same kind; ``staged`` is removed when it cannot be placed.
    ///
    /// Raises:
    ///     InvalidParameterError: the entry exists and may not be replaced.
    ///     OSError: a rename failed.
    fn place(&self, staged: PathBuf, name: &str) -> PyResult<()> {
        self.with(|dir| Ok(dir.place(&staged, name, dir.owns(name))?))
    }

    /// Removes the entry ``name`` when the command wrote it; anything else of that name is left
    /// alone. Returns whether an entry was removed.
    fn remove(&self, name: &str) -> PyResult<bool> {
        self.with(|dir| Ok(dir.remove(name)?))
    }

    /// Releases the folder: removes the scratch folder and the lock. Later calls raise.
    fn close(&self) {
        self.inner.lock().unwrap_or_else(std::sync::PoisonError::into_inner).take();
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_exc))]
    fn __exit__(&self, _exc: &Bound<'_, pyo3::types::PyTuple>) {
        self.close();
    }

    fn __repr__(&self) -> String {
        format!("OutDir({:?})", self.path.display().to_string())
    }
}

/// Refuses to write the output ``output`` onto an input, ``force`` or not: when it is, or
/// links to, one of ``inputs`` (files or folders), lies inside an input folder, or holds an
/// input. ``what`` names the output in the message.
///
/// Raises:
///     InvalidParameterError: naming both paths.
#[pyfunction]
pub(crate) fn refuse_output_on_input(what: &str, output: PathBuf, inputs: Vec<PathBuf>) -> PyResult<()> {
    Ok(out_dir::refuse_output_on_input(what, &output, &inputs).map_err(Failure::from)?)
}

/// Writes ``data`` to the file ``path`` whole or not at all: loops-io's one atomic writer, as
/// every file of the package is written (a temporary file beside it, synced, renamed into
/// place). An existing ``path`` is replaced only with ``overwrite``; a stream (``/dev/null``,
/// ``/dev/stdout``, a FIFO, or a link to one) is written into, never replaced.
///
/// Raises:
///     FileExistsError: ``path`` exists and ``overwrite`` is false.
///     OSError: the folder is missing or not writable, the disk is full, or ``path`` is a block
///         device or a socket.
#[pyfunction]
#[pyo3(signature = (path, data, *, overwrite=false))]
pub(crate) fn write_file(py: Python<'_>, path: PathBuf, data: &[u8], overwrite: bool) -> PyResult<()> {
    use std::io::Write;
    crate::detached(py, || {
        loops_io::write_atomically(&path, overwrite, |file| file.write_all(data)).map_err(Failure::from)
    })
}
