//! Bags: rosbag2 (sqlite3 and MCAP storage, compressed per message or per file, split in
//! several files) and ROS 1 (format 2.0), read into the same topic scan as MCAP files.
//!
//! Each storage file is walked by the reader of its kind, which reports topics and messages to
//! the MCAP reader's scan: topic choice, frame pairs, time sources, the table and its errors
//! are the same for every kind. What is ours and what is a crate's:
//!
//! | part | how | module |
//! |---|---|---|
//! | `metadata.yaml` | `serde_yaml_ng` + serde derive | [`rosbag2`] |
//! | sqlite3 storage (`.db3`) | `rusqlite`, SQLite bundled | [`sqlite`] |
//! | MCAP storage (`.mcap`) | the crate's MCAP walker (`mcap` crate) | `crate::mcap` |
//! | zstd, lz4, bz2 | `zstd`, `lz4_flex`, `bzip2`; the size limits are ours | [`compression`](crate::compression) |
//! | ROS 1 records | by hand (the `rosbag` crate does not fit: see the module) | [`ros1`] |
//! | ROS 1 messages | by hand, five types | [`ros1_message`](crate::ros1_message) |

mod ros1;
mod rosbag2;
mod sqlite;

use std::path::Path;

use crate::error::{IoError, Result};
use crate::format::Format;
use crate::mcap::{McapOptions, Scan};
use crate::mcap_records::{At, ChannelKey, MessageHeader, Visitor};
use crate::table::PoseTable;
use crate::topic::{FramePairInfo, TopicInfo};
use rosbag2::{Rosbag2, Storage, StorageFile, TopicCounts};

/// Reads the poses of one topic of a rosbag2 bag, named the way users name it: the bag's folder,
/// its `metadata.yaml`, or one of its storage files (`.db3`, `.mcap`, `.db3.zstd`,
/// `.mcap.zstd`: that file alone).
///
/// - Storage: sqlite3 (`.db3`, the default of ROS 2 Foxy to Humble) and MCAP (the default since
///   Iron).
/// - Splits: the files `metadata.yaml` lists (`relative_file_paths`), in its order; for a folder
///   without `metadata.yaml`, its `.db3` / `.mcap` files ordered by split index (`bag_2` before
///   `bag_10`). Poses of all files make one table, sorted by time.
/// - Nothing left out: with a `metadata.yaml`, a storage file in the folder that it does not
///   list is an error, and so is a storage file, a topic or the bag holding fewer messages than
///   its `message_count`s say.
/// - Compression: `compression_mode: message` (each CDR message a zstd frame, recognised by its
///   magic number whether or not `metadata.yaml` says so; an lz4 frame too), and `compression_mode:
///   file` (each storage file compressed whole, `*.db3.zstd`, `*.mcap.zstd`; decompressed to a
///   temporary file in `TMPDIR` that has no name, so that no exit of the process, Ctrl-C
///   included, leaves it behind ([`remove_temporary_files`](crate::remove_temporary_files)); at
///   most 1000 times the compressed file, and at least 64 MiB, so that a compression bomb is an
///   error, not a full disk). One message may decompress to at most 64 MiB.
/// - Topic, time and frame pair as `options` say, as for [`read_mcap`](crate::read_mcap). A
///   sqlite3 file records one time per message, so [`TimeSource::Log`](crate::TimeSource::Log)
///   and [`TimeSource::Publish`](crate::TimeSource::Publish) both take it.
///
/// The table's [`messages`](PoseTable::messages) name the storage files (the compressed file,
/// for a file-compressed one) and, for sqlite3, each message's row id in place of the offset.
///
/// Time O(size of the bag): every message is visited once; in a sqlite3 file the data of topics
/// not read stays on disk.
///
/// # Errors
/// - [`IoError::Open`] when a file cannot be read; [`IoError::Parse`] (with the line) for a
///   `metadata.yaml` that is not one; [`IoError::Bag`] for a bag whose metadata lists a missing
///   file or leaves out one in the folder, counts more messages than its files hold (naming the
///   file or topic and both counts), names a storage or compression this crate does not read,
///   or a compressed file that does not decompress;
/// - [`IoError::Sqlite`] naming the file (and row) for a `.db3` that SQLite cannot read or that
///   lacks the rosbag2 tables; [`IoError::Mcap`] naming the offset for a broken `.mcap`;
/// - [`IoError::Message`] naming the file, topic and offset (or row) for a message that does not
///   decompress or decode;
/// - the topic and frame errors of [`read_mcap_files`](crate::read_mcap_files).
///
/// # Examples
/// ```no_run
/// use loops_io::{McapOptions, read_rosbag2};
/// let by_folder = read_rosbag2("runs/drive", &McapOptions::default().topic("/odom"))?;
/// let by_metadata = read_rosbag2("runs/drive/metadata.yaml", &McapOptions::default().topic("/odom"))?;
/// assert_eq!(by_folder.positions, by_metadata.positions);
/// # Ok::<(), loops_io::IoError>(())
/// ```
pub fn read_rosbag2(path: impl AsRef<Path>, options: &McapOptions) -> Result<PoseTable> {
    let bag = Rosbag2::resolve(path.as_ref())?;
    let mut scan = Scan::new(Some(options));
    walk_rosbag2(&bag, &mut scan)?;
    scan.into_table(bag.files.iter().map(|file| file.path.clone()).collect(), options)
}

/// A short name for the log at `path`, for a folder of results or a row of a table: a rosbag2
/// bag's folder name, however the bag is named (its folder, its `metadata.yaml`, or one of its
/// storage files; a storage file of a bag of several splits adds its own name,
/// `drive-drive_1`); otherwise the file name without its storage and compression extensions
/// (`drive.mcap`, `drive.db3.zstd` and `drive.bag` are all `drive`). Not made unique: two bags
/// in folders of the same name have the same name.
///
/// Time O(1), or the reading of a bag's `metadata.yaml` for one of its storage files.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::log_name;
/// let bag = std::env::temp_dir().join(format!("loops-io-doc-{}-drive_2024", std::process::id()));
/// std::fs::create_dir_all(&bag)?;
/// std::fs::write(bag.join("metadata.yaml"), "rosbag2_bagfile_information:\n  relative_file_paths: [drive_0.db3]\n")?;
/// std::fs::write(bag.join("drive_0.db3"), "")?;
/// let name = bag.file_name().unwrap().to_string_lossy().into_owned();
/// for given in [bag.clone(), bag.join("metadata.yaml"), bag.join("drive_0.db3")] {
///     assert_eq!(log_name(&given), name);
/// }
/// assert_eq!(log_name("logs/monday.db3.zstd"), "monday");
/// assert_eq!(log_name("logs/monday.tum"), "monday");
/// # std::fs::remove_dir_all(&bag)?;
/// # Ok(())
/// # }
/// ```
pub fn log_name(path: impl AsRef<Path>) -> String {
    let path = path.as_ref();
    let full =
        std::fs::canonicalize(path).or_else(|_| std::path::absolute(path)).unwrap_or_else(|_| path.to_path_buf());
    let name_of = |p: &Path| p.file_name().map(|name| name.to_string_lossy().into_owned());
    let folder = full.parent().filter(|_| !full.is_dir());
    let stem = rosbag2::log_stem(&full);
    let bag_folder = match folder {
        None => return name_of(&full).unwrap_or(stem),
        Some(folder) if rosbag2::is_yaml(&full) => folder,
        Some(folder) if rosbag2::is_storage(&full) && folder.join("metadata.yaml").is_file() => folder,
        Some(_) => return stem,
    };
    let Some(bag) = name_of(bag_folder) else { return stem };
    let splits = Rosbag2::resolve(bag_folder).map_or(1, |bag| bag.files.len());
    if rosbag2::is_storage(&full) && splits > 1 { format!("{bag}-{stem}") } else { bag }
}

/// Reads the poses of one topic of a ROS 1 bag (format 2.0; chunks uncompressed, bz2 or lz4):
/// `geometry_msgs/PoseStamped`, `PoseWithCovarianceStamped`, `TransformStamped`,
/// `nav_msgs/Odometry`, `tf/tfMessage` and `tf2_msgs/TFMessage` (one frame pair).
///
/// Topic, time and frame pair as `options` say, as for [`read_mcap`](crate::read_mcap); a ROS 1
/// message has one record time, which [`TimeSource::Log`](crate::TimeSource::Log) and
/// [`TimeSource::Publish`](crate::TimeSource::Publish) both take. The table's
/// [`messages`](PoseTable::messages) locate each message as in an MCAP file: the chunk's offset
/// and the byte in the decompressed chunk.
///
/// Time O(file size): every chunk is decompressed once, one at a time.
///
/// # Errors
/// [`IoError::Open`] when the file cannot be read; [`IoError::Ros1`] naming the offset for a file
/// that is not a bag of format 2.0, is cut short, or has a record or chunk that does not parse or
/// decompress; [`IoError::Message`] naming topic and offset for a message of the topic read
/// that does not decode (shorter or longer than its type); the topic and frame errors of
/// [`read_mcap_files`](crate::read_mcap_files).
pub fn read_ros1(path: impl AsRef<Path>, options: &McapOptions) -> Result<PoseTable> {
    let path = path.as_ref();
    let mut scan = Scan::new(Some(options));
    scan.path = path.to_path_buf();
    ros1::walk(path, &mut scan)?;
    scan.into_table(vec![path.to_path_buf()], options)
}

/// The topics of an MCAP file, a rosbag2 bag (folder, `metadata.yaml` or storage file; all its
/// splits counted together) or a ROS 1 bag: name, type, encodings, message count, time span and
/// whether this crate reads poses from it; sorted by topic. For `loops info`.
///
/// The kind is told as [`Format::detect`] does (a folder is a rosbag2 bag, `.bag` is ROS 1, ...);
/// any other file is read as MCAP.
///
/// Time O(size of the file or bag): the messages are counted, not decoded.
///
/// # Errors
/// As the reader of the kind ([`read_mcap`](crate::read_mcap), [`read_rosbag2`],
/// [`read_ros1`]), for the structure of the files.
pub fn list_topics(path: impl AsRef<Path>) -> Result<Vec<TopicInfo>> {
    let mut scan = Scan::new(None);
    walk_any(path.as_ref(), &mut scan)?;
    Ok(scan.topics())
}

/// The frame pairs (parent -> child, with their transform counts) of each transform topic
/// (`tf2_msgs/TFMessage`, `tf/tfMessage`, `TransformStamped`, Foxglove `FrameTransform(s)`)
/// with messages, of an MCAP file or a bag as [`list_topics`] reads them; sorted by topic,
/// then by pair. These are the pairs `--frames` / [`McapOptions::frames`] choose from.
///
/// Time O(size of the file or bag): the transform topics' messages are decoded, the others
/// only counted.
///
/// # Errors
/// As [`list_topics`]; and [`IoError::Message`] for a transform message that does not decode.
///
/// # Examples
/// ```no_run
/// for (topic, pairs) in loops_io::list_frame_pairs("drive.bag")? {
///     for pair in pairs {
///         println!("{topic}: {pair}"); // /tf: odom -> base_link (1200)
///     }
/// }
/// # Ok::<(), loops_io::IoError>(())
/// ```
pub fn list_frame_pairs(path: impl AsRef<Path>) -> Result<Vec<(String, Vec<FramePairInfo>)>> {
    let mut scan = Scan::frame_pairs_only();
    walk_any(path.as_ref(), &mut scan)?;
    scan.frame_pairs()
}

/// Walks an MCAP file or a bag of the kind [`Format::detect`] tells (any other file as MCAP).
fn walk_any(path: &Path, scan: &mut Scan<'_>) -> Result<()> {
    match Format::detect(path) {
        Some(Format::Rosbag2) => walk_rosbag2(&Rosbag2::resolve(path)?, scan)?,
        Some(Format::Ros1) => {
            scan.path = path.to_path_buf();
            ros1::walk(path, scan)?;
        }
        _ => {
            scan.path = path.to_path_buf();
            crate::mcap_records::walk(path, scan)?;
        }
    }
    Ok(())
}

/// Walks the storage files of a rosbag2 bag in order, then checks the messages of each file and
/// topic against the counts of its metadata ([`Rosbag2::check_counts`]).
fn walk_rosbag2(bag: &Rosbag2, scan: &mut Scan<'_>) -> Result<()> {
    let mut read = Vec::with_capacity(bag.files.len());
    for (index, file) in bag.files.iter().enumerate() {
        scan.file = index;
        scan.path = file.path.clone();
        let mut counted = Counted { inner: &mut *scan, topics: Vec::new(), counts: TopicCounts::new() };
        walk_storage(file, &mut counted)?;
        read.push(counted.counts);
    }
    bag.check_counts(&read)
}

/// A visitor that counts the messages of each topic on their way to `inner`.
struct Counted<'v, V> {
    inner: &'v mut V,
    /// The topic of each channel `inner` numbered, by its number.
    topics: Vec<Option<String>>,
    counts: TopicCounts,
}

impl<V: Visitor> Visitor for Counted<'_, V> {
    fn channel(&mut self, key: ChannelKey, at: At) -> usize {
        let topic = key.topic.clone();
        let channel = self.inner.channel(key, at);
        if self.topics.len() <= channel {
            self.topics.resize(channel + 1, None);
        }
        self.topics[channel] = Some(topic);
        channel
    }

    fn message(&mut self, channel: usize, header: MessageHeader, data: &[u8], at: At) -> Result<()> {
        if let Some(Some(topic)) = self.topics.get(channel) {
            match self.counts.get_mut(topic) {
                Some(count) => *count += 1,
                None => {
                    self.counts.insert(topic.clone(), 1);
                }
            }
        }
        self.inner.message(channel, header, data, at)
    }

    fn decodes(&self, channel: usize) -> bool {
        self.inner.decodes(channel)
    }
}

/// Walks one storage file of a rosbag2 bag, decompressing it first when it is compressed whole
/// (into a file without a name: see `crate::temp_copy`).
fn walk_storage(file: &StorageFile, visitor: &mut impl Visitor) -> Result<()> {
    let shown = &file.path;
    let Some(frame) = file.compression else {
        return match file.storage {
            Storage::Sqlite3 => sqlite::walk(&sqlite::open(shown, shown, false)?, shown, visitor),
            Storage::Mcap => crate::mcap_records::walk(shown, visitor),
        };
    };
    let copy = crate::compression::decompress_file(shown, frame)?;
    match file.storage {
        Storage::Sqlite3 => {
            // SQLite opens files by name: the copy has one while SQLite opens it, no longer (on
            // Unix SQLite then reads through its handle; elsewhere the name goes after).
            let mut name = copy.name().map_err(|error| IoError::Bag {
                path: shown.clone(),
                message: format!(
                    "cannot name the decompressed copy for SQLite: {}",
                    crate::printable::one_line(&error)
                ),
            })?;
            let db = sqlite::open(name.path(), shown, true)?;
            if cfg!(unix) {
                name.remove();
            }
            sqlite::walk(&db, shown, visitor)
        }
        Storage::Mcap => {
            let file = copy.into_file();
            crate::mcap_records::walk_file(file, shown, visitor).map_err(in_decompressed)
        }
    }
}

/// An error about a decompressed copy, made about the compressed file it came from: its offsets
/// are in the decompressed bytes.
fn in_decompressed(error: IoError) -> IoError {
    match error {
        IoError::Mcap { path, offset, message } => {
            IoError::Mcap { path, offset, message: format!("{message} (offset in the decompressed file)") }
        }
        other => other,
    }
}
