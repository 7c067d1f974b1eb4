//! The ROS 1 serialisation of the few message types that carry poses, decoded by hand.
//!
//! ROS 1 messages are the fields in order, little endian, with no alignment and no
//! encapsulation header; a string is a `u32` byte count then the bytes (no NUL); a variable
//! array is a `u32` count then the elements; `time` is `u32 sec, u32 nsec`; `std_msgs/Header`
//! is `u32 seq, time stamp, string frame_id`. Five types need a dozen lines of reading, which
//! is why no crate is used: the Rust ROS 1 crates (`rosrust`'s `rosmsg`, `ros_message`) decode
//! through generated or dynamic message structs that allocate every string and covariance,
//! where a pose needs 7 doubles read in place.
//!
//! A message must be exactly as long as its type: ROS 1 messages carry no padding, so bytes
//! left over mean a different definition under the same name, which is an error rather than
//! poses read from the wrong bytes.

use crate::pose_type::{PoseType, Sample};

/// A reader over one ROS 1 message.
#[derive(Debug)]
struct Ros1<'a> {
    data: &'a [u8],
    pos: usize,
    type_name: &'static str,
}

impl<'a> Ros1<'a> {
    fn take(&mut self, size: usize, field: &str) -> Result<&'a [u8], String> {
        match self.pos.checked_add(size).filter(|&end| end <= self.data.len()) {
            Some(end) => {
                let bytes = &self.data[self.pos..end];
                self.pos = end;
                Ok(bytes)
            }
            None => Err(format!(
                "the ROS 1 message ends at byte {}, but {} needs {size} bytes for {field} at byte {}: the message is \
                 shorter than its type",
                self.data.len(),
                self.type_name,
                self.pos
            )),
        }
    }

    fn u32(&mut self, field: &str) -> Result<u32, String> {
        let bytes: [u8; 4] = self.take(4, field)?.try_into().expect("4 bytes");
        Ok(u32::from_le_bytes(bytes))
    }

    fn f64s<const N: usize>(&mut self, field: &str) -> Result<[f64; N], String> {
        let bytes = self.take(8 * N, field)?;
        Ok(std::array::from_fn(|i| f64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().expect("8 bytes"))))
    }

    fn skip_f64s(&mut self, count: usize, field: &str) -> Result<(), String> {
        self.take(8 * count, field).map(|_| ())
    }

    /// A string: `u32` byte count, then the bytes.
    fn string(&mut self, field: &str) -> Result<&'a str, String> {
        let len = self.u32(field)? as usize;
        let bytes = self.take(len, field)?;
        std::str::from_utf8(bytes).map_err(|error| format!("{field} is not UTF-8: {error}"))
    }

    /// `std_msgs/Header`: the stamp (nanoseconds) and the frame id; `seq` is skipped.
    fn header(&mut self) -> Result<(i64, &'a str), String> {
        self.u32("header.seq")?;
        let sec = self.u32("header.stamp.secs")?;
        let nsec = self.u32("header.stamp.nsecs")?;
        crate::pose_type::check_nanoseconds("header.stamp.nsecs", i64::from(nsec))?;
        let frame_id = self.string("header.frame_id")?;
        Ok((i64::from(sec) * 1_000_000_000 + i64::from(nsec), frame_id))
    }

    fn pose(&mut self, field: &str) -> Result<([f64; 3], [f64; 4]), String> {
        let [x, y, z, qx, qy, qz, qw] = self.f64s::<7>(field)?;
        Ok(([x, y, z], [qx, qy, qz, qw]))
    }

    fn transform_stamped(&mut self) -> Result<Sample<'a>, String> {
        let (stamp_ns, parent) = self.header()?;
        let child = self.string("child_frame_id")?;
        let (position, orientation) = self.pose("transform")?;
        Ok(Sample { stamp_ns, parent, child, position, orientation })
    }

    fn bytes_left(&self) -> usize {
        self.data.len() - self.pos
    }
}

/// Decodes a ROS 1 message of type `pose_type` (one of the ROS types), calling `emit` for each
/// pose it holds.
///
/// # Errors
/// What is wrong with the message, naming the field: shorter than its type, longer than its
/// type, a frame id that is not UTF-8.
pub(crate) fn decode(pose_type: PoseType, data: &[u8], mut emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    let type_name = match pose_type {
        PoseType::PoseStamped => "geometry_msgs/PoseStamped",
        PoseType::PoseWithCovarianceStamped => "geometry_msgs/PoseWithCovarianceStamped",
        PoseType::TransformStamped => "geometry_msgs/TransformStamped",
        PoseType::Odometry => "nav_msgs/Odometry",
        PoseType::TfMessage => "tf2_msgs/TFMessage",
        other => return Err(format!("{} is not a ROS type", other.schema_name())),
    };
    let mut r = Ros1 { data, pos: 0, type_name };
    match pose_type {
        PoseType::PoseStamped => {
            let (stamp_ns, frame_id) = r.header()?;
            let (position, orientation) = r.pose("pose")?;
            emit(Sample { stamp_ns, parent: frame_id, child: "", position, orientation });
        }
        PoseType::PoseWithCovarianceStamped => {
            let (stamp_ns, frame_id) = r.header()?;
            let (position, orientation) = r.pose("pose.pose")?;
            r.skip_f64s(36, "pose.covariance")?;
            emit(Sample { stamp_ns, parent: frame_id, child: "", position, orientation });
        }
        PoseType::TransformStamped => emit(r.transform_stamped()?),
        PoseType::Odometry => {
            let (stamp_ns, frame_id) = r.header()?;
            let child = r.string("child_frame_id")?;
            let (position, orientation) = r.pose("pose.pose")?;
            r.skip_f64s(36, "pose.covariance")?;
            r.skip_f64s(6, "twist.twist")?;
            r.skip_f64s(36, "twist.covariance")?;
            emit(Sample { stamp_ns, parent: frame_id, child, position, orientation });
        }
        _ => {
            let count = r.u32("transforms (array length)")?;
            // Each transform takes at least 76 bytes: a bogus count fails at the first missing
            // byte, without allocating.
            for index in 0..count {
                let sample = r
                    .transform_stamped()
                    .map_err(|error| format!("transform {index} of {count}: {error}; {} bytes left", r.bytes_left()))?;
                emit(sample);
            }
        }
    }
    if r.bytes_left() > 0 {
        return Err(format!(
            "the ROS 1 message has {} bytes after the last field of {type_name} (at byte {}): it is not {type_name} as \
             this crate reads it",
            r.bytes_left(),
            r.pos
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(out: &mut Vec<u8>, seq: u32, sec: u32, nsec: u32, frame: &str) {
        out.extend(seq.to_le_bytes());
        out.extend(sec.to_le_bytes());
        out.extend(nsec.to_le_bytes());
        out.extend((frame.len() as u32).to_le_bytes());
        out.extend(frame.as_bytes());
    }

    fn doubles(out: &mut Vec<u8>, values: &[f64]) {
        for v in values {
            out.extend(v.to_le_bytes());
        }
    }

    type Row = (i64, String, String, [f64; 3], [f64; 4]);

    fn rows(pose_type: PoseType, data: &[u8]) -> Result<Vec<Row>, String> {
        let mut out = Vec::new();
        decode(pose_type, data, |s| {
            out.push((s.stamp_ns, s.parent.into(), s.child.into(), s.position, s.orientation))
        })?;
        Ok(out)
    }

    #[test]
    fn pose_stamped_reads_and_every_prefix_and_extension_fails() {
        let mut data = Vec::new();
        header(&mut data, 7, 4_000_000_000, 999_999_999, "map");
        doubles(&mut data, &[1.5, -2.0, 3.0, 0.0, 0.0, 0.6, 0.8]);
        let got = rows(PoseType::PoseStamped, &data).unwrap();
        assert_eq!(
            got,
            [(4_000_000_000_999_999_999, "map".into(), String::new(), [1.5, -2.0, 3.0], [0.0, 0.0, 0.6, 0.8])]
        );
        for cut in 0..data.len() {
            let error = rows(PoseType::PoseStamped, &data[..cut]).unwrap_err();
            assert!(error.contains("shorter than its type"), "{cut}: {error}");
        }
        data.push(0);
        let error = rows(PoseType::PoseStamped, &data).unwrap_err();
        assert!(error.contains("1 bytes after the last field of geometry_msgs/PoseStamped"), "{error}");
    }

    #[test]
    fn odometry_and_tf() {
        let mut odom = Vec::new();
        header(&mut odom, 0, 5, 6, "odom");
        odom.extend(4u32.to_le_bytes());
        odom.extend(b"base");
        doubles(&mut odom, &[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]);
        doubles(&mut odom, &[0.5; 36 + 6 + 36]);
        let got = rows(PoseType::Odometry, &odom).unwrap();
        assert_eq!(got, [(5_000_000_006, "odom".into(), "base".into(), [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])]);

        let mut tf = 2u32.to_le_bytes().to_vec();
        for (i, child) in ["a", "bc"].iter().enumerate() {
            header(&mut tf, 0, 1, i as u32, "world");
            tf.extend((child.len() as u32).to_le_bytes());
            tf.extend(child.as_bytes());
            doubles(&mut tf, &[i as f64, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        }
        let got = rows(PoseType::TfMessage, &tf).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!((got[1].0, got[1].2.as_str(), got[1].3), (1_000_000_001, "bc", [1.0, 0.0, 0.0]));
        let error = rows(PoseType::TfMessage, &u32::MAX.to_le_bytes()).unwrap_err();
        assert!(error.starts_with("transform 0 of 4294967295:"), "{error}");
    }
}
