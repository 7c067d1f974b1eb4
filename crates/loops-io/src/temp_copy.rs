//! Temporary copies of storage files (a file-compressed rosbag2 split, decompressed): files with
//! no name, so that no exit of the process leaves one behind.
//!
//! A decompressed split can be hundreds of megabytes, and decompressing it takes most of the
//! time a bag's reading takes. A named temporary file (`tempfile::NamedTempFile`) is removed
//! when its handle drops, but an exit that runs no destructor keeps it: the CLI's Ctrl-C handler
//! exits the process from its own thread, and a process killed or aborted never unwinds. So the
//! copy is written to a file that has no name from the start ([`tempfile::tempfile`]: Linux's
//! `O_TMPFILE`, or a file unlinked as soon as it is created; on Windows, a file deleted on
//! close): the system frees it when the last handle closes, however the process ends.
//!
//! The MCAP walker reads that file through its handle. SQLite cannot: it opens a database by
//! path, and resolves a path through `/proc/self/fd/N` to the deleted file's old name, which
//! fails. So a copy gets a name only for the moment SQLite opens it ([`TempCopy::name`]): on
//! Linux a hard link to the nameless file (`linkat` through `/proc/self/fd`, which an `O_TMPFILE`
//! file allows), elsewhere a copy of its bytes; the reader then removes the name at once
//! ([`TempName::remove`]) and SQLite reads through its own open handle. While a name exists it
//! is listed for [`remove_temporary_files`], which the CLI's interrupt handler calls before it
//! exits; a Python `KeyboardInterrupt` returns through the reader, whose handles drop as usual.

use std::fs::File;
use std::io::{self, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The prefix of the names of the temporary files.
const PREFIX: &str = "loops-bag-";

/// The names of temporary files that exist now (see [`remove_temporary_files`]).
static NAMES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn names() -> MutexGuard<'static, Vec<PathBuf>> {
    // A panic while a name was listed or removed leaves the list as it was: still right.
    NAMES.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes the names of the temporary files this crate holds at the moment: for an interrupt
/// handler that exits the process without unwinding (as the `loops` CLI's does), so that it
/// leaves no `loops-bag-*` file in the temporary folder. The files themselves have no name
/// but while SQLite opens one (a few milliseconds per storage file; longer off Linux, where the
/// name is a copy): see the module `temp_copy`. A read still running then fails, which does no
/// harm to a process about to exit.
///
/// Time O(number of files held), at most one per reading thread.
pub fn remove_temporary_files() {
    for name in names().drain(..) {
        let _ = std::fs::remove_file(name);
    }
}

/// A temporary file with no name: a storage file's decompressed copy.
#[derive(Debug)]
pub(crate) struct TempCopy {
    file: File,
}

impl TempCopy {
    /// A new, empty copy in the temporary folder (`TMPDIR`).
    ///
    /// # Errors
    /// When the temporary folder cannot take a file.
    pub(crate) fn new() -> io::Result<Self> {
        Ok(Self { file: tempfile::tempfile()? })
    }

    /// The file, to write the copy and read it.
    pub(crate) fn file(&self) -> &File {
        &self.file
    }

    /// The file, to read it to the end: it goes when the handle drops.
    pub(crate) fn into_file(self) -> File {
        self.file
    }

    /// A name for the copy in the temporary folder, for a reader that opens files by path
    /// (SQLite), until [`TempName::remove`] or its drop: a hard link where the system can make
    /// one to a nameless file (Linux), else a copy of the bytes.
    ///
    /// # Errors
    /// When no name can be made: the folder cannot take a file, or the copy fails.
    pub(crate) fn name(&self) -> io::Result<TempName> {
        let named = tempfile::Builder::new().prefix(PREFIX).make(|path| {
            // Listed before it exists: an interrupt from now on removes it.
            names().push(path.to_path_buf());
            let made = link(&self.file, path).or_else(|_| copy(&self.file, path));
            if made.is_err() {
                names().retain(|name| name != path);
            }
            made
        })?;
        // This type removes the name from here on, and unlists it.
        let path = named.into_temp_path().keep().map_err(|error| error.error)?;
        Ok(TempName { path: Some(path) })
    }
}

/// A hard link at `path` to the nameless file `file`: Linux links an `O_TMPFILE` file through
/// its `/proc/self/fd` entry.
#[cfg(target_os = "linux")]
fn link(file: &File, path: &Path) -> io::Result<()> {
    use std::os::fd::AsRawFd;
    let source = format!("/proc/self/fd/{}", file.as_raw_fd());
    rustix::fs::linkat(rustix::fs::CWD, source.as_str(), rustix::fs::CWD, path, rustix::fs::AtFlags::SYMLINK_FOLLOW)
        .map_err(io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn link(_file: &File, _path: &Path) -> io::Result<()> {
    Err(io::Error::new(io::ErrorKind::Unsupported, "no hard link to a file without a name here"))
}

/// A new file at `path` holding the bytes of `file`; nothing at `path` when that fails.
fn copy(file: &File, path: &Path) -> io::Result<()> {
    let copied = (|| {
        let mut out = File::options().write(true).create_new(true).open(path)?;
        let mut input = file.try_clone()?;
        input.seek(SeekFrom::Start(0))?;
        io::copy(&mut input, &mut out)?;
        Ok(())
    })();
    if copied.is_err() {
        let _ = std::fs::remove_file(path);
    }
    copied
}

/// The name of a [`TempCopy`] (see [`TempCopy::name`]), removed by [`remove`](Self::remove) or
/// when dropped.
#[derive(Debug)]
pub(crate) struct TempName {
    /// The name, until removed.
    path: Option<PathBuf>,
}

impl TempName {
    /// The name.
    pub(crate) fn path(&self) -> &Path {
        self.path.as_deref().unwrap_or(Path::new(""))
    }

    /// Removes the name now: a reader that opened the file keeps reading it through its own
    /// handle (on Unix; Windows cannot remove an open file, and the drop does it after the
    /// reader closed it).
    pub(crate) fn remove(&mut self) {
        if let Some(path) = self.path.take() {
            if std::fs::remove_file(&path).is_ok() || !path.exists() {
                names().retain(|name| *name != path);
            } else {
                self.path = Some(path);
            }
        }
    }
}

impl Drop for TempName {
    fn drop(&mut self) {
        if let Some(path) = self.path.take() {
            let _ = std::fs::remove_file(&path);
            names().retain(|name| *name != path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    #[test]
    fn a_copy_is_named_only_until_its_name_is_removed() {
        let copy = TempCopy::new().unwrap();
        copy.file().write_all(b"some bytes").unwrap();
        let mut name = copy.name().unwrap();
        let path = name.path().to_path_buf();
        assert!(path.file_name().unwrap().to_string_lossy().starts_with(PREFIX), "{}", path.display());
        let mut opened = File::open(&path).unwrap();
        assert!(names().contains(&path));
        name.remove();
        assert!(!path.exists(), "the name is gone");
        assert!(!names().contains(&path));
        let mut read = String::new();
        opened.read_to_string(&mut read).unwrap();
        assert_eq!(read, "some bytes", "read through the handle opened before");
        drop(name);
        let name = copy.name().unwrap();
        let path = name.path().to_path_buf();
        drop(name);
        assert!(!path.exists() && !names().contains(&path), "a drop removes the name");
        let copied = tempfile::Builder::new().prefix(PREFIX).make(|path| copy_to(&copy, path)).unwrap();
        assert_eq!(std::fs::read(copied.path()).unwrap(), b"some bytes", "the copy where no link can be made");
    }

    fn copy_to(temp: &TempCopy, path: &Path) -> io::Result<()> {
        copy(temp.file(), path)
    }
}
