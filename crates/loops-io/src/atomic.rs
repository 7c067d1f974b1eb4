//! The one atomic writer of the workspace: a file is written whole or not at all, and an existing
//! file is replaced only when asked. The temporary file, its clean-up and the rename without
//! clobbering are the `tempfile` crate's.

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};

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
/// A `path` that is a stream rather than a file — a FIFO or a character device such as
/// `/dev/null` or `/dev/stdout`, or a link to one — is written into, not replaced (a rename
/// would put a file where the device was): its content is filled into an anonymous temporary
/// file first and copied in when every step succeeded, `overwrite` or not, as nothing is
/// replaced. A block device or a socket is refused.
///
/// The temporary file is removed when `fill` or a later step fails.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when `path` names no file, is a block device or a socket, its directory is missing or not
/// writable, the disk is full, or `fill` fails (with `fill`'s error).
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
    Staged::new(path.as_ref(), overwrite, fill)?.persist()
}

/// Several files written all or none, for a command that writes more than one: each file is
/// filled into its temporary file ([`stage`](Self::stage), checked and synced as by
/// [`write_atomically`]) and nothing is moved into place until every one succeeded
/// ([`persist`](Self::persist)). Dropped without `persist`, the temporary files are removed and
/// nothing was written.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use std::io::Write;
/// use loops_io::{StagedFiles, WriteError};
///
/// let dir = std::env::temp_dir().join(format!("loops-io-staged-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// std::fs::write(dir.join("input.tum"), "0 0 0 0 0 0 0 1\n")?;
/// let mut files = StagedFiles::new();
/// files.stage(dir.join("pairs.csv"), false, |file| file.write_all(b"i,j\n"))?;
/// // The second file is refused: the first is not written either.
/// let refused = files.stage(dir.join("input.tum"), false, |file| file.write_all(b"EDGE_SE2\n"));
/// assert!(matches!(refused, Err(WriteError::Exists { .. })));
/// drop(files);
/// assert!(!dir.join("pairs.csv").exists());
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Default)]
pub struct StagedFiles {
    files: Vec<Staged>,
}

impl StagedFiles {
    /// No files yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Fills the file `path` into a temporary file beside it, synced, and keeps it for
    /// [`persist`](Self::persist): as [`write_atomically`] up to the rename.
    ///
    /// # Errors
    /// As [`write_atomically`]; [`WriteError::Exists`] too when `path` is already staged here.
    pub fn stage(
        &mut self,
        path: impl AsRef<Path>,
        overwrite: bool,
        fill: impl FnOnce(&mut File) -> io::Result<()>,
    ) -> Result<(), WriteError> {
        let path = path.as_ref();
        if self.files.iter().any(|staged| staged.path == path) {
            return Err(WriteError::Exists { path: path.to_path_buf() });
        }
        self.files.push(Staged::new(path, overwrite, fill)?);
        Ok(())
    }

    /// Number of files staged.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether no file is staged.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// Moves every staged file into place, in the order staged. When one cannot be (another
    /// writer created it meanwhile, the disk failed), the files this call created are removed
    /// again, so none is left; a file replaced with `overwrite` keeps its new content.
    ///
    /// # Errors
    /// As [`write_atomically`], for the first file that could not be moved into place.
    pub fn persist(self) -> Result<(), WriteError> {
        let mut created = Vec::new();
        for staged in self.files {
            let (path, existed) = (staged.path.clone(), staged.existed);
            if let Err(error) = staged.persist() {
                for path in created {
                    let _ = std::fs::remove_file(path);
                }
                return Err(error);
            }
            if !existed {
                created.push(path);
            }
        }
        Ok(())
    }
}

/// One file filled into its temporary file, not yet moved into place.
#[derive(Debug)]
struct Staged {
    path: PathBuf,
    dir: PathBuf,
    overwrite: bool,
    /// Whether `path` existed when staged (it is then replaced, never removed).
    existed: bool,
    temporary: Temporary,
}

/// Where a staged file's content waits.
#[derive(Debug)]
enum Temporary {
    /// Beside the file, renamed into place.
    Beside(tempfile::NamedTempFile),
    /// Anywhere, copied into the stream `path` names.
    ForStream(File),
}

/// What an existing `path` is, following links.
enum Existing {
    /// Nothing, a file, a folder or a broken link: the rename's rules apply.
    Replaceable,
    /// A FIFO or a character device: written into.
    Stream,
    /// A block device or a socket, named for the message.
    Refused(&'static str),
}

impl Existing {
    #[cfg(unix)]
    fn of(path: &Path) -> Self {
        use std::os::unix::fs::FileTypeExt;
        match std::fs::metadata(path).map(|m| m.file_type()) {
            Ok(kind) if kind.is_fifo() || kind.is_char_device() => Self::Stream,
            Ok(kind) if kind.is_block_device() => Self::Refused("a block device"),
            Ok(kind) if kind.is_socket() => Self::Refused("a socket"),
            _ => Self::Replaceable,
        }
    }

    #[cfg(not(unix))]
    fn of(_path: &Path) -> Self {
        Self::Replaceable
    }
}

impl Staged {
    fn new(path: &Path, overwrite: bool, fill: impl FnOnce(&mut File) -> io::Result<()>) -> Result<Self, WriteError> {
        let failed = |error: io::Error| WriteError::Write { path: path.to_path_buf(), error };
        let existed = path.symlink_metadata().is_ok();
        match Existing::of(path) {
            Existing::Refused(what) => return Err(failed(io::Error::other(format!("it is {what}, not a file")))),
            Existing::Stream => {
                let mut temporary = tempfile::tempfile().map_err(failed)?;
                fill(&mut temporary).map_err(failed)?;
                let (path, dir) = (path.to_path_buf(), PathBuf::new());
                return Ok(Self { path, dir, overwrite, existed, temporary: Temporary::ForStream(temporary) });
            }
            Existing::Replaceable => {}
        }
        if !overwrite && existed {
            return Err(WriteError::Exists { path: path.to_path_buf() });
        }
        let name = path.file_name().ok_or_else(|| failed(io::Error::other("the path names no file")))?;
        let dir = path.parent().filter(|dir| !dir.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let prefix = format!(".{}.", name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        // A missing folder is told first: tempfile wraps the system's error with the temporary
        // file's path and hides its code (Python raises FileNotFoundError with it).
        std::fs::metadata(dir).map_err(failed)?;
        let mut temporary = builder.tempfile_in(dir).map_err(failed)?;
        fill(temporary.as_file_mut()).and_then(|()| temporary.as_file().sync_all()).map_err(failed)?;
        let temporary = Temporary::Beside(temporary);
        Ok(Self { path: path.to_path_buf(), dir: dir.to_path_buf(), overwrite, existed, temporary })
    }

    fn persist(self) -> Result<(), WriteError> {
        let path = self.path;
        let failed = |error: io::Error| WriteError::Write { path: path.clone(), error };
        let temporary = match self.temporary {
            Temporary::Beside(temporary) => temporary,
            Temporary::ForStream(mut content) => return copy_into_stream(&mut content, &path).map_err(failed),
        };
        let placed = if self.overwrite { temporary.persist(&path) } else { temporary.persist_noclobber(&path) };
        match placed {
            Ok(_) => {}
            // The temporary file is removed as the error drops.
            Err(error) if !self.overwrite && error.error.kind() == io::ErrorKind::AlreadyExists => {
                return Err(WriteError::Exists { path });
            }
            Err(error) => return Err(failed(error.error)),
        }
        sync_directory(&self.dir).map_err(failed)
    }
}

/// Copies `content`, from its start, into the stream `path` names (opened for writing, neither
/// created nor truncated).
fn copy_into_stream(content: &mut File, path: &Path) -> io::Result<()> {
    use std::io::{Seek, Write};
    content.seek(io::SeekFrom::Start(0))?;
    let mut stream = std::fs::OpenOptions::new().write(true).open(path)?;
    io::copy(content, &mut stream)?;
    stream.flush()
}

/// Makes the rename into `dir` durable: fsync of the directory (Unix; elsewhere nothing to do).
pub(crate) fn sync_directory(dir: &Path) -> io::Result<()> {
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

    /// A stream is written into and stays what it was: a FIFO (read by a thread), `/dev/null`
    /// through a link (a rename would replace the link, or the device itself when named); a
    /// socket is refused and left.
    #[cfg(unix)]
    #[test]
    fn streams_are_written_into_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch("streams");
        let fifo = dir.join("pipe");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || fs::read(fifo).unwrap())
        };
        write_atomically(&fifo, false, |file| file.write_all(b"through the pipe\n")).unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe\n");
        assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());

        let null = dir.join("null");
        std::os::unix::fs::symlink("/dev/null", &null).unwrap();
        for overwrite in [false, true] {
            write_atomically(&null, overwrite, |file| file.write_all(b"gone")).unwrap();
            let mut files = StagedFiles::new();
            files.stage(&null, overwrite, |file| file.write_all(b"gone too")).unwrap();
            files.persist().unwrap();
            assert!(fs::symlink_metadata(&null).unwrap().file_type().is_symlink(), "the link was replaced");
            assert!(fs::metadata(&null).unwrap().file_type().is_char_device());
        }

        let socket = dir.join("socket");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        let error = write_atomically(&socket, true, |file| file.write_all(b"no")).unwrap_err();
        assert!(error.to_string().contains("it is a socket, not a file"), "{error}");
        assert!(fs::metadata(&socket).unwrap().file_type().is_socket());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 3, "a temporary file was left");
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
        // A missing folder keeps its code (Python raises FileNotFoundError for it), and the
        // message names the file, not a temporary one.
        let error = write_atomically(dir.join("missing/out.txt"), true, |_| Ok(())).unwrap_err();
        let WriteError::Write { error: os, .. } = &error else { panic!("{error}") };
        assert_eq!(os.kind(), io::ErrorKind::NotFound);
        assert!(os.raw_os_error().is_some() && !error.to_string().contains(".tmp"), "{error}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn staged_files_are_written_all_or_none() {
        let dir = scratch("staged");
        let taken = dir.join("taken.txt");
        fs::write(&taken, "the user's").unwrap();
        let mut files = StagedFiles::new();
        files.stage(dir.join("a.csv"), false, |file| file.write_all(b"a")).unwrap();
        assert!(matches!(files.stage(dir.join("a.csv"), true, |_| Ok(())), Err(WriteError::Exists { .. })));
        assert!(matches!(files.stage(&taken, false, |_| Ok(())), Err(WriteError::Exists { .. })));
        assert!(matches!(
            files.stage(dir.join("b.csv"), false, |_| Err(io::Error::other("no"))),
            Err(WriteError::Write { .. })
        ));
        assert_eq!(files.len(), 1);
        drop(files);
        // Nothing written, no temporary file left.
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        // All staged: all written.
        let mut files = StagedFiles::new();
        files.stage(dir.join("a.csv"), false, |file| file.write_all(b"a")).unwrap();
        files.stage(&taken, true, |file| file.write_all(b"b")).unwrap();
        files.persist().unwrap();
        assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), "a");
        assert_eq!(fs::read_to_string(&taken).unwrap(), "b");
        // One that cannot be moved in place: the files created before it are removed again.
        let mut files = StagedFiles::new();
        files.stage(dir.join("c.csv"), false, |file| file.write_all(b"c")).unwrap();
        files.stage(dir.join("d.csv"), false, |file| file.write_all(b"d")).unwrap();
        fs::write(dir.join("d.csv"), "another writer's").unwrap();
        assert!(matches!(files.persist(), Err(WriteError::Exists { .. })));
        assert!(!dir.join("c.csv").exists());
        assert_eq!(fs::read_to_string(dir.join("d.csv")).unwrap(), "another writer's");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 3);
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
