//! Where given pairs of poses fall with respect to the loops: in which component, in a trivial
//! one, within γ but not a revisit, or outside S_γ. For the loop-closure edges of a pose graph,
//! the place-recognition detections of a front end, or any pairs a user holds.

use std::fmt;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::loops::Loops;
use crate::metric::Metric;
use crate::sublevel::try_path_length;
use crate::trajectory::Trajectory;

/// Where a pair of poses falls: [`Loops::pair_verdicts`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Verdict {
    /// In the loop component `component`, which is not trivial: a revisit (with a
    /// [`Separation`](crate::Separation), every component is one).
    Component {
        /// Its id in [`Loops::components`].
        component: usize,
    },
    /// In the trivial component `component` (one holding the diagonal): a simple loop, a pair
    /// that odometry already ties together. Only without a separation: with one, such pairs are
    /// [`Verdict::NotSeparated`].
    Trivial {
        /// Its id in [`Loops::components`].
        component: usize,
    },
    /// Within γ (in the paper's S_γ), but closer along the trajectory than the loops'
    /// separation (path length or time): left out of the revisits X, so in no component.
    NotSeparated,
    /// Farther apart than γ: outside S_γ.
    Outside,
}

impl Verdict {
    /// The names of the verdicts, as [`name`](Self::name) gives them, in this order.
    pub const NAMES: [&'static str; 4] = ["component", "trivial", "not-separated", "outside"];

    /// `component`, `trivial`, `not-separated` or `outside`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Component { .. } => Self::NAMES[0],
            Self::Trivial { .. } => Self::NAMES[1],
            Self::NotSeparated => Self::NAMES[2],
            Self::Outside => Self::NAMES[3],
        }
    }

    /// The component holding the pair, trivial or not; `None` outside every component.
    pub fn component(self) -> Option<usize> {
        match self {
            Self::Component { component } | Self::Trivial { component } => Some(component),
            Self::NotSeparated | Self::Outside => None,
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A pair of poses, its distance and its [`Verdict`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairVerdict {
    /// The pose indices `[i, j]`, as given.
    pub pair: [usize; 2],
    /// δ(x_i, x_j), in the metric's unit.
    pub distance: f64,
    /// Where the pair falls.
    pub verdict: Verdict,
}

impl Loops {
    /// Where each pair `[i, j]` (either order) falls: in a loop component (trivial or not),
    /// within γ but not separated (not a revisit), or outside S_γ; with δ(x_i, x_j).
    ///
    /// The component is the engine's ([`component_of`](Self::component_of)). A pair in none is
    /// `Outside` when δ > γ and `NotSeparated` otherwise: the separation is checked as the
    /// engine checks it, `s_j − s_i ≥ path` and `t_j − t_i ≥ time_s` for `i < j` on the path
    /// length `s` under `metric` ([`path_length`](crate::path_length)), and a pair of one pose is never separated.
    ///
    /// Time O(n) for the path length, plus O(log runs) and one distance per pair, in parallel.
    ///
    /// # Errors
    /// [`Error::TrajectoryMismatch`] when `traj` is not the trajectory the loops were found on;
    /// [`Error::MetricMismatch`] when `metric` is not theirs (by name); the metric's error when
    /// it does not fit `traj`; [`Error::IndexOutOfRange`] for a pose index past the last pose.
    ///
    /// # Examples
    /// Out along a line and back: the way back revisits the way out, 3 m of path later.
    /// ```
    /// use loops_core::{Euclidean, Separation, Trajectory, Verdict, find_loops_separated};
    /// let xs = [0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 0.0];
    /// let points: Vec<[f64; 1]> = xs.iter().map(|&x| [x]).collect();
    /// let traj = Trajectory::from_points((0..xs.len()).map(|i| i as f64).collect(), &points)?;
    /// let loops = find_loops_separated(&traj, &Euclidean, 0.5, Separation::path(3.0))?;
    /// let verdicts = loops.pair_verdicts(&traj, &Euclidean, &[[0, 6], [2, 4], [0, 3]])?;
    /// assert!(matches!(verdicts[0].verdict, Verdict::Component { .. })); // 6 m apart along the path
    /// assert_eq!(verdicts[1].verdict, Verdict::NotSeparated); // within γ, 2 m apart along the path
    /// assert_eq!((verdicts[2].verdict, verdicts[2].distance), (Verdict::Outside, 3.0));
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn pair_verdicts<M: Metric + ?Sized>(
        &self,
        traj: &Trajectory,
        metric: &M,
        pairs: &[[usize; 2]],
    ) -> Result<Vec<PairVerdict>> {
        self.check_trajectory(traj)?;
        if crate::spec::recorded_metric_name(metric) != self.metric_name() {
            return Err(Error::MetricMismatch {
                metric: metric.name(),
                expected: "the metric the loops were found with (Loops::metric_name)",
            });
        }
        traj.check_metric(metric)?;
        if let Some(&index) = pairs.iter().flatten().find(|&&p| p >= self.len()) {
            return Err(Error::IndexOutOfRange { index, len: self.len() });
        }
        let separation = self.separation();
        let s = if separation.is_none() { Vec::new() } else { try_path_length(traj, metric)? };
        let t = traj.timestamps_s();
        let separated = |i: usize, j: usize| {
            let (i, j) = (i.min(j), i.max(j));
            separation.is_none() || (j > i && s[j] - s[i] >= separation.path && t[j] - t[i] >= separation.time_s)
        };
        Ok(pairs
            .par_iter()
            .map(|&[i, j]| {
                let distance = metric.distance(traj.point(i), traj.point(j));
                let verdict = match self.component_of(i, j) {
                    Some(component) if self.components()[component].trivial => Verdict::Trivial { component },
                    Some(component) => Verdict::Component { component },
                    None if distance <= self.gamma() && !separated(i, j) => Verdict::NotSeparated,
                    None => Verdict::Outside,
                };
                PairVerdict { pair: [i, j], distance, verdict }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Euclidean, Separation, SublevelSet, find_loops_separated};

    /// A wandering 2-D walk with revisits.
    fn walk(n: usize) -> Trajectory {
        let points: Vec<[f64; 2]> = (0..n)
            .map(|k| [(k as f64 * 0.37).sin() * 5.0, (k as f64 * 0.23).cos() * 4.0 + (k % 7) as f64 * 0.1])
            .collect();
        Trajectory::from_points((0..n).map(|k| k as f64 * 0.5).collect(), &points).unwrap()
    }

    #[test]
    fn every_pair_as_the_brute_force_set_and_distance_say() {
        let traj = walk(60);
        let gamma = 1.5;
        let mut seen = std::collections::BTreeSet::new();
        for separation in [Separation::NONE, Separation::path(6.0), Separation { path: 2.0, time_s: 4.0 }] {
            let loops = find_loops_separated(&traj, &Euclidean, gamma, separation).unwrap();
            let paper = SublevelSet::brute_force(&traj, &Euclidean, gamma).unwrap();
            let pairs: Vec<[usize; 2]> = (0..traj.len()).flat_map(|i| (0..traj.len()).map(move |j| [i, j])).collect();
            let verdicts = loops.pair_verdicts(&traj, &Euclidean, &pairs).unwrap();
            for v in verdicts {
                let [i, j] = v.pair;
                let within = paper.contains(i.min(j), i.max(j));
                assert_eq!(v.distance, Euclidean.distance(traj.point(i), traj.point(j)));
                assert_eq!(within, v.distance <= gamma);
                match v.verdict {
                    Verdict::Outside => assert!(!within, "{v:?}"),
                    Verdict::NotSeparated => assert!(within && !separation.is_none(), "{v:?}"),
                    Verdict::Trivial { component } => {
                        assert!(separation.is_none() && loops.components()[component].trivial);
                        assert_eq!(loops.component_of(i, j), Some(component));
                    }
                    Verdict::Component { component } => {
                        assert!(!loops.components()[component].trivial);
                        assert_eq!(loops.component_of(i, j), Some(component));
                    }
                }
                assert_eq!(v.verdict.component(), loops.component_of(i, j));
                seen.insert(v.verdict.name());
            }
        }
        assert_eq!(seen.len(), 4, "every verdict is exercised: {seen:?}");
    }

    #[test]
    fn another_trajectory_metric_or_index_is_refused() {
        let traj = walk(20);
        let loops = find_loops_separated(&traj, &Euclidean, 1.0, Separation::NONE).unwrap();
        assert!(matches!(loops.pair_verdicts(&walk(21), &Euclidean, &[]), Err(Error::TrajectoryMismatch { .. })));
        assert!(matches!(
            loops.pair_verdicts(&traj, &Euclidean, &[[0, 20]]),
            Err(Error::IndexOutOfRange { index: 20, .. })
        ));
        let torus = crate::Torus;
        assert!(matches!(loops.pair_verdicts(&traj, &torus, &[]), Err(Error::MetricMismatch { .. })));
        assert_eq!(Verdict::NAMES.map(|name| name.len()), [9, 7, 13, 7]);
    }
}
