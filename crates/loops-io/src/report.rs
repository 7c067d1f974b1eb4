//! The loops report in JSON (`loops components --json`): the result's facts and every
//! component ([`LoopsReport`]).

use std::io::{self, Write};
use std::path::Path;

use loops_core::{LoopComponent, Loops, Scale, Selection, Side};

use crate::atomic::write_atomically;
use crate::components::ComponentMeasures;
use crate::error::WriteError;
use crate::json::write_json;

/// What [`find_loops`](loops_core::find_loops) found on a trajectory, as a JSON document.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct LoopsReport {
    /// Where the trajectory came from: a file name, `synthetic`, ... (`null` when not told).
    pub source: Option<String>,
    /// The number of poses.
    pub poses: usize,
    /// The trajectory's time span, seconds.
    pub span_s: f64,
    /// γ, in the metric's unit.
    pub gamma: f64,
    /// The metric's name.
    pub metric: String,
    /// The separation the pairs keep (both 0: the paper's S_γ).
    pub separation: SeparationReport,
    /// The number of cells of S_γ in the full (t, t′) plane ((i, j) and (j, i) both; in the
    /// revisits, with a separation).
    pub pair_count: u64,
    /// The number of pose pairs {i, j}, i < j, of S_γ: the count summaries print, and the sum
    /// of the components' `pose_pair_count`.
    pub pose_pair_count: u64,
    /// The mean loop duration over the whole trajectory, seconds.
    pub loop_density_s: f64,
    /// The result's warnings, as sentences.
    pub warnings: Vec<String>,
    /// Every component, by id.
    pub components: Vec<ComponentReport>,
}

/// The separation of a [`LoopsReport`]: `{"path": 24.0, "time_s": 0.0}`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SeparationReport {
    /// Minimum path length between the poses of a pair, in the metric's unit.
    pub path: f64,
    /// Minimum time between them, seconds.
    pub time_s: f64,
}

impl From<loops_core::Separation> for SeparationReport {
    fn from(s: loops_core::Separation) -> Self {
        Self { path: s.path, time_s: s.time_s }
    }
}

/// One component of a [`LoopsReport`]: ranges as `[first, last]`, times in seconds (the poses'
/// own timestamps). Its measures are `components.csv`'s; where the component lies is spelled as
/// ranges, the JSON report's layout, where `components.csv` has a column each
/// ([`ComponentExtent`](crate::ComponentExtent)).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct ComponentReport {
    /// The component's id.
    pub id: usize,
    /// Its measures.
    #[serde(flatten)]
    pub measures: ComponentMeasures,
    /// The times of its first and last pose by t, seconds.
    pub t_range_s: [f64; 2],
    /// The times of its first and last pose by t′, seconds.
    pub t_prime_range_s: [f64; 2],
    /// Its first and last pose index by t.
    pub i_range: [usize; 2],
    /// Its first and last pose index by t′.
    pub j_range: [usize; 2],
    /// Its pair closest in the metric, `[i, j]`.
    pub closest_pair: [usize; 2],
    /// δ of that pair, in the metric's unit.
    pub closest_distance: f64,
}

impl ComponentReport {
    /// The report of `component`, with the times of `timestamps_s` (the trajectory the loops
    /// were found on).
    ///
    /// # Panics
    /// When the component's indices are outside `timestamps_s`.
    pub fn new(component: &LoopComponent, timestamps_s: &[f64]) -> Self {
        let (c, t) = (component, timestamps_s);
        Self {
            id: c.id,
            measures: ComponentMeasures::new(c),
            t_range_s: [t[c.i_range[0]], t[c.i_range[1]]],
            t_prime_range_s: [t[c.j_range[0]], t[c.j_range[1]]],
            i_range: c.i_range,
            j_range: c.j_range,
            closest_pair: c.closest_pair,
            closest_distance: c.closest_distance,
        }
    }
}

impl LoopsReport {
    /// The report of `loops`, found on a trajectory read from `source` (when known).
    /// O(poses + components).
    ///
    /// # Errors
    /// What [`Loops::loop_density`] returns (nothing for a result of
    /// [`find_loops`](loops_core::find_loops)).
    pub fn new(source: Option<&str>, loops: &Loops) -> Result<Self, loops_core::Error> {
        let t = loops.timestamps_s();
        Ok(Self {
            source: source.map(str::to_owned),
            poses: loops.len(),
            span_s: loops.span_s(),
            gamma: loops.gamma(),
            metric: loops.metric_name().to_owned(),
            separation: loops.separation().into(),
            pair_count: loops.pair_count(),
            pose_pair_count: loops.pose_pair_count(),
            loop_density_s: loops.loop_density(t[0], t[t.len() - 1], Selection::All, Side::Both, Scale::Seconds)?,
            warnings: loops.warnings().iter().map(ToString::to_string).collect(),
            components: loops.components().iter().map(|c| ComponentReport::new(c, t)).collect(),
        })
    }
}

/// Writes `report` to `out` as pretty-printed JSON and a final newline. O(components).
///
/// # Errors
/// What `out` returns.
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, Trajectory, find_loops};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &[[0.0], [1.0], [1.0], [0.0]])?;
/// let loops = find_loops(&traj, &Euclidean, 0.5)?;
/// let report = loops_io::LoopsReport::new(Some("line"), &loops)?;
/// let mut text = Vec::new();
/// loops_io::loops_report_to_json(&report, &mut text).unwrap();
/// let value: serde_json::Value = serde_json::from_slice(&text).unwrap();
/// assert_eq!(value["poses"], 4);
/// assert_eq!(value["components"][0]["i_range"], serde_json::json!([0, 0])); // [first, last]
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn loops_report_to_json<W: Write>(report: &LoopsReport, out: W) -> io::Result<()> {
    write_json(report, out)
}

/// Writes `report` ([`loops_report_to_json`]) to the file `path`, atomically
/// ([`write_atomically`](crate::write_atomically)); an existing file is replaced only with
/// `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
pub fn write_loops_report(path: impl AsRef<Path>, report: &LoopsReport, overwrite: bool) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |file| loops_report_to_json(report, file))
}

#[cfg(test)]
mod tests {
    use loops_core::{Euclidean, Trajectory, find_loops};

    use super::*;
    use crate::json::ClosedPipe;

    #[test]
    fn the_document_is_what_serde_json_prints() {
        let traj =
            Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0, 4.5], &[[0.0], [1.0], [1.0], [0.0], [0.1]]).unwrap();
        let loops = find_loops(&traj, &Euclidean, 0.5).unwrap();
        let report = LoopsReport::new(Some("drive.tum"), &loops).unwrap();
        let mut out = Vec::new();
        loops_report_to_json(&report, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(text, serde_json::to_string_pretty(&report).unwrap() + "\n");
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        // The keys in the order of the CLI's report (serde_json's `Value` sorts them: look at the text).
        let component = &text[text.find("\"components\"").unwrap()..];
        let at = |key: &str| component.find(&format!("\"{key}\":")).unwrap();
        let keys = [
            "id",
            "trivial",
            "area_s2",
            "pair_count",
            "pose_pair_count",
            "run_count",
            "holes",
            "t_range_s",
            "t_prime_range_s",
            "i_range",
            "j_range",
            "closest_pair",
            "closest_distance",
        ];
        assert!(keys.windows(2).all(|pair| at(pair[0]) < at(pair[1])));
        assert_eq!(value["poses"], 5);
        assert_eq!(value["span_s"], 4.5);
    }

    #[test]
    fn a_closed_pipe_is_reported_as_one() {
        // Poses alternating between two points 10 apart: every pair of the same parity is its
        // own component, so the document outgrows the buffer and serde_json meets the error.
        let n = 40;
        let points: Vec<[f64; 1]> = (0..n).map(|i| [f64::from(i % 2) * 10.0]).collect();
        let traj = Trajectory::from_points((0..n).map(f64::from).collect(), &points).unwrap();
        let loops = find_loops(&traj, &Euclidean, 0.5).unwrap();
        let report = LoopsReport::new(None, &loops).unwrap();
        assert!(serde_json::to_string_pretty(&report).unwrap().len() > 64 * 1024);
        let error = loops_report_to_json(&report, ClosedPipe).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::BrokenPipe);
    }
}
