//! Metrics on manifolds: SO(3), SE(3), SE(2), tori, spheres, GNSS latitude/longitude, and
//! descriptor directions (paper, Sec. 3: "a metric δ on M").
//!
//! Every metric here satisfies the triangle inequality (sums and L2 combinations of metrics on
//! the factors of a product space are metrics), so the engine's arc-length skipping and ball
//! hierarchy stay exact. Points are rows of a [`Trajectory`](crate::Trajectory) in the layout
//! each metric documents; the constructors in [`pose`](crate::Trajectory::se3) build them
//! validated and normalised.

use std::f64::consts::{PI, TAU};

use crate::error::{Error, Result};
use crate::metric::{Metric, dim_error};
use crate::trajectory::{Manifold, Trajectory};

/// Tolerance on the norm of unit quaternions and unit vectors handed to a metric directly
/// (the [`Trajectory`] constructors normalise to ~1e-16).
pub const UNIT_TOLERANCE: f64 = 1e-9;

/// How two rotations are compared.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum RotationDistance {
    /// The geodesic angle θ ∈ [0, π] of R_a⁻¹ R_b, radians.
    #[default]
    Geodesic,
    /// The chordal (Frobenius) distance ‖R_a − R_b‖_F = ‖I − R_a R_bᵀ‖_F = 2√2 sin(θ/2) ∈
    /// [0, 2√2]: the paper's SO(3) metric (Fig. 4 caption).
    Chordal,
}

impl RotationDistance {
    /// The accepted names.
    pub const NAMES: &'static str = "geodesic, chordal";

    /// Distance between unit quaternions `a` and `b` (`[x, y, z, w]`; q and −q are the same
    /// rotation). Stable near 0 and near π.
    #[inline]
    pub fn between(self, a: &[f64], b: &[f64]) -> f64 {
        let (mut minus, mut plus) = (0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            minus += (x - y) * (x - y);
            plus += (x + y) * (x + y);
        }
        let (near, far) = if minus <= plus { (minus.sqrt(), plus.sqrt()) } else { (plus.sqrt(), minus.sqrt()) };
        // The angle φ between the quaternions as 4-vectors, taken ≤ π/2 over ±q, is
        // 2 atan2(‖a ∓ b‖, ‖a ± b‖); the rotation angle is θ = 2φ.
        match self {
            Self::Geodesic => 4.0 * near.atan2(far),
            // 2√2 sin(θ/2) = 2√2 sin φ = √2 ‖a ∓ b‖ ‖a ± b‖ for unit quaternions.
            Self::Chordal => std::f64::consts::SQRT_2 * near * far,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Geodesic => "geodesic",
            Self::Chordal => "chordal",
        }
    }
}

impl std::str::FromStr for RotationDistance {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        match name {
            "geodesic" => Ok(Self::Geodesic),
            "chordal" | "frobenius" => Ok(Self::Chordal),
            _ => Err(Error::UnknownName { kind: "rotation distance", name: name.to_owned(), expected: Self::NAMES }),
        }
    }
}

/// An angle wrapped to (−π, π], radians: the one angle wrap of the workspace.
///
/// # Examples
/// ```
/// use loops_core::wrap_angle;
/// use std::f64::consts::PI;
/// assert_eq!(wrap_angle(PI), PI);
/// assert_eq!(wrap_angle(-PI), PI);
/// assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
/// ```
#[inline]
pub fn wrap_angle(angle_rad: f64) -> f64 {
    let a = angle_rad.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

/// The least angular difference |a − b| mod 2π, in [0, π]: `|wrap_angle(a − b)|`.
#[inline]
pub fn angle_difference(a: f64, b: f64) -> f64 {
    wrap_angle(a - b).abs()
}

fn check_unit(traj: &Trajectory, offset: usize, len: usize, what: fn(usize, f64) -> Error) -> Result<()> {
    for i in 0..traj.len() {
        let v = &traj.point(i)[offset..offset + len];
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > UNIT_TOLERANCE {
            return Err(what(i, norm));
        }
    }
    Ok(())
}

fn non_unit_quaternion(index: usize, norm: f64) -> Error {
    Error::NonUnitQuaternion { index, norm }
}

fn non_unit_vector(index: usize, norm: f64) -> Error {
    Error::NonUnitVector { index, norm }
}

fn check_weight(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name, value, expected: "a finite weight ≥ 0" })
    }
}

fn check_radius(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name, value, expected: "a positive finite radius" })
    }
}

/// Rotations SO(3). Points: unit quaternions `[qx, qy, qz, qw]` (the ROS and scipy order).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct So3 {
    /// Geodesic angle (radians) or chordal Frobenius distance.
    pub rotation: RotationDistance,
}

impl Metric for So3 {
    fn name(&self) -> String {
        format!("so3(rotation={})", self.rotation.name())
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::So3 | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 4 { Ok(()) } else { Err(dim_error(self, "4 ([qx, qy, qz, qw])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        self.check_dim(traj.dim())?;
        check_unit(traj, 0, 4, non_unit_quaternion)
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.rotation.between(a, b)
    }
}

/// Rigid motions SE(3): `‖p_a − p_b‖ + w · rot(q_a, q_b)`, metres, with `w` in metres per
/// radian (geodesic) or metres per unit of chordal distance. `w = 0` compares translations only.
/// Points: `[x, y, z, qx, qy, qz, qw]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Se3 {
    /// Metres that one radian (or one chordal unit) of rotation counts for; ≥ 0.
    pub rotation_weight_m_per_rad: f64,
    /// How rotations are compared.
    pub rotation: RotationDistance,
}

impl Metric for Se3 {
    fn name(&self) -> String {
        format!("se3(rotation_weight_m_per_rad={}, rotation={})", self.rotation_weight_m_per_rad, self.rotation.name())
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Se3 | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 7 { Ok(()) } else { Err(dim_error(self, "7 ([x, y, z, qx, qy, qz, qw])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        check_weight("rotation_weight_m_per_rad", self.rotation_weight_m_per_rad)?;
        self.check_dim(traj.dim())?;
        check_unit(traj, 3, 4, non_unit_quaternion)
    }

    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        let position = (0..traj.len()).flat_map(|i| traj.point(i)[..3].to_vec()).fold(0.0_f64, |m, c| m.max(c.abs()));
        position + self.rotation_weight_m_per_rad * PI
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        let translation = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        if self.rotation_weight_m_per_rad == 0.0 {
            return translation;
        }
        translation + self.rotation_weight_m_per_rad * self.rotation.between(&a[3..7], &b[3..7])
    }
}

/// The rotation part of SE(3) poses only (a pseudometric on SE(3)): radians or chordal units.
/// Points: `[x, y, z, qx, qy, qz, qw]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Se3Rotation {
    /// How rotations are compared.
    pub rotation: RotationDistance,
}

impl Metric for Se3Rotation {
    fn name(&self) -> String {
        format!("se3_rotation(rotation={})", self.rotation.name())
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Se3 | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 7 { Ok(()) } else { Err(dim_error(self, "7 ([x, y, z, qx, qy, qz, qw])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        self.check_dim(traj.dim())?;
        check_unit(traj, 3, 4, non_unit_quaternion)
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.rotation.between(&a[3..7], &b[3..7])
    }
}

/// Planar poses SE(2): `‖p_a − p_b‖ + w · |θ_a − θ_b|` (least angular difference), metres.
/// Points: `[x, y, θ]`, θ in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Se2 {
    /// Metres that one radian of heading counts for; ≥ 0.
    pub rotation_weight_m_per_rad: f64,
}

impl Metric for Se2 {
    fn name(&self) -> String {
        format!("se2(rotation_weight_m_per_rad={})", self.rotation_weight_m_per_rad)
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Se2 | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 3 { Ok(()) } else { Err(dim_error(self, "3 ([x, y, theta])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        check_weight("rotation_weight_m_per_rad", self.rotation_weight_m_per_rad)?;
        self.check_dim(traj.dim())
    }

    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        let position = (0..traj.len()).flat_map(|i| traj.point(i)[..2].to_vec()).fold(0.0_f64, |m, c| m.max(c.abs()));
        position + self.rotation_weight_m_per_rad * 2.0 * PI
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
            + self.rotation_weight_m_per_rad * angle_difference(a[2], b[2])
    }
}

/// The flat torus S¹ × … × S¹: the L2 norm of the least angular differences, radians (paper,
/// Fig. 4 caption). Points: k ≥ 1 angles, radians.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Torus;

impl Metric for Torus {
    fn name(&self) -> String {
        "torus".to_owned()
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Torus | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim >= 1 { Ok(()) } else { Err(dim_error(self, "at least 1 angle", dim)) }
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| angle_difference(*x, *y).powi(2)).sum::<f64>().sqrt()
    }
}

/// The sphere S² with the great-circle distance `radius · angle`. Points: unit vectors
/// `[x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Radius; distances are `radius · angle` (1 gives radians).
    pub radius: f64,
}

impl Metric for Sphere {
    fn name(&self) -> String {
        format!("sphere(radius={})", self.radius)
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Sphere | Manifold::Descriptors | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 3 { Ok(()) } else { Err(dim_error(self, "3 (unit vectors [x, y, z])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        check_radius("radius", self.radius)?;
        self.check_dim(traj.dim())?;
        check_unit(traj, 0, 3, non_unit_vector)
    }

    fn rounding_scale(&self, _traj: &Trajectory) -> f64 {
        self.radius * PI
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.radius * unit_angle(a, b)
    }
}

/// The angle between unit vectors, stable at 0 and π: 2 atan2(‖a − b‖, ‖a + b‖).
#[inline]
fn unit_angle(a: &[f64], b: &[f64]) -> f64 {
    let (mut minus, mut plus) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        minus += (x - y) * (x - y);
        plus += (x + y) * (x + y);
    }
    2.0 * minus.sqrt().atan2(plus.sqrt())
}

/// Mean Earth radius (IUGG), metres.
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;

/// GNSS fixes: the great-circle (haversine) distance on a sphere of `radius_m`, combined in L2
/// with the height difference, metres. Points: `[ux, uy, uz, height_m]`, the fix's direction
/// from the Earth's centre as a unit vector and its height (see
/// [`Trajectory::gnss`](crate::Trajectory::gnss)). The angle is computed as
/// 2 atan2(‖a − b‖, ‖a + b‖) on the unit vectors: the same distance as the haversine formula,
/// but stable at every range (antipodes included) and free of longitude differences, so the
/// date line is nothing special.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Haversine {
    /// Sphere radius, metres.
    pub radius_m: f64,
}

impl Default for Haversine {
    fn default() -> Self {
        Self { radius_m: EARTH_RADIUS_M }
    }
}

impl Metric for Haversine {
    fn name(&self) -> String {
        format!("haversine(radius_m={})", self.radius_m)
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Gnss | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 4 { Ok(()) } else { Err(dim_error(self, "4 ([ux, uy, uz, height_m])", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        check_radius("radius_m", self.radius_m)?;
        self.check_dim(traj.dim())?;
        check_unit(traj, 0, 3, non_unit_vector)
    }

    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        let height = (0..traj.len()).map(|i| traj.point(i)[3].abs()).fold(0.0, f64::max);
        self.radius_m + height
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        let surface = self.radius_m * unit_angle(&a[..3], &b[..3]);
        surface.hypot(a[3] - b[3])
    }
}

/// Descriptor directions: the angle between unit vectors of any dimension, radians — the
/// (pseudo)metric of place recognition on normalised descriptors. Points: unit vectors (see
/// [`Trajectory::descriptors`](crate::Trajectory::descriptors)). For raw descriptors use
/// [`Euclidean`](crate::Euclidean).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Angular;

impl Metric for Angular {
    fn name(&self) -> String {
        "angular".to_owned()
    }

    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Descriptors | Manifold::Sphere | Manifold::Euclidean)
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim >= 1 { Ok(()) } else { Err(dim_error(self, "at least 1", dim)) }
    }

    fn validate(&self, traj: &Trajectory) -> Result<()> {
        check_unit(traj, 0, traj.dim(), non_unit_vector)
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        unit_angle(a, b)
    }
}
