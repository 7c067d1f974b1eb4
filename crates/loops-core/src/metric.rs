//! Distances between points: the [`Metric`] trait and the Euclidean metric.

use crate::error::{Error, Result};
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

    /// δ(a, b), in the metric's unit (metres for positions). `a` and `b` have the checked dimension.
    fn distance(&self, a: &[f64], b: &[f64]) -> f64;

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
            return Err(Error::DimensionMismatch { metric: self.name(), expected: "at least 1".into(), found: dim });
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
            [x0, x1, x2] => closest_fixed(points, |p: &[f64; 3]| {
                (p[0] - x0).powi(2) + (p[1] - x1).powi(2) + (p[2] - x2).powi(2)
            }),
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

/// Argmin of `rank` over fixed-size points: a first pass finds the minimum (branch free, so the
/// compiler vectorizes it), a second its earliest position.
#[inline]
fn closest_fixed<const D: usize>(points: &[f64], rank: impl Fn(&[f64; D]) -> f64) -> usize {
    let (blocks, _) = points.as_chunks::<D>();
    let least = blocks.iter().map(&rank).fold(f64::INFINITY, f64::min);
    blocks.iter().position(|p| rank(p) == least).unwrap_or(0)
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
}

/// A metric chosen by name at run time (from Python or the command line), dispatched once to
/// the statically typed engine, so the hot loops stay monomorphic.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[non_exhaustive]
pub enum MetricSpec {
    /// [`Euclidean`].
    #[default]
    Euclidean,
}

impl MetricSpec {
    /// The accepted names.
    pub const NAMES: &'static str = "euclidean";

    /// The name, as [`FromStr`](std::str::FromStr) accepts it.
    pub fn name(&self) -> String {
        match self {
            Self::Euclidean => Euclidean.name(),
        }
    }

    /// [`find_loops`](crate::find_loops) under this metric.
    ///
    /// # Errors
    /// As [`find_loops`](crate::find_loops).
    pub fn find_loops(&self, traj: &Trajectory, gamma: f64) -> Result<crate::Loops> {
        match self {
            Self::Euclidean => crate::find_loops(traj, &Euclidean, gamma),
        }
    }
}

impl std::str::FromStr for MetricSpec {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        match name.to_ascii_lowercase().as_str() {
            "euclidean" | "l2" => Ok(Self::Euclidean),
            _ => Err(Error::UnknownName { kind: "metric", name: name.to_owned(), expected: Self::NAMES }),
        }
    }
}
