//! Samples and τ from tiles: `TiledFleetLoops.draw` (`KeyedDraw`), `TileDrawRequest`,
//! `draw_tile` (`DrawCandidates`, from a rescan or the `TileRuns` a scan kept) and
//! `session_loop_duration` (from the scans' `TileDuration`s). The shipped objects pickle as their
//! bytes.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple, PyType};

use crate::convert::to_numpy;
use crate::detached;
use crate::error::{Failure, invalid_parameter};
use crate::py_separation::SeparationArg;
use crate::py_tile::{Tile, TileScan};
use crate::py_trajectory::Trajectory;
use crate::shared::Shared;
use loops_core::{SampleSize, Sampler};

/// A keyed draw of samples from a fleet's tiles (:meth:`TiledFleetLoops.draw`): the quotas from
/// the merged statistics, then passes in which every tile asked (:meth:`requests`) offers its
/// pairs (:func:`draw_tile`), until the draw is :attr:`done`. Its samples are those of
/// :func:`sample_fleet` with the same sampler, seed and options, pair for pair. Threads may share
/// it: its calls run one at a time.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct KeyedDraw {
    inner: Shared<loops_core::sample::KeyedDraw>,
    merged: Arc<loops_core::tile::MergedLoops>,
    names: Vec<String>,
    starts: Vec<usize>,
    skip_trivial: bool,
}

/// `TiledFleetLoops.draw`'s body, from its merge, the sessions' first fleet indices and names.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_draw(
    py: Python<'_>,
    (merged, starts, names): (&Arc<loops_core::tile::MergedLoops>, &[usize], &[String]),
    sampler: Option<&str>,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: u64,
    between_only: bool,
    skip_trivial: bool,
) -> PyResult<KeyedDraw> {
    let kind = crate::py_samples::sampler_kind(sampler)?;
    let size = SampleSize::or_default(rate, budget).map_err(Failure::from)?;
    let spec = Sampler { skip_trivial, ..Sampler::new(kind, size, seed) };
    let (merged, starts) = (Arc::clone(merged), starts.to_vec());
    let kept = Arc::clone(&merged);
    let keys = loops_core::sample::KeyLayout::sessions(&starts, names);
    let inner = detached(py, move || {
        let stats = merged.draw_stats();
        let blocks: Vec<[usize; 2]> = merged.components().iter().map(|m| m.sessions).collect();
        let keep = |c: usize| !between_only || blocks[c][0] != blocks[c][1];
        Ok(loops_core::sample::KeyedDraw::with_keys(&spec, &stats, &keep, keys)?)
    })?;
    Ok(KeyedDraw { inner: Shared::new(inner), merged: kept, names: names.to_vec(), starts, skip_trivial })
}

#[pymethods]
impl KeyedDraw {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let draw = self.inner.lock(py)?;
        Ok(format!(
            "KeyedDraw(sampler={:?}, {} groups, {} candidates, {})",
            draw.sampler().name(),
            draw.groups(),
            draw.available(),
            if draw.picks().is_some() { "done" } else { "passes to run" }
        ))
    }

    /// Whether every pass has run (:meth:`table` then holds the samples).
    #[getter]
    fn done(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.inner.lock(py)?.picks().is_some())
    }

    /// Number of groups (components with a pair to sample; 0 for σ_α).
    #[getter]
    fn groups(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.groups())
    }

    /// Number of candidate pairs.
    #[getter]
    fn available(&self, py: Python<'_>) -> PyResult<u64> {
        Ok(self.inner.lock(py)?.available())
    }

    /// The warnings of the quotas, as text.
    #[getter]
    fn warnings(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        Ok(self.inner.lock(py)?.warnings().iter().map(ToString::to_string).collect())
    }

    /// What the pending pass asks of the tiles: ``(tile index, TileDrawRequest)`` for every
    /// tile asked something (indices in the merge's order, :attr:`TiledFleetLoops.tiles`);
    /// empty once :attr:`done`.
    fn requests(&self, py: Python<'_>) -> PyResult<Vec<(usize, TileDrawRequest)>> {
        let Some(request) = self.inner.lock(py)?.request().cloned() else { return Ok(Vec::new()) };
        let merged = Arc::clone(&self.merged);
        let parts = detached(py, move || Ok(loops_core::tile::tile_requests(&merged, &request)))?;
        Ok(parts
            .into_iter()
            .enumerate()
            .filter_map(|(t, part)| {
                part.map(|request| {
                    let tile = self.merged.tiles()[t].clone();
                    (t, TileDrawRequest { tile, labels: self.merged.tile_labels(t).to_vec(), request })
                })
            })
            .collect())
    }

    /// Takes the tiles' offers to the pending pass (all at once, or in several calls), then,
    /// with ``complete=True`` (the last call of the pass), ends the pass: the samples, or
    /// another pass for components whose keyed pairs came back short (rare).
    ///
    /// Raises:
    ///     TypeError: an offer of another type.
    #[pyo3(signature = (offers, *, complete=true))]
    fn absorb(&self, py: Python<'_>, offers: Vec<PyRef<'_, DrawCandidates>>, complete: bool) -> PyResult<()> {
        let mut draw = self.inner.lock(py)?;
        for offer in offers {
            draw.absorb(offer.inner.clone());
        }
        if complete {
            draw.complete();
        }
        Ok(())
    }

    /// The samples, as :attr:`FleetSamples.table` gives them (the columns of ``loops fleet``'s
    /// ``samples.csv`` in its order, less ``sampler``), in order of the pairs.
    ///
    /// Raises:
    ///     InvalidParameterError: before the draw is :attr:`done`.
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let draw = self.inner.lock(py)?;
        let Some(picks) = draw.picks() else {
            return Err(invalid_parameter("the draw is not done: answer its requests() first".to_owned()));
        };
        let inner = &*draw;
        crate::warning::warn_sample_warnings(
            py,
            inner.warnings(),
            picks.is_empty(),
            inner.sampler(),
            inner.available(),
            self.skip_trivial,
        )?;
        let session_of = |f: usize| self.starts.partition_point(|&s| s <= f) - 1;
        let located: Vec<loops_core::fleet::FleetSample> = picks
            .iter()
            .map(|p| {
                let (a, b) = (session_of(p.pair[0]), session_of(p.pair[1]));
                loops_core::fleet::FleetSample {
                    sessions: [a, b],
                    poses: [p.pair[0] - self.starts[a], p.pair[1] - self.starts[b]],
                    times_s: p.times_s,
                    component: Some(p.component),
                    distance: Some(p.distance),
                }
            })
            .collect();
        crate::py_fleet::fleet_samples_table(py, &located, &self.names)
    }
}

/// What one tile must offer a pass of a :class:`KeyedDraw`: the tile, the component ids of its
/// provisional components, and the part of the request about them. Pickles as its bytes.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileDrawRequest {
    tile: loops_core::tile::Tile,
    labels: Vec<u32>,
    request: loops_core::sample::DrawRequest,
}

#[pymethods]
impl TileDrawRequest {
    /// The request from :meth:`to_bytes`'s parts (what pickling stores).
    ///
    /// Raises:
    ///     InvalidParameterError: corrupt bytes.
    #[new]
    fn new(tile: &Tile, labels: &[u8], request: &[u8]) -> PyResult<Self> {
        if !labels.len().is_multiple_of(4) {
            return Err(invalid_parameter(format!("{} bytes of labels are not 4 bytes each", labels.len())));
        }
        let labels = labels.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        let request = loops_core::sample::DrawRequest::from_bytes(request).map_err(Failure::from)?;
        Ok(Self { tile: tile.inner.clone(), labels, request })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.get();
        let labels: Vec<u8> = this.labels.iter().flat_map(|l| l.to_le_bytes()).collect();
        let args =
            (Tile { inner: this.tile.clone() }, PyBytes::new(py, &labels), PyBytes::new(py, &this.request.to_bytes()));
        (slf.get_type().getattr("_from_state")?, args).into_pyobject(py)
    }

    /// The constructor, for unpickling: its errors are `pickle.UnpicklingError`.
    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, tile: &Tile, labels: &[u8], request: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "TileDrawRequest", || Self::new(tile, labels, request))
    }

    fn __repr__(&self) -> String {
        format!("TileDrawRequest({:?}, {} components asked)", self.tile, self.request.components.len())
    }

    /// The tile.
    #[getter]
    fn tile(&self) -> Tile {
        Tile { inner: self.tile.clone() }
    }
}

/// What one tile offers a pass of a keyed draw (:func:`draw_tile`): its keyed pairs below the
/// thresholds and the closest pairs of requested rows. Pickles as its bytes.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct DrawCandidates {
    inner: loops_core::sample::DrawCandidates,
}

crate::pickling::pickled_as_bytes!(
    DrawCandidates,
    loops_core::sample::DrawCandidates,
    "offers",
    "The offers as bytes (a tag, the tile format version, then MessagePack)."
);

#[pymethods]
impl DrawCandidates {
    fn __len__(&self) -> usize {
        self.inner.pool.len() + self.inner.rows.len() + self.inner.best.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "DrawCandidates({} keyed pairs, {} row picks, {} best picks)",
            self.inner.pool.len(),
            self.inner.rows.len(),
            self.inner.best.len()
        )
    }
}

/// Rescans one tile from its two sessions, without the GIL, and offers its pairs to a pass of a
/// :class:`KeyedDraw` (the arguments as :func:`scan_tile`'s, which the request's tile must have
/// been scanned with). Given the tile's ``runs`` (:func:`scan_tile` with ``runs=True`` and the
/// same arguments), it offers the same pairs from them without rescanning.
///
/// Args:
///     request: a :class:`TileDrawRequest` of :meth:`KeyedDraw.requests`.
///     session_a, session_b, starts, gamma, metric, separation, threads: as :func:`scan_tile`.
///     runs: the request's tile's :class:`TileRuns`, or ``None`` (rescan the tile).
///
/// Returns:
///     :class:`DrawCandidates`.
///
/// Raises:
///     InvalidParameterError: as :func:`scan_tile`; labels that do not fit the tile's scan;
///         runs of another tile, metric or starts.
#[pyfunction]
#[pyo3(signature = (request, session_a, session_b=None, *, starts, gamma, metric=None, separation=SeparationArg::Auto,
    threads=None, runs=None))]
#[pyo3(
    text_signature = "(request, session_a, session_b=None, *, starts, gamma, metric=None, separation='auto', threads=None, runs=None)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn draw_tile(
    py: Python<'_>,
    request: &TileDrawRequest,
    session_a: &Trajectory,
    session_b: Option<&Trajectory>,
    starts: (usize, usize),
    gamma: f64,
    metric: Option<&Bound<'_, PyAny>>,
    separation: SeparationArg,
    threads: Option<usize>,
    runs: Option<&crate::py_tile_scan::TileRuns>,
) -> PyResult<DrawCandidates> {
    let r = request.clone();
    let scan = TileScan::new(&r.tile, session_a, session_b, starts, gamma, metric, separation, "draw_tile")?;
    let runs = runs.map(|runs| crate::py_tile_scan::runs_for(runs, &r.tile, scan.metric)).transpose()?;
    let inner = scan.run(py, threads, move |s| match runs {
        Some(runs) => s.metric.draw_tile_runs(s.sessions(), s.starts, &runs, &r.labels, &r.request),
        None => {
            s.metric.draw_session_tile(s.sessions(), s.starts, s.gamma, s.separation, &r.tile, &r.labels, &r.request)
        }
    })?;
    Ok(DrawCandidates { inner })
}

/// The loop duration τ of one session from the shares of the tiles that hold its rows or
/// columns (:func:`scan_tile` with ``duration=True``), as :meth:`FleetLoops.loop_duration` splits it.
///
/// Args:
///     session: the session's index in the fleet.
///     start: its first fleet index.
///     poses: its number of poses.
///     parts: :class:`TileDuration` shares, in any order (others are ignored).
///
/// Returns:
///     ``(own_s, other_s)``: float64 arrays of ``poses`` seconds, τ within the session and with
///     the other sessions.
///
/// Raises:
///     InvalidParameterError: a share that does not lie in the session.
#[pyfunction]
#[pyo3(signature = (session, *, start, poses, parts))]
pub(crate) fn session_loop_duration<'py>(
    py: Python<'py>,
    session: usize,
    start: usize,
    poses: usize,
    parts: Vec<PyRef<'py, crate::py_tile_scan::TileDuration>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let parts: Vec<loops_core::tile::TileDuration> = parts.iter().map(|p| p.inner.clone()).collect();
    let (own, other) =
        detached(py, move || Ok(loops_core::tile::session_loop_duration(session, start, poses, &parts)?))?;
    PyTuple::new(py, [to_numpy(py, own).into_any(), to_numpy(py, other).into_any()])
}
