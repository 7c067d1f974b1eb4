//! An output folder that a command fills with its results: `loops run`'s and `loops fleet`'s
//! `--out`, `loops-dask`'s `out`. One rule for all three, so that none of them ever removes or
//! replaces a file it did not write.
//!
//! - **One run owns it.** The run holds an exclusive lock on the folder itself (`flock` through
//!   std's `File::try_lock`, on Unix; a lock file `.loops-run.lock` elsewhere) from before it
//!   looks inside until the [`OutDir`] is dropped or the process ends, however it ends. A second
//!   run into the same folder stops at once, naming the folder and the holder's pid (recorded in
//!   the marker).
//! - **What it wrote, it marks.** The marker ([`Tool::marker`]: `loops-run.json`,
//!   `loops-fleet.json`, `loops-dask.json`; visible, so a finished folder holds no hidden file)
//!   lists every entry of the folder that the command wrote. An entry is listed before it is
//!   moved into place, so an interrupted run leaves nothing of its own unlisted. With `force` a
//!   listed entry may be replaced; anything else with the same name (a user's `index.html`, a
//!   folder of theirs with a log's name) never is: a clear error names it.
//! - **Work in progress stays in one folder of the command's.** Files and folders are filled in
//!   the scratch folder ([`Tool::scratch`], `.loops-run.partial`, ...), which the marker lists
//!   before it is created, then renamed into place; an entry replaced with `force` is first moved
//!   into the scratch folder, then removed. The scratch folder is removed when the [`OutDir`] is
//!   dropped. A run killed meanwhile leaves it behind; the next run removes it **only because the
//!   marker lists it**: no other entry of the folder is ever removed on the strength of its name,
//!   however much it looks like a leftover. Names in the scratch folder are short counters, so a
//!   log's name of any length fits.
//!
//! The lock is std's, the marker one serde struct; nothing here is an algorithm of the product:
//! it is how every surface keeps a user's files safe.

use std::collections::BTreeSet;
use std::fs::{File, TryLockError};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

use serde::{Deserialize, Serialize};

use crate::atomic::sync_directory;

/// A command that writes into an output folder: its name, its marker, its scratch folder, the
/// files it writes at the folder's top (beside a folder per log or session), and how its users
/// name the folder and `force` in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tool {
    /// The command, as the marker's `written_by` and the messages name it (`loops run`).
    pub command: &'static str,
    /// The marker's file name (`loops-run.json`).
    pub marker: &'static str,
    /// The scratch folder's name (`.loops-run.partial`).
    pub scratch: &'static str,
    /// The files it writes at the top of the folder.
    pub top_files: &'static [&'static str],
    /// The folder's name in messages (`--out`).
    pub out_flag: &'static str,
    /// How to ask for `force` in messages (`--force`).
    pub force_flag: &'static str,
}

impl Tool {
    /// Whether `name` is an entry of the folder the command itself uses (its marker, its scratch
    /// folder or one of its top files): no log or session may be given that name.
    pub fn reserves(&self, name: &str) -> bool {
        name == self.marker || name == self.scratch || name == self.marker_partial() || self.top_files.contains(&name)
    }

    /// The name the marker is written under before it is renamed into place
    /// (`.loops-run.json.partial`): one fixed name, so that a run killed while writing it leaves
    /// nothing the next run cannot recognise as its own.
    pub fn marker_partial(&self) -> String {
        format!(".{}.partial", self.marker)
    }
}

/// `loops run`: `loops-run.json`, `index.html` and `summary.json`.
pub const RUN: Tool = Tool {
    command: "loops run",
    marker: "loops-run.json",
    scratch: ".loops-run.partial",
    top_files: &["index.html", "summary.json"],
    out_flag: "--out",
    force_flag: "--force",
};

/// `loops fleet`: `loops-fleet.json` and the fleet's files.
pub const FLEET: Tool = Tool {
    command: "loops fleet",
    marker: "loops-fleet.json",
    scratch: ".loops-fleet.partial",
    top_files: &[
        "index.html",
        "components.csv",
        "session_pairs.csv",
        "samples.csv",
        "samples.g2o",
        "summary.json",
        "results.mcap",
        "foxglove-layout.json",
    ],
    out_flag: "--out",
    force_flag: "--force",
};

/// `loops-dask` (and Python's `run_fleet_dask`): `loops-dask.json` and the fleet's tables.
pub const DASK: Tool = Tool {
    command: "loops-dask",
    marker: "loops-dask.json",
    scratch: ".loops-dask.partial",
    top_files: &[
        "components.parquet",
        "session_pairs.parquet",
        "samples.parquet",
        "failures.parquet",
        "summary.json",
        "loop_duration",
    ],
    out_flag: "out",
    force_flag: "force=True (--force)",
};

/// A fleet store (`loops fleet --store`, Python's `FleetStore`): `loops-store.json`, the
/// pointer `store.json` and one folder per state (`state-000001`, ...).
pub const STORE: Tool = Tool {
    command: "loops fleet --store",
    marker: "loops-store.json",
    scratch: ".loops-store.partial",
    top_files: &["store.json"],
    out_flag: "--store",
    force_flag: "a new --store folder",
};

/// Every command that takes an output folder, for naming the holder of a lock and for
/// [`Tool::named`].
pub const TOOLS: [&Tool; 4] = [&RUN, &FLEET, &DASK, &STORE];

impl Tool {
    /// The tool whose command is `command` (`"loops run"`, `"loops fleet"`, `"loops-dask"`).
    pub fn named(command: &str) -> Option<Tool> {
        TOOLS.iter().find(|tool| tool.command == command).map(|tool| **tool)
    }
}

/// Why an output folder was refused, or an entry of it not written. Each message names the
/// folder or the entry, and what to do.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutDirError {
    /// Another run holds the folder.
    #[error("{flag} {} is in use by another {holder}; wait for it to finish or choose another {flag}", .path.display())]
    InUse {
        /// The folder.
        path: PathBuf,
        /// How the folder is named in messages.
        flag: &'static str,
        /// The holder: its command and pid, as far as its marker tells.
        holder: String,
    },
    /// The folder holds something and `force` was not given.
    #[error("{flag} {} exists and is not empty; pass {force} to replace the results of an earlier run", .path.display())]
    NotEmpty {
        /// The folder.
        path: PathBuf,
        /// How the folder is named in messages.
        flag: &'static str,
        /// How to ask for `force`.
        force: &'static str,
    },
    /// The folder holds an entry of the command's name that the command did not write.
    #[error(
        "{flag} {} holds {name}, which `{command}` did not write (it is not listed in {marker}); not replacing it: \
         move it away or choose another {flag}",
        .path.display()
    )]
    NotOurs {
        /// The folder.
        path: PathBuf,
        /// How the folder is named in messages.
        flag: &'static str,
        /// The entry.
        name: String,
        /// The command.
        command: &'static str,
        /// Its marker's name.
        marker: &'static str,
    },
    /// An entry to be replaced exists and `force` was not given.
    #[error("{} exists; pass {force} to replace it", .path.display())]
    Exists {
        /// The entry.
        path: PathBuf,
        /// How to ask for `force`.
        force: &'static str,
    },
    /// An entry to be replaced exists and is not one the command wrote.
    #[error("{} exists and is not an output of `{command}`; not replacing it", .path.display())]
    NotAnOutput {
        /// The entry.
        path: PathBuf,
        /// The command.
        command: &'static str,
    },
    /// A file named like the command's marker is not its marker.
    #[error("{} is not the marker of `{command}`; not touching the folder", .path.display())]
    NotMarker {
        /// The file.
        path: PathBuf,
        /// The command.
        command: &'static str,
    },
    /// The operating system refused.
    #[error("{what} {}: {error}", .path.display())]
    Io {
        /// What was being done (`reading`, `locking`, `renaming ... to`).
        what: String,
        /// The file or folder.
        path: PathBuf,
        /// What the operating system said.
        error: io::Error,
    },
}

fn io_error(what: impl Into<String>, path: &Path) -> impl FnOnce(io::Error) -> OutDirError {
    let (what, path) = (what.into(), path.to_path_buf());
    move |error| OutDirError::Io { what, path, error }
}

/// The marker: what the command wrote in the folder.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Marker {
    /// Always the tool's command (`loops run`): the marker is ours.
    written_by: String,
    /// The version of inexact-loops that wrote it last.
    version: String,
    /// The process of the run that wrote it last: while a run holds the lock, that run.
    pid: u32,
    /// The entries of the folder the command wrote (file and folder names), sorted.
    entries: BTreeSet<String>,
    /// The scratch folder, once a run created it (absent in markers of earlier versions, which
    /// kept no scratch folder: then nothing is removed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scratch: Option<String>,
}

/// An output folder this process holds: locked, its marker, and its scratch folder. See the
/// [module](self) for the rules.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use std::io::Write;
/// use loops_io::out_dir::{OutDir, OutDirError, RUN};
///
/// let out = std::env::temp_dir().join(format!("loops-io-out-dir-{}", std::process::id()));
/// # let _ = std::fs::remove_dir_all(&out);
/// std::fs::create_dir(&out)?;
/// let dir = OutDir::take(&out, false, RUN)?;
/// dir.write_file("summary.json", |file| file.write_all(b"{}\n"))?;
/// drop(dir);
/// // A user's file is never replaced, force or not.
/// std::fs::write(out.join("index.html"), "mine")?;
/// assert!(matches!(OutDir::take(&out, true, RUN), Err(OutDirError::NotOurs { .. })));
/// assert_eq!(std::fs::read_to_string(out.join("index.html"))?, "mine");
/// # std::fs::remove_dir_all(&out)?;
/// # Ok(())
/// # }
/// ```
#[derive(Debug)]
pub struct OutDir {
    path: PathBuf,
    tool: Tool,
    force: bool,
    marker: Mutex<Marker>,
    /// Names in the scratch folder: a counter, so that no name grows with a log's.
    next: AtomicU64,
    /// Whether [`take`](Self::take) removed the scratch folder of a killed run.
    cleaned: bool,
    /// Held until dropped (the lock goes with the file).
    _lock: File,
}

impl OutDir {
    /// Takes `out` (which must exist) for this run of `tool`: locks it, removes the scratch
    /// folder a killed run of `tool` left (only when its marker lists it), and refuses, before
    /// any work, an `out` that holds anything but an earlier run's results (without `force`:
    /// anything at all) or that holds a file of `tool`'s name it did not write. Then records
    /// this run in the marker and creates the scratch folder.
    ///
    /// # Errors
    /// [`OutDirError::InUse`], [`NotEmpty`](OutDirError::NotEmpty),
    /// [`NotOurs`](OutDirError::NotOurs), [`NotMarker`](OutDirError::NotMarker), or
    /// [`Io`](OutDirError::Io) when the folder cannot be read, locked or written.
    pub fn take(out: &Path, force: bool, tool: Tool) -> Result<Self, OutDirError> {
        let lock = lock(out, tool)?;
        let previous = read_marker(&out.join(tool.marker), tool)?;
        let owned = previous.as_ref().map(|m| m.entries.clone()).unwrap_or_default();
        let cleaned = previous.as_ref().and_then(|m| m.scratch.as_deref()) == Some(tool.scratch)
            && remove_scratch(&out.join(tool.scratch))?;
        let partial = out.join(tool.marker_partial());
        if is_marker_partial(&partial, tool) {
            std::fs::remove_file(&partial).map_err(io_error("removing", &partial))?;
        }
        let entries = entries(out, tool)?;
        if !entries.is_empty() && !force {
            return Err(OutDirError::NotEmpty { path: out.to_path_buf(), flag: tool.out_flag, force: tool.force_flag });
        }
        // In the tool's order, so that the message names the same entry every time.
        let partial_name = tool.marker_partial();
        let reserved = tool.top_files.iter().copied().chain([tool.scratch, partial_name.as_str()]);
        for name in reserved.filter(|name| entries.iter().any(|e| e == name)) {
            if !owned.contains(name) {
                return Err(OutDirError::NotOurs {
                    path: out.to_path_buf(),
                    flag: tool.out_flag,
                    name: name.to_owned(),
                    command: tool.command,
                    marker: tool.marker,
                });
            }
        }
        let marker = Marker {
            written_by: tool.command.to_owned(),
            version: env!("CARGO_PKG_VERSION").to_owned(),
            pid: std::process::id(),
            entries: owned,
            scratch: Some(tool.scratch.to_owned()),
        };
        let dir = Self {
            path: out.to_path_buf(),
            tool,
            force,
            marker: Mutex::new(marker),
            next: AtomicU64::new(0),
            cleaned,
            _lock: lock,
        };
        // Listed before it is created: the scratch folder is never ours unlisted.
        dir.save()?;
        let scratch = dir.scratch();
        std::fs::create_dir(&scratch).map_err(io_error("creating", &scratch))?;
        Ok(dir)
    }

    /// Whether [`take`](Self::take) removed what a killed run left in the scratch folder (for a
    /// command to say so).
    pub fn cleaned_up(&self) -> bool {
        self.cleaned
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The command that holds the folder.
    pub fn tool(&self) -> Tool {
        self.tool
    }

    /// Whether `force` was given: listed entries may be replaced.
    pub fn force(&self) -> bool {
        self.force
    }

    /// The scratch folder, where entries are filled before they are moved into place.
    pub fn scratch(&self) -> PathBuf {
        self.path.join(self.tool.scratch)
    }

    /// Whether `name` (an entry of the folder) is listed in the marker: the command wrote it.
    pub fn owns(&self, name: &str) -> bool {
        self.marker().entries.contains(name)
    }

    /// The entries the marker lists, sorted.
    pub fn entries(&self) -> Vec<String> {
        self.marker().entries.iter().cloned().collect()
    }

    fn marker(&self) -> std::sync::MutexGuard<'_, Marker> {
        self.marker.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Lists `name` in the marker (before it is written, so that it is never ours unlisted).
    ///
    /// # Errors
    /// [`OutDirError::Io`] when the marker cannot be written.
    pub fn claim(&self, name: &str) -> Result<(), OutDirError> {
        let added = self.marker().entries.insert(name.to_owned());
        if added { self.save() } else { Ok(()) }
    }

    /// A new path in the scratch folder, for one file or folder to fill and then
    /// [`place`](Self::place). Nothing is created.
    pub fn staging_path(&self) -> PathBuf {
        self.scratch().join(self.next.fetch_add(1, Ordering::Relaxed).to_string())
    }

    /// Writes the file `name` of the folder through `fill`: filled in the scratch folder, synced,
    /// then [`place`](Self::place)d (`owned` as [`owns`](Self::owns) says).
    ///
    /// # Errors
    /// As [`place`](Self::place); [`OutDirError::Io`] when the file cannot be written.
    pub fn write_file(&self, name: &str, fill: impl FnOnce(&mut File) -> io::Result<()>) -> Result<(), OutDirError> {
        let staged = self.staging_path();
        let filled = File::create_new(&staged).and_then(|mut file| {
            fill(&mut file)?;
            file.sync_all()
        });
        if let Err(error) = filled {
            let _ = std::fs::remove_file(&staged);
            return Err(OutDirError::Io { what: "writing".to_owned(), path: self.path.join(name), error });
        }
        self.place(&staged, name, self.owns(name))
    }

    /// Moves the filled file or folder `staged` (a [`staging_path`](Self::staging_path)) into
    /// place as the entry `name`, listing `name` in the marker first. An existing entry is
    /// replaced only with `force`, and only when `owned` (the caller's word that the command
    /// wrote it: at least [`owns`](Self::owns)) and of the same kind (a file for a file, a folder
    /// for a folder, never a link): never a file or folder of the user's. A replaced entry is
    /// moved into the scratch folder first, then removed. `staged` is removed when it cannot be
    /// placed.
    ///
    /// # Errors
    /// [`OutDirError::Exists`] without `force`, [`OutDirError::NotAnOutput`] for an entry that
    /// is not the command's, [`OutDirError::Io`] when a rename fails.
    pub fn place(&self, staged: &Path, name: &str, owned: bool) -> Result<(), OutDirError> {
        let placed = self.try_place(staged, name, owned);
        if placed.is_err() {
            let _ = remove_entry(staged);
        }
        placed
    }

    fn try_place(&self, staged: &Path, name: &str, owned: bool) -> Result<(), OutDirError> {
        let target = self.path.join(name);
        let existing = target.symlink_metadata().ok();
        if let Some(existing) = &existing {
            if !self.force {
                return Err(OutDirError::Exists { path: target, force: self.tool.force_flag });
            }
            let same_kind = staged.symlink_metadata().is_ok_and(|s| s.is_dir() == existing.is_dir());
            if !owned || !self.owns(name) || existing.is_symlink() || !same_kind {
                return Err(OutDirError::NotAnOutput { path: target, command: self.tool.command });
            }
        }
        self.claim(name)?;
        if existing.is_some() {
            let old = self.staging_path();
            std::fs::rename(&target, &old).map_err(io_error("moving aside the old", &target))?;
            if let Err(error) = std::fs::rename(staged, &target) {
                let _ = std::fs::rename(&old, &target);
                return Err(OutDirError::Io { what: format!("renaming {} to", staged.display()), path: target, error });
            }
            let _ = remove_entry(&old);
        } else {
            std::fs::rename(staged, &target).map_err(io_error(format!("renaming {} to", staged.display()), &target))?;
        }
        sync_directory(&self.path).map_err(io_error("syncing", &self.path))
    }

    /// Moves the filled file `staged` onto the file `name` in one rename, so that a reader finds
    /// the old file or the new one, never neither (a store's pointer to its state). `name` must
    /// be absent or a file the command wrote ([`owns`](Self::owns)); `staged` is removed when it
    /// cannot be placed.
    ///
    /// # Errors
    /// [`OutDirError::NotAnOutput`] for an entry that is not the command's file,
    /// [`OutDirError::Io`] when the rename fails.
    pub fn swap_file(&self, staged: &Path, name: &str) -> Result<(), OutDirError> {
        let target = self.path.join(name);
        let swapped = (|| {
            if let Ok(existing) = target.symlink_metadata()
                && (!self.owns(name) || !existing.is_file())
            {
                return Err(OutDirError::NotAnOutput { path: target.clone(), command: self.tool.command });
            }
            self.claim(name)?;
            std::fs::rename(staged, &target).map_err(io_error(format!("renaming {} to", staged.display()), &target))?;
            sync_directory(&self.path).map_err(io_error("syncing", &self.path))
        })();
        if swapped.is_err() {
            let _ = remove_entry(staged);
        }
        swapped
    }

    /// Removes the entry `name`, when the command wrote it (an earlier run's); anything else of
    /// that name is left alone. Returns whether an entry was removed.
    ///
    /// # Errors
    /// [`OutDirError::Io`] when it cannot be removed.
    pub fn remove(&self, name: &str) -> Result<bool, OutDirError> {
        let path = self.path.join(name);
        if !self.owns(name) || path.symlink_metadata().is_err() {
            return Ok(false);
        }
        let old = self.staging_path();
        std::fs::rename(&path, &old).map_err(io_error("removing", &path))?;
        remove_entry(&old).map_err(io_error("removing", &path))?;
        Ok(true)
    }

    /// Writes the marker, atomically: under [`Tool::marker_partial`], synced, then renamed into
    /// place. (Not through a temporary file of a random name: a run killed while writing it
    /// would leave a file the next run could not tell from a user's.)
    fn save(&self) -> Result<(), OutDirError> {
        let marker = self.marker().clone();
        let path = self.path.join(self.tool.marker);
        let partial = self.path.join(self.tool.marker_partial());
        let json = serde_json::to_string_pretty(&marker).map_err(io::Error::other).map(|json| json + "\n");
        let written = json.and_then(|json| {
            let mut file = File::create(&partial)?;
            file.write_all(json.as_bytes())?;
            file.sync_all()?;
            std::fs::rename(&partial, &path)?;
            sync_directory(&self.path)
        });
        written.map_err(|error| {
            let _ = std::fs::remove_file(&partial);
            OutDirError::Io { what: "writing".to_owned(), path, error }
        })
    }
}

impl Drop for OutDir {
    /// Removes the scratch folder (what a failed or finished run left in it); the marker keeps
    /// listing it, so that a run killed later is cleaned up too.
    fn drop(&mut self) {
        let _ = remove_scratch(&self.scratch());
    }
}

/// Refuses, before any work, an existing `out` that holds anything (but the tool's marker and
/// the scratch folder its marker lists) without `force`: the first check of [`OutDir::take`],
/// for a command that reads its input before it takes the folder.
///
/// # Errors
/// [`OutDirError::NotEmpty`], or [`OutDirError::Io`] when the folder cannot be read.
pub fn refuse_non_empty(out: &Path, force: bool, tool: Tool) -> Result<(), OutDirError> {
    if force || !out.is_dir() {
        return Ok(());
    }
    let mut entries = entries(out, tool)?;
    let scratch = read_marker(&out.join(tool.marker), tool).ok().flatten().and_then(|m| m.scratch);
    entries.retain(|name| Some(name) != scratch.as_ref());
    if entries.is_empty() {
        Ok(())
    } else {
        Err(OutDirError::NotEmpty { path: out.to_path_buf(), flag: tool.out_flag, force: tool.force_flag })
    }
}

/// Locks `out` for this process, or says who holds it: writes nothing (what a command that
/// may leave the folder as it is holds while it reads).
pub(crate) fn lock(out: &Path, tool: Tool) -> Result<File, OutDirError> {
    #[cfg(unix)]
    let file = File::open(out).map_err(io_error("opening", out))?;
    #[cfg(not(unix))]
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(out.join(".loops-run.lock"))
        .map_err(io_error("opening the lock of", out))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(TryLockError::WouldBlock) => {
            let holder = TOOLS.iter().find_map(|other| {
                read_marker(&out.join(other.marker), **other).ok().flatten().map(|m| (other.command, m.pid))
            });
            let holder = match holder {
                Some((command, pid)) => format!("`{command}` (pid {pid})"),
                None => format!("`{}` or another command of inexact-loops (pid unknown)", tool.command),
            };
            Err(OutDirError::InUse { path: out.to_path_buf(), flag: tool.out_flag, holder })
        }
        Err(TryLockError::Error(error)) => Err(OutDirError::Io { what: "locking".to_owned(), path: out.into(), error }),
    }
}

/// The marker of `tool` at `path`, if there is one; an error when the file is not its marker.
fn read_marker(path: &Path, tool: Tool) -> Result<Option<Marker>, OutDirError> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(error) if error.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(error) => return Err(OutDirError::Io { what: "reading".to_owned(), path: path.to_path_buf(), error }),
    };
    match serde_json::from_str::<Marker>(&text) {
        Ok(marker) if marker.written_by == tool.command => Ok(Some(marker)),
        _ => Err(OutDirError::NotMarker { path: path.to_path_buf(), command: tool.command }),
    }
}

/// Whether the file at `path` is a marker of `tool` being written when its run was killed: a
/// regular file whose bytes agree with the start every marker of `tool` has
/// (`{"written_by": "loops run", ...`, as written) as far as either goes.
fn is_marker_partial(path: &Path, tool: Tool) -> bool {
    if !path.symlink_metadata().is_ok_and(|m| m.is_file()) {
        return false;
    }
    let header = format!("{{\n  \"written_by\": \"{}\",", tool.command);
    let mut start = Vec::with_capacity(header.len());
    let read = File::open(path).and_then(|file| {
        use std::io::Read;
        file.take(header.len() as u64).read_to_end(&mut start)
    });
    read.is_ok() && header.as_bytes().starts_with(&start)
}

/// The entries of `out` but the tool's marker, by name.
fn entries(out: &Path, tool: Tool) -> Result<Vec<String>, OutDirError> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(out).map_err(io_error("reading", out))? {
        let name = entry.map_err(io_error("reading", out))?.file_name();
        let name = name.to_string_lossy().into_owned();
        if name != tool.marker {
            names.push(name);
        }
    }
    Ok(names)
}

/// Removes the scratch folder at `path`, if it is there (a link of that name is only
/// unlinked, never followed); whether it was.
fn remove_scratch(path: &Path) -> Result<bool, OutDirError> {
    match path.symlink_metadata() {
        Ok(_) => remove_entry(path).map(|()| true).map_err(io_error("removing", path)),
        Err(_) => Ok(false),
    }
}

/// Removes a file, a link or a folder with its contents (links inside are unlinked, not
/// followed: `remove_dir_all`'s rule).
fn remove_entry(path: &Path) -> io::Result<()> {
    let meta = path.symlink_metadata()?;
    if meta.is_dir() { std::fs::remove_dir_all(path) } else { std::fs::remove_file(path) }
}

/// Refuses to write an output onto an input, `force` or not: `output` (a file to be written, or
/// a folder results go into) is refused when it is, or links to, one of `inputs` (files, or
/// folders such as a rosbag2 bag), when it lies inside an input folder, and when an input lies
/// inside it. Links are resolved on both sides, also for paths that do not exist yet, so a link
/// or another spelling of the same file is caught. `what` names the output in the message
/// (`--json`, `--out`).
///
/// # Errors
/// [`OutputOnInput`] naming both paths.
pub fn refuse_output_on_input(what: &str, output: &Path, inputs: &[PathBuf]) -> Result<(), OutputOnInput> {
    let out = resolved(output);
    for input in inputs {
        let input_abs = resolved(input);
        let inside_out = input_abs.starts_with(&out) && input_abs != out;
        if out.starts_with(&input_abs) || inside_out {
            return Err(OutputOnInput {
                what: what.to_owned(),
                output: output.to_path_buf(),
                input: input.clone(),
                input_inside: inside_out,
            });
        }
    }
    Ok(())
}

/// An output that would be written onto an input ([`refuse_output_on_input`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.message())]
pub struct OutputOnInput {
    /// How the output is named (`--json`, `--out`).
    pub what: String,
    /// The output.
    pub output: PathBuf,
    /// The input it would overwrite, or that lies inside it.
    pub input: PathBuf,
    /// Whether the input lies inside the output (a folder), rather than the output on the input.
    pub input_inside: bool,
}

impl OutputOnInput {
    fn message(&self) -> String {
        let (what, output, input) = (&self.what, self.output.display(), self.input.display());
        if self.input_inside {
            format!("{input} lies inside {what} {output}; write the results elsewhere")
        } else {
            format!(
                "{what} {output} would overwrite the input {input}; refusing to write onto an input, --force or not"
            )
        }
    }
}

/// `path` with every link resolved ([`std::fs::canonicalize`]), also when it does not exist yet:
/// its longest existing ancestor resolved, and the rest appended. The absolute path as given when
/// nothing of it can be resolved.
pub fn resolved(path: &Path) -> PathBuf {
    let Ok(absolute) = std::path::absolute(path) else { return path.to_path_buf() };
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    loop {
        match std::fs::canonicalize(existing) {
            Ok(real) => return rest.iter().rev().fold(real, |dir, part| dir.join(part)),
            Err(_) => match (existing.parent(), existing.file_name()) {
                (Some(parent), Some(name)) => {
                    rest.push(name.to_owned());
                    existing = parent;
                }
                _ => return absolute,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("loops-io-out-dir-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn entries_shaped_like_leftovers_are_the_users() {
        let out = scratch_dir("leftovers");
        std::fs::create_dir(out.join(".thesis.partial-2024")).unwrap();
        std::fs::write(out.join(".thesis.partial-2024/ch1.tex"), "work").unwrap();
        std::fs::write(out.join(".notes.backup.tmp"), "draft").unwrap();
        std::fs::create_dir(out.join(".a.old-12")).unwrap();
        let before = names(&out);
        assert!(matches!(OutDir::take(&out, false, RUN), Err(OutDirError::NotEmpty { .. })));
        assert_eq!(names(&out), before);
        // With force they stay too, and a run goes ahead beside them.
        let dir = OutDir::take(&out, true, RUN).unwrap();
        dir.write_file("summary.json", |f| f.write_all(b"{}")).unwrap();
        drop(dir);
        assert_eq!(std::fs::read_to_string(out.join(".thesis.partial-2024/ch1.tex")).unwrap(), "work");
        assert_eq!(std::fs::read_to_string(out.join(".notes.backup.tmp")).unwrap(), "draft");
        assert_eq!(
            names(&out),
            [".a.old-12", ".notes.backup.tmp", ".thesis.partial-2024", "loops-run.json", "summary.json"]
        );
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn the_scratch_folder_of_a_killed_run_goes_only_when_listed() {
        let out = scratch_dir("killed");
        let dir = OutDir::take(&out, false, RUN).unwrap();
        let half = dir.staging_path();
        drop(dir);
        // What a killed run leaves: its scratch folder with work in progress, listed in the marker.
        std::fs::create_dir(out.join(RUN.scratch)).unwrap();
        std::fs::write(half, "half").unwrap();
        drop(OutDir::take(&out, false, RUN).unwrap());
        assert_eq!(names(&out), ["loops-run.json"]);
        // A scratch-named folder the marker does not list (a marker of an earlier version) stays.
        std::fs::write(out.join(RUN.marker), r#"{"written_by":"loops run","version":"0","pid":1,"entries":[]}"#)
            .unwrap();
        std::fs::create_dir(out.join(RUN.scratch)).unwrap();
        std::fs::write(out.join(RUN.scratch).join("mine"), "x").unwrap();
        assert!(matches!(OutDir::take(&out, false, RUN), Err(OutDirError::NotEmpty { .. })));
        assert!(matches!(OutDir::take(&out, true, RUN), Err(OutDirError::NotOurs { .. })));
        assert_eq!(std::fs::read_to_string(out.join(RUN.scratch).join("mine")).unwrap(), "x");
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn a_marker_cut_short_by_a_kill_is_recognised_and_a_users_file_of_its_name_is_not() {
        let out = scratch_dir("partial");
        drop(OutDir::take(&out, false, RUN).unwrap());
        let partial = out.join(RUN.marker_partial());
        for cut in ["", "{\n  \"writ", "{\n  \"written_by\": \"loops run\",\n  \"version\": \"0."] {
            std::fs::write(&partial, cut).unwrap();
            drop(OutDir::take(&out, false, RUN).unwrap());
            assert_eq!(names(&out), ["loops-run.json"], "{cut:?}");
        }
        std::fs::write(&partial, "notes of mine").unwrap();
        assert!(matches!(OutDir::take(&out, false, RUN), Err(OutDirError::NotEmpty { .. })));
        assert!(matches!(OutDir::take(&out, true, RUN), Err(OutDirError::NotOurs { .. })));
        assert_eq!(std::fs::read_to_string(&partial).unwrap(), "notes of mine");
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn only_listed_entries_of_the_same_kind_are_replaced() {
        let out = scratch_dir("replace");
        let dir = OutDir::take(&out, false, FLEET).unwrap();
        dir.write_file("components.csv", |f| f.write_all(b"1")).unwrap();
        let staged = dir.staging_path();
        std::fs::create_dir(&staged).unwrap();
        dir.place(&staged, "car0", true).unwrap();
        drop(dir);
        std::fs::write(out.join("mine.txt"), "mine").unwrap();
        let dir = OutDir::take(&out, true, FLEET).unwrap();
        dir.write_file("components.csv", |f| f.write_all(b"2")).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("components.csv")).unwrap(), "2");
        // A file over an owned folder, and an entry not listed, are refused.
        let refused = dir.write_file("car0", |f| f.write_all(b"x"));
        assert!(matches!(refused, Err(OutDirError::NotAnOutput { .. })), "{refused:?}");
        let refused = dir.write_file("mine.txt", |f| f.write_all(b"x"));
        assert!(matches!(refused, Err(OutDirError::NotAnOutput { .. })), "{refused:?}");
        assert!(!dir.remove("mine.txt").unwrap());
        assert!(dir.remove("car0").unwrap());
        drop(dir);
        assert_eq!(std::fs::read_to_string(out.join("mine.txt")).unwrap(), "mine");
        assert_eq!(names(&out), ["components.csv", "loops-fleet.json", "mine.txt"]);
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn a_second_holder_is_refused() {
        let out = scratch_dir("held");
        let dir = OutDir::take(&out, false, DASK).unwrap();
        let error = OutDir::take(&out, true, RUN).unwrap_err();
        assert!(error.to_string().contains("in use by another `loops-dask`"), "{error}");
        drop(dir);
        assert!(OutDir::take(&out, true, DASK).is_ok());
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn outputs_on_inputs_are_refused_through_links() {
        let dir = scratch_dir("inputs");
        let log = dir.join("a.mcap");
        std::fs::write(&log, "log").unwrap();
        let bag = dir.join("bag");
        std::fs::create_dir(&bag).unwrap();
        let inputs = [log.clone(), bag.clone()];
        assert!(refuse_output_on_input("--json", &log, &inputs).is_err());
        assert!(refuse_output_on_input("--json", &dir.join("./a.mcap"), &inputs).is_err());
        assert!(refuse_output_on_input("--json", &bag.join("metadata.yaml"), &inputs).is_err());
        assert!(refuse_output_on_input("--json", &dir.join("b.json"), &inputs).is_ok());
        #[cfg(unix)]
        {
            let link = dir.join("link.json");
            std::os::unix::fs::symlink(&log, &link).unwrap();
            let error = refuse_output_on_input("--json", &link, &inputs).unwrap_err();
            assert!(error.to_string().contains("refusing to write onto an input"), "{error}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
