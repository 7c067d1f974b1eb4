//! Tiles of a fleet's plane, for a cluster: `SessionBlocks` (`session_blocks`), `Tile`
//! (`plan_tiles`), `TileSummary` (`scan_tile`), `TileMerge` (`merge_tiles`) and
//! `TiledFleetLoops` (`TileMerge.finish`). Summaries and merges pickle as their bytes;
//! `TiledFleetLoops` as the other results do (`pickling`).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

use crate::convert::to_numpy;
use crate::detached;
use crate::error::{Failure, invalid_parameter};
use crate::py_fleet::{components_table, overlap_matrix, session_pairs_table};
use crate::py_metric::{MetricArg, MetricRef};
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
    inner: loops_core::SessionBlocks,
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

#[pymethods]
impl SessionBlocks {
    /// The blocks from :meth:`to_bytes` and the metric's name (what pickling stores).
    ///
    /// Raises:
    ///     InvalidParameterError: bytes of something else, of another format version, or corrupt.
    #[new]
    #[pyo3(signature = (data, metric))]
    fn new(data: &[u8], metric: &str) -> PyResult<Self> {
        let inner = loops_core::SessionBlocks::from_bytes(data).map_err(Failure::from)?;
        let metric = metric.parse::<MetricSpec>().map_err(Failure::from)?;
        Ok(Self { inner, metric })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.get();
        let args = (PyBytes::new(py, &this.inner.to_bytes()), this.metric.name());
        (slf.get_type(), args).into_pyobject(py)
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
///     >>> blocks = il.session_blocks(drive, block=4)
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
    pub(crate) inner: loops_core::Tile,
}

#[pymethods]
impl Tile {
    #[new]
    #[pyo3(signature = (sessions, rows, columns))]
    fn new(sessions: (usize, usize), rows: (usize, usize), columns: (usize, usize)) -> Self {
        Self {
            inner: loops_core::Tile {
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
///     >>> blocks = [il.session_blocks(s, block=3) for s in (out, far)]
///     >>> [t.sessions for t in il.plan_tiles(blocks, gamma=1.0)]  # far meets no one
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
    let blocks: Vec<loops_core::SessionBlocks> = sessions.iter().map(|s| s.inner.clone()).collect();
    let tiles = detached(py, move || Ok(metric.plan_session_tiles(&blocks, gamma)?))?;
    Ok(tiles.into_iter().map(|inner| Tile { inner }).collect())
}

/// What scanning one tile returns: the statistics of the tile's provisional components and the
/// runs on its edges, a few hundred bytes to a few kilobytes. Made by :func:`scan_tile`; merged
/// by :func:`merge_tiles`. Pickles as :meth:`to_bytes`.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileSummary {
    pub(crate) inner: loops_core::TileSummary,
}

#[pymethods]
impl TileSummary {
    /// The summary from :meth:`to_bytes` (what pickling stores).
    ///
    /// Raises:
    ///     InvalidParameterError: bytes of something else, of another format version, or corrupt
    ///         (the message says which).
    #[new]
    fn new(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        let data = data.to_vec();
        let inner = detached(py, move || Ok(loops_core::TileSummary::from_bytes(&data)?))?;
        Ok(Self { inner })
    }

    /// The summary from :meth:`to_bytes`; as the constructor.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        Self::new(py, data)
    }

    /// The summary as bytes: a 4-byte tag, the format version, then the fields (MessagePack).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        (slf.get_type(), (PyBytes::new(py, &slf.get().inner.to_bytes()),)).into_pyobject(py)
    }

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

/// Scans one tile from its two sessions alone — what a worker that read only those sessions
/// can do — without the GIL: the same cells as :func:`find_fleet_loops` finds in the tile,
/// summarised for :func:`merge_tiles`.
///
/// Args:
///     tile: a :class:`Tile` of :func:`plan_tiles`.
///     session_a: the :class:`Trajectory` of session ``tile.sessions[0]``.
///     session_b: that of session ``tile.sessions[1]``; ``None`` for a tile within one session.
///     starts: the two sessions' first fleet indices ``(start_a, start_b)``: the poses of the
///         sessions before each in the fleet (the same twice within one session).
///     gamma: the distance threshold γ > 0.
///     metric: a metric name or an ``inexact_loops.metrics`` object (not a callable); ``None``:
///         ``session_a``'s own.
///     separation: within a session, as in :func:`find_fleet_loops` (``"auto"``: 4 γ of path;
///         ``None``: none), measured over the whole session.
///     threads: worker threads; ``None``: one per core.
///
/// Returns:
///     :class:`TileSummary`.
///
/// Raises:
///     InvalidParameterError: a tile outside its sessions or below the diagonal, sessions of
///         different dimensions or manifolds, an invalid γ or separation, a metric that does
///         not fit the poses.
#[pyfunction]
#[pyo3(signature = (tile, session_a, session_b=None, *, starts, gamma, metric=None, separation=SeparationArg::Auto,
    threads=None))]
#[pyo3(
    text_signature = "(tile, session_a, session_b=None, *, starts, gamma, metric=None, separation='auto', threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn scan_tile(
    py: Python<'_>,
    tile: &Tile,
    session_a: &Trajectory,
    session_b: Option<&Trajectory>,
    starts: (usize, usize),
    gamma: f64,
    metric: Option<&Bound<'_, PyAny>>,
    separation: SeparationArg,
    threads: Option<usize>,
) -> PyResult<TileSummary> {
    let tile = tile.inner.clone();
    if session_b.is_none() && tile.sessions[0] != tile.sessions[1] {
        return Err(PyTypeError::new_err(format!(
            "tile of sessions ({}, {}) needs session_b: only a tile within one session takes one session",
            tile.sessions[0], tile.sessions[1]
        )));
    }
    let metric = tile_metric(metric, session_a.default_metric(), "scan_tile")?;
    let separation = separation.at(gamma);
    let a = session_a.inner.clone();
    let b = session_b.map_or_else(|| a.clone(), |s| s.inner.clone());
    let inner = MetricArg::Spec(metric).run(py, threads, move |metric| match metric {
        MetricRef::Spec(spec) => spec.scan_session_tile([&a, &b], [starts.0, starts.1], gamma, separation, &tile),
        MetricRef::Callable(callable) => {
            loops_core::scan_session_tile([&a, &b], [starts.0, starts.1], callable, gamma, separation, &tile)
        }
    })?;
    Ok(TileSummary { inner })
}

/// A partial merge of tiles: the components of the tiles it holds with every join between them
/// made, and only the edge runs that face tiles it does not hold yet. Merges of disjoint sets
/// of tiles merge again (:func:`merge_tiles`), in any grouping and order; the merge of every
/// tile of a plan :meth:`finish`\ es into the fleet's components. Pickles as :meth:`to_bytes`.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileMerge {
    inner: loops_core::TileMerge,
}

#[pymethods]
impl TileMerge {
    /// The merge from :meth:`to_bytes` (what pickling stores).
    ///
    /// Raises:
    ///     InvalidParameterError: bytes of something else, of another format version, or corrupt.
    #[new]
    fn new(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        let data = data.to_vec();
        let inner = detached(py, move || Ok(loops_core::TileMerge::from_bytes(&data)?))?;
        Ok(Self { inner })
    }

    /// The merge from :meth:`to_bytes`; as the constructor.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        Self::new(py, data)
    }

    /// The merge as bytes (as :meth:`TileSummary.to_bytes`, another tag).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        (slf.get_type(), (PyBytes::new(py, &slf.get().inner.to_bytes()),)).into_pyobject(py)
    }

    fn __repr__(&self) -> String {
        format!(
            "TileMerge({} tiles, {} components, {} open edge runs)",
            self.inner.tiles().len(),
            self.inner.component_count(),
            self.inner.open_edge_count()
        )
    }

    /// Number of tiles merged.
    #[getter]
    fn tile_count(&self) -> usize {
        self.inner.tiles().len()
    }

    /// Number of components (final ones and those that may still grow).
    #[getter]
    fn component_count(&self) -> usize {
        self.inner.component_count()
    }

    /// Number of edge runs still open (facing tiles not merged yet).
    #[getter]
    fn open_edge_count(&self) -> usize {
        self.inner.open_edge_count()
    }

    /// The fleet's loop components from the merge of every tile of a plan: numbered, and with
    /// the same tables, as :func:`find_fleet_loops` gives them (areas to rounding).
    ///
    /// Args:
    ///     sessions: the :class:`SessionBlocks` the plan was made from, in fleet order (their
    ///         pose counts give the fleet indices, their spans the densities).
    ///     names: the sessions' names, in fleet order.
    ///
    /// Returns:
    ///     :class:`TiledFleetLoops`.
    ///
    /// Raises:
    ///     InvalidParameterError: as many names as sessions are needed; a merge whose
    ///         components do not lie in these sessions, or whose counts do not fit together.
    #[pyo3(signature = (sessions, *, names))]
    fn finish(
        &self,
        py: Python<'_>,
        sessions: Vec<PyRef<'_, SessionBlocks>>,
        names: Vec<String>,
    ) -> PyResult<TiledFleetLoops> {
        if names.len() != sessions.len() {
            return Err(invalid_parameter(format!("{} names for {} sessions", names.len(), sessions.len())));
        }
        let mut starts = Vec::with_capacity(sessions.len());
        let mut next = 0;
        for s in &sessions {
            starts.push(next);
            next += s.inner.poses;
        }
        let spans: Vec<f64> = sessions.iter().map(|s| s.inner.span_s).collect();
        let merge = self.inner.clone();
        let fleet_starts = starts.clone();
        let (components, times, pairs, merged) = detached(py, move || {
            let merged = merge.finish()?;
            let components = merged.fleet_components(&fleet_starts)?;
            let times = merged.components().iter().map(|c| c.times_s).collect();
            Ok((components, times, merged.session_pairs(&spans)?, merged))
        })?;
        let merged = Some((std::sync::Arc::new(merged), starts));
        Ok(TiledFleetLoops { names, components, times, pairs, merged })
    }
}

/// Merges tile summaries and partial merges of disjoint sets of tiles into one partial merge,
/// without the GIL: O(their components + open edge runs + tiles). See :class:`TileMerge`.
///
/// Args:
///     parts: :class:`TileSummary` and :class:`TileMerge` objects, in any order.
///
/// Returns:
///     :class:`TileMerge`.
///
/// Raises:
///     InvalidParameterError: a tile in two parts; parts that do not fit together.
///     TypeError: a part of another type.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> s = 0.2 * np.arange(40)  # a circle and a third, the second lap over the first
///     >>> drive = il.Trajectory(s, np.c_[np.cos(s), np.sin(s)])
///     >>> blocks = [il.session_blocks(drive, block=8)]
///     >>> tiles = il.plan_tiles(blocks, gamma=0.5)
///     >>> parts = [il.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None) for t in tiles]
///     >>> merged = il.merge_tiles([il.merge_tiles(parts[:2]), *parts[2:]])
///     >>> loops = merged.finish(blocks, names=["drive"])
///     >>> fleet = il.find_fleet_loops(il.Fleet({"drive": drive}), gamma=0.5, separation=None)
///     >>> loops.components["pair_count"].tolist() == fleet.components["pair_count"].tolist()
///     True
#[pyfunction]
pub(crate) fn merge_tiles(py: Python<'_>, parts: Vec<Bound<'_, PyAny>>) -> PyResult<TileMerge> {
    let mut merges = Vec::with_capacity(parts.len());
    let mut summaries = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        if let Ok(summary) = part.cast::<TileSummary>() {
            summaries.push((merges.len(), summary.get().inner.clone()));
            merges.push(None);
        } else if let Ok(merge) = part.cast::<TileMerge>() {
            merges.push(Some(merge.get().inner.clone()));
        } else {
            return Err(PyTypeError::new_err(format!(
                "parts[{k}] must be a TileSummary or a TileMerge, got {}",
                part.get_type().name()?
            )));
        }
    }
    let inner = detached(py, move || {
        for (k, summary) in summaries {
            merges[k] = Some(loops_core::TileMerge::new(summary)?);
        }
        Ok(loops_core::TileMerge::merge(merges.into_iter().flatten().collect())?)
    })?;
    Ok(TileMerge { inner })
}

/// The loops of a fleet merged from tiles (:meth:`TileMerge.finish`): the tables of
/// :class:`FleetLoops` that the tiles give — components, the session pairs and the overlap
/// matrix — equal to :func:`find_fleet_loops`' (areas to rounding). Not the runs themselves:
/// they stayed on the machines that scanned the tiles.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct TiledFleetLoops {
    pub(crate) names: Vec<String>,
    components: Vec<loops_core::FleetComponent>,
    times: Vec<[[f64; 2]; 2]>,
    pairs: Vec<loops_core::SessionPair>,
    /// The merge and the sessions' first fleet indices, for keyed draws of samples
    /// (`py_tile_draw`); not pickled (an unpickled result draws no samples).
    pub(crate) merged: Option<(std::sync::Arc<loops_core::MergedLoops>, Vec<usize>)>,
}

impl TiledFleetLoops {
    /// The merge and the sessions' first fleet indices, or why not.
    pub(crate) fn merge(&self) -> PyResult<(&std::sync::Arc<loops_core::MergedLoops>, &[usize])> {
        self.merged.as_ref().map(|(m, s)| (m, s.as_slice())).ok_or_else(|| {
            invalid_parameter(
                "this TiledFleetLoops was read from a pickle, which keeps its tables but not the merge: draw \
                 samples from the one TileMerge.finish made"
                    .to_owned(),
            )
        })
    }
}

/// What a pickled `TiledFleetLoops` holds: names, components, their times, session pairs.
type TiledState = (Vec<String>, Vec<loops_core::FleetComponent>, Vec<[[f64; 2]; 2]>, Vec<loops_core::SessionPair>);

#[pymethods]
impl TiledFleetLoops {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get();
        let value = (&this.names, &this.components, &this.times, &this.pairs);
        crate::pickling::reduce(slf.as_any(), "TiledFleetLoops", &value)
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, pyo3::types::PyType>, state: &[u8]) -> PyResult<Self> {
        let py = cls.py();
        let (names, components, times, pairs): TiledState = crate::pickling::restore(py, "TiledFleetLoops", state)?;
        let invalid = |reason: String| crate::pickling::invalid(py, "TiledFleetLoops", reason);
        let n = names.len();
        let fits = |[a, b]: [usize; 2]| a <= b && b < n;
        if times.len() != components.len() {
            return Err(invalid(format!("{} components but {} time extents", components.len(), times.len())));
        }
        if let Some((k, c)) = components.iter().enumerate().find(|(k, c)| c.id != *k || !fits(c.sessions)) {
            return Err(invalid(format!("component {k} has id {} and sessions {:?}, of {n}", c.id, c.sessions)));
        }
        if let Some((k, p)) = pairs.iter().enumerate().find(|(_, p)| !fits(p.sessions)) {
            return Err(invalid(format!("session pair {k} has sessions {:?}, of {n}", p.sessions)));
        }
        Ok(Self { names, components, times, pairs, merged: None })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        self.names == other.names
            && self.components == other.components
            && self.times == other.times
            && self.pairs == other.pairs
    }

    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.names.len() as u64, self.components.len() as u64, self.pairs.len() as u64])
    }

    /// Plans a keyed draw of samples (see :class:`KeyedDraw`): the same samples as
    /// :func:`sample_fleet` on the same sessions, with the samplers of components (``"one"``,
    /// ``"rho"``, ``"rho-dispersed"``, ``"alpha"``, ``"closest-first"``; not the baselines,
    /// whose rules run over whole trajectories).
    ///
    /// Args:
    ///     sampler: the sampler's name.
    ///     rate, budget: as :func:`sample_fleet` (exactly one).
    ///     seed: the seed.
    ///     between_only: only the components between two sessions.
    ///     skip_trivial: leave out the trivial components.
    ///
    /// Returns:
    ///     :class:`KeyedDraw`.
    ///
    /// Raises:
    ///     InvalidParameterError: an unknown sampler, a baseline, both or neither of rate and
    ///         budget, a budget of 0, a rate out of range, a result read from a pickle (which
    ///         holds no merge); ``TooManySamplesError`` as :func:`sample_fleet`.
    #[pyo3(signature = (sampler, *, rate=None, budget=None, seed, between_only=false, skip_trivial=false))]
    #[allow(clippy::too_many_arguments)]
    fn draw(
        &self,
        py: Python<'_>,
        sampler: &str,
        rate: Option<f64>,
        budget: Option<usize>,
        seed: u64,
        between_only: bool,
        skip_trivial: bool,
    ) -> PyResult<crate::py_tile_draw::KeyedDraw> {
        crate::py_tile_draw::plan_draw(py, self, sampler, rate, budget, seed, between_only, skip_trivial)
    }

    /// The tiles merged, in the merge's order (the indices of :meth:`KeyedDraw.requests`).
    #[getter]
    ///
    /// Raises:
    ///     InvalidParameterError: a result read from a pickle, which holds no merge.
    fn tiles(&self) -> PyResult<Vec<Tile>> {
        let (merged, _) = self.merge()?;
        Ok(merged.tiles().iter().map(|t| Tile { inner: t.clone() }).collect())
    }

    fn __repr__(&self) -> String {
        let between = self.components.iter().filter(|c| c.sessions[0] != c.sessions[1]).count();
        format!(
            "TiledFleetLoops({} sessions, {} components ({between} between sessions))",
            self.names.len(),
            self.components.len()
        )
    }

    /// The sessions' names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.names.clone()
    }

    /// The loop components, as :attr:`FleetLoops.components` (the same columns).
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        components_table(py, &self.components, &self.names, &self.times)
    }

    /// The ids of the components between two different sessions, int64, increasing.
    fn between_sessions<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<i64>> {
        let ids = self.components.iter().filter(|c| c.sessions[0] != c.sessions[1]).map(|c| c.id as i64);
        to_numpy(py, ids.collect())
    }

    /// The sparse overlap matrix as a table, as :meth:`FleetLoops.session_pairs`.
    fn session_pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        session_pairs_table(py, &self.pairs, &self.names)
    }

    /// The overlap matrix, as :meth:`FleetLoops.overlap_matrix`.
    ///
    /// Args:
    ///     sparse: a ``scipy.sparse.csr_array`` instead of a dense numpy array.
    ///
    /// Raises:
    ///     ImportError: ``sparse=True`` without scipy.
    #[pyo3(signature = (*, sparse=false))]
    fn overlap_matrix<'py>(&self, py: Python<'py>, sparse: bool) -> PyResult<Bound<'py, PyAny>> {
        overlap_matrix(py, self.names.len(), &self.pairs, sparse)
    }
}
