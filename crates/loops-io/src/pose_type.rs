//! The message types that carry poses, their encodings, and one decoded pose as the decoders
//! hand it over: the vocabulary shared by the decoders (`cdr`, `foxglove`), the MCAP reader and
//! the errors.

use std::fmt;

/// The types [`read_mcap`](crate::read_mcap) reads, as error messages list them.
pub(crate) const SUPPORTED_TYPES: &str = "geometry_msgs/msg/PoseStamped, geometry_msgs/msg/PoseWithCovarianceStamped, \
     geometry_msgs/msg/TransformStamped, nav_msgs/msg/Odometry, tf2_msgs/msg/TFMessage in cdr or ros1 (and tf/tfMessage \
     in ros1); foxglove.PoseInFrame, \
     foxglove.PosesInFrame, foxglove.FrameTransform, foxglove.FrameTransforms, foxglove.Odometry in protobuf or json";

/// A message type this crate reads poses from.
///
/// ROS types come in CDR (ROS 2) or in the ROS 1 serialisation; Foxglove types in protobuf or
/// JSON ([`MessageEncoding`]). A type is matched by its schema name:
/// `geometry_msgs/msg/PoseStamped` (or the ROS 1 spelling `geometry_msgs/PoseStamped`; `tf/tfMessage`
/// is read as `TFMessage`), `foxglove.PoseInFrame`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum PoseType {
    /// `geometry_msgs/msg/PoseStamped`: one pose in `header.frame_id`.
    PoseStamped,
    /// `geometry_msgs/msg/PoseWithCovarianceStamped`: one pose (the covariance is skipped).
    PoseWithCovarianceStamped,
    /// `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in `header.frame_id`.
    TransformStamped,
    /// `nav_msgs/msg/Odometry`: the pose of `child_frame_id` in `header.frame_id` (the twist is
    /// skipped).
    Odometry,
    /// `tf2_msgs/msg/TFMessage`: several transforms per message; one frame pair is read.
    TfMessage,
    /// `foxglove.PoseInFrame`: one pose in `frame_id`.
    FoxglovePoseInFrame,
    /// `foxglove.PosesInFrame`: several poses in `frame_id`, all at the message's timestamp.
    FoxglovePosesInFrame,
    /// `foxglove.FrameTransform`: the pose of `child_frame_id` in `parent_frame_id`.
    FoxgloveFrameTransform,
    /// `foxglove.FrameTransforms`: several transforms per message; one frame pair is read.
    FoxgloveFrameTransforms,
    /// `foxglove.Odometry`: the pose of `body_frame_id` in `frame_id`.
    FoxgloveOdometry,
}

/// How the messages of a topic are encoded: the MCAP channel's message encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum MessageEncoding {
    /// ROS 2 CDR (`cdr`); a message compressed by rosbag2 (zstd, or an lz4 frame) is
    /// decompressed first.
    Cdr,
    /// The ROS 1 serialisation (`ros1`): little endian, unaligned, no encapsulation header.
    Ros1,
    /// Protocol buffers (`protobuf`).
    Protobuf,
    /// JSON (`json`).
    Json,
}

impl PoseType {
    /// Every type, in the order messages list them.
    pub const ALL: [PoseType; 10] = [
        Self::PoseStamped,
        Self::PoseWithCovarianceStamped,
        Self::TransformStamped,
        Self::Odometry,
        Self::TfMessage,
        Self::FoxglovePoseInFrame,
        Self::FoxglovePosesInFrame,
        Self::FoxgloveFrameTransform,
        Self::FoxgloveFrameTransforms,
        Self::FoxgloveOdometry,
    ];

    /// The schema name: `geometry_msgs/msg/PoseStamped`, `foxglove.PoseInFrame`, ...
    pub fn schema_name(self) -> &'static str {
        match self {
            Self::PoseStamped => "geometry_msgs/msg/PoseStamped",
            Self::PoseWithCovarianceStamped => "geometry_msgs/msg/PoseWithCovarianceStamped",
            Self::TransformStamped => "geometry_msgs/msg/TransformStamped",
            Self::Odometry => "nav_msgs/msg/Odometry",
            Self::TfMessage => "tf2_msgs/msg/TFMessage",
            Self::FoxglovePoseInFrame => "foxglove.PoseInFrame",
            Self::FoxglovePosesInFrame => "foxglove.PosesInFrame",
            Self::FoxgloveFrameTransform => "foxglove.FrameTransform",
            Self::FoxgloveFrameTransforms => "foxglove.FrameTransforms",
            Self::FoxgloveOdometry => "foxglove.Odometry",
        }
    }

    /// Whether this is a ROS type (CDR or ROS 1) rather than a Foxglove one (protobuf, JSON).
    pub fn is_ros(self) -> bool {
        matches!(
            self,
            Self::PoseStamped
                | Self::PoseWithCovarianceStamped
                | Self::TransformStamped
                | Self::Odometry
                | Self::TfMessage
        )
    }

    /// Whether the type holds transforms between named frames, of which one pair is read:
    /// `TransformStamped`, `TFMessage`, `FrameTransform`, `FrameTransforms`. Other types hold
    /// the poses of one thing and are preferred when a topic is picked automatically.
    pub fn is_transform(self) -> bool {
        matches!(
            self,
            Self::TransformStamped | Self::TfMessage | Self::FoxgloveFrameTransform | Self::FoxgloveFrameTransforms
        )
    }

    /// The type and encoding of a channel with this schema name and message encoding, if this
    /// crate reads it: ROS types in `cdr` or `ros1`, Foxglove types in `protobuf` or `json`.
    ///
    /// # Examples
    /// ```
    /// use loops_io::{MessageEncoding, PoseType};
    /// assert_eq!(
    ///     PoseType::of_channel("nav_msgs/msg/Odometry", "cdr"),
    ///     Some((PoseType::Odometry, MessageEncoding::Cdr))
    /// );
    /// assert_eq!(PoseType::of_channel("foxglove.PoseInFrame", "cdr"), None);
    /// ```
    pub fn of_channel(schema_name: &str, message_encoding: &str) -> Option<(PoseType, MessageEncoding)> {
        let encoding = match message_encoding {
            "cdr" => MessageEncoding::Cdr,
            "ros1" => MessageEncoding::Ros1,
            "protobuf" => MessageEncoding::Protobuf,
            "json" => MessageEncoding::Json,
            _ => return None,
        };
        let pose_type = Self::ALL.into_iter().find(|t| {
            let name = t.schema_name();
            name == schema_name
                || (t.is_ros() && name.replacen("/msg/", "/", 1) == schema_name)
                || (*t == Self::TfMessage && schema_name == "tf/tfMessage")
        })?;
        (pose_type.is_ros() == encoding.is_ros()).then_some((pose_type, encoding))
    }
}

impl MessageEncoding {
    /// Whether this is a ROS encoding (CDR or ROS 1), of ROS types.
    pub fn is_ros(self) -> bool {
        matches!(self, Self::Cdr | Self::Ros1)
    }
}

impl fmt::Display for PoseType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.schema_name())
    }
}

impl fmt::Display for MessageEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Cdr => "cdr",
            Self::Ros1 => "ros1",
            Self::Protobuf => "protobuf",
            Self::Json => "json",
        })
    }
}

/// One pose of a message, borrowing the frame names from the message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Sample<'a> {
    /// The message's (or transform's) stamp, nanoseconds.
    pub(crate) stamp_ns: i64,
    /// The frame the pose is in: `header.frame_id`, `parent_frame_id`.
    pub(crate) parent: &'a str,
    /// The frame the pose is of, for transforms and odometry; empty otherwise.
    pub(crate) child: &'a str,
    pub(crate) position: [f64; 3],
    pub(crate) orientation: [f64; 4],
}

/// The nanoseconds of a time stamp (`builtin_interfaces/Time.nanosec`, ROS 1 `nsecs`,
/// `google.protobuf.Timestamp.nanos`, a record's time), which every format keeps in
/// `0..10⁹`: a larger value is a corrupt stamp, not a time one more second on.
///
/// # Errors
/// What is wrong, naming `field`.
pub(crate) fn check_nanoseconds(field: &str, nanoseconds: i64) -> Result<(), String> {
    if (0..1_000_000_000).contains(&nanoseconds) {
        Ok(())
    } else {
        Err(format!(
            "{field} is {nanoseconds} ns, outside 0 to 999999999 (a second's nanoseconds): the stamp is corrupt"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_are_matched_by_schema_name_and_encoding() {
        for pose_type in PoseType::ALL {
            let encodings: &[_] = if pose_type.is_ros() { &["cdr"] } else { &["protobuf", "json"] };
            for encoding in encodings {
                assert_eq!(PoseType::of_channel(pose_type.schema_name(), encoding).map(|t| t.0), Some(pose_type));
            }
        }
        assert_eq!(PoseType::of_channel("geometry_msgs/PoseStamped", "cdr").map(|t| t.0), Some(PoseType::PoseStamped));
        assert_eq!(PoseType::of_channel("geometry_msgs/PoseStamped", "ros1").map(|t| t.0), Some(PoseType::PoseStamped));
        assert_eq!(PoseType::of_channel("tf/tfMessage", "ros1").map(|t| t.0), Some(PoseType::TfMessage));
        assert_eq!(PoseType::of_channel("foxglove.PoseInFrame", "ros1"), None);
        assert_eq!(PoseType::of_channel("nav_msgs/msg/Odometry", "json"), None);
        assert_eq!(PoseType::of_channel("sensor_msgs/msg/Imu", "cdr"), None);
    }
}
