//! [`OnlineLoops`]: the incremental engine.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::ball_tree::{BallTree, Leaf};
use crate::component;
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::memory::{try_filled, try_reserve, try_with_capacity};
use crate::metric::Metric;
use crate::spec::{MetricSpec, with_metric};
use crate::sublevel::{
    ArcLength, Block, LEAF_SIZE, Pruner, RowScanner, Run, StretchAxes, SublevelSet, check_gamma, closest_column,
    dense_limit, walk_reach,
};
use crate::trajectory::{MAX_POSES, Manifold, Trajectory, validate_coordinates, validate_timestamps};
use crate::union_find::MinRootForest;

/// A loop component's id in an [`OnlineLoops`]: ids are given in order of creation, from 0, and
/// stay stable while the component lives. When two components merge, the survivor keeps its id
/// (the smaller one) and the other is retired ([`Update::merged`]; [`OnlineLoops::resolve`]
/// follows merges).
pub type ComponentId = u32;

/// The loops of a trajectory that grows pose by pose: S_γ as runs, its loop components with
/// their statistics, and τ, updated per pose at a cost that follows the answer (the runs near
/// the new pose and a walk of the ball hierarchy), never the length of the trajectory.
///
/// Pose n adds row n of the lower half: the pairs (j, n), j ≤ n, within γ, as runs over j. They
/// are column n of the upper half that [`find_loops`](crate::find_loops) scans by rows, measured
/// as the batch measures them (δ(x_j, x_n), earlier pose first, so that even metrics whose
/// rounding is not symmetric decide every pair alike), so the set is the batch's, pair for pair.
/// A row's runs are joined to the previous row's by union-find: components only grow and merge.
///
/// # What "equal to the batch" means
/// - [`to_loops`](Self::to_loops) equals `find_loops` on the same trajectory bit for bit,
///   floats included (`Loops` compares equal with `==`): it turns the runs into the batch's rows
///   and labels and measures them with the batch's own code, in the batch's order.
/// - The live [`components`](Self::components) have the batch's integers exactly (pair and run
///   counts, holes, index ranges, triviality), its closest pairs and their distances bit for bit,
///   and the same components (numbered in creation order instead). Their areas, and
///   [`loop_duration_s`](Self::loop_duration_s), are the same sums of positive terms grouped by
///   column instead of by row (Σ_n w_n Σ_i w_i instead of Σ_i w_i Σ_n w_n), so they differ from
///   the batch's by rounding only: within a relative 1e-12 on trajectories whose span is up to
///   about 10³ of their shortest time cell, and within `4 · 2⁻⁵³ · span / shortest cell` in
///   general (both sums take widths of runs as differences of running sums of the time cells,
///   whose rounding grows with the span).
///
/// # Cost
/// A push costs the row's share of the batch's work: a walk of the ball hierarchy (a forest of
/// at most log₂(n / 16) + 1 perfect trees, grown leaf by leaf like a binary counter), shared by
/// the pushes within γ/4 of the pose it was centred on as a batch's block shares one, the
/// arc-length skipping scan of the stretches it could not rule out, and for every run of the new
/// row one closest column (O(log n) for long runs), one union with the previous row's runs and
/// O(log n) for τ. Memory is the trajectory, 24 bytes a pose, and 12 bytes a run.
///
/// # Examples
/// 1.9 laps of a circle of radius 10 m, 200 poses a lap, pushed pose by pose: the second lap
/// runs along the first, one component off the diagonal.
/// ```
/// use loops_core::online::OnlineLoops;
/// use loops_core::{Euclidean, MetricSpec, find_loops};
/// let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, 2.0)?;
/// for k in 0..380 {
///     let angle = std::f64::consts::TAU * k as f64 / 200.0;
///     let update = online.push(0.1 * k as f64, &[10.0 * angle.cos(), 10.0 * angle.sin()])?;
///     for id in &update.created {
///         println!("pose {}: component {id} appears", update.pose);
///     }
/// }
/// let laps: Vec<_> = online.components().filter(|(_, c)| !c.trivial).collect();
/// assert_eq!(laps.len(), 1);
/// let [i, j] = laps[0].1.closest_pair;
/// assert_eq!(j - i, 200);
/// // The snapshot is the batch's result, bit for bit.
/// let traj = online.trajectory().expect("two poses or more");
/// assert_eq!(online.to_loops()?, find_loops(traj, &Euclidean, 2.0)?);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct OnlineLoops {
    metric: MetricSpec,
    gamma: f64,
    /// The limit of the dense row scan ([`dense_limit`]), fixed by the metric, the dimension and
    /// γ; `None` where rows scan step by step.
    dense: Option<f64>,
    /// The poses so far (its last time cell is a half cell, as in a batch trajectory).
    traj: Trajectory,
    /// Path length under δ (rounded up, and plain), and the rounding margin of the poses so far.
    arc: ArcLength,
    /// The metric's rounding scale of the poses so far.
    scale: f64,
    /// The ball hierarchy over the poses so far, grown leaf by leaf.
    balls: BallTree,
    /// Running sums of the whole time cells: `prefix_s[k] = Σ_{i<k} w_i`, k ≤ n.
    prefix_s: Vec<f64>,
    /// Row n's runs are `runs[row_offsets[n]..row_offsets[n + 1]]`.
    row_offsets: Vec<usize>,
    runs: Vec<Run>,
    /// The component each run was given when its row was added (resolve it for today's).
    run_components: Vec<ComponentId>,
    /// Union-find over component ids (the smallest id of a set is its root).
    parent: Vec<u32>,
    /// Every component ever created, by id (a retired one keeps its last statistics).
    components: Vec<OnlineComponent>,
    /// τ of every pose from its own row (partners j ≤ i), seconds.
    own_tau_s: Vec<f64>,
    /// τ of every pose from later, settled rows (partners j > i), as range additions.
    later_tau_s: RangeSums,
    rebuilds: u64,
    /// This engine's identity, for the [`PushStamp`] of its updates.
    serial: Serial,
    /// Pushes since it was made, rebuilt or cleared.
    pushes: u64,
    /// The stretches of the last walk of the hierarchy, carried to the next pushes.
    near: NearStretches,
    /// Scratch: the runs of the row being added and their closest columns.
    row: Block,
}

/// How far, as a fraction of γ, a pose may be from the centre of the last walk of the ball
/// hierarchy for that walk's stretches to serve its row. A wider walk serves more rows but
/// hands each more stretches to rule out.
const CARRY_FRACTION: f64 = 0.25;

/// The stretches of one walk of the ball hierarchy, carried from push to push as the batch
/// carries a block's: the walk is centred on a pose x_c and reaches γ + R beyond it (R =
/// [`CARRY_FRACTION`] · γ), so by the triangle inequality its stretches hold every pose within
/// γ of any later pose x_n with δ(x_c, x_n) ≤ R ([`walk_reach`], the batch's rule for a block of
/// radius R); the leaves pushed since are appended as they come, each kept when its ball
/// reaches as far. A pose farther than R from the centre, a rounding margin grown past the
/// walk's, or the stretches grown to twice the walk's (a robot circling near the centre: the
/// new leaves are not merged as a fresh walk would merge them) walk again from the pose.
#[derive(Debug, Clone, Default)]
struct NearStretches {
    /// The pose the walk was centred on; `None` before the first walk.
    centre: Option<usize>,
    /// The rounding margin the walk allows for: twice the engine's when it walked.
    margin: f64,
    /// The walk's `(reach, inside_reach)`.
    reach: (f64, f64),
    /// The stretches, in pose order, to the last leaf pushed.
    stretches: Vec<Leaf>,
    /// For each stretch, the path length s up to which it is known to stay out of reach
    /// ([`RowScanner::scan_row`]'s `far_until`).
    far_until: Vec<f64>,
    /// For each stretch, its poses by axis where rows scan densely
    /// ([`RowScanner::scan_row_dense`]); else empty.
    axes: Vec<StretchAxes>,
    /// How many stretches the walk gave.
    walked: usize,
    /// The leaves pushed since the stretches were last brought up to date.
    new_leaves: Vec<u32>,
}

/// Which push of which engine an [`Update`] reports: the engine (a number drawn for it when it
/// was made, never reused in this process, so that an engine made where a dropped one was is
/// another engine), its [rebuild count](OnlineLoops::rebuild_count) and its pushes since. An
/// [`OnlineSampler`](super::OnlineSampler) offers an update only when it is its engine's
/// [`last_push`](OnlineLoops::last_push), and only once. The default stamp names no engine.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct PushStamp {
    engine: u64,
    rebuilds: u64,
    pushes: u64,
}

impl PushStamp {
    /// Whether `other` is a push of the same engine since the same rebuild (or clear): its
    /// component ids mean the same.
    pub(crate) fn same_run(self, other: Self) -> bool {
        (self.engine, self.rebuilds) == (other.engine, other.rebuilds)
    }

    /// The engine's rebuild count at the push.
    pub(crate) fn rebuilds(self) -> u64 {
        self.rebuilds
    }
}

/// An engine's number for its [`PushStamp`]s, from a process-wide counter starting at 1 (0 is
/// no engine). A clone draws a number of its own: it goes its own way from there.
#[derive(Debug)]
struct Serial(u64);

impl Serial {
    fn next() -> Self {
        static SERIALS: AtomicU64 = AtomicU64::new(1);
        Self(SERIALS.fetch_add(1, Ordering::Relaxed))
    }

    /// The same number, for the engine a rebuild or clear makes in this one's place.
    fn same(&self) -> Self {
        Self(self.0)
    }
}

impl Clone for Serial {
    fn clone(&self) -> Self {
        Self::next()
    }
}

/// Statistics of a live loop component, so far: the quantities of
/// [`LoopComponent`](crate::LoopComponent), in batch orientation (pairs (i, j) with i ≤ j;
/// a trivial component reported whole, a non-trivial one as its half with i ≤ j), equal to those
/// of the batch [`find_loops`](crate::find_loops) of the trajectory pushed so far (see the
/// [`OnlineLoops`] for the sums of floats), plus when it first appeared.
#[derive(Debug, Clone, PartialEq)]
pub struct OnlineComponent {
    /// Its id.
    pub id: ComponentId,
    /// Contains diagonal cells (i, i): its pairs are simple loops.
    pub trivial: bool,
    /// Area in the (t, t′) plane so far, s² (the last pose's time cell is a half cell until the
    /// next pose arrives, as in the batch).
    pub area_s2: f64,
    /// Number of lattice cells (i, j).
    pub pair_count: u64,
    /// Number of runs of the batch's upper half (row intervals), as
    /// [`LoopComponent::run_count`](crate::LoopComponent::run_count).
    pub run_count: usize,
    /// Number of holes in the full plane.
    pub holes: u64,
    /// First and last pose index i of the reported half.
    pub i_range: [usize; 2],
    /// First and last pose index j of the reported half.
    pub j_range: [usize; 2],
    /// The pair (i, j), i ≤ j, with the smallest distance, earliest in row order on ties.
    pub closest_pair: [usize; 2],
    /// δ at the closest pair.
    pub closest_distance: f64,
    /// The pose whose row created it (for a merged component, the earliest of its parts).
    pub first_pose: usize,
    /// The last pose whose row extended it.
    pub last_pose: usize,
    tally: Tally,
}

/// What a component's statistics are summed from: the batch labeller's tallies, gathered by
/// column (the online rows) instead of by row.
#[derive(Debug, Clone, PartialEq)]
struct Tally {
    /// Over the runs of the online rows (the columns of the upper half), whose Euler number is
    /// the rows', and the cells of settled rows (the last row's area is pending: its time cell
    /// is a half cell until the next pose).
    half: component::Tally,
    /// Runs of the batch's rows: cells (i, n) whose left neighbour (i, n − 1) is outside.
    row_runs: u64,
    pending_area_s2: f64,
    pending_diagonal_area_s2: f64,
}

impl OnlineComponent {
    /// A component created by a run of row n, before its run is tallied.
    fn new(id: ComponentId, n: usize) -> Self {
        Self {
            id,
            trivial: false,
            area_s2: 0.0,
            pair_count: 0,
            run_count: 0,
            holes: 0,
            i_range: [n, n],
            j_range: [n, n],
            closest_pair: [usize::MAX; 2],
            closest_distance: f64::INFINITY,
            first_pose: n,
            last_pose: n,
            tally: Tally {
                half: component::Tally {
                    rows: [usize::MAX, 0],
                    columns: [n, n],
                    closest: (f64::INFINITY, [usize::MAX; 2]),
                    ..component::Tally::default()
                },
                row_runs: 0,
                pending_area_s2: 0.0,
                pending_diagonal_area_s2: 0.0,
            },
        }
    }

    /// Adds the statistics of `other`, merged into this one.
    fn absorb(&mut self, other: &Self) {
        if component::closer(other.tally.half.closest, self.tally.half.closest) {
            self.closest_distance = other.closest_distance;
        }
        self.tally.half.absorb(&other.tally.half);
        self.tally.row_runs += other.tally.row_runs;
        self.tally.pending_area_s2 += other.tally.pending_area_s2;
        self.tally.pending_diagonal_area_s2 += other.tally.pending_diagonal_area_s2;
        self.first_pose = self.first_pose.min(other.first_pose);
        self.last_pose = self.last_pose.max(other.last_pose);
    }

    /// The reported statistics from the tallies, folded as the batch folds them.
    fn refresh(&mut self) {
        let mut whole = self.tally.half.clone();
        whole.area_s2 += self.tally.pending_area_s2;
        whole.diagonal_area_s2 += self.tally.pending_diagonal_area_s2;
        let folded = whole.fold();
        self.trivial = whole.trivial;
        self.area_s2 = folded.area_s2;
        self.pair_count = folded.pair_count;
        self.holes = folded.holes();
        (self.i_range, self.j_range) = (folded.i_range, folded.j_range);
        self.run_count = self.tally.row_runs as usize;
        self.closest_pair = whole.closest.1;
    }
}

impl NearStretches {
    /// Brings the stretches up to row `n` of `scanner` (the engine's, over `balls`): the leaves
    /// pushed since, when pose n is still within reach of the walk's centre, else a new walk
    /// centred on pose n; with their poses by axis when the row scans `dense`ly.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`] when the stretches do not fit in memory.
    fn update<M: Metric + ?Sized>(
        &mut self,
        scanner: &RowScanner<'_, M>,
        balls: &BallTree,
        n: usize,
        dense: bool,
    ) -> Result<()> {
        let (traj, radius) = (scanner.traj, CARRY_FRACTION * scanner.gamma);
        // Measured as the batch measures a block's radius: from the centre to the row.
        let carried = self.centre.is_some_and(|c| {
            scanner.arc.margin <= self.margin
                && self.stretches.len() <= 2 * self.walked + 8
                && scanner.metric.distance(traj.point(c), traj.point(n)) <= radius
        });
        if carried {
            let centre = traj.point(self.centre.unwrap_or(n));
            for &leaf in &self.new_leaves {
                balls.append_near_spans(leaf, scanner.metric, centre, self.reach, &mut self.stretches)?;
            }
        } else {
            self.centre = Some(n);
            self.margin = 2.0 * scanner.arc.margin;
            self.reach = walk_reach(scanner.gamma, radius, self.margin);
            balls.near_spans(scanner.metric, traj.point(n), 0, self.reach, &mut self.stretches)?;
            self.walked = self.stretches.len();
            self.far_until.clear();
            self.axes.clear();
        }
        self.new_leaves.clear();
        let missing = self.stretches.len() + 1 - self.far_until.len();
        try_reserve(&mut self.far_until, missing, "the stretches of a row scan")?;
        self.far_until.resize(self.stretches.len(), f64::NEG_INFINITY);
        if dense {
            // Appended stretches are new entries (only inside ones, which have no poses by axis,
            // grow in place), so the entries made before stay right.
            scanner.stretch_axes(&self.stretches[self.axes.len()..], &mut self.axes)?;
        }
        Ok(())
    }
}

/// A run of a new row n: the columns `run.start..=run.end` (all ≤ n) within γ of pose n.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RowRun {
    /// The row: the pose pushed.
    pub row: usize,
    /// Its columns j (earlier poses, and the pose itself when the run reaches the diagonal).
    pub run: Run,
    /// Its component once the row was added (a later row of the same
    /// [`push_many`](OnlineLoops::push_many) may merge it into another: see [`Update::merged`]).
    pub component: ComponentId,
    /// The column j of the run closest to pose `row` (the earliest on ties).
    pub closest: usize,
}

/// Two components that merged while a row was added.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Merge {
    /// The row whose runs joined them.
    pub pose: usize,
    /// The id that was retired.
    pub retired: ComponentId,
    /// The id that lives on (the smaller).
    pub survivor: ComponentId,
}

/// What a push changed. Two updates are equal when they report the same changes, whichever
/// push of whichever engine made them (their [`stamp`](Self::stamp)s are not compared).
#[derive(Debug, Clone, Default)]
pub struct Update {
    /// Index of the first pose the push added.
    pub first_pose: usize,
    /// Index of the last pose pushed (the keyframe).
    pub pose: usize,
    /// The new rows' runs, row by row, columns increasing.
    pub runs: Vec<RowRun>,
    /// Components created, in order.
    pub created: Vec<ComponentId>,
    /// Components that existed before the push and gained cells, each once, by their id after
    /// the push, increasing.
    pub extended: Vec<ComponentId>,
    /// Merges, in the order they happened.
    pub merged: Vec<Merge>,
    /// The loop duration τ of the last pose so far, seconds: how long the trajectory has stayed
    /// within γ of it (its own time cell included).
    pub loop_duration_s: f64,
    /// The push that made it ([`PushStamp::default`], no engine, for an update made otherwise,
    /// e.g. read back from a file: such an update cannot be offered).
    pub stamp: PushStamp,
}

impl PartialEq for Update {
    fn eq(&self, other: &Self) -> bool {
        let Self { first_pose, pose, runs, created, extended, merged, loop_duration_s, stamp: _ } = self;
        (first_pose, pose, runs, created, extended, merged, loop_duration_s)
            == (
                &other.first_pose,
                &other.pose,
                &other.runs,
                &other.created,
                &other.extended,
                &other.merged,
                &other.loop_duration_s,
            )
    }
}

impl OnlineLoops {
    /// The most coordinates a pose of an online engine may have: 65,536 (a place-recognition
    /// descriptor has a few thousand). With at most [`MAX_POSES`] poses, every buffer of an
    /// engine's coordinates then fits in memory's address space, so that
    /// [`coordinate_count`](Self::coordinate_count) never overflows.
    pub const MAX_DIM: usize = 1 << 16;

    /// An empty engine for poses of `dim` coordinates measured by `metric`, threshold γ (the
    /// metric's unit).
    ///
    /// # Errors
    /// [`Error::InvalidGamma`]; [`Error::DimensionTooLarge`] beyond [`MAX_DIM`](Self::MAX_DIM);
    /// the metric's dimension error.
    pub fn new(metric: MetricSpec, dim: usize, gamma: f64) -> Result<Self> {
        check_gamma(gamma)?;
        if dim > Self::MAX_DIM {
            return Err(Error::DimensionTooLarge { dim, max: Self::MAX_DIM });
        }
        metric.as_metric().check_dim(dim)?;
        Ok(Self::empty(metric, gamma, Trajectory::growing(dim, Manifold::Euclidean), 0, Serial::next()))
    }

    /// The number of coordinates of `poses` poses of this engine, `poses` × [`dim`](Self::dim),
    /// for a caller that takes them from a raw buffer: a count whose buffer fits in memory's
    /// address space.
    ///
    /// # Errors
    /// [`Error::TooManyPoses`] beyond [`MAX_POSES`].
    pub fn coordinate_count(&self, poses: usize) -> Result<usize> {
        const _: () = assert!(
            (MAX_POSES as u128) * (OnlineLoops::MAX_DIM as u128) * (size_of::<f64>() as u128) <= isize::MAX as u128
        );
        if poses > MAX_POSES {
            return Err(Error::TooManyPoses { count: poses, max: MAX_POSES });
        }
        Ok(poses * self.dim())
    }

    fn empty(metric: MetricSpec, gamma: f64, traj: Trajectory, rebuilds: u64, serial: Serial) -> Self {
        Self {
            dense: with_metric!(&metric, m => dense_limit(m, traj.dim(), gamma)),
            metric,
            gamma,
            balls: BallTree::growing(traj.dim()),
            traj,
            arc: ArcLength::default(),
            scale: 0.0,
            prefix_s: Vec::new(),
            row_offsets: vec![0],
            runs: Vec::new(),
            run_components: Vec::new(),
            parent: Vec::new(),
            components: Vec::new(),
            own_tau_s: Vec::new(),
            later_tau_s: RangeSums::default(),
            rebuilds,
            serial,
            pushes: 0,
            near: NearStretches::default(),
            row: Block::default(),
        }
    }

    /// Adds pose n at time `t_s` (after the last) with `point` (`dim` coordinates, validated as
    /// the batch validates a [`Trajectory`]'s points for the metric): row n of the plane's lower
    /// half, the pairs (j, n), j ≤ n.
    ///
    /// # Errors
    /// As [`Trajectory::new`] for the new pose (named by its index n), and the metric's checks
    /// (unit quaternions, ...); nothing changes then.
    pub fn push(&mut self, t_s: f64, point: &[f64]) -> Result<Update> {
        self.push_many(&[t_s], point)
    }

    /// Adds several poses (coordinates row-major), as that many [`push`](Self::push)es, with one
    /// [`Update`] covering all of them.
    ///
    /// # Errors
    /// As [`push`](Self::push), for the first bad pose; none of the poses is added then.
    /// [`Error::Interrupted`] when an [`Interrupt`] installed on this thread is interrupted: it
    /// is looked at before every pose, and the poses before the one it stopped at stay added, as
    /// their pushes would have left them ([`len`](Self::len) says how many); the rest are not.
    pub fn push_many(&mut self, timestamps_s: &[f64], coords: &[f64]) -> Result<Update> {
        let first = self.len();
        self.check_new_poses(timestamps_s, coords)?;
        let dim = self.dim();
        let pose = (first + timestamps_s.len()).saturating_sub(1);
        let mut update = Update { first_pose: first, pose, ..Update::default() };
        let ids_before = self.components.len() as ComponentId;
        let metric = self.metric;
        let interrupt = Interrupt::current();
        with_metric!(&metric, m => {
            for (k, &t_s) in timestamps_s.iter().enumerate() {
                if let Err(stopped) = interrupt.check() {
                    // The poses added so far make this a push: the update offered last is no
                    // longer the last.
                    if k > 0 {
                        self.pushes += 1;
                    }
                    return Err(stopped);
                }
                let n = first + k;
                self.traj.push_pose(t_s, &coords[k * dim..(k + 1) * dim]);
                self.add_row(m, n, &mut update);
            }
        });
        let mut extended: Vec<ComponentId> = std::mem::take(&mut update.extended);
        extended.retain(|&id| id < ids_before);
        extended.iter_mut().for_each(|id| *id = self.find(*id));
        extended.sort_unstable();
        extended.dedup();
        update.extended = extended;
        update.loop_duration_s = self.own_tau_s.last().copied().unwrap_or(0.0);
        self.pushes += 1;
        update.stamp = self.last_push();
        Ok(update)
    }

    /// Scans and joins the row of pose `n` (in the trajectory already).
    fn add_row<M: Metric + ?Sized>(&mut self, metric: &M, n: usize, update: &mut Update) {
        self.grow(metric, n);
        let mut block = std::mem::take(&mut self.row);
        block.runs.clear();
        block.closest.clear();
        self.scan_row(&Swapped(metric), n, &mut block);
        self.join_row(metric, n, &block.runs, &block.closest, Some(update));
        self.row = block;
    }

    /// Checks the new poses as [`Trajectory::new`] and the metric check them, naming each by
    /// its index in the whole trajectory, and raises the rounding scale to theirs; on an error
    /// nothing changes. [`push_many`](Self::push_many) then appends them one by one.
    fn check_new_poses(&mut self, timestamps_s: &[f64], coords: &[f64]) -> Result<()> {
        let (dim, first) = (self.dim(), self.len());
        if !coords.len().is_multiple_of(dim) {
            return Err(Error::RaggedCoordinates { len: coords.len(), dim });
        }
        let poses = coords.len() / dim;
        if timestamps_s.len() != poses {
            return Err(Error::LengthMismatch { timestamps: timestamps_s.len(), poses });
        }
        if first + poses > MAX_POSES {
            return Err(Error::TooManyPoses { count: first + poses, max: MAX_POSES });
        }
        let shift = |error: Error| shift_pose_index(error, first);
        validate_timestamps(timestamps_s).map_err(shift)?;
        if let (Some(&previous_s), Some(&value_s)) = (self.timestamps_s().last(), timestamps_s.first()) {
            // NaN is caught above.
            if value_s <= previous_s {
                return Err(Error::TimestampsNotIncreasing { index: first, previous_s, value_s });
            }
        }
        validate_coordinates(coords, dim, first)?;
        if poses == 0 {
            return Ok(());
        }
        // The metric's own checks (unit quaternions, weights) on the new poses alone.
        let mut fresh = Trajectory::growing(dim, self.traj.manifold());
        for (k, &t_s) in timestamps_s.iter().enumerate() {
            fresh.push_pose(t_s, &coords[k * dim..(k + 1) * dim]);
        }
        self.metric.validate(&fresh).map_err(shift)?;
        let scale = with_metric!(&self.metric, m => m.rounding_scale(&fresh));
        self.scale = self.scale.max(scale);
        Ok(())
    }

    /// The bookkeeping of pose n (in the trajectory already): path length and margin, running
    /// sums of the time cells (whole up to n − 1 now), τ's range sums, the ball hierarchy; and
    /// row n − 1's sums that used the half cell of pose n − 1, settled with its whole cell.
    fn grow<M: Metric + ?Sized>(&mut self, metric: &M, n: usize) {
        let step = if n == 0 { 0.0 } else { metric.distance(self.traj.point(n - 1), self.traj.point(n)) };
        self.arc.push(step, self.scale);
        let widths = self.traj.cell_widths_s();
        match self.prefix_s.last() {
            None => self.prefix_s.push(0.0),
            Some(&last) => self.prefix_s.push(last + widths[n - 1]),
        }
        self.later_tau_s.push();
        self.own_tau_s.push(0.0);
        if n + 1 - self.balls.covered() == LEAF_SIZE {
            let leaf = self.balls.push_leaf(&self.traj, metric, n + 1);
            if self.near.centre.is_some() {
                self.near.new_leaves.push(leaf);
            }
        }
        if n >= 1 {
            self.settle_row(n - 1);
        }
    }

    /// The width in seconds of the time cells `a..=b` (the last one as it is now), from the
    /// running sums, as the batch's labeller takes it.
    fn width_s(&self, a: usize, b: usize) -> f64 {
        (self.prefix_s[b] + self.traj.cell_widths_s()[b]) - self.prefix_s[a]
    }

    /// Row `r`'s sums with its whole time cell, now that pose r + 1 is in: its components' areas
    /// and diagonal areas move from pending to final, τ of its partners j < r gains w_r, and
    /// τ(r)'s own part is summed again.
    fn settle_row(&mut self, r: usize) {
        let w_r = self.traj.cell_widths_s()[r];
        let mut own_s = 0.0;
        for k in self.row_offsets[r]..self.row_offsets[r + 1] {
            let (a, b) = (self.runs[k].start as usize, self.runs[k].end as usize);
            let width_s = self.width_s(a, b);
            own_s += width_s;
            let id = self.find(self.run_components[k]);
            let tally = &mut self.components[id as usize].tally;
            tally.half.area_s2 += w_r * width_s;
            tally.pending_area_s2 = 0.0;
            if b == r {
                tally.half.diagonal_area_s2 += w_r * w_r;
                tally.pending_diagonal_area_s2 = 0.0;
            }
            if a < r {
                self.later_tau_s.add(a, b.min(r - 1), w_r);
            }
            self.refresh(id);
        }
        self.own_tau_s[r] = own_s;
    }

    /// Scans row n for its runs (columns j ≤ n) and their closest columns, with `metric` the
    /// engine's metric with its arguments swapped.
    fn scan_row<M: Metric + ?Sized>(&mut self, metric: &M, n: usize, block: &mut Block) {
        let scanner = RowScanner {
            traj: &self.traj,
            metric,
            arc: &self.arc,
            pruner: Pruner::Hierarchy(&self.balls),
            gamma: self.gamma,
            first_columns: &[],
            starts: &[0],
        };
        let dense = self.dense;
        // The stretches near one pose are few; a push has no way back from half-added rows,
        // so running out of memory here is not an error to return.
        let grown = self.near.update(&scanner, &self.balls, n, dense.is_some());
        grown.unwrap_or_else(|error| panic!("{error}"));
        let near = &mut self.near;
        // The poses after the last leaf: one stretch that no ball rules out, for this row only.
        let covered = self.balls.covered();
        let tail = covered <= n;
        if tail {
            let (lo, hi) = (covered as u32, n as u32 + 1);
            let leaf = Leaf { lo, hi, centre: lo, radius: f64::INFINITY, inside: false, uniform: false };
            near.stretches.push(leaf);
            near.far_until.push(f64::NEG_INFINITY);
            if dense.is_some() {
                scanner.stretch_axes(&[leaf], &mut near.axes).unwrap_or_else(|error| panic!("{error}"));
            }
        }
        match dense {
            Some(limit) => scanner.scan_row_dense(n, &near.stretches, &near.axes, limit, &mut near.far_until, block),
            None => scanner.scan_row(n, &near.stretches, &mut near.far_until, block),
        }
        if tail {
            near.stretches.pop();
            near.far_until.pop();
            if dense.is_some() {
                near.axes.pop();
            }
        }
    }

    /// Adds row n's runs (closest columns `closest`): joins them to row n − 1's by union-find,
    /// creating, extending and merging components, and tallies them; reports to `update`.
    fn join_row<M: Metric + ?Sized>(
        &mut self,
        metric: &M,
        n: usize,
        runs: &[Run],
        closest: &[u32],
        mut update: Option<&mut Update>,
    ) {
        let previous = if n == 0 { 0..0 } else { self.row_offsets[n - 1]..self.row_offsets[n] };
        let w_n = self.traj.cell_widths_s()[n];
        let first_new = self.runs.len();
        let mut p = previous.start;
        let mut own_s = 0.0;
        let mut joined: Vec<ComponentId> = Vec::new();
        for (&run, &column) in runs.iter().zip(closest) {
            let (a, b) = (run.start as usize, run.end as usize);
            // The runs of row n − 1 sharing a column with this one (4-adjacent cells).
            while p < previous.end && self.runs[p].end < run.start {
                p += 1;
            }
            joined.clear();
            let (mut overlaps, mut shared_cells) = (0_u64, 0_u64);
            let mut q = p;
            while q < previous.end && self.runs[q].start <= run.end {
                let other = self.runs[q];
                overlaps += 1;
                shared_cells += u64::from(other.end.min(run.end) - other.start.max(run.start) + 1);
                joined.push(self.run_components[q]);
                q += 1;
            }
            for id in joined.iter_mut() {
                *id = self.find(*id);
            }
            let id = match joined.iter().min().copied() {
                None => self.create(n, update.as_deref_mut()),
                Some(survivor) => {
                    for &other in &joined {
                        // An id merged by an earlier turn of this loop is found as the survivor.
                        let retired = self.find(other);
                        if retired != survivor {
                            self.merge(retired, survivor);
                            if let Some(update) = update.as_deref_mut() {
                                update.merged.push(Merge { pose: n, retired, survivor });
                            }
                        }
                    }
                    if let Some(update) = update.as_deref_mut() {
                        update.extended.push(survivor);
                    }
                    survivor
                }
            };
            let width_s = self.width_s(a, b);
            own_s += width_s;
            let j = column as usize;
            let (x_j, x_n) = (self.traj.point(j), self.traj.point(n));
            let rank = metric.distance_rank(x_j, x_n);
            let component = &mut self.components[id as usize];
            let tally = &mut component.tally;
            let half = &mut tally.half;
            half.runs += 1;
            half.overlaps += overlaps;
            half.pairs += run.len() as u64;
            half.rows = [half.rows[0].min(a), half.rows[1].max(b)];
            half.columns[1] = n;
            tally.row_runs += run.len() as u64 - shared_cells;
            tally.pending_area_s2 += w_n * width_s;
            if b == n {
                half.trivial = true;
                half.diagonal_cells += 1;
                tally.pending_diagonal_area_s2 = w_n * w_n;
            }
            // The smallest rank, then the earliest pair in the batch's row order.
            if (rank, [j, n]) < half.closest {
                half.closest = (rank, [j, n]);
                component.closest_distance = metric.distance(x_j, x_n);
            }
            component.last_pose = n;
            self.runs.push(run);
            self.run_components.push(id);
            if let Some(update) = update.as_deref_mut() {
                update.runs.push(RowRun { row: n, run, component: id, closest: j });
            }
        }
        // A diagonal link (n − 1, n − 1)–(n − 1, n), as the batch counts it in row n − 1.
        let diagonal_before =
            n >= 1 && previous.end > previous.start && self.runs[previous.end - 1].end as usize == n - 1;
        let link = runs.iter().position(|r| diagonal_before && (r.start as usize..=r.end as usize).contains(&(n - 1)));
        if let Some(k) = link {
            let id = self.find(self.run_components[first_new + k]);
            self.components[id as usize].tally.half.diagonal_links += 1;
        }
        self.row_offsets.push(self.runs.len());
        self.own_tau_s[n] = own_s;
        // The row's components as they are at its end (a later run may have merged them).
        let reported = update.map_or(&mut [][..], |update| {
            let base = update.runs.len() - runs.len();
            &mut update.runs[base..]
        });
        for k in first_new..self.runs.len() {
            let id = self.find(self.run_components[k]);
            self.refresh(id);
            if let Some(run) = reported.get_mut(k - first_new) {
                run.component = id;
            }
        }
    }

    /// A new component, created by a run of row n.
    fn create(&mut self, n: usize, update: Option<&mut Update>) -> ComponentId {
        let id = self.components.len() as ComponentId;
        self.parent.push(id);
        self.components.push(OnlineComponent::new(id, n));
        if let Some(update) = update {
            update.created.push(id);
        }
        id
    }

    /// Retires `retired` into `survivor` (smaller), adding up their statistics.
    fn merge(&mut self, retired: ComponentId, survivor: ComponentId) {
        debug_assert!(survivor < retired);
        MinRootForest::new(&mut self.parent, 0).union(retired as usize, survivor as usize);
        let gone = self.components[retired as usize].clone();
        self.components[survivor as usize].absorb(&gone);
    }

    /// The live id of `id`, halving the path to it.
    fn find(&mut self, id: ComponentId) -> ComponentId {
        MinRootForest::new(&mut self.parent, 0).find(id as usize) as ComponentId
    }

    /// Recomputes component `id`'s reported statistics from its tallies.
    fn refresh(&mut self, id: ComponentId) {
        self.components[id as usize].refresh();
    }

    /// Restarts from `traj`, the trajectory so far as the back end corrected it, with one batch
    /// computation (rows in parallel on the current rayon pool); later pushes continue from its
    /// last pose. Component ids restart from 0 (creation order, as pushing `traj` pose by pose
    /// would give them); nothing is reported. The time cells come from the timestamps.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for points of another dimension; the metric's errors on
    /// `traj` (fit, points); [`Error::OutOfMemory`], [`Error::Interrupted`]. Nothing changes
    /// then.
    pub fn rebuild(&mut self, traj: &Trajectory) -> Result<()> {
        if traj.dim() != self.dim() {
            return Err(Error::DimensionMismatch {
                metric: self.metric.name(),
                expected: format!("{} (the online engine's)", self.dim()),
                found: traj.dim(),
            });
        }
        let metric = self.metric;
        let rebuilt = with_metric!(&metric, m => self.rebuilt(m, traj))?;
        *self = rebuilt;
        Ok(())
    }

    /// The engine of [`rebuild`](Self::rebuild): the batch's S_γ, turned into rows of the lower
    /// half, then added row by row without scanning.
    fn rebuilt<M: Metric + ?Sized>(&self, metric: &M, traj: &Trajectory) -> Result<Self> {
        let set = SublevelSet::compute(traj, metric, self.gamma)?;
        let (row_offsets, runs) = transpose_runs(traj.len(), |i| set.row(i))?;
        let mut fresh = Self::empty(
            self.metric,
            self.gamma,
            Trajectory::growing(traj.dim(), traj.manifold()),
            self.rebuilds + 1,
            self.serial.same(),
        );
        fresh.scale = metric.rounding_scale(traj);
        let interrupt = Interrupt::current();
        let mut closest = Vec::new();
        for n in 0..traj.len() {
            if n % 4096 == 0 {
                interrupt.check()?;
            }
            fresh.traj.push_pose(traj.timestamps_s()[n], traj.point(n));
            fresh.grow(metric, n);
            let row = &runs[row_offsets[n]..row_offsets[n + 1]];
            closest.clear();
            closest.extend(
                row.iter().map(|run| fresh.closest_column(metric, n, run.start as usize, run.end as usize) as u32),
            );
            fresh.join_row(metric, n, row, &closest, None);
        }
        Ok(fresh)
    }

    /// The column of `a..=b` (all ≤ n) closest to pose n, measured as the batch measures pairs
    /// (j, n); the earliest on ties.
    pub(crate) fn closest_column<M: Metric + ?Sized>(&self, metric: &M, n: usize, a: usize, b: usize) -> usize {
        closest_column(&Swapped(metric), &self.traj, &self.balls, self.arc.margin, n, (a, b))
    }

    /// Forgets every pose: back to the state of [`new`](Self::new) (ids restart too).
    pub fn clear(&mut self) {
        *self = Self::empty(
            self.metric,
            self.gamma,
            Trajectory::growing(self.dim(), Manifold::Euclidean),
            self.rebuilds + 1,
            self.serial.same(),
        );
    }

    /// Number of poses pushed.
    pub fn len(&self) -> usize {
        self.traj.len()
    }

    /// Whether no pose was pushed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The threshold γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The metric.
    pub fn metric(&self) -> MetricSpec {
        self.metric
    }

    /// Coordinates per pose.
    pub fn dim(&self) -> usize {
        self.traj.dim()
    }

    /// Timestamps of the poses pushed, seconds.
    pub fn timestamps_s(&self) -> &[f64] {
        self.traj.timestamps_s()
    }

    /// The trajectory pushed so far (no copy), or `None` before the second pose (a
    /// [`Trajectory`] has at least two).
    pub fn trajectory(&self) -> Option<&Trajectory> {
        (self.len() >= 2).then_some(&self.traj)
    }

    /// The poses so far, even fewer than two.
    pub(crate) fn poses(&self) -> &Trajectory {
        &self.traj
    }

    /// The path length of every pose so far, as [`path_length`](crate::path_length) sums it.
    pub(crate) fn path_length(&self) -> &[f64] {
        &self.arc.plain
    }

    /// How many times the engine was [rebuilt](Self::rebuild) or [cleared](Self::clear): ids of
    /// an earlier count mean nothing now.
    pub fn rebuild_count(&self) -> u64 {
        self.rebuilds
    }

    /// The stamp of this engine's last push (its [`Update::stamp`]): another after every push,
    /// rebuild and clear, and never one of another engine's.
    pub fn last_push(&self) -> PushStamp {
        PushStamp { engine: self.serial.0, rebuilds: self.rebuilds, pushes: self.pushes }
    }

    /// The live components (not retired) by id, increasing, with their statistics so far.
    /// O(components ever created).
    pub fn components(&self) -> impl Iterator<Item = (ComponentId, &OnlineComponent)> + '_ {
        self.components.iter().filter(|c| self.parent[c.id as usize] == c.id).map(|c| (c.id, c))
    }

    /// The live component `id`, or `None` when it was retired or never existed.
    pub fn component(&self, id: ComponentId) -> Option<&OnlineComponent> {
        self.components.get(id as usize).filter(|c| self.parent[c.id as usize] == c.id)
    }

    /// The live id that `id` (possibly retired) now belongs to, following merges; `id` itself
    /// for a live id or one that never existed.
    pub fn resolve(&self, id: ComponentId) -> ComponentId {
        let mut id = id;
        while let Some(&up) = self.parent.get(id as usize) {
            if up == id {
                break;
            }
            id = up;
        }
        id
    }

    /// The loop duration τ(t_i) of pose `pose` so far (paper, Eq. 6, over all of S_γ, both
    /// sides), seconds: the time cells of its partners so far (the last pose's a half cell).
    /// O(log n).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`].
    pub fn loop_duration_s(&self, pose: usize) -> Result<f64> {
        let n = self.len();
        if pose >= n {
            return Err(Error::IndexOutOfRange { index: pose, len: n });
        }
        // Partners in the last row, not settled yet: its time cell, as it is now.
        let last = &self.runs[self.row_offsets[n - 1]..];
        let k = last.partition_point(|r| (r.end as usize) < pose);
        let in_last_row = pose < n - 1 && k < last.len() && last[k].start as usize <= pose;
        let pending_s = if in_last_row { self.traj.cell_widths_s()[n - 1] } else { 0.0 };
        Ok(self.own_tau_s[pose] + self.later_tau_s.at(pose) + pending_s)
    }

    /// A snapshot equal to [`find_loops`](crate::find_loops) on [`trajectory`](Self::trajectory)
    /// (components numbered in the batch's order, bit for bit: see [`OnlineLoops`]). O(runs + n):
    /// the runs are turned into the batch's rows and labelled and measured by the batch's code.
    ///
    /// # Errors
    /// [`Error::TooFewPoses`] before the second pose; [`Error::OutOfMemory`];
    /// [`Error::Interrupted`].
    pub fn to_loops(&self) -> Result<Loops> {
        let n = self.len();
        if n < 2 {
            return Err(Error::TooFewPoses { count: n });
        }
        let (row_offsets, runs) = transpose_runs(n, |k| &self.runs[self.row_offsets[k]..self.row_offsets[k + 1]])?;
        let interrupt = Interrupt::current();
        with_metric!(&self.metric, m => {
            let scanner = RowScanner {
                traj: &self.traj,
                metric: m,
                arc: &self.arc,
                pruner: Pruner::Hierarchy(&self.balls),
                gamma: self.gamma,
                first_columns: &[],
                starts: &[0],
            };
            let mut closest = try_with_capacity(runs.len(), "the closest columns of S_gamma")?;
            for i in 0..n {
                interrupt.check()?;
                for run in &runs[row_offsets[i]..row_offsets[i + 1]] {
                    closest.push(scanner.closest_of_run(i, run.start as usize, run.end as usize) as u32);
                }
            }
            let set = SublevelSet::from_rows(self.gamma, row_offsets, runs, closest);
            Loops::try_from_set(&self.traj, m, set)
        })
    }
}

/// The runs of the transposed set: given the runs of `rows` rows of a set of lattice cells
/// (`row(r)`: row r's runs over columns, increasing, all columns < `rows`), the runs of each
/// column over rows, as row offsets (rows + 1 of them) and runs. The upper half's rows become
/// the lower half's and back. O(runs of both): a cell enters or leaves the sweep only where a
/// run of either set starts or ends.
pub(crate) fn transpose_runs<'a>(rows: usize, row: impl Fn(usize) -> &'a [Run]) -> Result<(Vec<usize>, Vec<Run>)> {
    // (column, first row, last row) of every run of the transpose, in the order they close.
    let mut closed: Vec<(u32, u32, u32)> = Vec::new();
    let mut open_since: Vec<u32> = try_filled(rows, 0, "the transposed runs of S_gamma")?;
    let empty: &[Run] = &[];
    let mut previous = empty;
    for r in 0..=rows {
        let current = if r < rows { row(r) } else { empty };
        // Columns in the previous row only close a run (ending at r − 1); in this row only,
        // open one.
        for_each_difference(previous, current, |c| {
            try_reserve(&mut closed, 1, "the transposed runs of S_gamma")?;
            closed.push((c, open_since[c as usize], r as u32 - 1));
            Ok(())
        })?;
        for_each_difference(current, previous, |c| {
            open_since[c as usize] = r as u32;
            Ok(())
        })?;
        previous = current;
    }
    // Counting sort by column, keeping each column's runs in row order.
    let mut offsets = try_filled(rows + 1, 0_usize, "the transposed runs of S_gamma")?;
    for &(c, _, _) in &closed {
        offsets[c as usize + 1] += 1;
    }
    for k in 0..rows {
        offsets[k + 1] += offsets[k];
    }
    let mut next = offsets.clone();
    let mut runs = try_filled(closed.len(), Run { start: 0, end: 0 }, "the transposed runs of S_gamma")?;
    for (c, start, end) in closed {
        runs[next[c as usize]] = Run { start, end };
        next[c as usize] += 1;
    }
    Ok((offsets, runs))
}

/// Calls `f(c)` for every column c covered by the runs of `a` and not by those of `b` (both
/// sorted and apart), in increasing order. O(runs + the columns reported).
fn for_each_difference(a: &[Run], b: &[Run], mut f: impl FnMut(u32) -> Result<()>) -> Result<()> {
    let mut q = 0;
    for run in a {
        let (mut c, end) = (u64::from(run.start), u64::from(run.end));
        while q < b.len() && u64::from(b[q].end) < c {
            q += 1;
        }
        let mut k = q;
        while c <= end {
            let (gap_end, next) = match b.get(k) {
                Some(other) if u64::from(other.start) <= end => (u64::from(other.start), u64::from(other.end) + 1),
                _ => (end + 1, end + 1),
            };
            for column in c..gap_end.max(c) {
                f(column as u32)?;
            }
            c = c.max(next);
            k += 1;
        }
    }
    Ok(())
}

/// `M` with its arguments swapped: the online engine's row n measures its pairs (j, n) as
/// δ(x_j, x_n), the batch's order (earlier pose first), bit for bit even for metrics whose
/// rounding is not symmetric (angle wraps).
struct Swapped<'a, M: ?Sized>(&'a M);

impl<M: Metric + ?Sized> Metric for Swapped<'_, M> {
    fn name(&self) -> String {
        self.0.name()
    }

    fn check_dim(&self, dim: usize) -> Result<()> {
        self.0.check_dim(dim)
    }

    /// As `M`'s: the squared differences of coordinates are the same bit for bit either way.
    fn is_coordinate_euclidean(&self) -> bool {
        self.0.is_coordinate_euclidean()
    }

    #[inline]
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.0.distance(b, a)
    }

    #[inline]
    fn distance_2d(&self, a: &[f64; 2], b: &[f64; 2]) -> f64 {
        self.0.distance_2d(b, a)
    }

    #[inline]
    fn distance_3d(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
        self.0.distance_3d(b, a)
    }

    #[inline]
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        self.0.distance_rank(b, a)
    }

    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        if self.0.is_coordinate_euclidean() {
            // Squared differences are symmetric bit for bit: the fast path.
            return self.0.closest_in(x, points);
        }
        let mut best = (f64::INFINITY, 0);
        for (k, p) in points.chunks_exact(x.len()).enumerate() {
            let rank = self.0.distance_rank(p, x);
            if rank < best.0 {
                best = (rank, k);
            }
        }
        best.1
    }
}

/// Sums over ranges of poses that grow at the end: a Fenwick tree over a difference array
/// (range addition, point value in O(log n); a new pose in O(log n)).
#[derive(Debug, Clone, Default)]
struct RangeSums {
    /// 1-based: `tree[k]` sums the differences of positions (k − lowbit(k), k].
    tree: Vec<f64>,
}

impl RangeSums {
    /// Appends a position with value 0.
    fn push(&mut self) {
        if self.tree.is_empty() {
            self.tree.push(0.0);
        }
        let k = self.tree.len();
        let below = k - (k & k.wrapping_neg());
        let value = self.prefix(k - 1) - self.prefix(below);
        self.tree.push(value);
    }

    /// Adds `value` to positions `a..=b`.
    fn add(&mut self, a: usize, b: usize, value: f64) {
        self.add_from(a, value);
        self.add_from(b + 1, -value);
    }

    fn add_from(&mut self, position: usize, value: f64) {
        let mut k = position + 1;
        while k < self.tree.len() {
            self.tree[k] += value;
            k += k & k.wrapping_neg();
        }
    }

    /// The value at `position`.
    fn at(&self, position: usize) -> f64 {
        self.prefix(position + 1)
    }

    /// Σ of the differences of positions `0..k`.
    fn prefix(&self, k: usize) -> f64 {
        let mut sum = 0.0;
        let mut k = k;
        while k > 0 {
            sum += self.tree[k];
            k -= k & k.wrapping_neg();
        }
        sum
    }
}

/// `error` about the pose at `index` of a batch of new poses, renamed for the pose at
/// `first + index` of the whole trajectory.
fn shift_pose_index(error: Error, first: usize) -> Error {
    match error {
        Error::NonFiniteTimestamp { index, value } => Error::NonFiniteTimestamp { index: first + index, value },
        Error::TimestampTooLarge { index, value, max } => Error::TimestampTooLarge { index: first + index, value, max },
        Error::TimestampsNotIncreasing { index, previous_s, value_s } => {
            Error::TimestampsNotIncreasing { index: first + index, previous_s, value_s }
        }
        Error::NonUnitQuaternion { index, norm } => Error::NonUnitQuaternion { index: first + index, norm },
        Error::NonUnitVector { index, norm } => Error::NonUnitVector { index: first + index, norm },
        Error::LatitudeOutOfRange { index, value_deg } => Error::LatitudeOutOfRange { index: first + index, value_deg },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

    /// The Euclidean metric, counting the distances measured and the ranks taken.
    #[derive(Default)]
    struct Counting(AtomicU64);

    impl Metric for Counting {
        fn name(&self) -> String {
            Euclidean.name()
        }
        fn check_dim(&self, dim: usize) -> Result<()> {
            Euclidean.check_dim(dim)
        }
        fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
            self.0.fetch_add(1, Relaxed);
            Euclidean.distance(a, b)
        }
        fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
            self.0.fetch_add(1, Relaxed);
            Euclidean.distance_rank(a, b)
        }
        fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
            self.0.fetch_add((points.len() / x.len()) as u64, Relaxed);
            Euclidean.closest_in(x, points)
        }
    }

    /// Two stops of 4,000 identical poses each, 10⁻¹⁴ m, γ and one ulp beyond γ apart, joined by
    /// a drive out and back: each push of the second stop measures a bounded number of distances
    /// per row and run. The engine once ranked every pose of the first stop for each of them.
    #[test]
    fn a_second_stop_at_one_place_costs_a_bounded_number_of_distances_per_push() {
        let gamma: f64 = 1.5;
        let stop = 4000;
        let mut costs = Vec::new();
        for offset in [0.0, 1e-14, gamma, gamma.next_up()] {
            let mut points = vec![[0.0, 0.0]; stop];
            points.extend((1..42).map(|s: i32| [offset, f64::from(21 - (21 - s).abs()) * gamma / 7.0]));
            points.extend(vec![[offset, 0.0]; stop]);
            let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, gamma).unwrap();
            let counting = Counting::default();
            let (mut rows, mut runs) = (0, 0);
            for (n, point) in points.iter().enumerate() {
                let t_s = n as f64 * 0.1;
                online.check_new_poses(&[t_s], point).unwrap();
                online.traj.push_pose(t_s, point);
                let before = counting.0.load(Relaxed);
                let mut update = Update::default();
                online.add_row(&counting, n, &mut update);
                if n >= stop + 41 {
                    rows += 1;
                    runs += update.runs.len() as u64;
                } else {
                    // The first stop and the drive are not counted.
                    counting.0.store(before, Relaxed);
                }
            }
            costs.push((offset, counting.0.load(Relaxed) as f64 / (rows + runs) as f64));
        }
        assert!(costs.iter().all(|&(_, per_run)| per_run <= 64.0), "(offset, per row and run): {costs:?}");
    }
}
