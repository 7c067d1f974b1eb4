//! ROS 2 CDR decoding, by hand, of the few message types that carry poses.
//!
//! A CDR message is a 4-byte encapsulation header (`00 01` little endian, `00 00` big endian;
//! `00 06` / `00 07` and `00 10` / `00 11` for plain XCDR2, whose 8-byte values align to 4
//! only) and the body. Every primitive is aligned to its size relative to the start of the
//! body, not of the buffer; strings are a `u32` length counting the terminating NUL, then the
//! bytes; sequences are a `u32` count, then the elements. ROS 2 types are final, so there is no
//! delimiter or member header.
//!
//! Only what a pose needs is kept; the rest (covariances, twists) is checked to be there (a
//! message shorter than its type is an error) and skipped.

use crate::pose_type::{PoseType, Sample};

/// A reader over one CDR message.
#[derive(Debug)]
struct Cdr<'a> {
    /// The whole message, header included.
    data: &'a [u8],
    /// Next byte to read, an index into `data`.
    pos: usize,
    little_endian: bool,
    /// Largest alignment: 8 for XCDR1, 4 for XCDR2.
    max_align: usize,
    /// The type being decoded, for messages.
    type_name: &'static str,
}

/// Where the body starts: after the encapsulation header.
const BODY: usize = 4;

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8], type_name: &'static str) -> Result<Self, String> {
        let Some(header) = data.get(..BODY) else {
            return Err(format!(
                "the CDR message is {} bytes long, shorter than its 4-byte encapsulation header",
                data.len()
            ));
        };
        let (little_endian, max_align) = match [header[0], header[1]] {
            [0x00, 0x00] => (false, 8),
            [0x00, 0x01] => (true, 8),
            [0x00, 0x06] | [0x00, 0x10] => (false, 4),
            [0x00, 0x07] | [0x00, 0x11] => (true, 4),
            [a, b] => {
                return Err(format!(
                    "unsupported CDR encapsulation {a:02x} {b:02x}: expected plain CDR (00 00 / 00 01) or plain \
                     XCDR2 (00 06 / 00 07)"
                ));
            }
        };
        Ok(Self { data, pos: BODY, little_endian, max_align, type_name })
    }

    /// The next `size` bytes after aligning to `align`, or an error naming `field`.
    fn take(&mut self, size: usize, align: usize, field: &str) -> Result<&'a [u8], String> {
        let align = align.min(self.max_align);
        let body_pos = self.pos - BODY;
        let start = self.pos + (align - body_pos % align) % align;
        match start.checked_add(size).filter(|&end| end <= self.data.len()) {
            Some(end) => {
                self.pos = end;
                Ok(&self.data[start..end])
            }
            None => Err(format!(
                "the CDR message ends at byte {}, but {} needs {size} bytes for {field} at byte {start}: \
                 the message is shorter than its type",
                self.data.len(),
                self.type_name
            )),
        }
    }

    fn u32(&mut self, field: &str) -> Result<u32, String> {
        let bytes: [u8; 4] = self.take(4, 4, field)?.try_into().expect("4 bytes");
        Ok(if self.little_endian { u32::from_le_bytes(bytes) } else { u32::from_be_bytes(bytes) })
    }

    fn i32(&mut self, field: &str) -> Result<i32, String> {
        let bytes: [u8; 4] = self.take(4, 4, field)?.try_into().expect("4 bytes");
        Ok(if self.little_endian { i32::from_le_bytes(bytes) } else { i32::from_be_bytes(bytes) })
    }

    fn f64s<const N: usize>(&mut self, field: &str) -> Result<[f64; N], String> {
        let bytes = self.take(8 * N, 8, field)?;
        Ok(std::array::from_fn(|i| {
            let value: [u8; 8] = bytes[8 * i..8 * i + 8].try_into().expect("8 bytes");
            if self.little_endian { f64::from_le_bytes(value) } else { f64::from_be_bytes(value) }
        }))
    }

    /// Skips `count` doubles (a covariance), checking they are there.
    fn skip_f64s(&mut self, count: usize, field: &str) -> Result<(), String> {
        self.take(8 * count, 8, field).map(|_| ())
    }

    /// A string: `u32` length with the NUL, the bytes, the NUL.
    fn string(&mut self, field: &str) -> Result<&'a str, String> {
        let len = self.u32(field)? as usize;
        let bytes = self.take(len, 1, field)?;
        let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        std::str::from_utf8(bytes).map_err(|error| format!("{field} is not UTF-8: {error}"))
    }

    /// `builtin_interfaces/Time` as nanoseconds: `int32 sec`, `uint32 nanosec`.
    fn stamp_ns(&mut self, field_sec: &str, field_nanosec: &str) -> Result<i64, String> {
        let sec = self.i32(field_sec)?;
        let nanosec = self.u32(field_nanosec)?;
        crate::pose_type::check_nanoseconds(field_nanosec, i64::from(nanosec))?;
        Ok(i64::from(sec) * 1_000_000_000 + i64::from(nanosec))
    }

    /// `std_msgs/Header`: the stamp and the frame id.
    fn header(&mut self) -> Result<(i64, &'a str), String> {
        let stamp_ns = self.stamp_ns("header.stamp.sec", "header.stamp.nanosec")?;
        let frame_id = self.string("header.frame_id")?;
        Ok((stamp_ns, frame_id))
    }

    /// `geometry_msgs/Pose` (or `Transform`): 3 + 4 doubles.
    fn pose(&mut self, field: &str) -> Result<([f64; 3], [f64; 4]), String> {
        let [x, y, z, qx, qy, qz, qw] = self.f64s::<7>(field)?;
        Ok(([x, y, z], [qx, qy, qz, qw]))
    }

    fn bytes_left(&self) -> usize {
        self.data.len() - self.pos
    }
}

/// Decodes a CDR message of type `pose_type` (one of the ROS 2 types), calling `emit` for each
/// pose it holds.
///
/// # Errors
/// What is wrong with the message, naming the field: a bad encapsulation header, a message
/// shorter than its type, a frame id that is not UTF-8.
pub(crate) fn decode(pose_type: PoseType, data: &[u8], mut emit: impl FnMut(Sample<'_>)) -> Result<(), String> {
    let mut cdr = Cdr::new(data, pose_type.schema_name())?;
    match pose_type {
        PoseType::PoseStamped => {
            let (stamp_ns, frame_id) = cdr.header()?;
            let (position, orientation) = cdr.pose("pose")?;
            emit(Sample { stamp_ns, parent: frame_id, child: "", position, orientation });
        }
        PoseType::PoseWithCovarianceStamped => {
            let (stamp_ns, frame_id) = cdr.header()?;
            let (position, orientation) = cdr.pose("pose.pose")?;
            cdr.skip_f64s(36, "pose.covariance")?;
            emit(Sample { stamp_ns, parent: frame_id, child: "", position, orientation });
        }
        PoseType::TransformStamped => emit(transform_stamped(&mut cdr)?),
        PoseType::Odometry => {
            let (stamp_ns, frame_id) = cdr.header()?;
            let child = cdr.string("child_frame_id")?;
            let (position, orientation) = cdr.pose("pose.pose")?;
            cdr.skip_f64s(36, "pose.covariance")?;
            cdr.skip_f64s(6, "twist.twist")?;
            cdr.skip_f64s(36, "twist.covariance")?;
            emit(Sample { stamp_ns, parent: frame_id, child, position, orientation });
        }
        PoseType::TfMessage => {
            let count = cdr.u32("transforms (sequence length)")?;
            // Each transform takes at least 4 + 4 + 4 + 4 + 56 bytes: no count can ask for more
            // than the message holds, so a bogus count fails at the first missing byte below.
            for index in 0..count {
                let sample = transform_stamped(&mut cdr).map_err(|error| {
                    format!("transform {index} of {count}: {error}; {} bytes left", cdr.bytes_left())
                })?;
                emit(sample);
            }
        }
        other => return Err(format!("{} is not a ROS 2 type", other.schema_name())),
    }
    Ok(())
}

/// `geometry_msgs/TransformStamped`: header, child frame, translation, rotation.
fn transform_stamped<'a>(cdr: &mut Cdr<'a>) -> Result<Sample<'a>, String> {
    let (stamp_ns, parent) = cdr.header()?;
    let child = cdr.string("child_frame_id")?;
    let (position, orientation) = cdr.pose("transform")?;
    Ok(Sample { stamp_ns, parent, child, position, orientation })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian CDR writer for the tests: aligned relative to the body.
    struct Writer(Vec<u8>, bool);

    impl Writer {
        fn new(little_endian: bool) -> Self {
            Self(vec![0, u8::from(little_endian), 0, 0], little_endian)
        }
        fn align(&mut self, n: usize) {
            while !(self.0.len() - 4).is_multiple_of(n) {
                self.0.push(0);
            }
        }
        fn u32(&mut self, v: u32) {
            self.align(4);
            self.0.extend(if self.1 { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        fn f64(&mut self, v: f64) {
            self.align(8);
            self.0.extend(if self.1 { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        fn string(&mut self, s: &str) {
            self.u32(s.len() as u32 + 1);
            self.0.extend(s.as_bytes());
            self.0.push(0);
        }
    }

    fn pose_stamped(little_endian: bool, frame: &str) -> Vec<u8> {
        let mut w = Writer::new(little_endian);
        w.u32(1_700_000_000);
        w.u32(123_456_789);
        w.string(frame);
        for v in [1.5, -2.25, 3.0, 0.0, 0.0, 0.6, 0.8] {
            w.f64(v);
        }
        w.0
    }

    /// Stamp, parent, child, position, orientation.
    type Row = (i64, String, String, [f64; 3], [f64; 4]);

    fn samples(pose_type: PoseType, data: &[u8]) -> Result<Vec<Row>, String> {
        let mut out = Vec::new();
        decode(pose_type, data, |s| {
            out.push((s.stamp_ns, s.parent.to_owned(), s.child.to_owned(), s.position, s.orientation))
        })?;
        Ok(out)
    }

    #[test]
    fn pose_stamped_both_endians_and_alignment_after_the_frame_id() {
        for little_endian in [true, false] {
            for frame in ["", "m", "map", "odom_frame"] {
                let got = samples(PoseType::PoseStamped, &pose_stamped(little_endian, frame)).unwrap();
                assert_eq!(
                    got,
                    [(
                        1_700_000_000_123_456_789,
                        frame.to_owned(),
                        String::new(),
                        [1.5, -2.25, 3.0],
                        [0.0, 0.0, 0.6, 0.8]
                    )]
                );
            }
        }
    }

    #[test]
    fn short_messages_name_the_field() {
        let data = pose_stamped(true, "map");
        for cut in 0..data.len() {
            let error = samples(PoseType::PoseStamped, &data[..cut]).unwrap_err();
            if cut >= 4 {
                assert!(error.contains("shorter than its type"), "{cut}: {error}");
            }
        }
        let error = samples(PoseType::PoseStamped, &data[..data.len() - 1]).unwrap_err();
        assert_eq!(
            error,
            format!(
                "the CDR message ends at byte {}, but geometry_msgs/msg/PoseStamped needs 56 bytes for pose at byte {}: \
                 the message is shorter than its type",
                data.len() - 1,
                data.len() - 56
            )
        );
    }

    #[test]
    fn xcdr2_aligns_doubles_to_four() {
        let mut w = Writer::new(true);
        w.0[1] = 0x07;
        w.u32(5);
        w.u32(6);
        w.string("abcd"); // body bytes 0..17: XCDR2 doubles start at 20, XCDR1 ones at 24
        w.align(4);
        for v in [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0] {
            w.0.extend(f64::to_le_bytes(v));
        }
        let got = samples(PoseType::PoseStamped, &w.0).unwrap();
        assert_eq!((got[0].0, got[0].3, got[0].4), (5_000_000_006, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]));
        w.0[1] = 0x01;
        assert!(samples(PoseType::PoseStamped, &w.0).is_err(), "as XCDR1 the doubles would start at 24");
    }

    #[test]
    fn unknown_encapsulation() {
        let mut data = pose_stamped(true, "map");
        data[1] = 0x03;
        let error = samples(PoseType::PoseStamped, &data).unwrap_err();
        assert!(error.starts_with("unsupported CDR encapsulation 00 03"), "{error}");
    }

    #[test]
    fn a_huge_sequence_count_fails_without_allocating() {
        let mut w = Writer::new(true);
        w.u32(u32::MAX);
        let error = samples(PoseType::TfMessage, &w.0).unwrap_err();
        assert!(error.starts_with("transform 0 of 4294967295:"), "{error}");
    }
}
