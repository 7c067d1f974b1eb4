//! Far-field pruning for fleets: a KD-tree (kiddo) over the centres of chunk balls.
//!
//! The ball hierarchy ([`BallTree`]) groups poses by time, which is what one trajectory needs:
//! consecutive poses are close. A fleet's sessions share no time order, so near the top of the
//! hierarchy a ball holds several sessions and reaches across the whole city, and a row of one
//! session walks into every other session's subtree before their balls rule it out: a cost that
//! grows with the number of sessions for every row, sessions² in all. Here the hierarchy is cut
//! into chunks (the largest nodes of one session whose ball has a radius of at most `R`; a
//! parked session is one chunk), and their centres go into KD-trees, one per class of radius
//! (R, 2R, 4R, …, so a few fast stretches do not widen every query). A block of rows asks each
//! class for the centres within its reach plus the class's largest radius, keeps the chunks
//! whose ball reaches (the hierarchy's own test), and walks the hierarchy below those chunks
//! only. The cost of a block follows the path near it, not the number of sessions.
//!
//! The KD-tree measures Euclidean distances between coordinates, so it only serves metrics that
//! are the Euclidean distance of the coordinates (positions in Rⁿ, n ≤ 3); other metrics keep
//! the hierarchy walk, which is exact for every metric.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::ball_tree::{BallTree, Chunk, Leaf};
use crate::error::Result;
use crate::metric::Metric;
use crate::trajectory::Trajectory;

/// Chunks of a fleet's hierarchy indexed by their centres.
pub(crate) struct ChunkIndex {
    chunks: Vec<Chunk>,
    classes: Vec<RadiusClass>,
}

/// The chunks whose radius is at most `max_radius` (and above the previous class's).
struct RadiusClass {
    max_radius: f64,
    members: Vec<u32>,
    tree: Kd,
}

/// A KD-tree over points of 1, 2 or 3 coordinates.
pub(crate) enum Kd {
    One(ImmutableKdTree<f64, 1>),
    Two(ImmutableKdTree<f64, 2>),
    Three(ImmutableKdTree<f64, 3>),
}

impl Kd {
    pub(crate) fn new(points: &[&[f64]]) -> Option<Self> {
        fn fixed<const K: usize>(points: &[&[f64]]) -> Vec<[f64; K]> {
            points.iter().map(|p| std::array::from_fn(|k| p[k])).collect()
        }
        match points.first().map(|p| p.len())? {
            1 => Some(Self::One(ImmutableKdTree::new_from_slice(&fixed::<1>(points)))),
            2 => Some(Self::Two(ImmutableKdTree::new_from_slice(&fixed::<2>(points)))),
            3 => Some(Self::Three(ImmutableKdTree::new_from_slice(&fixed::<3>(points)))),
            _ => None,
        }
    }

    /// Calls `visit` with the item of every point within `radius` of `x` (and perhaps a few
    /// just beyond: the squared radius is widened by a relative 10⁻⁹ for rounding).
    pub(crate) fn within(&self, x: &[f64], radius: f64, mut visit: impl FnMut(usize)) {
        let squared = radius * radius * (1.0 + 1e-9);
        match self {
            Self::One(tree) => {
                tree.within_unsorted::<SquaredEuclidean>(&[x[0]], squared).iter().for_each(|n| visit(n.item as usize))
            }
            Self::Two(tree) => tree
                .within_unsorted::<SquaredEuclidean>(&[x[0], x[1]], squared)
                .iter()
                .for_each(|n| visit(n.item as usize)),
            Self::Three(tree) => tree
                .within_unsorted::<SquaredEuclidean>(&[x[0], x[1], x[2]], squared)
                .iter()
                .for_each(|n| visit(n.item as usize)),
        }
    }
}

impl ChunkIndex {
    /// The index of `tree`'s chunks of radius at most `chunk_radius` (see
    /// [`BallTree::chunks`]); `None` for points of more than 3 coordinates.
    pub(crate) fn new(traj: &Trajectory, tree: &BallTree, starts: &[usize], chunk_radius: f64) -> Option<Self> {
        if !((1..=3).contains(&traj.dim()) && chunk_radius > 0.0 && chunk_radius.is_finite()) {
            return None;
        }
        let chunks = tree.chunks(starts, chunk_radius);
        let class_of = |radius: f64| {
            if radius <= chunk_radius {
                0
            } else {
                ((radius / chunk_radius).log2().ceil() as i32).clamp(1, 64) as usize
            }
        };
        let mut members: Vec<Vec<u32>> = Vec::new();
        for (k, chunk) in chunks.iter().enumerate() {
            let class = class_of(chunk.radius);
            if members.len() <= class {
                members.resize(class + 1, Vec::new());
            }
            members[class].push(k as u32);
        }
        let classes = members
            .into_iter()
            .filter(|m| !m.is_empty())
            .map(|members| {
                let max_radius = members.iter().map(|&k| chunks[k as usize].radius).fold(0.0, f64::max);
                let centres: Vec<&[f64]> =
                    members.iter().map(|&k| traj.point(chunks[k as usize].centre as usize)).collect();
                Kd::new(&centres).map(|tree| RadiusClass { max_radius, members, tree })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Self { chunks, classes })
    }

    /// Number of chunks.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.chunks.len()
    }

    /// The same stretches as [`BallTree::near_spans`] gives for `x` (up to how they are cut
    /// into leaves and inside stretches), found through the chunks near `x`: in increasing
    /// order, adjacent inside stretches merged. `x` has the trajectory's 1 to 3 coordinates,
    /// and the metric is their Euclidean distance.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) when the stretches do not fit in memory.
    pub(crate) fn near_spans<M: Metric + ?Sized>(
        &self,
        tree: &BallTree,
        metric: &M,
        x: &[f64],
        from: usize,
        (reach, inside_reach): (f64, f64),
        out: &mut Vec<Leaf>,
    ) -> Result<()> {
        out.clear();
        let mut grown = Ok(());
        for class in &self.classes {
            class.tree.within(x, reach + class.max_radius, |item| {
                let chunk = self.chunks[class.members[item] as usize];
                if chunk.hi as usize > from && grown.is_ok() {
                    grown = tree.near_spans_under(chunk.node, metric, x, from, (reach, inside_reach), out);
                }
            });
        }
        grown?;
        out.sort_unstable_by_key(|leaf| leaf.lo);
        // Merge adjacent inside stretches, as the hierarchy walk does.
        let mut kept = 0;
        for k in 0..out.len() {
            let leaf = out[k];
            if kept == 0 || !out[kept - 1].absorb(&leaf) {
                out[kept] = leaf;
                kept += 1;
            }
        }
        out.truncate(kept);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;

    /// Sessions of random walks around random places, some parked.
    fn fleet_points(sessions: usize, seed: u64) -> (Trajectory, Vec<usize>) {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut points, mut starts) = (Vec::new(), Vec::new());
        for s in 0..sessions {
            starts.push(points.len());
            let mut p = [next() * 100.0, next() * 100.0];
            let parked = s % 5 == 3;
            for _ in 0..(20 + (next() * 200.0) as usize) {
                if !parked {
                    p = [p[0] + next() - 0.5, p[1] + next() - 0.5];
                }
                points.push(p);
            }
        }
        let traj = Trajectory::from_points((0..points.len()).map(|i| i as f64).collect(), &points).unwrap();
        (traj, starts)
    }

    #[test]
    fn chunks_find_what_the_walk_finds() {
        for seed in 0..6 {
            let (traj, starts) = fleet_points(12, seed);
            let tree = BallTree::with_sessions(&traj, &Euclidean, 16, &starts).unwrap();
            let index = ChunkIndex::new(&traj, &tree, &starts, 2.0).unwrap();
            assert!(index.len() < traj.len());
            let (mut by_walk, mut by_index) = (Vec::new(), Vec::new());
            for (q, from) in [(0, 0), (150, 100), (400, 0), (traj.len() - 1, 700)] {
                let x = traj.point(q.min(traj.len() - 1));
                tree.near_spans(&Euclidean, x, from, (3.0, 1.0), &mut by_walk).unwrap();
                index.near_spans(&tree, &Euclidean, x, from, (3.0, 1.0), &mut by_index).unwrap();
                let covered = |spans: &[Leaf], inside: bool| -> Vec<usize> {
                    spans
                        .iter()
                        .filter(|s| !inside || s.inside)
                        .flat_map(|s| (s.lo as usize).max(from)..s.hi as usize)
                        .collect()
                };
                // Every pose within reach is in a stretch of both; inside poses agree.
                for k in from..traj.len() {
                    if Euclidean.distance(x, traj.point(k)) <= 3.0 {
                        assert!(covered(&by_index, false).contains(&k), "seed {seed}: pose {k} missed");
                    }
                }
                for k in covered(&by_index, true) {
                    assert!(Euclidean.distance(x, traj.point(k)) <= 1.0, "seed {seed}: pose {k} inside but far");
                }
                assert!(covered(&by_index, false).len() <= covered(&by_walk, false).len() + 64, "seed {seed}");
                assert!(by_index.windows(2).all(|w| w[0].hi <= w[1].lo), "in order, disjoint");
            }
        }
    }
}
