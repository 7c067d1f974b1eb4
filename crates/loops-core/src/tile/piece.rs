//! The stretches of a tile that can hold a pair within γ: a tile of two disjoint ranges of poses
//! is scanned on those stretches only, so that its cost follows the poses that come near the
//! other side rather than the whole block (a block covers its district; only its passes near
//! the other block's district matter).
//!
//! Each side is cut into chunks of [`CHUNK`] consecutive poses with their bounding balls (centre
//! the middle pose, radius the largest distance from it); a chunk is live when its ball comes
//! within γ of a ball of the other side: first by groups of [`GROUP`] poses (balls joined from
//! their chunks'), then, within two groups that meet, by the chunks of each that reach the other
//! group, pair by pair. Consecutive live chunks make one stretch. A pose with a pose of the other
//! side within γ passes every test (its chunk's ball reaches the other's chunk and group, by the
//! triangle inequality, with a margin above rounding), so a pose of a chunk that is not live
//! holds no cell of S_γ in the tile.

use std::ops::Range;

use crate::metric::Metric;
use crate::trajectory::Trajectory;

/// Poses per chunk: the finest unit a tile's scan is trimmed to.
pub(crate) const CHUNK: usize = 64;

/// Poses per group: chunks are compared only within groups whose balls meet.
const GROUP: usize = 16 * CHUNK;

pub(crate) use crate::ball_tree::{joined_radius, pose_ball};

/// The bounding balls of `range` of `traj` cut every `size` poses: (range, centre pose, radius).
fn balls<M: Metric + ?Sized>(traj: &Trajectory, range: Range<usize>, size: usize, metric: &M) -> Vec<Ball> {
    range
        .clone()
        .step_by(size)
        .map(|lo| {
            let hi = (lo + size).min(range.end);
            let (centre, radius) = pose_ball(traj, lo, hi, metric);
            (lo..hi, centre, radius)
        })
        .collect()
}

/// Balls of `per` consecutive `balls` of `traj` each, centred on the middle ball's centre
/// ([`joined_radius`]): O(balls) distance evaluations, where bounding each group from its
/// poses would cost O(poses).
fn joined<M: Metric + ?Sized>(traj: &Trajectory, balls: &[Ball], per: usize, metric: &M) -> Vec<Ball> {
    balls
        .chunks(per)
        .map(|part| {
            let centre = part[part.len() / 2].1;
            let radius = joined_radius(traj.point(centre), part.iter().map(|(_, c, r)| (traj.point(*c), *r)), metric);
            (part[0].0.start..part[part.len() - 1].0.end, centre, radius)
        })
        .collect()
}

/// A ball: the poses `range`, its centre pose and its radius.
type Ball = (Range<usize>, usize, f64);

/// The balls of one side of a tile (a range of one session's poses): its chunks' and its
/// groups'. O(poses) distance evaluations; the same for every tile of the range, so that a scan
/// of many tiles makes them once per session block and shares them ([`SideBalls::new`]).
#[derive(Debug, Clone)]
pub(crate) struct SideBalls {
    range: Range<usize>,
    chunks: Vec<Ball>,
    groups: Vec<Ball>,
}

impl SideBalls {
    /// The balls of the poses `range` of `session`.
    pub(crate) fn new<M: Metric + ?Sized>(session: &Trajectory, range: Range<usize>, metric: &M) -> Self {
        let chunks = balls(session, range.clone(), CHUNK, metric);
        let groups = joined(session, &chunks, GROUP / CHUNK, metric);
        Self { range, chunks, groups }
    }

    /// The poses they bound (indices of their session).
    pub(crate) fn range(&self) -> &Range<usize> {
        &self.range
    }
}

/// The live stretches of the rows and columns that `rows` and `columns` bound (ranges of
/// indices of `row_session` and `column_session`, disjoint when the sessions are one):
/// increasing, disjoint, non-adjacent ranges; either side is empty when no pair can lie within
/// γ. Given the sides' balls ([`SideBalls`]), O(groups²) for the groups' balls, and for each
/// meeting pair of groups, the chunks of each that reach the other group, and the pairs of
/// those.
pub(crate) fn live_stretches<M: Metric + ?Sized>(
    row_session: &Trajectory,
    rows: &SideBalls,
    column_session: &Trajectory,
    columns: &SideBalls,
    metric: &M,
    gamma: f64,
) -> [Vec<Range<usize>>; 2] {
    // A relative 10⁻⁶ is far above the rounding of three distances.
    let meets = |(_, p, r_p): &Ball, (_, q, r_q): &Ball| {
        metric.distance(row_session.point(*p), column_session.point(*q)) <= (gamma + r_p + r_q) * (1.0 + 1e-6) + 1e-9
    };
    let per_group = GROUP / CHUNK;
    let (chunk_rows, chunk_columns) = (&rows.chunks, &columns.chunks);
    let (group_rows, group_columns) = (&rows.groups, &columns.groups);
    let (mut live_rows, mut live_columns) = (vec![false; chunk_rows.len()], vec![false; chunk_columns.len()]);
    for (g, group_row) in group_rows.iter().enumerate() {
        for (h, group_column) in group_columns.iter().enumerate() {
            if !meets(group_row, group_column) {
                continue;
            }
            // Only chunks whose ball meets the other side's group can meet one of its chunks:
            // 2 · 16 tests first, then the pairs of those (few, at a border between districts).
            let row_chunks: Vec<usize> = (g * per_group..((g + 1) * per_group).min(chunk_rows.len()))
                .filter(|&p| meets(&chunk_rows[p], group_column))
                .collect();
            let column_chunks: Vec<usize> = (h * per_group..((h + 1) * per_group).min(chunk_columns.len()))
                .filter(|&q| meets(group_row, &chunk_columns[q]))
                .collect();
            for &p in &row_chunks {
                for &q in &column_chunks {
                    if (!live_rows[p] || !live_columns[q]) && meets(&chunk_rows[p], &chunk_columns[q]) {
                        live_rows[p] = true;
                        live_columns[q] = true;
                    }
                }
            }
        }
    }
    let stretches = |chunks: &[Ball], live: &[bool]| {
        let mut out: Vec<Range<usize>> = Vec::new();
        for (chunk, _, _) in chunks.iter().zip(live).filter(|(_, live)| **live).map(|(c, _)| c) {
            match out.last_mut() {
                Some(last) if last.end == chunk.start => last.end = chunk.end,
                _ => out.push(chunk.clone()),
            }
        }
        out
    };
    [stretches(chunk_rows, &live_rows), stretches(chunk_columns, &live_columns)]
}
