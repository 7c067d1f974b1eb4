//! Loop components: the 4-connected components of S_γ on the sample lattice (paper, Def. 3).

use std::ops::Range;

use rayon::prelude::*;

use crate::error::Result;
use crate::interrupt::Interrupt;
use crate::memory::{try_filled, try_reserve, try_with_capacity};
use crate::metric::Metric;
use crate::sublevel::{PhaseTimer, Run, SublevelSet};
use crate::trajectory::{Trajectory, prefix_sums_by_session};
use crate::union_find::{MinRootForest, number_sets};

/// One loop component Ω.
///
/// A non-trivial component comes with its mirror Ωᵀ (t ↔ t′); it is reported once, as the half
/// with t ≤ t′, and its area and pair count are that half's. A *trivial* component contains
/// diagonal cells (i, i) and is its own mirror; it is reported whole (both halves, diagonal
/// once). So the area of S_γ is Σ area over trivial components + 2 Σ area over the others.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct LoopComponent {
    /// Index in [`Loops::components`](crate::Loops::components): components are numbered in
    /// order of their first cell, row by row.
    pub id: usize,
    /// Contains diagonal cells (i, i): its pairs are *simple loops*.
    pub trivial: bool,
    /// Area in the (t, t′) plane, s²: Σ w_i w_j over its cells.
    pub area_s2: f64,
    /// Number of lattice cells (i, j), by the rule of `area_s2` (the half for a non-trivial
    /// component, the whole for a trivial one).
    pub pair_count: u64,
    /// Number of pose pairs {i, j}, i < j: unordered pairs of distinct poses, the count every
    /// summary prints and the samplers draw from (the upper half without the diagonal). They
    /// sum over the components to [`Loops::pose_pair_count`](crate::Loops::pose_pair_count).
    pub pose_pair_count: u64,
    /// Number of runs (row intervals) in the upper half.
    pub run_count: usize,
    /// Number of holes (bounded background regions, 8-connected background) in the full plane.
    pub holes: u64,
    /// First and last pose index i (time t) of the reported half.
    pub i_range: [usize; 2],
    /// First and last pose index j (time t′) of the reported half.
    pub j_range: [usize; 2],
    /// The pair (i, j), i ≤ j, with the smallest distance: the argmin of the metric's
    /// [`distance_rank`](crate::Metric::distance_rank) (δ² for the Euclidean metric, which
    /// orders as δ does up to rounding), earliest in row order on ties.
    pub closest_pair: [usize; 2],
    /// δ at the closest pair (0 for a trivial component).
    pub closest_distance: f64,
}

#[cfg(feature = "serde")]
crate::packed::packed_record!(LoopComponent {
    id: usize,
    trivial: bool,
    area_s2: f64,
    pair_count: u64,
    pose_pair_count: u64,
    run_count: usize,
    holes: u64,
    i_range: [usize; 2],
    j_range: [usize; 2],
    closest_pair: [usize; 2],
    closest_distance: f64,
});

/// Component labels of runs, and the components themselves.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Labelling {
    pub labels: Vec<u32>,
    pub components: Vec<LoopComponent>,
}

/// What a component's statistics are summed from, over the runs of its upper half (rows for the
/// batch, columns for the online engine: the Euler number and everything else is the same).
///
/// The one home of the component tally: the batch labeller fills it row by row, the online
/// engine column by column, a tile's provisional component ([`TileComponent`]) is one with the
/// times of its extents; all of them merge parts with [`absorb`](Self::absorb) and report with
/// [`fold`](Self::fold).
///
/// [`TileComponent`]: crate::tile::TileComponent
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Tally {
    pub(crate) trivial: bool,
    pub(crate) runs: u64,
    /// Pairs of runs of consecutive rows (or columns) that share a column (or row).
    pub(crate) overlaps: u64,
    pub(crate) pairs: u64,
    pub(crate) area_s2: f64,
    pub(crate) diagonal_cells: u64,
    /// Pairs (i, i), (i, i + 1) both in the component.
    pub(crate) diagonal_links: u64,
    pub(crate) diagonal_area_s2: f64,
    pub(crate) rows: [usize; 2],
    pub(crate) columns: [usize; 2],
    /// The metric's rank of the closest pair, and the pair.
    pub(crate) closest: (f64, [usize; 2]),
}

/// A component's area, pair count, Euler number and extents ([`Tally::fold`]).
pub(crate) struct Folded {
    pub(crate) area_s2: f64,
    pub(crate) pair_count: u64,
    pub(crate) euler: i128,
    pub(crate) i_range: [usize; 2],
    pub(crate) j_range: [usize; 2],
}

impl Folded {
    /// Holes: 1 − χ for a connected set.
    pub(crate) fn holes(&self) -> u64 {
        u64::try_from(1 - self.euler).unwrap_or(u64::MAX)
    }
}

/// Whether the closest pair `candidate` (rank, pair) beats `current`: a smaller rank, or the
/// same rank at an earlier pair in row order.
pub(crate) fn closer(candidate: (f64, [usize; 2]), current: (f64, [usize; 2])) -> bool {
    candidate.0 < current.0 || (candidate.0 == current.0 && candidate.1 < current.1)
}

impl Tally {
    /// The reported statistics from the upper half's tallies: a trivial component whole (the
    /// half, its mirror, the diagonal counted once), another as its half. Counts saturate; only
    /// tallies decoded from corrupt bytes come near their limits ([`check`](Self::check)).
    pub(crate) fn fold(&self) -> Folded {
        let euler_half = i128::from(self.runs) - i128::from(self.overlaps);
        if self.trivial {
            let extent = [self.rows[0], self.columns[1]];
            Folded {
                area_s2: 2.0 * self.area_s2 - self.diagonal_area_s2,
                pair_count: self.pairs.saturating_mul(2).saturating_sub(self.diagonal_cells),
                euler: 2 * euler_half - i128::from(self.diagonal_cells) + i128::from(self.diagonal_links),
                i_range: extent,
                j_range: extent,
            }
        } else {
            Folded {
                area_s2: self.area_s2,
                pair_count: self.pairs,
                euler: euler_half,
                i_range: self.rows,
                j_range: self.columns,
            }
        }
    }

    /// Whether the counts are those of a set of cells: at most 2⁶³ pairs, no more diagonal
    /// cells than cells in a trivial component, and an Euler number of at most 1 (connected).
    ///
    /// # Errors
    /// What is wrong, as a phrase (“has Euler number 2, above …”), for the caller's error.
    pub(crate) fn check(&self) -> std::result::Result<(), String> {
        if self.trivial && self.pairs.checked_mul(2).and_then(|p| p.checked_sub(self.diagonal_cells)).is_none() {
            return Err("more diagonal cells than cells, or more than 2⁶³ cells".into());
        }
        let euler = self.fold().euler;
        if euler > 1 {
            return Err(format!("Euler number {euler}, above the 1 of a connected set"));
        }
        Ok(())
    }

    /// Pose pairs i < j of the component (its cells off the diagonal, in the upper half).
    pub(crate) fn pose_pair_count(&self) -> u64 {
        self.pairs.saturating_sub(self.diagonal_cells)
    }

    /// The component `id` these tallies report ([`fold`](Self::fold)), with δ at its closest
    /// pair: what the batch labeller and the tile merge give.
    pub(crate) fn loop_component(&self, id: usize, closest_distance: f64) -> LoopComponent {
        let folded = self.fold();
        LoopComponent {
            id,
            trivial: self.trivial,
            area_s2: folded.area_s2,
            pair_count: folded.pair_count,
            pose_pair_count: self.pose_pair_count(),
            run_count: self.runs as usize,
            holes: folded.holes(),
            i_range: folded.i_range,
            j_range: folded.j_range,
            closest_pair: self.closest.1,
            closest_distance,
        }
    }

    /// An empty tally, before its first run.
    pub(crate) fn empty() -> Self {
        Self { rows: [usize::MAX, 0], columns: [usize::MAX, 0], closest: (f64::INFINITY, [0, 0]), ..Self::default() }
    }

    /// Adds a run of row `i` over the columns `a..=b` (upper half: a ≥ i is not required, a = i
    /// is a diagonal cell), whose cells cover `area_s2`; `w_i` is row i's cell width, seconds.
    pub(crate) fn add_run(&mut self, i: usize, [a, b]: [usize; 2], area_s2: f64, w_i: f64) {
        self.runs += 1;
        self.pairs += (b - a + 1) as u64;
        self.area_s2 += area_s2;
        self.rows = [self.rows[0].min(i), self.rows[1].max(i)];
        self.columns = [self.columns[0].min(a), self.columns[1].max(b)];
        if a == i {
            self.trivial = true;
            self.diagonal_cells += 1;
            self.diagonal_area_s2 += w_i * w_i;
            if b > i {
                self.diagonal_links += 1;
            }
        }
    }

    /// Offers the pair `[i, j]` at the metric's `rank` as the closest; true when it is (a
    /// strictly smaller rank: runs come in row order, so the earliest pair wins ties).
    pub(crate) fn offer_closest(&mut self, rank: f64, pair: [usize; 2]) -> bool {
        let closer = rank < self.closest.0;
        if closer {
            self.closest = (rank, pair);
        }
        closer
    }

    /// Adds the tally of `other`, a part of the same component: counts and areas add, extents
    /// widen, the closer pair ([`closer`]) stays.
    pub(crate) fn absorb(&mut self, other: &Self) {
        self.trivial |= other.trivial;
        // Saturating: only counts decoded from corrupt bytes come near 2⁶⁴.
        self.runs = self.runs.saturating_add(other.runs);
        self.overlaps = self.overlaps.saturating_add(other.overlaps);
        self.pairs = self.pairs.saturating_add(other.pairs);
        self.area_s2 += other.area_s2;
        self.diagonal_cells = self.diagonal_cells.saturating_add(other.diagonal_cells);
        self.diagonal_links = self.diagonal_links.saturating_add(other.diagonal_links);
        self.diagonal_area_s2 += other.diagonal_area_s2;
        self.rows = [self.rows[0].min(other.rows[0]), self.rows[1].max(other.rows[1])];
        self.columns = [self.columns[0].min(other.columns[0]), self.columns[1].max(other.columns[1])];
        if closer(other.closest, self.closest) {
            self.closest = other.closest;
        }
    }
}

/// Labels the runs of `set` by union-find over 4-adjacent runs of consecutive rows (a
/// two-pointer sweep per row pair; stretches of rows in parallel, see
/// [`label_runs`]) and measures every component from its runs: stretches of
/// [`ROWS_PER_TALLY_TASK`] rows (counted from each session's first row) are tallied in parallel,
/// each in row order, and their partial tallies added up in stretch order, so that the sums are
/// the same on any number of threads, and a fleet's session the same as the session alone.
///
/// Time near-linear in runs plus one δ per run, memory O(runs). Holes come from the Euler number:
/// for the upper half, χ = #runs − #(overlapping run pairs in consecutive rows); a trivial
/// component adds its mirror, χ_full = 2χ − #diagonal cells + #diagonal links (i, i+1).
///
/// The labels, tallies and components are allocated fallibly ([`Error::OutOfMemory`]), and
/// `interrupt` is checked every 4096 rows ([`Error::Interrupted`]).
///
/// [`Error::OutOfMemory`]: crate::Error::OutOfMemory
/// [`Error::Interrupted`]: crate::Error::Interrupted
pub(crate) fn label_components<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    set: &SublevelSet,
    interrupt: &Interrupt,
) -> Result<Labelling> {
    let (labels, count) = try_label_runs(set, ROWS_PER_LABEL_TASK, interrupt)?;
    let timer = PhaseTimer::start("tally: prefix sums and tallies, serial");
    let widths = traj.cell_widths_s();
    let prefix = prefix_sums_by_session(widths, set.breaks())?;

    let mut tallies = try_filled(count as usize, Tally::empty(), "the loop components")?;
    let rows = widths.len();
    timer.finish();
    // Each task tallies the runs of its own stretch of rows, in row order, into partial tallies
    // of the components it meets; the partials are then added up in stretch order. The
    // stretches are fixed (not made from the number of threads), so the sums are the same on
    // any number of threads, and what stays serial is one `absorb` per component a stretch
    // meets, not one per run. They are counted from each session's first row, so that a
    // session's components in a fleet are summed, bit for bit, as those of the session alone.
    let breaks = set.breaks();
    let mut stretches = try_with_capacity(rows.div_ceil(ROWS_PER_TALLY_TASK) + breaks.len(), "the loop components")?;
    for (k, start) in std::iter::once(0).chain(breaks.iter().map(|&b| b as usize)).enumerate() {
        let end = breaks.get(k).map_or(rows, |&b| b as usize);
        stretches.extend((start..end).step_by(ROWS_PER_TALLY_TASK).map(|a| a..(a + ROWS_PER_TALLY_TASK).min(end)));
    }
    for batch in stretches.chunks(TALLY_TASKS_PER_BATCH) {
        interrupt.check()?;
        let timer = PhaseTimer::start("tally: stretches of rows, parallel");
        let partials: Vec<Result<Vec<(u32, Tally)>>> = batch
            .par_iter()
            .map_init(Vec::new, |table, task| {
                tally_rows((traj, metric, set, &labels), (widths, &prefix), task.clone(), table)
            })
            .collect();
        timer.finish();
        let _timer = PhaseTimer::start("tally: stretches added in order, serial");
        for partial in partials {
            for (label, part) in partial? {
                tallies[label as usize].absorb(&part);
            }
        }
    }

    let _timer = PhaseTimer::start("tally: components, serial");
    let mut components = try_with_capacity(tallies.len(), "the loop components")?;
    components.extend(tallies.into_iter().enumerate().map(|(id, t)| {
        debug_assert!(t.check().is_ok(), "a component's tally: {:?}", t.check());
        t.loop_component(id, metric.distance(traj.point(t.closest.1[0]), traj.point(t.closest.1[1])))
    }));
    Ok(Labelling { labels, components })
}

/// The partial tallies of the components that the runs of `rows` meet, each summed over its
/// runs in row order, in the order the components are first met. `widths` are the rows' cell
/// widths and `prefix` their running sums by session; `table` is the task's scratch, an open
/// hash table from a component to its partial, sized by the task's runs (not by the number of
/// components, so a task costs what its rows hold).
///
/// # Errors
/// [`Error::OutOfMemory`](crate::Error::OutOfMemory) when the partials do not fit in memory.
fn tally_rows<M: Metric + ?Sized>(
    (traj, metric, set, labels): (&Trajectory, &M, &SublevelSet, &[u32]),
    (widths, prefix): (&[f64], &[f64]),
    rows: Range<usize>,
    table: &mut Vec<u32>,
) -> Result<Vec<(u32, Tally)>> {
    const EMPTY: u32 = u32::MAX;
    let runs = set.row_offset(rows.end) - set.row_offset(rows.start);
    let size = (2 * runs).next_power_of_two().max(16);
    table.clear();
    try_reserve(table, size, "the loop components")?;
    table.resize(size, EMPTY);
    let (mask, shift) = (size - 1, u64::BITS - size.trailing_zeros());
    let mut partial: Vec<(u32, Tally)> = Vec::new();
    // The partial of each run of the row being tallied, for its overlaps with the next row.
    let mut row_parts: Vec<u32> = Vec::new();
    for i in rows {
        let w_i = widths[i];
        let row_offset = set.row_offset(i);
        row_parts.clear();
        try_reserve(&mut row_parts, set.row(i).len(), "the loop components")?;
        for (k, run) in set.row(i).iter().enumerate() {
            let r = row_offset + k;
            let label = labels[r];
            // Fibonacci hashing (the high bits of the product, so that labels with the same low
            // bits spread too), then linear probing.
            let mut h = (u64::from(label).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
            let part = loop {
                match table[h] {
                    EMPTY => {
                        try_reserve(&mut partial, 1, "the loop components")?;
                        table[h] = partial.len() as u32;
                        partial.push((label, Tally::empty()));
                        break table[h];
                    }
                    part if partial[part as usize].0 == label => break part,
                    _ => h = (h + 1) & mask,
                }
            };
            row_parts.push(part);
            let tally = &mut partial[part as usize].1;
            let (a, b) = (run.start as usize, run.end as usize);
            let j = set.closest_columns()[r] as usize;
            tally.add_run(i, [a, b], w_i * ((prefix[b] + widths[b]) - prefix[a]), w_i);
            tally.offer_closest(metric.distance_rank(traj.point(i), traj.point(j)), [i, j]);
        }
        if i + 1 < widths.len() {
            for_each_overlap(set, i..i + 1, |r, _| partial[row_parts[r - row_offset] as usize].1.overlaps += 1);
        }
    }
    Ok(partial)
}

/// Stretches of rows whose partial tallies are made before they are added up: bounds their
/// memory, and the rows between two looks at the interrupt.
const TALLY_TASKS_PER_BATCH: usize = 32;

/// Rows one rayon task tallies into partials, counted from each session's first row: fixed, so
/// that the sums do not depend on the number of threads.
const ROWS_PER_TALLY_TASK: usize = 1 << 9;

/// Rows whose runs are joined by one rayon task before the joins across tasks, at most.
pub(crate) const ROWS_PER_LABEL_TASK: usize = 1 << 14;

/// Stretches of rows a thread labels, of about equal runs: rayon hands them out as threads come
/// free, so a dense part of the drive does not leave the other threads waiting.
const LABEL_TASKS_PER_THREAD: usize = 8;

/// Runs of the smallest stretch of rows one task labels (the joins across stretches are serial,
/// one pair of rows each).
const MIN_RUNS_PER_LABEL_TASK: usize = 1 << 12;

/// The component id of every run, ids numbered by first appearance (row-major), and the number
/// of components.
///
/// Union-find over run ids in which a set's root is always its smallest id: joins point from
/// later runs to earlier ones, so one forward pass turns parents into ids (a run's parent is
/// numbered before it). The runs of consecutive stretches of rows are joined in parallel (each
/// stretch only touches its own slice of the parent array), then the pairs of rows across
/// stretches. The result does not depend on the stretches or the thread count. O(runs · log)
/// worst case, near-linear in practice; 4 bytes a run.
///
/// # Panics
/// When memory for the labels runs out ([`try_label_runs`] returns the error instead).
pub(crate) fn label_runs(set: &SublevelSet, rows_per_task: usize) -> (Vec<u32>, u32) {
    try_label_runs(set, rows_per_task, &Interrupt::new()).unwrap_or_else(|error| panic!("{error}"))
}

/// [`label_runs`], with the labels allocated fallibly and `interrupt` checked between
/// stretches.
fn try_label_runs(set: &SublevelSet, rows_per_task: usize, interrupt: &Interrupt) -> Result<(Vec<u32>, u32)> {
    let runs_per_task =
        set.runs().len().div_ceil(LABEL_TASKS_PER_THREAD * rayon::current_num_threads()).max(MIN_RUNS_PER_LABEL_TASK);
    try_label_runs_in(set, (rows_per_task, runs_per_task), interrupt)
}

/// [`try_label_runs`] over stretches of at most `rows_per_task` rows that end at the row that
/// takes them past `runs_per_task` runs.
fn try_label_runs_in(
    set: &SublevelSet,
    (rows_per_task, runs_per_task): (usize, usize),
    interrupt: &Interrupt,
) -> Result<(Vec<u32>, u32)> {
    let run_count = set.runs().len();
    debug_assert!(run_count <= u32::MAX as usize, "run ids are u32");
    let timer = PhaseTimer::start("label: stretches, parallel");
    let mut parent: Vec<u32> = Vec::new();
    try_reserve(&mut parent, run_count, "the component labels of the runs")?;
    parent.par_extend(0..run_count as u32);
    let rows = set.rows();
    // Stretches of about equal work (runs), several a thread, so that a part of the drive dense
    // with revisits is shared out too: a stretch ends after `rows_per_task` rows or at the row
    // that takes it past its share of the runs, whichever comes first.
    let offsets = set.row_offsets();
    let mut starts: Vec<usize> = Vec::new();
    let mut start = 0;
    while start < rows {
        try_reserve(&mut starts, 1, "the component labels of the runs")?;
        starts.push(start);
        let by_runs = offsets.partition_point(|&offset| offset < offsets[start].saturating_add(runs_per_task));
        start = by_runs.clamp(start + 1, (start + rows_per_task.max(1)).min(rows));
    }
    // Each stretch of rows with its own slice of the parent array.
    let mut stretches = try_with_capacity(starts.len(), "the component labels of the runs")?;
    let mut rest = parent.as_mut_slice();
    for (k, &start) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(rows);
        let (slice, tail) = rest.split_at_mut(set.row_offset(end) - set.row_offset(start));
        stretches.push((start..end, slice));
        rest = tail;
    }
    stretches.into_par_iter().for_each(|(stretch, slice)| {
        if interrupt.is_interrupted() {
            return;
        }
        let mut forest = MinRootForest::new(slice, set.row_offset(stretch.start));
        for_each_overlap(set, stretch.start..stretch.end - 1, |a, b| forest.union(a, b));
    });
    interrupt.check()?;
    timer.finish();
    let _timer = PhaseTimer::start("label: joins across stretches and numbering, serial");
    let mut forest = MinRootForest::new(&mut parent, 0);
    for &start in starts.iter().skip(1) {
        for_each_overlap(set, start - 1..start, |a, b| forest.union(a, b));
    }
    let count = number_sets(&mut parent);
    Ok((parent, count))
}

/// Calls `f(a, b)` for every pair of runs `a` (row i) and `b` (row i + 1) that share a column,
/// for the rows i in `upper_rows`, in order.
pub(crate) fn for_each_overlap(set: &SublevelSet, upper_rows: Range<usize>, mut f: impl FnMut(usize, usize)) {
    for i in upper_rows {
        if set.breaks_after(i) {
            // The last row of one session and the first of the next are not adjacent.
            continue;
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;

    /// Components by breadth-first search over 4-adjacent runs, numbered by their first run.
    fn reference_labels(set: &SublevelSet) -> Vec<u32> {
        let count = set.runs().len();
        let mut neighbours = vec![Vec::new(); count];
        for_each_overlap(set, 0..set.rows() - 1, |a, b| {
            neighbours[a].push(b);
            neighbours[b].push(a);
        });
        let mut labels = vec![u32::MAX; count];
        let mut next = 0;
        for first in 0..count {
            if labels[first] != u32::MAX {
                continue;
            }
            let mut queue = std::collections::VecDeque::from([first]);
            labels[first] = next;
            while let Some(r) = queue.pop_front() {
                for &other in &neighbours[r] {
                    if labels[other] == u32::MAX {
                        labels[other] = next;
                        queue.push_back(other);
                    }
                }
            }
            next += 1;
        }
        labels
    }

    #[test]
    fn labels_do_not_depend_on_the_stretches() {
        // A lattice walk in a small box: it comes back often, so rows hold several runs and
        // components cross every stretch boundary.
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut position = [0_i64, 0];
        let points: Vec<[f64; 2]> = (0..700)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let axis = (state % 2) as usize;
                let step = if (state / 2).is_multiple_of(2) { 1 } else { -1 };
                position[axis] = (position[axis] + step).clamp(0, 7);
                [position[0] as f64, position[1] as f64]
            })
            .collect();
        let traj = Trajectory::from_points((0..points.len()).map(|i| i as f64).collect(), &points).unwrap();
        let set = SublevelSet::compute(&traj, &Euclidean, 1.5).unwrap();
        let expected = reference_labels(&set);
        assert!(expected.iter().max().is_some_and(|&m| m > 3), "the walk should make several components");
        for rows_per_task in [1, 2, 3, 7, 64, 699, 700, 10_000] {
            for runs_per_task in [1, 2, 5, 40, 300, usize::MAX] {
                let stretches = (rows_per_task, runs_per_task);
                let (labels, count) = try_label_runs_in(&set, stretches, &Interrupt::new()).unwrap();
                assert_eq!(labels, expected, "{rows_per_task} rows, {runs_per_task} runs a task");
                assert_eq!(Some(count), expected.iter().max().map(|m| m + 1));
            }
        }
    }
}
