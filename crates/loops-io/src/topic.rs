//! What an MCAP file or a bag holds, as [`list_topics`](crate::list_topics) reports it and as errors
//! list it: its topics, and the frame pairs of a transform topic.

use std::fmt;

use crate::pose_type::PoseType;
use crate::printable::printable;

/// One topic of an MCAP file or a bag (or of several files, counted together), as
/// [`list_topics`](crate::list_topics) reports it and as errors list them.
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
        write!(
            f,
            "{} ({}, {}, {} message{plural})",
            printable(&self.topic),
            printable(schema),
            printable(&self.message_encoding),
            self.message_count
        )
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
        write!(f, "{} -> {} ({})", printable(&self.parent), printable(&self.child), self.count)
    }
}
