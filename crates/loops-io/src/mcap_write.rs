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

use crate::message::PoseType;
use crate::samples::{WriteError, write_atomically};
use crate::table::PoseTable;

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

/// The orientation of a table without orientations.
const IDENTITY_XYZW: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

const NS_PER_S: i64 = 1_000_000_000;

/// A ROS 2 `builtin_interfaces/Time` that is also an MCAP time: `sec` is not negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct RosTime {
    sec: i32,
    nanosec: u32,
}

impl RosTime {
    /// The time of `stamp_ns` nanoseconds since the epoch, if it is in `[0, 2³¹)` seconds.
    fn of_ns(stamp_ns: i64) -> Option<Self> {
        let sec = i32::try_from(stamp_ns.div_euclid(NS_PER_S)).ok().filter(|&sec| sec >= 0)?;
        let nanosec = u32::try_from(stamp_ns.rem_euclid(NS_PER_S)).expect("below 10⁹");
        Some(Self { sec, nanosec })
    }

    /// The time of `stamp_s` seconds, if it is in `[0, 2³¹)` seconds: the shortest decimal that
    /// reads back as `stamp_s` when it has at most 9 decimals (what a text file printed:
    /// `1700000000.1`, whose `f64` is 1700000000.0999999046...), else the `f64` itself, to the
    /// nearest nanosecond.
    fn of_seconds(stamp_s: f64) -> Option<Self> {
        if !(0.0..2_147_483_648.0).contains(&stamp_s) {
            return None; // also NaN
        }
        // `Display` prints the shortest round-trip decimal, never with an exponent.
        let text = stamp_s.to_string();
        let (whole, decimals) = text.split_once('.').unwrap_or((&text, ""));
        if decimals.len() <= 9 {
            let whole_s: i64 = whole.parse().ok()?;
            let nanos: i64 = format!("{decimals:0<9}").parse().ok()?;
            return Self::of_ns(whole_s * NS_PER_S + nanos);
        }
        let whole_s = stamp_s.floor();
        // `stamp_s - whole_s` is exact: one rounding, of the nanoseconds.
        let nanos = ((stamp_s - whole_s) * 1e9).round() as i64;
        Self::of_ns(whole_s as i64 * NS_PER_S + nanos)
    }

    /// Nanoseconds since the epoch: the record's log and publish time.
    fn ns(self) -> u64 {
        u64::from(self.sec.unsigned_abs()) * NS_PER_S as u64 + u64::from(self.nanosec)
    }
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

/// Nanoseconds as exact decimal seconds, for messages.
fn exact_seconds(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let abs = ns.unsigned_abs();
    format!("{sign}{}.{:09}", abs / NS_PER_S as u64, abs % NS_PER_S as u64)
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
        encode_message(&mut data, message, stamp, &options.frame_id, position, orientation);
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

/// Encodes one message into `data` (cleared first).
fn encode_message(
    data: &mut Vec<u8>,
    message: &McapPoseMessage,
    stamp: RosTime,
    frame_id: &str,
    position: [f64; 3],
    orientation_xyzw: [f64; 4],
) {
    let mut cdr = CdrWriter::new(data);
    cdr.i32(stamp.sec);
    cdr.u32(stamp.nanosec);
    cdr.string(frame_id);
    if let McapPoseMessage::Odometry { child_frame_id } = message {
        cdr.string(child_frame_id);
    }
    cdr.f64s(&position);
    cdr.f64s(&orientation_xyzw);
    if let McapPoseMessage::Odometry { .. } = message {
        cdr.f64s(&[0.0; 36]); // pose.covariance
        cdr.f64s(&[0.0; 6]); // twist.twist
        cdr.f64s(&[0.0; 36]); // twist.covariance
    }
}

/// A little-endian ROS 2 CDR message being written: the encapsulation header `00 01 00 00`,
/// then each primitive aligned to its size relative to the start of the body (what `cdr.rs`
/// reads).
#[derive(Debug)]
struct CdrWriter<'a> {
    data: &'a mut Vec<u8>,
}

/// The encapsulation header: plain CDR, little endian, no options.
const ENCAPSULATION: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

impl<'a> CdrWriter<'a> {
    fn new(data: &'a mut Vec<u8>) -> Self {
        data.clear();
        data.extend_from_slice(&ENCAPSULATION);
        Self { data }
    }

    /// Pads with zeros to a multiple of `align` bytes from the start of the body.
    fn align(&mut self, align: usize) {
        let body_len = self.data.len() - ENCAPSULATION.len();
        let padding = (align - body_len % align) % align;
        self.data.resize(self.data.len() + padding, 0);
    }

    fn i32(&mut self, value: i32) {
        self.align(4);
        self.data.extend_from_slice(&value.to_le_bytes());
    }

    fn u32(&mut self, value: u32) {
        self.align(4);
        self.data.extend_from_slice(&value.to_le_bytes());
    }

    fn f64s(&mut self, values: &[f64]) {
        self.align(8);
        for value in values {
            self.data.extend_from_slice(&value.to_le_bytes());
        }
    }

    /// A string: `u32` length counting the terminating NUL, the bytes, the NUL. Checked to fit
    /// by [`check_table`].
    fn string(&mut self, text: &str) {
        debug_assert!(text.len() < u32::MAX as usize && !text.contains('\0'));
        self.u32(text.len() as u32 + 1);
        self.data.extend_from_slice(text.as_bytes());
        self.data.push(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::{MessageEncoding, decode_poses};

    #[test]
    fn pose_stamped_has_the_ros2_layout() {
        let mut data = Vec::new();
        let stamp = RosTime { sec: 7, nanosec: 9 };
        encode_message(&mut data, &McapPoseMessage::PoseStamped, stamp, "map", [1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]);
        // Encapsulation 4, then sec, nanosec, length, "map\0": the doubles start at body byte 16, aligned.
        assert_eq!(data[..20], [0, 1, 0, 0, 7, 0, 0, 0, 9, 0, 0, 0, 4, 0, 0, 0, b'm', b'a', b'p', 0]);
        assert_eq!(data.len(), 20 + 7 * 8);
        assert_eq!(data[20..28], 1.0f64.to_le_bytes());
        // "base\0" ends at byte 21 (17 of the body): 7 bytes of padding to the doubles at body byte 24.
        encode_message(&mut data, &McapPoseMessage::PoseStamped, stamp, "base", [1.0, 2.0, 3.0], IDENTITY_XYZW);
        assert_eq!(data[16..28], [b'b', b'a', b's', b'e', 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(data.len(), 28 + 7 * 8);
        let poses = decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &data).unwrap();
        assert_eq!((poses[0].stamp_ns, poses[0].frame_id.as_str()), (7_000_000_009, "base"));
    }

    #[test]
    fn odometry_decodes_with_its_child_frame() {
        let mut data = Vec::new();
        let message = McapPoseMessage::Odometry { child_frame_id: "base_link".into() };
        let stamp = RosTime { sec: 1, nanosec: 2 };
        encode_message(&mut data, &message, stamp, "odom", [1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]);
        let poses = decode_poses(PoseType::Odometry, MessageEncoding::Cdr, &data).unwrap();
        assert_eq!(poses.len(), 1);
        assert_eq!((poses[0].frame_id.as_str(), poses[0].child_frame_id.as_str()), ("odom", "base_link"));
        assert_eq!((poses[0].position, poses[0].orientation_xyzw), ([1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]));
    }

    #[test]
    fn times_are_checked_and_rounded_to_nanoseconds() {
        assert_eq!(RosTime::of_ns(0), Some(RosTime { sec: 0, nanosec: 0 }));
        assert_eq!(RosTime::of_ns(-1), None);
        let last = i64::from(i32::MAX) * NS_PER_S + 999_999_999;
        assert_eq!(RosTime::of_ns(last), Some(RosTime { sec: i32::MAX, nanosec: 999_999_999 }));
        assert_eq!(RosTime::of_ns(last + 1), None);
        assert_eq!(RosTime::of_ns(last).unwrap().ns(), last as u64);
        assert_eq!(RosTime::of_seconds(0.1), Some(RosTime { sec: 0, nanosec: 100_000_000 }));
        assert_eq!(RosTime::of_seconds(1_700_000_000.25), Some(RosTime { sec: 1_700_000_000, nanosec: 250_000_000 }));
        // As printed, not as the f64 (1700000000.2999999523...).
        assert_eq!(RosTime::of_seconds(1_700_000_000.3), Some(RosTime { sec: 1_700_000_000, nanosec: 300_000_000 }));
        assert_eq!(RosTime::of_seconds(1.0 / 3.0), Some(RosTime { sec: 0, nanosec: 333_333_333 }));
        assert_eq!(RosTime::of_seconds(-0.0), Some(RosTime { sec: 0, nanosec: 0 }));
        assert_eq!(RosTime::of_seconds(2_147_483_647.5), Some(RosTime { sec: i32::MAX, nanosec: 500_000_000 }));
        // Rounds up into the next second.
        assert_eq!(RosTime::of_seconds(1.0 - 1e-12), Some(RosTime { sec: 1, nanosec: 0 }));
        for bad in [-1e-9, f64::NAN, f64::INFINITY, 2_147_483_648.0] {
            assert_eq!(RosTime::of_seconds(bad), None, "{bad}");
        }
    }

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
