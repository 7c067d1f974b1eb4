//! Output files that are whole or absent, even when the user presses Ctrl-C.
//!
//! Every write of `loops` goes through [`with_writes`], which holds one process-wide lock while a
//! file is written to a temporary name and renamed into place, and while a log's staging folder
//! is renamed to its final name. The SIGINT/SIGTERM handler takes the same lock, so it runs
//! between writes: it removes the staging folders of logs still in progress and the scratch
//! folders of output folders (and folders `loops` created that stayed empty) and the names of
//! temporary files the readers hold ([`loops_io::remove_temporary_files`]), says so, and exits
//! with 130. What is left is what was
//! finished: whole files and whole per-log folders.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, OnceLock, PoisonError};

use anyhow::{Context, Result};
use loops_core::Interrupt;
use loops_io::WriteError;

/// Exit code after an interrupt (128 + SIGINT), as shells report it.
pub(crate) const INTERRUPTED: u8 = 130;

/// What the interrupt handler must clean up.
#[derive(Debug, Default)]
pub(crate) struct Writes {
    /// Staging folders of logs in progress, removed on interrupt.
    staged: Vec<PathBuf>,
    /// Folders `loops` created, removed on interrupt if still empty (innermost first).
    created: Vec<PathBuf>,
    /// Marker files of output folders, removed on interrupt with their folder when `loops`
    /// created it and it holds nothing else.
    markers: Vec<PathBuf>,
    /// Scratch folders of output folders, removed on interrupt (after the staging folders in
    /// them are counted).
    scratch: Vec<PathBuf>,
}

static WRITES: Mutex<Writes> =
    Mutex::new(Writes { staged: Vec::new(), created: Vec::new(), markers: Vec::new(), scratch: Vec::new() });

fn lock() -> MutexGuard<'static, Writes> {
    // A panic while writing leaves the list as it was: still right to clean up.
    WRITES.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Runs `f` while no interrupt can clean up: for one file write or one rename.
pub(crate) fn with_writes<R>(f: impl FnOnce(&mut Writes) -> R) -> R {
    f(&mut lock())
}

/// The computation Ctrl-C stops instead of exiting the process, if any (see
/// [`stop_on_interrupt`]).
static STOP: Mutex<Option<Interrupt>> = Mutex::new(None);

/// While the returned guard lives, the first SIGINT/SIGTERM interrupts `stop` instead of
/// exiting: a command that ends cleanly on its own when interrupted (`loops replay` prints
/// its figures so far and exits with [`INTERRUPTED`]). A second one exits as usual.
pub(crate) fn stop_on_interrupt(stop: Interrupt) -> StopGuard {
    *STOP.lock().unwrap_or_else(PoisonError::into_inner) = Some(stop);
    StopGuard(())
}

/// Ends [`stop_on_interrupt`] when dropped.
#[derive(Debug)]
pub(crate) struct StopGuard(());

impl Drop for StopGuard {
    fn drop(&mut self) {
        *STOP.lock().unwrap_or_else(PoisonError::into_inner) = None;
    }
}

/// Installs the SIGINT/SIGTERM handler, once per process: a second command run in the same
/// process (the Python console script's) keeps the first handler.
pub(crate) fn install() -> Result<()> {
    static INSTALLED: OnceLock<()> = OnceLock::new();
    if INSTALLED.get().is_some() {
        return Ok(());
    }
    ctrlc::set_handler(|| {
        // A computation that stops by itself (`loops replay`) is asked to, the first time.
        let stop = STOP.lock().unwrap_or_else(PoisonError::into_inner).clone();
        if let Some(stop) = stop
            && !stop.is_interrupted()
        {
            stop.interrupt();
            return;
        }
        let writes = lock();
        let mut removed = 0;
        for dir in &writes.staged {
            if std::fs::remove_dir_all(dir).is_ok() {
                removed += 1;
            }
        }
        for dir in &writes.scratch {
            let _ = std::fs::remove_dir_all(dir);
        }
        for marker in &writes.markers {
            let alone = marker
                .parent()
                .and_then(|dir| std::fs::read_dir(dir).ok())
                .is_some_and(|mut e| e.next().is_some() && e.next().is_none());
            if alone && marker.parent().is_some_and(|dir| writes.created.iter().any(|c| c == dir)) {
                let _ = std::fs::remove_file(marker);
            }
        }
        for dir in writes.created.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
        // A bag's decompressed copy has no name but while SQLite opens it: remove that name too.
        loops_io::remove_temporary_files();
        if removed == 0 {
            eprintln!("loops: interrupted");
        } else {
            eprintln!("loops: interrupted; removed {removed} unfinished log folder(s), kept the finished ones");
        }
        std::process::exit(i32::from(INTERRUPTED));
    })
    .context("installing the Ctrl-C handler")?;
    let _ = INSTALLED.set(());
    Ok(())
}

impl Writes {
    /// Creates `dir` (and its missing parents), remembering the ones it created.
    pub(crate) fn create_dir(&mut self, dir: &Path) -> Result<()> {
        let mut missing = Vec::new();
        let mut cursor = Some(dir);
        while let Some(path) = cursor.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(path.to_path_buf());
            cursor = path.parent();
        }
        for path in missing.into_iter().rev() {
            std::fs::create_dir(&path).with_context(|| format!("creating {}", path.display()))?;
            self.created.push(path);
        }
        Ok(())
    }

    /// Remembers the marker file of an output folder (see [`Writes::markers`]).
    pub(crate) fn marker(&mut self, path: &Path) {
        if !self.markers.iter().any(|p| p == path) {
            self.markers.push(path.to_path_buf());
        }
    }

    /// Creates a staging folder (in an output folder's scratch folder), removed on interrupt
    /// until [`unstage`](Self::unstage)d.
    pub(crate) fn stage(&mut self, dir: &Path) -> Result<()> {
        std::fs::create_dir(dir).with_context(|| format!("creating {}", dir.display()))?;
        self.staged.push(dir.to_path_buf());
        Ok(())
    }

    /// Forgets a staging folder: moved into place, or removed.
    pub(crate) fn unstage(&mut self, dir: &Path) {
        self.staged.retain(|d| d != dir);
    }

    /// Remembers the scratch folder of an output folder, removed on interrupt.
    pub(crate) fn scratch(&mut self, dir: PathBuf) {
        if !self.scratch.contains(&dir) {
            self.scratch.push(dir);
        }
    }
}

/// The CLI's words for a refused write: an existing file is kept unless `--force`.
pub(crate) fn write_error(error: WriteError) -> anyhow::Error {
    match error {
        WriteError::Exists { path } => anyhow::anyhow!("{} exists; pass --force to replace it", path.display()),
        WriteError::Write { path, error } => anyhow::Error::new(error).context(format!("writing {}", path.display())),
        error => error.into(),
    }
}
