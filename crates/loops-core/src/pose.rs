//! Validated constructors of trajectories on manifolds, laying points out as the metrics in
//! [`manifold`](crate::So3) expect and recording the [`Manifold`], so that its metric measures
//! them by default ([`Trajectory::default_metric`]) and a metric that does not fit is refused.
//!
//! The only rotation algebra here is one formula (a rotation vector to a unit quaternion, with
//! its series near 0) and the normalisation of inputs, written out rather than taken from
//! nalgebra: the core keeps no linear-algebra dependency for two lines, and the metrics compare
//! quaternions with their own rounding-stable formulas (`RotationDistance::between`). Frames
//! from files (matrices, Euler angles, relative poses) are loops-io's, on nalgebra.

use crate::error::{Error, Result};
use crate::manifold::wrap_angle;
use crate::trajectory::{Manifold, Trajectory};

/// How far from unit length a quaternion may be before it is an error rather than normalised:
/// one rule for quaternions handed to a constructor and read from files. Files and arrays often
/// hold 4 decimals (TUM ground truth), which leaves norms up to ~1e-4 from 1; a quaternion
/// further off is no rotation written to a few digits but a mistake.
pub const QUATERNION_TOLERANCE: f64 = 1e-3;

fn same_length(positions: usize, quaternions: usize) -> Result<()> {
    if positions == quaternions {
        Ok(())
    } else {
        Err(Error::RowCountMismatch {
            first: "positions",
            first_rows: positions,
            second: "quaternions",
            second_rows: quaternions,
        })
    }
}

fn finite_row(index: usize, row: &[f64]) -> Result<()> {
    match row.iter().position(|v| !v.is_finite()) {
        Some(axis) => Err(Error::NonFiniteCoordinate { index, axis, value: row[axis] }),
        None => Ok(()),
    }
}

/// How far from unit length a quaternion read from a text file may be: the same rule as for
/// constructors, [`QUATERNION_TOLERANCE`] (kept as a name for the readers' callers).
pub const FILE_QUATERNION_TOLERANCE: f64 = QUATERNION_TOLERANCE;

/// A quaternion tolerance must be a number ≥ 0 (infinity: normalise any non-zero quaternion).
fn check_tolerance(tolerance: f64) -> Result<()> {
    if tolerance >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: "quaternion_tolerance",
            value: tolerance,
            expected: "a number ≥ 0: how far a quaternion's norm may be from 1",
        })
    }
}

/// `q / ‖q‖` when ‖q‖ is within `tolerance` of 1.
fn unit_quaternion(index: usize, q: &[f64; 4], tolerance: f64) -> Result<[f64; 4]> {
    check_tolerance(tolerance)?;
    finite_row(index, q)?;
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > tolerance || norm == 0.0 {
        return Err(Error::NonUnitQuaternion { index, norm });
    }
    Ok(q.map(|v| v / norm))
}

/// `v / ‖v‖` for any non-zero finite vector (scaled first, so huge and tiny vectors work).
fn normalised(index: usize, v: &[f64]) -> Result<Vec<f64>> {
    finite_row(index, v)?;
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return Err(Error::NonUnitVector { index, norm: 0.0 });
    }
    let scaled: Vec<f64> = v.iter().map(|x| x / largest).collect();
    let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    Ok(scaled.iter().map(|x| x / norm).collect())
}

/// The east, north and up axes, in ECEF coordinates, at geodetic latitude `lat_rad` and
/// longitude `lon_rad`: the rows of the rotation from ECEF to the local east-north-up frame.
///
/// # Examples
/// ```
/// // On the equator at 0° longitude: east is ECEF y, north is z, up is x.
/// assert_eq!(loops_core::enu_axes(0.0, 0.0), [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
/// ```
pub fn enu_axes(lat_rad: f64, lon_rad: f64) -> [[f64; 3]; 3] {
    let (slat, clat) = lat_rad.sin_cos();
    let (slon, clon) = lon_rad.sin_cos();
    [[-slon, clon, 0.0], [-slat * clon, -slat * slon, clat], [clat * clon, clat * slon, slat]]
}

fn latitude_checked(index: usize, latitude_deg: f64) -> Result<f64> {
    if latitude_deg.abs() > 90.0 {
        return Err(Error::LatitudeOutOfRange { index, value_deg: latitude_deg });
    }
    Ok(latitude_deg)
}

impl Trajectory {
    /// SE(3) poses for [`Se3`](crate::Se3) and [`Se3Rotation`](crate::Se3Rotation): positions
    /// and orientations as quaternions `[qx, qy, qz, qw]` (the ROS and scipy order), normalised.
    /// Points are `[x, y, z, qx, qy, qz, qw]`, on [`Manifold::Se3`]: measured by default by
    /// `se3(rotation_weight_m_per_rad=0)`, the translation; never by [`Euclidean`](crate::Euclidean).
    ///
    /// # Errors
    /// [`Error::NonUnitQuaternion`] for a quaternion farther than [`QUATERNION_TOLERANCE`] (1e-3) from unit length (a zero
    /// quaternion included), naming the pose; [`Error::LengthMismatch`]; and as
    /// [`Trajectory::new`].
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Se3, RotationDistance, Metric, Trajectory};
    /// let traj = Trajectory::se3(
    ///     vec![0.0, 1.0],
    ///     &[[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]],
    ///     &[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0]], // identity; 180° about z
    /// )?;
    /// let metric = Se3 { rotation_weight_m_per_rad: 1.0, rotation: RotationDistance::Geodesic };
    /// let d = metric.distance(traj.point(0), traj.point(1));
    /// assert!((d - (5.0 + std::f64::consts::PI)).abs() < 1e-12);
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn se3(timestamps_s: Vec<f64>, positions: &[[f64; 3]], quaternions_xyzw: &[[f64; 4]]) -> Result<Self> {
        Self::se3_with_tolerance(timestamps_s, positions, quaternions_xyzw, QUATERNION_TOLERANCE)
    }

    /// As [`Trajectory::se3`], normalising quaternions within `tolerance` of unit length (e.g.
    /// [`FILE_QUATERNION_TOLERANCE`] for quaternions printed with few decimals).
    ///
    /// # Errors
    /// As [`Trajectory::se3`], and [`Error::InvalidParameter`] for a negative or NaN tolerance.
    pub fn se3_with_tolerance(
        timestamps_s: Vec<f64>,
        positions: &[[f64; 3]],
        quaternions_xyzw: &[[f64; 4]],
        tolerance: f64,
    ) -> Result<Self> {
        same_length(positions.len(), quaternions_xyzw.len())?;
        let mut coords = Vec::with_capacity(7 * positions.len());
        for (index, (p, q)) in positions.iter().zip(quaternions_xyzw).enumerate() {
            finite_row(index, p)?;
            coords.extend_from_slice(p);
            coords.extend_from_slice(&unit_quaternion(index, q, tolerance)?);
        }
        Ok(Self::new(timestamps_s, coords, 7)?.on(Manifold::Se3))
    }

    /// Rotations for [`So3`](crate::So3): quaternions `[qx, qy, qz, qw]`, normalised.
    ///
    /// # Errors
    /// As [`Trajectory::se3`].
    pub fn so3(timestamps_s: Vec<f64>, quaternions_xyzw: &[[f64; 4]]) -> Result<Self> {
        Self::so3_with_tolerance(timestamps_s, quaternions_xyzw, QUATERNION_TOLERANCE)
    }

    /// As [`Trajectory::so3`], normalising quaternions within `tolerance` of unit length.
    ///
    /// # Errors
    /// As [`Trajectory::se3`], and [`Error::InvalidParameter`] for a negative or NaN tolerance.
    pub fn so3_with_tolerance(timestamps_s: Vec<f64>, quaternions_xyzw: &[[f64; 4]], tolerance: f64) -> Result<Self> {
        let mut coords = Vec::with_capacity(4 * quaternions_xyzw.len());
        for (index, q) in quaternions_xyzw.iter().enumerate() {
            coords.extend_from_slice(&unit_quaternion(index, q, tolerance)?);
        }
        Ok(Self::new(timestamps_s, coords, 4)?.on(Manifold::So3))
    }

    /// Rotations for [`So3`](crate::So3) from rotation vectors (axis × angle, radians; the
    /// paper's Fig. 4 parametrisation).
    ///
    /// # Errors
    /// As [`Trajectory::new`] (non-finite values name the pose).
    pub fn so3_from_rotation_vectors(timestamps_s: Vec<f64>, rotation_vectors: &[[f64; 3]]) -> Result<Self> {
        let mut coords = Vec::with_capacity(4 * rotation_vectors.len());
        for (index, v) in rotation_vectors.iter().enumerate() {
            finite_row(index, v)?;
            let angle = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            // sin(θ/2)/θ, with its Taylor series near 0.
            let k = if angle < 1e-8 { 0.5 - angle * angle / 48.0 } else { (0.5 * angle).sin() / angle };
            coords.extend_from_slice(&[k * v[0], k * v[1], k * v[2], (0.5 * angle).cos()]);
        }
        Ok(Self::new(timestamps_s, coords, 4)?.on(Manifold::So3))
    }

    /// Planar poses for [`Se2`](crate::Se2): `[x, y, θ]`, θ in radians, wrapped to (−π, π].
    ///
    /// # Errors
    /// As [`Trajectory::new`].
    pub fn se2(timestamps_s: Vec<f64>, poses_xy_theta: &[[f64; 3]]) -> Result<Self> {
        let mut coords = Vec::with_capacity(3 * poses_xy_theta.len());
        for (index, p) in poses_xy_theta.iter().enumerate() {
            finite_row(index, p)?;
            coords.extend_from_slice(&[p[0], p[1], wrap_angle(p[2])]);
        }
        Ok(Self::new(timestamps_s, coords, 3)?.on(Manifold::Se2))
    }

    /// Points on the torus (S¹)^dim for [`Torus`](crate::Torus): `dim` angles per pose,
    /// radians, row-major, wrapped to (−π, π].
    ///
    /// # Errors
    /// As [`Trajectory::new`].
    pub fn torus(timestamps_s: Vec<f64>, angles_rad: &[f64], dim: usize) -> Result<Self> {
        if let Some(k) = angles_rad.iter().position(|a| !a.is_finite()) {
            let dim = dim.max(1);
            return Err(Error::NonFiniteCoordinate { index: k / dim, axis: k % dim, value: angles_rad[k] });
        }
        Ok(Self::new(timestamps_s, angles_rad.iter().map(|&a| wrap_angle(a)).collect(), dim)?.on(Manifold::Torus))
    }

    /// Points on the sphere S² for [`Sphere`](crate::Sphere): any non-zero vectors, normalised.
    ///
    /// # Errors
    /// [`Error::NonUnitVector`] for a zero vector; as [`Trajectory::new`].
    pub fn sphere(timestamps_s: Vec<f64>, vectors: &[[f64; 3]]) -> Result<Self> {
        let mut coords = Vec::with_capacity(3 * vectors.len());
        for (index, v) in vectors.iter().enumerate() {
            coords.extend(normalised(index, v)?);
        }
        Ok(Self::new(timestamps_s, coords, 3)?.on(Manifold::Sphere))
    }

    /// Points on the sphere S² for [`Sphere`](crate::Sphere) from latitude and longitude,
    /// degrees.
    ///
    /// # Errors
    /// [`Error::LatitudeOutOfRange`]; as [`Trajectory::new`].
    pub fn sphere_from_lat_lon(timestamps_s: Vec<f64>, lat_lon_deg: &[[f64; 2]]) -> Result<Self> {
        let mut coords = Vec::with_capacity(3 * lat_lon_deg.len());
        for (index, p) in lat_lon_deg.iter().enumerate() {
            finite_row(index, p)?;
            let (lat, lon) = (latitude_checked(index, p[0])?.to_radians(), p[1].to_radians());
            coords.extend_from_slice(&[lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()]);
        }
        Ok(Self::new(timestamps_s, coords, 3)?.on(Manifold::Sphere))
    }

    /// GNSS fixes for [`Haversine`](crate::Haversine): latitude and longitude in degrees, height
    /// in metres. Points are `[ux, uy, uz, height_m]`: the direction of the fix from the
    /// Earth's centre (a unit vector) and its height.
    ///
    /// # Errors
    /// [`Error::LatitudeOutOfRange`]; as [`Trajectory::new`].
    pub fn gnss(timestamps_s: Vec<f64>, lat_lon_height: &[[f64; 3]]) -> Result<Self> {
        let mut coords = Vec::with_capacity(4 * lat_lon_height.len());
        for (index, p) in lat_lon_height.iter().enumerate() {
            finite_row(index, p)?;
            let (lat, lon) = (latitude_checked(index, p[0])?.to_radians(), p[1].to_radians());
            coords.extend_from_slice(&[lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin(), p[2]]);
        }
        Ok(Self::new(timestamps_s, coords, 4)?.on(Manifold::Gnss))
    }

    /// GNSS fixes as Earth-centred, Earth-fixed positions (WGS 84) relative to the first fix,
    /// turned into the first fix's east-north-up frame ([`enu_axes`]): metres east, north and
    /// up, so that a map of the trajectory is a map. A rotation of ECEF, for
    /// [`Euclidean`](crate::Euclidean): straight-line distances, exact at any range.
    ///
    /// # Errors
    /// As [`Trajectory::gnss`].
    ///
    /// # Examples
    /// ```
    /// use loops_core::Trajectory;
    /// // 0.001° north of the first fix is about 111 m north of it, and a little down (the Earth curves).
    /// let traj = Trajectory::gnss_ecef(vec![0.0, 1.0], &[[48.0, 11.0, 500.0], [48.001, 11.0, 500.0]])?;
    /// let [east, north, up] = [traj.point(1)[0], traj.point(1)[1], traj.point(1)[2]];
    /// assert!(east.abs() < 1e-9 && (north - 111.2).abs() < 0.1 && up < 0.0 && up > -0.01);
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn gnss_ecef(timestamps_s: Vec<f64>, lat_lon_height: &[[f64; 3]]) -> Result<Self> {
        const A: f64 = 6_378_137.0;
        const F: f64 = 1.0 / 298.257_223_563;
        let e2 = F * (2.0 - F);
        let mut coords = Vec::with_capacity(3 * lat_lon_height.len());
        let mut origin: Option<([f64; 3], [[f64; 3]; 3])> = None;
        for (index, p) in lat_lon_height.iter().enumerate() {
            finite_row(index, p)?;
            let (lat, lon, h) = (latitude_checked(index, p[0])?.to_radians(), p[1].to_radians(), p[2]);
            let n = A / (1.0 - e2 * lat.sin().powi(2)).sqrt();
            let xyz =
                [(n + h) * lat.cos() * lon.cos(), (n + h) * lat.cos() * lon.sin(), (n * (1.0 - e2) + h) * lat.sin()];
            let (o, axes) = *origin.get_or_insert((xyz, enu_axes(lat, lon)));
            let d = [xyz[0] - o[0], xyz[1] - o[1], xyz[2] - o[2]];
            coords.extend(axes.map(|axis| axis[0] * d[0] + axis[1] * d[1] + axis[2] * d[2]));
        }
        Self::new(timestamps_s, coords, 3)
    }

    /// Descriptor vectors (place recognition), `dim` values per pose, row-major; normalised to
    /// unit length when `normalize` (for [`Angular`](crate::Angular)), kept as given otherwise
    /// (for [`Euclidean`](crate::Euclidean)).
    ///
    /// # Errors
    /// [`Error::NonUnitVector`] for a zero descriptor when normalising; as [`Trajectory::new`].
    pub fn descriptors(timestamps_s: Vec<f64>, values: &[f64], dim: usize, normalize: bool) -> Result<Self> {
        if !normalize || dim == 0 || !values.len().is_multiple_of(dim) {
            return Self::new(timestamps_s, values.to_vec(), dim);
        }
        let mut coords = Vec::with_capacity(values.len());
        for (index, row) in values.chunks_exact(dim).enumerate() {
            coords.extend(normalised(index, row)?);
        }
        Ok(Self::new(timestamps_s, coords, dim)?.on(Manifold::Descriptors))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_quaternion_tolerance_is_named() {
        let q = [[0.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 1.0]];
        for tolerance in [f64::NAN, -1.0, f64::NEG_INFINITY] {
            let error = Trajectory::so3_with_tolerance(vec![0.0, 1.0], &q, tolerance).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { name: "quaternion_tolerance", .. }), "{error}");
            let error = Trajectory::se3_with_tolerance(vec![0.0, 1.0], &[[0.0; 3]; 2], &q, tolerance).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { name: "quaternion_tolerance", .. }), "{error}");
        }
    }
}
