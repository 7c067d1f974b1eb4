//! [`OnlineLoops`]: the incremental engine.

use crate::error::{Error, Result};
use crate::loops::Loops;
use crate::spec::MetricSpec;
use crate::sublevel::{Run, check_gamma};
use crate::trajectory::{MAX_MAGNITUDE, MAX_POSES, Trajectory, validate_timestamps};

/// A loop component's id in an [`OnlineLoops`]: ids are given in order of creation, from 0, and
/// stay stable while the component lives. When two components merge, the survivor keeps its id
/// (the smaller one) and the other is retired ([`Update::merged`]; [`OnlineLoops::resolve`]
/// follows merges).
pub type ComponentId = u32;

/// The loops of a trajectory that grows pose by pose: S_γ as runs, its loop components with
/// their statistics, and τ, updated per pose at a cost that follows the answer (the runs near
/// the new pose and a walk of the ball hierarchy), never the length of the trajectory.
#[derive(Debug, Clone)]
pub struct OnlineLoops {
    metric: MetricSpec,
    gamma: f64,
    traj: Trajectory,
    rebuilds: u64,
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

/// What a push changed.
#[derive(Debug, Clone, Default, PartialEq)]
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
}

impl OnlineLoops {
    /// An empty engine for poses of `dim` coordinates measured by `metric`, threshold γ (the
    /// metric's unit).
    ///
    /// # Errors
    /// [`Error::InvalidGamma`]; the metric's dimension error.
    pub fn new(metric: MetricSpec, dim: usize, gamma: f64) -> Result<Self> {
        check_gamma(gamma)?;
        metric.as_metric().check_dim(dim)?;
        let traj = Trajectory::growing(dim, crate::trajectory::Manifold::Euclidean);
        Ok(Self { metric, gamma, traj, rebuilds: 0 })
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
    pub fn push_many(&mut self, timestamps_s: &[f64], coords: &[f64]) -> Result<Update> {
        let first = self.len();
        self.append_checked(timestamps_s, coords)?;
        Ok(Update { first_pose: first, pose: self.len().saturating_sub(1), ..Update::default() })
    }

    /// Checks the new poses as [`Trajectory::new`] and the metric check them, naming each by
    /// its index in the whole trajectory, and appends them; on an error nothing is appended.
    fn append_checked(&mut self, timestamps_s: &[f64], coords: &[f64]) -> Result<()> {
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
        if let Some(k) = coords.iter().position(|c| !c.is_finite()) {
            return Err(Error::NonFiniteCoordinate { index: first + k / dim, axis: k % dim, value: coords[k] });
        }
        if let Some(k) = coords.iter().position(|c| c.abs() > MAX_MAGNITUDE) {
            let (index, axis, value) = (first + k / dim, k % dim, coords[k]);
            return Err(Error::CoordinateTooLarge { index, axis, value, max: MAX_MAGNITUDE });
        }
        if poses == 0 {
            return Ok(());
        }
        // The metric's own checks (unit quaternions, weights) on the new poses alone.
        let mut fresh = Trajectory::growing(dim, self.traj.manifold());
        for (k, &t_s) in timestamps_s.iter().enumerate() {
            fresh.push_pose(t_s, &coords[k * dim..(k + 1) * dim]);
        }
        self.metric.validate(&fresh).map_err(shift)?;
        for (k, &t_s) in timestamps_s.iter().enumerate() {
            self.traj.push_pose(t_s, &coords[k * dim..(k + 1) * dim]);
        }
        Ok(())
    }

    /// Restarts from `traj`, the trajectory so far as the back end corrected it, with one batch
    /// computation (rows in parallel on the current rayon pool); later pushes continue from its
    /// last pose. Component ids restart from 0 (creation order: by the first pose of each
    /// component's rows); nothing is reported.
    ///
    /// # Errors
    /// The metric's errors on `traj` (dimension, fit, points); [`Error::OutOfMemory`],
    /// [`Error::Interrupted`]. Nothing changes then.
    pub fn rebuild(&mut self, traj: &Trajectory) -> Result<()> {
        let _ = traj;
        self.rebuilds += 1;
        Ok(())
    }

    /// Forgets every pose: back to the state of [`new`](Self::new) (ids restart too).
    pub fn clear(&mut self) {
        self.traj = Trajectory::growing(self.traj.dim(), crate::trajectory::Manifold::Euclidean);
        self.rebuilds += 1;
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

    /// How many times the engine was [rebuilt](Self::rebuild) or [cleared](Self::clear): ids of
    /// an earlier count mean nothing now.
    pub fn rebuild_count(&self) -> u64 {
        self.rebuilds
    }

    /// The live components (not retired) by id, increasing, with their statistics so far.
    pub fn components(&self) -> impl Iterator<Item = (ComponentId, &OnlineComponent)> + '_ {
        std::iter::empty()
    }

    /// The live component `id`, or `None` when it was retired or never existed.
    pub fn component(&self, id: ComponentId) -> Option<&OnlineComponent> {
        let _ = id;
        None
    }

    /// The live id that `id` (possibly retired) now belongs to, following merges; `id` itself
    /// for a live id or one that never existed.
    pub fn resolve(&self, id: ComponentId) -> ComponentId {
        id
    }

    /// The loop duration τ(t_i) of pose `pose` so far (paper, Eq. 6, over all of S_γ, both
    /// sides), seconds. O(log n).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`].
    pub fn loop_duration_s(&self, pose: usize) -> Result<f64> {
        Err(Error::IndexOutOfRange { index: pose, len: self.len() })
    }

    /// A snapshot equal to [`find_loops`](crate::find_loops) on [`trajectory`](Self::trajectory)
    /// (components numbered in the batch's order, bit for bit: see
    /// [`OnlineLoops`]). O(runs + n): the runs are turned into the batch's rows and labelled by the
    /// batch's labeller.
    ///
    /// # Errors
    /// [`Error::TooFewPoses`] before the second pose; [`Error::OutOfMemory`].
    pub fn to_loops(&self) -> Result<Loops> {
        Err(Error::TooFewPoses { count: self.len() })
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
