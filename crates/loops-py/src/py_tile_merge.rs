//! Merges of a fleet's tiles: `TileMerge` (`merge_tiles`) and the fleet's loops they finish
//! into, `TiledFleetLoops` (`TileMerge.finish`), whose keyed draws of samples come from
//! `py_tile_draw`. Merges pickle as their bytes; `TiledFleetLoops` as the other results do
//! (`pickling`).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::convert::to_numpy;
use crate::detached;
use crate::error::invalid_parameter;
use crate::py_fleet::{components_table, overlap_matrix, session_pairs_table};
use crate::py_tile::{SessionBlocks, Tile, TileSummary};

/// A partial merge of tiles: the components of the tiles it holds with every join between them
/// made, and only the edge runs that face tiles it does not hold yet. Merges of disjoint sets
/// of tiles merge again (:func:`merge_tiles`), in any grouping and order; the merge of every
/// tile of a plan :meth:`finish`\ es into the fleet's components. Pickles as :meth:`to_bytes`.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct TileMerge {
    inner: loops_core::tile::TileMerge,
}

crate::pickling::pickled_as_bytes!(
    TileMerge,
    loops_core::tile::TileMerge,
    "merge",
    "The merge as bytes (as :meth:`TileSummary.to_bytes`, another tag).",
    from_bytes
);

#[pymethods]
impl TileMerge {
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
///     >>> blocks = [il.tiles.session_blocks(drive, block=8)]
///     >>> tiles = il.tiles.plan_tiles(blocks, gamma=0.5)
///     >>> parts = [il.tiles.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None) for t in tiles]
///     >>> merged = il.tiles.merge_tiles([il.tiles.merge_tiles(parts[:2]), *parts[2:]])
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
            merges[k] = Some(loops_core::tile::TileMerge::new(summary)?);
        }
        Ok(loops_core::tile::TileMerge::merge(merges.into_iter().flatten().collect())?)
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
    components: Vec<loops_core::fleet::FleetComponent>,
    times: Vec<[[f64; 2]; 2]>,
    pairs: Vec<loops_core::fleet::SessionPair>,
    /// The merge and the sessions' first fleet indices, for keyed draws of samples
    /// (`py_tile_draw`); not pickled (an unpickled result draws no samples).
    pub(crate) merged: Option<(std::sync::Arc<loops_core::tile::MergedLoops>, Vec<usize>)>,
}

impl TiledFleetLoops {
    /// The merge and the sessions' first fleet indices, or why not.
    pub(crate) fn merge(&self) -> PyResult<(&std::sync::Arc<loops_core::tile::MergedLoops>, &[usize])> {
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
type TiledState =
    (Vec<String>, Vec<loops_core::fleet::FleetComponent>, Vec<[[f64; 2]; 2]>, Vec<loops_core::fleet::SessionPair>);

#[pymethods]
impl TiledFleetLoops {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get();
        let value = (&this.names, &this.components, &this.times, &this.pairs);
        crate::pickling::reduce(slf.as_any(), "TiledFleetLoops", &value)
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, pyo3::types::PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "TiledFleetLoops", || {
            let py = cls.py();
            let (names, components, times, pairs): TiledState = crate::pickling::restore(py, "TiledFleetLoops", state)?;
            loops_core::fleet::check_fleet_tables(names.len(), &components, &times, &pairs)
                .map_err(crate::error::Failure::from)?;
            Ok(Self { names, components, times, pairs, merged: None })
        })
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
    /// ``"rho"``, ``"rho-dispersed"``, ``"alpha"``, ``"closest-first"``,
    /// ``"closest-then-spread"``, ``"nearest-then-uniform"``; not the baselines, whose rules
    /// run over whole trajectories).
    ///
    /// Args:
    ///     sampler: the sampler's name (``None``: :data:`DEFAULT_SAMPLER`).
    ///     rate, budget: as :func:`sample_fleet` (at most one; neither:
    ///         :data:`DEFAULT_BUDGET`).
    ///     seed: the seed.
    ///     between_only: only the components between two sessions.
    ///     skip_trivial: leave out the trivial components.
    ///
    /// Returns:
    ///     :class:`KeyedDraw`.
    ///
    /// Raises:
    ///     InvalidParameterError: an unknown sampler, a baseline, both rate and budget, a
    ///         budget of 0, a rate out of range, a result read from a pickle (which
    ///         holds no merge); ``TooManySamplesError`` as :func:`sample_fleet`.
    #[pyo3(signature = (sampler=None, *, rate=None, budget=None, seed, between_only=false, skip_trivial=false))]
    #[allow(clippy::too_many_arguments)]
    fn draw(
        &self,
        py: Python<'_>,
        sampler: Option<&str>,
        rate: Option<f64>,
        budget: Option<usize>,
        seed: u64,
        between_only: bool,
        skip_trivial: bool,
    ) -> PyResult<crate::py_tile_draw::KeyedDraw> {
        let (merged, starts) = self.merge()?;
        crate::py_tile_draw::plan_draw(
            py,
            (merged, starts, &self.names),
            sampler,
            rate,
            budget,
            seed,
            between_only,
            skip_trivial,
        )
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
        components_table(py, &self.components, &self.names, &self.times, &[])
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
