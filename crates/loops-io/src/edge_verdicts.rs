//! The loop-closure edges of a pose graph against the loops (`loops components --edges`): where
//! each edge's two poses fall ([`loops_core::Verdict`]), as CSV or JSON, with the counts per
//! verdict.

use std::io::{self, Write};
use std::path::Path;

use loops_core::{Loops, PairVerdict, Verdict};

use crate::atomic::write_atomically;
use crate::csv_rows::write_csv;
use crate::error::WriteError;
use crate::graph::{GraphEdge, PoseGraph};
use crate::json::write_json;
use crate::report::SeparationReport;

/// The columns of the edge verdicts CSV ([`EdgeVerdictRow`]).
pub const EDGE_VERDICT_COLUMNS: [&str; 10] =
    ["line", "from_id", "to_id", "i", "j", "t_s", "t_prime_s", "distance", "verdict", "component"];

/// One edge and its verdict: a row of the CSV, an object of the JSON `edges` list.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct EdgeVerdictRow {
    /// The edge's line in the graph file.
    pub line: usize,
    /// Its first vertex id.
    pub from_id: u64,
    /// Its second vertex id.
    pub to_id: u64,
    /// The pose index (trajectory row) of `from_id`.
    pub i: usize,
    /// The pose index of `to_id`.
    pub j: usize,
    /// The time of pose `i`, seconds.
    pub t_s: f64,
    /// The time of pose `j`, seconds.
    pub t_prime_s: f64,
    /// δ(x_i, x_j) under the loops' metric.
    pub distance: f64,
    /// `component`, `trivial`, `not-separated` or `outside` ([`Verdict::name`]).
    pub verdict: &'static str,
    /// The loop component holding the pair (trivial or not), if any.
    pub component: Option<usize>,
}

impl EdgeVerdictRow {
    /// The row of `edge` and its verdict `verdict` (whose pair are the edge's rows), with the
    /// times of `timestamps_s`.
    ///
    /// # Panics
    /// When the pair's indices are outside `timestamps_s`.
    pub fn new(edge: &GraphEdge, verdict: &PairVerdict, timestamps_s: &[f64]) -> Self {
        let [i, j] = verdict.pair;
        Self {
            line: edge.line,
            from_id: edge.from,
            to_id: edge.to,
            i,
            j,
            t_s: timestamps_s[i],
            t_prime_s: timestamps_s[j],
            distance: verdict.distance,
            verdict: verdict.verdict.name(),
            component: verdict.verdict.component(),
        }
    }
}

/// How many edges got each verdict.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct VerdictCounts {
    /// In a non-trivial loop component: a revisit.
    pub component: usize,
    /// In a trivial component (a simple loop; only without a separation).
    pub trivial: usize,
    /// Within γ, but closer along the trajectory than the separation: not a revisit.
    #[serde(rename = "not-separated")]
    pub not_separated: usize,
    /// Farther apart than γ: outside S_γ.
    pub outside: usize,
}

impl VerdictCounts {
    /// The counts of `verdicts`.
    pub fn of<'a>(verdicts: impl IntoIterator<Item = &'a Verdict>) -> Self {
        let mut counts = Self::default();
        for verdict in verdicts {
            match verdict {
                Verdict::Component { .. } => counts.component += 1,
                Verdict::Trivial { .. } => counts.trivial += 1,
                Verdict::NotSeparated => counts.not_separated += 1,
                Verdict::Outside => counts.outside += 1,
            }
        }
        counts
    }

    /// `(name, count)` in the order of [`Verdict::NAMES`].
    pub fn named(&self) -> [(&'static str, usize); 4] {
        let n = Verdict::NAMES;
        [(n[0], self.component), (n[1], self.trivial), (n[2], self.not_separated), (n[3], self.outside)]
    }

    /// The number of edges counted.
    pub fn total(&self) -> usize {
        self.component + self.trivial + self.not_separated + self.outside
    }
}

/// The loop-closure edges of a pose graph and their verdicts against loops found on its
/// vertices: the rows and counts the CSV and JSON files hold.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct EdgeVerdicts {
    /// Where the graph came from (`null` when not told).
    pub source: Option<String>,
    /// The number of edges of the graph.
    pub edges: usize,
    /// The number of loop closures among them (joining vertices more than one id apart): the
    /// edges classified.
    pub loop_closures: usize,
    /// γ, in the metric's unit.
    pub gamma: f64,
    /// The metric's name.
    pub metric: String,
    /// The loops' separation (both 0: the paper's S_γ, where no edge is `not-separated`).
    pub separation: SeparationReport,
    /// The edges per verdict.
    pub counts: VerdictCounts,
    /// One row per loop-closure edge, in file order.
    pub rows: Vec<EdgeVerdictRow>,
}

impl EdgeVerdicts {
    /// The verdicts of the loop-closure edges of `graph` ([`PoseGraph::loop_closures`]) against
    /// `loops`, found on the graph's vertices, under `metric` (the loops'). O(loop closures ·
    /// log runs + poses).
    ///
    /// # Errors
    /// [`loops_core::Error::TrajectoryMismatch`] when the graph's vertices are not the poses of
    /// `loops` (their times differ, as after dropping poses); as [`Loops::pair_verdicts`] when
    /// `traj` is not the trajectory of `loops` or `metric` not their metric.
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use loops_core::{Euclidean, Separation, find_loops_separated};
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-verdicts.g2o", std::process::id()));
    /// // Out and back along x; the edge 4 -> 0 closes the loop, 2 -> 0 is 2 m long.
    /// let vertices: String = [0.0, 1.0, 2.0, 1.0, 0.1].iter().enumerate().map(|(k, x)| format!("VERTEX_SE2 {k} {x} 0 0\n")).collect();
    /// std::fs::write(&path, vertices + "EDGE_SE2 4 0 0 0 0\nEDGE_SE2 2 0 0 0 0\n")?;
    /// let graph = loops_io::read_pose_graph(&path, &Default::default())?;
    /// let traj = graph.vertices.to_trajectory()?;
    /// let loops = find_loops_separated(&traj, &Euclidean, 0.5, Separation::path(2.0))?;
    /// let verdicts = loops_io::EdgeVerdicts::new(Some("graph"), &graph, &traj, &Euclidean, &loops)?;
    /// assert_eq!((verdicts.counts.component, verdicts.counts.outside), (1, 1));
    /// assert_eq!(verdicts.rows[0].verdict, "component");
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn new<M: loops_core::Metric + ?Sized>(
        source: Option<&str>,
        graph: &PoseGraph,
        traj: &loops_core::Trajectory,
        metric: &M,
        loops: &Loops,
    ) -> Result<Self, loops_core::Error> {
        let (a, b) = (&graph.vertices.timestamps_s, loops.timestamps_s());
        let differ = a.iter().zip(b).position(|(x, y)| x != y);
        if differ.is_some() || a.len() != b.len() || graph.vertex_ids.len() != a.len() {
            return Err(loops_core::Error::TrajectoryMismatch {
                what: "pose graph's vertices",
                index: differ.unwrap_or(a.len().min(b.len())),
                poses: a.len(),
                loops_poses: b.len(),
            });
        }
        let closures: Vec<&GraphEdge> = graph.loop_closures().collect();
        // Every edge of a graph read from a file joins two of its vertices; an edge of a graph
        // built otherwise without them is left out.
        let closures: Vec<(&GraphEdge, [usize; 2])> =
            closures.into_iter().filter_map(|edge| graph.edge_rows(edge).map(|rows| (edge, rows))).collect();
        let pairs: Vec<[usize; 2]> = closures.iter().map(|(_, rows)| *rows).collect();
        let verdicts = loops.pair_verdicts(traj, metric, &pairs)?;
        let t = traj.timestamps_s();
        Ok(Self {
            source: source.map(str::to_owned),
            edges: graph.edges.len(),
            loop_closures: closures.len(),
            gamma: loops.gamma(),
            metric: loops.metric_name().to_owned(),
            separation: loops.separation().into(),
            counts: VerdictCounts::of(verdicts.iter().map(|v| &v.verdict)),
            rows: closures
                .iter()
                .zip(&verdicts)
                .map(|((edge, _), verdict)| EdgeVerdictRow::new(edge, verdict, t))
                .collect(),
        })
    }

    /// Writes the rows as CSV: [`EDGE_VERDICT_COLUMNS`], then one line an edge (an empty
    /// `component` outside every component). O(rows).
    ///
    /// # Errors
    /// What `out` returns.
    pub fn to_csv<W: Write>(&self, out: W) -> io::Result<()> {
        write_csv(out, &EDGE_VERDICT_COLUMNS, &self.rows)
    }

    /// Writes everything as one pretty-printed JSON object: `source`, `edges`,
    /// `loop_closures`, `gamma`, `metric`, `separation`, `counts` (per verdict) and `rows`.
    ///
    /// # Errors
    /// What `out` returns.
    pub fn to_json<W: Write>(&self, out: W) -> io::Result<()> {
        write_json(self, out)
    }

    /// Writes the CSV ([`to_csv`](Self::to_csv)) to the file `path`, atomically
    /// ([`write_atomically`]); an existing file is replaced only with `overwrite`.
    ///
    /// # Errors
    /// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
    /// when it cannot be written.
    pub fn write_csv(&self, path: &Path, overwrite: bool) -> Result<(), WriteError> {
        write_atomically(path, overwrite, |out| self.to_csv(out))
    }

    /// Writes the JSON ([`to_json`](Self::to_json)) to the file `path`, as
    /// [`write_csv`](Self::write_csv) does.
    ///
    /// # Errors
    /// As [`write_csv`](Self::write_csv).
    pub fn write_json(&self, path: &Path, overwrite: bool) -> Result<(), WriteError> {
        write_atomically(path, overwrite, |out| self.to_json(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_columns_are_the_row_fields() {
        let row = EdgeVerdictRow {
            line: 1,
            from_id: 2,
            to_id: 0,
            i: 2,
            j: 0,
            t_s: 2.0,
            t_prime_s: 0.0,
            distance: 0.5,
            verdict: "outside",
            component: None,
        };
        assert_eq!(crate::csv_rows::inferred_columns(&row), EDGE_VERDICT_COLUMNS);
        let mut text = Vec::new();
        write_csv(&mut text, &EDGE_VERDICT_COLUMNS, [&row]).unwrap();
        assert_eq!(String::from_utf8(text).unwrap().lines().nth(1), Some("1,2,0,2,0,2,0,0.5,outside,"));
        let counts = VerdictCounts::of(&[Verdict::Outside, Verdict::NotSeparated, Verdict::Outside]);
        assert_eq!(counts.named().map(|(_, n)| n), [0, 0, 1, 2]);
        assert_eq!(serde_json::to_value(counts).unwrap()["not-separated"], 1);
    }
}
