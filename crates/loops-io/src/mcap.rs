//! MCAP files (ROS 2 and Foxglove logs): the poses of one topic, and the list of topics.
//!
//! The file is walked record by record from the start (`mcap_records`), so every record has a
//! byte offset to name in errors; chunks are decompressed (zstd, lz4, or none) as streams and
//! their CRCs checked, so memory stays at one record plus the poses, whatever a corrupt length
//! declares. The walk goes to the closing magic and checks what the file says of itself: the
//! data and summary CRCs, the message counts of the message indexes and of the summary's
//! statistics, the chunks of its chunk indexes. A file cut short or missing messages is an
//! error naming the offset, not a silently shorter trajectory. This module sorts the channels
//! into topics and keeps the poses of the topic read.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::error::{IoError, MessageLocation, Result};
use crate::frame_tree::{self, Link, Row};
use crate::mcap_records::{At, ChannelKey, MessageHeader, Visitor, walk};
use crate::message::decode_samples;
use crate::pose_type::{MessageEncoding, PoseType};
use crate::table::{MessageRef, MessageSources, PoseTable, seconds_of_ns};
use crate::topic::{FramePairInfo, TopicInfo};

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
    /// `None` takes the topic's one pair. Not used for other topics. Frames that no single
    /// transform links are composed along the tree of the topic's transforms and of its static
    /// topic (`/tf` → `/tf_static`): see [`read_mcap_files`].
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
///   only pair. When no transform goes straight from `parent` to `child`, the pose is composed
///   along the tree of transforms (`map → odom → base_link → velodyne`) of the topic and of its
///   static topic (the topic's name with `_static`: `/tf_static` for `/tf`), whose transforms
///   hold at all times. The poses are those of the moving link nearest to `child`, at its
///   stamps; the other moving links are interpolated at each such stamp (positions linearly,
///   rotations by slerp between the transforms around it), and a stamp outside their span has
///   no pose (as in TF, nothing is extrapolated). Each pose keeps the message of that link.
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
///   short or has bytes after its closing magic, has a chunk whose CRC or decompression fails
///   (or that declares more than 4 GiB), a record that does not parse (a length past its
///   record's end, a name that is not UTF-8), a data or summary CRC that does not match, or
///   fewer (or more) messages than its message indexes or statistics count, or a chunk its
///   chunk index lists missing (a chunk whose opcode is corrupt);
/// - [`IoError::Message`] naming the file, topic and offset for a message of the topic read
///   that does not decode (shorter than its type, a stamp's nanoseconds of 10⁹ or more, over
///   64 MiB, ...);
/// - [`IoError::TopicNotFound`], [`IoError::UnsupportedTopic`] (a type this crate does not
///   read), [`IoError::EmptyTopic`] for the topic named; [`IoError::NoPoseTopic`] and
///   [`IoError::AmbiguousTopic`] when none is named;
/// - [`IoError::FramePair`] for a transform topic with several pairs and none named;
///   [`IoError::FrameTree`] when the frames named are not linked by the transforms (naming the
///   top of each chain), a frame has two parents, every link between them is static, or no
///   stamp falls within the span of every moving link;
/// - [`IoError::Trajectory`] holding [`loops_core::Error::InvalidParameter`] for no file at all.
pub fn read_mcap_files<P: AsRef<Path>>(paths: &[P], options: &McapOptions) -> Result<PoseTable> {
    let files: Vec<PathBuf> = paths.iter().map(|path| path.as_ref().to_path_buf()).collect();
    if files.is_empty() {
        return Err(IoError::invalid(Path::new(""), "number of MCAP files", 0.0, "at least one file"));
    }
    let mut scan = Scan::new(Some(options));
    for (index, path) in files.iter().enumerate() {
        scan.file = index;
        scan.path = path.clone();
        walk(path, &mut scan)?;
    }
    scan.into_table(files, options)
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
pub(crate) struct Scan<'o> {
    /// `None` to count only.
    options: Option<&'o McapOptions>,
    /// The file being walked: its index and path.
    pub(crate) file: usize,
    pub(crate) path: PathBuf,
    buckets: Vec<Bucket>,
    index: HashMap<ChannelKey, usize>,
    /// Decodes transform topics only, to count their frame pairs, keeping no pose.
    frames_only: bool,
}

/// The options of a scan that counts frame pairs: every transform topic, stamps from headers.
static FRAME_PAIR_OPTIONS: McapOptions = McapOptions { topic: None, time: TimeSource::Header, frames: None };

impl<'o> Scan<'o> {
    pub(crate) fn new(options: Option<&'o McapOptions>) -> Self {
        Self { options, file: 0, path: PathBuf::new(), buckets: Vec::new(), index: HashMap::new(), frames_only: false }
    }

    /// A scan that decodes the transform topics (TF, `FrameTransform`) to count their frame
    /// pairs ([`frame_pairs`](Self::frame_pairs)), and counts the messages of the others.
    pub(crate) fn frame_pairs_only() -> Scan<'static> {
        Scan { frames_only: true, ..Scan::new(Some(&FRAME_PAIR_OPTIONS)) }
    }

    /// The frame pairs of each transform topic with messages, sorted by topic then pair; the
    /// first message that did not decode is an error.
    pub(crate) fn frame_pairs(&mut self) -> Result<Vec<(String, Vec<FramePairInfo>)>> {
        let mut topics = Vec::new();
        for bucket in &mut self.buckets {
            if !bucket.kind.is_some_and(|(pose_type, _)| pose_type.is_transform()) || bucket.info.message_count == 0 {
                continue;
            }
            if let Some(error) = bucket.error.take() {
                return Err(error);
            }
            topics.push((bucket.info.topic.clone(), pairs_of(bucket)));
        }
        topics.sort_by(|a, b| a.0.cmp(&b.0));
        Ok(topics)
    }

    /// The poses of the topic to read, as a table (see [`read_mcap_files`]): `files` are the
    /// files walked, in order; the first names the table.
    pub(crate) fn into_table(mut self, files: Vec<PathBuf>, options: &McapOptions) -> Result<PoseTable> {
        let Some(first) = files.first().cloned() else {
            return Err(IoError::invalid(Path::new(""), "number of files", 0.0, "at least one file"));
        };
        let chosen = self.choose(&first, options)?;
        let bucket = &self.buckets[chosen];
        let (rows, frames) = match choose_group(&files, bucket, options) {
            Ok((group, frames)) => {
                let mut rows = std::mem::take(&mut self.buckets[chosen].groups[group].rows);
                rows.sort_by_key(|row| row.stamp_ns);
                (rows, frames)
            }
            Err(IoError::FramePair { path, topic, wanted: Some((parent, child)), pairs }) => {
                let rows = self.composed(chosen, &parent, &child).map_err(|message| {
                    let on_topic = |frame: &str| pairs.iter().any(|pair| pair.parent == frame || pair.child == frame);
                    if on_topic(&parent) || on_topic(&child) {
                        IoError::FrameTree { path: path.clone(), topic: topic.clone(), message }
                    } else {
                        // Neither frame is on the topic: the list of pairs says more.
                        IoError::FramePair {
                            path: path.clone(),
                            topic: topic.clone(),
                            wanted: Some((parent.clone(), child.clone())),
                            pairs: pairs.clone(),
                        }
                    }
                })?;
                (rows, Some((parent, child)))
            }
            Err(error) => return Err(error),
        };
        let bucket = &self.buckets[chosen];
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

    /// The topics, sorted.
    pub(crate) fn topics(&self) -> Vec<TopicInfo> {
        let mut topics: Vec<TopicInfo> = self.buckets.iter().map(|bucket| bucket.info.clone()).collect();
        topics.sort_by(|a, b| {
            (&a.topic, &a.schema_name, &a.message_encoding).cmp(&(&b.topic, &b.schema_name, &b.message_encoding))
        });
        topics
    }

    /// The poses of `child` in `parent` composed along the transforms of the bucket `chosen`
    /// and of its static topic (see [`read_mcap_files`]).
    fn composed(&mut self, chosen: usize, parent: &str, child: &str) -> std::result::Result<Vec<Row>, String> {
        let static_topic = static_topic_of(&self.buckets[chosen].info.topic);
        for bucket in &mut self.buckets {
            for group in &mut bucket.groups {
                group.rows.sort_by_key(|row| row.stamp_ns);
            }
        }
        let mut links = Vec::new();
        for (index, bucket) in self.buckets.iter().enumerate() {
            let is_static = bucket.info.topic == static_topic;
            if index != chosen && !(is_static && bucket.kind.is_some_and(|(t, _)| t.is_transform())) {
                continue;
            }
            links.extend(bucket.groups.iter().map(|group| Link {
                parent: &group.parent,
                child: &group.child,
                rows: &group.rows,
                is_static,
            }));
        }
        frame_tree::compose(&links, parent, child)
    }

    /// The index of the bucket to read: the topic named, or the one topic with poses.
    fn choose(&mut self, first: &Path, options: &McapOptions) -> Result<usize> {
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
        Ok(chosen[0])
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
        None => Err(IoError::FramePair { path, topic, wanted: options.frames.clone(), pairs: pairs_of(bucket) }),
    }
}

/// The static topic that goes with a transform topic: `/tf_static` for `/tf`.
fn static_topic_of(topic: &str) -> String {
    format!("{topic}_static")
}

/// The frame pairs of a transform topic's bucket with their transform counts, sorted.
fn pairs_of(bucket: &Bucket) -> Vec<FramePairInfo> {
    let mut pairs: Vec<FramePairInfo> = bucket
        .groups
        .iter()
        .map(|group| FramePairInfo { parent: group.parent.clone(), child: group.child.clone(), count: group.count })
        .collect();
    pairs.sort_by(|a, b| (&a.parent, &a.child).cmp(&(&b.parent, &b.child)));
    pairs
}

impl Visitor for Scan<'_> {
    fn decodes(&self, channel: usize) -> bool {
        self.buckets[channel].decode
    }

    fn channel(&mut self, key: ChannelKey, at: At) -> usize {
        if let Some(&index) = self.index.get(&key) {
            return index;
        }
        let kind = PoseType::of_channel(&key.schema_name, &key.message_encoding);
        let decode = match self.options {
            Some(options) => {
                kind.is_some_and(|(pose_type, _)| !self.frames_only || pose_type.is_transform())
                    && options.topic.as_ref().is_none_or(|topic| {
                        topic == &key.topic
                            || (options.frames.is_some()
                                && kind.is_some_and(|(pose_type, _)| pose_type.is_transform())
                                && static_topic_of(topic) == key.topic)
                    })
            }
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
        // With frames named, every pair is kept: the pair may be a chain of them.
        let keep_rows = !self.frames_only;
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
            if keep_rows {
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
