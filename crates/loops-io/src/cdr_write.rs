//! ROS 2 messages out, by hand: `PoseStamped` and `Odometry` in little-endian CDR, and their
//! stamps; the primitives for the scene's `MarkerArray` ([`CdrWriter`]). Written by hand as `cdr.rs` reads them: two fixed layouts do not need a serde CDR
//! crate, and the reader's tests decode what this writes.

/// The orientation of a table without orientations.
pub(crate) const IDENTITY_XYZW: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

const NS_PER_S: i64 = 1_000_000_000;

/// A ROS 2 `builtin_interfaces/Time` that is also an MCAP time: `sec` is not negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RosTime {
    pub(crate) sec: i32,
    pub(crate) nanosec: u32,
}

impl RosTime {
    /// The time of `stamp_ns` nanoseconds since the epoch, if it is in `[0, 2³¹)` seconds.
    pub(crate) fn of_ns(stamp_ns: i64) -> Option<Self> {
        let sec = i32::try_from(stamp_ns.div_euclid(NS_PER_S)).ok().filter(|&sec| sec >= 0)?;
        let nanosec = u32::try_from(stamp_ns.rem_euclid(NS_PER_S)).expect("below 10⁹");
        Some(Self { sec, nanosec })
    }

    /// The time of `stamp_s` seconds, if it is in `[0, 2³¹)` seconds: the shortest decimal that
    /// reads back as `stamp_s` when it has at most 9 decimals (what a text file printed:
    /// `1700000000.1`, whose `f64` is 1700000000.0999999046...), else the `f64` itself, to the
    /// nearest nanosecond.
    pub(crate) fn of_seconds(stamp_s: f64) -> Option<Self> {
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
    pub(crate) fn ns(self) -> u64 {
        u64::from(self.sec.unsigned_abs()) * NS_PER_S as u64 + u64::from(self.nanosec)
    }
}

/// Encodes one `PoseStamped`, or with a `child_frame_id` one `Odometry` (zero covariances and
/// twist), into `data` (cleared first).
pub(crate) fn encode_message(
    data: &mut Vec<u8>,
    stamp: RosTime,
    frame_id: &str,
    child_frame_id: Option<&str>,
    position: [f64; 3],
    orientation_xyzw: [f64; 4],
) {
    let mut cdr = CdrWriter::new(data);
    cdr.i32(stamp.sec);
    cdr.u32(stamp.nanosec);
    cdr.string(frame_id);
    if let Some(child_frame_id) = child_frame_id {
        cdr.string(child_frame_id);
    }
    cdr.f64s(&position);
    cdr.f64s(&orientation_xyzw);
    if child_frame_id.is_some() {
        cdr.f64s(&[0.0; 36]); // pose.covariance
        cdr.f64s(&[0.0; 6]); // twist.twist
        cdr.f64s(&[0.0; 36]); // twist.covariance
    }
}

/// A little-endian ROS 2 CDR message being written: the encapsulation header `00 01 00 00`,
/// then each primitive aligned to its size relative to the start of the body (what `cdr.rs`
/// reads).
#[derive(Debug)]
pub(crate) struct CdrWriter<'a> {
    data: &'a mut Vec<u8>,
}

/// The encapsulation header: plain CDR, little endian, no options.
const ENCAPSULATION: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

impl<'a> CdrWriter<'a> {
    /// Starts a message in `data` (cleared first) with the encapsulation header.
    pub(crate) fn new(data: &'a mut Vec<u8>) -> Self {
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

    pub(crate) fn i32(&mut self, value: i32) {
        self.align(4);
        self.data.extend_from_slice(&value.to_le_bytes());
    }

    pub(crate) fn u32(&mut self, value: u32) {
        self.align(4);
        self.data.extend_from_slice(&value.to_le_bytes());
    }

    pub(crate) fn f64s(&mut self, values: &[f64]) {
        self.align(8);
        for value in values {
            self.data.extend_from_slice(&value.to_le_bytes());
        }
    }

    /// `float32`s, each aligned to 4 bytes.
    pub(crate) fn f32s(&mut self, values: &[f32]) {
        self.align(4);
        for value in values {
            self.data.extend_from_slice(&value.to_le_bytes());
        }
    }

    /// A `bool`: one byte, 0 or 1.
    pub(crate) fn bool(&mut self, value: bool) {
        self.data.push(u8::from(value));
    }

    /// A string: `u32` length counting the terminating NUL, the bytes, the NUL. Checked to fit
    /// by the writer before anything is written.
    pub(crate) fn string(&mut self, text: &str) {
        debug_assert!(text.len() < u32::MAX as usize && !text.contains('\0'));
        self.u32(text.len() as u32 + 1);
        self.data.extend_from_slice(text.as_bytes());
        self.data.push(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::decode_poses;
    use crate::pose_type::{MessageEncoding, PoseType};

    #[test]
    fn pose_stamped_has_the_ros2_layout() {
        let mut data = Vec::new();
        let stamp = RosTime { sec: 7, nanosec: 9 };
        encode_message(&mut data, stamp, "map", None, [1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]);
        // Encapsulation 4, then sec, nanosec, length, "map\0": the doubles start at body byte 16, aligned.
        assert_eq!(data[..20], [0, 1, 0, 0, 7, 0, 0, 0, 9, 0, 0, 0, 4, 0, 0, 0, b'm', b'a', b'p', 0]);
        assert_eq!(data.len(), 20 + 7 * 8);
        assert_eq!(data[20..28], 1.0f64.to_le_bytes());
        // "base\0" ends at byte 21 (17 of the body): 7 bytes of padding to the doubles at body byte 24.
        encode_message(&mut data, stamp, "base", None, [1.0, 2.0, 3.0], IDENTITY_XYZW);
        assert_eq!(data[16..28], [b'b', b'a', b's', b'e', 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(data.len(), 28 + 7 * 8);
        let poses = decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &data).unwrap();
        assert_eq!((poses[0].stamp_ns, poses[0].frame_id.as_str()), (7_000_000_009, "base"));
    }

    #[test]
    fn odometry_decodes_with_its_child_frame() {
        let mut data = Vec::new();
        let stamp = RosTime { sec: 1, nanosec: 2 };
        encode_message(&mut data, stamp, "odom", Some("base_link"), [1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]);
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
}
