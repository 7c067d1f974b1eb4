//! Distances between points: the [`Metric`] trait and the Euclidean metric.

use crate::error::{Error, Result};
use crate::trajectory::{Manifold, Trajectory};

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

    /// Whether it measures the points of trajectories on `manifold` (a trajectory records the
    /// manifold its constructor built it on, [`Trajectory::manifold`]). The engine refuses a
    /// metric that does not fit before measuring anything, naming both. Defaults to `true`, for
    /// metrics defined outside this crate; the crate's own metrics fit their manifold and plain
    /// [`Euclidean`](Manifold::Euclidean) coordinates of their layout, and the Euclidean metric
    /// fits no manifold whose coordinates are not a vector space (quaternions, angles).
    fn fits(&self, manifold: Manifold) -> bool {
        let _ = manifold;
        true
    }

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

    /// δ(a, b) between 2-D points: [`distance`](Self::distance)'s value bit for bit. The
    /// engine's row scan calls it on trajectories of dimension 2, reading the points as arrays
    /// (no slice to build and check a distance). Defaults to `distance`; a metric overrides it
    /// only with the same arithmetic.
    #[inline]
    fn distance_2d(&self, a: &[f64; 2], b: &[f64; 2]) -> f64 {
        self.distance(a, b)
    }

    /// δ(a, b) between 3-D points, as [`distance_2d`](Self::distance_2d) for dimension 3.
    #[inline]
    fn distance_3d(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
        self.distance(a, b)
    }

    /// The size of δ's absolute rounding error, in ulps of this value, on `traj`'s points: the
    /// engine widens its triangle-inequality margin by 64 ulps of it. Defaults to the largest
    /// absolute coordinate (right for metrics computed from coordinate differences); metrics
    /// that scale angles (spheres, rotation weights) return the scale they multiply by.
    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        traj.coords().iter().fold(0.0_f64, |m, c| m.max(c.abs()))
    }

    /// Whether δ is the Euclidean distance of the coordinates: then a KD-tree over points
    /// prunes for it (a fleet's spatial index). Defaults to `false`.
    fn is_coordinate_euclidean(&self) -> bool {
        false
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

    /// Rⁿ coordinates, and unit descriptors (their chordal distance). Not quaternions, angles
    /// or the GNSS layout, whose columns are not a vector space.
    fn fits(&self, manifold: Manifold) -> bool {
        matches!(manifold, Manifold::Euclidean | Manifold::Descriptors)
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        squared_l2(a, b).sqrt()
    }

    #[inline]
    fn distance_2d(&self, a: &[f64; 2], b: &[f64; 2]) -> f64 {
        squared_l2_2d(a, b).sqrt()
    }

    #[inline]
    fn distance_3d(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
        squared_l2_3d(a, b).sqrt()
    }

    #[inline]
    fn is_coordinate_euclidean(&self) -> bool {
        true
    }

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
        (&[ax, ay], &[bx, by]) => squared_l2_2d(&[ax, ay], &[bx, by]),
        (&[ax, ay, az], &[bx, by, bz]) => squared_l2_3d(&[ax, ay, az], &[bx, by, bz]),
        _ => a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum(),
    }
}

/// δ² between 2-D points, summed in coordinate order (every Euclidean path of dimension 2).
#[inline]
fn squared_l2_2d(&[ax, ay]: &[f64; 2], &[bx, by]: &[f64; 2]) -> f64 {
    (ax - bx).powi(2) + (ay - by).powi(2)
}

/// δ² between 3-D points, summed in coordinate order (every Euclidean path of dimension 3).
#[inline]
pub(crate) fn squared_l2_3d(&[ax, ay, az]: &[f64; 3], &[bx, by, bz]: &[f64; 3]) -> f64 {
    (ax - bx).powi(2) + (ay - by).powi(2) + (az - bz).powi(2)
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
    fn fixed_size_distances_are_the_slices_bit_for_bit() {
        // Coordinates of many magnitudes, where a different order of the sum would round
        // differently in some pairs.
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut next = || (rng.random::<f64>() - 0.5) * 10f64.powi(rng.random_range(-4..9));
        for _ in 0..10_000 {
            let (a, b) = ([next(), next(), next()], [next(), next(), next()]);
            let expected = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).fold(0.0, |s, t| s + t).sqrt();
            assert_eq!(Euclidean.distance_3d(&a, &b).to_bits(), expected.to_bits());
            assert_eq!(Euclidean.distance(&a, &b).to_bits(), expected.to_bits());
            let (a, b) = ([a[0], a[1]], [b[0], b[1]]);
            let expected = ((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])).sqrt();
            assert_eq!(Euclidean.distance_2d(&a, &b).to_bits(), expected.to_bits());
            assert_eq!(Euclidean.distance(&a, &b).to_bits(), expected.to_bits());
        }
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
}
