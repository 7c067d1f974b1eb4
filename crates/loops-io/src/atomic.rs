//! The one atomic writer of the workspace: a file is written whole, or not at all, and an existing
//! file is replaced only when asked.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::WriteError;

/// Writes through `fill` into a temporary file beside `path`, then moves it into place.
pub(crate) fn write_atomically(
    path: &Path,
    overwrite: bool,
    fill: impl FnOnce(&mut fs::File) -> io::Result<()>,
) -> Result<(), WriteError> {
    let exists = || WriteError::Exists { path: path.to_path_buf() };
    let failed = |error: io::Error| WriteError::Write { path: path.to_path_buf(), error };
    if !overwrite && fs::symlink_metadata(path).is_ok() {
        return Err(exists());
    }
    let temporary = temporary_path(path).ok_or_else(|| failed(io::Error::other("the path names no file")))?;
    let written = fs::OpenOptions::new().write(true).create_new(true).open(&temporary).and_then(|mut file| {
        fill(&mut file)?;
        file.sync_all()
    });
    let placed = written.and_then(|()| {
        if overwrite {
            return fs::rename(&temporary, path).map(|()| true);
        }
        // A hard link fails if the file appeared meanwhile: no race with another writer.
        match fs::hard_link(&temporary, path) {
            Ok(()) => Ok(true),
            Err(error) if error.kind() == io::ErrorKind::AlreadyExists => Ok(false),
            // No hard links on this file system: the check above has to do.
            Err(_) if fs::symlink_metadata(path).is_err() => fs::rename(&temporary, path).map(|()| true),
            Err(_) => Ok(false),
        }
    });
    // Left behind after a failure, or as the second name of a hard link.
    let _ = fs::remove_file(&temporary);
    match placed {
        Ok(true) => Ok(()),
        Ok(false) => Err(exists()),
        Err(error) => Err(failed(error)),
    }
}

/// `.{name}.{pid}.{count}.tmp` in the directory of `path`; `None` when `path` names no file.
fn temporary_path(path: &Path) -> Option<PathBuf> {
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name()?.to_string_lossy();
    let count = COUNT.fetch_add(1, Ordering::Relaxed);
    Some(path.with_file_name(format!(".{name}.{}.{count}.tmp", std::process::id())))
}
