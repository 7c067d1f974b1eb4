//! Foxglove pose messages in protobuf and in JSON.
//!
//! The protobuf structs are written by hand with the field numbers of the Foxglove schemas
//! (`foxglove/PoseInFrame.proto`, ...; no protoc at build time). `timestamp` is a
//! `google.protobuf.Timestamp {int64 seconds = 1; int32 nanos = 2}`. In JSON, a timestamp is
//! `{"sec": .., "nsec": ..}` (`seconds` / `nanos` are accepted too).
//!
//! A message without an orientation gives the identity quaternion; other missing fields are 0,
//! as protobuf's defaults.

use prost::Message as _;
use serde::Deserialize;

use crate::pose_type::{PoseType, Sample};

/// `google.protobuf.Timestamp`.
#[derive(Clone, Copy, PartialEq, prost::Message)]
struct Timestamp {
    #[prost(int64, tag = "1")]
    seconds: i64,
    #[prost(int32, tag = "2")]
    nanos: i32,
}

/// `foxglove.Vector3`.
#[derive(Clone, Copy, PartialEq, prost::Message)]
struct Vector3 {
    #[prost(double, tag = "1")]
    x: f64,
    #[prost(double, tag = "2")]
    y: f64,
    #[prost(double, tag = "3")]
    z: f64,
}

/// `foxglove.Quaternion`. Its `x`, `y`, `z` are [`Vector3`]'s, tags included, as in the schemas:
/// two messages, each decoding its own fields only.
#[derive(Clone, Copy, PartialEq, prost::Message)]
struct Quaternion {
    #[prost(double, tag = "1")]
    x: f64,
    #[prost(double, tag = "2")]
    y: f64,
    #[prost(double, tag = "3")]
    z: f64,
    #[prost(double, tag = "4")]
    w: f64,
}

/// `foxglove.Pose`.
#[derive(Clone, Copy, PartialEq, prost::Message)]
struct Pose {
    #[prost(message, optional, tag = "1")]
    position: Option<Vector3>,
    #[prost(message, optional, tag = "2")]
    orientation: Option<Quaternion>,
}

/// `foxglove.PoseInFrame`.
#[derive(Clone, PartialEq, prost::Message)]
struct PoseInFrame {
    #[prost(message, optional, tag = "1")]
    timestamp: Option<Timestamp>,
    #[prost(string, tag = "2")]
    frame_id: String,
    #[prost(message, optional, tag = "3")]
    pose: Option<Pose>,
}

/// `foxglove.PosesInFrame`.
#[derive(Clone, PartialEq, prost::Message)]
struct PosesInFrame {
    #[prost(message, optional, tag = "1")]
    timestamp: Option<Timestamp>,
    #[prost(string, tag = "2")]
    frame_id: String,
    #[prost(message, repeated, tag = "3")]
    poses: Vec<Pose>,
}

/// `foxglove.FrameTransform`.
#[derive(Clone, PartialEq, prost::Message)]
struct FrameTransform {
    #[prost(message, optional, tag = "1")]
    timestamp: Option<Timestamp>,
    #[prost(string, tag = "2")]
    parent_frame_id: String,
    #[prost(string, tag = "3")]
    child_frame_id: String,
    #[prost(message, optional, tag = "4")]
    translation: Option<Vector3>,
    #[prost(message, optional, tag = "5")]
    rotation: Option<Quaternion>,
}

/// `foxglove.FrameTransforms`.
#[derive(Clone, PartialEq, prost::Message)]
struct FrameTransforms {
    #[prost(message, repeated, tag = "1")]
    transforms: Vec<FrameTransform>,
}

/// `foxglove.Odometry` (the velocities and covariances are not read).
#[derive(Clone, PartialEq, prost::Message)]
struct Odometry {
    #[prost(message, optional, tag = "1")]
    timestamp: Option<Timestamp>,
    #[prost(string, tag = "2")]
    frame_id: String,
    #[prost(string, tag = "3")]
    body_frame_id: String,
    #[prost(message, optional, tag = "4")]
    pose: Option<Pose>,
}

const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// A timestamp: `{"sec", "nsec"}` or `{"seconds", "nanos"}` in JSON, a
/// `google.protobuf.Timestamp` converted.
#[derive(Debug, Default, Clone, Copy, Deserialize)]
#[serde(default)]
struct Time {
    #[serde(alias = "seconds")]
    sec: i64,
    #[serde(alias = "nanos", alias = "nanosec")]
    nsec: i64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct Vec3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct Quat {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct PoseFields {
    position: Option<Vec3>,
    orientation: Option<Quat>,
}

/// The fields of every Foxglove pose type, all optional: one struct reads them all from JSON,
/// and holds a protobuf message converted, so that both encodings give their poses in one place
/// ([`emit_poses`]).
#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct Message {
    timestamp: Option<Time>,
    frame_id: String,
    parent_frame_id: String,
    child_frame_id: String,
    body_frame_id: String,
    pose: Option<PoseFields>,
    poses: Vec<PoseFields>,
    translation: Option<Vec3>,
    rotation: Option<Quat>,
    transforms: Vec<Message>,
}

impl From<Timestamp> for Time {
    fn from(t: Timestamp) -> Self {
        Self { sec: t.seconds, nsec: i64::from(t.nanos) }
    }
}

impl From<Vector3> for Vec3 {
    fn from(v: Vector3) -> Self {
        Self { x: v.x, y: v.y, z: v.z }
    }
}

impl From<Quaternion> for Quat {
    fn from(q: Quaternion) -> Self {
        Self { x: q.x, y: q.y, z: q.z, w: q.w }
    }
}

impl From<Pose> for PoseFields {
    fn from(pose: Pose) -> Self {
        Self { position: pose.position.map(Into::into), orientation: pose.orientation.map(Into::into) }
    }
}

impl From<FrameTransform> for Message {
    fn from(m: FrameTransform) -> Self {
        Self {
            timestamp: m.timestamp.map(Into::into),
            parent_frame_id: m.parent_frame_id,
            child_frame_id: m.child_frame_id,
            translation: m.translation.map(Into::into),
            rotation: m.rotation.map(Into::into),
            ..Self::default()
        }
    }
}

impl Message {
    /// The stamp in nanoseconds; `nanos` names the nanoseconds' field in messages.
    fn stamp_ns(&self, nanos: &str) -> Result<i64, String> {
        let Time { sec, nsec } = self.timestamp.unwrap_or_default();
        crate::pose_type::check_nanoseconds(nanos, nsec)?;
        sec.checked_mul(1_000_000_000)
            .and_then(|ns| ns.checked_add(nsec))
            .ok_or_else(|| format!("timestamp {sec} s {nsec} ns is out of range"))
    }
}

fn position(v: Option<&Vec3>) -> [f64; 3] {
    v.map_or([0.0; 3], |v| [v.x, v.y, v.z])
}

fn orientation(q: Option<&Quat>) -> [f64; 4] {
    q.map_or(IDENTITY, |q| [q.x, q.y, q.z, q.w])
}

fn pose_parts(pose: Option<&PoseFields>) -> ([f64; 3], [f64; 4]) {
    match pose {
        Some(pose) => (position(pose.position.as_ref()), orientation(pose.orientation.as_ref())),
        None => ([0.0; 3], IDENTITY),
    }
}

/// Decodes a protobuf message of a Foxglove type, calling `emit` for each pose.
pub(crate) fn decode_protobuf(pose_type: PoseType, data: &[u8], emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    let invalid =
        |error: prost::DecodeError| format!("invalid protobuf for {pose_type}: {}", crate::printable::one_line(&error));
    let m = match pose_type {
        PoseType::FoxglovePoseInFrame => {
            let m = PoseInFrame::decode(data).map_err(invalid)?;
            let pose = m.pose.map(Into::into);
            Message { timestamp: m.timestamp.map(Into::into), frame_id: m.frame_id, pose, ..Message::default() }
        }
        PoseType::FoxglovePosesInFrame => {
            let m = PosesInFrame::decode(data).map_err(invalid)?;
            let poses = m.poses.into_iter().map(Into::into).collect();
            Message { timestamp: m.timestamp.map(Into::into), frame_id: m.frame_id, poses, ..Message::default() }
        }
        PoseType::FoxgloveFrameTransform => FrameTransform::decode(data).map_err(invalid)?.into(),
        PoseType::FoxgloveFrameTransforms => {
            let m = FrameTransforms::decode(data).map_err(invalid)?;
            Message { transforms: m.transforms.into_iter().map(Into::into).collect(), ..Message::default() }
        }
        PoseType::FoxgloveOdometry => {
            let m = Odometry::decode(data).map_err(invalid)?;
            Message {
                timestamp: m.timestamp.map(Into::into),
                frame_id: m.frame_id,
                body_frame_id: m.body_frame_id,
                pose: m.pose.map(Into::into),
                ..Message::default()
            }
        }
        other => return Err(format!("{other} is not a Foxglove type")),
    };
    emit_poses(pose_type, &m, "timestamp.nanos", emit)
}

/// Decodes a JSON message of a Foxglove type, calling `emit` for each pose.
pub(crate) fn decode_json(pose_type: PoseType, data: &[u8], emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    let m: Message = serde_json::from_slice(data)
        .map_err(|error| format!("invalid JSON for {pose_type}: {}", crate::printable::one_line(&error)))?;
    emit_poses(pose_type, &m, "timestamp.nsec", emit)
}

/// Calls `emit` for each pose of `m`, a message of `pose_type` (`nanos`: the name of its stamps'
/// nanoseconds field, for errors).
fn emit_poses(pose_type: PoseType, m: &Message, nanos: &str, mut emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    match pose_type {
        PoseType::FoxglovePoseInFrame => {
            let (position, orientation) = pose_parts(m.pose.as_ref());
            emit(Sample { stamp_ns: m.stamp_ns(nanos)?, parent: &m.frame_id, child: "", position, orientation });
        }
        PoseType::FoxglovePosesInFrame => {
            let stamp_ns = m.stamp_ns(nanos)?;
            for pose in &m.poses {
                let (position, orientation) = pose_parts(Some(pose));
                emit(Sample { stamp_ns, parent: &m.frame_id, child: "", position, orientation });
            }
        }
        PoseType::FoxgloveFrameTransform => emit(transform(m, nanos)?),
        PoseType::FoxgloveFrameTransforms => {
            for (index, m) in m.transforms.iter().enumerate() {
                emit(transform(m, nanos).map_err(|error| format!("transform {index}: {error}"))?);
            }
        }
        PoseType::FoxgloveOdometry => {
            let (position, orientation) = pose_parts(m.pose.as_ref());
            emit(Sample {
                stamp_ns: m.stamp_ns(nanos)?,
                parent: &m.frame_id,
                child: &m.body_frame_id,
                position,
                orientation,
            });
        }
        other => return Err(format!("{other} is not a Foxglove type")),
    }
    Ok(())
}

fn transform<'a>(m: &'a Message, nanos: &str) -> Result<Sample<'a>, String> {
    Ok(Sample {
        stamp_ns: m.stamp_ns(nanos)?,
        parent: &m.parent_frame_id,
        child: &m.child_frame_id,
        position: position(m.translation.as_ref()),
        orientation: orientation(m.rotation.as_ref()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stamp, parent, child, position, orientation.
    type Row = (i64, String, String, [f64; 3], [f64; 4]);

    fn collect(pose_type: PoseType, json: bool, data: &[u8]) -> Result<Vec<Row>, String> {
        let mut out = Vec::new();
        let emit =
            |s: Sample<'_>| out.push((s.stamp_ns, s.parent.to_owned(), s.child.to_owned(), s.position, s.orientation));
        if json {
            decode_json(pose_type, data, emit)?
        } else {
            decode_protobuf(pose_type, data, emit)?
        }
        Ok(out)
    }

    #[test]
    fn protobuf_round_trip_through_prost() {
        let m = FrameTransforms {
            transforms: vec![
                FrameTransform {
                    timestamp: Some(Timestamp { seconds: 3, nanos: 4 }),
                    parent_frame_id: "map".into(),
                    child_frame_id: "base".into(),
                    translation: Some(Vector3 { x: 1.0, y: 2.0, z: 3.0 }),
                    rotation: None,
                },
                FrameTransform::default(),
            ],
        };
        let got = collect(PoseType::FoxgloveFrameTransforms, false, &m.encode_to_vec()).unwrap();
        assert_eq!(got[0], (3_000_000_004, "map".into(), "base".into(), [1.0, 2.0, 3.0], IDENTITY));
        assert_eq!(got[1], (0, String::new(), String::new(), [0.0; 3], IDENTITY));
    }

    #[test]
    fn json_messages_and_errors() {
        let got = collect(
            PoseType::FoxgloveFrameTransform,
            true,
            br#"{"timestamp":{"seconds":1,"nanos":2},"parent_frame_id":"a","child_frame_id":"b","translation":{"x":1},"rotation":{"w":1}}"#,
        )
        .unwrap();
        assert_eq!(got, [(1_000_000_002, "a".into(), "b".into(), [1.0, 0.0, 0.0], IDENTITY)]);
        let error = collect(PoseType::FoxglovePoseInFrame, true, b"{\"timestamp\": 5").unwrap_err();
        assert!(error.starts_with("invalid JSON for foxglove.PoseInFrame: "), "{error}");
        let error =
            collect(PoseType::FoxglovePoseInFrame, true, br#"{"timestamp":{"sec":9223372036854775807}}"#).unwrap_err();
        assert!(error.contains("out of range"), "{error}");
    }
}
