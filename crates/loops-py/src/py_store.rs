//! `FleetStore`: a fleet store on disk (`loops_io::store` over `loops_core::store::FleetStore`), its
//! updates and its tables.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyReadonlyArrayDyn};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyList};

use crate::convert::{float64_column, int64_column, table, to_numpy};
use crate::detached;
use crate::error::{Failure, invalid_parameter};
use crate::py_fleet::{
    common_metric, components_table, fleet_samples_table, loop_duration_table, overlap_matrix, read_sessions,
    read_sessions_if, session_index_of, session_pairs_table,
};
use crate::py_metric::MetricArg;
use crate::py_samples::sampler_of;
use crate::py_separation::{Separation, SeparationArg};
use crate::py_trajectory::ReadArgs;
use loops_core::{
    fleet::FleetSample,
    store::{ScannedTile, StoreLoops, StoreSettings},
};
use loops_io::store::{
    StoreConfig, StoreError, StorePlan, StoredFleet, plan_store_update, read_samples, read_store, scan_store_tiles,
    update_opened_store, update_store, update_store_scanned,
};

/// A fleet's loops kept in a folder and updated at the cost of the new data: each
/// :meth:`update` adds sessions (replacing those of the same name) and removes others,
/// scans only the tiles that hold a new or replaced session, merges again from the stored tile
/// summaries and redraws the samples by keyed draws. After any sequence of updates the tables
/// are those of :func:`find_fleet_loops` and :func:`sample_fleet` over the stored sessions in
/// name order, whatever the order of the updates.
///
/// The folder is what ``loops fleet --store DIR`` keeps: Parquet tables that pandas, pyarrow
/// and DuckDB read (``store.json`` names the current state, ``state-NNNNNN/``, holding
/// ``sessions``, ``components``, ``session_pairs``, ``loop_duration`` and ``samples``,
/// ``.parquet`` each, and the folders ``tiles/`` and ``merges/`` of the stored tiles and
/// session pairs' merges by part); each update makes a new state (linking the parts it keeps,
/// writing its new tiles and merges as one more each) and then points at it, so a reader or a
/// killed update sees the old state or the new one. Made by :meth:`open` and :meth:`update`.
///
/// Example:
///     Monday drives out along a street; Tuesday's drive, added the next day, comes back along
///     it half a metre aside: the store's answer is the fleet's.
///
///     >>> import tempfile, numpy as np, inexact_loops as il
///     >>> x = np.arange(21) * 0.5
///     >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
///     >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
///     >>> folder = tempfile.mkdtemp() + "/city"
///     >>> store = il.FleetStore.open(folder)
///     >>> store.update(add=[("monday", monday)], gamma=1.0, separation=None, block=8)["added"]
///     ['monday']
///     >>> update = store.update(add=[("tuesday", tuesday)])
///     >>> update["added"], update["tiles_kept"] > 0
///     (['tuesday'], True)
///     >>> store.names, store.added.tolist()  # Tuesday's own component and the one with Monday
///     (['monday', 'tuesday'], [1, 2])
///     >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
///     >>> scratch = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
///     >>> np.array_equal(store.overlap_matrix(), scratch.overlap_matrix())
///     True
#[pyclass(module = "inexact_loops._core")]
pub(crate) struct FleetStore {
    dir: PathBuf,
    /// None until the first update makes the store.
    state: Option<State>,
}

/// A store as read or written, and its answer.
struct State {
    stored: StoredFleet,
    loops: StoreLoops,
    samples: Vec<FleetSample>,
    added: Vec<usize>,
}

impl State {
    /// The answer of a store written by `update_store` (`loops` and `samples` as written) or
    /// read back (`None`: merged again, and the samples table read).
    fn new(stored: StoredFleet, loops: Option<StoreLoops>, samples: Option<Vec<FleetSample>>) -> Result<Self, Failure> {
        let loops = match loops {
            Some(loops) => loops,
            None => stored.store.loops()?,
        };
        let samples = match samples {
            Some(samples) => samples,
            None => read_samples(&stored)?,
        };
        let added = stored.store.added_components(&loops);
        Ok(Self { stored, loops, samples, added })
    }
}

impl FleetStore {
    /// The settings of an update of this store ([`update_config`]).
    #[allow(clippy::too_many_arguments)]
    fn config(
        &self,
        gamma: Option<f64>,
        metric: Option<&Bound<'_, PyAny>>,
        separation: SeparationArg,
        block: Option<usize>,
        sampler: Option<&str>,
        rate: Option<f64>,
        budget: Option<usize>,
        seed: Option<u64>,
        between_only: bool,
        skip_trivial: bool,
        sessions: &[(String, crate::py_trajectory::Trajectory)],
    ) -> PyResult<Option<StoreConfig>> {
        let store = self.state.as_ref().map(|s| s.stored.store.settings());
        update_config(
            &self.dir,
            self.state.is_some(),
            store,
            gamma,
            metric,
            separation,
            block,
            sampler,
            rate,
            budget,
            seed,
            between_only,
            skip_trivial,
            sessions,
        )
    }

    fn names(&self) -> Vec<String> {
        self.state
            .as_ref()
            .map_or_else(Vec::new, |s| s.stored.store.sessions().iter().map(|s| s.name.clone()).collect())
    }

    fn settings(&self) -> Option<&StoreSettings> {
        self.state.as_ref().map(|s| s.stored.store.settings())
    }
}

/// The settings of an update of the store in `dir` (`exists`: made; `store`: its settings, where
/// read): `None` without `gamma` (the store's own), else all of them.
#[allow(clippy::too_many_arguments)]
fn update_config(
    dir: &std::path::Path,
    exists: bool,
    store: Option<&StoreSettings>,
    gamma: Option<f64>,
    metric: Option<&Bound<'_, PyAny>>,
    separation: SeparationArg,
    block: Option<usize>,
    sampler: Option<&str>,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: Option<u64>,
    between_only: bool,
    skip_trivial: bool,
    sessions: &[(String, crate::py_trajectory::Trajectory)],
) -> PyResult<Option<StoreConfig>> {
    let Some(gamma) = gamma else {
        let given = metric.is_some()
            || block.is_some()
            || sampler.is_some()
            || rate.is_some()
            || budget.is_some()
            || seed.is_some()
            || between_only
            || skip_trivial;
        if given || !exists {
            return Err(invalid_parameter(format!(
                "FleetStore.update: {}: give gamma= with the other settings (metric=, separation=, block=, \
                     sampler=, ...), or no setting to keep the store's",
                if !exists {
                    format!("{} holds no store yet, which needs its settings", dir.display())
                } else {
                    "a store's settings are given whole".to_owned()
                }
            )));
        }
        return Ok(None);
    };
    let metric = match metric {
        Some(_) => MetricArg::spec_from_py(metric, "FleetStore.update")?,
        None => {
            let of_sessions =
                sessions.iter().map(|(name, t)| (name.as_str(), t.metric.unwrap_or_else(|| t.inner.default_metric())));
            match (common_metric(of_sessions)?, store) {
                (Some(metric), _) => metric,
                (None, Some(settings)) => settings.metric,
                (None, None) => loops_core::MetricSpec::default(),
            }
        }
    };
    let sampler = match (sampler, seed) {
        (Some(name), Some(seed)) => Some((sampler_of(Some(name), rate, budget, seed, skip_trivial)?, between_only)),
        (Some(_), None) => return Err(invalid_parameter("FleetStore.update: sampler= needs seed=".to_owned())),
        (None, _) if rate.is_some() || budget.is_some() || seed.is_some() || between_only || skip_trivial => {
            return Err(invalid_parameter(
                "FleetStore.update: rate=, budget=, seed=, between_only= and skip_trivial= go with sampler=".to_owned(),
            ));
        }
        (None, _) => None,
    };
    let block = block.unwrap_or(StoreSettings::DEFAULT_BLOCK);
    let settings = StoreSettings { metric, gamma, separation: separation.at(gamma), block };
    settings.check().map_err(Failure::from)?;
    Ok(Some(StoreConfig { settings, sampler }))
}

/// `update`'s report as a dict.
fn update_dict<'py>(py: Python<'py>, update: &loops_core::store::StoreUpdate) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("added", &update.added)?;
    dict.set_item("replaced", &update.replaced)?;
    dict.set_item("unchanged", &update.unchanged)?;
    dict.set_item("removed", &update.removed)?;
    dict.set_item("tiles_scanned", update.tiles_scanned)?;
    dict.set_item("tiles_kept", update.tiles_kept)?;
    dict.set_item("tiles_dropped", update.tiles_dropped)?;
    dict.set_item("changed", !update.changes_nothing())?;
    Ok(dict)
}

#[pymethods]
impl FleetStore {
    /// Poses per block of a session when ``block=`` is not given (tiles are blocks × blocks);
    /// also the unit :mod:`inexact_loops.dask` cuts sessions into.
    #[classattr]
    const DEFAULT_BLOCK: usize = StoreSettings::DEFAULT_BLOCK;

    /// The store in the folder ``path``: its current state, or, for a missing or empty folder,
    /// a store that the first :meth:`update` makes there (with the settings it gives). Opening
    /// reads the state's small tables and where its tiles lie; a stored tile is decoded (and
    /// checked) when an update or a draw first needs it.
    ///
    /// Raises:
    ///     FileNotFoundError: ``path`` holds files but no store (no ``store.json``).
    ///     LoopsIOError: a file of the store that cannot be read back (named).
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let dir = path.clone();
        let state = detached(py, move || {
            if dir.join("store.json").is_file() {
                return Ok(Some(State::new(read_store(&dir)?, None, None)?));
            }
            let empty = match std::fs::read_dir(&dir) {
                Ok(mut entries) => entries.next().is_none(),
                Err(error) => error.kind() == std::io::ErrorKind::NotFound,
            };
            if empty { Ok(None) } else { Err(Failure::from(StoreError::NotAStore { path: dir })) }
        })?;
        Ok(Self { dir: path, state })
    }

    /// Adds the sessions ``add`` (replacing stored ones of the same name) and removes the
    /// sessions named in ``remove``, in one update written atomically; a session given with the
    /// content it has in the store changes nothing. Scans only the tiles that hold an added or
    /// replaced session (reading the stored sessions they meet from the store's pose files).
    /// Starts from the store as this object holds it while the folder still holds that state
    /// (another process may have updated it since: the folder is then read again).
    ///
    /// The settings are fixed when the store is made: the first update gives ``gamma`` and
    /// whichever others it wants; a later one gives none (the store's own) or all of them as
    /// the store has them (a check: otherwise an error, the store unchanged).
    ///
    /// Args:
    ///     add: sessions as :class:`Fleet` takes them (a dict ``{name: session}``, ``(name,
    ///         session)`` pairs or paths named by their stem), read with the reading keywords.
    ///     remove: names of stored sessions to remove.
    ///     gamma: γ, in the metric's unit.
    ///     metric: a metric name or object (not a callable); ``None``: the sessions' own.
    ///     separation: within each session, as in :func:`find_fleet_loops`.
    ///     block: poses per block of a session; ``None``: :attr:`DEFAULT_BLOCK`.
    ///     sampler, rate, budget, seed, skip_trivial, between_only: the samples of every state,
    ///         as :func:`sample_fleet` draws them (a component sampler); ``None``: no samples.
    ///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
    ///     format, axes, topic, time, frames, rate_hz, drop_duplicate_stamps,
    ///         quaternion_tolerance: how paths are read, as in :class:`Fleet`.
    ///     scanned: the update's new tiles scanned elsewhere (:meth:`StoreUpdatePlan.scan` of
    ///         every tile of the :class:`StoreUpdatePlan` with the same arguments, in any
    ///         order); ``None``: scanned here. The update then checks that they are exactly its
    ///         plan's tiles, of this state, and scans nothing.
    ///
    /// Returns:
    ///     What this update did, as :attr:`last_update` holds it. An update of a store that
    ///     changes nothing (nothing given or removed, or every session given stored with this
    ///     content) says ``changed`` False and writes nothing: no new state, no file or time of
    ///     the folder touched, and :attr:`last_update` still that of the last update that
    ///     changed the store.
    ///
    /// Raises:
    ///     InvalidParameterError: no ``gamma`` for a new store; settings other than the store's;
    ///         a name given twice, or removed and given, or removed but not stored; a session of
    ///         another dimension or manifold. The store is then unchanged.
    ///     OSError, LoopsIOError: a path that cannot be read; a store file that cannot be read
    ///         or written (named; a stored tile the update reads, by part file and row).
    #[pyo3(signature = (*, add=None, remove=None, gamma=None, metric=None, separation=SeparationArg::Auto, block=None,
        sampler=None, rate=None, budget=None, seed=None, between_only=false, skip_trivial=false, threads=None,
        format=None, axes=None, topic=None, time=None, frames=None, rate_hz=None, drop_duplicate_stamps=false,
        quaternion_tolerance=None, scanned=None))]
    #[pyo3(
        text_signature = "($self, *, add=None, remove=None, gamma=None, metric=None, separation='auto', block=None, \
                          sampler=None, rate=None, budget=None, seed=None, between_only=False, skip_trivial=False, \
                          threads=None, format=None, axes=None, topic=None, time=None, frames=None, rate_hz=None, \
                          drop_duplicate_stamps=False, quaternion_tolerance=None, scanned=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        add: Option<&Bound<'py, PyAny>>,
        remove: Option<Vec<String>>,
        gamma: Option<f64>,
        metric: Option<&Bound<'py, PyAny>>,
        separation: SeparationArg,
        block: Option<usize>,
        sampler: Option<&str>,
        rate: Option<f64>,
        budget: Option<usize>,
        seed: Option<u64>,
        between_only: bool,
        skip_trivial: bool,
        threads: Option<usize>,
        format: Option<String>,
        axes: Option<(usize, usize)>,
        topic: Option<String>,
        time: Option<String>,
        frames: Option<(String, String)>,
        rate_hz: Option<f64>,
        drop_duplicate_stamps: bool,
        quaternion_tolerance: Option<f64>,
        scanned: Option<Vec<Vec<u8>>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let args = ReadArgs {
            format,
            axes,
            topic,
            time,
            frames,
            rate_hz,
            drop_duplicate_stamps,
            quaternion_tolerance,
            ..ReadArgs::default()
        };
        let sessions = read_add(py, add, metric, &args)?;
        let config = self.config(
            gamma,
            metric,
            separation,
            block,
            sampler,
            rate,
            budget,
            seed,
            between_only,
            skip_trivial,
            &sessions,
        )?;
        let put: Vec<(String, loops_core::Trajectory)> =
            sessions.into_iter().map(|(name, t)| (name, Arc::unwrap_or_clone(t.inner))).collect();
        let remove = remove.unwrap_or_default();
        let dir = self.dir.clone();
        // The store as opened is where the update starts, unless the folder has moved on since
        // (update_opened_store checks); after a failed update it is read again.
        let opened = self.state.take().map(|s| s.stored);
        let state = detached(py, move || {
            let scanned = scanned
                .map(|s| s.iter().map(|b| ScannedTile::from_bytes(b)).collect::<Result<Vec<_>, _>>())
                .transpose()?;
            let report = loops_core::with_threads(threads, || match (opened, scanned) {
                (Some(opened), scanned) => update_opened_store(opened, config.as_ref(), put, &remove, scanned),
                (None, None) => update_store(&dir, config.as_ref(), put, &remove),
                (None, Some(scanned)) => update_store_scanned(&dir, config.as_ref(), put, &remove, scanned),
            })??;
            // Samples written with the state, else (nothing written) read from its table.
            let written = !report.update.changes_nothing();
            let samples = written.then(|| report.samples.map(|s| s.rows).unwrap_or_default());
            Ok::<_, Failure>((State::new(report.stored, Some(report.loops), samples)?, report.update))
        });
        let (state, update) = match state {
            Ok(done) => done,
            Err(error) => {
                let dir = self.dir.clone();
                self.state = detached(py, move || {
                    let made = dir.join("store.json").is_file();
                    made.then(|| State::new(read_store(&dir)?, None, None)).transpose()
                })
                .unwrap_or(None);
                return Err(error);
            }
        };
        let update = update_dict(py, &update)?;
        self.state = Some(state);
        Ok(update)
    }

    fn __len__(&self) -> usize {
        self.state.as_ref().map_or(0, |s| s.stored.store.sessions().len())
    }

    fn __repr__(&self) -> String {
        match &self.state {
            None => format!("FleetStore({:?}, no store yet)", self.dir.display().to_string()),
            Some(s) => {
                let settings = s.stored.store.settings();
                format!(
                    "FleetStore({:?}, {}, gamma={}, metric={}, block={}, {} sessions, {} components, {} samples)",
                    self.dir.display().to_string(),
                    s.stored.state,
                    settings.gamma,
                    settings.metric.name(),
                    settings.block,
                    s.stored.store.sessions().len(),
                    s.loops.components().len(),
                    s.samples.len()
                )
            }
        }
    }

    /// The store's folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.dir.clone()
    }

    /// Pickles as its folder: unpickling opens the store there (:meth:`open`), in the state the
    /// folder holds then, so a store crosses to another process (a process pool, a Dask worker)
    /// that sees the same folder, without copying its tables.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (PathBuf,))> {
        Ok((slf.get_type().getattr("open")?, (slf.borrow().dir.clone(),)))
    }

    /// The folder of the current state (``path / "state-NNNNNN"``), whose ``.parquet`` tables
    /// are the store's; ``None`` before the first update.
    #[getter]
    fn state_path(&self) -> Option<PathBuf> {
        self.state.as_ref().map(|s| s.stored.dir.join(&s.stored.state))
    }

    /// The stored sessions' names, in name order (the order of the session indices of the
    /// tables).
    #[getter]
    #[pyo3(name = "names")]
    fn py_names(&self) -> Vec<String> {
        self.names()
    }

    /// γ; ``None`` before the first update.
    #[getter]
    fn gamma(&self) -> Option<f64> {
        self.settings().map(|s| s.gamma)
    }

    /// The name of the store's metric; ``None`` before the first update.
    #[getter]
    fn metric_name(&self) -> Option<String> {
        self.settings().map(|s| s.metric.name())
    }

    /// The separation within a session (:class:`Separation`); ``None`` before the first update.
    #[getter]
    fn separation(&self) -> Option<Separation> {
        self.settings().map(|s| Separation { inner: s.separation })
    }

    /// Poses per block of a session; ``None`` before the first update.
    #[getter]
    fn block(&self) -> Option<usize> {
        self.settings().map(|s| s.block)
    }

    /// The name of the store's sampler; ``None`` for a store without samples.
    #[getter]
    fn sampler(&self) -> Option<&'static str> {
        self.state.as_ref().and_then(|s| s.stored.config.sampler.as_ref().map(|(sampler, _)| sampler.kind.name()))
    }

    /// What the last update that changed the store did: a dict of ``added``, ``replaced``,
    /// ``unchanged``, ``removed`` (session names, each in name order), ``tiles_scanned``,
    /// ``tiles_kept``, ``tiles_dropped`` (int) and ``changed`` (bool: whether it added,
    /// replaced or removed a session).
    #[getter]
    fn last_update<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let empty = loops_core::store::StoreUpdate::default();
        update_dict(py, self.state.as_ref().map_or(&empty, |s| s.stored.store.last_update()))
    }

    /// The loop components as a :class:`~inexact_loops.Table`, with the columns of
    /// :attr:`FleetLoops.components` (sessions by index in :attr:`names`).
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let names = self.names();
        match &self.state {
            None => components_table(py, &[], &names, &[], &[]),
            Some(s) => components_table(py, s.loops.components(), &names, &s.loops.component_times_s(), &[]),
        }
    }

    /// The ids of the components the last update added: those of a session it added or
    /// replaced (with itself or another), int64, increasing.
    #[getter]
    fn added<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let added = self.state.as_ref().map_or_else(Vec::new, |s| s.added.iter().map(|&c| c as i64).collect());
        to_numpy(py, added)
    }

    /// Which sessions pass near a place, and when: per session, the maximal runs of
    /// consecutive poses within ``radius`` of ``place`` (poses read from the store's pose
    /// files). A place lies in the map plane of the positions' first two coordinates (x, y of
    /// Euclidean points, SE(2) and SE(3) poses), with the plane's distance; a pose is within
    /// ``radius`` of a polygon when inside it (even-odd rule) or within ``radius`` of its
    /// boundary.
    ///
    /// Args:
    ///     place: a point ``(x, y)`` or a polygon, an array of shape ``(n, 2)`` of its vertices
    ///         in order (n ≥ 3; the last joins the first).
    ///     radius: in the plane's unit (metres); ``None``: :attr:`gamma`.
    ///
    /// Returns:
    ///     A :class:`~inexact_loops.Table` with a row per pass, in session order and time
    ///     order: ``session`` (index in :attr:`names`), ``name``, ``i_start``, ``i_end`` (its
    ///     first and last pose, both within the radius), ``t_start_s``, ``t_end_s`` (their
    ///     times on the session's clock).
    ///
    /// Raises:
    ///     InvalidParameterError: a place of another shape, a polygon of fewer than 3
    ///         vertices, a coordinate that is not finite, a negative radius, sessions without
    ///         a map plane.
    ///
    /// Example:
    ///     >>> import tempfile, numpy as np, inexact_loops as il
    ///     >>> x = np.arange(21) * 0.5
    ///     >>> store = il.FleetStore.open(tempfile.mkdtemp() + "/city")
    ///     >>> out = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
    ///     >>> _ = store.update(add={"out": out}, gamma=1.0, separation=None)
    ///     >>> passes = store.near((5.0, 0.3), radius=1.0)
    ///     >>> passes["name"].tolist(), passes["i_start"].tolist(), passes["i_end"].tolist()
    ///     (['out'], [9], [11])
    ///     >>> store.near([(0, -1), (2, -1), (2, 1), (0, 1)])["t_end_s"].tolist()  # within γ
    ///     [6.0]
    #[pyo3(signature = (place, *, radius=None))]
    fn near<'py>(
        &self,
        py: Python<'py>,
        place: &Bound<'py, PyAny>,
        radius: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let place = place_of(place)?;
        let names = self.names();
        let passes = match &self.state {
            None => {
                radius.map(loops_core::check_radius).transpose().map_err(Failure::from)?;
                Vec::new()
            }
            Some(state) => {
                let stored = &state.stored;
                detached(py, || Ok(stored.near(&place, radius)?))?
            }
        };
        table(
            py,
            [
                ("session", int64_column(py, &passes, |p| p.session)),
                ("name", names_column(py, passes.iter().map(|p| names[p.session].as_str()))?),
                ("i_start", int64_column(py, &passes, |p| p.pass.poses[0])),
                ("i_end", int64_column(py, &passes, |p| p.pass.poses[1])),
                ("t_start_s", float64_column(py, &passes, |p| p.pass.times_s[0])),
                ("t_end_s", float64_column(py, &passes, |p| p.pass.times_s[1])),
            ],
        )
    }

    /// The sessions that revisit ``session``: those sharing at least one loop component with
    /// it (other than itself), read from the overlap matrix.
    ///
    /// Args:
    ///     session: its name or index.
    ///
    /// Returns:
    ///     A :class:`~inexact_loops.Table` with a row per revisiting session, in session
    ///     order: ``session`` (index in :attr:`names`), ``name``, ``components`` (shared),
    ///     ``pair_count`` (pose pairs within γ between the two), ``area_s2``, ``density``
    ///     (their block of :meth:`session_pairs`).
    ///
    /// Raises:
    ///     KeyError: no session of that name. IndexError: an index out of range.
    ///
    /// Example:
    ///     >>> import tempfile, numpy as np, inexact_loops as il
    ///     >>> x = np.arange(21) * 0.5
    ///     >>> store = il.FleetStore.open(tempfile.mkdtemp() + "/city")
    ///     >>> there = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
    ///     >>> back = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
    ///     >>> _ = store.update(add={"there": there, "back": back}, gamma=1.0, separation=None)
    ///     >>> store.revisits("there")["name"].tolist()
    ///     ['back']
    fn revisits<'py>(&self, py: Python<'py>, session: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let names = self.names();
        let a = session_index_of(&names, session)?;
        let revisits = self.state.as_ref().map_or_else(Vec::new, |s| s.loops.revisits(a));
        table(
            py,
            [
                ("session", int64_column(py, &revisits, |r| r.session)),
                ("name", names_column(py, revisits.iter().map(|r| names[r.session].as_str()))?),
                ("components", int64_column(py, &revisits, |r| r.components)),
                ("pair_count", int64_column(py, &revisits, |r| r.pair_count as usize)),
                ("area_s2", float64_column(py, &revisits, |r| r.area_s2)),
                ("density", float64_column(py, &revisits, |r| r.density)),
            ],
        )
    }

    /// The sparse overlap matrix as a :class:`~inexact_loops.Table`, as
    /// :meth:`FleetLoops.session_pairs`.
    fn session_pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pairs = self.state.as_ref().map_or(&[][..], |s| s.loops.session_pairs());
        session_pairs_table(py, pairs, &self.names())
    }

    /// The overlap matrix, as :meth:`FleetLoops.overlap_matrix`.
    #[pyo3(signature = (*, sparse=false))]
    fn overlap_matrix<'py>(&self, py: Python<'py>, sparse: bool) -> PyResult<Bound<'py, PyAny>> {
        let pairs = self.state.as_ref().map_or(&[][..], |s| s.loops.session_pairs());
        overlap_matrix(py, self.__len__(), pairs, sparse)
    }

    /// Loop duration τ per pose, split into own and other sessions, as
    /// :meth:`FleetLoops.loop_duration` (times read from the store's pose files).
    ///
    /// Args:
    ///     session: only this session's poses (its name or index); ``None``: every pose.
    ///
    /// Raises:
    ///     KeyError: no session of that name. IndexError: an index out of range.
    #[pyo3(signature = (session=None))]
    fn loop_duration<'py>(&self, py: Python<'py>, session: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyAny>> {
        let names = self.names();
        let Some(state) = &self.state else { return loop_duration_table(py, &[], &[], &[]) };
        let chosen = match session {
            Some(key) => {
                let a = session_index_of(&names, key)?;
                a..a + 1
            }
            None => 0..names.len(),
        };
        let store = &state.stored;
        let (times, own, other) = detached(py, || {
            let sessions = store.store.sessions();
            let times = chosen
                .clone()
                .map(|a| Ok((a, store.poses(&sessions[a])?.timestamps_s().to_vec())))
                .collect::<Result<Vec<_>, StoreError>>()?;
            let (own, other) = store.store.loop_duration()?;
            Ok((times, own, other))
        })?;
        let starts = state.stored.store.starts();
        let span = match times.last() {
            Some((last, t)) => starts[chosen.start]..starts[*last] + t.len(),
            None => 0..0,
        };
        let sessions: Vec<(usize, &[f64])> = times.iter().map(|(a, t)| (*a, t.as_slice())).collect();
        loop_duration_table(py, &sessions, &own[span.clone()], &other[span])
    }

    /// The samples of the current state as a :class:`~inexact_loops.Table`, with the columns
    /// of :attr:`FleetSamples.table`; no rows for a store without a sampler.
    #[getter]
    fn samples<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let samples = self.state.as_ref().map_or(&[][..], |s| &s.samples[..]);
        fleet_samples_table(py, samples, &self.names())
    }
}

/// A place from Python: a point ``(x, y)`` or polygon vertices of shape ``(n, 2)``.
fn place_of(place: &Bound<'_, PyAny>) -> PyResult<loops_core::Place> {
    let py = place.py();
    let array = py.import("numpy")?.call_method1("asarray", (place, "float64")).map_err(|error| {
        invalid_parameter(format!("FleetStore.near: place must be a point (x, y) or polygon vertices (n, 2): {error}"))
    })?;
    let array: PyReadonlyArrayDyn<'_, f64> = array.extract()?;
    let values = array.as_array();
    let shape = values.shape().to_vec();
    let place = match shape[..] {
        [2] => loops_core::Place::point([values[[0]], values[[1]]]),
        [_, 2] => loops_core::Place::polygon(values.outer_iter().map(|v| [v[0], v[1]]).collect()),
        _ => {
            return Err(invalid_parameter(format!(
                "FleetStore.near: place has shape {shape:?}; a point has shape (2,), a polygon (n, 2)"
            )));
        }
    };
    Ok(place.map_err(Failure::from)?)
}

/// A column of session names (numpy ``str``).
fn names_column<'py, 'a>(py: Python<'py>, names: impl Iterator<Item = &'a str>) -> PyResult<Bound<'py, PyAny>> {
    let kwargs = [("dtype", "str")].into_py_dict(py)?;
    py.import("numpy")?.call_method("array", (PyList::new(py, names)?,), Some(&kwargs))
}

/// The sessions of `add` (as :class:`Fleet` takes them), read with `args`.
fn read_add(
    py: Python<'_>,
    add: Option<&Bound<'_, PyAny>>,
    metric: Option<&Bound<'_, PyAny>>,
    args: &ReadArgs,
) -> PyResult<Vec<(String, crate::py_trajectory::Trajectory)>> {
    match add {
        None => Ok(Vec::new()),
        Some(add) => read_sessions(py, add, metric, args),
    }
}

/// The plan of an update of the fleet store in the folder ``path``, made from the store's
/// small tables (settings and sessions; no tile is read): the tiles the update must scan, each
/// of which :meth:`scan` scans on its own, on any machine that reads the new sessions and the
/// store's folder; :meth:`FleetStore.update` with ``scanned=`` then applies them and writes the
/// new state. The three steps are those :meth:`FleetStore.update` makes in one process;
/// :func:`inexact_loops.dask.update_store` spreads the scans over a cluster's workers.
///
/// The arguments are :meth:`FleetStore.update`'s (the same for the plan, the scans and the
/// update). A plan holds no poses and no stored tile (O(sessions + blocks + tiles to scan)),
/// and pickles.
///
/// Example:
///     >>> import tempfile, numpy as np, inexact_loops as il
///     >>> x = np.arange(21) * 0.5
///     >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
///     >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
///     >>> folder = tempfile.mkdtemp() + "/city"
///     >>> _ = il.FleetStore.open(folder).update(add={"monday": monday}, gamma=1.0, block=8)
///     >>> plan = il.StoreUpdatePlan(folder, add={"tuesday": tuesday})
///     >>> len(plan), plan.tile_sessions[0]
///     (10, ('monday', 'tuesday'))
///     >>> scanned = [b for k in range(len(plan)) for b in plan.scan([k], add={"tuesday": tuesday})]
///     >>> il.FleetStore.open(folder).update(add={"tuesday": tuesday}, scanned=scanned)["tiles_scanned"]
///     10
#[pyclass(module = "inexact_loops._core", frozen)]
pub(crate) struct StoreUpdatePlan {
    inner: StorePlan,
}

#[pymethods]
impl StoreUpdatePlan {
    /// Plans the update of the store in ``path`` that :meth:`FleetStore.update` makes with the
    /// same arguments.
    ///
    /// Raises:
    ///     As :meth:`FleetStore.update`.
    #[new]
    #[pyo3(signature = (path, *, add=None, remove=None, gamma=None, metric=None, separation=SeparationArg::Auto,
        block=None, sampler=None, rate=None, budget=None, seed=None, between_only=false, skip_trivial=false,
        format=None, axes=None, topic=None, time=None, frames=None, rate_hz=None, drop_duplicate_stamps=false,
        quaternion_tolerance=None))]
    #[pyo3(
        text_signature = "(path, *, add=None, remove=None, gamma=None, metric=None, separation='auto', block=None, \
                          sampler=None, rate=None, budget=None, seed=None, between_only=False, skip_trivial=False, \
                          format=None, axes=None, topic=None, time=None, frames=None, rate_hz=None, \
                          drop_duplicate_stamps=False, quaternion_tolerance=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        path: PathBuf,
        add: Option<&Bound<'_, PyAny>>,
        remove: Option<Vec<String>>,
        gamma: Option<f64>,
        metric: Option<&Bound<'_, PyAny>>,
        separation: SeparationArg,
        block: Option<usize>,
        sampler: Option<&str>,
        rate: Option<f64>,
        budget: Option<usize>,
        seed: Option<u64>,
        between_only: bool,
        skip_trivial: bool,
        format: Option<String>,
        axes: Option<(usize, usize)>,
        topic: Option<String>,
        time: Option<String>,
        frames: Option<(String, String)>,
        rate_hz: Option<f64>,
        drop_duplicate_stamps: bool,
        quaternion_tolerance: Option<f64>,
    ) -> PyResult<Self> {
        let args = ReadArgs {
            format,
            axes,
            topic,
            time,
            frames,
            rate_hz,
            drop_duplicate_stamps,
            quaternion_tolerance,
            ..ReadArgs::default()
        };
        let sessions = read_add(py, add, metric, &args)?;
        let exists = path.join("store.json").is_file();
        let config = update_config(
            &path,
            exists,
            None,
            gamma,
            metric,
            separation,
            block,
            sampler,
            rate,
            budget,
            seed,
            between_only,
            skip_trivial,
            &sessions,
        )?;
        let put: Vec<(String, loops_core::Trajectory)> =
            sessions.into_iter().map(|(name, t)| (name, Arc::unwrap_or_clone(t.inner))).collect();
        let remove = remove.unwrap_or_default();
        let inner = detached(py, move || Ok(plan_store_update(&path, config.as_ref(), &put, &remove)?))?;
        Ok(Self { inner })
    }

    /// The number of tiles to scan.
    fn __len__(&self) -> usize {
        self.inner.plan.tiles().len()
    }

    fn __repr__(&self) -> String {
        let report = self.inner.plan.report();
        format!(
            "StoreUpdatePlan({} tiles to scan, {} added, {} replaced, {} removed)",
            self.inner.plan.tiles().len(),
            report.added.len(),
            report.replaced.len(),
            report.removed.len()
        )
    }

    /// The names of the two sessions of each tile to scan (the same name twice for a tile of
    /// one session), in tile order.
    #[getter]
    fn tile_sessions(&self) -> Vec<(String, String)> {
        let plan = &self.inner.plan;
        let name = |s: usize| plan.sessions()[s].name.clone();
        plan.tiles().iter().map(|t| (name(t.sessions[0]), name(t.sessions[1]))).collect()
    }

    /// What the update will do, by name (``added``, ``replaced``, ``unchanged``, ``removed``),
    /// ``tiles_scanned``, and ``changed`` (False: the update writes nothing); the other counts
    /// are set when it is applied.
    #[getter]
    fn last_update<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        update_dict(py, self.inner.plan.report())
    }

    /// Scans the tiles ``tiles`` (indices, ``range(len(plan))``) of the plan: the sessions the
    /// update adds or replaces that they hold are read from ``add`` (the plan's, or only those
    /// sessions), the stored ones from the store's pose files; each is checked against the
    /// plan (its fingerprint) before the scan.
    ///
    /// Args:
    ///     tiles: indices of the plan's tiles.
    ///     add, metric, format, ...: as given to the plan.
    ///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
    ///
    /// Returns:
    ///     One ``bytes`` per tile, in the order of ``tiles``: what ``FleetStore.update(scanned=)``
    ///     takes.
    ///
    /// Raises:
    ///     InvalidParameterError: a tile out of range, a session to scan not in ``add``, or poses
    ///         that are not those planned.
    ///     OSError, LoopsIOError: a file that cannot be read.
    #[pyo3(signature = (tiles, *, add=None, metric=None, threads=None, format=None, axes=None, topic=None,
        time=None, frames=None, rate_hz=None, drop_duplicate_stamps=false, quaternion_tolerance=None))]
    #[allow(clippy::too_many_arguments)]
    fn scan<'py>(
        &self,
        py: Python<'py>,
        tiles: Vec<usize>,
        add: Option<&Bound<'py, PyAny>>,
        metric: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        format: Option<String>,
        axes: Option<(usize, usize)>,
        topic: Option<String>,
        time: Option<String>,
        frames: Option<(String, String)>,
        rate_hz: Option<f64>,
        drop_duplicate_stamps: bool,
        quaternion_tolerance: Option<f64>,
    ) -> PyResult<Vec<Bound<'py, pyo3::types::PyBytes>>> {
        let args = ReadArgs {
            format,
            axes,
            topic,
            time,
            frames,
            rate_hz,
            drop_duplicate_stamps,
            quaternion_tolerance,
            ..ReadArgs::default()
        };
        // Only the sessions given anew that the tiles hold are read.
        let plan = &self.inner.plan;
        let mut needed = std::collections::HashSet::new();
        for &k in &tiles {
            for s in plan.tiles().get(k).map_or([0; 2], |t| t.sessions) {
                if plan.tiles().get(k).is_some() && plan.is_new(s) {
                    needed.insert(plan.sessions()[s].name.clone());
                }
            }
        }
        let read = match add {
            None => Vec::new(),
            Some(add) => read_sessions_if(py, add, metric, &args, |name| needed.contains(name))?,
        };
        let put: Vec<(String, loops_core::Trajectory)> =
            read.into_iter().map(|(name, t)| (name, Arc::unwrap_or_clone(t.inner))).collect();
        let planned = &self.inner;
        let scanned = detached(py, move || {
            let scanned = loops_core::with_threads(threads, || scan_store_tiles(planned, &tiles, &put))??;
            Ok(scanned.iter().map(ScannedTile::to_bytes).collect::<Vec<_>>())
        })?;
        Ok(scanned.iter().map(|b| pyo3::types::PyBytes::new(py, b)).collect())
    }
}

crate::pickling::pickled!(StoreUpdatePlan, StorePlan, |value| Ok(StoreUpdatePlan { inner: value }));
