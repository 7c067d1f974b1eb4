//! The rotations the formats need, on nalgebra's `UnitQuaternion`: quaternions `[x, y, z, w]`
//! (the order of the files and of nalgebra's coordinates) from headings and roll-pitch-yaw,
//! normalised, headings of them and relative poses, bit for bit as the hand-written algebra they
//! replace (a test checks), so the written files keep their bytes. Two things stay by hand:
//!
//! - the quaternion of a rotation matrix keeps Shepperd's method with its branch on the largest
//!   of the trace and the diagonal: nalgebra's `UnitQuaternion::from_rotation_matrix` branches on
//!   `trace > 0` and does not normalise. For the not-quite-orthonormal matrices of files printed
//!   to a few digits (KITTI), the two branches give quaternions that differ by the matrix's
//!   error (~1e-7), and the sign convention differs (largest component positive here), so the
//!   orientations read from such files would change;
//! - the east-north-up frame of an ECEF point (WGS84 geodetic latitude): nalgebra has no
//!   geodesy.

use nalgebra::{Quaternion, UnitQuaternion, Vector3, Vector4};

/// The unit quaternion of a rotation matrix (rows), by Shepperd's method: stable for every
/// rotation, normalised (matrices printed to a few digits are not quite orthonormal).
pub(crate) fn quaternion_from_matrix(r: [[f64; 3]; 3]) -> [f64; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > r[0][0].max(r[1][1]).max(r[2][2]) {
        let s = 2.0 * (1.0 + trace).sqrt();
        [(r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, 0.25 * s]
    } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
        let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s, (r[2][1] - r[1][2]) / s]
    } else if r[1][1] >= r[2][2] {
        let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [(r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s, (r[0][2] - r[2][0]) / s]
    } else {
        let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [(r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s, (r[1][0] - r[0][1]) / s]
    };
    normalized(q).unwrap_or([0.0, 0.0, 0.0, 1.0])
}

/// `[x, y, z, w]` as nalgebra's quaternion.
fn quaternion(q: [f64; 4]) -> Quaternion<f64> {
    Quaternion::from_vector(Vector4::from(q))
}

/// A unit quaternion as `[x, y, z, w]`.
fn xyzw(q: UnitQuaternion<f64>) -> [f64; 4] {
    q.into_inner().coords.into()
}

/// The rotation by `yaw_rad` about z; `x` and `y` are `+0`, as the files print them (`0`, not
/// `-0`).
pub(crate) fn quaternion_from_yaw(yaw_rad: f64) -> [f64; 4] {
    let [x, y, z, w] = xyzw(UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw_rad));
    // `0 * sin` is `-0` for a negative sine; adding `+0` makes it `+0` and leaves the rest.
    [x + 0.0, y + 0.0, z, w]
}

/// The heading (rotation about z) of the unit quaternion `q`, radians in (-π, π]: the direction
/// of the rotated x axis in the x-y plane (defined at every pitch, unlike nalgebra's
/// `euler_angles`, which gives a yaw of 0 at a pitch of ±90°).
pub(crate) fn yaw_of(q: [f64; 4]) -> f64 {
    heading_in_plane(q, [0, 1])
}

/// The heading of the unit quaternion `q` in the plane of the position axes `[a, b]` (0 = x,
/// 1 = y, 2 = z), radians in (-π, π]: the direction of the rotated axis `a` projected on the
/// plane, measured from axis `a` towards axis `b`. This is the rotation about the plane's normal
/// `e_a × e_b`, the first angle of the intrinsic Euler sequence (normal, b, a): for `[0, 1]` the
/// yaw about z ([`yaw_of`]); for `[0, 2]` (KITTI's ground plane, y pointing down) the rotation
/// about −y, that is about up. Defined at every tilt but a rotated axis `a` along the normal.
///
/// Axes must be two different indices below 3 (the caller checks).
pub(crate) fn heading_in_plane(q: [f64; 4], [a, b]: [usize; 2]) -> f64 {
    let axis = Vector3::ith(a, 1.0);
    let heading = UnitQuaternion::new_unchecked(quaternion(q)) * axis;
    heading[b].atan2(heading[a])
}

/// The rotation `R = Rz(yaw) Ry(pitch) Rx(roll)` (TORO's `VERTEX3`).
pub(crate) fn quaternion_from_roll_pitch_yaw(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> [f64; 4] {
    xyzw(UnitQuaternion::from_euler_angles(roll_rad, pitch_rad, yaw_rad))
}

/// `q / ‖q‖`, or `None` for a zero or non-finite quaternion.
///
/// The norm is summed in `x, y, z, w` order, as the written files always had it: nalgebra's
/// `norm` (an unrolled dot product) rounds differently in the last bit, which would change the
/// digits of the quaternions in g2o files.
pub(crate) fn normalized(q: [f64; 4]) -> Option<[f64; 4]> {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    (norm.is_finite() && norm > 0.0).then(|| xyzw(UnitQuaternion::new_unchecked(quaternion(q) / norm)))
}

/// The rows of the rotation from ECEF to the local east-north-up frame at `origin` (ECEF
/// metres, WGS84 geodetic latitude).
pub(crate) fn ecef_to_enu(origin: [f64; 3]) -> [[f64; 3]; 3] {
    const A: f64 = 6_378_137.0;
    const E2: f64 = 6.694_379_990_141_316e-3;
    let [x, y, z] = origin;
    let lon = y.atan2(x);
    let p = x.hypot(y);
    // Geodetic latitude by fixed-point iteration: converges to ~1e-12 rad in a few steps.
    let mut lat = z.atan2(p * (1.0 - E2));
    for _ in 0..8 {
        let n = A / (1.0 - E2 * lat.sin().powi(2)).sqrt();
        let height = if lat.cos().abs() > 1e-12 { p / lat.cos() - n } else { z.abs() - n * (1.0 - E2) };
        // Deep inside the Earth (not a real fix) the iteration has no meaning: keep the estimate.
        let next = z.atan2(p * (1.0 - E2 * n / (n + height)));
        if !next.is_finite() || n + height <= 0.0 {
            break;
        }
        lat = next;
    }
    if !lat.is_finite() {
        lat = 0.0;
    }
    loops_core::enu_axes(lat, lon)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product `a b` (apply `b`, then `a`).
    fn multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
        (quaternion(a) * quaternion(b)).coords.into()
    }

    /// `v` rotated by the unit quaternion `q`.
    fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
        (UnitQuaternion::new_unchecked(quaternion(q)) * Vector3::from(v)).into()
    }

    fn matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
        let [x, y, z, w] = q;
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    }

    fn close(a: [f64; 4], b: [f64; 4]) -> bool {
        let same = a.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-12);
        let opposite = a.iter().zip(&b).all(|(a, b)| (a + b).abs() < 1e-12);
        same || opposite
    }

    #[test]
    fn matrix_round_trip_in_every_branch() {
        for q in [
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.5, -0.5, 0.5, 0.5],
            [0.1, 0.7, -0.1, 0.7],
        ] {
            let q = normalized(q).unwrap();
            assert!(close(quaternion_from_matrix(matrix(q)), q), "{q:?}");
        }
    }

    #[test]
    fn yaw_and_roll_pitch_yaw() {
        for yaw in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            assert!((yaw_of(quaternion_from_yaw(yaw)) - yaw).abs() < 1e-12);
            assert!(close(quaternion_from_roll_pitch_yaw(0.0, 0.0, yaw), quaternion_from_yaw(yaw)));
        }
        // Rz(yaw) Ry(pitch) Rx(roll) as a product of the three.
        let (roll, pitch, yaw): (f64, f64, f64) = (0.3, -0.4, 1.2);
        let rx = [(0.5 * roll).sin(), 0.0, 0.0, (0.5 * roll).cos()];
        let ry = [0.0, (0.5 * pitch).sin(), 0.0, (0.5 * pitch).cos()];
        let rz = quaternion_from_yaw(yaw);
        assert!(close(quaternion_from_roll_pitch_yaw(roll, pitch, yaw), multiply(rz, multiply(ry, rx))));
    }

    #[test]
    fn heading_in_a_plane_is_the_rotation_about_its_normal() {
        // A heading φ about each axis, then a tilt about the other two: the heading in the plane
        // normal to that axis is ±φ, the sign of e_a × e_b along the axis.
        let about = |axis: usize, angle: f64| {
            let mut q = [0.0, 0.0, 0.0, (0.5 * angle).cos()];
            q[axis] = (0.5 * angle).sin();
            q
        };
        for phi in [-2.5, -0.4, 0.0, 1.0, 3.0] {
            for ([a, b], normal, sign) in [([0, 1], 2, 1.0), ([1, 0], 2, -1.0), ([0, 2], 1, -1.0), ([2, 0], 1, 1.0)] {
                let heading = heading_in_plane(about(normal, phi), [a, b]);
                assert!((heading - sign * phi).abs() < 1e-12, "{a},{b}: {heading} for {phi}");
                // Tilting about the last axis of the sequence (a itself) leaves the heading.
                let tilted = multiply(about(normal, phi), about(a, 0.3));
                assert!((heading_in_plane(tilted, [a, b]) - sign * phi).abs() < 1e-12);
            }
        }
        assert_eq!(yaw_of(quaternion_from_yaw(0.7)), heading_in_plane(quaternion_from_yaw(0.7), [0, 1]));
    }

    #[test]
    fn relative_pose_composes_back() {
        use loops_core::se3_between as relative_pose;
        let a = ([1.0, 2.0, 3.0], normalized([0.1, 0.2, 0.3, 0.9]).unwrap());
        let b = ([-4.0, 0.5, 2.0], normalized([-0.3, 0.1, 0.0, 0.8]).unwrap());
        let (t, q) = relative_pose(a, b);
        let back = rotate(a.1, t);
        for ((start, step), end) in a.0.iter().zip(back).zip(b.0) {
            assert!((start + step - end).abs() < 1e-12);
        }
        assert!(close(multiply(a.1, q), b.1));
    }

    #[test]
    fn enu_is_a_rotation_anywhere() {
        for origin in [[0.0; 3], [0.0, 0.0, 6.4e6], [1.0, -1.0, 0.0], [1e300, 1e300, -1e300], [-0.0, 0.0, -0.0]] {
            let r = ecef_to_enu(origin);
            assert!(r.iter().flatten().all(|v| v.is_finite()), "{origin:?}: {r:?}");
        }
    }

    #[test]
    fn enu_at_a_known_place() {
        // Chemnitz: up is the normalised ellipsoid normal, east is horizontal.
        let origin = [3_934_098.670_252_7, 902_425.342_798_05, 4_922_416.429_090_7];
        let r = ecef_to_enu(origin);
        let lat = r[2][2].asin().to_degrees();
        let lon = r[2][1].atan2(r[2][0]).to_degrees();
        assert!((lat - 50.83).abs() < 0.01 && (lon - 12.92).abs() < 0.01, "{lat} {lon}");
        for i in 0..3 {
            for j in 0..3 {
                let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                assert!((dot - f64::from(u8::from(i == j))).abs() < 1e-12);
            }
        }
    }

    /// The hand-written algebra these functions replaced: nalgebra gives its results bit for
    /// bit, so the written files keep their bytes.
    mod reference {
        pub(super) fn yaw_of([x, y, z, w]: [f64; 4]) -> f64 {
            (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
        }

        pub(super) fn multiply([ax, ay, az, aw]: [f64; 4], [bx, by, bz, bw]: [f64; 4]) -> [f64; 4] {
            [
                aw * bx + ax * bw + ay * bz - az * by,
                aw * by - ax * bz + ay * bw + az * bx,
                aw * bz + ax * by - ay * bx + az * bw,
                aw * bw - ax * bx - ay * by - az * bz,
            ]
        }

        pub(super) fn relative_pose(a: ([f64; 3], [f64; 4]), b: ([f64; 3], [f64; 4])) -> ([f64; 3], [f64; 4]) {
            let inverse = [-a.1[0], -a.1[1], -a.1[2], a.1[3]];
            let [dx, dy, dz] = [b.0[0] - a.0[0], b.0[1] - a.0[1], b.0[2] - a.0[2]];
            let [x, y, z, _] = multiply(multiply(inverse, [dx, dy, dz, 0.0]), a.1);
            ([x, y, z], multiply(inverse, b.1))
        }
    }

    #[test]
    fn nalgebra_gives_the_hand_written_results_bit_for_bit() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let raw = [uniform(), uniform(), uniform(), uniform()];
            let q = normalized(raw).unwrap();
            let norm = raw.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert_eq!(q, raw.map(|v| v / norm));
            assert_eq!(yaw_of(q), reference::yaw_of(q), "{q:?}");
            let a = ([uniform() * 100.0, uniform() * 100.0, uniform()], q);
            let b = (
                [uniform() * 100.0, uniform() * 100.0, uniform()],
                normalized([uniform(), 0.1, uniform(), 1.0]).unwrap(),
            );
            let (t, r) = loops_core::se3_between(a, b);
            let (t_ref, r_ref) = reference::relative_pose(a, b);
            assert_eq!((t, r), (t_ref, r_ref), "{a:?} {b:?}");
            let (roll, pitch, yaw) = (uniform() * 3.2, uniform() * 1.6, uniform() * 3.2);
            let (sr, cr) = (0.5 * roll).sin_cos();
            let (sp, cp) = (0.5 * pitch).sin_cos();
            let (sy, cy) = (0.5 * yaw).sin_cos();
            let rpy = [
                sr * cp * cy - cr * sp * sy,
                cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy,
                cr * cp * cy + sr * sp * sy,
            ];
            assert_eq!(quaternion_from_roll_pitch_yaw(roll, pitch, yaw), rpy);
            assert_eq!(quaternion_from_yaw(yaw * 2.0), [0.0, 0.0, (yaw).sin(), (yaw).cos()]);
        }
        for yaw in [-7.0, -3.0, -1.0, 0.0, 2.0, 4.0] {
            assert!(quaternion_from_yaw(yaw)[..2].iter().all(|v| v.is_sign_positive()), "{yaw}");
        }
        assert_eq!(normalized([0.0; 4]), None);
        assert_eq!(normalized([f64::NAN, 0.0, 0.0, 1.0]), None);
        assert_eq!(normalized([f64::INFINITY, 0.0, 0.0, 1.0]), None);
        // A heading at a pitch of 90°.
        let pitched = multiply(
            quaternion_from_yaw(0.5),
            [0.0, std::f64::consts::FRAC_1_SQRT_2, 0.0, std::f64::consts::FRAC_1_SQRT_2],
        );
        assert!((yaw_of(pitched) - reference::yaw_of(pitched)).abs() < 1e-12);
    }
}
