//! `components.csv`: the loop components of a result, one row each ([`ComponentRow`]).

use std::io::{self, Write};
use std::path::Path;

use loops_core::{LoopComponent, Loops};

use crate::atomic::write_atomically;
use crate::csv_rows::write_csv;
use crate::error::WriteError;

/// The columns of `components.csv`, without the optional `samples`: the names of the Python
/// API's `Loops.components` columns. `id`, then [`MEASURE_COLUMNS`], [`EXTENT_COLUMNS`] and
/// [`CLOSEST_POSITION_COLUMNS`].
pub const COMPONENT_COLUMNS: [&str; 24] =
    columns(&[&["id"], &MEASURE_COLUMNS, &EXTENT_COLUMNS, &CLOSEST_POSITION_COLUMNS]);

/// The columns of a [`ClosestPositions`]: where the closest pair's two poses are, x, y and z of
/// pose `closest_i`, then of pose `closest_j` (the positions of `loop_duration.csv`).
pub const CLOSEST_POSITION_COLUMNS: [&str; 6] =
    ["closest_i_x", "closest_i_y", "closest_i_z", "closest_j_x", "closest_j_y", "closest_j_z"];

/// The columns of a [`ComponentMeasures`], as every component table names them.
pub const MEASURE_COLUMNS: [&str; 6] = ["trivial", "area_s2", "pair_count", "pose_pair_count", "run_count", "holes"];

/// The columns of a [`ComponentExtent`], as `components.csv` and a fleet's name them.
pub const EXTENT_COLUMNS: [&str; 11] = [
    "i_min",
    "i_max",
    "j_min",
    "j_max",
    "t_min_s",
    "t_max_s",
    "t_prime_min_s",
    "t_prime_max_s",
    "closest_i",
    "closest_j",
    "closest_distance",
];

/// The column groups `parts`, one after the other, as one table's columns (`N` of them).
///
/// # Panics
/// At compile time, when the groups do not hold `N` columns.
pub(crate) const fn columns<const N: usize>(parts: &[&[&'static str]]) -> [&'static str; N] {
    let mut out = [""; N];
    let mut k = 0;
    let mut part = 0;
    while part < parts.len() {
        let mut i = 0;
        while i < parts[part].len() {
            out[k] = parts[part][i];
            k += 1;
            i += 1;
        }
        part += 1;
    }
    assert!(k == N, "the column groups hold another number of columns");
    out
}

/// One row of `components.csv`: a [`LoopComponent`] with the times of its index ranges.
///
/// `i` indexes poses by t, `j` by t′ (`i_min..=i_max` and `j_min..=j_max` are the component's
/// index ranges); times are the poses' own timestamps, seconds. With the columns `B` of its
/// block after its id, a row of another table: a fleet's
/// ([`FleetComponentRow`](crate::FleetComponentRow), whose block is its two sessions; `P = ()`
/// for a table without positions).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ComponentRow<B = (), P = ClosestPositions> {
    /// The component's id: its index in [`Loops::components`].
    pub id: usize,
    /// Its block's columns (none for a trajectory's).
    #[serde(flatten)]
    pub block: B,
    /// Its measures.
    #[serde(flatten)]
    pub measures: ComponentMeasures,
    /// Its index ranges with their times, and its closest pair.
    #[serde(flatten)]
    pub extent: ComponentExtent,
    /// Where its closest pair's poses are.
    #[serde(flatten)]
    pub positions: P,
    /// Samples drawn from the component, when a sampling is written with it (the column is
    /// left out otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<u64>,
}

impl ComponentRow<()> {
    /// The row of `component`, with the times of `timestamps_s` (the trajectory the loops
    /// were found on), the positions of its poses when known, and, optionally, its number of
    /// samples.
    ///
    /// # Panics
    /// When the component's indices are outside `timestamps_s` or `positions` (loops of another
    /// trajectory).
    pub fn new(
        component: &LoopComponent,
        timestamps_s: &[f64],
        positions: Option<&[[f64; 3]]>,
        samples: Option<u64>,
    ) -> Self {
        let c = component;
        let extent =
            ComponentExtent::new([c.i_range, c.j_range], c.closest_pair, c.closest_distance, [timestamps_s; 2]);
        let positions = ClosestPositions::new(c.closest_pair, positions);
        Self { id: c.id, block: (), measures: ComponentMeasures::new(c), extent, positions, samples }
    }
}

/// Where a component's closest pair is: the positions of its two poses, the columns
/// [`CLOSEST_POSITION_COLUMNS`] (`None`: unknown, an empty field).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ClosestPositions {
    /// x of pose `closest_i`.
    pub closest_i_x: Option<f64>,
    /// y of pose `closest_i`.
    pub closest_i_y: Option<f64>,
    /// z of pose `closest_i`.
    pub closest_i_z: Option<f64>,
    /// x of pose `closest_j`.
    pub closest_j_x: Option<f64>,
    /// y of pose `closest_j`.
    pub closest_j_y: Option<f64>,
    /// z of pose `closest_j`.
    pub closest_j_z: Option<f64>,
}

impl ClosestPositions {
    /// The positions of the poses `closest_pair` among `positions` (none without them).
    ///
    /// # Panics
    /// When an index is outside `positions`.
    pub fn new(closest_pair: [usize; 2], positions: Option<&[[f64; 3]]>) -> Self {
        let Some(positions) = positions else { return Self::default() };
        Self::of_poses(closest_pair.map(|k| Some(positions[k])))
    }

    /// The positions of the poses `closest_pair` of `traj` ([`point_position`](crate::point_position)),
    /// without the positions of the others.
    ///
    /// # Panics
    /// When an index is not a pose of `traj`.
    pub fn of_trajectory(closest_pair: [usize; 2], traj: &loops_core::Trajectory) -> Self {
        Self::of_poses(closest_pair.map(|k| Some(crate::point_position(traj, k))))
    }

    /// The positions of the closest pair's poses `closest_i` and `closest_j` (`None`: unknown),
    /// wherever they come from: one trajectory's ([`ClosestPositions::new`]) or two sessions'
    /// ([`fleet_closest_positions`](crate::fleet_closest_positions)).
    pub fn of_poses(poses: [Option<[f64; 3]>; 2]) -> Self {
        let [[ix, iy, iz], [jx, jy, jz]] = poses.map(|p| p.map_or([None; 3], |p| p.map(Some)));
        Self { closest_i_x: ix, closest_i_y: iy, closest_i_z: iz, closest_j_x: jx, closest_j_y: jy, closest_j_z: jz }
    }
}

/// A component's measures, the columns every component table shares (`components.csv`, a
/// fleet's, the JSON report's components): [`LoopComponent`]'s fields of the same names, copied
/// on purpose into a serde row, so that the core's type stays free of a file's layout.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ComponentMeasures {
    /// Whether the component is trivial (touches the diagonal t = t′ only).
    pub trivial: bool,
    /// Its area in the (t, t′) plane, s².
    pub area_s2: f64,
    /// Its number of lattice cells, by the rule of `area_s2`.
    pub pair_count: u64,
    /// Its number of pose pairs {i, j}, i < j: the count summaries print.
    pub pose_pair_count: u64,
    /// Its number of runs (row intervals).
    pub run_count: usize,
    /// Its number of holes.
    pub holes: u64,
}

impl ComponentMeasures {
    /// The measures of `component`.
    pub fn new(component: &LoopComponent) -> Self {
        let c = component;
        Self {
            trivial: c.trivial,
            area_s2: c.area_s2,
            pair_count: c.pair_count,
            pose_pair_count: c.pose_pair_count,
            run_count: c.run_count,
            holes: c.holes,
        }
    }
}

/// Where a component lies, the columns `components.csv` and a fleet's share: its first and last
/// pose by t (`i`, the rows) and by t′ (`j`, the columns), their times, and its closest pair.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ComponentExtent {
    /// First pose index by t.
    pub i_min: usize,
    /// Last pose index by t.
    pub i_max: usize,
    /// First pose index by t′.
    pub j_min: usize,
    /// Last pose index by t′.
    pub j_max: usize,
    /// Time of pose `i_min`, seconds.
    pub t_min_s: f64,
    /// Time of pose `i_max`, seconds.
    pub t_max_s: f64,
    /// Time of pose `j_min`, seconds.
    pub t_prime_min_s: f64,
    /// Time of pose `j_max`, seconds.
    pub t_prime_max_s: f64,
    /// The pair of the component closest in the metric: pose by t.
    pub closest_i: usize,
    /// The pair of the component closest in the metric: pose by t′.
    pub closest_j: usize,
    /// δ of that pair, in the metric's unit.
    pub closest_distance: f64,
}

impl ComponentExtent {
    /// The extent of a component whose pose ranges' times are known already: `times_s` is
    /// `[[t_min, t_max], [t′_min, t′_max]]` (a fleet component's on its sessions' clocks).
    pub fn from_times(
        ranges: [[usize; 2]; 2],
        closest_pair: [usize; 2],
        closest_distance: f64,
        times_s: [[f64; 2]; 2],
    ) -> Self {
        let [[i_min, i_max], [j_min, j_max]] = ranges;
        let [[t_min_s, t_max_s], [t_prime_min_s, t_prime_max_s]] = times_s;
        Self {
            i_min,
            i_max,
            j_min,
            j_max,
            t_min_s,
            t_max_s,
            t_prime_min_s,
            t_prime_max_s,
            closest_i: closest_pair[0],
            closest_j: closest_pair[1],
            closest_distance,
        }
    }

    /// The extent of a component with the index ranges `[[i_min, i_max], [j_min, j_max]]`, its
    /// closest pair `[i, j]` at δ `closest_distance`, and the timestamps of the poses `i` index
    /// and of those `j` index (the same trajectory's twice, or two sessions').
    ///
    /// # Panics
    /// When an index is outside its timestamps.
    pub fn new(
        ranges: [[usize; 2]; 2],
        closest_pair: [usize; 2],
        closest_distance: f64,
        timestamps_s: [&[f64]; 2],
    ) -> Self {
        let [[i_min, i_max], [j_min, j_max]] = ranges;
        let [t, t_prime] = timestamps_s;
        Self::from_times(
            ranges,
            closest_pair,
            closest_distance,
            [[t[i_min], t[i_max]], [t_prime[j_min], t_prime[j_max]]],
        )
    }
}

/// The rows of `components.csv`: one per component of `loops`, in id order, with the times of
/// the trajectory they were found on and the `positions` of its poses, when known
/// ([`point_positions`](crate::point_positions), or a log's own). With `samples_per_component`
/// (by component id, as [`SampleQuality::per_component`](loops_core::SampleQuality::per_component)),
/// each row has its number of samples (0 for an id past its end). O(components).
///
/// # Panics
/// When `positions` has another length than the loops' trajectory.
pub fn component_rows(
    loops: &Loops,
    positions: Option<&[[f64; 3]]>,
    samples_per_component: Option<&[u64]>,
) -> Vec<ComponentRow> {
    let t = loops.timestamps_s();
    assert!(positions.is_none_or(|p| p.len() == t.len()), "positions of another trajectory");
    loops
        .components()
        .iter()
        .map(|c| ComponentRow::new(c, t, positions, samples_per_component.map(|s| s.get(c.id).copied().unwrap_or(0))))
        .collect()
}

/// Writes `components.csv` to `out`: a header of [`COMPONENT_COLUMNS`] (and `samples` with
/// `samples_per_component`), then the [`component_rows`]. Numbers are printed in the shortest
/// form that reads back as the same `f64`, without an exponent. O(components).
///
/// # Errors
/// What `out` returns.
///
/// # Panics
/// As [`component_rows`].
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, Trajectory, find_loops};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &[[0.0], [1.0], [1.0], [0.0]])?;
/// let loops = find_loops(&traj, &Euclidean, 0.5)?;
/// let mut text = Vec::new();
/// let positions = loops_io::point_positions(&traj);
/// loops_io::components_to_csv(&loops, Some(&positions), None, &mut text).unwrap();
/// let text = String::from_utf8(text).unwrap();
/// assert!(text.starts_with("id,trivial,area_s2,pair_count,pose_pair_count,run_count,holes,i_min,"));
/// assert_eq!(text.lines().count(), 1 + loops.components().len());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn components_to_csv<W: Write>(
    loops: &Loops,
    positions: Option<&[[f64; 3]]>,
    samples_per_component: Option<&[u64]>,
    out: W,
) -> io::Result<()> {
    let rows = component_rows(loops, positions, samples_per_component);
    component_rows_to_csv(&rows, samples_per_component.is_some(), out)
}

/// Writes `components.csv` from its `rows` ([`component_rows`], with the closest pairs'
/// positions set wherever they come from): a header of [`COMPONENT_COLUMNS`] (and `samples`
/// `with_samples`), then the rows, as [`components_to_csv`] writes them. O(components).
///
/// # Errors
/// What `out` returns.
pub fn component_rows_to_csv<W: Write>(rows: &[ComponentRow], with_samples: bool, out: W) -> io::Result<()> {
    let mut columns = COMPONENT_COLUMNS.to_vec();
    if with_samples {
        columns.push("samples");
    }
    write_csv(out, &columns, rows)
}

/// Writes `components.csv` ([`components_to_csv`]) to the file `path`, atomically
/// ([`write_atomically`](crate::write_atomically)); an existing file is replaced only with
/// `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
///
/// # Panics
/// As [`component_rows`].
pub fn write_components(
    path: impl AsRef<Path>,
    loops: &Loops,
    positions: Option<&[[f64; 3]]>,
    samples_per_component: Option<&[u64]>,
    overwrite: bool,
) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |file| components_to_csv(loops, positions, samples_per_component, file))
}

#[cfg(test)]
mod tests {
    use std::fmt::Write as _;

    use loops_core::{Euclidean, Trajectory, find_loops};

    use super::*;

    fn result() -> (Trajectory, Loops) {
        let t = vec![0.0, 0.5, 1.0, 1.5, 2.0, 3.0000001, 10.0];
        let x: [[f64; 1]; 7] = [[0.0], [1.0], [2.0], [1.0], [0.0], [0.05], [7.0]];
        let traj = Trajectory::from_points(t, &x).unwrap();
        let loops = find_loops(&traj, &Euclidean, 0.5).unwrap();
        (traj, loops)
    }

    /// components.csv as `loops run` wrote it with `writeln!`, the positions the trajectory's
    /// points (1-D: y and z are 0).
    fn by_hand(traj: &Trajectory, loops: &Loops, samples: Option<&[u64]>) -> String {
        let t = traj.timestamps_s();
        let mut csv = COMPONENT_COLUMNS.join(",");
        if samples.is_some() {
            csv += ",samples";
        }
        csv.push('\n');
        for c in loops.components() {
            let _ = write!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},0,0,{},0,0",
                c.id,
                c.trivial,
                c.area_s2,
                c.pair_count,
                c.pose_pair_count,
                c.run_count,
                c.holes,
                c.i_range[0],
                c.i_range[1],
                c.j_range[0],
                c.j_range[1],
                t[c.i_range[0]],
                t[c.i_range[1]],
                t[c.j_range[0]],
                t[c.j_range[1]],
                c.closest_pair[0],
                c.closest_pair[1],
                c.closest_distance,
                traj.point(c.closest_pair[0])[0],
                traj.point(c.closest_pair[1])[0],
            );
            if let Some(samples) = samples {
                let _ = write!(csv, ",{}", samples.get(c.id).copied().unwrap_or(0));
            }
            csv.push('\n');
        }
        csv
    }

    #[test]
    fn the_bytes_are_those_written_by_hand() {
        let (traj, loops) = result();
        assert!(loops.components().iter().any(|c| !c.trivial));
        for samples in [None, Some(&[3u64, 0][..])] {
            let mut out = Vec::new();
            components_to_csv(&loops, Some(&crate::point_positions(&traj)), samples, &mut out).unwrap();
            assert_eq!(String::from_utf8(out).unwrap(), by_hand(&traj, &loops, samples));
        }
    }

    #[test]
    fn the_columns_name_the_row_fields() {
        let (_, loops) = result();
        let rows = component_rows(&loops, None, Some(&[1]));
        let mut expected: Vec<&str> = COMPONENT_COLUMNS.to_vec();
        expected.push("samples");
        assert_eq!(crate::csv_rows::inferred_columns(&rows[0]), expected);
        assert_eq!(rows[0].samples, Some(1));
        assert_eq!(rows.last().unwrap().samples, Some(0));
        assert_eq!(rows[0].positions, ClosestPositions::default());
        let mut unknown = Vec::new();
        components_to_csv(&loops, None, None, &mut unknown).unwrap();
        let unknown = String::from_utf8(unknown).unwrap();
        assert!(unknown.lines().skip(1).all(|line| line.ends_with(",,,,,,")), "{unknown}");
    }
}
