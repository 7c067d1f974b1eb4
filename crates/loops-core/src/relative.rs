//! The relative pose a trajectory predicts between two of its poses: the initial guess a scan
//! matcher starts from when it checks a candidate pair, and the measurement of a candidate
//! loop-closure edge.
//!
//! - SE(3) `[x, y, z, qx, qy, qz, qw]`: the pose of `b` in the frame of `a`, `T_a⁻¹ T_b` (what
//!   GTSAM's `Pose3::between` and evo's relative poses give);
//! - SE(2) `[x, y, θ]`: `T_a⁻¹ T_b` in the plane, `dθ` wrapped to (−π, π];
//! - Rⁿ, n ≤ 3 (positions without orientation): the difference `b − a`, in the world axes.
//!
//! Other manifolds (rotations alone, angles, directions, descriptors) have no such guess.
//!
//! No uncertainty goes with it: the trajectory holds no covariance (the readers do not keep
//! the covariances of the messages that have them), so a back end sets its own.
//!
//! The quaternion algebra is written out (the core has no linear-algebra dependency): the
//! translation is rotated by the product `a⁻¹ (b − a) a`, the rotation is `a⁻¹ b`, both in
//! one fixed order of operations, so that files written from it keep their bytes.

use crate::manifold::wrap_angle;
use crate::trajectory::{Manifold, Trajectory};

/// The pose of one pose of a trajectory in the frame of another (see the module docs).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativePose {
    /// The translation, in the frame of the first pose for SE(2) and SE(3), in the world's
    /// axes for Rⁿ (the trajectory's unit: metres for positions); missing axes are 0.
    pub translation: [f64; 3],
    /// The rotation of the second pose in the frame of the first, `[qx, qy, qz, qw]`: for SE(3),
    /// and for SE(2) the rotation by `rotation_rad` about z; `None` for Rⁿ.
    pub rotation_xyzw: Option<[f64; 4]>,
    /// For SE(2): `dθ`, radians in (−π, π]; `None` otherwise.
    pub rotation_rad: Option<f64>,
}

/// The relative pose from pose `i` to pose `j` of `traj` (the pose of `j` in the frame of `i`),
/// or `None` where the trajectory's manifold has no such guess (see the module docs). O(1).
///
/// `i` and `j` must be poses of `traj` (it panics otherwise, as indexing does).
///
/// # Examples
/// ```
/// use loops_core::{Trajectory, relative_pose};
/// let traj = Trajectory::se2(vec![0.0, 1.0], &[[1.0, 1.0, std::f64::consts::FRAC_PI_2], [1.0, 3.0, 0.0]])?;
/// let guess = relative_pose(&traj, 0, 1).unwrap();
/// // Two metres ahead of the first pose (which faces +y), turned right by 90°.
/// assert!((guess.translation[0] - 2.0).abs() < 1e-12 && guess.translation[1].abs() < 1e-12);
/// assert!((guess.rotation_rad.unwrap() + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn relative_pose(traj: &Trajectory, i: usize, j: usize) -> Option<RelativePose> {
    let (a, b) = (traj.point(i), traj.point(j));
    match traj.manifold() {
        Manifold::Se3 => {
            let pose = |p: &[f64]| ([p[0], p[1], p[2]], [p[3], p[4], p[5], p[6]]);
            let (translation, rotation) = se3_between(pose(a), pose(b));
            Some(RelativePose { translation, rotation_xyzw: Some(rotation), rotation_rad: None })
        }
        Manifold::Se2 => {
            let (translation, dtheta) = se2_between([a[0], a[1], a[2]], [b[0], b[1], b[2]]);
            let (s, c) = (0.5 * dtheta).sin_cos();
            Some(RelativePose {
                translation: [translation[0], translation[1], 0.0],
                rotation_xyzw: Some([0.0, 0.0, s, c]),
                rotation_rad: Some(dtheta),
            })
        }
        Manifold::Euclidean if a.len() <= 3 => {
            let mut translation = [0.0; 3];
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                translation[k] = y - x;
            }
            Some(RelativePose { translation, rotation_xyzw: None, rotation_rad: None })
        }
        _ => None,
    }
}

/// The pose `b` in the frame of the pose `a`, both `(position, unit quaternion [x, y, z, w])`:
/// `T_a⁻¹ T_b`. The translation is `a⁻¹ (b − a) a` as quaternion products.
pub fn se3_between(a: ([f64; 3], [f64; 4]), b: ([f64; 3], [f64; 4])) -> ([f64; 3], [f64; 4]) {
    let inverse = [-a.1[0], -a.1[1], -a.1[2], a.1[3]];
    let [dx, dy, dz] = [b.0[0] - a.0[0], b.0[1] - a.0[1], b.0[2] - a.0[2]];
    let [x, y, z, _] = multiply(multiply(inverse, [dx, dy, dz, 0.0]), a.1);
    ([x, y, z], multiply(inverse, b.1))
}

/// The pose `b = [x, y, θ]` in the frame of `a`: `[dx, dy]` and `dθ` wrapped to (−π, π].
///
/// `dθ` is the difference itself when it lies in (−π, π] (bit for bit), else shifted by one
/// turn; headings further apart than a turn and a half are wrapped by [`wrap_angle`].
pub fn se2_between(a: [f64; 3], b: [f64; 3]) -> ([f64; 2], f64) {
    use std::f64::consts::{PI, TAU};
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let dtheta = b[2] - a[2];
    let dtheta = match dtheta {
        d if d > PI && d <= PI + TAU => d - TAU,
        d if d <= -PI && d > -PI - TAU => d + TAU,
        d if d > -PI && d <= PI => d,
        d => wrap_angle(d),
    };
    ([c * dx + s * dy, -s * dx + c * dy], dtheta)
}

/// The Hamilton product `a b` of quaternions `[x, y, z, w]`.
fn multiply([ax, ay, az, aw]: [f64; 4], [bx, by, bz, bw]: [f64; 4]) -> [f64; 4] {
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn se3_between_is_the_inverse_composition() {
        // a: at (1, 2, 3) turned 90° about z; b: 1 m along a's x axis, same heading.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let a = ([1.0, 2.0, 3.0], [0.0, 0.0, h, h]);
        let b = ([1.0, 3.0, 3.0], [0.0, 0.0, h, h]);
        let (t, q) = se3_between(a, b);
        assert!((t[0] - 1.0).abs() < 1e-12 && t[1].abs() < 1e-12 && t[2].abs() < 1e-12, "{t:?}");
        assert!((q[3].abs() - 1.0).abs() < 1e-12, "{q:?}");
    }

    #[test]
    fn euclidean_guesses_are_differences_and_others_none() {
        let traj = Trajectory::from_points(vec![0.0, 1.0], &[[1.0, 2.0], [4.0, 6.0]]).unwrap();
        let guess = relative_pose(&traj, 0, 1).unwrap();
        assert_eq!(guess.translation, [3.0, 4.0, 0.0]);
        assert_eq!((guess.rotation_xyzw, guess.rotation_rad), (None, None));
        let wide = Trajectory::from_points(vec![0.0, 1.0], &[[0.0; 4], [1.0; 4]]).unwrap();
        assert_eq!(relative_pose(&wide, 0, 1), None);
    }
}
