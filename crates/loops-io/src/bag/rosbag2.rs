//! rosbag2 bags as users name them: the folder, its `metadata.yaml`, or one storage file; the
//! storage files in order, with their storage plugin and file compression.
//!
//! `metadata.yaml` is read with `serde_yaml_ng` (serde derive on the few fields needed). Among
//! the YAML crates that build here, it is the maintained continuation of `serde_yaml` (archived
//! in 2024) with the same API and the same YAML 1.1 behaviour that rosbag2's own writer (yaml-cpp)
//! targets, it reports errors with a line, and it keeps serde's derive, which `yaml-rust2` (a
//! DOM without serde) would make us replace by hand-written field lookups. `serde_norway` is a
//! fork of the same code with fewer users.
//!
//! The fields read: `storage_identifier` (`sqlite3` or `mcap`), `relative_file_paths` (the
//! splits, in recording order; else `files[].path`), `compression_format` (`zstd`; `lz4` for
//! third-party plugins) and `compression_mode` (`FILE`: each storage file is compressed as a
//! whole and named `*.zstd`; `MESSAGE`: each message is compressed, which the CDR decoder
//! recognises by the frame's magic number whatever the metadata says); and the message counts,
//! `message_count` (the bag's), `topics_with_message_count` (each topic's) and
//! `files[].message_count` (each storage file's). Everything else (durations, QoS) is ignored.
//!
//! The storage files hold the messages, and the metadata says what they should hold. Two
//! checks keep a bag from being read short without a word:
//! - the folder's storage files are the ones the metadata lists: a `.db3` or `.mcap` file
//!   (compressed or not) in the folder that the metadata does not list is an error, as is a
//!   listed file that is missing. A split left out of `relative_file_paths` (a bag copied in
//!   parts, a metadata file written before the last split) would otherwise be skipped;
//! - after the walk ([`Rosbag2::check_counts`]), a storage file, a topic or the bag with fewer
//!   messages than the metadata counts is an error naming the counts. More messages than
//!   counted are read: a recording stopped before its metadata was last written leaves it
//!   short, and nothing is lost then. Metadata without counts (written by hand, by tools that
//!   leave them out) is not checked.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::compression::Frame;
use crate::error::{IoError, Result};

/// A storage plugin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Storage {
    Sqlite3,
    Mcap,
}

/// One storage file of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct StorageFile {
    /// The file as it is on disk (compressed, for file compression).
    pub(crate) path: PathBuf,
    pub(crate) storage: Storage,
    /// How the whole file is compressed, if it is.
    pub(crate) compression: Option<Frame>,
}

/// The storage files of a bag, in order, and the message counts its metadata declares.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Rosbag2 {
    pub(crate) files: Vec<StorageFile>,
    /// The counts of `metadata.yaml` (none without one).
    counts: Option<Counts>,
}

/// The message counts a `metadata.yaml` declares, each where it gives one.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Counts {
    /// The metadata file, which errors name.
    metadata: PathBuf,
    /// `message_count`: the bag's.
    total: Option<u64>,
    /// `topics_with_message_count`: each topic's.
    topics: Vec<(String, u64)>,
    /// `files[].message_count`: each storage file's, in the order of [`Rosbag2::files`].
    files: Vec<Option<u64>>,
}

/// The messages read from one storage file, per topic: what [`Rosbag2::check_counts`] checks.
pub(crate) type TopicCounts = BTreeMap<String, u64>;

#[derive(Debug, Deserialize)]
struct MetadataFile {
    rosbag2_bagfile_information: Metadata,
}

#[derive(Debug, Deserialize)]
struct Metadata {
    #[serde(default)]
    storage_identifier: Option<String>,
    #[serde(default)]
    relative_file_paths: Vec<String>,
    #[serde(default)]
    files: Vec<FileEntry>,
    #[serde(default)]
    compression_format: Option<String>,
    #[serde(default)]
    compression_mode: Option<String>,
    #[serde(default)]
    message_count: Option<u64>,
    #[serde(default)]
    topics_with_message_count: Vec<TopicEntry>,
}

#[derive(Debug, Deserialize)]
struct FileEntry {
    path: String,
    #[serde(default)]
    message_count: Option<u64>,
}

#[derive(Debug, Deserialize)]
struct TopicEntry {
    topic_metadata: TopicMetadata,
    message_count: u64,
}

#[derive(Debug, Deserialize)]
struct TopicMetadata {
    name: String,
}

/// The storage a file name says: `.db3` or `.mcap`, under a `.zstd` / `.lz4` compression
/// extension or not; and that compression.
fn storage_of_name(path: &Path) -> Option<(Storage, Option<Frame>)> {
    let compression = Frame::of_name(path);
    let inner = if compression.is_some() { Path::new(path.file_stem()?) } else { path };
    let storage = match inner.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "db3" => Storage::Sqlite3,
        "mcap" => Storage::Mcap,
        _ => return None,
    };
    Some((storage, compression))
}

/// Whether `path` names a YAML file (a bag's `metadata.yaml`).
pub(crate) fn is_yaml(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"))
}

/// Whether `path` names a storage file (`.db3`, `.mcap`, compressed or not).
pub(crate) fn is_storage(path: &Path) -> bool {
    storage_of_name(path).is_some()
}

/// The file name of `path` without its extension, and without a storage extension under a
/// compression one: `drive.db3.zstd` is `drive`, `drive.tum` is `drive`.
pub(crate) fn log_stem(path: &Path) -> String {
    let inner = match Frame::of_name(path) {
        Some(_) => path.file_stem().map_or(path, Path::new),
        None => path,
    };
    let stem = if inner != path && storage_of_name(path).is_none() { inner.file_name() } else { inner.file_stem() };
    stem.map_or_else(String::new, |stem| stem.to_string_lossy().into_owned())
}

impl Rosbag2 {
    /// The bag at `path`: a folder (with or without `metadata.yaml`), a `metadata.yaml` (or any
    /// `.yaml` file of a bag), or one storage file (that file alone).
    ///
    /// # Errors
    /// [`IoError::Open`] when the path cannot be read; [`IoError::Parse`] with the line for a
    /// `metadata.yaml` that is not YAML or lacks `rosbag2_bagfile_information`; [`IoError::Bag`]
    /// for a metadata file listing no file or a missing one, a storage or compression this
    /// crate does not read, a folder without metadata or storage files, or a file whose name
    /// is not a storage file's.
    pub(crate) fn resolve(path: &Path) -> Result<Rosbag2> {
        let bag_error = |path: &Path, message: String| IoError::Bag { path: path.to_path_buf(), message };
        if path.is_dir() {
            let metadata = path.join("metadata.yaml");
            if metadata.is_file() {
                return Self::from_metadata(&metadata);
            }
            return Self::from_folder(path);
        }
        let is_yaml = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
        if is_yaml {
            return Self::from_metadata(path);
        }
        std::fs::metadata(path).map_err(|error| IoError::Open { path: path.to_path_buf(), error })?;
        match storage_of_name(path) {
            Some((storage, compression)) => Ok(Rosbag2 {
                files: vec![StorageFile { path: path.to_path_buf(), storage, compression }],
                counts: None,
            }),
            None => Err(bag_error(
                path,
                "not a rosbag2 storage file: expected a .db3 or .mcap file (or .db3.zstd, .mcap.zstd), a bag's folder, \
                 or its metadata.yaml"
                    .to_owned(),
            )),
        }
    }

    fn from_metadata(metadata_path: &Path) -> Result<Rosbag2> {
        let bag_error = |message: String| IoError::Bag { path: metadata_path.to_path_buf(), message };
        let text = read_metadata(metadata_path)?;
        let file: MetadataFile = serde_yaml_ng::from_str(&text).map_err(|error| {
            let line = error.location().map_or(1, |location| location.line());
            IoError::parse(
                metadata_path,
                line,
                format!("not a rosbag2 metadata.yaml: {}", crate::printable::one_line(&error)),
            )
        })?;
        let metadata = file.rosbag2_bagfile_information;
        let folder = metadata_path.parent().unwrap_or(Path::new("."));
        let declared = match metadata.storage_identifier.as_deref().map(str::to_ascii_lowercase).as_deref() {
            Some("sqlite3") => Some(Storage::Sqlite3),
            Some("mcap") => Some(Storage::Mcap),
            None | Some("") => None,
            Some(other) => {
                return Err(bag_error(format!(
                    "storage_identifier {other:?}: this crate reads the sqlite3 and mcap storage plugins"
                )));
            }
        };
        let format = metadata.compression_format.as_deref().unwrap_or("").to_ascii_lowercase();
        let mode = metadata.compression_mode.as_deref().unwrap_or("").to_ascii_lowercase();
        let file_frame = match (mode.as_str(), format.as_str()) {
            ("" | "none", _) | ("message", "zstd" | "lz4") => None,
            ("file", "zstd") => Some(Frame::Zstd),
            ("file", "lz4") => Some(Frame::Lz4),
            ("file" | "message", other) => {
                return Err(bag_error(format!(
                    "compression_format {other:?}: this crate reads zstd (and lz4) compressed bags"
                )));
            }
            (other, _) => {
                return Err(bag_error(format!("compression_mode {other:?}: expected FILE, MESSAGE or none")));
            }
        };
        let file_counts: HashMap<String, u64> =
            metadata.files.iter().filter_map(|file| Some((file.path.clone(), file.message_count?))).collect();
        let names: Vec<String> = if metadata.relative_file_paths.is_empty() {
            metadata.files.into_iter().map(|file| file.path).collect()
        } else {
            metadata.relative_file_paths
        };
        if names.is_empty() {
            return Err(bag_error("the bag lists no storage file (relative_file_paths is empty)".to_owned()));
        }
        let mut files = Vec::with_capacity(names.len());
        for name in &names {
            let mut path = folder.join(name);
            // rosbag2 lists a file-compressed split under its compressed name; accept the plain
            // name too, when only the compressed file is there.
            if !path.exists() && file_frame.is_some() {
                let compressed =
                    folder.join(format!("{name}.{}", if file_frame == Some(Frame::Lz4) { "lz4" } else { "zstd" }));
                if compressed.exists() {
                    path = compressed;
                }
            }
            if !path.is_file() {
                return Err(bag_error(format!(
                    "the storage file {name:?} that the bag lists is missing: no {}",
                    path.display()
                )));
            }
            let (storage, compression) = match storage_of_name(&path) {
                Some((storage, compression)) => (storage, compression),
                None => match declared {
                    Some(storage) => (storage, file_frame),
                    None => {
                        return Err(bag_error(format!(
                            "cannot tell the storage of {name:?}: no storage_identifier, and the name is not .db3 or .mcap"
                        )));
                    }
                },
            };
            files.push(StorageFile { path, storage, compression });
        }
        check_unlisted(metadata_path, folder, &files)?;
        let counts = Counts {
            metadata: metadata_path.to_path_buf(),
            total: metadata.message_count,
            topics: metadata
                .topics_with_message_count
                .into_iter()
                .map(|topic| (topic.topic_metadata.name, topic.message_count))
                .collect(),
            files: names.iter().map(|name| file_counts.get(name).copied()).collect(),
        };
        Ok(Rosbag2 { files, counts: Some(counts) })
    }

    /// Checks what the walk read, `read` (per storage file, the messages of each topic), against
    /// the counts of the metadata: no storage file, topic or bag may have fewer messages.
    ///
    /// # Errors
    /// [`IoError::Bag`] naming the metadata file, the storage file or topic, and both counts.
    pub(crate) fn check_counts(&self, read: &[TopicCounts]) -> Result<()> {
        let Some(counts) = &self.counts else { return Ok(()) };
        let short = |message: String| {
            Err(IoError::Bag {
                path: counts.metadata.clone(),
                message: format!("{message}: messages were lost (a storage file cut short or corrupt?)"),
            })
        };
        for ((file, declared), read) in self.files.iter().zip(&counts.files).zip(read) {
            let held: u64 = read.values().sum();
            if let Some(declared) = *declared
                && held < declared
            {
                let name = file.path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                return short(format!(
                    "the bag counts {declared} messages in its storage file {name:?}, which holds {held}"
                ));
            }
        }
        let mut topics = TopicCounts::new();
        for (topic, count) in read.iter().flatten() {
            *topics.entry(topic.clone()).or_default() += count;
        }
        for (topic, declared) in &counts.topics {
            let held = topics.get(topic).copied().unwrap_or(0);
            if held < *declared {
                return short(format!(
                    "the bag counts {declared} messages on topic {}, but its {} storage file(s) ({}) hold {held}",
                    crate::printable::printable(topic),
                    self.files.len(),
                    self.file_names()
                ));
            }
        }
        let held: u64 = topics.values().sum();
        if let Some(declared) = counts.total
            && held < declared
        {
            return short(format!(
                "the bag counts {declared} messages (message_count), but its {} storage file(s) ({}) hold {held}",
                self.files.len(),
                self.file_names()
            ));
        }
        Ok(())
    }

    /// The names of the storage files, for messages: `a_0.db3, a_1.db3` (the first few).
    fn file_names(&self) -> String {
        const SHOWN: usize = 4;
        let mut names: Vec<String> = self
            .files
            .iter()
            .take(SHOWN)
            .map(|file| file.path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()))
            .collect();
        if self.files.len() > SHOWN {
            names.push(format!("and {} more", self.files.len() - SHOWN));
        }
        names.join(", ")
    }

    /// A folder without `metadata.yaml`: its storage files, splits in order of their index.
    fn from_folder(folder: &Path) -> Result<Rosbag2> {
        let entries = std::fs::read_dir(folder).map_err(|error| IoError::Open { path: folder.to_path_buf(), error })?;
        let mut files = Vec::new();
        for entry in entries {
            let path = entry.map_err(|error| IoError::Open { path: folder.to_path_buf(), error })?.path();
            if let (true, Some((storage, compression))) = (path.is_file(), storage_of_name(&path)) {
                files.push(StorageFile { path, storage, compression });
            }
        }
        if files.is_empty() {
            return Err(IoError::Bag {
                path: folder.to_path_buf(),
                message: "not a rosbag2 bag: the folder has no metadata.yaml and no .db3 or .mcap file".to_owned(),
            });
        }
        files.sort_by_key(|file| split_key(&file.path));
        Ok(Rosbag2 { files, counts: None })
    }
}

/// Checks that the folder of `metadata` holds no storage file beyond `listed` (the files the
/// metadata lists): a split it leaves out would not be read. A file and its compressed twin
/// (`a.db3` beside a listed `a.db3.zstd`, or the other way round) are one storage file.
fn check_unlisted(metadata: &Path, folder: &Path, listed: &[StorageFile]) -> Result<()> {
    let stem_of = |path: &Path| {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        match Frame::of_name(path) {
            Some(_) => name.rsplit_once('.').map_or(name.clone(), |(stem, _)| stem.to_owned()),
            None => name,
        }
    };
    let known: Vec<String> = listed.iter().map(|file| stem_of(&file.path)).collect();
    // `metadata.yaml` named alone: its folder is the working one.
    let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
    let entries = std::fs::read_dir(folder).map_err(|error| IoError::Open { path: folder.to_path_buf(), error })?;
    let mut unlisted = Vec::new();
    for entry in entries {
        let path = entry.map_err(|error| IoError::Open { path: folder.to_path_buf(), error })?.path();
        if storage_of_name(&path).is_some() && path.is_file() && !known.contains(&stem_of(&path)) {
            unlisted.push(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
        }
    }
    unlisted.sort();
    match unlisted.first() {
        None => Ok(()),
        Some(first) => Err(IoError::Bag {
            path: metadata.to_path_buf(),
            message: format!(
                "the folder holds the storage file {first:?}{}, which the bag does not list (relative_file_paths lists \
                 {}): its messages would not be read; list it there, or move it out of the folder",
                match unlisted.len() {
                    1 => String::new(),
                    n => format!(" and {} more", n - 1),
                },
                listed.len()
            ),
        }),
    }
}

/// The order of splits named `<bag>_<index>.<ext>`: by name before the index, then by the index
/// as a number (`_2` before `_10`), then by the whole name.
fn split_key(path: &Path) -> (String, u64, String) {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.split('.').next().unwrap_or("");
    match stem.rsplit_once('_') {
        Some((base, index)) if !index.is_empty() && index.bytes().all(|b| b.is_ascii_digit()) => {
            (base.to_owned(), index.parse().unwrap_or(u64::MAX), name)
        }
        _ => (stem.to_owned(), 0, name),
    }
}

/// Largest `metadata.yaml` read: 16 MiB (a bag of a thousand splits and topics has ~1 MB).
const MAX_METADATA_BYTES: u64 = 16 << 20;

/// The text of a `metadata.yaml`, at most [`MAX_METADATA_BYTES`].
fn read_metadata(path: &Path) -> Result<String> {
    use std::io::Read;
    let open_error = |error| IoError::Open { path: path.to_path_buf(), error };
    let mut text = String::new();
    std::fs::File::open(path)
        .and_then(|file| file.take(MAX_METADATA_BYTES + 1).read_to_string(&mut text))
        .map_err(open_error)?;
    if text.len() as u64 > MAX_METADATA_BYTES {
        return Err(IoError::Bag {
            path: path.to_path_buf(),
            message: format!("the file is larger than {} MiB: not a rosbag2 metadata.yaml", MAX_METADATA_BYTES >> 20),
        });
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_from_names() {
        assert_eq!(storage_of_name(Path::new("b/x_0.db3")), Some((Storage::Sqlite3, None)));
        assert_eq!(storage_of_name(Path::new("b/x_0.MCAP")), Some((Storage::Mcap, None)));
        assert_eq!(storage_of_name(Path::new("b/x_0.db3.zstd")), Some((Storage::Sqlite3, Some(Frame::Zstd))));
        assert_eq!(storage_of_name(Path::new("b/x_0.mcap.lz4")), Some((Storage::Mcap, Some(Frame::Lz4))));
        assert_eq!(storage_of_name(Path::new("b/x.tum.zstd")), None);
        assert!(crate::error::is_sqlite_name(Path::new("x.db3.zstd")));
        assert!(!crate::error::is_sqlite_name(Path::new("x.mcap")));
    }

    #[test]
    fn splits_sort_by_their_index() {
        let mut names = ["bag_10.db3", "bag_2.db3", "bag_0.db3", "bag_1.db3"].map(PathBuf::from).to_vec();
        names.sort_by_key(|path| split_key(path));
        assert_eq!(names, ["bag_0.db3", "bag_1.db3", "bag_2.db3", "bag_10.db3"].map(PathBuf::from));
    }
}
