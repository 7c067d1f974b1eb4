//! [`find_loops`]: the sublevel set, its loop components and the measures over them.

use std::fmt;

use rayon::prelude::*;

use crate::component::{LoopComponent, label_components};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::measure::{Scale, Selection, Side, integrate_s, loop_duration_s};
use crate::memory::{try_copy_parallel, try_reserve};
use crate::metric::Metric;
use crate::separation::Separation;
use crate::spec::{MetricSpec, recorded_metric_name, with_metric};
use crate::sublevel::{PhaseTimer, SublevelSet};
use crate::trajectory::{Timeline, Trajectory, cell_of, sealed};

/// Something worth telling the user about a result that is still correct.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Warning {
    /// Consecutive poses farther apart than γ: the diagonal of S_γ breaks, and there is more than
    /// one trivial component (usually a data gap, or γ below the step length).
    DiagonalBroken {
        /// Number of consecutive pairs (i, i + 1) with δ > γ.
        gaps: usize,
        /// The first such i.
        first_gap: usize,
        /// The largest such δ.
        largest_step: f64,
        /// Number of trivial components.
        trivial_components: usize,
    },
    /// No revisit at all: a separation was asked for, and no pair within γ keeps it.
    NoLoops {
        /// The threshold γ.
        gamma: f64,
        /// The separation the pairs had to keep.
        separation: Separation,
    },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DiagonalBroken { gaps, first_gap, largest_step, trivial_components } => write!(
                f,
                "{gaps} consecutive pose pair(s) are farther apart than gamma (first at index {first_gap}, \
                 largest step {largest_step:.6}): the diagonal of S_gamma is broken there, and S_gamma has \
                 {trivial_components} trivial component(s)"
            ),
            Self::NoLoops { gamma, separation } => write!(
                f,
                "no revisit at gamma {gamma} with separation {separation}: no pair within gamma is that far \
                 apart along the trajectory; try a larger gamma or a smaller separation"
            ),
        }
    }
}

/// One run of S_γ's upper half (row `row`, columns `start..=end`, `row ≤ start`) and the loop
/// component it belongs to, as [`Loops::runs`] yields them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LabelledRun {
    /// Row: pose index i (time t).
    pub row: usize,
    /// First column: pose index j (time t′), inclusive.
    pub start: usize,
    /// Last column, inclusive.
    pub end: usize,
    /// Id of its component in [`Loops::components`].
    pub component: usize,
}

impl LabelledRun {
    /// Number of cells (i, j) of the run.
    pub fn len(&self) -> usize {
        self.end - self.start + 1
    }

    /// Never: a run has at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Inexact loops of a trajectory at one γ: S_γ as runs, its loop components, and the measures.
///
/// Memory is proportional to the number of runs, never to the number of pairs.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "LoopsState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct Loops {
    gamma: f64,
    separation: Separation,
    metric: String,
    timestamps_s: Vec<f64>,
    cell_widths_s: Vec<f64>,
    set: SublevelSet,
    labels: Vec<u32>,
    components: Vec<LoopComponent>,
    warnings: Vec<Warning>,
}

/// Finds every inexact loop of `traj` under `metric` at threshold `gamma` (the metric's unit),
/// exactly, and partitions them into loop components.
///
/// Runs on the current rayon pool (wrap in `ThreadPool::install` to choose the thread count);
/// the result does not depend on the number of threads. Time is about the number of times the
/// path passes near itself, times a logarithm, plus the number of runs; memory O(runs).
///
/// # Errors
/// [`Error::InvalidGamma`] unless `gamma` is positive and finite; the metric's dimension error;
/// [`Error::OutOfMemory`] when the answer, or a buffer of the engine that grows with the input,
/// does not fit in memory (naming the size it needs);
/// [`Error::Interrupted`] when an [`Interrupt`] installed on this thread is interrupted.
///
/// # Examples
/// A 95% circle of radius 10 m: its ends come within 3.1 m of each other.
/// ```
/// use loops_core::{Euclidean, Trajectory, find_loops};
/// let n = 200;
/// let angle = |i: usize| 0.95 * std::f64::consts::TAU * i as f64 / (n - 1) as f64;
/// let points: Vec<[f64; 2]> = (0..n).map(|i| [10.0 * angle(i).cos(), 10.0 * angle(i).sin()]).collect();
/// let traj = Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &points)?;
/// let loops = find_loops(&traj, &Euclidean, 4.0)?;
/// assert_eq!(loops.components().len(), 2); // the trivial one and the loop at (0, 1)
/// assert!(loops.components()[0].trivial && !loops.components()[1].trivial);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn find_loops<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, gamma: f64) -> Result<Loops> {
    find_loops_separated(traj, metric, gamma, Separation::NONE)
}

/// Finds the *revisits* of `traj`: the loops whose two poses also lie `separation` apart along
/// the trajectory (the subset X ⊆ S_γ of [`Separation`]), exactly, with their components,
/// holes and measures. Pairs that odometry already ties together are left out, and no
/// component is trivial. Same cost as [`find_loops`], or less: the scan of each row starts at
/// its first separated column. With [`Separation::NONE`], exactly [`find_loops`].
///
/// # Errors
/// As [`find_loops`]; [`Error::InvalidSeparation`] unless both bounds are finite and ≥ 0.
///
/// # Examples
/// 1.9 laps of a circle, 200 poses a lap: one revisit component, the second lap along the first.
/// ```
/// use loops_core::{Euclidean, Separation, Trajectory, find_loops_separated};
/// let n = 380;
/// let angle = |i: usize| std::f64::consts::TAU * i as f64 / 200.0;
/// let points: Vec<[f64; 2]> = (0..n).map(|i| [10.0 * angle(i).cos(), 10.0 * angle(i).sin()]).collect();
/// let traj = Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &points)?;
/// let loops = find_loops_separated(&traj, &Euclidean, 2.0, Separation::for_gamma(2.0))?;
/// assert_eq!(loops.components().len(), 1);
/// let lap = loops.components()[0].closest_pair;
/// assert_eq!(lap[1] - lap[0], 200);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn find_loops_separated<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    gamma: f64,
    separation: Separation,
) -> Result<Loops> {
    let set = SublevelSet::compute_separated(traj, metric, gamma, separation)?;
    Loops::try_from_set(traj, metric, set)
}

impl sealed::Sealed for Loops {}

impl Timeline for Loops {
    fn pose_times_s(&self) -> &[f64] {
        self.timestamps_s()
    }
}

impl MetricSpec {
    /// [`find_loops`] under this metric, dispatched once so the engine's loops stay monomorphic.
    ///
    /// # Errors
    /// As [`find_loops`].
    pub fn find_loops(&self, traj: &Trajectory, gamma: f64) -> Result<Loops> {
        with_metric!(self, m => find_loops(traj, m, gamma))
    }

    /// [`find_loops_separated`] under this metric.
    ///
    /// # Errors
    /// As [`find_loops_separated`].
    pub fn find_loops_separated(&self, traj: &Trajectory, gamma: f64, separation: Separation) -> Result<Loops> {
        with_metric!(self, m => find_loops_separated(traj, m, gamma, separation))
    }

    /// [`path_length`](crate::path_length) under this metric.
    ///
    /// # Errors
    /// The metric's dimension error; [`Error::OutOfMemory`].
    pub fn path_length(&self, traj: &Trajectory) -> Result<Vec<f64>> {
        self.validate(traj)?;
        with_metric!(self, m => crate::sublevel::try_path_length(traj, m))
    }
}

impl Loops {
    /// Labels and measures an already computed sublevel set of `traj` under `metric`.
    ///
    /// # Panics
    /// If `set` has a different number of rows than `traj` has poses; where
    /// [`try_from_set`](Self::try_from_set) returns an error.
    pub fn from_set<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, set: SublevelSet) -> Self {
        Self::try_from_set(traj, metric, set).unwrap_or_else(|error| panic!("{error}"))
    }

    /// [`from_set`](Self::from_set), with the components and copies allocated fallibly and an
    /// [`Interrupt`] installed on this thread watched.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`], [`Error::Interrupted`].
    ///
    /// # Panics
    /// If `set` has a different number of rows than `traj` has poses.
    pub fn try_from_set<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, set: SublevelSet) -> Result<Self> {
        assert_eq!(set.rows(), traj.len(), "sublevel set and trajectory differ in length");
        let labelling = label_components(traj, metric, &set, &Interrupt::current())?;
        let _timer = PhaseTimer::start("result: diagonal gaps and copies, parallel");
        let n = traj.len();
        // A row whose first run does not reach column i + 1 breaks the diagonal (a metric that
        // breaks δ(x, x) = 0 may even leave the diagonal cell out).
        // A separated set has no diagonal to break.
        let separation = set.separation();
        let broken = |i: &usize| !set.breaks_after(*i) && set.row(*i).first().is_none_or(|r| (r.end as usize) <= *i);
        let mut gaps: Vec<usize> = Vec::new();
        if separation.is_none() {
            let count = (0..n - 1).into_par_iter().filter(broken).count();
            if count > 0 {
                try_reserve(&mut gaps, count, "the gaps of the diagonal")?;
                gaps.extend((0..n - 1).filter(broken));
            }
        }
        let mut warnings = Vec::new();
        if let Some(&first_gap) = gaps.first() {
            let largest_step =
                gaps.iter().map(|&i| metric.distance(traj.point(i), traj.point(i + 1))).fold(0.0, f64::max);
            let trivial_components = labelling.components.iter().filter(|c| c.trivial).count();
            warnings.push(Warning::DiagonalBroken { gaps: gaps.len(), first_gap, largest_step, trivial_components });
        }
        // Without a separation the trivial components always remain, and the paper's answer
        // stays as it was; an empty sample is the samplers' warning.
        if !separation.is_none() && labelling.components.is_empty() {
            warnings.push(Warning::NoLoops { gamma: set.gamma(), separation });
        }
        Ok(Self {
            gamma: set.gamma(),
            separation,
            metric: recorded_metric_name(metric),
            timestamps_s: try_copy_parallel(traj.timestamps_s(), "the timestamps of the loops")?,
            cell_widths_s: try_copy_parallel(traj.cell_widths_s(), "the time cells of the loops")?,
            labels: labelling.labels,
            components: labelling.components,
            set,
            warnings,
        })
    }

    /// The threshold γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The separation its pairs keep ([`Separation::NONE`]: the paper's S_γ).
    pub fn separation(&self) -> Separation {
        self.separation
    }

    /// Whether these are revisits: a separation was asked for, so no component is trivial.
    pub fn is_separated(&self) -> bool {
        !self.separation.is_none()
    }

    /// The metric's name, as [`recorded_metric_name`] gives it: a
    /// [`MetricSpec`](crate::MetricSpec)'s, which parses back, or `custom(NAME)` for a metric of
    /// the caller's own.
    pub fn metric_name(&self) -> &str {
        &self.metric
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.timestamps_s.len()
    }

    /// Never: a trajectory has at least two poses.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Timestamps of the trajectory, seconds.
    pub fn timestamps_s(&self) -> &[f64] {
        &self.timestamps_s
    }

    /// `t_{n−1} − t_0`, seconds.
    pub fn span_s(&self) -> f64 {
        self.timestamps_s[self.len() - 1] - self.timestamps_s[0]
    }

    /// The loop components, by id.
    pub fn components(&self) -> &[LoopComponent] {
        &self.components
    }

    /// The sublevel set as runs.
    pub fn sublevel_set(&self) -> &SublevelSet {
        &self.set
    }

    /// Warnings about the result (e.g. a broken diagonal).
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The component id of each run of [`sublevel_set`](Self::sublevel_set).
    pub fn run_components(&self) -> &[u32] {
        &self.labels
    }

    /// Every run of the upper half with its component, row after row, columns increasing.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Euclidean, LabelledRun, Trajectory, find_loops};
    /// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0], [5.0], [0.0]])?;
    /// let loops = find_loops(&traj, &Euclidean, 1.0)?;
    /// let first = loops.runs().next();
    /// assert_eq!(first, Some(LabelledRun { row: 0, start: 0, end: 0, component: 0 }));
    /// assert_eq!(loops.runs().count(), 4); // (0, 0), (0, 2), (1, 1), (2, 2)
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn runs(&self) -> impl Iterator<Item = LabelledRun> + '_ {
        (0..self.len()).flat_map(move |i| {
            let offset = self.set.row_offset(i);
            self.set.row(i).iter().enumerate().map(move |(k, run)| LabelledRun {
                row: i,
                start: run.start as usize,
                end: run.end as usize,
                component: self.labels[offset + k] as usize,
            })
        })
    }

    /// Checks that `traj` is the trajectory these loops were found on: the same timestamps
    /// (points are not compared). O(poses).
    ///
    /// # Errors
    /// [`Error::TrajectoryMismatch`] naming the first pose whose time differs, or the pose counts.
    pub fn check_trajectory(&self, traj: &Trajectory) -> Result<()> {
        let (a, b) = (traj.timestamps_s(), self.timestamps_s());
        let differ = a.iter().zip(b).position(|(x, y)| x != y);
        match differ {
            None if a.len() == b.len() => Ok(()),
            _ => Err(Error::TrajectoryMismatch {
                what: "trajectory",
                index: differ.unwrap_or(a.len().min(b.len())),
                poses: a.len(),
                loops_poses: b.len(),
            }),
        }
    }

    /// Checks that `index` is a pose index.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] when it is not.
    pub fn check_index(&self, index: usize) -> Result<()> {
        if index < self.len() { Ok(()) } else { Err(Error::IndexOutOfRange { index, len: self.len() }) }
    }

    /// The component holding the pair (i, j) (either order), or `None` when δ(x_i, x_j) > γ or,
    /// with a [`Separation`], when the pair is not that far apart.
    /// O(log runs in the row).
    ///
    /// # Panics
    /// When `i` or `j` is not a pose index (see [`check_index`](Self::check_index)), as slice
    /// indexing does: `None` always means "not in S_γ".
    pub fn component_of(&self, i: usize, j: usize) -> Option<usize> {
        assert!(i < self.len() && j < self.len(), "pose index ({i}, {j}) out of range for {} poses", self.len());
        self.set.run_index(i, j).map(|r| self.labels[r] as usize)
    }

    /// Whether (i, j) is a *simple loop*: a pair in a trivial component.
    ///
    /// # Panics
    /// As [`component_of`](Self::component_of).
    pub fn is_simple(&self, i: usize, j: usize) -> bool {
        self.component_of(i, j).is_some_and(|c| self.components[c].trivial)
    }

    /// Number of lattice cells of S_γ in the full (t, t′) plane, both halves: (i, j) and
    /// (j, i) are two cells. Summaries count [`pose_pair_count`](Self::pose_pair_count).
    pub fn pair_count(&self) -> u64 {
        2 * self.set.upper_pairs() - self.diagonal_cells()
    }

    /// Number of pose pairs {i, j}, i < j, of S_γ: unordered pairs of distinct poses within γ
    /// (the upper half without the diagonal). The one count of pairs the summaries, reports and
    /// the component tables print ([`LoopComponent::pose_pair_count`] sums to it), and what the
    /// samplers draw from. O(n).
    pub fn pose_pair_count(&self) -> u64 {
        self.set.upper_pairs() - self.diagonal_cells()
    }

    /// The diagonal cells (i, i) of S_γ (every pose, without a separation).
    fn diagonal_cells(&self) -> u64 {
        (0..self.len()).filter(|&i| self.set.row(i).first().is_some_and(|r| r.start as usize == i)).count() as u64
    }

    /// Loop duration τ_X(t_i) for every sample (paper, Eq. 6): how long the trajectory stays
    /// within γ of ξ(t_i), restricted to X and to one `side`. Seconds, or fractions of the span
    /// with [`Scale::Normalized`]. O(runs + n).
    ///
    /// # Errors
    /// [`Error::UnknownComponent`] for an id that does not exist.
    pub fn loop_duration(&self, selection: Selection<'_>, side: Side, scale: Scale) -> Result<Vec<f64>> {
        let keep = self.selection_mask(selection)?;
        let mut tau = loop_duration_s(&self.cell_widths_s, &self.set, |r| keep(self.labels[r] as usize), side)?;
        if scale == Scale::Normalized {
            let span = self.span_s();
            tau.iter_mut().for_each(|t| *t /= span);
        }
        Ok(tau)
    }

    /// Loop area α_X(a, b) = ∫_a^b τ_X(t) dt (paper, Eq. 7): the area of X over t ∈ [a, b] in the
    /// (t, t′) plane. `a`, `b` and the result in seconds and s², or in the normalized units.
    ///
    /// # Errors
    /// [`Error::InvalidInterval`] unless `a < b`, both finite; [`Error::UnknownComponent`].
    pub fn loop_area(&self, a: f64, b: f64, selection: Selection<'_>, side: Side, scale: Scale) -> Result<f64> {
        if !(a.is_finite() && b.is_finite() && a < b) {
            return Err(Error::InvalidInterval { a, b });
        }
        let tau = self.loop_duration(selection, side, Scale::Seconds)?;
        // Integrate on the clock of the first pose: exact differences, no epoch rounding.
        let (t0, span) = (self.timestamps_s[0], self.span_s());
        let relative: Vec<f64> = self.timestamps_s.iter().map(|t| t - t0).collect();
        let (a_rel, b_rel) = match scale {
            Scale::Seconds => (a - t0, b - t0),
            Scale::Normalized => (a * span, b * span),
        };
        let area_s2 = integrate_s(&tau, |i| cell_of(&relative, i), a_rel, b_rel);
        Ok(match scale {
            Scale::Seconds => area_s2,
            Scale::Normalized => area_s2 / (span * span),
        })
    }

    /// Loop density ρ_X(a, b) = α_X(a, b) / (b − a) (paper, Eq. 8): the mean loop duration over
    /// [a, b]. Seconds, or normalized.
    ///
    /// # Errors
    /// As [`loop_area`](Self::loop_area).
    pub fn loop_density(&self, a: f64, b: f64, selection: Selection<'_>, side: Side, scale: Scale) -> Result<f64> {
        Ok(self.loop_area(a, b, selection, side, scale)? / (b - a))
    }

    fn selection_mask(&self, selection: Selection<'_>) -> Result<impl Fn(usize) -> bool + Sync + use<>> {
        let count = self.components.len();
        let mask = match selection {
            Selection::All => vec![true; count],
            Selection::Components(ids) => {
                let mut mask = vec![false; count];
                for &id in ids {
                    *mask.get_mut(id).ok_or(Error::UnknownComponent { id, count })? = true;
                }
                mask
            }
        };
        Ok(move |c: usize| mask[c])
    }
}

/// What a serialised [`Loops`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct LoopsState {
    gamma: f64,
    separation: Separation,
    metric: String,
    timestamps_s: Vec<f64>,
    cell_widths_s: Vec<f64>,
    set: SublevelSet,
    labels: Vec<u32>,
    components: Vec<LoopComponent>,
    warnings: Vec<Warning>,
}

#[cfg(feature = "serde")]
impl TryFrom<LoopsState> for Loops {
    type Error = Error;

    /// Checks the timestamps (as a trajectory's) and time cells, the metric's name (as
    /// [`recorded_metric_name`] gives one), the sublevel set, and that every run's label
    /// names a component and every component's indices are pose indices.
    fn try_from(state: LoopsState) -> Result<Self> {
        let invalid = |reason: String| Error::InvalidState { what: "Loops", reason };
        let n = state.timestamps_s.len();
        crate::trajectory::validate_timestamps(&state.timestamps_s)?;
        if n != state.set.rows() {
            return Err(invalid(format!("{n} timestamps but {} rows of S_gamma", state.set.rows())));
        }
        if state.gamma != state.set.gamma() || state.separation != state.set.separation() {
            return Err(invalid(format!(
                "gamma {} and separation {} differ from its S_gamma's",
                state.gamma, state.separation
            )));
        }
        if state.labels.len() != state.set.runs().len() {
            return Err(invalid(format!("{} labels for {} runs", state.labels.len(), state.set.runs().len())));
        }
        crate::spec::check_recorded_metric_name(&state.metric).map_err(invalid)?;
        let count = state.components.len();
        if let Some(r) = state.labels.iter().position(|&c| c as usize >= count) {
            return Err(invalid(format!("run {r} belongs to component {}, of {count}", state.labels[r])));
        }
        for (k, c) in state.components.iter().enumerate() {
            let indices = c.i_range.iter().chain(&c.j_range).chain(&c.closest_pair);
            if c.id != k || indices.clone().any(|&i| i >= n) {
                return Err(invalid(format!(
                    "component {k} has id {}, rows {:?}, columns {:?} and closest pair {:?}, of {n} poses",
                    c.id, c.i_range, c.j_range, c.closest_pair
                )));
            }
        }
        let LoopsState { gamma, separation, metric, timestamps_s, cell_widths_s, set, labels, components, warnings } =
            state;
        let cell_widths_s = crate::trajectory::checked_cell_widths("Loops", cell_widths_s, &timestamps_s)?;
        Ok(Self { gamma, separation, metric, timestamps_s, cell_widths_s, set, labels, components, warnings })
    }
}
