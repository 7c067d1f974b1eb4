//! Distances between points: the [`Metric`] trait and the Euclidean metric.

use crate::error::{Error, Result};

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
