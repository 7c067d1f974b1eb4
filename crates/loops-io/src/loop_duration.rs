//! `loop_duration.csv`: the loop duration τ of every pose, with its time and position
//! ([`LoopDurationRow`]).

use std::io::{self, Write};
use std::path::Path;

use crate::atomic::write_atomically;
use crate::csv_rows::write_csv;
use crate::error::WriteError;

/// The columns of `loop_duration.csv`.
pub const LOOP_DURATION_COLUMNS: [&str; 6] = ["index", "t_s", "x", "y", "z", "loop_duration_s"];

/// One row of `loop_duration.csv`: a pose and its loop duration τ.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct LoopDurationRow {
    /// The pose's index.
    pub index: usize,
    /// Its time, seconds.
    pub t_s: f64,
    /// Its position, in the file's units (`NaN` when unknown).
    pub x: f64,
    /// See `x`.
    pub y: f64,
    /// See `x` (0 for a 2-D trajectory).
    pub z: f64,
    /// τ of the pose: the time it spends in loops, seconds
    /// ([`Loops::loop_duration`](loops_core::Loops::loop_duration)).
    pub loop_duration_s: f64,
}

/// The rows of `loop_duration.csv`: one per pose of `loop_duration_s`, with its time from
/// `timestamps_s` and its position from `positions` (`NaN` for a pose past the end of
/// `positions`). Stops at the shorter of `timestamps_s` and `loop_duration_s`. O(poses).
pub fn loop_duration_rows(
    timestamps_s: &[f64],
    positions: &[[f64; 3]],
    loop_duration_s: &[f64],
) -> impl Iterator<Item = LoopDurationRow> {
    timestamps_s.iter().zip(loop_duration_s).enumerate().map(|(index, (&t_s, &loop_duration_s))| {
        let [x, y, z] = positions.get(index).copied().unwrap_or([f64::NAN; 3]);
        LoopDurationRow { index, t_s, x, y, z, loop_duration_s }
    })
}

/// The `x`, `y`, `z` of `loop_duration.csv` for a trajectory read without its file's
/// [`PoseTable`](crate::PoseTable) (whose positions the CLI writes): each point's first three
/// coordinates, 0 for those a point lacks (1-D and 2-D trajectories, as the readers fill `z`).
/// These are the positions for trajectories of positions and of SE(3) poses (position first);
/// for other charts (an SE(2) pose's heading, quaternions, angles) they are the chart's first
/// coordinates. O(poses).
///
/// # Examples
/// ```
/// let traj = loops_core::Trajectory::from_points(vec![0.0, 1.0], &[[1.0, 2.0], [3.0, 4.0]])?;
/// assert_eq!(loops_io::point_positions(&traj), vec![[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn point_positions(traj: &loops_core::Trajectory) -> Vec<[f64; 3]> {
    (0..traj.len()).map(|i| point_position(traj, i)).collect()
}

/// The position of pose `i` of `traj`, as [`point_positions`] gives every pose's: where only a
/// few poses are wanted (the closest pairs of the components), without the O(poses) copy.
///
/// # Panics
/// When `i` is not a pose of `traj`.
///
/// # Examples
/// ```
/// let traj = loops_core::Trajectory::from_points(vec![0.0, 1.0], &[[1.0, 2.0], [3.0, 4.0]])?;
/// assert_eq!(loops_io::point_position(&traj, 1), [3.0, 4.0, 0.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn point_position(traj: &loops_core::Trajectory, i: usize) -> [f64; 3] {
    let mut position = [0.0; 3];
    for (axis, &value) in position.iter_mut().zip(traj.point(i)) {
        *axis = value;
    }
    position
}

/// Writes `loop_duration.csv` to `out`: a header of [`LOOP_DURATION_COLUMNS`], then the
/// [`loop_duration_rows`]. Numbers are printed in the shortest form that reads back as the same
/// `f64`, without an exponent. O(poses).
///
/// # Errors
/// What `out` returns.
///
/// # Examples
/// ```
/// let mut text = Vec::new();
/// loops_io::loop_duration_to_csv(&[0.0, 0.5], &[[1.0, 2.0, 0.0], [1.5, 2.0, 0.0]], &[0.0, 0.25], &mut text).unwrap();
/// assert_eq!(String::from_utf8(text).unwrap(), "index,t_s,x,y,z,loop_duration_s\n0,0,1,2,0,0\n1,0.5,1.5,2,0,0.25\n");
/// ```
pub fn loop_duration_to_csv<W: Write>(
    timestamps_s: &[f64],
    positions: &[[f64; 3]],
    loop_duration_s: &[f64],
    out: W,
) -> io::Result<()> {
    write_csv(out, &LOOP_DURATION_COLUMNS, loop_duration_rows(timestamps_s, positions, loop_duration_s))
}

/// Writes `loop_duration.csv` ([`loop_duration_to_csv`]) to the file `path`, atomically
/// ([`write_atomically`](crate::write_atomically)); an existing file is replaced only with
/// `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
pub fn write_loop_duration(
    path: impl AsRef<Path>,
    timestamps_s: &[f64],
    positions: &[[f64; 3]],
    loop_duration_s: &[f64],
    overwrite: bool,
) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |file| loop_duration_to_csv(timestamps_s, positions, loop_duration_s, file))
}

#[cfg(test)]
mod tests {
    use std::fmt::Write as _;

    use super::*;

    #[test]
    fn the_bytes_are_those_written_by_hand() {
        let t = [0.0, 1e-7, 3.0, 1e16, 7.25];
        let positions = [[0.0, -1.5, 2.0], [1e-9, 3.0, 0.0], [4.0, 5.0, 6.0]];
        let tau = [0.0, 0.1, 1.0 / 3.0, 2.0, 1e-300];
        let mut expected = String::from("index,t_s,x,y,z,loop_duration_s\n");
        for (i, (&t, &tau)) in t.iter().zip(&tau).enumerate() {
            let [x, y, z] = positions.get(i).copied().unwrap_or([f64::NAN; 3]);
            let _ = writeln!(expected, "{i},{t},{x},{y},{z},{tau}");
        }
        let mut out = Vec::new();
        loop_duration_to_csv(&t, &positions, &tau, &mut out).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), expected);
        let row = loop_duration_rows(&t, &positions, &tau).next().unwrap();
        assert_eq!(crate::csv_rows::inferred_columns(&row), LOOP_DURATION_COLUMNS);
    }
}
