//! The sublevel set S_γ = {(t, t′) : δ(ξ(t), ξ(t′)) ≤ γ} (paper, Eq. 3) on the sample lattice,
//! stored as runs.

use rayon::prelude::*;

use crate::ball_tree::{BallTree, Leaf};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::memory::{try_collect, try_copy, try_reserve, try_with_capacity};
use crate::metric::{Metric, squared_l2_3d};
use crate::separation::Separation;
use crate::spatial::ChunkIndex;
use crate::trajectory::Trajectory;

/// Checks a distance threshold γ: positive and finite. Front ends call it to refuse a bad γ
/// before any work; the engine calls it too.
///
/// # Errors
/// [`Error::InvalidGamma`] otherwise.
///
/// # Examples
/// ```
/// assert!(loops_core::check_gamma(40.0).is_ok());
/// assert!(loops_core::check_gamma(-1.0).is_err());
/// ```
pub fn check_gamma(gamma: f64) -> Result<()> {
    if gamma.is_finite() && gamma > 0.0 { Ok(()) } else { Err(Error::InvalidGamma(gamma)) }
}

/// A maximal interval of columns `start..=end` of one row `i` of S_γ, with `i ≤ start`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Run {
    /// First column (pose index j), inclusive.
    pub start: u32,
    /// Last column, inclusive.
    pub end: u32,
}

impl Run {
    /// Number of cells.
    pub fn len(self) -> usize {
        (self.end - self.start) as usize + 1
    }

    /// Never: a run has at least one cell.
    pub fn is_empty(self) -> bool {
        false
    }

    /// Whether the two runs share a column (4-adjacency between consecutive rows).
    pub fn overlaps(self, other: Run) -> bool {
        self.start.max(other.start) <= self.end.min(other.end)
    }
}

/// The upper half (j ≥ i, diagonal included) of S_γ on the sample lattice: every pair `(i, j)`
/// with `δ(x_i, x_j) ≤ γ`, exactly, as runs per row. Never a list of pairs.
///
/// With a [`Separation`], the subset X ⊆ S_γ of the pairs that also lie far enough apart along
/// the trajectory (no diagonal cell then).
///
/// Memory is 12 bytes a run plus 8 bytes a row.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "SublevelSetState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct SublevelSet {
    gamma: f64,
    separation: Separation,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed::offsets"))]
    row_offsets: Vec<usize>,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    runs: Vec<Run>,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    closest: Vec<u32>,
    /// A fleet's session starts after the first (rows of different sessions are not
    /// 4-adjacent); empty for one trajectory.
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    breaks: Vec<u32>,
}

#[cfg(feature = "serde")]
crate::packed::packed_record!(Run { start: u32, end: u32 });

/// The wall and CPU time of one phase of the engine, written to stderr (`phase NAME WALL_MS
/// CPU_MS`) when it is dropped, with the `phase-times` feature: profiles of the parallel split
/// name the phases that run on one thread `serial`. The CPU time is the process's, summed over
/// its threads (`/proc/self/task/*/schedstat`, Linux), so that a loaded machine, which stretches
/// the wall time, does not change it. Nothing without the feature.
#[derive(Debug)]
pub(crate) struct PhaseTimer {
    #[cfg(feature = "phase-times")]
    phase: (&'static str, std::time::Instant, u64),
}

impl PhaseTimer {
    /// Starts timing the phase `name`.
    #[inline]
    pub(crate) fn start(name: &'static str) -> Self {
        let _ = name;
        Self {
            #[cfg(feature = "phase-times")]
            phase: (name, std::time::Instant::now(), process_cpu_ns()),
        }
    }

    /// Ends the phase here (the time is written as the timer is dropped).
    #[inline]
    pub(crate) fn finish(self) {}
}

/// CPU time of this process so far, nanoseconds: its threads' run time (0 where unknown).
#[cfg(feature = "phase-times")]
fn process_cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return 0 };
    let run_ns = |task: std::fs::DirEntry| -> Option<u64> {
        std::fs::read_to_string(task.path().join("schedstat")).ok()?.split_whitespace().next()?.parse().ok()
    };
    tasks.filter_map(|task| task.ok().and_then(run_ns)).sum()
}

#[cfg(feature = "phase-times")]
impl Drop for PhaseTimer {
    fn drop(&mut self) {
        let (name, start, cpu_ns) = self.phase;
        let cpu_ms = process_cpu_ns().saturating_sub(cpu_ns) as f64 * 1e-6;
        eprintln!("phase {name} {:.3} {cpu_ms:.3}", start.elapsed().as_secs_f64() * 1e3);
    }
}

/// Rows handed to one rayon task at a time.
const ROWS_PER_TASK: usize = 32;

/// Blocks scanned in parallel before their runs are moved into the result.
const BLOCKS_PER_BATCH: usize = 1024;

/// Poses per leaf of the far-field ball hierarchy.
pub(crate) const LEAF_SIZE: usize = 16;

impl SublevelSet {
    /// Computes S_γ by arc-length skipping within the stretches of the path that a
    /// hierarchy of bounding balls cannot rule out, rows in parallel on the current rayon pool.
    ///
    /// With s_k the cumulative path length under δ, the triangle inequality gives
    /// `|δ(x_i, x_k) − δ(x_i, x_j)| ≤ s_k − s_j` for k ≥ j. Scanning row i, a column j with
    /// `d = δ(x_i, x_j) > γ` lets the scan jump to the first k with `s_k − s_j ≥ d − γ`; a column
    /// with `d ≤ γ` puts every k with `s_k − s_j ≤ γ − d` inside without measuring it. The cost of
    /// a row is about the number of times the path passes the γ-ball around `x_i` plus the number
    /// of far-field jumps, times a logarithm; not the number of pairs. The path length is summed
    /// rounding up, and both bounds keep a margin for rounding, so the result equals the brute
    /// force's `δ ≤ γ` test on every pair.
    ///
    /// Far-field pruning: the path is cut into stretches of 16 consecutive poses, each in a ball
    /// around its middle pose, and the balls into a binary hierarchy. A row visits only the
    /// stretches whose ball comes within γ of `x_i`, so the cost of a row no longer grows with
    /// the length of path far away.
    ///
    /// A robot that stops (consecutive poses at one point, bit for bit) costs its runs: the
    /// hierarchy's nodes of one point are decided with one distance and ranked once for a
    /// closest column, and a row whose pose is the previous row's repeats that row's runs. Two
    /// stops at nearly one place would otherwise cost n²: the arc-length bounds jump over no
    /// pose of a stop, whose path length is 0.
    ///
    /// Each run also records its closest column (the argmin of δ over the run, the earliest on
    /// ties), measured over the cells of the run that the distances the scan measured at its
    /// ends do not put farther than its least.
    ///
    /// Euclidean coordinates of 2 or 3 axes are not stepped through: a stretch whose ball neither
    /// lies within γ of `x_i` nor stays beyond it is measured whole, the squared distances of
    /// its 16 poses in one vectorised pass (a block's stretches laid out by axis once for its
    /// rows) against the largest double whose square root is at most γ, which decides each cell
    /// as `δ ≤ γ` does; a run measured whole takes its closest column from those distances. The
    /// stretches near a row's γ-sphere cost a pass each instead of a chain of dependent
    /// distances and gallops. The runs and closest columns are the same, bit for bit.
    ///
    /// # Errors
    /// [`Error::InvalidGamma`](crate::Error::InvalidGamma) when γ is not positive and finite; the metric's dimension error.
    pub fn compute<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, gamma: f64) -> Result<Self> {
        Self::compute_separated(traj, metric, gamma, Separation::NONE)
    }

    /// The part X of S_γ whose pairs are also `separation` apart, by the same scan:
    /// row i starts at its first separated column instead of at i, so runs are clipped where
    /// they are produced and no distance is measured that [`compute`](Self::compute) would not
    /// measure. With [`Separation::NONE`], exactly [`compute`](Self::compute).
    ///
    /// # Errors
    /// As [`compute`](Self::compute); [`Error::InvalidSeparation`]; [`Error::OutOfMemory`] when
    /// the runs do not fit in memory; [`Error::Interrupted`] when an [`Interrupt`] installed on
    /// this thread is interrupted (checked every row).
    pub fn compute_separated<M: Metric + ?Sized>(
        traj: &Trajectory,
        metric: &M,
        gamma: f64,
        separation: Separation,
    ) -> Result<Self> {
        check_gamma(gamma)?;
        separation.check()?;
        traj.check_metric(metric)?;
        let timer = PhaseTimer::start("prepare: arc length | ball tree (2 tasks)");
        let (arc, balls) = rayon::join(
            || ArcLength::new(traj, metric, !separation.is_none()),
            || BallTree::new(traj, metric, LEAF_SIZE),
        );
        let (mut arc, balls) = (arc?, balls?);
        let first_columns = separation.first_columns(&arc.plain, traj.timestamps_s())?;
        arc.plain = Vec::new();
        let pruner = Pruner::Hierarchy(&balls);
        timer.finish();
        Self::scan(traj, metric, gamma, separation, &arc, pruner, &first_columns, &[0], traj.len())
    }

    /// The scan of [`compute_separated`](Self::compute_separated), over the sessions starting at
    /// `starts` (`[0]` for one trajectory): row blocks never span two sessions, runs are cut
    /// where a session starts, and rows of different sessions are not 4-adjacent. Only the rows
    /// before `scan_rows` are scanned (a tile's rows); the others are left empty.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`] when the runs do not fit in memory; [`Error::Interrupted`] when
    /// the [`Interrupt`] installed on this thread is interrupted (checked every row).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn scan<M: Metric + ?Sized>(
        traj: &Trajectory,
        metric: &M,
        gamma: f64,
        separation: Separation,
        arc: &ArcLength,
        pruner: Pruner<'_>,
        first_columns: &[u32],
        starts: &[usize],
        scan_rows: usize,
    ) -> Result<Self> {
        let n = traj.len();
        let interrupt = Interrupt::current();
        let scanner = RowScanner { traj, metric, arc, pruner, gamma, first_columns, starts };
        // Euclidean coordinates of 2 or 3 axes are measured a stretch at a time.
        let dense = dense_limit(metric, traj.dim(), gamma);
        // Blocks of rows, cut where a session starts; rows from `scan_rows` on are left empty.
        let mut block_rows: Vec<std::ops::Range<usize>> =
            try_with_capacity(n.div_ceil(ROWS_PER_TASK) + starts.len(), "the row blocks of S_gamma")?;
        for (k, &start) in starts.iter().enumerate() {
            let end = starts.get(k + 1).copied().unwrap_or(n).min(scan_rows);
            block_rows.extend((start..end).step_by(ROWS_PER_TASK).map(|a| a..(a + ROWS_PER_TASK).min(end)));
        }
        // Each batch's blocks go into room taken fallibly first (a parallel collect would grow
        // its vector as usual); the first error in block order is the batch's.
        let scan_batch = |blocks: &[std::ops::Range<usize>]| -> Result<Vec<Result<Block>>> {
            let mut scanned = try_with_capacity(blocks.len(), "the row blocks of S_gamma")?;
            let scan_block = |scratch: &mut BlockScratch, rows: &std::ops::Range<usize>| -> Result<Block> {
                // Every block of the batch is started: once interrupted, they end here.
                interrupt.check()?;
                let BlockScratch { block, candidates, far_until, axes } = scratch;
                block.clear();
                candidates.clear();
                scanner.candidates_for(rows.clone(), candidates)?;
                far_until.clear();
                try_reserve(far_until, candidates.len(), "the stretches of a row scan")?;
                far_until.resize(candidates.len(), f64::NEG_INFINITY);
                if dense.is_some() {
                    axes.clear();
                    scanner.stretch_axes(candidates, axes)?;
                }
                for i in rows.clone() {
                    interrupt.check()?;
                    block.make_room()?;
                    if i > rows.start && traj.same_point(i - 1, i) {
                        scanner.repeat_row(i, block);
                    } else if let Some(limit) = dense {
                        scanner.scan_row_dense(i, candidates, axes, limit, far_until, block);
                    } else {
                        scanner.scan_row(i, candidates, far_until, block);
                    }
                    block.row_lengths.push(block.runs.len());
                }
                block.try_copy()
            };
            // Each worker scans into buffers it keeps from block to block, so that their growth
            // is paid once, and hands over a copy of each block in room of its exact size.
            blocks.par_iter().map_init(BlockScratch::default, scan_block).collect_into_vec(&mut scanned);
            Ok(scanned)
        };
        let breaks = try_collect(starts.iter().skip(1).map(|&s| s as u32), "the session starts of S_gamma")?;
        let row_offsets = try_with_capacity(n + 1, "the row offsets of S_gamma")?;
        let mut set = Self { gamma, separation, row_offsets, runs: Vec::new(), closest: Vec::new(), breaks };
        set.row_offsets.push(0);
        // Blocks are scanned in parallel a batch at a time, and each batch is moved into the
        // result while the next one is scanned (the copy, and the page faults of a result that
        // grows to hundreds of MB, would otherwise leave every other thread idle), so the
        // per-block buffers never hold more than two batches of runs.
        let mut scanned = Vec::new();
        let timer = PhaseTimer::start("scan: batches of blocks, parallel");
        for batch in block_rows.chunks(BLOCKS_PER_BATCH) {
            let previous = std::mem::take(&mut scanned);
            // The copy first: on one thread the order of work and allocation is that of a
            // plain loop; on more, the others start on the scan meanwhile.
            let (appended, batch) = rayon::join(|| set.append(previous), || scan_batch(batch));
            appended?;
            scanned = batch?;
        }
        timer.finish();
        let timer = PhaseTimer::start("scan: last batch's append, serial");
        set.append(scanned)?;
        let last = set.runs.len();
        set.row_offsets.resize(n + 1, last);
        set.runs.shrink_to_fit();
        set.closest.shrink_to_fit();
        timer.finish();
        Ok(set)
    }

    /// The set of one trajectory (no sessions) from its rows: `row_offsets` (rows + 1 of them,
    /// from 0), the runs and their closest columns, as [`compute`](Self::compute) leaves them.
    pub(crate) fn from_rows(gamma: f64, row_offsets: Vec<usize>, runs: Vec<Run>, closest: Vec<u32>) -> Self {
        debug_assert!(row_offsets.last() == Some(&runs.len()) && closest.len() == runs.len());
        Self { gamma, separation: Separation::NONE, row_offsets, runs, closest, breaks: Vec::new() }
    }

    /// Appends the rows of scanned blocks, in order, growing the result fallibly; the first
    /// block that failed ends it with its error. The room is taken and the runs are copied in
    /// parallel, each block into its own part (the page faults of fresh pages dominate the
    /// copy), so the last batch, which nothing else overlaps, is no serial phase.
    fn append(&mut self, blocks: Vec<Result<Block>>) -> Result<()> {
        let blocks: Vec<Block> = blocks.into_iter().collect::<Result<_>>()?;
        let added: usize = blocks.iter().map(|block| block.runs.len()).sum();
        let rows: usize = blocks.iter().map(|block| block.row_lengths.len()).sum();
        try_reserve(&mut self.runs, added, "the runs of S_gamma")?;
        try_reserve(&mut self.closest, added, "the closest columns of S_gamma")?;
        try_reserve(&mut self.row_offsets, rows, "the row offsets of S_gamma")?;
        let base = self.runs.len();
        let mut offset = base;
        for block in &blocks {
            self.row_offsets.extend(block.row_lengths.iter().map(|len| offset + len));
            offset += block.runs.len();
        }
        self.runs.par_extend(rayon::iter::repeat_n(Run { start: 0, end: 0 }, added));
        self.closest.par_extend(rayon::iter::repeat_n(0, added));
        let (mut runs, mut closest) = (&mut self.runs[base..], &mut self.closest[base..]);
        let mut parts = try_with_capacity(blocks.len(), "the row blocks of S_gamma")?;
        for block in &blocks {
            let (runs_part, runs_rest) = std::mem::take(&mut runs).split_at_mut(block.runs.len());
            let (closest_part, closest_rest) = std::mem::take(&mut closest).split_at_mut(block.runs.len());
            parts.push((runs_part, closest_part, block));
            (runs, closest) = (runs_rest, closest_rest);
        }
        parts.into_par_iter().for_each(|(runs, closest, block)| {
            runs.copy_from_slice(&block.runs);
            closest.copy_from_slice(&block.closest);
        });
        Ok(())
    }

    /// Builds the set by measuring every pair: O(n²) time, for tests and tiny inputs.
    ///
    /// # Errors
    /// As [`SublevelSet::compute`].
    pub fn brute_force<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, gamma: f64) -> Result<Self> {
        Self::brute_force_separated(traj, metric, gamma, Separation::NONE)
    }

    /// Builds the separated set by measuring every pair, and testing each pair's separation on
    /// its own against [`path_length`]: O(n²) time, for tests.
    ///
    /// # Errors
    /// As [`SublevelSet::compute_separated`].
    pub fn brute_force_separated<M: Metric + ?Sized>(
        traj: &Trajectory,
        metric: &M,
        gamma: f64,
        separation: Separation,
    ) -> Result<Self> {
        check_gamma(gamma)?;
        separation.check()?;
        traj.check_metric(metric)?;
        let n = traj.len();
        let (s, t) = (try_path_length(traj, metric)?, traj.timestamps_s());
        let separated = |i: usize, j: usize| {
            separation.is_none() || (j > i && s[j] - s[i] >= separation.path && t[j] - t[i] >= separation.time_s)
        };
        let mut set =
            Self { gamma, separation, row_offsets: vec![0], runs: Vec::new(), closest: Vec::new(), breaks: Vec::new() };
        for i in 0..n {
            let mut open: Option<(usize, usize)> = None;
            for j in i..=n {
                let inside = j < n && separated(i, j) && metric.distance(traj.point(i), traj.point(j)) <= gamma;
                match (inside, open) {
                    (true, None) => open = Some((j, j)),
                    (true, Some((a, _))) => open = Some((a, j)),
                    (false, Some((a, b))) => {
                        let run = Run { start: a as u32, end: b as u32 };
                        let closest = (a..=b)
                            .min_by(|&x, &y| {
                                let dx = metric.distance_rank(traj.point(i), traj.point(x));
                                let dy = metric.distance_rank(traj.point(i), traj.point(y));
                                dx.total_cmp(&dy)
                            })
                            .unwrap_or(a);
                        set.runs.push(run);
                        set.closest.push(closest as u32);
                        open = None;
                    }
                    (false, None) => {}
                }
            }
            set.row_offsets.push(set.runs.len());
        }
        Ok(set)
    }

    /// The threshold γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The separation the pairs keep ([`Separation::NONE`]: all of S_γ).
    pub fn separation(&self) -> Separation {
        self.separation
    }

    /// Number of rows (poses).
    pub fn rows(&self) -> usize {
        self.row_offsets.len() - 1
    }

    /// The runs of row `i`, in increasing column order; without separation, the first starts at
    /// column `i` (unless the metric breaks δ(x, x) = 0).
    ///
    /// # Panics
    /// If `i >= rows()`.
    pub fn row(&self, i: usize) -> &[Run] {
        &self.runs[self.row_offsets[i]..self.row_offsets[i + 1]]
    }

    /// Index of the first run of row `i` in [`runs`](Self::runs).
    pub(crate) fn row_offset(&self, i: usize) -> usize {
        self.row_offsets[i]
    }

    /// Index of the first run of every row in [`runs`](Self::runs), and the number of runs.
    pub(crate) fn row_offsets(&self) -> &[usize] {
        &self.row_offsets
    }

    /// A fleet's session starts after the first (empty for one trajectory).
    pub(crate) fn breaks(&self) -> &[u32] {
        &self.breaks
    }

    /// Whether rows `i` and `i + 1` belong to different sessions of a fleet.
    #[inline]
    pub(crate) fn breaks_after(&self, i: usize) -> bool {
        !self.breaks.is_empty() && self.breaks.binary_search(&((i + 1) as u32)).is_ok()
    }

    /// All runs, row after row.
    pub fn runs(&self) -> &[Run] {
        &self.runs
    }

    /// The closest column of each run: the argmin over the run of the metric's
    /// [`distance_rank`](Metric::distance_rank) (δ² for the Euclidean metric, which orders pairs
    /// as δ does up to rounding), ties to the earliest column.
    pub fn closest_columns(&self) -> &[u32] {
        &self.closest
    }

    /// Number of lattice cells (i, j) with j ≥ i in the set.
    pub fn upper_pairs(&self) -> u64 {
        self.runs.iter().map(|r| r.len() as u64).sum()
    }

    /// Whether `(i, j)` (either order) is in S_γ: O(log runs in the row).
    pub fn contains(&self, i: usize, j: usize) -> bool {
        self.run_index(i, j).is_some()
    }

    /// Index in [`runs`](Self::runs) of the run holding `(min(i, j), max(i, j))`, if any.
    pub fn run_index(&self, i: usize, j: usize) -> Option<usize> {
        let (i, j) = (i.min(j), i.max(j));
        if j >= self.rows() {
            return None;
        }
        let row = self.row(i);
        let k = row.partition_point(|r| (r.end as usize) < j);
        (k < row.len() && row[k].start as usize <= j).then(|| self.row_offsets[i] + k)
    }
}

/// The runs of scanned rows, with their closest columns.
#[derive(Debug, Clone, Default)]
pub(crate) struct Block {
    pub(crate) runs: Vec<Run>,
    pub(crate) closest: Vec<u32>,
    row_lengths: Vec<usize>,
}

/// A worker's buffers for scanning blocks of rows: the block being scanned, its candidate
/// stretches and what its rows learnt about them (see [`RowScanner::scan_row`]).
#[derive(Debug, Default)]
struct BlockScratch {
    block: Block,
    candidates: Vec<Leaf>,
    far_until: Vec<f64>,
    /// The candidates' poses by axis, for the dense scan ([`RowScanner::scan_row_dense`]).
    axes: Vec<StretchAxes>,
}

impl Block {
    /// Empties it, keeping its room.
    fn clear(&mut self) {
        self.runs.clear();
        self.closest.clear();
        self.row_lengths.clear();
    }

    /// A copy of its runs, closest columns and rows, each in room of its exact size.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`].
    fn try_copy(&self) -> Result<Self> {
        Ok(Self {
            runs: try_copy(&self.runs, "the runs of S_gamma")?,
            closest: try_copy(&self.closest, "the closest columns of S_gamma")?,
            row_lengths: try_copy(&self.row_lengths, "the row offsets of S_gamma")?,
        })
    }

    /// The runs of the last row scanned: indices into `runs` and `closest`.
    fn last_row(&self) -> std::ops::Range<usize> {
        let end = self.row_lengths.last().copied().unwrap_or(0);
        let start = self.row_lengths.len().checked_sub(2).map_or(0, |k| self.row_lengths[k]);
        start..end
    }

    /// Before a row: room for as many runs again as the block holds (at least 64), allocated
    /// fallibly, so that the row's pushes do not have to grow the buffers.
    fn make_room(&mut self) -> Result<()> {
        let room = self.runs.len().max(64);
        try_reserve(&mut self.runs, room, "the runs of S_gamma")?;
        try_reserve(&mut self.closest, room, "the closest columns of S_gamma")?;
        try_reserve(&mut self.row_lengths, ROWS_PER_TASK, "the row offsets of S_gamma")
    }
}

/// Runs at least this long find their closest column through the ball hierarchy; shorter ones
/// by one vectorised pass over their cells.
const TREE_CLOSEST_LEN: usize = 256;

/// A candidate stretch's poses by axis (x, y, z; z is 0 in two dimensions), NaN past its end:
/// one stretch of at most [`LEAF_SIZE`] poses measured from a row's pose in one vectorised pass.
pub(crate) type StretchAxes = [[f64; LEAF_SIZE]; 3];

/// The limit of the dense scan ([`squared_limit`]\(γ\)) where `metric` measures coordinates of
/// `dim` axes by their Euclidean distance and `dim` is 2 or 3; `None` where rows scan step by
/// step. The one rule of the batch's and the online engine's scans.
pub(crate) fn dense_limit<M: Metric + ?Sized>(metric: &M, dim: usize, gamma: f64) -> Option<f64> {
    (metric.is_coordinate_euclidean() && (2..=3).contains(&dim)).then(|| squared_limit(gamma))
}

/// The largest double whose square root is at most γ: `s ≤ limit` exactly when `√s ≤ γ`, for
/// every s ≥ 0 (the square root is correctly rounded and monotone; NaN is neither), so a sum
/// of squares decides a cell as the metric's δ would, bit for bit.
fn squared_limit(gamma: f64) -> f64 {
    let mut limit = gamma * gamma;
    while limit > 0.0 && limit.sqrt() > gamma {
        limit = limit.next_down();
    }
    while limit.next_up().sqrt() <= gamma {
        limit = limit.next_up();
    }
    limit
}

/// A run of a row of the dense scan: columns `start..=end`, with the least squared distance
/// measured in it and its first column; `measured` when every column of it was measured.
#[derive(Clone, Copy)]
struct DenseRun {
    start: usize,
    end: usize,
    rank: f64,
    column: usize,
    measured: bool,
    /// The squared distance at the first column, when measured.
    entry: Option<f64>,
}

/// What a stretch's centre decides for a row ([`RowScanner::centre_decides`]).
enum Centre {
    /// Every pose of the stretch is farther than γ.
    Beyond,
    /// Every pose of the stretch is the centre's point, within γ.
    Within,
    /// Neither is known from the centre.
    Near,
}

/// The index of the next candidate stretch a row scan visits, from `*next` on (which moves past
/// it), with the scan at column `j` and the row at path length `s_i`: stretches that end by `j`
/// are passed in O(log) after a long run or jump, and so are those that the block's earlier rows
/// found out of reach for this row (`far_until`, empty when not kept).
#[inline(always)]
fn next_stretch(candidates: &[Leaf], far_until: &[f64], next: &mut usize, j: usize, s_i: f64) -> Option<usize> {
    while *next < candidates.len() {
        if candidates[*next].hi as usize <= j {
            *next += candidates[*next..].partition_point(|leaf| leaf.hi as usize <= j);
            continue;
        }
        let c = *next;
        *next += 1;
        if far_until.get(c).is_none_or(|&until| s_i >= until) {
            return Some(c);
        }
    }
    None
}

/// A run of a row being scanned: columns `start..=end`, with what the scan measured of it.
#[derive(Clone, Copy)]
struct OpenRun {
    start: usize,
    end: usize,
    /// δ at the first column, when the scan measured it there.
    entry: Option<f64>,
    /// The column of least δ that the scan measured inside the run, and its δ.
    least: Option<(usize, f64)>,
}

impl DenseRun {
    /// This run followed by `next`, which starts at the column after its end: the earlier of
    /// two equal least distances is kept.
    fn joined(self, next: Self) -> Self {
        let (rank, column) = if next.rank < self.rank { (next.rank, next.column) } else { (self.rank, self.column) };
        Self { end: next.end, rank, column, measured: self.measured && next.measured, entry: self.entry, ..self }
    }
}

impl OpenRun {
    /// A run that the scan entered without measuring (a stretch within γ as a whole).
    fn unmeasured(start: usize, end: usize) -> Self {
        Self { start, end, entry: None, least: None }
    }

    /// A run entered at column `start`, measured at `distance`, and reaching to `end`.
    fn entered(start: usize, distance: f64, end: usize) -> Self {
        Self { start, end, entry: Some(distance), least: Some((start, distance)) }
    }

    /// The run grown to `end` from column `column`, measured at `distance`.
    fn measured(self, column: usize, distance: f64, end: usize) -> Self {
        let least = match self.least {
            Some((_, least)) if least <= distance => self.least,
            _ => Some((column, distance)),
        };
        Self { end, least, ..self }
    }
}

/// The cumulative path length s_k = Σ_{m<k} δ(x_m, x_{m+1}) of every pose under `metric`, in the
/// metric's unit, summed in order (as `numpy.cumsum` of the steps sums them): the path length a
/// [`Separation`] bounds. O(n).
///
/// # Panics
/// When the path lengths do not fit in memory ([`MetricSpec::path_length`] returns the error
/// instead).
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, Trajectory, path_length};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [3.0, 4.0], [3.0, 4.0]])?;
/// assert_eq!(path_length(&traj, &Euclidean), vec![0.0, 5.0, 5.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
///
/// [`MetricSpec::path_length`]: crate::MetricSpec::path_length
pub fn path_length<M: Metric + ?Sized>(traj: &Trajectory, metric: &M) -> Vec<f64> {
    try_path_length(traj, metric).unwrap_or_else(|error| panic!("{error}"))
}

/// [`path_length`], allocated fallibly.
///
/// # Errors
/// [`Error::OutOfMemory`].
pub(crate) fn try_path_length<M: Metric + ?Sized>(traj: &Trajectory, metric: &M) -> Result<Vec<f64>> {
    Ok(ArcLength::new(traj, metric, true)?.plain)
}

/// Cumulative path length under δ, summed rounding up, with the rounding margin for bounds.
#[derive(Debug, Clone, Default)]
pub(crate) struct ArcLength {
    s: Vec<f64>,
    pub(crate) margin: f64,
    /// The plain sums ([`path_length`]) when asked for, from the same steps; else empty.
    pub(crate) plain: Vec<f64>,
    largest_step: f64,
}

impl ArcLength {
    /// The sums of `traj` under `metric`, and the plain ones `with_plain`.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`].
    pub(crate) fn new<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, with_plain: bool) -> Result<Self> {
        let n = traj.len();
        // The steps first, measured in parallel, then summed in order on one thread.
        let mut s = try_with_capacity(n, "the path lengths")?;
        s.par_extend(
            (0..n)
                .into_par_iter()
                .map(|k| if k == 0 { 0.0 } else { metric.distance(traj.point(k - 1), traj.point(k)) }),
        );
        let mut plain = try_with_capacity(if with_plain { n } else { 0 }, "the path lengths")?;
        let mut total = 0.0_f64;
        let mut plain_total = 0.0_f64;
        if with_plain {
            plain.push(0.0);
        }
        let mut largest_step = 0.0_f64;
        let scale = metric.rounding_scale(traj);
        for sum in s.iter_mut().skip(1) {
            let step = *sum;
            largest_step = largest_step.max(step);
            // Rounding up keeps s_k − s_j ≥ Σ δ over the stretch, so bounds never over-reach.
            total = (total + step).next_up();
            *sum = total;
            if with_plain {
                plain_total += step;
                plain.push(plain_total);
            }
        }
        let margin = rounding_margin(total, largest_step, scale);
        Ok(Self { s, margin, plain, largest_step })
    }

    /// Appends a pose `step` = δ(x_{k−1}, x_k) after the last (the step of the first pose is
    /// ignored), with the plain sums, as [`new`](Self::new) sums them; `scale` is the metric's
    /// rounding scale of the poses so far. For the online engine.
    pub(crate) fn push(&mut self, step: f64, scale: f64) {
        match (self.s.last(), self.plain.last()) {
            (Some(&total), Some(&plain_total)) => {
                self.largest_step = self.largest_step.max(step);
                self.s.push((total + step).next_up());
                self.plain.push(plain_total + step);
            }
            _ => {
                self.s.push(0.0);
                self.plain.push(0.0);
            }
        }
        self.margin = rounding_margin(self.s[self.s.len() - 1], self.largest_step, scale);
    }

    /// Largest k ≥ j with s_k ≤ s_j + budget (k = j when the budget is below zero).
    #[inline]
    fn last_within(&self, j: usize, budget: f64) -> usize {
        let limit = self.s[j] + budget;
        let s = &self.s;
        let n = s.len();
        // `!(x >= 0)` also catches NaN (an infinite path length): then nothing is skipped.
        if !(budget >= 0.0 && limit.is_finite()) || j + 1 >= n || s[j + 1] > limit {
            return j;
        }
        // Gallop: s[j + lo] ≤ limit is known.
        let (mut lo, mut hi) = (1, 2);
        while j + hi < n && s[j + hi] <= limit {
            lo = hi;
            hi *= 2;
        }
        let hi = hi.min(n - j);
        // Invariant: s[j + lo] ≤ limit, and s[j + hi] > limit or j + hi == n.
        j + lo + s[j + lo + 1..j + hi].partition_point(|&x| x <= limit)
    }

    /// Smallest k > j with s_k ≥ s_j + distance, or n when there is none.
    #[inline]
    fn first_beyond(&self, j: usize, distance: f64) -> usize {
        let target = self.s[j] + distance;
        let s = &self.s;
        let n = s.len();
        // NaN (an infinite path length) jumps no further than the next column.
        if !(target.is_finite()) || j + 1 >= n || s[j + 1] >= target {
            return j + 1;
        }
        let (mut lo, mut hi) = (1, 2);
        while j + hi < n && s[j + hi] < target {
            lo = hi;
            hi *= 2;
        }
        let hi = hi.min(n - j);
        j + lo + 1 + s[j + lo + 1..j + hi].partition_point(|&x| x < target)
    }
}

/// Rounding of δ (relative to the metric's scale: coordinates, or the radius an angle is
/// multiplied by) and of differences of s: 64 ulps of the largest magnitude in play.
fn rounding_margin(total: f64, largest_step: f64, scale: f64) -> f64 {
    64.0 * f64::EPSILON * (total + largest_step + scale + 1.0)
}

/// The reaches `(reach, inside_reach)` of a walk of the hierarchy centred on a pose within
/// `radius` of every row it serves, with `margin` the rounding margin of those rows: a pose
/// farther than `reach` from the centre is farther than γ from every row, and one within
/// `inside_reach` is within γ of every row, with room for the rounding of the three distances of
/// the triangle inequality. The one rule for the batch's blocks and the online engine's carried
/// stretches.
pub(crate) fn walk_reach(gamma: f64, radius: f64, margin: f64) -> (f64, f64) {
    (gamma + radius + 2.0 * margin, gamma - radius - 3.0 * margin)
}

/// Where a row scan finds the stretches of the path that may come within γ.
#[derive(Clone, Copy)]
pub(crate) enum Pruner<'a> {
    /// A walk of the ball hierarchy (every metric).
    Hierarchy(&'a BallTree),
    /// The chunks of the hierarchy near the row, by KD-tree (Euclidean coordinates).
    Chunks(&'a BallTree, &'a ChunkIndex),
}

/// Scans rows of S_γ: the batch's rows i (columns j ≥ i), or the online engine's rows n
/// (columns j ≤ n, under the metric with its arguments swapped so that δ is measured as the
/// batch measures it).
pub(crate) struct RowScanner<'a, M: ?Sized> {
    pub(crate) traj: &'a Trajectory,
    pub(crate) metric: &'a M,
    pub(crate) arc: &'a ArcLength,
    pub(crate) pruner: Pruner<'a>,
    pub(crate) gamma: f64,
    /// The first column each row keeps ([`Separation::first_columns`]); rows past its end (the
    /// online engine's) start at column 0.
    pub(crate) first_columns: &'a [u32],
    /// The first pose of each session (`[0]` for one trajectory): runs are cut there.
    pub(crate) starts: &'a [usize],
}

impl<M: Metric + ?Sized> RowScanner<'_, M> {
    /// The first column row `i` keeps.
    fn first_column(&self, i: usize) -> usize {
        self.first_columns.get(i).map_or(0, |&c| c as usize)
    }

    /// The stretches of the path that may hold a pose within γ of any row in `rows`: one walk of
    /// the hierarchy per block with the block's own bounding ball, instead of one per row.
    /// Stretches that lie within γ of every row of the block come whole, marked `inside`.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`] when the stretches do not fit in memory.
    pub(crate) fn candidates_for(&self, rows: std::ops::Range<usize>, out: &mut Vec<Leaf>) -> Result<()> {
        let centre = self.traj.point(rows.start + (rows.end - rows.start) / 2);
        let radius = rows.clone().map(|i| self.metric.distance(centre, self.traj.point(i))).fold(0.0, f64::max);
        let reach = walk_reach(self.gamma, radius, self.arc.margin);
        // The first columns grow with the row, so the block's first row has the smallest.
        let from = self.first_column(rows.start);
        match self.pruner {
            Pruner::Hierarchy(balls) => balls.near_spans(self.metric, centre, from, reach, out),
            Pruner::Chunks(balls, index) => index.near_spans(balls, self.metric, centre, from, reach, out),
        }
    }

    /// Scans row `i` over the stretches `candidates` (from [`candidates_for`](Self::candidates_for))
    /// into `out`: its runs and their closest columns.
    ///
    /// `far_until` (one entry per candidate, or empty) carries what earlier rows of the block
    /// learnt about each stretch: a stretch whose ball lies farther than its reach from x_i by
    /// a slack stays out of reach for every later row i′ with s_i′ − s_i below that slack (the
    /// triangle inequality through x_i and the path between them), so those rows skip it
    /// without measuring. The entry is the path length s up to which that holds.
    pub(crate) fn scan_row(&self, i: usize, candidates: &[Leaf], far_until: &mut [f64], out: &mut Block) {
        // The points as arrays of their dimension, read once a row: a distance then builds and
        // checks no slices (the metric's fixed-size δ, bit for bit its `distance`).
        let coords = self.traj.coords();
        match self.traj.dim() {
            2 => {
                let points = coords.as_chunks::<2>().0;
                let x_i = points[i];
                self.scan_row_by(i, |j| self.metric.distance_2d(&x_i, &points[j]), candidates, far_until, out);
            }
            3 => {
                let points = coords.as_chunks::<3>().0;
                let x_i = points[i];
                self.scan_row_by(i, |j| self.metric.distance_3d(&x_i, &points[j]), candidates, far_until, out);
            }
            _ => {
                let x_i = self.traj.point(i);
                let distance_to = |j| self.metric.distance(x_i, self.traj.point(j));
                self.scan_row_by(i, distance_to, candidates, far_until, out);
            }
        }
    }

    /// What δ = `d` from row `i`'s pose (at path length `s_i`) to the centre of `leaf`, a stretch
    /// the block's walk did not put inside, decides for the row; where it puts the stretch
    /// beyond γ, `far` (the stretch's entry of `far_until`) learns for how much more path that
    /// holds. The one rule of both scans.
    #[inline(always)]
    fn centre_decides(&self, leaf: &Leaf, d: f64, s_i: f64, far: Option<&mut f64>) -> Centre {
        let margin = self.arc.margin;
        let reach = self.gamma + margin;
        if leaf.uniform {
            // Every pose of the stretch is the centre's point, bit for bit: δ from x_i to each
            // of them is d, so d decides them all, exactly.
            if d > self.gamma {
                if let Some(until) = far {
                    *until = s_i + (d - self.gamma - 2.0 * margin);
                }
                return Centre::Beyond;
            }
            return Centre::Within;
        }
        if d - leaf.radius > reach {
            // Poses of a stretch whose ball stays farther than γ from x_i are all outside, and
            // stay so for the next rows while their path from x_i is shorter than the slack (one
            // margin more for the rounding of the slack and of s).
            if let Some(until) = far {
                *until = s_i + (d - leaf.radius - reach - margin);
            }
            return Centre::Beyond;
        }
        Centre::Near
    }

    /// [`scan_row`](Self::scan_row) with `distance_to(j)` = δ(x_i, x_j).
    #[inline(always)]
    fn scan_row_by(
        &self,
        i: usize,
        distance_to: impl Fn(usize) -> f64,
        candidates: &[Leaf],
        far_until: &mut [f64],
        out: &mut Block,
    ) {
        let margin = self.arc.margin;
        let s_i = if far_until.is_empty() { 0.0 } else { self.arc.s[i] };
        let mut open: Option<OpenRun> = None;
        // Next column to examine; columns before it are decided (or not separated from i).
        let first = self.first_column(i);
        let mut j = first;
        let mut next = 0;
        while let Some(c) = next_stretch(candidates, far_until, &mut next, j, s_i) {
            let leaf = candidates[c];
            let (lo, hi) = ((leaf.lo as usize).max(first), leaf.hi as usize);
            // Every pose of the stretch is within γ of x_i, known without measuring them.
            let mut whole = leaf.inside;
            if !leaf.inside {
                match self.centre_decides(&leaf, distance_to(leaf.centre as usize), s_i, far_until.get_mut(c)) {
                    Centre::Beyond => continue,
                    Centre::Within => whole = true,
                    Centre::Near => {}
                }
            }
            if j < lo {
                // Columns j..lo lie in pruned stretches: all outside, so a run open at j − 1 ends.
                if let Some(run) = open.take() {
                    self.close_run(i, run, None, out);
                }
                j = lo;
            }
            if whole {
                // Every pose of the stretch is within γ of x_i: one run.
                open = match open {
                    Some(run) if run.end + 1 == j => Some(OpenRun { end: hi - 1, ..run }),
                    other => {
                        if let Some(run) = other {
                            self.close_run(i, run, None, out);
                        }
                        Some(OpenRun::unmeasured(j, hi - 1))
                    }
                };
                j = hi;
                continue;
            }
            while j < hi {
                let d = distance_to(j);
                if d <= self.gamma {
                    // Every k up to here has δ(x_i, x_k) ≤ d + (s_k − s_j) ≤ γ − margin.
                    let k = self.arc.last_within(j, self.gamma - d - margin);
                    open = match open {
                        Some(run) if run.end + 1 == j => Some(run.measured(j, d, k)),
                        other => {
                            if let Some(run) = other {
                                self.close_run(i, run, None, out);
                            }
                            Some(OpenRun::entered(j, d, k))
                        }
                    };
                    j = k + 1;
                } else {
                    if let Some(run) = open.take() {
                        self.close_run(i, run, Some((j, d)), out);
                    }
                    // Every k before the jump has δ(x_i, x_k) ≥ d − (s_k − s_j) > γ + margin.
                    j = self.arc.first_beyond(j, d - self.gamma - margin);
                }
            }
        }
        if let Some(run) = open {
            self.close_run(i, run, None, out);
        }
    }

    /// The candidates' poses by axis, for [`scan_row_dense`](Self::scan_row_dense), appended to
    /// `axes` (one entry a candidate): stretches that the dense scan measures (neither inside
    /// nor of one point) get their poses, the others NaN.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`] when they do not fit in memory.
    pub(crate) fn stretch_axes(&self, candidates: &[Leaf], axes: &mut Vec<StretchAxes>) -> Result<()> {
        try_reserve(axes, candidates.len(), "the stretches of a row scan")?;
        let (coords, dim) = (self.traj.coords(), self.traj.dim());
        axes.extend(candidates.iter().map(|leaf| {
            let mut by_axis = [[f64::NAN; LEAF_SIZE]; 3];
            let (lo, hi) = (leaf.lo as usize, leaf.hi as usize);
            if !leaf.inside && !leaf.uniform && hi - lo <= LEAF_SIZE {
                for (k, point) in coords[lo * dim..hi * dim].chunks_exact(dim).enumerate() {
                    by_axis[0][k] = point[0];
                    by_axis[1][k] = point[1];
                    by_axis[2][k] = if dim == 3 { point[2] } else { 0.0 };
                }
            }
            by_axis
        }));
        Ok(())
    }

    /// [`scan_row`](Self::scan_row) for Euclidean coordinates of 2 or 3 axes: a stretch that
    /// its ball does not decide is measured whole (its squared distances in one pass, against
    /// `limit` = [`squared_limit`]\(γ\)), and a run measured whole takes its closest column
    /// from those distances. The same runs and closest columns as `scan_row`.
    pub(crate) fn scan_row_dense(
        &self,
        i: usize,
        candidates: &[Leaf],
        axes: &[StretchAxes],
        limit: f64,
        far_until: &mut [f64],
        out: &mut Block,
    ) {
        let dim = self.traj.dim();
        let p = self.traj.point(i);
        let x_i = [p[0], p[1], if dim == 3 { p[2] } else { 0.0 }];
        let squared = |j: usize| {
            let q = self.traj.point(j);
            squared_l2_3d(&x_i, &[q[0], q[1], if dim == 3 { q[2] } else { 0.0 }])
        };
        let margin = self.arc.margin;
        let s_i = if far_until.is_empty() { 0.0 } else { self.arc.s[i] };
        let mut open: Option<DenseRun> = None;
        let first = self.first_column(i);
        let mut j = first;
        let mut next = 0;
        while let Some(c) = next_stretch(candidates, far_until, &mut next, j, s_i) {
            let leaf = candidates[c];
            let (lo, hi) = ((leaf.lo as usize).max(first), leaf.hi as usize);
            // A stretch known within γ as a whole, with one measured pose of it (the centre): the
            // rank of each of its poses when they are all one point, else a bound for the closest.
            let rank = squared(leaf.centre as usize);
            let mut whole = leaf.inside.then_some(false);
            if !leaf.inside {
                let d = rank.sqrt();
                match self.centre_decides(&leaf, d, s_i, far_until.get_mut(c)) {
                    Centre::Beyond => continue,
                    Centre::Within => whole = Some(true),
                    // Its ball lies within γ of x_i: every pose is inside.
                    Centre::Near if d <= self.gamma - leaf.radius - 3.0 * margin => whole = Some(false),
                    Centre::Near => {}
                }
            }
            if j < lo {
                if let Some(run) = open.take() {
                    self.close_dense(i, run, None, out);
                }
                j = lo;
            }
            if let Some(uniform) = whole {
                // One point: every pose ranks as the centre, the first of them the earliest.
                let column = if uniform { j } else { (leaf.centre as usize).max(j) };
                let rank = if uniform || column == leaf.centre as usize { rank } else { squared(column) };
                let part =
                    DenseRun { start: j, end: hi - 1, rank, column, measured: uniform, entry: uniform.then_some(rank) };
                open = Some(self.joined_dense(i, open, part, out));
                j = hi;
                continue;
            }
            // Every pose of the stretch at once: its squared distances and which are within γ.
            let by_axis = &axes[c];
            let mut ranks = [0.0; LEAF_SIZE];
            for (rank, &x) in ranks.iter_mut().zip(&by_axis[0]) {
                *rank = (x_i[0] - x) * (x_i[0] - x);
            }
            for (rank, &y) in ranks.iter_mut().zip(&by_axis[1]) {
                *rank += (x_i[1] - y) * (x_i[1] - y);
            }
            for (rank, &z) in ranks.iter_mut().zip(&by_axis[2]) {
                *rank += (x_i[2] - z) * (x_i[2] - z);
            }
            let mut within = 0_u32;
            for (k, &rank) in ranks.iter().enumerate() {
                within |= u32::from(rank <= limit) << k;
            }
            let base = leaf.lo as usize;
            while j < hi {
                let bits = within >> (j - base);
                if bits & 1 == 1 {
                    let end = (j + (!bits).trailing_zeros() as usize).min(hi);
                    let rank = ranks[j - base];
                    let mut part =
                        DenseRun { start: j, end: end - 1, rank, column: j, measured: true, entry: Some(rank) };
                    for k in j + 1..end {
                        if ranks[k - base] < part.rank {
                            (part.rank, part.column) = (ranks[k - base], k);
                        }
                    }
                    open = Some(self.joined_dense(i, open, part, out));
                    j = end;
                } else {
                    if let Some(run) = open.take() {
                        self.close_dense(i, run, Some((j, ranks[j - base])), out);
                    }
                    j = if bits == 0 { hi } else { j + bits.trailing_zeros() as usize };
                }
            }
        }
        if let Some(run) = open {
            self.close_dense(i, run, None, out);
        }
    }

    /// The open run grown by `part` when `part` starts at the column after its end, else `part`
    /// alone, the open run (if any) recorded first.
    fn joined_dense(&self, i: usize, open: Option<DenseRun>, part: DenseRun, out: &mut Block) -> DenseRun {
        match open {
            Some(run) if run.end + 1 == part.start => run.joined(part),
            other => {
                if let Some(run) = other {
                    self.close_dense(i, run, None, out);
                }
                part
            }
        }
    }

    /// Records a run of the dense scan with its closest column: the least measured when every
    /// column was measured, else ranked again as [`closest_of`](Self::closest_of) ranks it.
    fn close_dense(&self, i: usize, run: DenseRun, exit: Option<(usize, f64)>, out: &mut Block) {
        let (a, b) = (run.start, run.end);
        let exit = exit.map(|(column, rank)| (column, rank.sqrt()));
        let open = OpenRun {
            start: a,
            end: b,
            entry: run.entry.map(f64::sqrt),
            least: run.rank.is_finite().then(|| (run.column, run.rank.sqrt())),
        };
        let k = self.starts.partition_point(|&s| s <= a);
        if k < self.starts.len() && self.starts[k] <= b {
            return self.close_run(i, open, exit, out);
        }
        let column = if a == i {
            i
        } else if run.measured {
            run.column
        } else {
            self.closest_of_scanned(i, open, exit)
        };
        out.runs.push(Run { start: a as u32, end: b as u32 });
        out.closest.push(column as u32);
    }

    /// Row `i` of a robot that stands still, from row `i − 1` (the last row of `out`) when the two
    /// poses are one point bit for bit: every distance from x_i is the one from x_{i−1}, so row
    /// i is row i − 1 from row i's first column on, cut where sessions start as before. A run
    /// kept whole keeps its closest column; a run cut at its start takes the diagonal cell when
    /// it starts there, else keeps its closest column when that is still in the run (the
    /// earliest argmin of a run is the earliest of any part of it that holds it), takes its new
    /// first column when that is the same point as the one cut off (a stop within the run),
    /// else is ranked again. No distance is measured for the rest: a stop of m poses costs its
    /// runs, not m scans.
    pub(crate) fn repeat_row(&self, i: usize, out: &mut Block) {
        let first = self.first_column(i);
        debug_assert!(self.first_column(i - 1) <= first, "first columns grow with the row");
        for k in out.last_row() {
            let (run, column) = (out.runs[k], out.closest[k] as usize);
            let (a, b) = (run.start as usize, run.end as usize);
            if b < first {
                continue;
            }
            let start = a.max(first);
            let column = if start == i {
                i
            } else if start == a || column >= start {
                column
            } else if self.traj.same_point(start, column) {
                // The cut-off closest pose's twin is the run's first: the earliest of the least.
                start
            } else {
                self.closest_of(i, start, b)
            };
            out.runs.push(Run { start: start as u32, end: run.end });
            out.closest.push(column as u32);
        }
    }

    /// Records the run `run` of row `i` with its closest column (row i's own cell when the run
    /// starts on the diagonal); `exit` is the column after it that ended it, with its δ, when the
    /// scan measured one.
    fn close_run(&self, i: usize, run: OpenRun, exit: Option<(usize, f64)>, out: &mut Block) {
        let OpenRun { start: a, end: b, .. } = run;
        // A run reaching into the next session is cut where that session starts.
        let mut k = self.starts.partition_point(|&s| s <= a);
        let column = if k < self.starts.len() && self.starts[k] <= b {
            let mut a = a;
            while k < self.starts.len() && self.starts[k] <= b {
                self.close_part(i, a, self.starts[k] - 1, &mut out.runs, &mut out.closest);
                a = self.starts[k];
                k += 1;
            }
            (a, self.closest_of(i, a, b))
        } else {
            (a, self.closest_of_scanned(i, run, exit))
        };
        out.runs.push(Run { start: column.0 as u32, end: b as u32 });
        out.closest.push(column.1 as u32);
    }

    /// Records the run `a..=b`, within one session's columns, with its closest column.
    fn close_part(&self, i: usize, a: usize, b: usize, runs: &mut Vec<Run>, closest: &mut Vec<u32>) {
        let column = self.closest_of(i, a, b);
        runs.push(Run { start: a as u32, end: b as u32 });
        closest.push(column as u32);
    }

    /// The closest column of a scanned run, as [`closest_of`](Self::closest_of) finds it, over the
    /// columns that the distances the scan measured leave open. With d* the least δ measured inside
    /// the run (by the scan, and once more where the bounds below meet), δ(x_i, x_k) ≥ d − |s_k −
    /// s_j| for a column j measured at d (the triangle inequality through the path between them)
    /// puts every column whose bound from the run's first column, or from the column after it that
    /// ended it, exceeds d* by more than the rounding margin strictly farther than the column of
    /// d*: neither the least rank nor the earliest of its ties is there. A pass by x_i at a few
    /// metres leaves the columns within a few metres of path of the closest one (on the 2.1 h urban
    /// drive, 22 of a run's 95 cells); a run the scan entered without measuring leaves the whole
    /// run. Where [`TREE_CLOSEST_LEN`] columns or more stay open (a slow pass: hundreds of cells in
    /// a few metres of path), the ball hierarchy searches them knowing d*, so that it skips every
    /// ball farther than that from the start instead of ranking the first leaves it reaches.
    fn closest_of_scanned(&self, i: usize, run: OpenRun, exit: Option<(usize, f64)>) -> usize {
        let (a, b) = (run.start, run.end);
        let Some((guess, least)) = run.least.filter(|_| a != i) else {
            return self.closest_of(i, a, b);
        };
        let s = &self.arc.s;
        // First one more distance, at the column where the bounds from both sides meet (the
        // least of their lower bound), found by interpolating the path length: the scan's least
        // is often a pass's approach, metres from its closest pose.
        let meet = match (run.entry, exit) {
            (Some(entry), Some((after, distance))) => 0.5 * (s[a] + s[after] + entry - distance),
            _ => 0.5 * (s[a] + s[b]),
        };
        // A fraction in 0..=1 (NaN, from a path too long to sum, casts to column a).
        let fraction = ((meet - s[a]) / (s[b] - s[a])).clamp(0.0, 1.0);
        let m = a + (fraction * (b - a) as f64) as usize;
        let d = self.metric.distance(self.traj.point(i), self.traj.point(m));
        let (guess, least) = if d < least { (m, d) } else { (guess, least) };
        // Column k is farther than `least` by the slack when its bound d − |s_k − s_j| from a
        // measured column j (at d) exceeds it: the two bounds are searched independently.
        let slack = 2.0 * self.arc.margin;
        let path = &s[a..=b];
        let lo = match run.entry {
            Some(entry) if entry - least - slack > 0.0 => {
                let limit = s[a] + (entry - least - slack);
                a + path.partition_point(|&x| x < limit)
            }
            _ => a,
        };
        let hi = match exit {
            Some((after, distance)) if distance - least - slack > 0.0 => {
                let limit = s[after] - (distance - least - slack);
                (a + path.partition_point(|&x| x <= limit)).saturating_sub(1)
            }
            _ => b,
        };
        let (lo, hi) = (lo.min(guess), hi.max(guess));
        if hi - lo + 1 >= TREE_CLOSEST_LEN {
            let balls = match self.pruner {
                Pruner::Hierarchy(balls) | Pruner::Chunks(balls, _) => balls,
            };
            let x_i = self.traj.point(i);
            return balls.closest_in_range_within(self.metric, self.traj, x_i, (lo, hi), slack, least);
        }
        self.closest_of(i, lo, hi)
    }

    /// The closest column of the run `a..=b` of row `i` (columns j ≥ i) of a set known whole,
    /// unscanned (the online engine's snapshot turns its rows into the batch's), as
    /// [`closest_of_scanned`](Self::closest_of_scanned) finds it from one distance at the run's
    /// first column: the columns just outside the run, a − 1 and b + 1, are farther than γ (a
    /// run ends where the set does), and bound the columns near them from below just as a
    /// measured exit would.
    pub(crate) fn closest_of_run(&self, i: usize, a: usize, b: usize) -> usize {
        if a == i || b - a + 1 >= TREE_CLOSEST_LEN {
            return self.closest_of(i, a, b);
        }
        let d = self.metric.distance(self.traj.point(i), self.traj.point(a));
        let run = OpenRun::entered(a, d, b);
        let exit = (b + 1 < self.traj.len()).then_some((b + 1, self.gamma));
        self.closest_of_scanned(i, run, exit)
    }

    /// The closest column of the run `a..=b` of row `i` ([`closest_column`]).
    fn closest_of(&self, i: usize, a: usize, b: usize) -> usize {
        let balls = match self.pruner {
            Pruner::Hierarchy(balls) | Pruner::Chunks(balls, _) => balls,
        };
        closest_column(self.metric, self.traj, balls, self.arc.margin, i, (a, b))
    }
}

/// The closest column of the run `a..=b` of row `i`: `i` itself when the run starts on the
/// diagonal, else the argmin of the metric's rank from pose `i` over the run (the earliest on
/// ties), by the ball hierarchy for long runs and one pass over the cells for short ones.
pub(crate) fn closest_column<M: Metric + ?Sized>(
    metric: &M,
    traj: &Trajectory,
    balls: &BallTree,
    margin: f64,
    i: usize,
    (a, b): (usize, usize),
) -> usize {
    if a == i {
        i
    } else if b - a + 1 >= TREE_CLOSEST_LEN {
        balls.closest_in_range(metric, traj, traj.point(i), (a, b), 2.0 * margin)
    } else {
        let dim = traj.dim();
        a + metric.closest_in(traj.point(i), &traj.coords()[a * dim..(b + 1) * dim])
    }
}

/// What a serialised [`SublevelSet`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct SublevelSetState {
    gamma: f64,
    separation: Separation,
    #[serde(with = "crate::packed::offsets")]
    row_offsets: Vec<usize>,
    #[serde(with = "crate::packed")]
    runs: Vec<Run>,
    #[serde(with = "crate::packed")]
    closest: Vec<u32>,
    #[serde(with = "crate::packed")]
    breaks: Vec<u32>,
}

#[cfg(feature = "serde")]
impl TryFrom<SublevelSetState> for SublevelSet {
    type Error = Error;

    /// Checks γ, the separation, the session starts (increasing, inside), and that the runs are
    /// runs of an upper half: per row in increasing column order, apart, within `row..rows`,
    /// each closest column inside its run.
    fn try_from(state: SublevelSetState) -> Result<Self> {
        check_gamma(state.gamma)?;
        state.separation.check()?;
        let invalid = |reason: String| Error::InvalidState { what: "SublevelSet", reason };
        let SublevelSetState { row_offsets, runs, closest, breaks, .. } = &state;
        let rows = row_offsets.len().saturating_sub(1);
        if rows < 2 || row_offsets[0] != 0 || row_offsets[rows] != runs.len() || closest.len() != runs.len() {
            return Err(invalid(format!(
                "{} row offsets from {:?} to {:?} for {} runs and {} closest columns",
                row_offsets.len(),
                row_offsets.first(),
                row_offsets.last(),
                runs.len(),
                closest.len()
            )));
        }
        let mut previous_break = 0;
        for &start in breaks {
            if start <= previous_break || start as usize >= rows {
                return Err(invalid(format!(
                    "session start {start} does not follow {previous_break} within {rows} rows"
                )));
            }
            previous_break = start;
        }
        for i in 0..rows {
            let (a, b) = (row_offsets[i], row_offsets[i + 1]);
            if b < a || b > runs.len() {
                return Err(invalid(format!("the runs of row {i} are {a}..{b}, of {} runs", runs.len())));
            }
            let mut previous_end: Option<u64> = None;
            for (k, (run, &column)) in runs[a..b].iter().zip(&closest[a..b]).enumerate() {
                let (start, end) = (run.start as usize, run.end as usize);
                let apart = previous_end.is_none_or(|e| u64::from(run.start) > e + 1);
                if start < i || start > end || end >= rows || !apart || !(run.start..=run.end).contains(&column) {
                    return Err(invalid(format!(
                        "run {k} of row {i} ({start}..={end}, closest column {column}) is not a run of {rows} rows"
                    )));
                }
                previous_end = Some(u64::from(run.end));
            }
        }
        let SublevelSetState { gamma, separation, row_offsets, runs, closest, breaks } = state;
        Ok(Self { gamma, separation, row_offsets, runs, closest, breaks })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use crate::metric::Euclidean;

    fn line(xs: &[f64]) -> Trajectory {
        Trajectory::new((0..xs.len()).map(|i| i as f64).collect(), xs.to_vec(), 1).unwrap()
    }

    #[test]
    fn out_and_back_on_a_line() {
        let traj = line(&[0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 0.0]);
        let set = SublevelSet::compute(&traj, &Euclidean, 1.0).unwrap();
        assert_eq!(set, SublevelSet::brute_force(&traj, &Euclidean, 1.0).unwrap());
        assert_eq!(set.row(0), &[Run { start: 0, end: 1 }, Run { start: 5, end: 6 }]);
        assert!(set.contains(6, 0) && !set.contains(0, 4));
        assert_eq!(set.closest_columns()[1], 6);
    }

    #[test]
    fn gallop_bounds() {
        let traj = line(&[0.0, 0.0, 0.0, 1.0, 1.0, 5.0, 9.0]);
        let arc = ArcLength::new(&traj, &Euclidean, false).unwrap();
        // s = [0, 0, 0, 1, 1, 5, 9], each rounded up by at most a few ulps.
        assert_eq!(arc.last_within(0, 0.5), 2);
        assert_eq!(arc.last_within(0, 1.5), 4);
        assert_eq!(arc.last_within(0, 100.0), 6);
        assert_eq!(arc.last_within(3, -1.0), 3);
        assert_eq!(arc.last_within(5, 3.9), 5);
        assert_eq!(arc.first_beyond(0, 0.5), 3);
        assert_eq!(arc.first_beyond(0, 1.5), 5);
        assert_eq!(arc.first_beyond(0, 100.0), 7);
        assert_eq!(arc.first_beyond(6, 1.0), 7);
        assert_eq!(arc.first_beyond(1, -1.0), 2);
    }

    #[test]
    fn gallops_are_the_linear_scans() {
        // Steps of every kind: stops (0), creeps, walks, jumps; budgets around each s_k.
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..50 {
            let mut x = 0.0;
            let xs: Vec<f64> = (0..200)
                .map(|_| {
                    x += [0.0, 1e-9, 0.3, 1.0, 1.1, 40.0][rng.random_range(0..6)];
                    x
                })
                .collect();
            let arc = ArcLength::new(&line(&xs), &Euclidean, false).unwrap();
            let s = &arc.s;
            for _ in 0..200 {
                let j = rng.random_range(0..200);
                let length = f64::from(rng.random_range(0..4000_u32)) / 40.0 - 5.0;
                let within = (j..s.len()).take_while(|&k| s[k] <= s[j] + length).last().unwrap_or(j);
                assert_eq!(arc.last_within(j, length), if length < 0.0 { j } else { within });
                let beyond = (j + 1..s.len()).find(|&k| s[k] >= s[j] + length).unwrap_or(s.len());
                assert_eq!(arc.first_beyond(j, length), beyond, "j {j}, length {length}");
            }
        }
    }

    #[test]
    fn squared_limit_decides_as_the_square_root() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut gammas = vec![40.0, 10.0, 0.1, 1.0, 2.0, 1e-160, 1e-200, 1e160, 1e300, f64::MIN_POSITIVE];
        gammas.extend((0..2000).map(|_| 10f64.powf(rng.random_range(-300.0..300.0))));
        for gamma in gammas {
            let limit = squared_limit(gamma);
            assert!(limit.sqrt() <= gamma && limit.next_up().sqrt() > gamma, "gamma {gamma:e}: limit {limit:e}");
            let mut s = limit;
            for _ in 0..4 {
                s = s.next_down();
            }
            for _ in 0..9 {
                // Sums of squares are never below 0, where the square root is NaN.
                if s >= 0.0 {
                    assert_eq!(s <= limit, s.sqrt() <= gamma, "gamma {gamma:e}, s {s:e}");
                }
                s = s.next_up();
            }
            let s = limit * rng.random_range(0.5..2.0);
            assert_eq!(s <= limit, s.sqrt() <= gamma, "gamma {gamma:e}, s {s:e}");
        }
    }

    /// The Euclidean metric without its coordinate form: the engine scans it step by step.
    struct Stepped;

    impl Metric for Stepped {
        fn name(&self) -> String {
            "stepped".into()
        }
        fn check_dim(&self, dim: usize) -> Result<()> {
            Euclidean.check_dim(dim)
        }
        fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
            Euclidean.distance(a, b)
        }
        fn distance_2d(&self, a: &[f64; 2], b: &[f64; 2]) -> f64 {
            Euclidean.distance_2d(a, b)
        }
        fn distance_3d(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
            Euclidean.distance_3d(a, b)
        }
        fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
            Euclidean.distance_rank(a, b)
        }
        fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
            Euclidean.closest_in(x, points)
        }
    }

    #[test]
    fn the_dense_scan_is_the_stepped_scan() {
        // Random walks in 2 and 3 axes with stops, creeps and jumps, so that stretches come
        // whole, partly within γ, of one point, and at every distance from a row's pose.
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for round in 0..40 {
            let dim = 2 + round % 2;
            let n = rng.random_range(50..1500);
            let mut x = vec![0.0_f64; dim];
            let mut coords = Vec::with_capacity(n * dim);
            for _ in 0..n {
                let step: f64 = [0.0, 0.0, 1e-9, 0.2, 1.0, 3.0][rng.random_range(0..6)];
                x.iter_mut().for_each(|c| *c = (*c + step * rng.random_range(-1.0_f64..1.0)).clamp(-20.0, 20.0));
                coords.extend_from_slice(&x);
            }
            let traj = Trajectory::new((0..n).map(|i| i as f64).collect(), coords, dim).unwrap();
            // γ at a pair's own distance too: cells exactly at γ, where `s ≤ limit` must hold.
            let pairs: Vec<f64> = (0..3)
                .map(|_| Euclidean.distance(traj.point(rng.random_range(0..n)), traj.point(rng.random_range(0..n))))
                .collect();
            for gamma in [0.5, 2.0, 7.5].into_iter().chain(pairs.into_iter().filter(|&d| d > 0.0)) {
                let dense = SublevelSet::compute(&traj, &Euclidean, gamma).unwrap();
                assert_eq!(
                    dense,
                    SublevelSet::compute(&traj, &Stepped, gamma).unwrap(),
                    "round {round}, gamma {gamma}"
                );
                let separation = Separation::for_gamma(gamma);
                let dense = SublevelSet::compute_separated(&traj, &Euclidean, gamma, separation).unwrap();
                let stepped = SublevelSet::compute_separated(&traj, &Stepped, gamma, separation).unwrap();
                assert_eq!(dense, stepped, "round {round}, gamma {gamma}, separated");
            }
        }
    }

    #[test]
    fn bad_gamma() {
        let traj = line(&[0.0, 1.0]);
        for gamma in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(SublevelSet::compute(&traj, &Euclidean, gamma), Err(Error::InvalidGamma(_))));
        }
    }
}
