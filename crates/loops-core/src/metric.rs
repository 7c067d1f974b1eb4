//! Distances between points: the [`Metric`] trait and the Euclidean metric.

use crate::error::{Error, Result};
use crate::manifold::RotationDistance;
use crate::trajectory::Trajectory;

/// A distance δ between points of a trajectory (rows of its coordinate buffer).
///
/// The engine relies on two things only: `δ(a, a) = 0` and the triangle inequality
/// `δ(a, c) ≤ δ(a, b) + δ(b, c)`. Symmetry is assumed. A pseudometric (δ(a, b) = 0 for a ≠ b, as
/// for descriptor distances) is fine. A metric that breaks the triangle inequality makes the
/// engine skip pairs it should not.
pub trait Metric: Sync {
    /// A short name, e.g. `"euclidean"`.
    fn name(&self) -> String;

    /// Checks that points of dimension `dim` can be measured.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when they cannot.
    fn check_dim(&self, dim: usize) -> Result<()>;

    /// Checks the whole trajectory: its dimension, and whatever else the metric needs (unit
    /// quaternions, latitudes within ±90°, non-negative weights). The engine calls it once.
    ///
    /// # Errors
    /// The first problem found, naming the pose index.
    fn validate(&self, traj: &Trajectory) -> Result<()> {
        self.check_dim(traj.dim())
    }

    /// δ(a, b), in the metric's unit (metres for positions). `a` and `b` have the checked dimension.
    fn distance(&self, a: &[f64], b: &[f64]) -> f64;

    /// The size of δ's absolute rounding error, in ulps of this value, on `traj`'s points: the
    /// engine widens its triangle-inequality margin by 64 ulps of it. Defaults to the largest
    /// absolute coordinate (right for metrics computed from coordinate differences); metrics
    /// that scale angles (spheres, rotation weights) return the scale they multiply by.
    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        traj.coords().iter().fold(0.0_f64, |m, c| m.max(c.abs()))
    }

    /// Any strictly increasing function of δ(a, b), for comparisons only (the Euclidean metric
    /// skips the square root). Defaults to δ itself.
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        self.distance(a, b)
    }

    /// The offset (within `points`, a row-major block of points of `x`'s dimension) of the point
    /// closest to `x`, the earliest on ties. `points` is not empty.
    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (k, p) in points.chunks_exact(x.len()).enumerate() {
            let rank = self.distance_rank(x, p);
            if rank < best.0 {
                best = (rank, k);
            }
        }
        best.1
    }
}

/// The L2 distance on Rⁿ, any n ≥ 1 (2 and 3 are the fast paths).
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, Metric};
/// assert_eq!(Euclidean.distance(&[0.0, 0.0], &[3.0, 4.0]), 5.0);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Euclidean;

impl Metric for Euclidean {
    fn name(&self) -> String {
        "euclidean".to_owned()
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        if dim == 0 {
            return Err(dim_error(self, "at least 1", dim));
        }
        Ok(())
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        squared_l2(a, b).sqrt()
    }

    #[inline]
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        squared_l2(a, b)
    }

    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        match *x {
            [x0, x1] => closest_fixed(points, |p: &[f64; 2]| (p[0] - x0).powi(2) + (p[1] - x1).powi(2)),
            [x0, x1, x2] => {
                closest_fixed(points, |p: &[f64; 3]| (p[0] - x0).powi(2) + (p[1] - x1).powi(2) + (p[2] - x2).powi(2))
            }
            _ => {
                let mut best = (f64::INFINITY, 0);
                for (k, p) in points.chunks_exact(x.len()).enumerate() {
                    let rank = squared_l2(x, p);
                    if rank < best.0 {
                        best = (rank, k);
                    }
                }
                best.1
            }
        }
    }
}

/// Argmin of `rank` over fixed-size points, the earliest on ties, in one pass: four lanes (points
/// k ≡ l mod 4) each keep their earliest least rank, with no dependence between lanes so the
/// compiler can keep them in vector registers; the lanes are then merged by (rank, position).
#[inline]
fn closest_fixed<const D: usize>(points: &[f64], rank: impl Fn(&[f64; D]) -> f64) -> usize {
    const LANES: usize = 4;
    let (blocks, _) = points.as_chunks::<D>();
    let (groups, rest) = blocks.as_chunks::<LANES>();
    let mut least = [f64::INFINITY; LANES];
    let mut group_of = [0usize; LANES];
    for (g, group) in groups.iter().enumerate() {
        for lane in 0..LANES {
            let r = rank(&group[lane]);
            let better = r < least[lane];
            least[lane] = if better { r } else { least[lane] };
            group_of[lane] = if better { g } else { group_of[lane] };
        }
    }
    let mut best = (f64::INFINITY, 0);
    if !groups.is_empty() {
        best = (least[0], group_of[0] * LANES);
        for lane in 1..LANES {
            let k = group_of[lane] * LANES + lane;
            if least[lane] < best.0 || (least[lane] == best.0 && k < best.1) {
                best = (least[lane], k);
            }
        }
    }
    // The remaining points come after every lane's: only a smaller rank wins.
    for (offset, p) in rest.iter().enumerate() {
        let r = rank(p);
        if r < best.0 {
            best = (r, groups.len() * LANES + offset);
        }
    }
    best.1
}

/// The error for points of the wrong dimension.
pub(crate) fn dim_error<M: Metric + ?Sized>(metric: &M, expected: &str, found: usize) -> Error {
    Error::DimensionMismatch { metric: metric.name(), expected: expected.to_owned(), found }
}

#[inline]
fn squared_l2(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    match (a, b) {
        ([ax, ay], [bx, by]) => (ax - bx).powi(2) + (ay - by).powi(2),
        ([ax, ay, az], [bx, by, bz]) => (ax - bx).powi(2) + (ay - by).powi(2) + (az - bz).powi(2),
        _ => a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum(),
    }
}

/// A metric chosen by name at run time (from Python or the command line), dispatched once to
/// the statically typed engine, so the hot loops stay monomorphic.
///
/// The text form is `name` or `name(key=value, ...)`; [`FromStr`](std::str::FromStr) parses it
/// and [`Display`](std::fmt::Display) writes it back:
///
/// | name | parameters | points |
/// |---|---|---|
/// | `euclidean` | | Rⁿ |
/// | `so3` | `rotation=geodesic\|chordal` (default geodesic) | `[qx, qy, qz, qw]` |
/// | `se3` | `rotation_weight_m_per_rad=W` (required), `rotation=...` | `[x, y, z, qx, qy, qz, qw]` |
/// | `se3_rotation` | `rotation=...` | as `se3` |
/// | `se2` | `rotation_weight_m_per_rad=W` (required) | `[x, y, θ]` |
/// | `torus` | | angles |
/// | `sphere` | `radius=R` (default 1) | unit vectors `[x, y, z]` |
/// | `haversine` | `radius_m=R` (default the mean Earth radius) | `[ux, uy, uz, height_m]` |
/// | `angular` | | unit vectors |
///
/// # Examples
/// ```
/// use loops_core::MetricSpec;
/// let spec: MetricSpec = "se3(rotation_weight_m_per_rad=10)".parse()?;
/// assert_eq!(spec.to_string(), "se3(rotation_weight_m_per_rad=10, rotation=geodesic)");
/// assert!("se3".parse::<MetricSpec>().is_err()); // the weight has no universal default
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[non_exhaustive]
pub enum MetricSpec {
    /// [`Euclidean`].
    #[default]
    Euclidean,
    /// [`So3`](crate::So3).
    So3(crate::So3),
    /// [`Se3`](crate::Se3).
    Se3(crate::Se3),
    /// [`Se3Rotation`](crate::Se3Rotation).
    Se3Rotation(crate::Se3Rotation),
    /// [`Se2`](crate::Se2).
    Se2(crate::Se2),
    /// [`Torus`](crate::Torus).
    Torus,
    /// [`Sphere`](crate::Sphere).
    Sphere(crate::Sphere),
    /// [`Haversine`](crate::Haversine).
    Haversine(crate::Haversine),
    /// [`Angular`](crate::Angular).
    Angular,
}

/// Calls `$body` with `$m` bound to the concrete metric of a [`MetricSpec`].
macro_rules! with_metric {
    ($spec:expr, $m:ident => $body:expr) => {
        match $spec {
            MetricSpec::Euclidean => {
                let $m = &Euclidean;
                $body
            }
            MetricSpec::So3(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Se3(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Se3Rotation(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Se2(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Torus => {
                let $m = &crate::Torus;
                $body
            }
            MetricSpec::Sphere(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Haversine(metric) => {
                let $m = metric;
                $body
            }
            MetricSpec::Angular => {
                let $m = &crate::Angular;
                $body
            }
        }
    };
}

impl MetricSpec {
    /// The accepted names.
    pub const NAMES: &'static str = "euclidean, so3, se3, se3_rotation, se2, torus, sphere, haversine, angular";

    /// The canonical text form, as [`FromStr`](std::str::FromStr) accepts it.
    pub fn name(&self) -> String {
        with_metric!(self, m => m.name())
    }

    /// [`find_loops`](crate::find_loops) under this metric.
    ///
    /// # Errors
    /// As [`find_loops`](crate::find_loops).
    pub fn find_loops(&self, traj: &Trajectory, gamma: f64) -> Result<crate::Loops> {
        with_metric!(self, m => crate::find_loops(traj, m, gamma))
    }

    /// The metric as a trait object, for code that takes `&dyn Metric` (dispatched per call;
    /// [`find_loops`](Self::find_loops) keeps the engine's loops monomorphic instead).
    pub fn as_metric(&self) -> &dyn Metric {
        with_metric!(self, m => m as &dyn Metric)
    }

    /// [`sample_loops`](crate::sample_loops) under this metric.
    ///
    /// # Errors
    /// As [`sample_loops`](crate::sample_loops).
    pub fn sample_loops(
        &self,
        traj: &Trajectory,
        loops: &crate::Loops,
        sampler: &crate::Sampler,
    ) -> Result<crate::Samples> {
        with_metric!(self, m => crate::sample_loops(traj, m, loops, sampler))
    }

    /// δ between two points under this metric (dispatched per call: for tests and small jobs).
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        with_metric!(self, m => m.distance(a, b))
    }

    /// Validates `traj` for this metric (see [`Metric::validate`]).
    ///
    /// # Errors
    /// As the metric's `validate`.
    pub fn validate(&self, traj: &Trajectory) -> Result<()> {
        with_metric!(self, m => m.validate(traj))
    }
}

impl std::fmt::Display for MetricSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

impl std::str::FromStr for MetricSpec {
    type Err = Error;

    fn from_str(spec: &str) -> Result<Self> {
        let invalid = |reason: String| Error::InvalidMetricSpec { spec: spec.to_owned(), reason };
        let text = spec.trim();
        let (name, args) = match text.split_once('(') {
            None => (text, ""),
            Some((name, rest)) => {
                let args = rest.strip_suffix(')').ok_or_else(|| invalid("missing the closing ')'".into()))?;
                (name.trim(), args)
            }
        };
        let mut params: Vec<(String, String)> = Vec::new();
        for item in args.split(',').map(str::trim).filter(|item| !item.is_empty()) {
            let (key, value) = item.split_once('=').ok_or_else(|| invalid(format!("{item:?} is not key=value")))?;
            params.push((key.trim().to_owned(), value.trim().to_owned()));
        }
        let mut take = |key: &str| -> Option<String> {
            let at = params.iter().position(|(k, _)| k == key)?;
            Some(params.remove(at).1)
        };
        let number = |key: &str, value: Option<String>| -> Result<Option<f64>> {
            value.map(|v| v.parse::<f64>().map_err(|_| invalid(format!("{key}={v} is not a number")))).transpose()
        };
        let rotation = |value: Option<String>| -> Result<RotationDistance> {
            value.map_or(Ok(RotationDistance::default()), |v| v.parse())
        };
        let required = |key: &'static str, value: Option<f64>| {
            value.ok_or_else(|| invalid(format!("{key} is required, e.g. {name}({key}=10)")))
        };
        let parsed = match name.to_ascii_lowercase().as_str() {
            "euclidean" | "l2" => Self::Euclidean,
            "so3" => Self::So3(crate::So3 { rotation: rotation(take("rotation"))? }),
            "se3" => {
                let weight = number("rotation_weight_m_per_rad", take("rotation_weight_m_per_rad"))?;
                let rotation = rotation(take("rotation"))?;
                Self::Se3(crate::Se3 {
                    rotation_weight_m_per_rad: required("rotation_weight_m_per_rad", weight)?,
                    rotation,
                })
            }
            "se3_rotation" => Self::Se3Rotation(crate::Se3Rotation { rotation: rotation(take("rotation"))? }),
            "se2" => {
                let weight = number("rotation_weight_m_per_rad", take("rotation_weight_m_per_rad"))?;
                Self::Se2(crate::Se2 { rotation_weight_m_per_rad: required("rotation_weight_m_per_rad", weight)? })
            }
            "torus" => Self::Torus,
            "sphere" => Self::Sphere(crate::Sphere { radius: number("radius", take("radius"))?.unwrap_or(1.0) }),
            "haversine" => Self::Haversine(crate::Haversine {
                radius_m: number("radius_m", take("radius_m"))?.unwrap_or(crate::EARTH_RADIUS_M),
            }),
            "angular" => Self::Angular,
            _ => return Err(Error::UnknownName { kind: "metric", name: name.to_owned(), expected: Self::NAMES }),
        };
        if let Some((key, _)) = params.first() {
            return Err(invalid(format!("{name} takes no parameter {key:?}")));
        }
        // Weights and radii are checked here too, so a bad spec fails before any data is read.
        match parsed {
            MetricSpec::Se3(m) if !(m.rotation_weight_m_per_rad.is_finite() && m.rotation_weight_m_per_rad >= 0.0) => {
                Err(invalid(format!(
                    "rotation_weight_m_per_rad must be finite and ≥ 0, got {}",
                    m.rotation_weight_m_per_rad
                )))
            }
            MetricSpec::Se2(m) if !(m.rotation_weight_m_per_rad.is_finite() && m.rotation_weight_m_per_rad >= 0.0) => {
                Err(invalid(format!(
                    "rotation_weight_m_per_rad must be finite and ≥ 0, got {}",
                    m.rotation_weight_m_per_rad
                )))
            }
            MetricSpec::Sphere(m) if !(m.radius.is_finite() && m.radius > 0.0) => {
                Err(invalid(format!("radius must be positive and finite, got {}", m.radius)))
            }
            MetricSpec::Haversine(m) if !(m.radius_m.is_finite() && m.radius_m > 0.0) => {
                Err(invalid(format!("radius_m must be positive and finite, got {}", m.radius_m)))
            }
            _ => Ok(parsed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euclidean_in_every_dimension() {
        assert_eq!(Euclidean.distance(&[1.0], &[-2.0]), 3.0);
        assert_eq!(Euclidean.distance(&[0.0, 0.0, 0.0], &[2.0, 3.0, 6.0]), 7.0);
        assert_eq!(Euclidean.distance(&[1.0, 1.0, 1.0, 1.0], &[0.0, 0.0, 0.0, 0.0]), 2.0);
        assert_eq!(Euclidean.distance_rank(&[0.0, 0.0], &[3.0, 4.0]), 25.0);
        assert!(Euclidean.check_dim(0).is_err());
    }

    #[test]
    fn closest_is_the_earliest_argmin() {
        // Coordinates on a small grid: many exact ties, at every position modulo the lanes.
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % 4) as f64
        };
        for dim in [2, 3, 4] {
            for len in (1..40).chain([97, 250]) {
                for _ in 0..8 {
                    let points: Vec<f64> = (0..len * dim).map(|_| next()).collect();
                    let x: Vec<f64> = (0..dim).map(|_| next()).collect();
                    let ranks: Vec<f64> = points.chunks(dim).map(|p| Euclidean.distance_rank(&x, p)).collect();
                    let least = ranks.iter().copied().fold(f64::INFINITY, f64::min);
                    let expected = ranks.iter().position(|&r| r == least);
                    assert_eq!(Some(Euclidean.closest_in(&x, &points)), expected, "dim {dim}, {len} points");
                }
            }
        }
    }

    #[test]
    fn metric_specs_round_trip_and_reject_bad_text() {
        for text in [
            "euclidean",
            "so3(rotation=chordal)",
            "se3(rotation_weight_m_per_rad=2.5, rotation=geodesic)",
            "se3_rotation(rotation=geodesic)",
            "se2(rotation_weight_m_per_rad=4)",
            "torus",
            "sphere(radius=2)",
            "haversine(radius_m=6371008.8)",
            "angular",
        ] {
            let spec: MetricSpec = text.parse().unwrap();
            assert_eq!(spec.to_string(), text);
            assert_eq!(spec.to_string().parse::<MetricSpec>().unwrap(), spec);
        }
        assert_eq!("L2".parse::<MetricSpec>().unwrap(), MetricSpec::Euclidean);
        for bad in [
            "manhattan",
            "se3",
            "se3(rotation_weight_m_per_rad=-1)",
            "se3(rotation_weight_m_per_rad=x)",
            "se3(rotation_weight_m_per_rad=1",
            "se2(weight=1)",
            "so3(rotation=euler)",
            "sphere(radius=0)",
            "torus(radius=1)",
        ] {
            assert!(bad.parse::<MetricSpec>().is_err(), "{bad}");
        }
    }
}
