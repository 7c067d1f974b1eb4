//! The little rotation algebra the formats need: quaternions `[x, y, z, w]` from matrices,
//! headings and roll-pitch-yaw, products and relative poses, and the local east-north-up frame
//! of an ECEF point.

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

/// The rotation by `yaw_rad` about z.
pub(crate) fn quaternion_from_yaw(yaw_rad: f64) -> [f64; 4] {
    let (s, c) = (0.5 * yaw_rad).sin_cos();
    [0.0, 0.0, s, c]
}

/// The heading (rotation about z) of `q`, radians in (-π, π].
pub(crate) fn yaw_of(q: [f64; 4]) -> f64 {
    let [x, y, z, w] = q;
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// The rotation `R = Rz(yaw) Ry(pitch) Rx(roll)` (TORO's `VERTEX3`).
pub(crate) fn quaternion_from_roll_pitch_yaw(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> [f64; 4] {
    let (sr, cr) = (0.5 * roll_rad).sin_cos();
    let (sp, cp) = (0.5 * pitch_rad).sin_cos();
    let (sy, cy) = (0.5 * yaw_rad).sin_cos();
    [sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy]
}

/// `q / ‖q‖`, or `None` for a zero or non-finite quaternion.
pub(crate) fn normalized(q: [f64; 4]) -> Option<[f64; 4]> {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    (norm.is_finite() && norm > 0.0).then(|| q.map(|v| v / norm))
}

/// The product `a b` (apply `b`, then `a`).
pub(crate) fn multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// The inverse of a unit quaternion.
pub(crate) fn conjugate(q: [f64; 4]) -> [f64; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

/// `v` rotated by the unit quaternion `q`.
pub(crate) fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, _] = multiply(multiply(q, [v[0], v[1], v[2], 0.0]), conjugate(q));
    [x, y, z]
}

/// The pose of `b` in the frame of `a` (`a⁻¹ b`), for unit quaternions: translation and
/// rotation.
pub(crate) fn relative_pose(a: ([f64; 3], [f64; 4]), b: ([f64; 3], [f64; 4])) -> ([f64; 3], [f64; 4]) {
    let inverse = conjugate(a.1);
    let delta = [b.0[0] - a.0[0], b.0[1] - a.0[1], b.0[2] - a.0[2]];
    (rotate(inverse, delta), multiply(inverse, b.1))
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
    let (slat, clat) = lat.sin_cos();
    let (slon, clon) = lon.sin_cos();
    [[-slon, clon, 0.0], [-slat * clon, -slat * slon, clat], [clat * clon, clat * slon, slat]]
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn relative_pose_composes_back() {
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
}
