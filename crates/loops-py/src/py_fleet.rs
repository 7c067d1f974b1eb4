//! Fleets: `Fleet` (named sessions in one frame, each on its own clock), `find_fleet_loops` and
//! its `FleetLoops`, `sample_fleet` and its `FleetSamples`, and `urban_fleet`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyIndexError, PyKeyError, PyTypeError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{IntoPyDict, PyBool, PyBytes, PyDict, PyList, PyString, PyTuple, PyType};

use crate::convert::{
    bool_column, closest_position_columns, extent_columns, float64_column, int64_column, pose_index, str_column, table,
    to_numpy,
};
use crate::detached;
use crate::error::{Failure, invalid_parameter};
use crate::pickling::ReducedWith;
use crate::py_loops::Loops;
use crate::py_metric::loops_metric;
use crate::py_metric::{MetricArg, MetricRef};
use crate::py_samples::{Samples, baseline_params, sampler_of};
use crate::py_separation::{Separation, SeparationArg};
use crate::py_trajectory::{DriveOptions, ReadArgs, Trajectory, read_trajectory_with};
use loops_core::{
    MetricSpec, Sampler,
    fleet::{FleetOptions, Pruning},
};

/// Sessions — vehicles, days, robots — in one frame, each a :class:`Trajectory` with a name and
/// its own clock: the input of :func:`find_fleet_loops`.
///
/// The sessions keep the order given, which orders the blocks of the fleet's plane (rows of
/// session a, columns of session b, a ≤ b). All must have the same dimension and manifold.
///
/// Args:
///     sessions: a dict ``{name: session}``, a list of ``(name, session)`` pairs, or a list of
///         paths; a session is a :class:`Trajectory` or a path read by :func:`read_trajectory`
///         (in a dict or a pair, also a list of paths read as one trajectory). A path given
///         alone is named by its file stem (``logs/monday.tum``: ``"monday"``; a rosbag2 bag's
///         ``metadata.yaml``: its folder's name).
///     format, axes, metric, topic, time, frames, rate_hz, drop_duplicate_stamps,
///         quaternion_tolerance: how the paths are read, as in :func:`read_trajectory` (each
///         path with the same options). ``metric`` is then each session's metric
///         (:attr:`Trajectory.metric_name`).
///
/// Raises:
///     InvalidParameterError: no session; two sessions of the same name (for paths named by
///         their stem, the message names both paths); sessions of different dimensions or
///         manifolds (names the session); more poses in all than one trajectory may hold.
///     TypeError: ``sessions`` (or one of its items) of another type.
///     OSError, LoopsIOError, InvalidTrajectoryError: a path that cannot be read, as
///         :func:`read_trajectory` (the message names the file).
///
/// Warns:
///     DroppedInputWarning: as :func:`read_trajectory`, per file.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> monday = il.Trajectory([0.0, 1.0, 2.0], [[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
///     >>> tuesday = il.Trajectory([100.0, 101.0], [[10.0, 0.5], [0.0, 0.5]])
///     >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
///     >>> fleet.names, len(fleet), fleet.starts.tolist(), fleet.locate(3)
///     (['monday', 'tuesday'], 2, [0, 3], (1, 0))
///     >>> fleet.session("tuesday").timestamps.tolist()
///     [100.0, 101.0]
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Fleet {
    pub(crate) inner: Arc<loops_core::fleet::Fleet>,
    /// Per session, what its `Trajectory` carries beside the poses: the plane it was read on and
    /// the metric it was read for.
    plane_axes: Vec<Option<(usize, usize)>>,
    metrics: Vec<Option<MetricSpec>>,
}

/// A session of the `sessions` argument before it is read: a trajectory or what
/// `read_trajectory` takes.
enum SessionSource<'py> {
    Trajectory(Trajectory),
    Read(Bound<'py, PyAny>),
}

/// The name a path gives its session ([`loops_io::log_name`], the rule of every surface), or
/// none for a path that names no file.
fn stem_name(path: &Path) -> Option<String> {
    path.file_name()?;
    Some(loops_io::log_name(path)).filter(|name| !name.is_empty())
}

/// The `(name, source)` pairs of `sessions`.
fn session_sources<'py>(sessions: &Bound<'py, PyAny>) -> PyResult<Vec<(String, SessionSource<'py>)>> {
    let source = |value: Bound<'py, PyAny>| -> SessionSource<'py> {
        match value.cast::<Trajectory>() {
            Ok(traj) => SessionSource::Trajectory(traj.get().clone()),
            Err(_) => SessionSource::Read(value),
        }
    };
    if let Ok(dict) = sessions.cast::<PyDict>() {
        let mut out = Vec::with_capacity(dict.len());
        for (key, value) in dict.iter() {
            let Ok(name) = key.extract::<String>() else {
                return Err(PyTypeError::new_err(format!(
                    "session names must be str, got {} ({key:?})",
                    key.get_type().name()?
                )));
            };
            out.push((name, source(value)));
        }
        return Ok(out);
    }
    if !(sessions.is_instance_of::<PyList>() || sessions.is_instance_of::<PyTuple>()) {
        return Err(PyTypeError::new_err(format!(
            "sessions must be a dict {{name: Trajectory or path}}, a list of (name, Trajectory or path) pairs or a \
             list of paths, got {}",
            sessions.get_type().name()?
        )));
    }
    let mut out: Vec<(String, SessionSource<'py>)> = Vec::new();
    // Paths named by their stems, to name both paths when two stems are the same.
    let mut by_stem: Vec<(String, usize, PathBuf)> = Vec::new();
    for (index, item) in sessions.try_iter()?.enumerate() {
        let item = item?;
        if let Ok(pair) = item.cast::<PyTuple>()
            && pair.len() == 2
        {
            let name = pair.get_item(0)?;
            let Ok(name) = name.extract::<String>() else {
                return Err(PyTypeError::new_err(format!(
                    "sessions[{index}] must be a (name, Trajectory or path) pair with a str name, got a {} name",
                    name.get_type().name()?
                )));
            };
            out.push((name, source(pair.get_item(1)?)));
            continue;
        }
        if !item.is_instance_of::<PyTuple>()
            && let Ok(path) = item.extract::<PathBuf>()
        {
            let Some(name) = stem_name(&path) else {
                return Err(invalid_parameter(format!(
                    "sessions[{index}] = {:?} has no file name to name its session: pass {{name: path}}",
                    path.display().to_string()
                )));
            };
            if let Some((_, first, other)) = by_stem.iter().find(|(n, _, _)| *n == name) {
                return Err(invalid_parameter(format!(
                    "sessions[{first}] ({}) and sessions[{index}] ({}) are both named {name:?} by their file \
                     stem: pass {{name: path}} to name them",
                    other.display(),
                    path.display()
                )));
            }
            by_stem.push((name.clone(), index, path));
            out.push((name, source(item)));
            continue;
        }
        let what = if item.cast::<Trajectory>().is_ok() {
            "a Trajectory without a name: pass (name, trajectory) or {name: trajectory}".to_owned()
        } else {
            format!("a {}", item.get_type().name()?)
        };
        return Err(PyTypeError::new_err(format!(
            "sessions[{index}] must be a (name, Trajectory or path) pair or a path, got {what}"
        )));
    }
    Ok(out)
}

/// The sessions of `sessions` (what :class:`Fleet` takes), each read with the options given
/// where it is a path: `Fleet`'s rule, for every surface that takes sessions.
pub(crate) fn read_sessions(
    py: Python<'_>,
    sessions: &Bound<'_, PyAny>,
    metric: Option<&Bound<'_, PyAny>>,
    read: &ReadArgs,
) -> PyResult<Vec<(String, Trajectory)>> {
    read_sessions_if(py, sessions, metric, read, |_| true)
}

/// [`read_sessions`] of the sessions whose names `wanted` accepts; the others are not read.
pub(crate) fn read_sessions_if(
    py: Python<'_>,
    sessions: &Bound<'_, PyAny>,
    metric: Option<&Bound<'_, PyAny>>,
    read: &ReadArgs,
    wanted: impl Fn(&str) -> bool,
) -> PyResult<Vec<(String, Trajectory)>> {
    session_sources(sessions)?
        .into_iter()
        .filter(|(name, _)| wanted(name))
        .map(|(name, source)| {
            let traj = match source {
                SessionSource::Trajectory(traj) => traj,
                SessionSource::Read(path) => read_trajectory_with(py, &path, metric, read.clone())?,
            };
            Ok((name, traj))
        })
        .collect()
}

/// The index of the session `key` names among `names`: its name, or its index.
///
/// # Errors
/// `KeyError` for an unknown name, `IndexError` for an index out of range, `TypeError` for
/// anything else.
pub(crate) fn session_index_of(names: &[String], key: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(name) = key.cast::<PyString>() {
        let name = name.to_str()?;
        return names.iter().position(|n| n == name).ok_or_else(|| {
            let shown: Vec<&str> = names.iter().take(10).map(String::as_str).collect();
            let more = if names.len() > 10 { format!(", ... ({} in all)", names.len()) } else { String::new() };
            PyKeyError::new_err(format!("no session is named {name:?}; the sessions are {shown:?}{more}"))
        });
    }
    if !key.is_instance_of::<PyBool>()
        && let Ok(index) = key.extract::<i64>()
    {
        return usize::try_from(index).ok().filter(|&a| a < names.len()).ok_or_else(|| {
            PyIndexError::new_err(format!("session {index} out of range: the fleet has {} sessions", names.len()))
        });
    }
    Err(PyTypeError::new_err(format!(
        "a session is named by its name (str) or its index (int), got {}",
        key.get_type().name()?
    )))
}

/// The one metric that sessions `(name, metric)` are measured by when no `metric=` is given.
///
/// # Errors
/// `InvalidParameterError` when two sessions are measured by different metrics.
pub(crate) fn common_metric<'a>(
    mut sessions: impl Iterator<Item = (&'a str, MetricSpec)>,
) -> PyResult<Option<MetricSpec>> {
    let Some((first_name, first)) = sessions.next() else { return Ok(None) };
    for (name, metric) in sessions {
        if metric != first {
            return Err(invalid_parameter(format!(
                "session {name:?} is measured by {} but session {first_name:?} by {}: pass metric=",
                metric.name(),
                first.name()
            )));
        }
    }
    Ok(Some(first))
}

impl Fleet {
    /// The session `key` names: its name, or its index.
    ///
    /// # Errors
    /// `KeyError` for an unknown name, `IndexError` for an index out of range, `TypeError`
    /// for anything else.
    pub(crate) fn session_index(&self, key: &Bound<'_, PyAny>) -> PyResult<usize> {
        session_index_of(self.inner.names(), key)
    }

    /// Whether two fleets hold the same sessions, read on the same planes for the same metrics.
    pub(crate) fn same(&self, other: &Self) -> bool {
        (Arc::ptr_eq(&self.inner, &other.inner) || self.inner == other.inner)
            && self.plane_axes == other.plane_axes
            && self.metrics == other.metrics
    }

    /// The `Trajectory` of session `a`, with the plane and metric it came with.
    fn session_trajectory(&self, a: usize) -> Trajectory {
        Trajectory {
            inner: Arc::new(self.inner.session(a).clone()),
            plane_axes: self.plane_axes[a],
            metric: self.metrics[a],
        }
    }

    /// The metric every session is measured by when no `metric=` is given.
    ///
    /// # Errors
    /// `InvalidParameterError` when two sessions are measured by different metrics.
    fn default_metric(&self) -> PyResult<MetricSpec> {
        let names = self.inner.names();
        let metric = |a: usize| self.metrics[a].unwrap_or_else(|| self.inner.session(a).default_metric());
        let metric = common_metric((0..self.inner.len()).map(|a| (names[a].as_str(), metric(a))))?;
        Ok(metric.expect("a fleet has a session"))
    }
}

#[pymethods]
impl Fleet {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get();
        let fleet = &this.inner;
        let sessions: Vec<(&str, &loops_core::Trajectory)> =
            fleet.names().iter().enumerate().map(|(a, name)| (name.as_str(), fleet.session(a))).collect();
        let metrics: Vec<Option<String>> = this.metrics.iter().map(|m| m.map(|m| m.to_string())).collect();
        crate::pickling::reduce(slf.as_any(), "Fleet", &(sessions, &this.plane_axes, metrics))
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "Fleet", || {
            let py = cls.py();
            type State = (Vec<(String, loops_core::Trajectory)>, Vec<Option<(usize, usize)>>, Vec<Option<String>>);
            let (sessions, plane_axes, metrics): State = crate::pickling::restore(py, "Fleet", state)?;
            let invalid = |reason: String| crate::pickling::invalid(py, "Fleet", reason);
            if plane_axes.len() != sessions.len() || metrics.len() != sessions.len() {
                return Err(invalid(format!(
                    "{} sessions but {} planes and {} metrics",
                    sessions.len(),
                    plane_axes.len(),
                    metrics.len()
                )));
            }
            let mut specs = Vec::with_capacity(metrics.len());
            for ((name, traj), metric) in sessions.iter().zip(metrics) {
                let Some(text) = metric else {
                    specs.push(None);
                    continue;
                };
                let spec: MetricSpec =
                    text.parse().map_err(|e: loops_core::Error| invalid(format!("session {name:?}: {e}")))?;
                spec.validate(traj).map_err(|e| invalid(format!("session {name:?}: {e}")))?;
                specs.push(Some(spec));
            }
            let inner =
                py.detach(move || loops_core::fleet::Fleet::new(sessions)).map_err(|e| invalid(e.to_string()))?;
            Ok(Self { inner: Arc::new(inner), plane_axes, metrics: specs })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        self.same(&other)
    }

    fn __hash__(&self) -> u64 {
        let first = self.inner.joint().timestamps_s()[0];
        crate::pickling::hash_of(&[self.inner.len() as u64, self.inner.poses() as u64, first.to_bits()])
    }

    #[new]
    #[pyo3(signature = (sessions, *, format=None, axes=None, metric=None, topic=None, time=None, frames=None,
        rate_hz=None, drop_duplicate_stamps=false, quaternion_tolerance=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        sessions: &Bound<'_, PyAny>,
        format: Option<String>,
        axes: Option<(usize, usize)>,
        metric: Option<&Bound<'_, PyAny>>,
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
        let read = read_sessions(py, sessions, metric, &args)?;
        let mut named = Vec::with_capacity(read.len());
        let (mut plane_axes, mut metrics) = (Vec::new(), Vec::new());
        for (name, traj) in read {
            plane_axes.push(traj.plane_axes);
            metrics.push(traj.metric);
            named.push((name, traj.inner));
        }
        let inner = detached(py, move || {
            // A trajectory no one else holds (one just read) moves into the fleet uncopied.
            let sessions = named.into_iter().map(|(name, traj)| (name, Arc::unwrap_or_clone(traj))).collect::<Vec<_>>();
            Ok(loops_core::fleet::Fleet::new(sessions)?)
        })?;
        Ok(Self { inner: Arc::new(inner), plane_axes, metrics })
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        let names = self.inner.names();
        let shown = names.iter().take(4).map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
        let more = if names.len() > 4 { ", ..." } else { "" };
        format!("Fleet({} sessions [{shown}{more}], {} poses)", names.len(), self.inner.poses())
    }

    /// The sessions' names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.inner.names().to_vec()
    }

    /// Number of poses in all sessions.
    #[getter]
    fn poses(&self) -> usize {
        self.inner.poses()
    }

    /// The first *fleet index* of each session, int64, shape ``(len(fleet),)``: the sessions'
    /// poses numbered one session after another, as :attr:`FleetLoops.loops` and
    /// :attr:`FleetSamples.samples` index them.
    #[getter]
    fn starts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.starts().iter().map(|&s| s as i64).collect())
    }

    /// Fleet clock minus session clock, seconds, per session (float64): the *fleet clock* runs
    /// the sessions one after another, each starting an hour after the previous one ends, as
    /// :attr:`joint` and :attr:`FleetLoops.loops` time them.
    #[getter]
    fn clock_offsets<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.clock_offsets().to_vec())
    }

    /// The sessions one after another as one :class:`Trajectory` on the fleet clock (each
    /// session keeps its own time cells): the trajectory of :attr:`FleetLoops.loops` (a copy).
    #[getter]
    fn joint(&self) -> Trajectory {
        let metric = self.default_metric().ok().filter(|m| *m != self.inner.joint().default_metric());
        Trajectory { inner: Arc::new(self.inner.joint().clone()), plane_axes: self.plane_axes[0], metric }
    }

    /// A session's :class:`Trajectory`, on its own clock (a copy).
    ///
    /// Args:
    ///     session: its name or its index.
    ///
    /// Raises:
    ///     KeyError: no session of that name. IndexError: an index out of range.
    fn session(&self, session: &Bound<'_, PyAny>) -> PyResult<Trajectory> {
        Ok(self.session_trajectory(self.session_index(session)?))
    }

    /// The ``(session, pose)`` indices of a fleet index.
    ///
    /// Raises:
    ///     IndexError: a negative index or one past the last pose.
    fn locate(&self, index: i64) -> PyResult<(usize, usize)> {
        let index = pose_index(index, "index")?;
        Ok(self.inner.locate(index).map_err(Failure::from)?)
    }

    /// The fleet index of pose ``pose`` of ``session`` (its name or index).
    ///
    /// Raises:
    ///     KeyError: no session of that name. IndexError: a session or pose out of range.
    fn index(&self, session: &Bound<'_, PyAny>, pose: i64) -> PyResult<usize> {
        let a = self.session_index(session)?;
        let pose = pose_index(pose, "pose")?;
        Ok(self.inner.index(a, pose).map_err(Failure::from)?)
    }
}

/// What `pruning=` was given.
fn parse_pruning(pruning: &str) -> PyResult<Pruning> {
    Ok(pruning.parse().map_err(Failure::from)?)
}

/// Finds every inexact loop of a fleet at threshold ``gamma`` exactly: for every pair of
/// sessions (a, b), a ≤ b, the pairs (t_a, t′_b) within γ — a *block* of the fleet's plane —
/// grouped into loop components, 4-connected on each block's own lattice, never across
/// sessions. A block (a, a) is session a alone (with the revisit separation, component for
/// component :func:`find_loops` of that session); a block (a, b), a < b, has no diagonal and
/// no separation, and each of its components is one place where the two sessions overlap.
///
/// The same engine as :func:`find_loops`, on the sessions laid one after another; with
/// Euclidean positions of 1 to 3 coordinates the far field is pruned by a KD-tree over chunks of
/// the paths, so that session pairs that never come within γ cost no distance evaluation.
///
/// Args:
///     fleet: a :class:`Fleet`.
///     gamma: the distance threshold γ > 0, in the metric's unit.
///     metric: as in :func:`find_loops`; ``None`` takes the sessions' own
///         (:attr:`Trajectory.metric_name`; they must agree).
///     separation: within each session, as in :func:`find_loops` (``"auto"``: 4 γ of path;
///         ``None``: the paper's S_γ). Pairs of different sessions are always kept.
///     pruning: ``"auto"`` (the KD-tree where it applies, else the hierarchy), ``"hierarchy"``
///         (the time-ordered ball hierarchy, any metric) or ``"kd-tree"`` (Euclidean positions
///         of 1 to 3 coordinates). The result does not depend on it.
///     chunk_radius: the largest radius of a chunk of path in the KD-tree, in the metric's
///         unit; ``None``: γ. The result does not depend on it.
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///
/// Returns:
///     :class:`FleetLoops`.
///
/// Raises:
///     InvalidParameterError: as :func:`find_loops`; an unknown pruning; ``"kd-tree"`` with a
///         metric it does not serve; sessions measured by different metrics and no ``metric=``.
///
/// Warns:
///     DiagonalBrokenWarning, NoLoopsWarning: as :func:`find_loops`, for the fleet's sessions.
///
/// Example:
///     Monday drives out along a street; Tuesday drives back along it, half a metre aside: one
///     place where the two sessions overlap.
///
///     >>> import numpy as np, inexact_loops as il
///     >>> x = np.arange(21) * 0.5
///     >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
///     >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
///     >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
///     >>> loops = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
///     >>> c = loops.components
///     >>> between = c["session_a"] != c["session_b"]
///     >>> c["name_a"][between].tolist(), c["name_b"][between].tolist(), c["pair_count"][between].tolist()
///     (['monday'], ['tuesday'], [61])
///     >>> loops.overlap_matrix()
///     array([[93.5, 57.5],
///            [57.5, 93.5]])
#[pyfunction]
#[pyo3(signature = (fleet, *, gamma, metric=None, separation=SeparationArg::Auto, pruning="auto", chunk_radius=None,
    threads=None))]
#[pyo3(
    text_signature = "(fleet, *, gamma, metric=None, separation='auto', pruning='auto', chunk_radius=None, threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn find_fleet_loops(
    py: Python<'_>,
    fleet: Bound<'_, Fleet>,
    gamma: f64,
    metric: Option<&Bound<'_, PyAny>>,
    separation: SeparationArg,
    pruning: &str,
    chunk_radius: Option<f64>,
    threads: Option<usize>,
) -> PyResult<FleetLoops> {
    let options = FleetOptions { separation: separation.at(gamma), pruning: parse_pruning(pruning)?, chunk_radius };
    let metric = match metric {
        None => MetricArg::Spec(fleet.get().default_metric()?),
        Some(_) => MetricArg::from_py(metric)?,
    };
    let inner_fleet = Arc::clone(&fleet.get().inner);
    let inner = metric.run(py, threads, move |metric| match metric {
        MetricRef::Spec(spec) => spec.find_fleet_loops(&inner_fleet, gamma, &options),
        MetricRef::Callable(callable) => loops_core::fleet::find_fleet_loops(&inner_fleet, callable, gamma, &options),
    })?;
    crate::warning::warn_loops(py, inner.loops())?;
    Ok(FleetLoops { inner: Arc::new(inner), fleet: fleet.unbind(), loops: PyOnceLock::new() })
}

/// The loops of a fleet at one γ: every block's loop components, the sessions' overlap (α per
/// session pair) and the loop duration split into own and other sessions. Returned by
/// :func:`find_fleet_loops`.
///
/// Times in its tables are on each session's own clock; :attr:`loops` is the result over the
/// joint trajectory (:attr:`Fleet.joint`: fleet indices, fleet clock), for everything
/// :class:`Loops` does.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct FleetLoops {
    pub(crate) inner: Arc<loops_core::fleet::FleetLoops>,
    pub(crate) fleet: Py<Fleet>,
    /// The joint result as a `Loops`, copied on first use.
    loops: PyOnceLock<Py<Loops>>,
}

impl FleetLoops {
    fn fleet_ref(&self) -> &Fleet {
        self.fleet.get()
    }
}

#[pymethods]
impl FleetLoops {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<ReducedWith<'py, Fleet>> {
        let this = slf.get();
        let value = (this.inner.loops(), this.inner.pruning().name());
        crate::pickling::reduce_with(slf.as_any(), "FleetLoops", &value, this.fleet.clone_ref(slf.py()))
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8], fleet: &Bound<'_, PyAny>) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "FleetLoops", || {
            let py = cls.py();
            let fleet = crate::pickling::companion::<Fleet>(fleet, "FleetLoops", "fleet")?;
            let (loops, pruning): (loops_core::Loops, String) = crate::pickling::restore(py, "FleetLoops", state)?;
            let invalid = |e: loops_core::Error| crate::pickling::invalid(py, "FleetLoops", e);
            let pruning = pruning.parse().map_err(invalid)?;
            let inner_fleet = Arc::clone(&fleet.get().inner);
            let inner = py
                .detach(move || loops_core::fleet::FleetLoops::from_loops(&inner_fleet, loops, pruning))
                .map_err(invalid)?;
            Ok(Self { inner: Arc::new(inner), fleet: fleet.clone().unbind(), loops: PyOnceLock::new() })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        self.inner == other.inner && self.fleet_ref().same(other.fleet_ref())
    }

    fn __hash__(&self) -> u64 {
        let loops = self.inner.loops();
        crate::pickling::hash_of(&[
            loops.len() as u64,
            loops.gamma().to_bits(),
            loops.sublevel_set().runs().len() as u64,
            self.inner.sessions() as u64,
        ])
    }

    fn __repr__(&self) -> String {
        let between = self.inner.between_sessions().len();
        format!(
            "FleetLoops(gamma={}, metric={}, separation={}, {} sessions, {} components ({} between sessions), \
             pruning={})",
            self.inner.loops().gamma(),
            self.inner.loops().metric_name(),
            self.inner.loops().separation(),
            self.inner.sessions(),
            self.inner.component_sessions().len(),
            between,
            self.inner.pruning().name()
        )
    }

    /// The :class:`Fleet` the loops were found on.
    #[getter]
    fn fleet(&self, py: Python<'_>) -> Py<Fleet> {
        self.fleet.clone_ref(py)
    }

    /// The sessions' names, in order (as :attr:`Fleet.names`).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.fleet_ref().inner.names().to_vec()
    }

    /// The threshold γ.
    #[getter]
    fn gamma(&self) -> f64 {
        self.inner.loops().gamma()
    }

    /// The separation the pairs within a session keep (:class:`Separation`).
    #[getter]
    fn separation(&self) -> Separation {
        Separation { inner: self.inner.loops().separation() }
    }

    /// The name of the metric the loops were found with (as :attr:`Loops.metric_name`).
    #[getter]
    fn metric_name(&self) -> String {
        self.inner.loops().metric_name().to_owned()
    }

    /// The far-field pruning the scan used: ``"hierarchy"`` or ``"kd-tree"`` (``"auto"``
    /// resolved).
    #[getter]
    fn pruning(&self) -> &'static str {
        self.inner.pruning().name()
    }

    /// Warnings about the result, as sentences (as :attr:`Loops.warnings`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.loops().warnings().iter().map(ToString::to_string).collect()
    }

    /// The result over the joint trajectory (:attr:`Fleet.joint`) as :class:`Loops`: fleet
    /// indices (:attr:`Fleet.starts`), fleet clock; component ids are those of
    /// :attr:`components`. Made on first use (a copy of the runs), then kept.
    #[getter]
    fn loops(&self, py: Python<'_>) -> PyResult<Py<Loops>> {
        let loops = self.loops.get_or_try_init(py, || {
            Py::new(py, Loops { inner: Arc::new(self.inner.loops().clone()), closest: None })
        })?;
        Ok(loops.clone_ref(py))
    }

    /// The loop components of every block as a :class:`~inexact_loops.Table`, one row a
    /// component, by id (the ids of :attr:`loops`): ``id`` (int64); ``session_a``,
    /// ``session_b`` (int64, a ≤ b) and ``name_a``, ``name_b`` (str): the block, rows in session
    /// a, columns in session b; ``trivial`` (bool, a = b only); ``area_s2`` (float64, s², each
    /// session's own time cells: within a session, the half t ≤ t′ of a non-trivial
    /// component, as :attr:`Loops.components`); ``pair_count``, ``holes`` (int64); ``i_min``,
    /// ``i_max`` (poses of session a), ``j_min``, ``j_max`` (poses of session b), int64;
    /// ``t_min_s``, ``t_max_s``, ``t_prime_min_s``, ``t_prime_max_s`` (float64, seconds, each
    /// on its session's clock); ``closest_i``, ``closest_j`` (int64, poses of sessions a and
    /// b) and ``closest_distance`` (float64, the metric's unit); ``closest_i_x``,
    /// ``closest_i_y``, ``closest_i_z``, ``closest_j_x``, ``closest_j_y``, ``closest_j_z``
    /// (float64: where pose ``closest_i`` of session a and pose ``closest_j`` of session b are,
    /// their points' first three coordinates, 0 past a point's dimension).
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let fleet = &self.fleet_ref().inner;
        let cs = self.inner.components();
        let time = |a: usize, pose: usize| fleet.session(a).timestamps_s()[pose];
        let times: Vec<[[f64; 2]; 2]> = cs
            .iter()
            .map(|c| {
                let [a, b] = c.sessions;
                [[time(a, c.poses[0][0]), time(a, c.poses[0][1])], [time(b, c.poses[1][0]), time(b, c.poses[1][1])]]
            })
            .collect();
        let closest: Vec<_> = cs.iter().map(|c| loops_io::fleet_closest_positions_in(c, fleet)).collect();
        components_table(py, &cs, fleet.names(), &times, &closest)
    }

    /// The ids of the components between two different sessions, int64, increasing.
    fn between_sessions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.between_sessions().into_iter().map(|c| c as i64).collect())
    }

    /// The sparse overlap matrix as a :class:`~inexact_loops.Table`, one row per session pair
    /// (a, b), a ≤ b, with at least one loop component, in order of (a, b): ``session_a``,
    /// ``session_b`` (int64), ``name_a``, ``name_b`` (str), ``components`` (int64, in the
    /// block), ``pair_count`` (int64, lattice cells), ``area_s2`` (float64: the loop area α of
    /// the block, s²) and ``density`` (float64: ρ = α / (T_a T_b), T the sessions' spans: the
    /// share of the block within γ). For a = b the block is the session's whole square (both
    /// halves, the diagonal once), so ``area_s2`` is ∫τ over the session alone.
    fn session_pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        session_pairs_table(py, &self.inner.session_pairs(), self.fleet_ref().inner.names())
    }

    /// The overlap matrix: α between every two sessions, s², symmetric, rows and columns in
    /// the order of :attr:`names`; the diagonal is each session's α alone (``area_s2`` of
    /// :meth:`session_pairs`), 0 where two sessions never come within γ.
    ///
    /// Args:
    ///     sparse: return a ``scipy.sparse.csr_array`` holding only the pairs that overlap
    ///         (both triangles) instead of a dense numpy array: for large fleets, where the
    ///         dense matrix takes 8 bytes per session pair.
    ///
    /// Returns:
    ///     float64 array of shape ``(len(fleet), len(fleet))``, or a ``scipy.sparse.csr_array``.
    ///
    /// Raises:
    ///     ImportError: ``sparse=True`` without scipy.
    #[pyo3(signature = (*, sparse=false))]
    fn overlap_matrix<'py>(&self, py: Python<'py>, sparse: bool) -> PyResult<Bound<'py, PyAny>> {
        overlap_matrix(py, self.inner.sessions(), &self.inner.session_pairs(), sparse)
    }

    /// Loop duration τ per pose, split: ``own_s``, τ within the pose's session (that session's
    /// :meth:`Loops.loop_duration` alone), and ``other_s``, τ with the poses of every other
    /// session; seconds. A :class:`~inexact_loops.Table` of one row per pose, sessions in
    /// order: ``session`` (int64), ``pose`` (int64, in its session), ``t_s`` (float64, the
    /// session's clock), ``own_s`` and ``other_s`` (float64). Per session: ∫ own_s dt is the
    /// session's α alone; summed over the fleet, ∫ other_s dt is twice the α of all blocks
    /// between sessions (each block counts for the poses of both).
    ///
    /// Args:
    ///     session: only this session's poses (its name or index); ``None``: every pose.
    ///
    /// Raises:
    ///     KeyError: no session of that name. IndexError: an index out of range.
    #[pyo3(signature = (session=None))]
    fn loop_duration<'py>(&self, py: Python<'py>, session: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyAny>> {
        let fleet = self.fleet_ref();
        let sessions = match session {
            Some(key) => {
                let a = fleet.session_index(key)?;
                a..a + 1
            }
            None => 0..fleet.inner.len(),
        };
        let inner = Arc::clone(&self.inner);
        let (own, other) = detached(py, move || Ok(inner.loop_duration()))?;
        let f = &fleet.inner;
        let end = f.starts()[sessions.end - 1] + f.session(sessions.end - 1).len();
        let span = f.starts()[sessions.start]..end;
        let sessions: Vec<(usize, &[f64])> = sessions.map(|a| (a, f.session(a).timestamps_s())).collect();
        loop_duration_table(py, &sessions, &own[span.clone()], &other[span])
    }
}

/// The table of :meth:`FleetLoops.loop_duration` (see there) of `sessions` (index, times of
/// its poses) in order, with τ `own` and `other` of their poses.
pub(crate) fn loop_duration_table<'py>(
    py: Python<'py>,
    sessions: &[(usize, &[f64])],
    own: &[f64],
    other: &[f64],
) -> PyResult<Bound<'py, PyAny>> {
    let session_of: Vec<i64> = sessions.iter().flat_map(|&(a, t)| std::iter::repeat_n(a as i64, t.len())).collect();
    let pose: Vec<i64> = sessions.iter().flat_map(|(_, t)| 0..t.len() as i64).collect();
    let t_s: Vec<f64> = sessions.iter().flat_map(|(_, t)| t.iter().copied()).collect();
    table(
        py,
        [
            ("session", to_numpy(py, session_of).into_any()),
            ("pose", to_numpy(py, pose).into_any()),
            ("t_s", to_numpy(py, t_s).into_any()),
            ("own_s", to_numpy(py, own.to_vec()).into_any()),
            ("other_s", to_numpy(py, other.to_vec()).into_any()),
        ],
    )
}

/// The table of :attr:`FleetLoops.components` (see there) of fleet components with the times
/// of their extents on their sessions' clocks (`[[t_min, t_max], [t′_min, t′_max]]`) and the
/// positions of their closest pairs (`closest`, one per component; NaN for all when empty).
pub(crate) fn components_table<'py>(
    py: Python<'py>,
    cs: &[loops_core::fleet::FleetComponent],
    names: &[String],
    times: &[[[f64; 2]; 2]],
    closest: &[loops_io::ClosestPositions],
) -> PyResult<Bound<'py, PyAny>> {
    // The columns of a fleet's components.csv, in its order, less the joint component's
    // pose_pair_count and run_count (a store's or a tile merge's components do not keep them).
    let [id, session_a, session_b, name_a, name_b] = loops_io::FLEET_COMPONENT_COLUMNS[..5] else {
        unreachable!("the block's columns")
    };
    let [trivial, area_s2, pair_count, _pose_pair_count, _run_count, holes] = loops_io::MEASURE_COLUMNS;
    let extents: Vec<_> = cs
        .iter()
        .zip(times)
        .map(|(c, &times)| loops_io::ComponentExtent::from_times(c.poses, c.closest_pair, c.closest_distance, times))
        .collect();
    let columns = [
        (id, int64_column(py, cs, |c| c.id)),
        (session_a, int64_column(py, cs, |c| c.sessions[0])),
        (session_b, int64_column(py, cs, |c| c.sessions[1])),
        (name_a, str_column(py, cs.iter().map(|c| names[c.sessions[0]].as_str()))?),
        (name_b, str_column(py, cs.iter().map(|c| names[c.sessions[1]].as_str()))?),
        (trivial, bool_column(py, cs, |c| c.trivial)),
        (area_s2, float64_column(py, cs, |c| c.area_s2)),
        (pair_count, int64_column(py, cs, |c| c.pair_count as usize)),
        (holes, int64_column(py, cs, |c| c.holes as usize)),
    ];
    let unknown = vec![loops_io::ClosestPositions::default(); if closest.is_empty() { cs.len() } else { 0 }];
    let closest = if closest.is_empty() { &unknown } else { closest };
    table(py, columns.into_iter().chain(extent_columns(py, &extents)).chain(closest_position_columns(py, closest)))
}

/// The table of :meth:`FleetLoops.session_pairs` (see there).
pub(crate) fn session_pairs_table<'py>(
    py: Python<'py>,
    ps: &[loops_core::fleet::SessionPair],
    names: &[String],
) -> PyResult<Bound<'py, PyAny>> {
    let rows: Vec<_> = ps.iter().map(|pair| loops_io::SessionPairRow::new(pair, names)).collect();
    let [session_a, session_b, name_a, name_b, components, pair_count, area_s2, density] =
        loops_io::SESSION_PAIR_COLUMNS;
    table(
        py,
        [
            (session_a, int64_column(py, &rows, |r| r.session_a)),
            (session_b, int64_column(py, &rows, |r| r.session_b)),
            (name_a, str_column(py, rows.iter().map(|r| names[r.session_a].as_str()))?),
            (name_b, str_column(py, rows.iter().map(|r| names[r.session_b].as_str()))?),
            (components, int64_column(py, &rows, |r| r.components)),
            (pair_count, int64_column(py, &rows, |r| r.pair_count as usize)),
            (area_s2, float64_column(py, &rows, |r| r.area_s2)),
            (density, float64_column(py, &rows, |r| r.density)),
        ],
    )
}

/// The matrix of :meth:`FleetLoops.overlap_matrix` (see there) of `n` sessions.
pub(crate) fn overlap_matrix<'py>(
    py: Python<'py>,
    n: usize,
    pairs: &[loops_core::fleet::SessionPair],
    sparse: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if sparse {
        let scipy = py.import("scipy.sparse").map_err(|error| {
            pyo3::exceptions::PyImportError::new_err(format!(
                "overlap_matrix(sparse=True) needs scipy, which is not installed ({error}): `pip install scipy`, \
                     or use the dense matrix"
            ))
        })?;
        let (mut rows, mut cols, mut values) = (Vec::new(), Vec::new(), Vec::new());
        for p in pairs {
            let [a, b] = p.sessions;
            rows.push(a as i64);
            cols.push(b as i64);
            values.push(p.area_s2);
            if a != b {
                rows.push(b as i64);
                cols.push(a as i64);
                values.push(p.area_s2);
            }
        }
        let coordinates = (to_numpy(py, rows), to_numpy(py, cols));
        let kwargs = [("shape", (n, n))].into_py_dict(py)?;
        return scipy.call_method("csr_array", ((to_numpy(py, values), coordinates),), Some(&kwargs));
    }
    let mut dense = vec![0.0; n * n];
    for p in pairs {
        let [a, b] = p.sessions;
        dense[a * n + b] = p.area_s2;
        dense[b * n + a] = p.area_s2;
    }
    let matrix: Bound<'py, PyArray2<f64>> = to_numpy(py, dense).reshape([n, n])?;
    Ok(matrix.into_any())
}

/// Samples the loops of a fleet (paper, Sec. 5) with one budget over all components of all
/// blocks, as :func:`sample` samples the components of one trajectory: P1–P3 hold across the
/// fleet. With ``between_only``, only the components between different sessions are sampled:
/// the pairs that tie sessions together (map merging, multi-session SLAM).
///
/// Args:
///     loops: :class:`FleetLoops` (from :func:`find_fleet_loops`).
///     sampler, rate, budget, seed, metric, threads, skip_trivial: as in :func:`sample` (a
///         baseline rule runs over the joint trajectory, :attr:`Fleet.joint`).
///     between_only: sample only the components between two different sessions (not with a
///         baseline, whose rule knows no components).
///     lio_sam_keyframe_step, lio_sam_period_s, lio_sam_min_age_s, hdl_keyframe_step,
///         hdl_min_travel, hdl_edge_spacing, cartographer_min_gap_s, time_gap_s: as in
///         :func:`sample`.
///
/// Returns:
///     :class:`FleetSamples`.
///
/// Raises:
///     InvalidParameterError: as :func:`sample`; ``between_only`` with a baseline.
///
/// Warns:
///     EmptySampleWarning, SampleBudgetWarning: as :func:`sample`.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> fleet = il.urban_fleet(vehicles=3, duration_s=300.0, seed=1)
///     >>> loops = il.find_fleet_loops(fleet, gamma=20.0)
///     >>> samples = il.sample_fleet(loops, "one", budget=50, seed=0, between_only=True)
///     >>> rows = samples.table
///     >>> bool((rows["session_a"] != rows["session_b"]).all()), len(samples)
///     (True, 50)
#[pyfunction]
#[pyo3(signature = (loops, sampler=None, *, rate=None, budget=None, seed, between_only=false, metric=None, threads=None,
    skip_trivial=false, lio_sam_keyframe_step=None, lio_sam_period_s=None, lio_sam_min_age_s=None, hdl_keyframe_step=None,
    hdl_min_travel=None, hdl_edge_spacing=None, cartographer_min_gap_s=None, time_gap_s=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_fleet(
    py: Python<'_>,
    loops: &FleetLoops,
    sampler: Option<&str>,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: u64,
    between_only: bool,
    metric: Option<&Bound<'_, PyAny>>,
    threads: Option<usize>,
    skip_trivial: bool,
    lio_sam_keyframe_step: Option<f64>,
    lio_sam_period_s: Option<f64>,
    lio_sam_min_age_s: Option<f64>,
    hdl_keyframe_step: Option<f64>,
    hdl_min_travel: Option<f64>,
    hdl_edge_spacing: Option<f64>,
    cartographer_min_gap_s: Option<f64>,
    time_gap_s: Option<f64>,
) -> PyResult<FleetSamples> {
    let baseline = baseline_params(
        lio_sam_keyframe_step,
        lio_sam_period_s,
        lio_sam_min_age_s,
        hdl_keyframe_step,
        hdl_min_travel,
        hdl_edge_spacing,
        cartographer_min_gap_s,
        time_gap_s,
    );
    let spec = Sampler { baseline, ..sampler_of(sampler, rate, budget, seed, skip_trivial)? };
    let metric = loops_metric(metric, loops.inner.loops())?;
    let fleet = Arc::clone(&loops.fleet_ref().inner);
    let inner = Arc::clone(&loops.inner);
    let (samples, located) = metric.run(py, threads, move |metric| {
        let samples = loops_core::fleet::sample_fleet(&fleet, metric.as_metric(), &inner, &spec, between_only)?;
        let located = fleet.localize(&samples)?;
        Ok((samples, located))
    })?;
    crate::warning::warn_samples(py, &samples, skip_trivial)?;
    let samples = Py::new(py, Samples { inner: Arc::new(samples) })?;
    Ok(FleetSamples { samples, located, fleet: loops.fleet.clone_ref(py) })
}

/// The samples of a fleet's loops, each naming both its sessions (name, pose, time on the
/// session's clock). Returned by :func:`sample_fleet`.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct FleetSamples {
    pub(crate) samples: Py<Samples>,
    located: Vec<loops_core::fleet::FleetSample>,
    fleet: Py<Fleet>,
}

#[pymethods]
impl FleetSamples {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<ReducedWith<'py, Fleet>> {
        let this = slf.get();
        let py = slf.py();
        let samples = &this.samples.bind(py).get().inner;
        crate::pickling::reduce_with(slf.as_any(), "FleetSamples", &**samples, this.fleet.clone_ref(py))
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8], fleet: &Bound<'_, PyAny>) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "FleetSamples", || {
            let py = cls.py();
            let fleet = crate::pickling::companion::<Fleet>(fleet, "FleetSamples", "fleet")?;
            let samples: loops_core::Samples = crate::pickling::restore(py, "FleetSamples", state)?;
            let poses = fleet.get().inner.poses();
            if samples.poses() != Some(poses) {
                return Err(crate::pickling::invalid(
                    py,
                    "FleetSamples",
                    match samples.poses() {
                        Some(count) => format!("the samples are of {count} poses, its fleet has {poses}"),
                        None => format!("the samples are of no trajectory, its fleet has {poses} poses"),
                    },
                ));
            }
            let located =
                fleet.get().inner.localize(&samples).map_err(|e| crate::pickling::invalid(py, "FleetSamples", e))?;
            let samples = Py::new(py, Samples { inner: Arc::new(samples) })?;
            Ok(Self { samples, located, fleet: fleet.clone().unbind() })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>, py: Python<'_>) -> bool {
        self.samples.bind(py).get().inner == other.samples.bind(py).get().inner
            && self.fleet.get().same(other.fleet.get())
    }

    fn __hash__(&self, py: Python<'_>) -> u64 {
        let inner = &self.samples.bind(py).get().inner;
        crate::pickling::hash_of(&[inner.len() as u64, inner.available(), self.fleet.get().inner.poses() as u64])
    }

    fn __len__(&self) -> usize {
        self.located.len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let between = self.located.iter().filter(|s| s.sessions[0] != s.sessions[1]).count();
        let inner = &self.samples.bind(py).get().inner;
        format!(
            "FleetSamples({} samples ({between} between sessions), sampler={:?}, {} groups, {} candidates)",
            self.located.len(),
            inner.sampler().name(),
            inner.groups(),
            inner.available()
        )
    }

    /// The same samples as :class:`Samples` on the joint trajectory (:attr:`Fleet.joint`:
    /// fleet indices ``i``, ``j`` and the fleet clock), e.g. for :func:`sample_quality` against
    /// :attr:`FleetLoops.loops`.
    #[getter]
    fn samples(&self, py: Python<'_>) -> Py<Samples> {
        self.samples.clone_ref(py)
    }

    /// The :class:`Fleet` sampled.
    #[getter]
    fn fleet(&self, py: Python<'_>) -> Py<Fleet> {
        self.fleet.clone_ref(py)
    }

    /// The sampler's name.
    #[getter]
    fn sampler(&self, py: Python<'_>) -> &'static str {
        self.samples.bind(py).get().inner.sampler().name()
    }

    /// Number of groups sampled from (components with a pair; 0 for σ_α and the baselines).
    #[getter]
    fn groups(&self, py: Python<'_>) -> usize {
        self.samples.bind(py).get().inner.groups()
    }

    /// Number of candidates the sampler chose from.
    #[getter]
    fn available(&self, py: Python<'_>) -> u64 {
        self.samples.bind(py).get().inner.available()
    }

    /// Warnings, as sentences (as :attr:`Samples.warnings`).
    #[getter]
    fn warnings(&self, py: Python<'_>) -> Vec<String> {
        self.samples.bind(py).get().inner.warnings().iter().map(ToString::to_string).collect()
    }

    /// The samples as a :class:`~inexact_loops.Table`, one row a sample in order of the fleet
    /// index of the earlier pose, with the columns of ``loops fleet``'s ``samples.csv`` in its
    /// order (less ``sampler``: :attr:`sampler`): ``session_a`` and ``session_b`` (int64, the
    /// sessions of the two poses, a ≤ b; a = b within a session), ``name_a`` and ``name_b``
    /// (str), ``i`` and ``j`` (int64, the poses in sessions a and b), ``t_s`` and ``t_prime_s``
    /// (float64, seconds, each on its session's clock), ``component`` (int64, the component id of
    /// :attr:`FleetLoops.components`, −1 for a baseline's pair outside S_γ) and ``distance``
    /// (float64, δ between the poses).
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        fleet_samples_table(py, &self.located, self.fleet.bind(py).get().inner.names())
    }

    /// :attr:`table` as a ``pandas.DataFrame``.
    ///
    /// Raises:
    ///     ImportError: pandas is not installed (it is not a dependency of the library).
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.table(py)?.call_method0("to_pandas")
    }
}

/// The table of :attr:`FleetSamples.table` (see there): the columns of a fleet's samples.csv
/// ([`loops_io::FLEET_SAMPLE_COLUMNS`]), in its order, less `sampler` (the samples' own
/// attribute). Destructured so that a column added there does not compile here until it is.
pub(crate) fn fleet_samples_table<'py>(
    py: Python<'py>,
    s: &[loops_core::fleet::FleetSample],
    names: &[String],
) -> PyResult<Bound<'py, PyAny>> {
    let [session_a, session_b, name_a, name_b, i, j, t_s, t_prime_s, component, distance, _sampler] =
        loops_io::FLEET_SAMPLE_COLUMNS;
    table(
        py,
        [
            (session_a, int64_column(py, s, |s| s.sessions[0])),
            (session_b, int64_column(py, s, |s| s.sessions[1])),
            (name_a, str_column(py, s.iter().map(|s| names[s.sessions[0]].as_str()))?),
            (name_b, str_column(py, s.iter().map(|s| names[s.sessions[1]].as_str()))?),
            (i, int64_column(py, s, |s| s.poses[0])),
            (j, int64_column(py, s, |s| s.poses[1])),
            (t_s, float64_column(py, s, |s| s.times_s[0])),
            (t_prime_s, float64_column(py, s, |s| s.times_s[1])),
            (component, to_numpy(py, s.iter().map(|s| s.component.map_or(-1, |c| c as i64)).collect()).into_any()),
            (distance, float64_column(py, s, |s| s.distance.unwrap_or(f64::NAN))),
        ],
    )
}

/// A seeded synthetic fleet: ``vehicles`` cars driving every one of ``days`` days in one city
/// (:func:`urban_drive`'s), each session with its own seed, start time (within
/// ``start_spread_s`` of midnight, day d starting at d × 86,400 s) and, with districts, its own
/// first district. Sessions are named ``car<v>-day<d>`` (zero-padded), vehicles first within a
/// day. The same seed gives the same fleet on any number of threads.
///
/// Every argument left as ``None`` takes the library default: 10 vehicles, one day, 10-minute
/// drives (``duration_s=600``) in :func:`urban_drive`'s 1 km² city, starts spread over an hour.
/// The other keywords are :func:`urban_drive`'s, for every session's drive; ``seed`` is the
/// fleet's, from which each session's own is drawn.
///
/// Raises:
///     InvalidParameterError: no vehicles or days, a negative spread, or a drive parameter out
///         of range (named).
///
/// Example:
///     >>> import inexact_loops as il
///     >>> fleet = il.urban_fleet(vehicles=3, days=2, duration_s=120.0, seed=7)
///     >>> len(fleet), fleet.names[4], bool(fleet.session(4).timestamps[0] >= 86_400.0)
///     (6, 'car1-day1', True)
#[pyfunction]
#[pyo3(signature = (*, vehicles=None, days=None, start_spread_s=None, duration_s=None, rate_hz=None, city_size_m=None,
    block_m=None, min_speed_mps=None, max_speed_mps=None, stop_probability=None, min_stop_s=None, max_stop_s=None,
    lane_offset_m=None, lateral_noise_m=None, seed=None, district_m=None, district_dwell_s=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn urban_fleet(
    py: Python<'_>,
    vehicles: Option<usize>,
    days: Option<usize>,
    start_spread_s: Option<f64>,
    duration_s: Option<f64>,
    rate_hz: Option<f64>,
    city_size_m: Option<f64>,
    block_m: Option<f64>,
    min_speed_mps: Option<f64>,
    max_speed_mps: Option<f64>,
    stop_probability: Option<f64>,
    min_stop_s: Option<f64>,
    max_stop_s: Option<f64>,
    lane_offset_m: Option<f64>,
    lateral_noise_m: Option<f64>,
    seed: Option<u64>,
    district_m: Option<f64>,
    district_dwell_s: Option<f64>,
) -> PyResult<Fleet> {
    let d = loops_core::UrbanFleet::default();
    let options = DriveOptions {
        duration_s,
        rate_hz,
        city_size_m,
        block_m,
        min_speed_mps,
        max_speed_mps,
        stop_probability,
        min_stop_s,
        max_stop_s,
        lane_offset_m,
        lateral_noise_m,
        seed,
        district_m,
        district_dwell_s,
    };
    let spec = loops_core::UrbanFleet {
        vehicles: vehicles.unwrap_or(d.vehicles),
        days: days.unwrap_or(d.days),
        drive: options.drive(d.drive)?,
        start_spread_s: start_spread_s.unwrap_or(d.start_spread_s),
    };
    let inner = detached(py, move || Ok(spec.generate()?))?;
    let n = inner.len();
    Ok(Fleet { inner: Arc::new(inner), plane_axes: vec![None; n], metrics: vec![None; n] })
}
