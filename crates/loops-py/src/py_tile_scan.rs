//! One tile's scan (`scan_tile`), from its two sessions alone: the `TileSummary` that merges,
//! and, as asked, the tile's share of τ (`TileDuration`, pickled as its bytes) and its runs
//! (`TileRuns`), which stay where the tile was scanned for `draw_tile(runs=...)` to offer a
//! draw's pairs without rescanning the tile.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::error::invalid_parameter;
use crate::py_separation::SeparationArg;
use crate::py_tile::{Tile, TileScan, TileSummary};
use crate::py_trajectory::Trajectory;
use loops_core::{MetricSpec, tile::TileKeep};

/// Scans one tile from its two sessions alone — what a worker that read only those sessions
/// can do — without the GIL: the same cells as :func:`find_fleet_loops` finds in the tile,
/// summarised for :func:`merge_tiles`; from the same scan, as asked, the tile's share of the loop
/// duration τ (for :func:`session_loop_duration`) and its runs (for :func:`draw_tile` to offer a
/// draw's pairs without rescanning the tile).
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
///     duration: also return the tile's :class:`TileDuration`.
///     runs: also return the tile's :class:`TileRuns`.
///
/// Returns:
///     :class:`TileSummary` alone, or with ``duration`` or ``runs`` a tuple of it and what was
///     asked, in that order: ``(TileSummary, TileDuration, TileRuns)`` with both.
///
/// Raises:
///     InvalidParameterError: a tile outside its sessions or below the diagonal, sessions of
///         different dimensions or manifolds, an invalid γ or separation, a metric that does
///         not fit the poses.
///
/// Examples:
///     >>> import inexact_loops as il
///     >>> drive = il.Trajectory([0.0, 1.0, 2.0, 3.0], [[0, 0], [5, 0], [5, 5], [0, 0.1]])
///     >>> tile = il.tiles.plan_tiles([il.tiles.session_blocks(drive, block=4)], gamma=0.5)[0]
///     >>> summary, share = il.tiles.scan_tile(tile, drive, starts=(0, 0), gamma=0.5, separation=None, duration=True)
///     >>> summary.component_count, share.tile == tile
///     (5, True)
#[pyfunction]
#[pyo3(signature = (tile, session_a, session_b=None, *, starts, gamma, metric=None, separation=SeparationArg::Auto,
    threads=None, duration=false, runs=false))]
#[pyo3(
    text_signature = "(tile, session_a, session_b=None, *, starts, gamma, metric=None, separation='auto', threads=None, duration=False, runs=False)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn scan_tile<'py>(
    py: Python<'py>,
    tile: &Tile,
    session_a: &Trajectory,
    session_b: Option<&Trajectory>,
    starts: (usize, usize),
    gamma: f64,
    metric: Option<&Bound<'py, PyAny>>,
    separation: SeparationArg,
    threads: Option<usize>,
    duration: bool,
    runs: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let tile = tile.inner.clone();
    let keep = TileKeep::asking(duration, runs);
    let scan = TileScan::new(&tile, session_a, session_b, starts, gamma, metric, separation, "scan_tile")?;
    let metric = scan.metric;
    let scanned = scan.run(py, threads, move |s| {
        s.metric.scan_session_tile(s.sessions(), s.starts, s.gamma, s.separation, &tile, keep)
    })?;
    scan_result(py, scanned, metric)
}

/// A tile's scan as :func:`scan_tile` returns it: its summary alone, or a tuple of it and what
/// was kept.
fn scan_result(py: Python<'_>, scanned: loops_core::tile::TileScan, metric: MetricSpec) -> PyResult<Bound<'_, PyAny>> {
    let summary = TileSummary { inner: scanned.summary }.into_pyobject(py)?.into_any();
    if scanned.duration.is_none() && scanned.runs.is_none() {
        return Ok(summary);
    }
    let mut parts = vec![summary];
    if let Some(inner) = scanned.duration {
        parts.push(TileDuration { inner }.into_pyobject(py)?.into_any());
    }
    if let Some(inner) = scanned.runs {
        parts.push(TileRuns { inner: Arc::new(inner), metric }.into_pyobject(py)?.into_any());
    }
    Ok(PyTuple::new(py, parts)?.into_any())
}

/// Scans a group of tiles, in parallel and without the GIL: each the scan :func:`scan_tile`
/// makes, the balls that bound each side of a tile made once for the tiles of the group that
/// share it (a session given as the same :class:`Trajectory` object to several tiles is bounded
/// once, not once a tile).
///
/// Args:
///     jobs: ``(tile, session_a, session_b, starts)`` per tile, as :func:`scan_tile` takes them
///         (``session_b`` ``None`` for a tile within one session).
///     gamma: the distance threshold γ > 0.
///     metric: a metric name or an ``inexact_loops.metrics`` object (not a callable); ``None``:
///         the first ``session_a``'s own.
///     separation: as in :func:`scan_tile`.
///     threads: worker threads; ``None``: one per core.
///     duration: also return each tile's :class:`TileDuration`.
///     runs: also return each tile's :class:`TileRuns`.
///
/// Returns:
///     What :func:`scan_tile` returns for each tile, in the order of ``jobs``.
///
/// Raises:
///     InvalidParameterError: as :func:`scan_tile`, for the first tile in order that has it;
///         sessions whose own metrics differ when ``metric`` is ``None``.
///
/// Examples:
///     >>> import inexact_loops as il
///     >>> drive = il.Trajectory([0.0, 1.0, 2.0, 3.0], [[0, 0], [5, 0], [5, 5], [0, 0.1]])
///     >>> plan = il.tiles.plan_tiles([il.tiles.session_blocks(drive, block=2)], gamma=0.5)
///     >>> jobs = [(t, drive, None, (0, 0)) for t in plan]
///     >>> summaries = il.tiles.scan_tiles(jobs, gamma=0.5, separation=None)
///     >>> [s.component_count for s in summaries] == [
///     ...     il.tiles.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None).component_count for t in plan]
///     True
#[pyfunction]
#[pyo3(signature = (jobs, *, gamma, metric=None, separation=SeparationArg::Auto, threads=None, duration=false, runs=false))]
#[pyo3(text_signature = "(jobs, *, gamma, metric=None, separation='auto', threads=None, duration=False, runs=False)")]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn scan_tiles<'py>(
    py: Python<'py>,
    jobs: Vec<(PyRef<'py, Tile>, PyRef<'py, Trajectory>, Option<PyRef<'py, Trajectory>>, (usize, usize))>,
    gamma: f64,
    metric: Option<&Bound<'py, PyAny>>,
    separation: SeparationArg,
    threads: Option<usize>,
    duration: bool,
    runs: bool,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let keep = TileKeep::asking(duration, runs);
    let mut scans: Vec<(loops_core::tile::Tile, TileScan)> = Vec::with_capacity(jobs.len());
    for (tile, a, b, starts) in &jobs {
        let scan = TileScan::new(&tile.inner, a, b.as_deref(), *starts, gamma, metric, separation, "scan_tiles")?;
        if let Some(first) = scans.first().map(|(_, s)| s.metric)
            && first != scan.metric
        {
            return Err(invalid_parameter(format!(
                "scan_tiles: tile {} of the group scans under metric {}, the first under {first}: name one metric",
                scans.len(),
                scan.metric
            )));
        }
        scans.push((tile.inner.clone(), scan));
    }
    let Some(metric) = scans.first().map(|(_, s)| s.metric) else {
        return Ok(Vec::new());
    };
    let (gamma, separation) = (scans[0].1.gamma, scans[0].1.separation);
    let scanned = crate::py_metric::MetricArg::Spec(metric).run(py, threads, move |_| {
        let group: Vec<_> = scans.iter().map(|(tile, s)| (tile, s.sessions(), s.starts)).collect();
        metric.scan_session_tiles(&group, gamma, separation, keep)
    })?;
    scanned.into_iter().map(|s| scan_result(py, s, metric)).collect()
}

/// What one tile's runs add to the loop duration τ of its rows and columns
/// (:func:`scan_tile` with ``duration=True``); :func:`session_loop_duration` adds up a session's.
/// Pickles as its bytes.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileDuration {
    pub(crate) inner: loops_core::tile::TileDuration,
}

crate::pickling::pickled_as_bytes!(
    TileDuration,
    loops_core::tile::TileDuration,
    "share",
    "The share as bytes (a tag, the tile format version, then MessagePack)."
);

#[pymethods]
impl TileDuration {
    fn __repr__(&self) -> String {
        format!("TileDuration({:?})", self.inner.tile)
    }

    /// The tile.
    #[getter]
    fn tile(&self) -> Tile {
        Tile { inner: self.inner.tile.clone() }
    }
}

/// One tile's runs as its scan made them (:func:`scan_tile` with ``runs=True``), with their
/// provisional labels: what :func:`draw_tile` reads of the tile when given them instead of
/// rescanning it. About 16 bytes a run; it holds no poses. Lives in the process that scanned the
/// tile (it does not pickle): a worker keeps it for the draws of its tiles.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct TileRuns {
    pub(crate) inner: Arc<loops_core::tile::TileRuns>,
    pub(crate) metric: MetricSpec,
}

#[pymethods]
impl TileRuns {
    fn __repr__(&self) -> String {
        format!("TileRuns({:?}, {} runs)", self.inner.tile(), self.inner.run_count())
    }

    /// Its runs.
    fn __len__(&self) -> usize {
        self.inner.run_count()
    }

    /// The bytes it holds (its runs, 16 bytes each, and 8 bytes a row).
    #[getter]
    fn nbytes(&self) -> usize {
        self.inner.heap_bytes()
    }

    /// The tile.
    #[getter]
    fn tile(&self) -> Tile {
        Tile { inner: self.inner.tile().clone() }
    }

    /// The metric's name the tile was scanned with.
    #[getter]
    fn metric_name(&self) -> String {
        self.metric.name()
    }
}

/// The runs to draw `tile` from, checked against the draw's tile and metric.
pub(crate) fn runs_for(
    runs: &TileRuns,
    tile: &loops_core::tile::Tile,
    metric: MetricSpec,
) -> PyResult<Arc<loops_core::tile::TileRuns>> {
    if runs.inner.tile() != tile {
        return Err(invalid_parameter(format!(
            "draw_tile: the runs are of tile {:?}, the request of tile {tile:?}",
            runs.inner.tile()
        )));
    }
    if runs.metric != metric {
        return Err(invalid_parameter(format!(
            "draw_tile: the runs were scanned with metric {}, the draw asks {}",
            runs.metric.name(),
            metric.name()
        )));
    }
    Ok(runs.inner.clone())
}
