//! `PoseGraph` and `read_pose_graph`: a g2o/TORO pose graph's vertices as a trajectory and a
//! table, its edges (relative pose, information) as a table, and where its loop-closure edges
//! fall against the loops (the verdicts of `Loops.pair_verdicts`).

use std::path::PathBuf;
use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyType;

use crate::convert::{bool_column, float64_column, id_column, int64_column, str_column, table, to_numpy};
use crate::detached;
use crate::error::Failure;
use crate::py_loops::Loops;
use crate::py_metric::{MetricArg, loops_metric};
use crate::py_trajectory::{ReadArgs, Source, Trajectory, trajectory_for};
use loops_io::{GraphEdge, RelativePose};

/// The information columns: the upper triangle of the 3 × 3 (2-D) or 6 × 6 (3-D) matrix, row by
/// row.
const INFORMATION_2D: [&str; 6] = ["info_00", "info_01", "info_02", "info_11", "info_12", "info_22"];
const INFORMATION_3D: [&str; 21] = [
    "info_00", "info_01", "info_02", "info_03", "info_04", "info_05", "info_11", "info_12", "info_13", "info_14",
    "info_15", "info_22", "info_23", "info_24", "info_25", "info_33", "info_34", "info_35", "info_44", "info_45",
    "info_55",
];

/// A pose graph read from a g2o or TORO file (:func:`read_pose_graph`): its vertices as a
/// :class:`Trajectory` and a :class:`~inexact_loops.Table`, and its edges — odometry and loop
/// closures, with their relative poses and information matrices — as a table.
///
/// Row k of :attr:`vertices` is pose k of :attr:`trajectory` (vertices sorted by id); the
/// edges' ``i`` and ``j`` are those pose indices. The vertex values of the classic data sets
/// are odometry guesses, not ground truth.
///
/// Example:
///     >>> import pathlib, tempfile, inexact_loops as il
///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "square.g2o"
///     >>> _ = path.write_text(
///     ...     "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 1.5708\nVERTEX_SE2 2 1 1 3.1416\n"
///     ...     "EDGE_SE2 0 1 1 0 1.5708 10 0 0 10 0 100\nEDGE_SE2 1 2 1 0 1.5708 10 0 0 10 0 100\n"
///     ...     "EDGE_SE2 2 0 1 1 -3.1416 5 0 0 5 0 50\n")
///     >>> graph = il.read_pose_graph(path)
///     >>> graph
///     PoseGraph(3 vertices, 3 edges, 1 loop closures, 2-D)
///     >>> edges = graph.edges
///     >>> edges["i"].tolist(), edges["j"].tolist(), edges["loop_closure"].tolist()
///     ([0, 1, 2], [1, 2, 0], [False, False, True])
///     >>> edges["dtheta"].tolist(), edges["info_22"].tolist()
///     ([1.5708, 1.5708, -3.1416], [100.0, 100.0, 50.0])
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct PoseGraph {
    graph: Arc<loops_io::PoseGraph>,
    trajectory: Py<Trajectory>,
}

/// Checks that the parts of a graph read back from a state fit together and fit `traj`, its
/// trajectory: every table column one entry per vertex, ids increasing, every edge between two
/// of its vertices with a measurement and information of the graph's dimension.
fn check_graph(graph: &loops_io::PoseGraph, traj: &loops_core::Trajectory) -> Result<(), String> {
    let v = &graph.vertices;
    let n = graph.vertex_ids.len();
    if v.dim != 2 && v.dim != 3 {
        return Err(format!("its vertices have {} coordinates (2 or 3)", v.dim));
    }
    let lengths = [
        ("times", v.timestamps_s.len()),
        ("positions", v.positions.len()),
        ("orientations", v.orientations_xyzw.as_ref().map_or(n, Vec::len)),
        ("integer times", v.timestamps_ns.as_ref().map_or(n, Vec::len)),
        ("lines", if v.source_lines.is_empty() { n } else { v.source_lines.len() }),
    ];
    if let Some((what, len)) = lengths.into_iter().find(|&(_, len)| len != n) {
        return Err(format!("{n} vertex ids but {len} {what}"));
    }
    if let Some(k) = graph.vertex_ids.windows(2).position(|w| w[0] >= w[1]) {
        return Err(format!(
            "vertex id {} follows {}: ids must increase",
            graph.vertex_ids[k + 1],
            graph.vertex_ids[k]
        ));
    }
    let information = if v.dim == 2 { 6 } else { 21 };
    for (k, edge) in graph.edges.iter().enumerate() {
        let dim = match edge.measurement {
            RelativePose::Se2 { .. } => 2,
            RelativePose::Se3 { .. } => 3,
        };
        let joins = graph.edge_rows(edge).is_some();
        let sized = edge.information.is_empty() || edge.information.len() == information;
        if !joins || dim != v.dim || !sized {
            return Err(format!(
                "edge {k} (line {}, {} -> {}) does not fit a {}-D graph of its vertices",
                edge.line, edge.from, edge.to, v.dim
            ));
        }
    }
    if traj.timestamps_s() != v.timestamps_s.as_slice() {
        return Err(format!("its trajectory has {} poses, not its {n} vertices' times", traj.len()));
    }
    Ok(())
}

#[pymethods]
impl PoseGraph {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<crate::pickling::ReducedWith<'py, Trajectory>> {
        let this = slf.get();
        crate::pickling::reduce_with(slf.as_any(), "PoseGraph", &*this.graph, this.trajectory.clone_ref(slf.py()))
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8], trajectory: &Bound<'_, PyAny>) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "PoseGraph", || {
            let py = cls.py();
            let trajectory = crate::pickling::companion::<Trajectory>(trajectory, "PoseGraph", "trajectory")?;
            let graph: loops_io::PoseGraph = crate::pickling::restore(py, "PoseGraph", state)?;
            check_graph(&graph, &trajectory.get().inner)
                .map_err(|reason| crate::pickling::invalid(py, "PoseGraph", reason))?;
            Ok(Self { graph: Arc::new(graph), trajectory: trajectory.clone().unbind() })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        let (a, b) = (self.trajectory.get(), other.trajectory.get());
        self.graph == other.graph && a.inner == b.inner && a.plane_axes == b.plane_axes && a.metric == b.metric
    }

    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.graph.vertex_ids.len() as u64, self.graph.edges.len() as u64])
    }

    fn __repr__(&self) -> String {
        let g = &self.graph;
        let chained = if g.chain.is_some() { ", chained from its edges" } else { "" };
        format!(
            "PoseGraph({} vertices, {} edges, {} loop closures, {}-D{chained})",
            g.vertex_ids.len(),
            g.edges.len(),
            g.loop_closures().count(),
            g.vertices.dim
        )
    }

    /// The vertices as a :class:`Trajectory`, built for the ``metric`` and ``axes`` given to
    /// :func:`read_pose_graph` (positions by default); pose k is vertex ``vertex_ids[k]``.
    #[getter]
    fn trajectory(&self, py: Python<'_>) -> Py<Trajectory> {
        self.trajectory.clone_ref(py)
    }

    /// The vertex ids, increasing: int64, one per pose.
    #[getter]
    fn vertex_ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.graph.vertex_ids.iter().map(|&id| id as i64).collect())
    }

    /// 2 or 3: the dimension of the graph's poses.
    #[getter]
    fn dim(&self) -> usize {
        self.graph.vertices.dim
    }

    /// Whether the file had no vertices and they were chained from its odometry edges
    /// (``chain_edges=True``): dead reckoning.
    #[getter]
    fn chained(&self) -> bool {
        self.graph.chain.is_some()
    }

    /// The vertices as a :class:`~inexact_loops.Table`, one row per pose of :attr:`trajectory`:
    /// ``id`` (int64), ``t`` (float64, seconds: the id, or as ``rate_hz`` / ``times`` say),
    /// ``x``, ``y``, then ``theta`` (2-D: the heading, radians in (−π, π]) or ``z``, ``qx``,
    /// ``qy``, ``qz``, ``qw`` (3-D), and ``line`` (int64: the vertex's line in the file; for a
    /// chained graph, the line of the edge that placed it).
    ///
    /// Example:
    ///     >>> import pathlib, tempfile, inexact_loops as il
    ///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "two.graph"
    ///     >>> _ = path.write_text("VERTEX2 7 1.5 2 0.25\nVERTEX2 3 0 0 0\n")
    ///     >>> vertices = il.read_pose_graph(path).vertices
    ///     >>> list(vertices), vertices["id"].tolist(), vertices["theta"].tolist()
    ///     (['id', 't', 'x', 'y', 'theta', 'line'], [3, 7], [0.0, 0.25])
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = &self.graph;
        let v = &g.vertices;
        let rows: Vec<usize> = (0..v.len()).collect();
        let mut columns = vec![
            ("id", int64_column(py, &g.vertex_ids, |&id| id as usize)),
            ("t", float64_column(py, &v.timestamps_s, |&t| t)),
            ("x", float64_column(py, &v.positions, |p| p[0])),
            ("y", float64_column(py, &v.positions, |p| p[1])),
        ];
        match (g.headings_rad(), &v.orientations_xyzw) {
            (Some(headings), _) => columns.push(("theta", float64_column(py, &headings, |&h| h))),
            (None, orientations) => {
                columns.push(("z", float64_column(py, &v.positions, |p| p[2])));
                for (name, axis) in [("qx", 0), ("qy", 1), ("qz", 2), ("qw", 3)] {
                    let value = |&k: &usize| orientations.as_ref().map_or(f64::NAN, |o| o[k][axis]);
                    columns.push((name, float64_column(py, &rows, value)));
                }
            }
        }
        columns.push(("line", int64_column(py, &rows, |&k| v.source_lines.get(k).copied().unwrap_or(0))));
        table(py, columns)
    }

    /// The edges as a :class:`~inexact_loops.Table`, one row per edge in file order: ``line``,
    /// ``from_id``, ``to_id`` (int64), ``i``, ``j`` (int64: the pose indices of the two
    /// vertices in :attr:`trajectory`), ``loop_closure`` (bool: the vertices are more than one
    /// id apart), the measured pose of ``to_id`` in the frame of ``from_id`` — ``dx``, ``dy``,
    /// ``dtheta`` (2-D, as written) or ``dx``, ``dy``, ``dz``, ``qx``, ``qy``, ``qz``, ``qw``
    /// (3-D; TORO's roll, pitch, yaw as a quaternion) — and the information matrix's upper
    /// triangle ``info_ab`` (float64, rows and columns x, y, θ in 2-D; x, y, z and the three
    /// rotation parameters in 3-D; g2o's order, TORO's ``EDGE2`` reordered; NaN where the line
    /// gives none).
    ///
    /// The full matrices, shape ``(edges, 3, 3)`` in 2-D::
    ///
    ///     info = np.zeros((edges.num_rows, 3, 3))
    ///     for a in range(3):
    ///         for b in range(a, 3):
    ///             info[:, a, b] = info[:, b, a] = edges[f"info_{a}{b}"]
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = &self.graph;
        let e = &g.edges;
        let rows = |edge: &GraphEdge| g.edge_rows(edge).unwrap_or([usize::MAX, usize::MAX]);
        let mut columns = vec![
            ("line", int64_column(py, e, |edge| edge.line)),
            ("from_id", int64_column(py, e, |edge| edge.from as usize)),
            ("to_id", int64_column(py, e, |edge| edge.to as usize)),
            ("i", int64_column(py, e, |edge| rows(edge)[0])),
            ("j", int64_column(py, e, |edge| rows(edge)[1])),
            ("loop_closure", bool_column(py, e, GraphEdge::is_loop_closure)),
        ];
        let se2 = |edge: &GraphEdge, k: usize| match edge.measurement {
            RelativePose::Se2 { translation, rotation_rad } => [translation[0], translation[1], rotation_rad][k],
            RelativePose::Se3 { .. } => f64::NAN,
        };
        let se3 = |edge: &GraphEdge, k: usize| match edge.measurement {
            RelativePose::Se3 { translation: t, rotation_xyzw: q } => [t[0], t[1], t[2], q[0], q[1], q[2], q[3]][k],
            RelativePose::Se2 { .. } => f64::NAN,
        };
        let information: &[&'static str] = if g.vertices.dim == 2 {
            for (k, name) in ["dx", "dy", "dtheta"].into_iter().enumerate() {
                columns.push((name, float64_column(py, e, |edge| se2(edge, k))));
            }
            &INFORMATION_2D
        } else {
            for (k, name) in ["dx", "dy", "dz", "qx", "qy", "qz", "qw"].into_iter().enumerate() {
                columns.push((name, float64_column(py, e, |edge| se3(edge, k))));
            }
            &INFORMATION_3D
        };
        for (k, &name) in information.iter().enumerate() {
            columns.push((name, float64_column(py, e, |edge| edge.information.get(k).copied().unwrap_or(f64::NAN))));
        }
        table(py, columns)
    }

    /// Where each loop-closure edge (vertices more than one id apart) falls against ``loops``,
    /// found on :attr:`trajectory`: a :class:`~inexact_loops.Table` with the rows and columns of
    /// ``loops components --edges-csv`` — ``line``, ``from_id``, ``to_id``, ``i``, ``j``,
    /// ``t_s``, ``t_prime_s``, ``distance`` (δ under the loops' metric), ``verdict`` (str) and
    /// ``component`` (int64, −1 in none). The verdicts are those of :meth:`Loops.pair_verdicts`:
    /// ``"component"``, ``"trivial"``, ``"not-separated"``, ``"outside"``.
    ///
    /// Args:
    ///     loops: :class:`Loops` found on :attr:`trajectory`.
    ///     metric: the metric the loops were found with; ``None`` takes it from the loops (pass
    ///         the same callable for loops found with one).
    ///
    /// Raises:
    ///     InvalidParameterError: loops of another trajectory or metric.
    ///
    /// Example:
    ///     >>> import pathlib, tempfile, inexact_loops as il
    ///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "back.g2o"
    ///     >>> xs = [0, 1, 2, 3, 2, 1, 0.1]
    ///     >>> text = "".join(f"VERTEX_SE2 {k} {x} 0 0\n" for k, x in enumerate(xs))
    ///     >>> _ = path.write_text(text + "EDGE_SE2 6 0 0 0 0\nEDGE_SE2 4 2 0 0 0\nEDGE_SE2 3 0 0 0 0\n")
    ///     >>> graph = il.read_pose_graph(path)
    ///     >>> loops = il.find_loops(graph.trajectory, gamma=0.5, separation=il.Separation(path=3.0))
    ///     >>> graph.edge_verdicts(loops)["verdict"].tolist()
    ///     ['component', 'not-separated', 'outside']
    #[pyo3(signature = (loops, *, metric=None))]
    fn edge_verdicts<'py>(
        &self,
        py: Python<'py>,
        loops: &Loops,
        metric: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let metric = loops_metric(metric, &loops.inner)?;
        let (graph, inner) = (Arc::clone(&self.graph), Arc::clone(&loops.inner));
        let traj = Arc::clone(&self.trajectory.get().inner);
        let verdicts =
            metric.run(py, None, move |m| loops_io::EdgeVerdicts::new(None, &graph, &traj, m.as_metric(), &inner))?;
        let r = &verdicts.rows;
        table(
            py,
            [
                ("line", int64_column(py, r, |row| row.line)),
                ("from_id", int64_column(py, r, |row| row.from_id as usize)),
                ("to_id", int64_column(py, r, |row| row.to_id as usize)),
                ("i", int64_column(py, r, |row| row.i)),
                ("j", int64_column(py, r, |row| row.j)),
                ("t_s", float64_column(py, r, |row| row.t_s)),
                ("t_prime_s", float64_column(py, r, |row| row.t_prime_s)),
                ("distance", float64_column(py, r, |row| row.distance)),
                ("verdict", str_column(py, r.iter().map(|row| row.verdict))?),
                ("component", id_column(py, r.iter().map(|row| row.component)).into_any()),
            ],
        )
    }
}

/// Reads a pose graph in g2o or TORO text (``VERTEX_SE2`` / ``VERTEX2``, ``VERTEX_SE3:QUAT``,
/// ``VERTEX3`` and their ``EDGE`` lines): its vertices as a trajectory and a table, and its
/// edges — relative pose and information matrix — as a table (:class:`PoseGraph`).
///
/// A file of edges without vertices (an ``EDGE3`` list, ``EDGE2`` odometry and loop closures)
/// is an error, unless ``chain_edges=True``: then its odometry edges (vertex k to k + 1) are
/// composed from the first vertex at the origin, and a :class:`DeadReckoningWarning` says that
/// the poses are dead reckoning, whose error grows along the path. A gap in the chain is an
/// error naming the vertex no edge reaches.
///
/// Args:
///     path: the file (``.g2o``, ``.graph``, or a ``.txt`` whose first line is a vertex or edge).
///     metric, axes: the trajectory's points, as in :func:`read_trajectory` (positions by
///         default; ``"se2(rotation_weight_m_per_rad=W)"`` for x, y and the heading).
///     rate_hz: vertex id k at k / rate_hz seconds (default: the id in seconds).
///     times: a file of one time a line, one per vertex in id order.
///     chain_edges: chain the odometry edges of a file without vertices (dead reckoning).
///     quaternion_tolerance: as in :func:`read_trajectory`.
///
/// Returns:
///     :class:`PoseGraph`.
///
/// Raises:
///     OSError: the file cannot be opened. LoopsIOError: a malformed line (naming it), edges
///     without vertices (naming ``chain_edges``), a gap in the odometry chain.
///     InvalidParameterError: both ``rate_hz`` and ``times``; a metric whose points are not
///     poses.
///
/// Warns:
///     DeadReckoningWarning: the vertices were chained from the edges (``chain_edges=True`` on
///         a file without vertices).
///
/// Example:
///     >>> import pathlib, tempfile, warnings, inexact_loops as il
///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "edges.graph"
///     >>> _ = path.write_text("EDGE2 0 1 1 0 1.5707963267948966\nEDGE2 1 2 1 0 0\nEDGE2 2 0 -1 1 -1.5707963267948966\n")
///     >>> with warnings.catch_warnings(record=True) as caught:
///     ...     warnings.simplefilter("always")
///     ...     graph = il.read_pose_graph(path, chain_edges=True)
///     >>> graph.trajectory.positions.round(12).tolist(), caught[0].category.__name__
///     ([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], 'DeadReckoningWarning')
#[pyfunction]
#[pyo3(signature = (path, *, metric=None, axes=None, rate_hz=None, times=None, chain_edges=false,
    quaternion_tolerance=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn read_pose_graph(
    py: Python<'_>,
    path: PathBuf,
    metric: Option<&Bound<'_, PyAny>>,
    axes: Option<(usize, usize)>,
    rate_hz: Option<f64>,
    times: Option<PathBuf>,
    chain_edges: bool,
    quaternion_tolerance: Option<f64>,
) -> PyResult<PoseGraph> {
    let spec = MetricArg::spec_from_py(metric, "read_pose_graph")?;
    let options = ReadArgs { rate_hz, times, chain_edges, ..ReadArgs::default() }.options()?;
    let (graph, traj) = detached(py, move || {
        let mut graph = loops_io::read_pose_graph_with(&path, &options)?;
        if let Some(tolerance) = quaternion_tolerance {
            graph.vertices.normalize_orientations(tolerance)?;
        }
        let traj = trajectory_for(&graph.vertices, &spec, axes, Source::File)?;
        Ok::<_, Failure>((graph, traj))
    })?;
    if let Some(chain) = &graph.chain {
        crate::warning::warn_dead_reckoning(py, &chain.to_string())?;
    }
    if let Some(skipped) = &graph.skipped {
        crate::warning::warn_dropped_input(py, &skipped.to_string())?;
    }
    let trajectory = Trajectory::read(traj, axes, metric.is_some().then_some(spec));
    Ok(PoseGraph { graph: Arc::new(graph), trajectory: Py::new(py, trajectory)? })
}
