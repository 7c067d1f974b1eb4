//! Pose logs out as MCAP: one topic of ROS 2 `PoseStamped` (or `Odometry`) messages in CDR, as
//! the `mcap-ros2-support` writer makes them, for Foxglove and other MCAP tools and for our own
//! [`read_mcap`](crate::read_mcap).
//!
//! The file is chunked (zstd by default), with message indexes and a summary section (schema,
//! channel, statistics, chunk indexes), so indexed readers and `mcap info` see the topic and its
//! message count without reading the messages.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use mcap::records::MessageHeader;

use crate::atomic::write_atomically;
use crate::cdr_write::{IDENTITY_XYZW, RosTime, encode_message};
use crate::error::WriteError;
use crate::pose_type::PoseType;
use crate::table::{PoseTable, exact_seconds};

/// The message type [`write_mcap`] writes, in ROS 2 CDR with its `ros2msg` schema.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum McapPoseMessage {
    /// `geometry_msgs/msg/PoseStamped`: the pose in the frame `frame_id`.
    #[default]
    PoseStamped,
    /// `nav_msgs/msg/Odometry`: the pose of `child_frame_id` (the body, `base_link`) in the
    /// frame `frame_id`; the covariances and the twist are zeros.
    Odometry {
        /// The frame whose pose the message gives.
        child_frame_id: String,
    },
}

impl McapPoseMessage {
    /// The type as the reader knows it: [`PoseType::PoseStamped`] or [`PoseType::Odometry`].
    pub fn pose_type(&self) -> PoseType {
        match self {
            Self::PoseStamped => PoseType::PoseStamped,
            Self::Odometry { .. } => PoseType::Odometry,
        }
    }

    /// The `ros2msg` schema text: the type's definition, then each type it uses after a line of
    /// 80 `=` and `MSG: package/Type`, as rosbag2 and `mcap-ros2-support` write it.
    fn schema_text(&self) -> String {
        const TIME: &str = "int32 sec\nuint32 nanosec\n";
        const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
        const POINT: &str = "float64 x\nfloat64 y\nfloat64 z\n";
        const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
        const POSE: &str = "Point position\nQuaternion orientation\n";
        const BASE: [(&str, &str); 2] = [("std_msgs/Header", HEADER), ("builtin_interfaces/Time", TIME)];
        const POSE_PARTS: [(&str, &str); 3] =
            [("geometry_msgs/Pose", POSE), ("geometry_msgs/Point", POINT), ("geometry_msgs/Quaternion", QUATERNION)];
        let (main, dependencies): (&str, Vec<(&str, &str)>) = match self {
            Self::PoseStamped => ("std_msgs/Header header\nPose pose\n", [&BASE[..], &POSE_PARTS].concat()),
            Self::Odometry { .. } => (
                "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
                 geometry_msgs/TwistWithCovariance twist\n",
                [
                    &BASE[..],
                    &[("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n")],
                    &POSE_PARTS,
                    &[
                        ("geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"),
                        ("geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"),
                        ("geometry_msgs/Vector3", POINT),
                    ],
                ]
                .concat(),
            ),
        };
        let mut text = main.to_owned();
        for (name, definition) in dependencies {
            text += &format!("\n{}\nMSG: {name}\n{definition}", "=".repeat(80));
        }
        text
    }
}

/// How [`write_mcap`] compresses the chunks of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum McapCompression {
    /// Chunks stored as they are.
    None,
    /// Zstandard, the default of the MCAP writers and of rosbag2.
    #[default]
    Zstd,
    /// LZ4: faster, larger.
    Lz4,
}

impl McapCompression {
    /// The `mcap` crate's name for it.
    fn mcap(self) -> Option<mcap::Compression> {
        match self {
            Self::None => None,
            Self::Zstd => Some(mcap::Compression::Zstd),
            Self::Lz4 => Some(mcap::Compression::Lz4),
        }
    }
}

/// What [`write_mcap`] writes: which topic, frame, message type and compression.
///
/// # Examples
/// ```
/// use loops_io::{McapCompression, McapPoseMessage, McapWriteOptions};
/// let options = McapWriteOptions::default()
///     .topic("/odom")
///     .frame_id("odom")
///     .message(McapPoseMessage::Odometry { child_frame_id: "base_link".into() })
///     .compression(McapCompression::Lz4);
/// assert_eq!((McapWriteOptions::default().topic.as_str(), options.topic.as_str()), ("/pose", "/odom"));
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct McapWriteOptions {
    /// The topic: `/pose` by default.
    pub topic: String,
    /// The frame the poses are in, `header.frame_id`: `map` by default.
    pub frame_id: String,
    /// The message type: `PoseStamped` by default.
    pub message: McapPoseMessage,
    /// The chunks' compression: zstd by default.
    pub compression: McapCompression,
}

impl Default for McapWriteOptions {
    fn default() -> Self {
        Self {
            topic: "/pose".to_owned(),
            frame_id: "map".to_owned(),
            message: McapPoseMessage::default(),
            compression: McapCompression::default(),
        }
    }
}

impl McapWriteOptions {
    /// Writes on `topic`.
    pub fn topic(mut self, topic: impl Into<String>) -> Self {
        self.topic = topic.into();
        self
    }

    /// Gives the poses in the frame `frame_id`.
    pub fn frame_id(mut self, frame_id: impl Into<String>) -> Self {
        self.frame_id = frame_id.into();
        self
    }

    /// Writes messages of type `message`.
    pub fn message(mut self, message: McapPoseMessage) -> Self {
        self.message = message;
        self
    }

    /// Compresses the chunks with `compression`.
    pub fn compression(mut self, compression: McapCompression) -> Self {
        self.compression = compression;
        self
    }
}

/// Writes `table` as an MCAP file with one topic of ROS 2 messages (profile `ros2`, schema
/// encoding `ros2msg`, message encoding `cdr`): one message per pose, in table order.
///
/// - The stamp (`header.stamp`) is the pose's time: [`PoseTable::timestamps_ns`] exactly when
///   the table has them, else [`PoseTable::timestamps_s`] to the nearest nanosecond of the
///   shortest decimal that reads back as each (`1700000000.1` gives `.100000000`, not the
///   `.099999905` of the nearest `f64`), which [`seconds_of_ns`](crate::seconds_of_ns) turns
///   back into the same `f64`. Each
///   record's log time and publish time are the same stamp in nanoseconds since the Unix epoch.
/// - The position is `[x, y, z]` (a 2-D table's `z` is 0); the orientation is
///   [`PoseTable::orientations_xyzw`] as stored (not normalised), or the identity for a table
///   without orientations.
/// - The message is little-endian CDR (encapsulation `00 01 00 00`), the type's schema the
///   standard concatenated `ros2msg` definition (see [`McapPoseMessage`]).
///
/// So [`read_mcap`](crate::read_mcap) gives the table's positions, orientations and
/// nanosecond stamps back bit for bit, and the official Python reader (`mcap` with
/// `mcap-ros2-support`) decodes the same numbers.
///
/// The file is chunked (about 1 MiB of messages a chunk, compressed by
/// [`McapWriteOptions::compression`], single-threaded), with CRCs, message indexes and a
/// summary section. It is written to a temporary file beside `path`, then moved in place; an
/// existing file is replaced only with `overwrite`. Time O(n); memory O(n) for the stamps,
/// plus one chunk.
///
/// # Errors
/// - [`WriteError::Exists`] when `path` exists and `overwrite` is false;
/// - [`WriteError::Write`] when the file cannot be written, and, with an
///   [`io::ErrorKind::InvalidInput`] error naming the pose (its row, from 0), for a table that
///   MCAP and ROS 2 cannot hold: a stamp before 1970 (log times are unsigned) or after
///   2038-01-19 03:14:07 UTC (`header.stamp.sec` is an `int32`), a non-finite time, a frame id
///   with a NUL character, or vectors of different lengths (a table built by hand). Nothing is
///   written then.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{McapOptions, McapWriteOptions, read_mcap, read_tum, write_mcap};
/// let dir = std::env::temp_dir().join(format!("loops-io-doc-{}-mcap", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let source = dir.join("in.tum");
/// std::fs::write(&source, "1700000000.1 1 2 3 0 0 0 1\n1700000000.2 1.5 2 3 0 0 0.6 0.8\n")?;
/// let table = read_tum(&source)?;
/// let log = dir.join("drive.mcap");
/// write_mcap(&log, &table, &McapWriteOptions::default(), false)?;
/// let back = read_mcap(&log, &McapOptions::default())?;
/// assert_eq!((&back.positions, &back.orientations_xyzw), (&table.positions, &table.orientations_xyzw));
/// assert_eq!(back.timestamps_ns, Some(vec![1_700_000_000_100_000_000, 1_700_000_000_200_000_000]));
/// assert!(write_mcap(&log, &table, &McapWriteOptions::default(), false).is_err()); // not overwritten
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn write_mcap(
    path: impl AsRef<Path>,
    table: &PoseTable,
    options: &McapWriteOptions,
    overwrite: bool,
) -> Result<(), WriteError> {
    let path = path.as_ref();
    let invalid = |message: String| WriteError::Write {
        path: path.to_path_buf(),
        error: io::Error::new(io::ErrorKind::InvalidInput, message),
    };
    check_table(table, options).map_err(invalid)?;
    let stamps = ros_stamps(table).map_err(invalid)?;
    write_atomically(path, overwrite, |file| {
        write_messages(file, table, &stamps, options).map_err(|error| match error {
            mcap::McapError::Io(error) => error,
            error => io::Error::other(error),
        })
    })
}

/// Why `table` cannot be written with `options`, before anything is written.
fn check_table(table: &PoseTable, options: &McapWriteOptions) -> Result<(), String> {
    let len = table.positions.len();
    let lengths = [
        ("timestamps_s", Some(table.timestamps_s.len())),
        ("timestamps_ns", table.timestamps_ns.as_ref().map(Vec::len)),
        ("orientations_xyzw", table.orientations_xyzw.as_ref().map(Vec::len)),
    ];
    if let Some((name, Some(other))) = lengths.into_iter().find(|(_, other)| other.is_some_and(|other| other != len)) {
        return Err(format!("the table has {len} positions but {other} {name}"));
    }
    let mut frames = vec![("frame_id", &options.frame_id)];
    if let McapPoseMessage::Odometry { child_frame_id } = &options.message {
        frames.push(("child_frame_id", child_frame_id));
    }
    for (field, frame) in frames {
        // A CDR string ends at its first NUL for C and C++ readers; its length is a u32.
        if frame.contains('\0') || u32::try_from(frame.len() + 1).is_err() {
            return Err(format!(
                "{field} {frame:?} is not a ROS 2 string: it has a NUL character or is longer than 4 GiB"
            ));
        }
    }
    Ok(())
}

/// The stamp of each pose, or why one is not a ROS 2 and MCAP time.
fn ros_stamps(table: &PoseTable) -> Result<Vec<RosTime>, String> {
    let out_of_range = |index: usize, text: String, seconds: f64| {
        let why = if seconds.is_nan() || seconds.is_infinite() {
            "is not a finite number of seconds".to_owned()
        } else if seconds < 0.0 {
            "is before 1970-01-01 00:00:00 UTC (0 s): MCAP log times cannot be negative".to_owned()
        } else {
            format!("is after 2038-01-19 03:14:07 UTC ({} s): the seconds of a ROS 2 stamp are an int32", i32::MAX)
        };
        format!("pose {index}: its stamp, {text} s, {why}")
    };
    match &table.timestamps_ns {
        Some(stamps_ns) => stamps_ns
            .iter()
            .enumerate()
            .map(|(index, &ns)| RosTime::of_ns(ns).ok_or_else(|| out_of_range(index, exact_seconds(ns), ns as f64)))
            .collect(),
        None => table
            .timestamps_s
            .iter()
            .enumerate()
            .map(|(index, &s)| RosTime::of_seconds(s).ok_or_else(|| out_of_range(index, s.to_string(), s)))
            .collect(),
    }
}

/// Writes the whole MCAP file into `file`.
fn write_messages(
    file: &mut File,
    table: &PoseTable,
    stamps: &[RosTime],
    options: &McapWriteOptions,
) -> mcap::McapResult<()> {
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .library(concat!("loops-io ", env!("CARGO_PKG_VERSION")))
        .compression(options.compression.mcap())
        // One thread: pose logs are small, and the output does not depend on the core count.
        .compression_threads(0)
        .create(BufWriter::new(file))?;
    let message = &options.message;
    let schema_id =
        writer.add_schema(message.pose_type().schema_name(), "ros2msg", message.schema_text().as_bytes())?;
    let channel_id = writer.add_channel(schema_id, &options.topic, "cdr", &BTreeMap::new())?;
    let mut data = Vec::new();
    for (index, (&stamp, &position)) in stamps.iter().zip(&table.positions).enumerate() {
        let orientation = table.orientations_xyzw.as_ref().map_or(IDENTITY_XYZW, |q| q[index]);
        let child_frame_id = match message {
            McapPoseMessage::PoseStamped => None,
            McapPoseMessage::Odometry { child_frame_id } => Some(child_frame_id.as_str()),
        };
        encode_message(&mut data, stamp, &options.frame_id, child_frame_id, position, orientation);
        let header = MessageHeader {
            channel_id,
            // A u32 counter wraps.
            sequence: index as u32,
            log_time: stamp.ns(),
            publish_time: stamp.ns(),
        };
        writer.write_to_known_channel(&header, &data)?;
    }
    writer.finish()?;
    writer.into_inner().flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemas_are_the_concatenated_definitions() {
        let text = McapPoseMessage::PoseStamped.schema_text();
        let separator = "=".repeat(80);
        assert!(text.starts_with(&format!("std_msgs/Header header\nPose pose\n\n{separator}\nMSG: std_msgs/Header\n")));
        assert_eq!(text.matches("\nMSG: ").count(), 5);
        let odometry = McapPoseMessage::Odometry { child_frame_id: String::new() }.schema_text();
        assert_eq!(odometry.matches("\nMSG: ").count(), 9);
        assert!(odometry.ends_with("MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"));
    }
}
