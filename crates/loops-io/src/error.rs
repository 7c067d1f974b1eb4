//! The error types of the readers and writers: every error names the file, and the line, or
//! the topic and byte offset, where there is one. [`IoError`] for reading (and the writers that
//! check their input), [`WriteError`] for writing a file.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

use crate::format::Format;
use crate::pose_type::SUPPORTED_TYPES;
use crate::printable::printable;
use crate::topic::{FramePairInfo, TopicInfo};

/// `Result` with [`IoError`] as the default error type.
pub type Result<T, E = IoError> = std::result::Result<T, E>;

/// Everything that can go wrong reading or writing a pose file. The message always starts with
/// the file's path, then where in it: `line N` for text files (`drive.tum line 12: column 3
/// ("abc") is not a number`), the byte offset for the structure of an MCAP file (`drive.mcap
/// offset 1234: ...`, `drive.bag offset 4117: ...`), the topic and the message's offset for a
/// message (`drive.mcap topic /odom, message at offset 1234: ...`), or its row for a rosbag2
/// sqlite3 file (`bag/bag_0.db3 row 17: ...`, `bag/bag_0.db3 topic /odom, message at row 17:
/// ...`).
///
/// Each message is complete on its own, so the wrapped errors (`error` fields) are public fields
/// to match on and are not repeated as [`source`](std::error::Error::source): a report that
/// walks the source chain (`anyhow`'s `{:#}`) prints every cause once.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be read: missing, a directory, no permission.
    #[error("{}: cannot read the file: {error}", .path.display())]
    Open {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// A line that does not fit the format.
    #[error("{} line {line}: {message}", .path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong, naming the 1-based column and the offending text where there is one:
        /// `column 3 ("abc") is not a number`.
        message: String,
    },
    /// A file with no data lines (only blank lines, comments or a header).
    #[error("{}: no poses: the file has no data lines", .path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// Poses that the core rejects as a trajectory (duplicate timestamps, too few poses, ...),
    /// located in the file: at a line for text files, at a message for MCAP files.
    #[error("{}", trajectory_message(.path, *.line, *.previous_line, .messages.as_deref(), .error))]
    Trajectory {
        /// The file (for a pose from an MCAP file, the file holding its message); boxed, as
        /// `messages`, so that errors stay small.
        path: Box<Path>,
        /// The line of the pose the core names, when it names one (text files).
        line: Option<usize>,
        /// For timestamps out of order: the line of the pose before (comments and blank lines
        /// may lie between the two).
        previous_line: Option<usize>,
        /// The message of the pose the core names, when it names one (MCAP files), and the one
        /// before for timestamps out of order (boxed: errors stay small).
        messages: Option<Box<TrajectoryMessages>>,
        /// What the core said, with pose indices rather than lines.
        error: loops_core::Error,
    },
    /// Detections that the core rejects (outside the trajectory's time span, ...), located in
    /// the file.
    #[error("{}{}: {error}{}", .path.display(), .line.map(|l| format!(" line {l}")).unwrap_or_default(),
        if matches!(.error, loops_core::Error::DetectionOutsideSpan { .. }) { DROP_OUTSIDE_HINT } else { "" })]
    Detections {
        /// The file.
        path: PathBuf,
        /// The line of the detection the core names, when it names one.
        line: Option<usize>,
        /// What the core said, with detection indices rather than lines.
        error: loops_core::Error,
    },
    /// Files read as one trajectory that do not join ([`PoseTable::join`](crate::PoseTable::join)):
    /// their times overlap (the message names both files, and the stamp and line on each side),
    /// or their poses differ in dimension.
    #[error("{}: {message}", .path.display())]
    Join {
        /// The later file of the two.
        path: PathBuf,
        /// What is wrong, naming the other file.
        message: String,
    },
    /// No format was given and neither the file's extension nor its first line tells it.
    #[error("{}: {}", .path.display(), unknown_format_message(.extension.as_deref()))]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The file's extension, if it has one.
        extension: Option<String>,
    },
    /// An MCAP file whose structure is broken at a byte offset: not an MCAP file (bad magic), cut
    /// short, a chunk whose CRC or compression fails, a record that does not parse.
    #[error("{} offset {offset}: {message}", .path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// Byte offset in the file of the record at fault (0 for the magic at the start).
        offset: u64,
        /// What is wrong.
        message: String,
    },
    /// An MCAP message that does not decode as its schema says: too short for its type, a bad
    /// CDR encapsulation, invalid protobuf or JSON.
    #[error("{location}: {message}")]
    Message {
        /// The message: file, topic and offset.
        location: MessageLocation,
        /// What is wrong, naming the field where there is one.
        message: String,
    },
    /// The topic asked for is not in the file(s).
    #[error("{}: no topic {topic:?}; the topics are: {}", .path.display(), list(.topics))]
    TopicNotFound {
        /// The (first) file.
        path: PathBuf,
        /// The topic asked for.
        topic: String,
        /// Every topic of the file(s).
        topics: Vec<TopicInfo>,
    },
    /// No topic was asked for and none holds poses of a type this crate reads.
    #[error("{}: no topic holds poses of a type this crate reads ({}); the topics are: {}",
        .path.display(), SUPPORTED_TYPES, list(.topics))]
    NoPoseTopic {
        /// The (first) file.
        path: PathBuf,
        /// Every topic of the file(s).
        topics: Vec<TopicInfo>,
    },
    /// No topic was asked for and several hold poses: name one.
    #[error("{}: {} topics hold poses, name one: {}", .path.display(), .candidates.len(), list(.candidates))]
    AmbiguousTopic {
        /// The (first) file.
        path: PathBuf,
        /// The topics that hold poses.
        candidates: Vec<TopicInfo>,
    },
    /// The topic asked for has a type this crate cannot read poses from (an unknown schema, or a
    /// known schema in an unknown encoding).
    #[error("{}: topic {} has type {:?} in encoding {:?}, which this crate does not read poses from; it reads {}",
        .path.display(), printable(&.topic.topic), .topic.schema_name, .topic.message_encoding, SUPPORTED_TYPES)]
    UnsupportedTopic {
        /// The (first) file.
        path: PathBuf,
        /// The topic (boxed: errors stay small).
        topic: Box<TopicInfo>,
    },
    /// The topic has a channel but no message, or messages without poses.
    #[error("{} topic {}: no poses ({} message{}; {})",
        .path.display(), printable(&.topic.topic), .topic.message_count, if .topic.message_count == 1 { "" } else { "s" },
        channel_place(.path, *.channel_offset))]
    EmptyTopic {
        /// The file of the topic's first channel record.
        path: PathBuf,
        /// The topic (boxed: errors stay small).
        topic: Box<TopicInfo>,
        /// Byte offset in `path` of the topic's first channel record, or of the chunk holding it.
        channel_offset: u64,
    },
    /// A transform topic (TF, `FrameTransform`) whose frame pair is ambiguous or missing: no
    /// pair was asked for and the topic has several, or the pair asked for is not on it.
    #[error("{} topic {}: {}", .path.display(), printable(.topic), frames_message(.wanted.as_ref(), .pairs))]
    FramePair {
        /// The (first) file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The pair `(parent, child)` asked for, if any.
        wanted: Option<(String, String)>,
        /// The pairs on the topic, with their transform counts.
        pairs: Vec<FramePairInfo>,
    },
    /// A transform topic whose frames asked for are not linked by its transforms (with those of
    /// its static topic, `/tf` → `/tf_static`), or whose chain cannot be composed: the message
    /// names the frames at the top of each chain, a frame with two parents, or the spans.
    #[error("{} topic {}: {message}", .path.display(), printable(.topic))]
    FrameTree {
        /// The (first) file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// What does not link up.
        message: String,
    },
    /// A ROS 1 bag whose structure is broken at a byte offset: not a ROS 1 bag of format 2.0,
    /// cut short, a record whose header does not parse, a chunk that does not decompress.
    #[error("{} offset {offset}: {message}", .path.display())]
    Ros1 {
        /// The file.
        path: PathBuf,
        /// Byte offset in the file of the record at fault (of the chunk, for a record in one).
        offset: u64,
        /// What is wrong; for a record in a chunk, naming its byte in the decompressed chunk.
        message: String,
    },
    /// A rosbag2 sqlite3 file (`.db3`) that SQLite cannot read, that lacks the rosbag2 tables,
    /// or whose row does not fit them (a message on an unknown topic, data that is not a blob).
    #[error("{}{}: {message}", .path.display(), .row.map(|row| format!(" row {row}")).unwrap_or_default())]
    Sqlite {
        /// The file (the compressed file, for a `.db3.zstd`).
        path: PathBuf,
        /// The row id in the `messages` table, when one row is at fault.
        row: Option<i64>,
        /// What is wrong, with SQLite's own message where it has one.
        message: String,
    },
    /// A rosbag2 bag that cannot be read as a whole: a `metadata.yaml` without the fields
    /// needed, a storage file it lists that is missing, a storage or compression this crate
    /// does not read, a file-compressed storage file that does not decompress.
    #[error("{}: {message}", .path.display())]
    Bag {
        /// The file at fault (`metadata.yaml`, a storage file), or the bag's folder.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A pose graph that gives no trajectory as asked: edges but no vertices (unless its
    /// odometry edges are chained, `chain_edges`), or odometry edges with a gap (naming the
    /// vertex no edge reaches).
    #[error("{}: {message}", .path.display())]
    PoseGraph {
        /// The file.
        path: PathBuf,
        /// What is wrong, and what would do.
        message: String,
    },
    /// A file could not be written: it exists and overwriting was not asked for, or the system
    /// refused.
    #[error(transparent)]
    Write(WriteError),
}

impl IoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Open { path, .. }
            | Self::Parse { path, .. }
            | Self::Empty { path }
            | Self::Detections { path, .. }
            | Self::UnknownFormat { path, .. }
            | Self::Mcap { path, .. }
            | Self::Ros1 { path, .. }
            | Self::Sqlite { path, .. }
            | Self::Bag { path, .. }
            | Self::PoseGraph { path, .. }
            | Self::Join { path, .. }
            | Self::TopicNotFound { path, .. }
            | Self::NoPoseTopic { path, .. }
            | Self::AmbiguousTopic { path, .. }
            | Self::UnsupportedTopic { path, .. }
            | Self::EmptyTopic { path, .. }
            | Self::FramePair { path, .. }
            | Self::FrameTree { path, .. } => path,
            Self::Trajectory { path, .. } => path,
            Self::Message { location, .. } => &location.path,
            Self::Write(WriteError::Exists { path } | WriteError::Write { path, .. }) => path,
        }
    }

    /// The 1-based line the error is about, when there is one.
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Parse { line, .. } => Some(*line),
            Self::Trajectory { line, .. } | Self::Detections { line, .. } => *line,
            _ => None,
        }
    }

    /// The byte offset in an MCAP file or ROS 1 bag the error is about, when there is one: of
    /// the record at fault, of the message (of its chunk, for a message in a chunk), or of an
    /// empty topic's channel record. For a rosbag2 sqlite3 file, the row id (see
    /// [`MessageLocation`]).
    pub fn offset(&self) -> Option<u64> {
        match self {
            Self::Mcap { offset, .. } | Self::Ros1 { offset, .. } => Some(*offset),
            Self::Sqlite { row, .. } => row.and_then(|row| u64::try_from(row).ok()),
            Self::Message { location, .. } => Some(location.offset),
            Self::Trajectory { messages: Some(messages), .. } => Some(messages.message.offset),
            Self::EmptyTopic { channel_offset, .. } => Some(*channel_offset),
            _ => None,
        }
    }

    /// The topic the error is about, when there is one.
    pub fn topic(&self) -> Option<&str> {
        match self {
            Self::Message { location, .. } => Some(&location.topic),
            Self::Trajectory { messages: Some(messages), .. } => Some(&messages.message.topic),
            Self::TopicNotFound { topic, .. } | Self::FramePair { topic, .. } | Self::FrameTree { topic, .. } => {
                Some(topic)
            }
            Self::UnsupportedTopic { topic, .. } | Self::EmptyTopic { topic, .. } => Some(&topic.topic),
            _ => None,
        }
    }

    pub(crate) fn parse(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self::Parse { path: path.to_path_buf(), line, message: message.into() }
    }

    pub(crate) fn mcap(path: &Path, offset: u64, message: impl Into<String>) -> Self {
        Self::Mcap { path: path.to_path_buf(), offset, message: message.into() }
    }

    /// An invalid option (a rate, an axis) reported as the core's `InvalidParameter`.
    pub(crate) fn invalid(path: &Path, name: &'static str, value: f64, expected: &'static str) -> Self {
        Self::Trajectory {
            path: path.into(),
            line: None,
            previous_line: None,
            messages: None,
            error: loops_core::Error::InvalidParameter { name, value, expected },
        }
    }
}

/// Why a result file could not be written. The message starts with the file's path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// The file exists and replacing it was not asked for.
    #[error("{}: the file exists; refusing to overwrite it", .path.display())]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// The operating system refused: a missing directory, no permission, a full disk.
    #[error("{}: cannot write the file: {error}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: io::Error,
    },
}

/// The messages an [`IoError::Trajectory`] names in MCAP files.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct TrajectoryMessages {
    /// The message of the pose the core names.
    pub message: MessageLocation,
    /// For timestamps out of order: the message of the pose before.
    pub previous: Option<MessageLocation>,
}

/// Where a message lies in an MCAP file or a bag: the file, its topic, and its byte offset.
///
/// Displays as `drive.mcap topic /odom, message at offset 1234`, or for a message inside a
/// compressed or uncompressed chunk (MCAP, ROS 1) `drive.mcap topic /odom, message at byte 56 of
/// the chunk at offset 1234` (the byte counts from the start of the chunk's decompressed
/// records). In a rosbag2 sqlite3 file (a file named `*.db3`, or `*.db3.zstd` compressed) the
/// offset is the message's row id in the `messages` table: `bag_0.db3 topic /odom, message at
/// row 17`. In a file-compressed bag file the offset is in the decompressed file.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct MessageLocation {
    /// The file.
    pub path: PathBuf,
    /// The message's topic.
    pub topic: String,
    /// Byte offset in the file of the message record, or of the chunk record holding it; the
    /// row id in a rosbag2 sqlite3 file.
    pub offset: u64,
    /// For a message in a chunk: its byte offset in the chunk's decompressed records.
    pub offset_in_chunk: Option<u64>,
}

impl MessageLocation {
    /// Where in its file: `message at offset 1234`, `message at byte 56 of the chunk at offset
    /// 1234`, `message at row 17`.
    fn place(&self) -> String {
        match self.offset_in_chunk {
            Some(inner) => format!("message at byte {inner} of the chunk at offset {}", self.offset),
            None if is_sqlite_name(&self.path) => format!("message at row {}", self.offset),
            None => format!("message at offset {}", self.offset),
        }
    }
}

impl fmt::Display for MessageLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} topic {}, {}", self.path.display(), printable(&self.topic), self.place())
    }
}

/// Where an empty topic's channel lies: a record, or a row of a sqlite3 file's `topics`.
fn channel_place(path: &Path, offset: u64) -> String {
    if is_sqlite_name(path) {
        format!("it is row {offset} of the topics table")
    } else {
        format!("its channel is in the record at offset {offset}")
    }
}

fn list<T: fmt::Display>(items: &[T]) -> String {
    if items.is_empty() {
        return "none".to_owned();
    }
    items.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
}

fn frames_message(wanted: Option<&(String, String)>, pairs: &[FramePairInfo]) -> String {
    match wanted {
        Some((parent, child)) => {
            format!("no transform from {parent:?} to {child:?}; the frame pairs (parent -> child) are: {}", list(pairs))
        }
        None => format!("{} frame pairs (parent -> child), name one: {}", pairs.len(), list(pairs)),
    }
}

/// What a repeated timestamp's message adds: the option that drops such poses, as Python and
/// the command line spell it.
const DROP_DUPLICATES_HINT: &str =
    "; drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first pose of each stamp";

/// What a detection outside the trajectory's span adds: the option that drops such detections.
const DROP_OUTSIDE_HINT: &str = "; drop_outside_span=True (--drop-detections-outside-span) drops such detections";

/// The core's message in terms of the file: lines or messages instead of pose indices.
fn trajectory_message(
    path: &Path,
    line: Option<usize>,
    previous_line: Option<usize>,
    messages: Option<&TrajectoryMessages>,
    error: &loops_core::Error,
) -> String {
    use loops_core::Error;

    let message = messages.map(|m| &m.message);
    let previous_message = messages.and_then(|m| m.previous.as_ref());
    let location = match (message, line) {
        (Some(message), _) => message.to_string(),
        (None, Some(line)) => format!("{} line {line}", path.display()),
        (None, None) => path.display().to_string(),
    };
    let located = line.is_some() || message.is_some();
    let what = match (located, error) {
        (true, Error::TimestampsNotIncreasing { previous_s, value_s, .. }) => {
            let previous = match (previous_message, previous_line) {
                (Some(previous), _) if previous.path == message.map_or(path, |m| &m.path) => {
                    format!(" ({})", previous.place())
                }
                (Some(previous), _) => format!(" ({previous})"),
                (None, Some(p)) => format!(" (line {p})"),
                (None, None) => String::new(),
            };
            let hint = if value_s == previous_s { DROP_DUPLICATES_HINT } else { "" };
            format!("timestamps must strictly increase: {value_s} s is not after {previous_s} s{previous}{hint}")
        }
        (true, Error::NonFiniteTimestamp { value, .. }) => format!("the timestamp is not finite ({value})"),
        (true, Error::NonFiniteCoordinate { axis, value, .. }) => {
            format!("coordinate {axis} of the position is not finite ({value})")
        }
        _ => error.to_string(),
    };
    format!("{location}: {what}")
}

fn unknown_format_message(extension: Option<&str>) -> String {
    let known: Vec<String> = Format::ALL
        .iter()
        .filter(|format| !format.extensions().is_empty())
        .map(|format| {
            let extensions: Vec<String> = format.extensions().iter().map(|e| format!(".{e}")).collect();
            format!("{} for {}", extensions.join(" or "), format.name())
        })
        .collect();
    let names: Vec<&str> = Format::ALL.iter().map(|format| format.name()).collect();
    let given = match extension {
        Some(extension) => format!("the extension {:?}", format!(".{extension}")),
        None => "a file without an extension".to_owned(),
    };
    format!(
        "cannot tell the file format from {given}: expected {}, or name the format ({})",
        known.join(", "),
        names.join(", ")
    )
}

/// Whether `path` names a rosbag2 sqlite3 file (`*.db3`, or compressed `*.db3.zstd`,
/// `*.db3.zst`, `*.db3.lz4`): offsets in its errors are rows.
pub(crate) fn is_sqlite_name(path: &std::path::Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let inner = [".zstd", ".zst", ".lz4"].iter().find_map(|suffix| name.strip_suffix(suffix)).unwrap_or(&name);
    inner.ends_with(".db3")
}
