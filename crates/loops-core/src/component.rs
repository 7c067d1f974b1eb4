//! Loop components: the 4-connected components of S_γ on the sample lattice (paper, Def. 3).

use petgraph::unionfind::UnionFind;

use crate::metric::Metric;
use crate::sublevel::{Run, SublevelSet};
use crate::trajectory::{Trajectory, prefix_sums};

/// One loop component Ω.
///
/// A non-trivial component comes with its mirror Ωᵀ (t ↔ t′); it is reported once, as the half
/// with t ≤ t′, and its area and pair count are that half's. A *trivial* component contains
/// diagonal cells (i, i) and is its own mirror; it is reported whole (both halves, diagonal
/// once). So the area of S_γ is Σ area over trivial components + 2 Σ area over the others.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopComponent {
    /// Index in [`Loops::components`](crate::Loops::components): components are numbered in
    /// order of their first cell, row by row.
    pub id: usize,
    /// Contains diagonal cells (i, i): its pairs are *simple loops*.
    pub trivial: bool,
    /// Area in the (t, t′) plane, s²: Σ w_i w_j over its cells.
    pub area_s2: f64,
    /// Number of lattice cells (i, j).
    pub pairs: u64,
    /// Number of runs (row intervals) in the upper half.
    pub runs: usize,
    /// Number of holes (bounded background regions, 8-connected background) in the full plane.
    pub holes: u64,
    /// First and last row index i (time t) of the reported half.
    pub rows: [usize; 2],
    /// First and last column index j (time t′) of the reported half.
    pub columns: [usize; 2],
    /// The pair (i, j), i ≤ j, with the smallest distance: the argmin of the metric's
    /// [`distance_rank`](crate::Metric::distance_rank) (δ² for the Euclidean metric, which
    /// orders as δ does up to rounding), earliest in row order on ties.
    pub closest_pair: [usize; 2],
    /// δ at the closest pair (0 for a trivial component).
    pub closest_distance: f64,
}

/// Component labels of runs, and the components themselves.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Labelling {
    pub labels: Vec<u32>,
    pub components: Vec<LoopComponent>,
}

#[derive(Debug, Clone, Default)]
struct Tally {
    trivial: bool,
    runs: usize,
    overlaps: u64,
    pairs: u64,
    area_s2: f64,
    diagonal_cells: u64,
    diagonal_links: u64,
    diagonal_area_s2: f64,
    rows: [usize; 2],
    columns: [usize; 2],
    closest: (f64, [usize; 2]),
}

/// Labels the runs of `set` by union-find over 4-adjacent runs of consecutive rows (a
/// two-pointer sweep per row pair; DESIGN §4.2) and measures every component from its runs.
///
/// Time O(runs · α(runs)) plus one δ per run, memory O(runs). Holes come from the Euler number:
/// for the upper half, χ = #runs − #(overlapping run pairs in consecutive rows); a trivial
/// component adds its mirror, χ_full = 2χ − #diagonal cells + #diagonal links (i, i+1).
pub(crate) fn label_components<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, set: &SublevelSet) -> Labelling {
    let runs = set.runs();
    debug_assert!(runs.len() < 1 << 31, "run ids must leave the top bit free for numbering");
    let mut union_find = UnionFind::<u32>::new(runs.len());
    for_each_overlap(set, |a, b| {
        union_find.union(a as u32, b as u32);
    });

    // Number components by first appearance (row-major): deterministic ids. The labelling
    // array (each run's root) is turned into ids in place: a root's slot holds its component's
    // id, flagged, once the component is seen, so no second run-sized table is needed.
    const SEEN: u32 = 1 << 31;
    let mut labels = union_find.into_labeling();
    let mut count = 0u32;
    for r in 0..labels.len() {
        let root = labels[r];
        let id = if root & SEEN != 0 {
            root & !SEEN // r is a root already numbered through an earlier member
        } else if labels[root as usize] & SEEN != 0 {
            labels[root as usize] & !SEEN
        } else {
            count += 1;
            labels[root as usize] = (count - 1) | SEEN;
            count - 1
        };
        labels[r] = id | SEEN;
    }
    labels.iter_mut().for_each(|label| *label &= !SEEN);

    let widths = traj.cell_widths_s();
    let prefix = prefix_sums(widths);

    let mut tallies = vec![
        Tally {
            rows: [usize::MAX, 0],
            columns: [usize::MAX, 0],
            closest: (f64::INFINITY, [0, 0]),
            ..Tally::default()
        };
        count as usize
    ];
    for (i, &w_i) in widths.iter().enumerate() {
        let offset = set.row_offset(i);
        for (k, run) in set.row(i).iter().enumerate() {
            let r = offset + k;
            let tally = &mut tallies[labels[r] as usize];
            let (a, b) = (run.start as usize, run.end as usize);
            tally.runs += 1;
            tally.pairs += run.len() as u64;
            tally.area_s2 += w_i * (prefix[b + 1] - prefix[a]);
            tally.rows = [tally.rows[0].min(i), tally.rows[1].max(i)];
            tally.columns = [tally.columns[0].min(a), tally.columns[1].max(b)];
            if a == i {
                tally.trivial = true;
                tally.diagonal_cells += 1;
                tally.diagonal_area_s2 += w_i * w_i;
                if b > i {
                    tally.diagonal_links += 1;
                }
            }
            let j = set.closest_columns()[r] as usize;
            let rank = metric.distance_rank(traj.point(i), traj.point(j));
            if rank < tally.closest.0 {
                tally.closest = (rank, [i, j]);
            }
        }
    }
    for_each_overlap(set, |a, _| tallies[labels[a] as usize].overlaps += 1);

    let components = tallies
        .into_iter()
        .enumerate()
        .map(|(id, t)| {
            let euler_half = t.runs as i64 - t.overlaps as i64;
            let (area_s2, pairs, euler, rows, columns) = if t.trivial {
                // Whole: the half, its mirror, the diagonal counted once.
                let euler = 2 * euler_half - t.diagonal_cells as i64 + t.diagonal_links as i64;
                let extent = [t.rows[0], t.columns[1]];
                (2.0 * t.area_s2 - t.diagonal_area_s2, 2 * t.pairs - t.diagonal_cells, euler, extent, extent)
            } else {
                (t.area_s2, t.pairs, euler_half, t.rows, t.columns)
            };
            debug_assert!(euler <= 1, "a connected set has Euler number ≤ 1");
            LoopComponent {
                id,
                trivial: t.trivial,
                area_s2,
                pairs,
                runs: t.runs,
                holes: (1 - euler) as u64,
                rows,
                columns,
                closest_pair: t.closest.1,
                closest_distance: metric.distance(traj.point(t.closest.1[0]), traj.point(t.closest.1[1])),
            }
        })
        .collect();
    Labelling { labels, components }
}

/// Calls `f(a, b)` for every pair of runs `a` (row i) and `b` (row i + 1) that share a column.
fn for_each_overlap(set: &SublevelSet, mut f: impl FnMut(usize, usize)) {
    for i in 0..set.rows().saturating_sub(1) {
        let (upper, lower) = (set.row(i), set.row(i + 1));
        let (base_upper, base_lower) = (set.row_offset(i), set.row_offset(i + 1));
        let (mut p, mut q) = (0, 0);
        while p < upper.len() && q < lower.len() {
            let (a, b): (Run, Run) = (upper[p], lower[q]);
            if a.overlaps(b) {
                f(base_upper + p, base_lower + q);
            }
            // Advance the run that ends first; both when they end together.
            if a.end <= b.end {
                p += 1;
            }
            if b.end <= a.end {
                q += 1;
            }
        }
    }
}
