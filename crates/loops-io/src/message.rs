//! Decoding one message of a type that carries poses ([`PoseType`]), by its encoding.

use crate::pose_type::{MessageEncoding, PoseType, Sample};
use crate::{cdr, foxglove};

/// Decodes one message, calling `emit` for each pose in it.
pub(crate) fn decode_samples(
    pose_type: PoseType,
    encoding: MessageEncoding,
    data: &[u8],
    emit: impl FnMut(Sample<'_>),
) -> Result<(), String> {
    match encoding {
        MessageEncoding::Cdr => match crate::compression::message_frame(data) {
            None => cdr::decode(pose_type, data, emit),
            Some(frame) => cdr::decode(pose_type, &crate::compression::decompress_message(frame, data)?, emit),
        },
        MessageEncoding::Ros1 => crate::ros1_message::decode(pose_type, data, emit),
        MessageEncoding::Protobuf => foxglove::decode_protobuf(pose_type, data, emit),
        MessageEncoding::Json => foxglove::decode_json(pose_type, data, emit),
    }
}

/// A pose decoded from one message.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedPose {
    /// The stamp in the message (`header.stamp`, `timestamp`), nanoseconds since its epoch.
    pub stamp_ns: i64,
    /// The frame the pose is in: `header.frame_id`, `frame_id`, `parent_frame_id`.
    pub frame_id: String,
    /// The frame the pose is of (`child_frame_id`, `body_frame_id`) for transforms and
    /// odometry; empty for the other types.
    pub child_frame_id: String,
    /// Position, or translation, `[x, y, z]`.
    pub position: [f64; 3],
    /// Orientation, or rotation, `[qx, qy, qz, qw]`, as in the message (not normalised). A
    /// Foxglove message without an orientation gives the identity.
    pub orientation_xyzw: [f64; 4],
}

/// Why a message does not decode: a message shorter than its type, a bad CDR encapsulation,
/// invalid protobuf or JSON, a type in an encoding this crate does not read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct DecodeError(String);

/// The poses in one message of `pose_type` in `encoding`: one for most types, any number for
/// `TFMessage`, `PosesInFrame` and `FrameTransforms`. This is what the MCAP reader does for
/// each message; it is public for decoding messages from elsewhere (a live stream, a database).
///
/// Time O(message size).
///
/// # Errors
/// [`DecodeError`] saying what is wrong, naming the field: for CDR a bad encapsulation header
/// or a message shorter than its type, for protobuf and JSON a message that does not parse, for
/// a ROS 2 type in protobuf or JSON or a Foxglove type in CDR that the pair is not read.
///
/// # Examples
/// ```
/// use loops_io::{MessageEncoding, PoseType, decode_poses};
///
/// let json = br#"{"timestamp": {"sec": 10, "nsec": 5}, "frame_id": "map",
///     "pose": {"position": {"x": 1, "y": 2, "z": 3}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}}"#;
/// let poses = decode_poses(PoseType::FoxglovePoseInFrame, MessageEncoding::Json, json)?;
/// assert_eq!((poses[0].stamp_ns, poses[0].position), (10_000_000_005, [1.0, 2.0, 3.0]));
///
/// let short = [0u8, 1, 0, 0, 1, 0, 0, 0];
/// let error = decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &short).unwrap_err();
/// assert!(error.to_string().contains("shorter than its type"));
/// # Ok::<(), loops_io::DecodeError>(())
/// ```
pub fn decode_poses(
    pose_type: PoseType,
    encoding: MessageEncoding,
    data: &[u8],
) -> Result<Vec<DecodedPose>, DecodeError> {
    if pose_type.is_ros() != encoding.is_ros() {
        return Err(DecodeError(format!("{pose_type} in {encoding} is not a type this crate reads")));
    }
    let mut poses = Vec::new();
    decode_samples(pose_type, encoding, data, |sample| {
        poses.push(DecodedPose {
            stamp_ns: sample.stamp_ns,
            frame_id: sample.parent.to_owned(),
            child_frame_id: sample.child.to_owned(),
            position: sample.position,
            orientation_xyzw: sample.orientation,
        });
    })
    .map_err(DecodeError)?;
    Ok(poses)
}
