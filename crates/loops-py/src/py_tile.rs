//! Tiles of a fleet's plane, for a cluster: `SessionBlocks` (`session_blocks`), `Tile`
//! (`plan_tiles`) and `TileSummary`; the scan is in `py_tile_scan`, the merges in `py_tile_merge`.
//! Summaries pickle as their bytes.

use std::sync::Arc;

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple, PyType};

use crate::detached;
use crate::error::{Failure, invalid_parameter};
use crate::py_metric::MetricArg;
use crate::py_separation::SeparationArg;
use crate::py_trajectory::Trajectory;
use loops_core::MetricSpec;

/// What planning tiles needs of one session, learnt by whoever reads it: its pose count, its
/// span, and the bounding balls of its blocks of ``block`` consecutive poses under the metric
/// it was measured with. Made by :func:`session_blocks`; :func:`plan_tiles` takes one per
/// session. Pickles (as :meth:`to_bytes` and the metric's name).
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct SessionBlocks {
    pub(crate) inner: loops_core::tile::SessionBlocks,
    metric: MetricSpec,
}

/// The metric of `metric=` (a name or an `inexact_loops.metrics` object), or `default`.
pub(crate) fn tile_metric(
    metric: Option<&Bound<'_, PyAny>>,
    default: MetricSpec,
    function: &str,
) -> PyResult<MetricSpec> {
    match metric {
        None => Ok(default),
        Some(_) => MetricArg::spec_from_py(metric, function),
    }
}

/// A scan (or draw) of one tile, from the arguments that `scan_tile` and `draw_tile` share: the two sessions (session a twice for a tile within
/// one session), their first fleet indices, γ, the separation at γ and the metric
/// (`session_a`'s own unless given; only the core's metrics, so the engine's loops stay
/// monomorphic).
pub(crate) struct TileScan {
    sessions: [Arc<loops_core::Trajectory>; 2],
    pub(crate) starts: [usize; 2],
    pub(crate) gamma: f64,
    pub(crate) separation: loops_core::Separation,
    pub(crate) metric: MetricSpec,
}

impl TileScan {
    /// The scan of `tile` that `function` was asked for.
    ///
    /// # Errors
    /// `TypeError`: a tile between two sessions without `session_b`; `InvalidParameterError`:
    /// an unknown metric.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        tile: &loops_core::tile::Tile,
        session_a: &Trajectory,
        session_b: Option<&Trajectory>,
        starts: (usize, usize),
        gamma: f64,
        metric: Option<&Bound<'_, PyAny>>,
        separation: SeparationArg,
        function: &str,
    ) -> PyResult<Self> {
        if session_b.is_none() && tile.sessions[0] != tile.sessions[1] {
            return Err(PyTypeError::new_err(format!(
                "tile of sessions ({}, {}) needs session_b: only a tile within one session takes one session",
                tile.sessions[0], tile.sessions[1]
            )));
        }
        let metric = tile_metric(metric, session_a.default_metric(), function)?;
        let a = session_a.inner.clone();
        let b = session_b.map_or_else(|| a.clone(), |s| s.inner.clone());
        let separation = separation.at(gamma);
        Ok(Self { sessions: [a, b], starts: [starts.0, starts.1], gamma, separation, metric })
    }

    /// The two sessions.
    pub(crate) fn sessions(&self) -> [&loops_core::Trajectory; 2] {
        [&self.sessions[0], &self.sessions[1]]
    }

    /// Runs `job` on this scan on `threads` threads (`None`: one per core), without the GIL.
    pub(crate) fn run<T: Send>(
        self,
        py: Python<'_>,
        threads: Option<usize>,
        job: impl FnOnce(&Self) -> loops_core::Result<T> + Send,
    ) -> PyResult<T> {
        MetricArg::Spec(self.metric).run(py, threads, move |_| job(&self))
    }
}

#[pymethods]
impl SessionBlocks {
    /// The blocks from :meth:`to_bytes` and the metric's name (what pickling stores).
    ///
    /// Raises:
    ///     InvalidParameterError: bytes of something else, of another format version, or corrupt.
    #[new]
    #[pyo3(signature = (data, metric))]
    fn new(data: &[u8], metric: &str) -> PyResult<Self> {
        let inner = loops_core::tile::SessionBlocks::from_bytes(data).map_err(Failure::from)?;
        let metric = metric.parse::<MetricSpec>().map_err(Failure::from)?;
        Ok(Self { inner, metric })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.get();
        let args = (PyBytes::new(py, &this.inner.to_bytes()), this.metric.name());
        (slf.get_type().getattr("_from_state")?, args).into_pyobject(py)
    }

    /// The constructor, for unpickling: its errors are `pickle.UnpicklingError`.
    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, data: &[u8], metric: &str) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "SessionBlocks", || Self::new(data, metric))
    }

    fn __repr__(&self) -> String {
        format!(
            "SessionBlocks({} poses, span {} s, {} blocks of {}, metric={})",
            self.inner.poses,
            self.inner.span_s,
            self.inner.len(),
            self.inner.block,
            self.metric.name()
        )
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Number of poses of the session.
    #[getter]
    fn poses(&self) -> usize {
        self.inner.poses
    }

    /// The session's span t_{n−1} − t_0, seconds.
    #[getter]
    fn span_s(&self) -> f64 {
        self.inner.span_s
    }

    /// Poses per block.
    #[getter]
    fn block(&self) -> usize {
        self.inner.block
    }

    /// The name of the metric the balls' radii are measured with.
    #[getter]
    fn metric_name(&self) -> String {
        self.metric.name()
    }

    /// The blocks as bytes (a tag, a format version, then the fields).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }

    /// The same session in blocks ``factor`` times larger, bounded from these blocks' balls
    /// (each ball still holds every pose of its block): a planner learns every session's
    /// length first and then chooses the tiles' size without reading the sessions again.
    /// O(blocks) distances.
    ///
    /// Raises:
    ///     InvalidParameterError: a factor of 0.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> drive = il.Trajectory(np.arange(10.0), np.c_[np.arange(10.0), np.zeros(10)])
    ///     >>> coarse = il.tiles.session_blocks(drive, block=2).coarsened(3)
    ///     >>> coarse.block, len(coarse), coarse.poses
    ///     (6, 2, 10)
    fn coarsened(&self, factor: usize) -> PyResult<Self> {
        let inner = self.metric.coarsened_blocks(&self.inner, factor).map_err(Failure::from)?;
        Ok(Self { inner, metric: self.metric })
    }
}

/// Cuts a session into blocks of ``block`` consecutive poses and bounds each by a ball: what
/// :func:`plan_tiles` needs of the session, without its poses. O(poses) distances.
///
/// Args:
///     session: a :class:`Trajectory`.
///     block: poses per block (the tiles' side), at least 1.
///     metric: a metric name or an ``inexact_loops.metrics`` object (not a callable);
///         ``None``: the session's own (:attr:`Trajectory.metric_name`).
///
/// Returns:
///     :class:`SessionBlocks`.
///
/// Raises:
///     InvalidParameterError: a block of 0 poses; an unknown metric.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> drive = il.Trajectory(np.arange(10.0), np.c_[np.arange(10.0), np.zeros(10)])
///     >>> blocks = il.tiles.session_blocks(drive, block=4)
///     >>> blocks.poses, len(blocks), blocks.span_s, blocks.metric_name
///     (10, 3, 9.0, 'euclidean')
#[pyfunction]
#[pyo3(signature = (session, *, block, metric=None))]
pub(crate) fn session_blocks(
    py: Python<'_>,
    session: &Trajectory,
    block: usize,
    metric: Option<&Bound<'_, PyAny>>,
) -> PyResult<SessionBlocks> {
    let metric = tile_metric(metric, session.default_metric(), "session_blocks")?;
    let traj = session.inner.clone();
    let inner = detached(py, move || Ok(metric.session_blocks(&traj, block)?))?;
    Ok(SessionBlocks { inner, metric })
}

/// A tile of a fleet's plane: rows ``rows`` of session ``sessions[0]`` against columns
/// ``columns`` of session ``sessions[1]``, each a half-open range ``(start, end)`` of *fleet
/// indices* (the sessions' poses numbered one session after another, as :attr:`Fleet.starts`).
/// Made by :func:`plan_tiles`; pickles; equal tiles are equal and hash alike.
#[pyclass(frozen, eq, hash, module = "inexact_loops._core")]
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct Tile {
    pub(crate) inner: loops_core::tile::Tile,
}

#[pymethods]
impl Tile {
    #[new]
    #[pyo3(signature = (sessions, rows, columns))]
    fn new(sessions: (usize, usize), rows: (usize, usize), columns: (usize, usize)) -> Self {
        Self {
            inner: loops_core::tile::Tile {
                sessions: [sessions.0, sessions.1],
                rows: rows.0..rows.1,
                columns: columns.0..columns.1,
            },
        }
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let t = &slf.get().inner;
        let args = ((t.sessions[0], t.sessions[1]), (t.rows.start, t.rows.end), (t.columns.start, t.columns.end));
        (slf.get_type(), args).into_pyobject(py)
    }

    fn __repr__(&self) -> String {
        let t = &self.inner;
        format!(
            "Tile(sessions=({}, {}), rows=({}, {}), columns=({}, {}))",
            t.sessions[0], t.sessions[1], t.rows.start, t.rows.end, t.columns.start, t.columns.end
        )
    }

    /// The session pair ``(a, b)``, a ≤ b.
    #[getter]
    fn sessions(&self) -> (usize, usize) {
        (self.inner.sessions[0], self.inner.sessions[1])
    }

    /// The rows' fleet indices, ``(start, end)``, end excluded (poses of session a).
    #[getter]
    fn rows(&self) -> (usize, usize) {
        (self.inner.rows.start, self.inner.rows.end)
    }

    /// The columns' fleet indices, ``(start, end)``, end excluded (poses of session b).
    #[getter]
    fn columns(&self) -> (usize, usize) {
        (self.inner.columns.start, self.inner.columns.end)
    }
}

/// The tiles of a fleet whose sessions (in fleet order) have these blocks: every pair of a
/// row block and a column block (a ≤ b; on or above the diagonal within a session) whose balls
/// come within γ. Every pair of poses within γ lies in one of them; tiles left out hold none.
///
/// Args:
///     sessions: one :class:`SessionBlocks` per session, in fleet order, cut into blocks of one
///         size.
///     gamma: the distance threshold γ > 0.
///     metric: ``None``: the metric the blocks were measured with (they must agree); or a name
///         or metric object, which must be that metric.
///
/// Returns:
///     list of :class:`Tile`, by session pair, then row block, then column block.
///
/// Raises:
///     InvalidParameterError: no sessions; blocks of different sizes, dimensions or metrics;
///         an invalid γ.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> out = il.Trajectory(np.arange(6.0), np.c_[np.arange(6.0), np.zeros(6)])
///     >>> far = il.Trajectory(np.arange(4.0), np.c_[np.arange(4.0), np.full(4, 100.0)])
///     >>> blocks = [il.tiles.session_blocks(s, block=3) for s in (out, far)]
///     >>> [t.sessions for t in il.tiles.plan_tiles(blocks, gamma=1.0)]  # far meets no one
///     [(0, 0), (0, 0), (0, 0), (1, 1), (1, 1), (1, 1)]
#[pyfunction]
#[pyo3(signature = (sessions, *, gamma, metric=None))]
pub(crate) fn plan_tiles(
    py: Python<'_>,
    sessions: Vec<PyRef<'_, SessionBlocks>>,
    gamma: f64,
    metric: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Tile>> {
    let Some(first) = sessions.first() else {
        return Err(invalid_parameter("plan_tiles needs at least one session's blocks".to_owned()));
    };
    let metric = tile_metric(metric, first.metric, "plan_tiles")?;
    if let Some((k, other)) = sessions.iter().enumerate().find(|(_, s)| s.metric != metric) {
        return Err(invalid_parameter(format!(
            "the blocks of session {k} were measured with {}, the plan with {}: use one metric",
            other.metric.name(),
            metric.name()
        )));
    }
    let blocks: Vec<loops_core::tile::SessionBlocks> = sessions.iter().map(|s| s.inner.clone()).collect();
    let tiles = detached(py, move || Ok(metric.plan_session_tiles(&blocks, gamma)?))?;
    Ok(tiles.into_iter().map(|inner| Tile { inner }).collect())
}

/// What scanning one tile returns: the statistics of the tile's provisional components and the
/// runs on its edges, a few hundred bytes to a few kilobytes. Made by :func:`scan_tile`; merged
/// by :func:`merge_tiles`. Pickles as :meth:`to_bytes`.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileSummary {
    pub(crate) inner: loops_core::tile::TileSummary,
}

crate::pickling::pickled_as_bytes!(
    TileSummary,
    loops_core::tile::TileSummary,
    "summary",
    "The summary as bytes: a 4-byte tag, the format version, then the fields (MessagePack).",
    from_bytes
);

#[pymethods]
impl TileSummary {
    fn __repr__(&self) -> String {
        format!(
            "TileSummary({}, {} components, {} edge runs)",
            Tile { inner: self.inner.tile.clone() }.__repr__(),
            self.inner.components.len(),
            self.inner.edges.len()
        )
    }

    /// The tile.
    #[getter]
    fn tile(&self) -> Tile {
        Tile { inner: self.inner.tile.clone() }
    }

    /// Number of provisional components.
    #[getter]
    fn component_count(&self) -> usize {
        self.inner.components.len()
    }

    /// Number of runs on the tile's edges.
    #[getter]
    fn edge_count(&self) -> usize {
        self.inner.edges.len()
    }
}
