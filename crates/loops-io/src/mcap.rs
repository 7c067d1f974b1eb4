//! MCAP files (ROS 2 and Foxglove logs): the poses of one topic, and the list of topics.
//!
//! The file is walked record by record from the start, so every record has a byte offset to
//! name in errors; chunks are decompressed (zstd, lz4, or none) and their CRCs checked by the
//! `mcap` crate's sans-I/O reader, one chunk at a time, so memory stays at one chunk plus the
//! poses. The summary section is not needed and only checked to be there, up to the footer and
//! the closing magic: a file cut short is an error, not a silently shorter trajectory.

use std::collections::HashMap;
use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use mcap::records::{Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{IoError, MessageLocation, Result};
use crate::message::{MessageEncoding, PoseType, decode_samples};
use crate::table::{MessageRef, MessageSources, PoseTable, seconds_of_ns};

/// The types [`read_mcap`] reads, as error messages list them.
pub(crate) const SUPPORTED_TYPES: &str = "geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
     geometry_msgs/msg/TransformStamped, nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage in cdr; foxglove.PoseInFrame, \
     foxglove.PosesInFrame, foxglove.FrameTransform, foxglove.FrameTransforms, foxglove.Odometry in protobuf or json";

/// Which time each pose of an MCAP file gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum TimeSource {
    /// The stamp in the message: `header.stamp` (ROS 2), `timestamp` (Foxglove); for TF and
    /// `FrameTransforms`, each transform's own stamp. The default: it is when the pose was
    /// valid, while log time is when it reached the recorder.
    #[default]
    Header,
    /// The record's log time: when the recorder received the message.
    Log,
    /// The record's publish time: when the publisher sent it.
    Publish,
}

impl TimeSource {
    /// The accepted names.
    pub const NAMES: &'static str = "header, log, publish";
}

impl std::str::FromStr for TimeSource {
    type Err = loops_core::Error;

    fn from_str(name: &str) -> std::result::Result<Self, Self::Err> {
        match name {
            "header" => Ok(Self::Header),
            "log" => Ok(Self::Log),
            "publish" => Ok(Self::Publish),
            _ => Err(loops_core::Error::UnknownName {
                kind: "time source",
                name: name.to_owned(),
                expected: Self::NAMES,
            }),
        }
    }
}

/// What [`read_mcap`] reads: which topic, which time, which frame pair.
///
/// # Examples
/// ```
/// use loops_io::{McapOptions, TimeSource};
/// let options = McapOptions::default().topic("/tf").frames("odom", "base_link").time(TimeSource::Log);
/// assert_eq!(options.topic.as_deref(), Some("/tf"));
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct McapOptions {
    /// The topic to read; `None` picks the one topic holding poses (see [`read_mcap`]).
    pub topic: Option<String>,
    /// Which time each pose gets; the message's stamp by default.
    pub time: TimeSource,
    /// For transform topics (TF, `FrameTransform`): the `(parent, child)` frame pair to read;
    /// `None` takes the topic's one pair. Not used for other topics.
    pub frames: Option<(String, String)>,
}

impl McapOptions {
    /// Reads `topic`.
    pub fn topic(mut self, topic: impl Into<String>) -> Self {
        self.topic = Some(topic.into());
        self
    }

    /// Stamps poses with `time`.
    pub fn time(mut self, time: TimeSource) -> Self {
        self.time = time;
        self
    }

    /// Reads the transforms from `parent` to `child` (the pose of `child` in `parent`).
    pub fn frames(mut self, parent: impl Into<String>, child: impl Into<String>) -> Self {
        self.frames = Some((parent.into(), child.into()));
        self
    }
}

/// One topic of an MCAP file (or of several files, counted together), as [`list_topics`]
/// reports it and as errors list them.
///
/// Displays as `/odom (nav_msgs/msg/Odometry, cdr, 120 messages)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// The topic.
    pub topic: String,
    /// Its schema's name: `nav_msgs/msg/Odometry`; empty for a channel without schema.
    pub schema_name: String,
    /// Its schema's encoding: `ros2msg`, `protobuf`, `jsonschema`, ...
    pub schema_encoding: String,
    /// Its messages' encoding: `cdr`, `protobuf`, `json`, ...
    pub message_encoding: String,
    /// The number of messages.
    pub message_count: u64,
    /// The first and last log time, nanoseconds (as in the file: usually since the Unix
    /// epoch); `None` without messages.
    pub log_time_span_ns: Option<(u64, u64)>,
    /// The pose type, when this crate reads poses from the topic.
    pub pose_type: Option<PoseType>,
}

impl fmt::Display for TopicInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let schema = if self.schema_name.is_empty() { "no schema" } else { &self.schema_name };
        let plural = if self.message_count == 1 { "" } else { "s" };
        write!(f, "{} ({schema}, {}, {} message{plural})", self.topic, self.message_encoding, self.message_count)
    }
}

/// A frame pair of a transform topic, with the number of transforms between them.
///
/// Displays as `map -> base_link (120)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FramePairInfo {
    /// The parent frame (`header.frame_id`, `parent_frame_id`).
    pub parent: String,
    /// The child frame (`child_frame_id`).
    pub child: String,
    /// The number of transforms.
    pub count: u64,
}

impl fmt::Display for FramePairInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} -> {} ({})", self.parent, self.child, self.count)
    }
}

/// Reads the poses of one topic of an MCAP file: see [`read_mcap_files`].
///
/// # Errors
/// As [`read_mcap_files`].
pub fn read_mcap(path: impl AsRef<Path>, options: &McapOptions) -> Result<PoseTable> {
    read_mcap_files(&[path.as_ref()], options)
}

/// Reads the poses of one topic of one or more MCAP files (a recording split in parts) as one
/// table ordered by time.
///
/// - The topic is `options.topic`, or, when `None`, the one topic of a type this crate reads
///   ([`PoseType`]) that has messages; poses (odometry, `PoseStamped`, ...) come before
///   transforms, so a log with `/odom` and `/tf` reads `/odom`. Several candidates are an error
///   listing them.
/// - Time is the message's stamp by default, the log or publish time on request
///   ([`TimeSource`]). Rows are sorted by time (stably: poses of one message keep their order),
///   across all files; duplicate times are left for [`PoseTable::to_trajectory`] to report, at
///   their messages.
/// - For transform topics, one `(parent, child)` frame pair: `options.frames`, or the topic's
///   only pair.
///
/// The table is 3-D with orientations, and holds the exact integer stamps
/// ([`PoseTable::timestamps_ns`]) and each pose's message ([`PoseTable::messages`]).
///
/// Time O(file size): every record is read once, chunks decompressed one at a time; messages on
/// other topics are not decoded when a topic is named. About 10⁶ `PoseStamped` per second.
///
/// # Errors
/// - [`IoError::Open`] when a file cannot be read;
/// - [`IoError::Mcap`] naming the byte offset for a file that is not MCAP (bad magic), is cut
///   short, has a chunk whose CRC or decompression fails, or a record that does not parse;
/// - [`IoError::Message`] naming the file, topic and offset for a message of the topic read
///   that does not decode (shorter than its type, ...);
/// - [`IoError::TopicNotFound`], [`IoError::UnsupportedTopic`] (a type this crate does not
///   read), [`IoError::EmptyTopic`] for the topic named; [`IoError::NoPoseTopic`] and
///   [`IoError::AmbiguousTopic`] when none is named;
/// - [`IoError::FramePair`] for a transform topic with several pairs and none named, or without
///   the pair named;
/// - [`IoError::Trajectory`] holding [`loops_core::Error::InvalidParameter`] for no file at all.
pub fn read_mcap_files<P: AsRef<Path>>(paths: &[P], options: &McapOptions) -> Result<PoseTable> {
    let files: Vec<PathBuf> = paths.iter().map(|path| path.as_ref().to_path_buf()).collect();
    let Some(first) = files.first().cloned() else {
        return Err(IoError::invalid(Path::new(""), "number of MCAP files", 0.0, "at least one file"));
    };
    let mut scan = Scan::new(Some(options));
    for (index, path) in files.iter().enumerate() {
        scan.file = index;
        scan.path = path.clone();
        walk(path, &mut scan)?;
    }
    let bucket = scan.choose(&first, options)?;
    let (group, frames) = choose_group(&files, bucket, options)?;
    let mut rows = std::mem::take(&mut bucket.groups[group].rows);
    rows.sort_by_key(|row| row.stamp_ns);
    let mut table = PoseTable::empty(&first, 3);
    table.timestamps_s = rows.iter().map(|row| seconds_of_ns(row.stamp_ns)).collect();
    table.timestamps_ns = Some(rows.iter().map(|row| row.stamp_ns).collect());
    table.positions = rows.iter().map(|row| row.position).collect();
    table.orientations_xyzw = Some(rows.iter().map(|row| row.orientation).collect());
    table.messages = Some(MessageSources {
        files,
        topic: bucket.info.topic.clone(),
        schema_name: bucket.info.schema_name.clone(),
        frames,
        messages: rows.iter().map(|row| row.source).collect(),
    });
    Ok(table)
}

/// The topics of an MCAP file: name, schema, encodings, message count, log time span and
/// whether this crate reads poses from it; sorted by topic. For `loops info`.
///
/// Time O(file size): the messages are counted, not decoded.
///
/// # Errors
/// [`IoError::Open`] when the file cannot be read; [`IoError::Mcap`] naming the offset when it
/// is not MCAP, cut short, or broken.
pub fn list_topics(path: impl AsRef<Path>) -> Result<Vec<TopicInfo>> {
    let path = path.as_ref();
    let mut scan = Scan::new(None);
    scan.path = path.to_path_buf();
    walk(path, &mut scan)?;
    Ok(scan.topics())
}

/// A channel's identity across files: topics with the same name, schema and encodings are one.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct ChannelKey {
    topic: String,
    schema_name: String,
    schema_encoding: String,
    message_encoding: String,
}

/// Where a record lies: the offset of the top-level record (the chunk, for records in one),
/// and within a chunk the offset in its decompressed records.
#[derive(Debug, Clone, Copy)]
struct At {
    offset: u64,
    in_chunk: Option<u64>,
}

/// A message record's header.
#[derive(Debug, Clone, Copy)]
struct MessageHeader {
    channel_id: u16,
    log_time: u64,
    publish_time: u64,
}

/// What the walker reports: channels as they appear, and messages.
trait Visitor {
    /// A channel appears (for the first time in this file); returns the visitor's index for it.
    fn channel(&mut self, key: ChannelKey, at: At) -> usize;
    /// A message on the channel the visitor numbered `channel`.
    fn message(&mut self, channel: usize, header: MessageHeader, data: &[u8], at: At) -> Result<()>;
}

/// One pose, with where it came from.
#[derive(Debug, Clone, Copy)]
struct Row {
    stamp_ns: i64,
    position: [f64; 3],
    orientation: [f64; 4],
    source: MessageRef,
}

/// The poses of one frame pair of a topic (the only group of a topic that is not a transform).
#[derive(Debug, Default)]
struct Group {
    parent: String,
    child: String,
    count: u64,
    rows: Vec<Row>,
}

/// One topic, across files.
#[derive(Debug)]
struct Bucket {
    info: TopicInfo,
    kind: Option<(PoseType, MessageEncoding)>,
    /// Whether its messages are decoded.
    decode: bool,
    /// The file and offset of its first channel record.
    first_channel: (usize, u64),
    groups: Vec<Group>,
    /// The first message that did not decode.
    error: Option<IoError>,
}

/// Collects topics and, when reading, poses.
#[derive(Debug)]
struct Scan<'o> {
    /// `None` to count only.
    options: Option<&'o McapOptions>,
    /// The file being walked: its index and path.
    file: usize,
    path: PathBuf,
    buckets: Vec<Bucket>,
    index: HashMap<ChannelKey, usize>,
}

impl<'o> Scan<'o> {
    fn new(options: Option<&'o McapOptions>) -> Self {
        Self { options, file: 0, path: PathBuf::new(), buckets: Vec::new(), index: HashMap::new() }
    }

    /// The topics, sorted.
    fn topics(&self) -> Vec<TopicInfo> {
        let mut topics: Vec<TopicInfo> = self.buckets.iter().map(|bucket| bucket.info.clone()).collect();
        topics.sort_by(|a, b| {
            (&a.topic, &a.schema_name, &a.message_encoding).cmp(&(&b.topic, &b.schema_name, &b.message_encoding))
        });
        topics
    }

    /// The bucket to read: the topic named, or the one topic with poses.
    fn choose(&mut self, first: &Path, options: &McapOptions) -> Result<&mut Bucket> {
        let path = first.to_path_buf();
        let chosen: Vec<usize> = match &options.topic {
            Some(topic) => {
                let named: Vec<usize> =
                    (0..self.buckets.len()).filter(|&i| &self.buckets[i].info.topic == topic).collect();
                if named.is_empty() {
                    return Err(IoError::TopicNotFound { path, topic: topic.clone(), topics: self.topics() });
                }
                let readable: Vec<usize> = named.iter().copied().filter(|&i| self.buckets[i].kind.is_some()).collect();
                match readable.len() {
                    0 => {
                        return Err(IoError::UnsupportedTopic {
                            path,
                            topic: Box::new(self.buckets[named[0]].info.clone()),
                        });
                    }
                    _ => readable,
                }
            }
            None => {
                let with_messages = |transform: bool| -> Vec<usize> {
                    (0..self.buckets.len())
                        .filter(|&i| {
                            let bucket = &self.buckets[i];
                            bucket.info.message_count > 0
                                && bucket.kind.is_some_and(|(pose_type, _)| pose_type.is_transform() == transform)
                        })
                        .collect()
                };
                let poses = with_messages(false);
                let candidates = if poses.is_empty() { with_messages(true) } else { poses };
                if candidates.is_empty() {
                    // A readable topic without messages is the likelier mistake to report.
                    if let Some(empty) = self.buckets.iter().position(|bucket| bucket.kind.is_some()) {
                        vec![empty]
                    } else {
                        return Err(IoError::NoPoseTopic { path, topics: self.topics() });
                    }
                } else {
                    candidates
                }
            }
        };
        if chosen.len() > 1 {
            let mut candidates: Vec<TopicInfo> = chosen.iter().map(|&i| self.buckets[i].info.clone()).collect();
            candidates.sort_by(|a, b| a.topic.cmp(&b.topic));
            return Err(IoError::AmbiguousTopic { path, candidates });
        }
        let bucket = &mut self.buckets[chosen[0]];
        if let Some(error) = bucket.error.take() {
            return Err(error);
        }
        Ok(bucket)
    }
}

/// The group (frame pair) to read from the chosen bucket, and the pair for transforms.
fn choose_group(
    files: &[PathBuf],
    bucket: &Bucket,
    options: &McapOptions,
) -> Result<(usize, Option<(String, String)>)> {
    let empty = || IoError::EmptyTopic {
        path: files[bucket.first_channel.0].clone(),
        topic: Box::new(bucket.info.clone()),
        channel_offset: bucket.first_channel.1,
    };
    let is_transform = bucket.kind.is_some_and(|(pose_type, _)| pose_type.is_transform());
    if !is_transform {
        return match bucket.groups.first() {
            Some(group) if !group.rows.is_empty() => Ok((0, None)),
            _ => Err(empty()),
        };
    }
    if bucket.info.message_count == 0 {
        return Err(empty());
    }
    let pairs = || {
        let mut pairs: Vec<FramePairInfo> = bucket
            .groups
            .iter()
            .map(|group| FramePairInfo { parent: group.parent.clone(), child: group.child.clone(), count: group.count })
            .collect();
        pairs.sort_by(|a, b| (&a.parent, &a.child).cmp(&(&b.parent, &b.child)));
        pairs
    };
    let path = files[0].clone();
    let topic = bucket.info.topic.clone();
    let found = match &options.frames {
        Some((parent, child)) => bucket.groups.iter().position(|g| &g.parent == parent && &g.child == child),
        None if bucket.groups.len() == 1 => Some(0),
        None => None,
    };
    match found {
        Some(index) => {
            let group = &bucket.groups[index];
            Ok((index, Some((group.parent.clone(), group.child.clone()))))
        }
        None => Err(IoError::FramePair { path, topic, wanted: options.frames.clone(), pairs: pairs() }),
    }
}

impl Visitor for Scan<'_> {
    fn channel(&mut self, key: ChannelKey, at: At) -> usize {
        if let Some(&index) = self.index.get(&key) {
            return index;
        }
        let kind = PoseType::of_channel(&key.schema_name, &key.message_encoding);
        let decode = match self.options {
            Some(options) => kind.is_some() && options.topic.as_ref().is_none_or(|topic| topic == &key.topic),
            None => false,
        };
        let index = self.buckets.len();
        self.buckets.push(Bucket {
            info: TopicInfo {
                topic: key.topic.clone(),
                schema_name: key.schema_name.clone(),
                schema_encoding: key.schema_encoding.clone(),
                message_encoding: key.message_encoding.clone(),
                message_count: 0,
                log_time_span_ns: None,
                pose_type: kind.map(|(pose_type, _)| pose_type),
            },
            kind,
            decode,
            first_channel: (self.file, at.offset),
            groups: Vec::new(),
            error: None,
        });
        self.index.insert(key, index);
        index
    }

    fn message(&mut self, channel: usize, header: MessageHeader, data: &[u8], at: At) -> Result<()> {
        let bucket = &mut self.buckets[channel];
        bucket.info.message_count += 1;
        bucket.info.log_time_span_ns = Some(match bucket.info.log_time_span_ns {
            Some((first, last)) => (first.min(header.log_time), last.max(header.log_time)),
            None => (header.log_time, header.log_time),
        });
        let (Some(options), Some((pose_type, encoding)), true, None) =
            (self.options, bucket.kind, bucket.decode, &bucket.error)
        else {
            return Ok(());
        };
        let source = MessageRef { file: self.file, offset: at.offset, offset_in_chunk: at.in_chunk };
        let record_time = match options.time {
            TimeSource::Header => None,
            TimeSource::Log => Some(header.log_time),
            TimeSource::Publish => Some(header.publish_time),
        };
        let record_time = match record_time.map(i64::try_from) {
            None => None,
            Some(Ok(time)) => Some(time),
            Some(Err(_)) => {
                return self.fail(channel, at, format!("the record's time {} ns is too large", header.log_time));
            }
        };
        let transform = pose_type.is_transform();
        let wanted = options.frames.as_ref().filter(|_| transform);
        let groups = &mut bucket.groups;
        let result = decode_samples(pose_type, encoding, data, |sample| {
            let index = if transform {
                match groups.iter().position(|g| g.parent == sample.parent && g.child == sample.child) {
                    Some(index) => index,
                    None => {
                        groups.push(Group {
                            parent: sample.parent.to_owned(),
                            child: sample.child.to_owned(),
                            ..Group::default()
                        });
                        groups.len() - 1
                    }
                }
            } else {
                if groups.is_empty() {
                    groups.push(Group::default());
                }
                0
            };
            let group = &mut groups[index];
            group.count += 1;
            if wanted.is_none_or(|(parent, child)| parent == sample.parent && child == sample.child) {
                group.rows.push(Row {
                    stamp_ns: record_time.unwrap_or(sample.stamp_ns),
                    position: sample.position,
                    orientation: sample.orientation,
                    source,
                });
            }
        });
        match result {
            Ok(()) => Ok(()),
            Err(message) => self.fail(channel, at, message),
        }
    }
}

impl Scan<'_> {
    /// A message of `channel` that does not decode: an error now when its topic was named, kept
    /// for later otherwise (it matters only if the topic is picked).
    fn fail(&mut self, channel: usize, at: At, message: String) -> Result<()> {
        let bucket = &mut self.buckets[channel];
        let error = IoError::Message {
            location: MessageLocation {
                path: self.path.clone(),
                topic: bucket.info.topic.clone(),
                offset: at.offset,
                offset_in_chunk: at.in_chunk,
            },
            message,
        };
        if self.options.is_some_and(|options| options.topic.is_some()) {
            return Err(error);
        }
        bucket.error = Some(error);
        Ok(())
    }
}

/// The name of a record type, for messages.
fn record_name(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "header",
        op::FOOTER => "footer",
        op::SCHEMA => "schema",
        op::CHANNEL => "channel",
        op::MESSAGE => "message",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index",
        op::CHUNK_INDEX => "chunk index",
        op::ATTACHMENT => "attachment",
        op::ATTACHMENT_INDEX => "attachment index",
        op::STATISTICS => "statistics",
        op::METADATA => "metadata",
        op::METADATA_INDEX => "metadata index",
        op::SUMMARY_OFFSET => "summary offset",
        op::DATA_END => "data end",
        _ => "unknown",
    }
}

/// An `mcap` error with its causes, for a message.
fn describe(error: &mcap::McapError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        text += &format!(": {cause}");
        source = cause.source();
    }
    text
}

/// Largest record in a chunk, and largest buffer for one: bounds what a corrupt length can make
/// the reader allocate.
const MAX_CHUNK_BUFFER: u64 = 1 << 30;

/// The bytes between records: opcode and length.
const RECORD_HEADER: u64 = 9;

/// Walks the records of the MCAP file at `path`, reporting channels and messages to `visitor`.
fn walk(path: &Path, visitor: &mut impl Visitor) -> Result<()> {
    let open_error = |error| IoError::Open { path: path.to_path_buf(), error };
    let file = File::open(path).map_err(open_error)?;
    let len = file.metadata().map_err(open_error)?.len();
    let mut walker = Walker {
        path,
        reader: BufReader::with_capacity(1 << 20, file),
        len,
        schemas: HashMap::new(),
        channels: HashMap::new(),
        body: Vec::new(),
    };
    walker.run(visitor)
}

/// A schema as a channel needs it.
#[derive(Debug, Clone)]
struct SchemaInfo {
    name: String,
    encoding: String,
}

#[derive(Debug)]
struct Walker<'p> {
    path: &'p Path,
    reader: BufReader<File>,
    /// The file's length in bytes.
    len: u64,
    schemas: HashMap<u16, SchemaInfo>,
    /// MCAP channel id to the visitor's index.
    channels: HashMap<u16, usize>,
    /// Reused buffer for record bodies.
    body: Vec<u8>,
}

impl Walker<'_> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::mcap(self.path, offset, message)
    }

    fn read_error(&self, offset: u64, error: std::io::Error) -> IoError {
        self.error(offset, format!("cannot read the file: {error}"))
    }

    fn run(&mut self, visitor: &mut impl Visitor) -> Result<()> {
        let mut magic = [0u8; 8];
        let start = self.reader.read_exact(&mut magic);
        if self.len < 8 || start.is_err() || magic != mcap::MAGIC {
            return Err(self.error(
                0,
                format!(
                    "not an MCAP file: it does not start with the MCAP magic bytes (89 4D 43 41 50 30 0D 0A); \
                     the file is {} bytes long",
                    self.len
                ),
            ));
        }
        let mut pos = 8u64;
        let mut in_summary = false;
        loop {
            if self.len - pos < RECORD_HEADER {
                let what = if pos == self.len { "ends" } else { "ends in the middle of a record header" };
                return Err(self.error(pos, format!("the file {what} before its footer: it is truncated")));
            }
            let mut head = [0u8; 9];
            self.reader.read_exact(&mut head).map_err(|e| self.read_error(pos, e))?;
            let opcode = head[0];
            let body_len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
            let body_start = pos + RECORD_HEADER;
            let left = self.len - body_start;
            if body_len > left {
                return Err(self.error(
                    pos,
                    format!(
                        "the {} record is {body_len} bytes long, but the file has {left} bytes left: it is truncated",
                        record_name(opcode)
                    ),
                ));
            }
            match opcode {
                op::FOOTER => return self.finish(body_start, body_len),
                op::DATA_END => in_summary = true,
                _ => {}
            }
            match opcode {
                op::SCHEMA | op::CHANNEL | op::MESSAGE if !in_summary => {
                    self.read_body(body_start, body_len)?;
                    let body = std::mem::take(&mut self.body);
                    let result = self.record(opcode, &body, At { offset: pos, in_chunk: None }, visitor);
                    self.body = body;
                    result?;
                }
                op::CHUNK if !in_summary => self.chunk(pos, body_len, visitor)?,
                _ => self.reader.seek_relative(body_len as i64).map_err(|e| self.read_error(pos, e))?,
            }
            pos = body_start + body_len;
        }
    }

    /// After the footer: the closing magic, and nothing after it.
    fn finish(&mut self, body_start: u64, body_len: u64) -> Result<()> {
        let magic_at = body_start + body_len;
        if self.len - magic_at < 8 {
            return Err(self.error(magic_at, "the file ends before the closing MCAP magic bytes: it is truncated"));
        }
        self.reader.seek_relative(body_len as i64).map_err(|e| self.read_error(magic_at, e))?;
        let mut magic = [0u8; 8];
        self.reader.read_exact(&mut magic).map_err(|e| self.read_error(magic_at, e))?;
        if magic != mcap::MAGIC {
            return Err(self.error(magic_at, "bad magic: the footer is not followed by the MCAP magic bytes"));
        }
        Ok(())
    }

    fn read_body(&mut self, offset: u64, len: u64) -> Result<()> {
        self.body.clear();
        self.body.resize(len as usize, 0);
        let Self { reader, body, .. } = self;
        reader.read_exact(body).map_err(|e| IoError::mcap(self.path, offset, format!("cannot read the file: {e}")))
    }

    /// A schema, channel or message record, at the top level or in a chunk.
    fn record(&mut self, opcode: u8, body: &[u8], at: At, visitor: &mut impl Visitor) -> Result<()> {
        let located = |message: String| match at.in_chunk {
            Some(inner) => format!("in the record at byte {inner} of this chunk: {message}"),
            None => message,
        };
        match opcode {
            op::MESSAGE => {
                let Some((head, data)) = body.split_first_chunk::<22>() else {
                    return Err(self.error(
                        at.offset,
                        located(format!(
                            "the message record is {} bytes long, shorter than its 22-byte header",
                            body.len()
                        )),
                    ));
                };
                let header = MessageHeader {
                    channel_id: u16::from_le_bytes([head[0], head[1]]),
                    log_time: u64::from_le_bytes(head[6..14].try_into().expect("8 bytes")),
                    publish_time: u64::from_le_bytes(head[14..22].try_into().expect("8 bytes")),
                };
                let Some(&channel) = self.channels.get(&header.channel_id) else {
                    return Err(self.error(
                        at.offset,
                        located(format!(
                            "a message on channel {}, which no earlier channel record defines",
                            header.channel_id
                        )),
                    ));
                };
                visitor.message(channel, header, data, at)
            }
            op::SCHEMA => {
                match mcap::parse_record(opcode, body) {
                    Ok(Record::Schema { header, .. }) => {
                        self.schemas
                            .entry(header.id)
                            .or_insert(SchemaInfo { name: header.name, encoding: header.encoding });
                        Ok(())
                    }
                    Ok(_) => unreachable!("a schema opcode parses as a schema"),
                    Err(error) => Err(self
                        .error(at.offset, located(format!("the schema record does not parse: {}", describe(&error))))),
                }
            }
            op::CHANNEL => {
                match mcap::parse_record(opcode, body) {
                    Ok(Record::Channel(channel)) => {
                        if self.channels.contains_key(&channel.id) {
                            return Ok(());
                        }
                        let schema = match channel.schema_id {
                            0 => SchemaInfo { name: String::new(), encoding: String::new() },
                            id => match self.schemas.get(&id) {
                                Some(schema) => schema.clone(),
                                None => {
                                    return Err(self.error(
                                    at.offset,
                                    located(format!(
                                        "channel {} ({:?}) refers to schema {id}, which no earlier schema record defines",
                                        channel.id, channel.topic
                                    )),
                                ));
                                }
                            },
                        };
                        let key = ChannelKey {
                            topic: channel.topic,
                            schema_name: schema.name,
                            schema_encoding: schema.encoding,
                            message_encoding: channel.message_encoding,
                        };
                        let index = visitor.channel(key, at);
                        self.channels.insert(channel.id, index);
                        Ok(())
                    }
                    Ok(_) => unreachable!("a channel opcode parses as a channel"),
                    Err(error) => Err(self
                        .error(at.offset, located(format!("the channel record does not parse: {}", describe(&error))))),
                }
            }
            _ => Ok(()),
        }
    }

    /// A chunk record at `offset`: decompressed (and its CRC checked) by the `mcap` crate's
    /// reader, one record at a time.
    fn chunk(&mut self, offset: u64, body_len: u64, visitor: &mut impl Visitor) -> Result<()> {
        let total = (RECORD_HEADER + body_len) as usize;
        self.read_body(offset + RECORD_HEADER, body_len)?;
        // The declared uncompressed size, to bound the buffers (bytes 16..24 of the header).
        let declared = self.body.get(16..24).map_or(0, |b| u64::from_le_bytes(b.try_into().expect("8 bytes")));
        let limit = declared.max(body_len).min(MAX_CHUNK_BUFFER) as usize;
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_skip_start_magic(true)
                .with_skip_end_magic(true)
                .with_validate_chunk_crcs(true)
                .with_record_length_limit(limit),
        );
        let buffer = reader.insert(total);
        buffer[0] = op::CHUNK;
        buffer[1..9].copy_from_slice(&body_len.to_le_bytes());
        buffer[9..].copy_from_slice(&self.body);
        reader.notify_read(total);
        let mut inner = 0u64;
        let mut at_end = false;
        loop {
            match reader.next_event() {
                None => return Ok(()),
                Some(Ok(LinearReadEvent::ReadRequest(_))) if !at_end => {
                    // The whole chunk is in: asking for more means it ended cleanly (the next
                    // record would start here) or it is inconsistent, which EOF tells apart.
                    at_end = true;
                    reader.notify_read(0);
                }
                Some(Ok(LinearReadEvent::ReadRequest(_))) => {
                    return Err(self.error(offset, "the chunk's records do not fit its length"));
                }
                Some(Ok(LinearReadEvent::Record { opcode, data })) => {
                    let at = At { offset, in_chunk: Some(inner) };
                    inner += RECORD_HEADER + data.len() as u64;
                    self.record(opcode, data, at, visitor)?;
                }
                Some(Err(error)) => {
                    let what = match error {
                        mcap::McapError::BadChunkCrc { .. } => "the chunk is corrupt",
                        mcap::McapError::UnexpectedEof | mcap::McapError::UnexpectedEoc => {
                            "the chunk ends in the middle of a record"
                        }
                        _ => "the chunk does not decode",
                    };
                    return Err(self.error(offset, format!("{what}: {}", describe(&error))));
                }
            }
        }
    }
}
