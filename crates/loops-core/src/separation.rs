//! Revisits: the part X ⊆ S_γ whose pairs lie at least a path length L and a time T apart along
//! the trajectory.
//!
//! Near the diagonal of S_γ every pair is a loop by the paper's definition: poses a step apart
//! are within γ of each other. A SLAM system calls a pair a loop only when the robot has been
//! away and come back (LIO-SAM waits 30 s, hdl_graph_slam a travelled distance). The separation
//! keeps exactly the pairs `(i, j)`, `i < j`, with `s_j − s_i ≥ L` and `t_j − t_i ≥ T`, where
//! `s` is the path length under the metric ([`path_length`]). In row i these are the columns from
//! one first column c_i on, found by a binary search; the scan of S_γ starts there, so the
//! separation costs no distance evaluation and clips runs where they are produced. With L > 0 or
//! T > 0 no diagonal cell remains and no component is trivial: every component is a revisit.

use std::fmt;

use crate::error::{Error, Result};
use crate::memory::try_collect;

/// The minimum separation along the trajectory between the two poses of a loop: a path length
/// (the metric's unit, e.g. metres) and a time (seconds). Both must hold. [`Separation::NONE`]
/// (both zero) is the paper's S_γ, with its trivial components.
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, Separation, Trajectory, find_loops, find_loops_separated};
/// // Out along a line and back: by the paper's topology one trivial component, and nothing else.
/// let xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0];
/// let points: Vec<[f64; 1]> = xs.iter().map(|&x| [x]).collect();
/// let traj = Trajectory::from_points((0..xs.len()).map(|i| i as f64).collect(), &points)?;
/// assert_eq!(find_loops(&traj, &Euclidean, 1.0)?.components().len(), 1);
/// // At least 3 m apart along the path: the way back revisits the way out.
/// let revisits = find_loops_separated(&traj, &Euclidean, 1.0, Separation::path(3.0))?;
/// assert_eq!(revisits.components().len(), 1);
/// assert!(!revisits.components()[0].trivial);
/// assert_eq!(revisits.components()[0].closest_pair, [0, 10]);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "SeparationState"))]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Separation {
    /// Minimum path length between the poses, in the metric's unit: `s_j − s_i ≥ path`.
    pub path: f64,
    /// Minimum time between the poses, seconds: `t_j − t_i ≥ time_s`.
    pub time_s: f64,
}

/// What a serialised [`Separation`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct SeparationState {
    path: f64,
    time_s: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<SeparationState> for Separation {
    type Error = Error;

    /// Checked as [`Separation::check`] checks it.
    fn try_from(state: SeparationState) -> Result<Self> {
        let separation = Self { path: state.path, time_s: state.time_s };
        separation.check()?;
        Ok(separation)
    }
}

impl Separation {
    /// No separation: the paper's S_γ.
    pub const NONE: Self = Self { path: 0.0, time_s: 0.0 };

    /// The default path separation, in multiples of γ: [`Separation::for_gamma`].
    pub const DEFAULT_GAMMAS: f64 = 4.0;

    /// At least `path` apart along the path (the metric's unit).
    pub fn path(path: f64) -> Self {
        Self { path, time_s: 0.0 }
    }

    /// At least `time_s` seconds apart.
    pub fn time_s(time_s: f64) -> Self {
        Self { path: 0.0, time_s }
    }

    /// The default for SLAM: at least [`DEFAULT_GAMMAS`](Self::DEFAULT_GAMMAS) · γ apart along
    /// the path, no time separation. Chosen from the table of separations measured on real
    /// trajectories in the documentation's guide "Choose γ and the separation".
    ///
    /// ```
    /// assert_eq!(loops_core::Separation::for_gamma(6.0).path, 24.0);
    /// ```
    pub fn for_gamma(gamma: f64) -> Self {
        Self::path(Self::DEFAULT_GAMMAS * gamma)
    }

    /// Whether both are zero: the paper's S_γ.
    pub fn is_none(&self) -> bool {
        self.path == 0.0 && self.time_s == 0.0
    }

    /// Checks both bounds: finite and not negative.
    ///
    /// # Errors
    /// [`Error::InvalidSeparation`] naming the bound and its value.
    pub fn check(&self) -> Result<()> {
        for (what, value) in [("path", self.path), ("time", self.time_s)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::InvalidSeparation { what, value });
            }
        }
        Ok(())
    }

    /// The first column of every row that the separation keeps: c_i = the smallest j > i with
    /// `s_j − s_i ≥ path` and `t_j − t_i ≥ time_s` (`n` when there is none), or i itself with no
    /// separation. Non-decreasing in i. O(n log n).
    ///
    /// # Errors
    /// [`Error::OutOfMemory`].
    pub(crate) fn first_columns(&self, path_length: &[f64], timestamps_s: &[f64]) -> Result<Vec<u32>> {
        let n = timestamps_s.len();
        let columns = (0..n).map(|i| {
            if self.is_none() {
                return i as u32;
            }
            let after = |values: &[f64], bound: f64| {
                let start = i + 1;
                start + values[start..].partition_point(|&v| v - values[i] < bound)
            };
            after(path_length, self.path).max(after(timestamps_s, self.time_s)) as u32
        });
        try_collect(columns, "the first columns of the rows")
    }
}

impl fmt::Display for Separation {
    /// `none`, or e.g. `path >= 24, time >= 30 s`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.path > 0.0, self.time_s > 0.0) {
            (false, false) => write!(f, "none"),
            (true, false) => write!(f, "path >= {}", self.path),
            (false, true) => write!(f, "time >= {} s", self.time_s),
            (true, true) => write!(f, "path >= {}, time >= {} s", self.path, self.time_s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_columns_by_path_and_time() {
        let s = [0.0, 1.0, 1.0, 3.0, 6.0];
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        assert_eq!(Separation::NONE.first_columns(&s, &t).unwrap(), vec![0, 1, 2, 3, 4]);
        assert_eq!(Separation::path(2.0).first_columns(&s, &t).unwrap(), vec![3, 3, 3, 4, 5]);
        assert_eq!(Separation::time_s(2.0).first_columns(&s, &t).unwrap(), vec![2, 3, 4, 5, 5]);
        let both = Separation { path: 2.0, time_s: 2.0 };
        assert_eq!(both.first_columns(&s, &t).unwrap(), vec![3, 3, 4, 5, 5]);
        // A tiny separation still leaves the diagonal out.
        assert_eq!(Separation::time_s(1e-9).first_columns(&s, &t).unwrap(), vec![1, 2, 3, 4, 5]);
    }

    #[test]
    fn bad_bounds() {
        for bad in [Separation::path(-1.0), Separation::time_s(f64::NAN), Separation::path(f64::INFINITY)] {
            assert!(matches!(bad.check(), Err(Error::InvalidSeparation { .. })), "{bad:?}");
        }
        assert!(Separation::NONE.check().is_ok() && Separation::for_gamma(2.0).check().is_ok());
        assert_eq!(Separation { path: 24.0, time_s: 30.0 }.to_string(), "path >= 24, time >= 30 s");
    }
}
