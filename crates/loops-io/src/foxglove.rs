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

/// `foxglove.Quaternion`.
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

fn stamp_ns(timestamp: Option<Timestamp>) -> Result<i64, String> {
    let Timestamp { seconds, nanos } = timestamp.unwrap_or_default();
    crate::pose_type::check_nanoseconds("timestamp.nanos", i64::from(nanos))?;
    seconds
        .checked_mul(1_000_000_000)
        .and_then(|ns| ns.checked_add(i64::from(nanos)))
        .ok_or_else(|| format!("timestamp {seconds} s {nanos} ns is out of range"))
}

fn position(v: Option<Vector3>) -> [f64; 3] {
    v.map_or([0.0; 3], |v| [v.x, v.y, v.z])
}

fn orientation(q: Option<Quaternion>) -> [f64; 4] {
    q.map_or(IDENTITY, |q| [q.x, q.y, q.z, q.w])
}

fn pose_parts(pose: Option<Pose>) -> ([f64; 3], [f64; 4]) {
    let pose = pose.unwrap_or(Pose { position: None, orientation: None });
    (position(pose.position), orientation(pose.orientation))
}

/// Decodes a protobuf message of a Foxglove type, calling `emit` for each pose.
pub(crate) fn decode_protobuf(
    pose_type: PoseType,
    data: &[u8],
    mut emit: impl FnMut(Sample<'_>),
) -> Result<(), String> {
    let invalid =
        |error: prost::DecodeError| format!("invalid protobuf for {pose_type}: {}", crate::printable::one_line(&error));
    match pose_type {
        PoseType::FoxglovePoseInFrame => {
            let m = PoseInFrame::decode(data).map_err(invalid)?;
            let (position, orientation) = pose_parts(m.pose);
            emit(Sample { stamp_ns: stamp_ns(m.timestamp)?, parent: &m.frame_id, child: "", position, orientation });
        }
        PoseType::FoxglovePosesInFrame => {
            let m = PosesInFrame::decode(data).map_err(invalid)?;
            let stamp_ns = stamp_ns(m.timestamp)?;
            for pose in m.poses {
                let (position, orientation) = pose_parts(Some(pose));
                emit(Sample { stamp_ns, parent: &m.frame_id, child: "", position, orientation });
            }
        }
        PoseType::FoxgloveFrameTransform => {
            let m = FrameTransform::decode(data).map_err(invalid)?;
            emit(frame_transform_sample(&m)?);
        }
        PoseType::FoxgloveFrameTransforms => {
            let m = FrameTransforms::decode(data).map_err(invalid)?;
            for (index, transform) in m.transforms.iter().enumerate() {
                emit(frame_transform_sample(transform).map_err(|error| format!("transform {index}: {error}"))?);
            }
        }
        PoseType::FoxgloveOdometry => {
            let m = Odometry::decode(data).map_err(invalid)?;
            let (position, orientation) = pose_parts(m.pose);
            emit(Sample {
                stamp_ns: stamp_ns(m.timestamp)?,
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

fn frame_transform_sample(m: &FrameTransform) -> Result<Sample<'_>, String> {
    Ok(Sample {
        stamp_ns: stamp_ns(m.timestamp)?,
        parent: &m.parent_frame_id,
        child: &m.child_frame_id,
        position: position(m.translation),
        orientation: orientation(m.rotation),
    })
}

/// A JSON timestamp: `{"sec", "nsec"}`, or `{"seconds", "nanos"}`.
#[derive(Debug, Default, Clone, Copy, Deserialize)]
#[serde(default)]
struct JsonTime {
    #[serde(alias = "seconds")]
    sec: i64,
    #[serde(alias = "nanos", alias = "nanosec")]
    nsec: i64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct JsonVector3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct JsonQuaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct JsonPose {
    position: Option<JsonVector3>,
    orientation: Option<JsonQuaternion>,
}

/// The fields of every Foxglove pose type, all optional: one struct reads them all.
#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct JsonMessage {
    timestamp: Option<JsonTime>,
    frame_id: String,
    parent_frame_id: String,
    child_frame_id: String,
    body_frame_id: String,
    pose: Option<JsonPose>,
    poses: Vec<JsonPose>,
    translation: Option<JsonVector3>,
    rotation: Option<JsonQuaternion>,
    transforms: Vec<JsonMessage>,
}

impl JsonMessage {
    fn stamp_ns(&self) -> Result<i64, String> {
        let JsonTime { sec, nsec } = self.timestamp.unwrap_or_default();
        crate::pose_type::check_nanoseconds("timestamp.nsec", nsec)?;
        sec.checked_mul(1_000_000_000)
            .and_then(|ns| ns.checked_add(nsec))
            .ok_or_else(|| format!("timestamp {sec} s {nsec} ns is out of range"))
    }
}

fn json_position(v: Option<&JsonVector3>) -> [f64; 3] {
    v.map_or([0.0; 3], |v| [v.x, v.y, v.z])
}

fn json_orientation(q: Option<&JsonQuaternion>) -> [f64; 4] {
    q.map_or(IDENTITY, |q| [q.x, q.y, q.z, q.w])
}

fn json_pose(pose: Option<&JsonPose>) -> ([f64; 3], [f64; 4]) {
    match pose {
        Some(pose) => (json_position(pose.position.as_ref()), json_orientation(pose.orientation.as_ref())),
        None => ([0.0; 3], IDENTITY),
    }
}

/// Decodes a JSON message of a Foxglove type, calling `emit` for each pose.
pub(crate) fn decode_json(pose_type: PoseType, data: &[u8], mut emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    let m: JsonMessage = serde_json::from_slice(data)
        .map_err(|error| format!("invalid JSON for {pose_type}: {}", crate::printable::one_line(&error)))?;
    match pose_type {
        PoseType::FoxglovePoseInFrame => {
            let (position, orientation) = json_pose(m.pose.as_ref());
            emit(Sample { stamp_ns: m.stamp_ns()?, parent: &m.frame_id, child: "", position, orientation });
        }
        PoseType::FoxglovePosesInFrame => {
            let stamp_ns = m.stamp_ns()?;
            for pose in &m.poses {
                let (position, orientation) = json_pose(Some(pose));
                emit(Sample { stamp_ns, parent: &m.frame_id, child: "", position, orientation });
            }
        }
        PoseType::FoxgloveFrameTransform => emit(json_transform(&m)?),
        PoseType::FoxgloveFrameTransforms => {
            for (index, transform) in m.transforms.iter().enumerate() {
                emit(json_transform(transform).map_err(|error| format!("transform {index}: {error}"))?);
            }
        }
        PoseType::FoxgloveOdometry => {
            let (position, orientation) = json_pose(m.pose.as_ref());
            emit(Sample {
                stamp_ns: m.stamp_ns()?,
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

fn json_transform(m: &JsonMessage) -> Result<Sample<'_>, String> {
    Ok(Sample {
        stamp_ns: m.stamp_ns()?,
        parent: &m.parent_frame_id,
        child: &m.child_frame_id,
        position: json_position(m.translation.as_ref()),
        orientation: json_orientation(m.rotation.as_ref()),
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
