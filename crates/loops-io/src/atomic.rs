//! The one atomic writer of the workspace: a file is written whole or not at all, and an existing
//! file is replaced only when asked. The temporary file, its clean-up and the rename without
//! clobbering are the `tempfile` crate's.

use std::fs::File;
use std::io;
use std::path::Path;

use crate::error::WriteError;

/// Writes a file through `fill`, atomically: into a temporary file in the same directory
/// (`.{name}.XXXXXX.tmp`), synced to disk, then renamed into place and the directory synced
/// (Unix), so that a reader, a crash or an interrupt sees the old file or the new one, never
/// half of one. The file gets the permissions of a new file (`0o666` less the umask on Unix).
///
/// Without `overwrite`, an existing `path` (a file, a folder or a link, even a broken one) is
/// left alone: checked before writing, and again without a race when the file is moved in place
/// (`persist_noclobber`: another writer that creates `path` meanwhile wins). With `overwrite`,
/// `path` is replaced.
///
/// The temporary file is removed when `fill` or a later step fails.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when `path` names no file, its directory is missing or not writable, the disk is full, or
/// `fill` fails (with `fill`'s error).
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use std::io::Write;
/// use loops_io::{WriteError, write_atomically};
///
/// let path = std::env::temp_dir().join(format!("loops-io-atomic-{}.txt", std::process::id()));
/// # let _ = std::fs::remove_file(&path);
/// write_atomically(&path, false, |file| file.write_all(b"first\n"))?;
/// let again = write_atomically(&path, false, |file| file.write_all(b"second\n"));
/// assert!(matches!(again, Err(WriteError::Exists { .. })));
/// write_atomically(&path, true, |file| file.write_all(b"second\n"))?;
/// assert_eq!(std::fs::read_to_string(&path)?, "second\n");
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn write_atomically(
    path: impl AsRef<Path>,
    overwrite: bool,
    fill: impl FnOnce(&mut File) -> io::Result<()>,
) -> Result<(), WriteError> {
    let path = path.as_ref();
    let exists = || WriteError::Exists { path: path.to_path_buf() };
    let failed = |error: io::Error| WriteError::Write { path: path.to_path_buf(), error };
    if !overwrite && path.symlink_metadata().is_ok() {
        return Err(exists());
    }
    let name = path.file_name().ok_or_else(|| failed(io::Error::other("the path names no file")))?;
    let dir = path.parent().filter(|dir| !dir.as_os_str().is_empty()).unwrap_or(Path::new("."));
    // A missing or unreadable folder is reported with the operating system's own error (and
    // errno, so Python raises FileNotFoundError): `tempfile` would wrap it with the temporary
    // file's name.
    std::fs::metadata(dir).map_err(failed)?;
    let prefix = format!(".{}.", name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut temporary = builder.tempfile_in(dir).map_err(failed)?;
    fill(temporary.as_file_mut()).and_then(|()| temporary.as_file().sync_all()).map_err(failed)?;
    let placed = if overwrite { temporary.persist(path) } else { temporary.persist_noclobber(path) };
    match placed {
        Ok(_) => {}
        // The temporary file is removed as the error drops.
        Err(error) if !overwrite && error.error.kind() == io::ErrorKind::AlreadyExists => return Err(exists()),
        Err(error) => return Err(failed(error.error)),
    }
    sync_directory(dir).map_err(failed)
}

/// Makes the rename into `dir` durable: fsync of the directory (Unix; elsewhere nothing to do).
fn sync_directory(dir: &Path) -> io::Result<()> {
    #[cfg(unix)]
    File::open(dir)?.sync_all()?;
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::fs;
    use std::io::Write;

    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("loops-io-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn files_are_replaced_only_when_asked_and_nothing_is_left_behind() {
        let dir = scratch("replace");
        let path = dir.join("out.txt");
        write_atomically(&path, false, |file| file.write_all(b"one")).unwrap();
        let error = write_atomically(&path, false, |file| file.write_all(b"two")).unwrap_err();
        assert!(matches!(error, WriteError::Exists { .. }));
        assert!(error.to_string().ends_with("out.txt: the file exists; refusing to overwrite it"), "{error}");
        assert_eq!(fs::read_to_string(&path).unwrap(), "one");
        write_atomically(&path, true, |file| file.write_all(b"two")).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "two");
        // A failing fill leaves the old file and no temporary file.
        let error = write_atomically(&path, true, |_| Err(io::Error::other("no"))).unwrap_err();
        assert!(matches!(error, WriteError::Write { .. }));
        assert_eq!(fs::read_to_string(&path).unwrap(), "two");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_appearing_while_writing_is_not_clobbered() {
        let dir = scratch("race");
        let path = dir.join("out.txt");
        let error = write_atomically(&path, false, |file| {
            fs::write(&path, "the other writer's")?;
            file.write_all(b"ours")
        })
        .unwrap_err();
        assert!(matches!(error, WriteError::Exists { .. }));
        assert_eq!(fs::read_to_string(&path).unwrap(), "the other writer's");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_folders_and_paths_without_a_file_are_write_errors() {
        let dir = scratch("missing");
        for path in [dir.join("missing/out.txt"), dir.join("..")] {
            let error = write_atomically(&path, true, |file| file.write_all(b"x")).unwrap_err();
            assert!(matches!(error, WriteError::Write { .. }), "{path:?}: {error}");
        }
        // The operating system's error, naming the file asked for (not the temporary one).
        let path = dir.join("missing/out.txt");
        match write_atomically(&path, false, |file| file.write_all(b"x")).unwrap_err() {
            WriteError::Write { path: named, error } => {
                assert_eq!(
                    (named, error.kind(), error.raw_os_error().is_some()),
                    (path, io::ErrorKind::NotFound, true)
                );
                assert!(!error.to_string().contains(".tmp"), "{error}");
            }
            other => panic!("{other}"),
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn new_files_get_the_permissions_of_a_new_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let path = dir.join("out.txt");
        write_atomically(&path, false, |file| file.write_all(b"x")).unwrap();
        let reference = dir.join("reference.txt");
        fs::write(&reference, "x").unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&reference));
        fs::remove_dir_all(&dir).unwrap();
    }
}
