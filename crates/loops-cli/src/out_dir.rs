//! The folder of `loops run` and `loops fleet` (`--out`): one run at a time, and `--force`
//! replaces only what the command wrote there. Each command has its own marker ([`Tool`]), so
//! neither takes the other's files for its own.
//!
//! - **One run owns it.** The run holds an exclusive lock on the folder itself (`flock` through
//!   std's `File::try_lock`, on Unix; a lock file `.loops-run.lock` elsewhere) from before it
//!   looks inside until it exits; the kernel drops the lock when the process ends, however it
//!   ends. A second run into the same folder stops at once, naming the folder and the holder's
//!   pid (recorded in the marker).
//! - **What it wrote, it marks.** The marker [`MARKER`] (`loops-run.json`; `loops-fleet.json`
//!   for `loops fleet`; visible: the folder holds no hidden file after a run) lists every entry
//!   of `--out` that the command wrote: the log (session) folders and its top files
//!   ([`Tool::top_files`]: `index.html`, `summary.json`, ...). An entry is listed before it is moved into
//!   place, so an interrupted run leaves nothing of its own unlisted. With `--force` a listed
//!   entry may be replaced; anything else with the same name (a user's `index.html`, a folder of
//!   theirs with a log's name) never is: a clear error names it. Inside a log folder,
//!   `summary.json` still has to be present, as before.
//! - **Leftovers of killed runs go.** Staging folders (`.NAME.partial-PID`), folders moved aside
//!   (`.NAME.old-PID`) and temporary files (`.FILE.XXXXXX.tmp`) in `--out` belong to runs that
//!   no longer hold the lock, since this one does: they are removed, and said so on stderr.
//!
//! The marker is hand-written JSON of one serde struct; the lock is std's. Nothing here is an
//! algorithm of the product: it is how the CLI keeps a user's files safe.

use std::collections::BTreeSet;
use std::fs::{File, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::guard::{self, Writes};

/// A command that writes into an output folder: its name, its marker (what it wrote there) and
/// the files it writes at the folder's top (beside a folder per log or session).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Tool {
    /// The command, as the marker's `written_by` and the messages name it.
    pub(crate) command: &'static str,
    /// The marker's file name.
    pub(crate) marker: &'static str,
    /// The files it writes at the top of the folder.
    pub(crate) top_files: &'static [&'static str],
}

/// `loops run`: `loops-run.json`, `index.html` and `summary.json`.
pub(crate) const RUN: Tool = Tool { command: "loops run", marker: MARKER, top_files: &TOP_FILES };

/// The marker of an output folder of `loops run`: what it wrote there.
pub(crate) const MARKER: &str = "loops-run.json";

/// The top-level files of a run.
pub(crate) const TOP_FILES: [&str; 2] = ["index.html", "summary.json"];

/// `loops fleet`: `loops-fleet.json` and the fleet's files.
pub(crate) const FLEET: Tool = Tool { command: "loops fleet", marker: "loops-fleet.json", top_files: &FLEET_FILES };

/// The top-level files of `loops fleet`.
pub(crate) const FLEET_FILES: [&str; 6] =
    ["index.html", "components.csv", "session_pairs.csv", "samples.csv", "samples.g2o", "summary.json"];

/// The tools that lock an output folder, for naming the holder of a lock.
const TOOLS: [&Tool; 2] = [&RUN, &FLEET];

/// `loops-run.json` (`loops-fleet.json`, ...).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Marker {
    /// Always the tool's command (`loops run`): the marker is ours.
    written_by: String,
    /// The version of `loops` that wrote it last.
    version: String,
    /// The process of the run that wrote it last: while a run holds the lock, that run.
    pid: u32,
    /// The entries of the folder the command wrote (file and folder names), sorted.
    entries: BTreeSet<String>,
}

/// An output folder this process holds: locked, and its marker.
#[derive(Debug)]
pub(crate) struct OutDir {
    path: PathBuf,
    tool: Tool,
    marker: Mutex<Marker>,
    /// Held until the process ends (the lock goes with the file).
    _lock: File,
}

impl OutDir {
    /// Takes `out` (which must exist) for this run of `tool`: locks it, removes what killed
    /// runs left, and refuses, before any work, an `out` that holds anything but an earlier
    /// run's results (without `force`: anything at all). Then records this run in the marker.
    pub(crate) fn take(out: &Path, force: bool, tool: Tool) -> Result<Self> {
        let lock = lock(out)?;
        let marker_path = out.join(tool.marker);
        let previous = read_marker(&marker_path, tool)?;
        remove_leftovers(out)?;
        let entries = entries(out, tool)?;
        if !entries.is_empty() && !force {
            bail!(
                "--out {} exists and is not empty; pass --force to replace the results of an earlier run",
                out.display()
            );
        }
        let owned = previous.as_ref().map(|m| m.entries.clone()).unwrap_or_default();
        for &name in tool.top_files {
            if entries.iter().any(|e| e == name) && !owned.contains(name) {
                bail!(
                    "--out {} holds {name}, which `{}` did not write (it is not listed in {}); \
                     not replacing it: move it away or choose another --out",
                    out.display(),
                    tool.command,
                    tool.marker
                );
            }
        }
        let marker = Marker {
            written_by: tool.command.to_owned(),
            version: env!("CARGO_PKG_VERSION").to_owned(),
            pid: std::process::id(),
            entries: owned,
        };
        let dir = Self { path: out.to_path_buf(), tool, marker: Mutex::new(marker), _lock: lock };
        guard::with_writes(|writes| dir.save(writes))?;
        Ok(dir)
    }

    /// The command that holds the folder.
    pub(crate) fn command(&self) -> &'static str {
        self.tool.command
    }

    /// Whether `name` (an entry of the folder) was written by this command.
    pub(crate) fn owns(&self, name: &str) -> bool {
        self.marker.lock().unwrap_or_else(PoisonError::into_inner).entries.contains(name)
    }

    /// Lists `name` in the marker (before it is written, so that it is never ours unlisted),
    /// under the write lock of [`guard`] (`writes`).
    pub(crate) fn claim(&self, writes: &mut Writes, name: &str) -> Result<()> {
        let added = self.marker.lock().unwrap_or_else(PoisonError::into_inner).entries.insert(name.to_owned());
        if added { self.save(writes) } else { Ok(()) }
    }

    /// Writes the marker, atomically, under the write lock of [`guard`] (`writes`).
    fn save(&self, writes: &mut Writes) -> Result<()> {
        let marker = self.marker.lock().unwrap_or_else(PoisonError::into_inner).clone();
        let json = serde_json::to_string_pretty(&marker)? + "\n";
        let path = self.path.join(self.tool.marker);
        writes.marker(&path);
        loops_io::write_atomically(&path, true, |file| file.write_all(json.as_bytes()))
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// Refuses, before any work, an existing `out` that holds anything (but the tool's marker and
/// what killed runs left) without `force`: the first check of [`OutDir::take`], for a command
/// that reads its input before it takes the folder.
pub(crate) fn refuse_non_empty(out: &Path, force: bool, tool: Tool) -> Result<()> {
    if force || !out.is_dir() {
        return Ok(());
    }
    let mut entries = entries(out, tool)?;
    entries.retain(|name| !is_leftover(name, out.join(name).is_dir()));
    if !entries.is_empty() {
        bail!("--out {} exists and is not empty; pass --force to replace the results of an earlier run", out.display());
    }
    Ok(())
}

/// Locks `out` for this process, or says who holds it.
fn lock(out: &Path) -> Result<File> {
    #[cfg(unix)]
    let file = File::open(out).with_context(|| format!("opening {}", out.display()))?;
    #[cfg(not(unix))]
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(out.join(".loops-run.lock"))
        .with_context(|| format!("opening the lock of {}", out.display()))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(TryLockError::WouldBlock) => {
            let holder = TOOLS.iter().find_map(|tool| {
                read_marker(&out.join(tool.marker), **tool).ok().flatten().map(|m| (tool.command, m.pid))
            });
            let holder = match holder {
                Some((command, pid)) => format!("`{command}` (pid {pid})"),
                None => "`loops run` or `loops fleet` (pid unknown)".to_owned(),
            };
            bail!(
                "--out {} is in use by another {holder}; wait for it to finish or choose another --out",
                out.display()
            )
        }
        Err(TryLockError::Error(error)) => Err(error).with_context(|| format!("locking {}", out.display())),
    }
}

/// The marker of `tool` at `path`, if there is one; an error when the file is not its marker.
fn read_marker(path: &Path, tool: Tool) -> Result<Option<Marker>> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(error) => return Err(error).with_context(|| format!("reading {}", path.display())),
    };
    match serde_json::from_str::<Marker>(&text) {
        Ok(marker) if marker.written_by == tool.command => Ok(Some(marker)),
        _ => bail!("{} is not the marker of `{}`; not touching the folder", path.display(), tool.command),
    }
}

/// The entries of `out` but the tool's marker, by name.
fn entries(out: &Path, tool: Tool) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))? {
        let name = entry.with_context(|| format!("reading {}", out.display()))?.file_name();
        let name = name.to_string_lossy().into_owned();
        if name != tool.marker {
            names.push(name);
        }
    }
    Ok(names)
}

/// Whether `name` is an entry a killed run of `loops` leaves: `.NAME.partial-PID` or
/// `.NAME.old-PID` (folders), `.FILE.XXXXXX.tmp` (files of the atomic writer).
pub(crate) fn is_leftover(name: &str, is_dir: bool) -> bool {
    let Some(rest) = name.strip_prefix('.') else { return false };
    let pid_suffix = |tag: &str| {
        rest.rsplit_once(tag)
            .is_some_and(|(stem, pid)| !stem.is_empty() && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
    };
    if is_dir {
        pid_suffix(".partial-") || pid_suffix(".old-")
    } else {
        // tempfile's random part: six letters and digits.
        rest.strip_suffix(".tmp").and_then(|r| r.rsplit_once('.')).is_some_and(|(file, random)| {
            !file.is_empty() && random.len() == 6 && random.bytes().all(|b| b.is_ascii_alphanumeric())
        })
    }
}

/// Removes what killed runs left in `out` (this process holds the lock: no live run writes
/// there), and says so on stderr.
fn remove_leftovers(out: &Path) -> Result<()> {
    let mut removed = Vec::new();
    for entry in std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))? {
        let entry = entry.with_context(|| format!("reading {}", out.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if !is_leftover(&name, is_dir) {
            continue;
        }
        let path = entry.path();
        if is_dir { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) }
            .with_context(|| format!("removing {}, left by an interrupted run", path.display()))?;
        removed.push(name);
    }
    if !removed.is_empty() {
        removed.sort();
        eprintln!(
            "loops: removed {} leftover(s) of an interrupted run from {}: {}",
            removed.len(),
            out.display(),
            removed.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leftovers_are_told_by_name() {
        for (name, dir) in [(".a.partial-123", true), (".drive-2.old-9", true), (".summary.json.Ab12xZ.tmp", false)] {
            assert!(is_leftover(name, dir), "{name}");
        }
        for (name, dir) in [
            ("a.partial-123", true),
            (".a.partial-", true),
            (".a.partial-12x", true),
            (".partial-12", true),
            (".git", true),
            (".a.partial-123", false),
            (".notes.tmp", false),
            (".my.notes.tmp", false),
            ("x.tmp", false),
            (".summary.json.Ab12xZ.tmp", true),
        ] {
            assert!(!is_leftover(name, dir), "{name}");
        }
    }
}
