//! Detections D ⊂ S_γ (paper, Sec. 5.3): pairs of times (t, t′) at which the trajectory is
//! believed to come back to itself, given by the user (place recognition) or drawn uniformly from
//! the exact S_γ.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::draw::{DETECTION_BYTES, PairSpace, SampleSize, check_count};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::trajectory::{Timeline, nearest_pose};

/// The pose nearest the time `t` of detection `index` (see [`Detections::locate`]).
pub(crate) fn place_detection(times: &[f64], t: f64, index: usize) -> Result<usize> {
    nearest_pose(times, t).ok_or(Error::DetectionOutsideSpan {
        index,
        time_s: t,
        start_s: times[0],
        end_s: times[times.len() - 1],
    })
}

/// One detection, as [`Detections::get`] returns it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// The earlier time of the pair, seconds.
    pub t_s: f64,
    /// The later time of the pair (t′ ≥ t), seconds.
    pub t_prime_s: f64,
    /// The poses (i, j), i ≤ j, when the detections are placed on a trajectory.
    pub pair: Option<[usize; 2]>,
    /// The detection's score (higher is more confident, e.g. a place-recognition similarity).
    pub score: Option<f64>,
}

#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
struct Located {
    pairs: Vec<[u32; 2]>,
    poses: usize,
}

/// A set of detections D: unordered pairs of times (t, t′), seconds, with optional scores and,
/// when placed on a trajectory, the pose indices (i, j) of the pair.
///
/// Pairs are unordered: a pair given as (t′, t) with t′ > t is stored as (t, t′), the same loop
/// (loop components are reported once per mirror pair, on the half t ≤ t′). Rows keep the order
/// they were given in; duplicates are allowed. A detection set is never empty.
///
/// Memory: 16 bytes a detection, plus 8 when placed on a trajectory and 8 with scores.
///
/// # Examples
/// ```
/// use loops_core::{Detections, Trajectory};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &[[0.0], [1.0], [1.0], [0.0]])?;
/// // Given by times, in any order, placed on the nearest poses.
/// let det = Detections::new(vec![3.0, 0.9], vec![0.1, 2.2])?.locate(&traj)?;
/// assert_eq!(det.get(0).t_s, 0.1); // stored as (t, t') with t <= t'
/// assert_eq!(det.get(0).pair, Some([0, 3]));
/// assert_eq!(det.get(1).pair, Some([1, 2]));
/// // Given by pose indices.
/// let det = Detections::from_indices(&traj, &[3], &[0])?;
/// assert_eq!((det.get(0).t_s, det.get(0).t_prime_s), (0.0, 3.0));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "DetectionsState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct Detections {
    t_s: Vec<f64>,
    t_prime_s: Vec<f64>,
    located: Option<Located>,
    scores: Option<Vec<f64>>,
}

impl Detections {
    /// Detections from times alone (seconds; either order within a pair). O(n).
    ///
    /// # Errors
    /// [`Error::NoDetections`] when empty, [`Error::ColumnLengthMismatch`] when the columns
    /// differ in length, [`Error::NonFiniteDetection`] for a NaN or infinite time.
    pub fn new(t_s: Vec<f64>, t_prime_s: Vec<f64>) -> Result<Self> {
        if t_s.is_empty() && t_prime_s.is_empty() {
            return Err(Error::NoDetections);
        }
        if t_prime_s.len() != t_s.len() {
            return Err(Error::ColumnLengthMismatch { column: "t_prime_s", len: t_prime_s.len(), expected: t_s.len() });
        }
        for (column, values) in [("t_s", &t_s), ("t_prime_s", &t_prime_s)] {
            if let Some(index) = values.iter().position(|t| !t.is_finite()) {
                return Err(Error::NonFiniteDetection { column, index, value: values[index] });
            }
        }
        let (mut t_s, mut t_prime_s) = (t_s, t_prime_s);
        for (a, b) in t_s.iter_mut().zip(t_prime_s.iter_mut()) {
            if *a > *b {
                std::mem::swap(a, b);
            }
        }
        Ok(Self { t_s, t_prime_s, located: None, scores: None })
    }

    /// The same detections with a score each (higher is more confident). The dispersed σ_ρ
    /// prefers the best-scored detection of a row.
    ///
    /// # Errors
    /// [`Error::ColumnLengthMismatch`], [`Error::NonFiniteDetection`] (column `score`).
    pub fn with_scores(self, scores: Vec<f64>) -> Result<Self> {
        if scores.len() != self.len() {
            return Err(Error::ColumnLengthMismatch { column: "score", len: scores.len(), expected: self.len() });
        }
        if let Some(index) = scores.iter().position(|s| !s.is_finite()) {
            return Err(Error::NonFiniteDetection { column: "score", index, value: scores[index] });
        }
        Ok(Self { scores: Some(scores), ..self })
    }

    /// Detections from pose indices (i, j) of a trajectory (either order); the times are the
    /// poses' timestamps. O(n).
    ///
    /// # Errors
    /// [`Error::NoDetections`], [`Error::ColumnLengthMismatch`], and
    /// [`Error::PoseIndexOutOfRange`] for an index past the last pose.
    pub fn from_indices<T: Timeline + ?Sized>(timeline: &T, i: &[usize], j: &[usize]) -> Result<Self> {
        let times = timeline.pose_times_s();
        if i.is_empty() && j.is_empty() {
            return Err(Error::NoDetections);
        }
        if j.len() != i.len() {
            return Err(Error::ColumnLengthMismatch { column: "j", len: j.len(), expected: i.len() });
        }
        let poses = times.len();
        let mut pairs = Vec::with_capacity(i.len());
        for (index, (&a, &b)) in i.iter().zip(j).enumerate() {
            if let Some(&pose) = [a, b].iter().find(|&&p| p >= poses) {
                return Err(Error::PoseIndexOutOfRange { index, pose, poses });
            }
            pairs.push([a.min(b) as u32, a.max(b) as u32]);
        }
        Ok(Self::from_pairs(times, pairs))
    }

    /// Detections at pose pairs known to be valid (i ≤ j < times.len()).
    pub(crate) fn from_pairs(times: &[f64], pairs: Vec<[u32; 2]>) -> Self {
        let t_s = pairs.iter().map(|p| times[p[0] as usize]).collect();
        let t_prime_s = pairs.iter().map(|p| times[p[1] as usize]).collect();
        Self { t_s, t_prime_s, located: Some(Located { pairs, poses: times.len() }), scores: None }
    }

    /// Places every detection on the trajectory: each time goes to the nearest pose (the pose
    /// whose time cell holds it; ties to the earlier). The detection times are kept as given.
    /// O(n log poses).
    ///
    /// # Errors
    /// [`Error::DetectionOutsideSpan`] for a time before the first or after the last timestamp.
    pub fn locate<T: Timeline + ?Sized>(self, timeline: &T) -> Result<Self> {
        let times = timeline.pose_times_s();
        let mut pairs = Vec::with_capacity(self.len());
        for (index, (&a, &b)) in self.t_s.iter().zip(&self.t_prime_s).enumerate() {
            pairs.push([place_detection(times, a, index)? as u32, place_detection(times, b, index)? as u32]);
        }
        Ok(Self { located: Some(Located { pairs, poses: times.len() }), ..self })
    }

    /// Detections drawn uniformly from the exact S_γ of `loops`, without materialising it: the
    /// off-diagonal pairs (i, j), i < j, of its runs (each unordered loop once; the diagonal
    /// (i, i) is no detection).
    ///
    /// - [`SampleSize::Rate`]`(p)`, 0 < p ≤ 1: every pair independently with probability p
    ///   (geometric skips over the runs: O(runs + drawn)).
    /// - [`SampleSize::Budget`]`(k)`: exactly k distinct pairs, uniformly (k indices into the
    ///   pairs, then each mapped to its run by binary search, i.e. runs weighted by length, then
    ///   a column: O(runs + k log runs)).
    ///
    /// Seeded (ChaCha8): the same seed gives the same detections on every machine and thread
    /// count. Rows are in row-major order of (i, j). Memory O(runs + drawn).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a rate outside (0, 1], a budget of 0 or more than the
    /// pairs available; [`Error::NoDetections`] when the draw comes out empty;
    /// [`Error::TooManySamples`] for more than [`MAX_SAMPLES`](crate::MAX_SAMPLES) detections
    /// (the expected count for a rate), before any is drawn.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Detections, Euclidean, SampleSize, UrbanDrive, find_loops};
    /// let drive = UrbanDrive { duration_s: 600.0, ..UrbanDrive::default() }.generate()?;
    /// let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
    /// let det = Detections::draw(&loops, SampleSize::Budget(1000), 7)?;
    /// assert_eq!(det.len(), 1000);
    /// assert!(det.iter().all(|d| { let [i, j] = d.pair.unwrap(); i < j && loops.component_of(i, j).is_some() }));
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn draw(loops: &Loops, size: SampleSize, seed: u64) -> Result<Self> {
        let space = PairSpace::of_loops(loops, 0.0, &Interrupt::current())?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let indices = match size {
            SampleSize::Rate(rate) => {
                if !(rate > 0.0 && rate <= 1.0) {
                    return Err(Error::InvalidParameter {
                        name: "rate",
                        value: rate,
                        expected: "a probability in (0, 1]",
                    });
                }
                check_count("detections", size, rate * space.len() as f64, DETECTION_BYTES)?;
                space.bernoulli(rate, &mut rng)
            }
            SampleSize::Budget(count) => {
                if count == 0 || count as u64 > space.len() {
                    return Err(Error::InvalidParameter {
                        name: "budget",
                        value: count as f64,
                        expected: "at least 1 and at most the off-diagonal pairs of S_gamma",
                    });
                }
                check_count("detections", size, count as f64, DETECTION_BYTES)?;
                space.choose(count as u64, &mut rng)
            }
        };
        if indices.is_empty() {
            return Err(Error::NoDetections);
        }
        Ok(Self::from_pairs(loops.timestamps_s(), space.pairs_at(&indices)?))
    }

    /// Number of detections (at least 1).
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// Never: a detection set holds at least one detection.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The earlier time t of each pair, seconds.
    pub fn t_s(&self) -> &[f64] {
        &self.t_s
    }

    /// The later time t′ ≥ t of each pair, seconds.
    pub fn t_prime_s(&self) -> &[f64] {
        &self.t_prime_s
    }

    /// Pose indices (i, j), i ≤ j, of each pair, when placed on a trajectory.
    pub fn pairs(&self) -> Option<&[[u32; 2]]> {
        self.located.as_ref().map(|l| l.pairs.as_slice())
    }

    /// Number of poses of the trajectory the detections are placed on.
    pub fn poses(&self) -> Option<usize> {
        self.located.as_ref().map(|l| l.poses)
    }

    /// Scores, when given.
    pub fn scores(&self) -> Option<&[f64]> {
        self.scores.as_deref()
    }

    /// Detection `k`.
    ///
    /// # Panics
    /// If `k >= len()`.
    pub fn get(&self, k: usize) -> Detection {
        Detection {
            t_s: self.t_s[k],
            t_prime_s: self.t_prime_s[k],
            pair: self.located.as_ref().map(|l| [l.pairs[k][0] as usize, l.pairs[k][1] as usize]),
            score: self.scores.as_ref().map(|s| s[k]),
        }
    }

    /// Every detection, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Detection> + '_ {
        (0..self.len()).map(|k| self.get(k))
    }
}

/// What a serialised [`Detections`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct DetectionsState {
    t_s: Vec<f64>,
    t_prime_s: Vec<f64>,
    located: Option<Located>,
    scores: Option<Vec<f64>>,
}

#[cfg(feature = "serde")]
impl TryFrom<DetectionsState> for Detections {
    type Error = Error;

    /// Validated as [`Detections::new`] and [`Detections::with_scores`]; pairs (i ≤ j) within
    /// their trajectory, one per detection.
    fn try_from(state: DetectionsState) -> Result<Self> {
        let mut detections = Self::new(state.t_s, state.t_prime_s)?;
        if let Some(scores) = state.scores {
            detections = detections.with_scores(scores)?;
        }
        if let Some(located) = &state.located {
            let bad = located.pairs.iter().position(|&[i, j]| i > j || j as usize >= located.poses);
            if located.pairs.len() != detections.len() || bad.is_some() {
                return Err(Error::InvalidState {
                    what: "Detections",
                    reason: format!(
                        "{} pairs for {} detections on {} poses (first bad pair: {:?})",
                        located.pairs.len(),
                        detections.len(),
                        located.poses,
                        bad.map(|k| located.pairs[k])
                    ),
                });
            }
        }
        detections.located = state.located;
        Ok(detections)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trajectory::Trajectory;

    fn line() -> Trajectory {
        Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0, 4.0], &[[0.0], [1.0], [2.0], [1.0], [0.0]]).unwrap()
    }

    #[test]
    fn times_are_validated_and_ordered() {
        assert_eq!(Detections::new(vec![], vec![]).unwrap_err(), Error::NoDetections);
        assert!(matches!(
            Detections::new(vec![1.0], vec![]).unwrap_err(),
            Error::ColumnLengthMismatch { column: "t_prime_s", len: 0, expected: 1 }
        ));
        let err = Detections::new(vec![1.0, 2.0], vec![f64::NAN, 3.0]).unwrap_err();
        assert_eq!(err.to_string(), "t_prime_s of detection 0 is not finite (NaN)");
        let det = Detections::new(vec![3.0, 1.0], vec![1.0, 1.0]).unwrap();
        assert_eq!(det.t_s(), &[1.0, 1.0]);
        assert_eq!(det.t_prime_s(), &[3.0, 1.0]);
        assert!(det.clone().with_scores(vec![1.0]).is_err());
        assert!(det.clone().with_scores(vec![1.0, f64::INFINITY]).is_err());
        assert_eq!(det.with_scores(vec![0.5, 1.0]).unwrap().get(1).score, Some(1.0));
    }

    #[test]
    fn locate_and_indices() {
        let traj = line();
        let det = Detections::new(vec![0.5, 4.0, 1.49], vec![2.51, 0.0, 1.51]).unwrap().locate(&traj).unwrap();
        assert_eq!(det.pairs().unwrap(), &[[0, 3], [0, 4], [1, 2]]);
        assert_eq!(det.poses(), Some(5));
        let err = Detections::new(vec![0.0], vec![4.5]).unwrap().locate(&traj).unwrap_err();
        assert_eq!(err, Error::DetectionOutsideSpan { index: 0, time_s: 4.5, start_s: 0.0, end_s: 4.0 });
        let err = Detections::from_indices(&traj, &[0, 1], &[5, 1]).unwrap_err();
        assert_eq!(err, Error::PoseIndexOutOfRange { index: 0, pose: 5, poses: 5 });
        let det = Detections::from_indices(&traj, &[4, 1], &[0, 1]).unwrap();
        assert_eq!(det.get(0), Detection { t_s: 0.0, t_prime_s: 4.0, pair: Some([0, 4]), score: None });
    }
}
