//! What a sampler returns: [`Sample`] rows and the [`Samples`] with what the sampler knew.

use super::SamplerKind;
use crate::detection::place_detection;
use crate::draw::SampleWarning;
use crate::error::{Error, Result};
use crate::loops::Loops;
use crate::metric::Metric;
use crate::spec::check_fits;
use crate::trajectory::Trajectory;

// The memory estimate of a draw that is too big counts at least one and a half rows a sample.
const _: () = assert!(3 * size_of::<Sample>() as u64 / 2 <= crate::draw::SAMPLE_BYTES);

/// One sampled loop: a candidate pair for the scan matcher.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Pose indices (i, j), i ≤ j, when known (always from [`sample_loops`](crate::sample_loops); from
    /// [`sample_clusters`](crate::sample_clusters) when the detections are placed on a trajectory).
    pub pair: Option<[usize; 2]>,
    /// The earlier time, seconds (the detection's own time for detections).
    pub t_s: f64,
    /// The later time, seconds.
    pub t_prime_s: f64,
    /// The exact loop component holding (i, j), when known.
    pub component: Option<usize>,
    /// The detection cluster it was drawn from (detections only).
    pub cluster: Option<usize>,
    /// The index of the detection (detections only).
    pub detection: Option<usize>,
    /// δ(x_i, x_j) in the metric's unit, when measured.
    pub distance: Option<f64>,
    /// The detection's score, when it has one.
    pub score: Option<f64>,
    /// The pose of x_j in the frame of x_i that the trajectory predicts ([`relative_pose`](crate::relative_pose)):
    /// the scan matcher's initial guess. `None` without a pose pair, or on a manifold without
    /// such a guess. No uncertainty goes with it: trajectories hold no covariance.
    pub relative_pose: Option<crate::RelativePose>,
    /// Where its two poses are, `[x, y, z]` of pose i then of pose j, when its caller said
    /// ([`set_positions`](Samples::set_positions)).
    #[cfg_attr(feature = "serde", serde(default))]
    pub positions: Option<[[f64; 3]; 2]>,
    /// The sampler that chose it.
    pub sampler: SamplerKind,
}

/// The samples a sampler chose, in order of (t, t′), with what it knew.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "SamplesState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    sampler: SamplerKind,
    rows: Vec<Sample>,
    groups: usize,
    available: u64,
    poses: Option<usize>,
    pub(super) warnings: Vec<SampleWarning>,
}

impl Samples {
    /// The samples, ordered by (t, t′).
    pub fn rows(&self) -> &[Sample] {
        &self.rows
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there are none (a baseline may find nothing).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The sampler.
    pub fn sampler(&self) -> SamplerKind {
        self.sampler
    }

    /// Number of groups sampled from (clusters or components with a pair to sample; 0 for σ_α
    /// and the baselines, which do not group).
    pub fn groups(&self) -> usize {
        self.groups
    }

    /// Number of candidates the sampler chose from (detections, pairs, or the rule's pairs).
    pub fn available(&self) -> u64 {
        self.available
    }

    /// Number of poses of the trajectory the pairs index, when known.
    pub fn poses(&self) -> Option<usize> {
        self.poses
    }

    /// Warnings (budget below the number of groups, or above the candidates).
    pub fn warnings(&self) -> &[SampleWarning] {
        &self.warnings
    }

    /// Fills in pose pairs (placing times on the nearest poses where missing) and the exact
    /// component of every sample. O(samples · log).
    ///
    /// # Errors
    /// [`Error::TrajectoryMismatch`] when the samples index another trajectory;
    /// [`Error::DetectionOutsideSpan`] for a time outside the loops' trajectory.
    pub fn locate(&mut self, loops: &Loops) -> Result<()> {
        let pairs = self.pairs_on(loops.timestamps_s())?;
        for (row, pair) in self.rows.iter_mut().zip(pairs) {
            row.pair = Some(pair);
            row.component = loops.component_of(pair[0], pair[1]);
        }
        self.poses = Some(loops.len());
        Ok(())
    }

    /// Sets the relative pose of every sample with a pose pair `(i, j)` to `guess(i, j)`: for
    /// a caller that holds the poses in another form than the trajectory sampled (orientations
    /// kept beside positions measured alone), so every output of a pair gives one guess.
    /// O(samples) calls.
    pub fn set_relative_poses(&mut self, mut guess: impl FnMut(usize, usize) -> Option<crate::RelativePose>) {
        for row in &mut self.rows {
            row.relative_pose = row.pair.and_then(|[i, j]| guess(i, j));
        }
    }

    /// Sets the positions of the two poses of every sample with a pose pair `(i, j)` to
    /// `position(i)` and `position(j)` (`None` when either is unknown): the positions a caller
    /// draws its map with (a log's own, or the trajectory's first three coordinates).
    /// O(samples) calls.
    pub fn set_positions(&mut self, mut position: impl FnMut(usize) -> Option<[f64; 3]>) {
        for row in &mut self.rows {
            row.positions = row.pair.and_then(|[i, j]| Some([position(i)?, position(j)?]));
        }
    }

    /// Fills in the distance δ(x_i, x_j) and the relative pose ([`relative_pose`](crate::relative_pose))
    /// of every sample (placing times on the nearest poses where pairs are missing). O(samples)
    /// distances.
    ///
    /// # Errors
    /// As [`locate`](Self::locate), for `traj`; the metric's dimension error.
    pub fn measure<M: Metric + ?Sized>(&mut self, traj: &Trajectory, metric: &M) -> Result<()> {
        check_fits(metric, traj)?;
        metric.check_dim(traj.dim())?;
        let pairs = self.pairs_on(traj.timestamps_s())?;
        for (row, pair) in self.rows.iter_mut().zip(pairs) {
            row.pair = Some(pair);
            row.distance = Some(metric.distance(traj.point(pair[0]), traj.point(pair[1])));
            row.relative_pose = crate::relative_pose(traj, pair[0], pair[1]);
        }
        self.poses = Some(traj.len());
        Ok(())
    }

    /// The pose pair of every sample on a trajectory with these timestamps.
    pub(crate) fn pairs_on(&self, times: &[f64]) -> Result<Vec<[usize; 2]>> {
        if let Some(poses) = self.poses
            && poses != times.len()
        {
            return Err(Error::TrajectoryMismatch {
                what: "samples",
                index: poses.min(times.len()),
                poses,
                loops_poses: times.len(),
            });
        }
        self.rows
            .iter()
            .enumerate()
            .map(|(k, row)| match row.pair {
                Some(pair) => Ok(pair),
                None => Ok([place_detection(times, row.t_s, k)?, place_detection(times, row.t_prime_s, k)?]),
            })
            .collect()
    }

    pub(super) fn new(
        sampler: SamplerKind,
        mut rows: Vec<Sample>,
        groups: usize,
        available: u64,
        poses: Option<usize>,
    ) -> Self {
        rows.sort_by(|a, b| {
            a.t_s.total_cmp(&b.t_s).then(a.t_prime_s.total_cmp(&b.t_prime_s)).then(a.detection.cmp(&b.detection))
        });
        Self { sampler, rows, groups, available, poses, warnings: Vec::new() }
    }
}

/// What a serialised [`Samples`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct SamplesState {
    sampler: SamplerKind,
    rows: Vec<Sample>,
    groups: usize,
    available: u64,
    poses: Option<usize>,
    warnings: Vec<SampleWarning>,
}

#[cfg(feature = "serde")]
impl TryFrom<SamplesState> for Samples {
    type Error = Error;

    /// Checks that every pair (i ≤ j) is a pair of poses of the samples' trajectory, and that
    /// every time is finite and every distance finite and at least 0.
    fn try_from(state: SamplesState) -> Result<Self> {
        let unmeasurable = state.rows.iter().position(|row| {
            !(row.t_s.is_finite() && row.t_prime_s.is_finite())
                || row.distance.is_some_and(|d| !(d.is_finite() && d >= 0.0))
        });
        if let Some(k) = unmeasurable {
            let row = &state.rows[k];
            return Err(Error::InvalidState {
                what: "Samples",
                reason: format!(
                    "sample {k} has the times ({}, {}) s and the distance {:?}",
                    row.t_s, row.t_prime_s, row.distance
                ),
            });
        }
        let bad = state
            .rows
            .iter()
            .position(|row| row.pair.is_some_and(|[i, j]| i > j || state.poses.is_none_or(|poses| j >= poses)));
        if let Some(k) = bad {
            return Err(Error::InvalidState {
                what: "Samples",
                reason: format!("sample {k} has the pair {:?}, on {:?} poses", state.rows[k].pair, state.poses),
            });
        }
        let SamplesState { sampler, rows, groups, available, poses, warnings } = state;
        Ok(Self { sampler, rows, groups, available, poses, warnings })
    }
}
