//! `OnlineLoops` (the loops of a trajectory that grows pose by pose) and `Update` (what a push
//! changed). The candidate sampler is in `py_online_sampler`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyType};
use serde::{Deserialize, Serialize};

use crate::convert::{
    bool_column, closest_position_columns, extent_columns, float64_column, int64_column, real_array, table,
    timestamps_and_points, to_numpy,
};
use crate::error::{Failure, value_error};
use crate::py_loops::Loops;
use crate::py_metric::MetricArg;
use crate::py_trajectory::Trajectory;
use crate::shared::Shared;
use crate::{attached, detached};
use loops_core::online::ComponentId;

/// The loops of a trajectory that grows pose by pose, as a SLAM front end sees it: S_γ, its
/// loop components with their statistics, and the loop duration τ, kept up to date as poses
/// are pushed one at a time (:meth:`push`) or in batches (:meth:`push_many`), at a cost that
/// follows the answer (the runs near the new pose), not the length of the trajectory.
///
/// After every push, the components equal those of :func:`find_loops` on the poses so far
/// with ``separation=None`` (the paper's S_γ; :meth:`to_loops` gives exactly that result).
/// Component ids are stable: given in creation order from 0; when two components merge, the
/// survivor keeps the smaller id and the other is retired (:attr:`Update.merged`,
/// :meth:`resolve`). When the back end corrects the trajectory, :meth:`rebuild` restarts from
/// it in one batch computation. An :class:`OnlineSampler` picks loop-closure candidates from
/// each :class:`Update`.
///
/// Args:
///     gamma: the distance threshold γ > 0, in the metric's unit.
///     dim: coordinates per pose (3 for positions, 7 for SE(3) poses ``x y z qx qy qz qw``).
///     metric: as in :func:`find_loops`, a name or an :mod:`inexact_loops.metrics` object
///         (not a callable); ``None`` is ``"euclidean"``.
///
/// Raises:
///     InvalidParameterError: gamma not positive and finite, an unknown metric, a metric that
///         does not take ``dim`` coordinates.
///
/// Example:
///     A 95% circle of radius 10 m, pushed pose by pose: its ends come within γ of each other.
///
///     >>> import numpy as np, inexact_loops as il
///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
///     >>> points = 10 * np.c_[np.cos(angle), np.sin(angle)]
///     >>> online = il.OnlineLoops(gamma=4.0, dim=2)
///     >>> for k in range(200):
///     ...     update = online.push(0.1 * k, points[k])
///     >>> online.components["trivial"].tolist(), online.components["first_pose"].tolist()
///     ([True, False], [0, 197])
///     >>> online.to_loops() == il.find_loops(online.trajectory, gamma=4.0, separation=None)
///     True
///
/// Threads may share an engine: its calls run one at a time, each whole (a call waits, without
/// the GIL, while another thread's is in progress).
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct OnlineLoops {
    pub(crate) engine: Shared<Engine>,
}

/// What an `OnlineLoops` changes as poses are pushed.
#[derive(Debug)]
pub(crate) struct Engine {
    pub(crate) inner: loops_core::online::OnlineLoops,
    /// The number of poses the last rebuild started from (0: none, or cleared): a pickle
    /// replays the same rebuild and pushes.
    rebuilt_len: usize,
}

/// What a push changed. Returned by :meth:`OnlineLoops.push` and :meth:`OnlineLoops.push_many`;
/// hand it to :meth:`OnlineSampler.offer` for its loop-closure candidates.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
///     >>> update = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
///     >>> update.first_pose, update.pose, update.created.tolist()
///     (0, 3, [0, 1, 2, 3])
///     >>> update.runs["row"].tolist(), update.runs["start"].tolist(), update.runs["component"].tolist()
///     ([0, 1, 2, 3, 3], [0, 1, 1, 0, 3], [0, 1, 1, 2, 3])
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Update {
    pub(crate) inner: Arc<loops_core::online::Update>,
}

/// What a pickled `OnlineLoops` holds: enough to replay it exactly.
#[derive(Serialize, Deserialize)]
struct OnlineState {
    metric: String,
    dim: usize,
    gamma: f64,
    rebuilt_len: usize,
    timestamps_s: Vec<f64>,
    coords: Vec<f64>,
    /// Its rebuild count (older states: the one rebuild `rebuilt_len` implies, if any), so that
    /// a sampler pickled with it goes on with the copy.
    #[serde(default)]
    rebuild_count: Option<u64>,
}

/// A pickled `Update`: the fields of the core's.
#[derive(Serialize, Deserialize)]
struct UpdateState {
    first_pose: usize,
    pose: usize,
    /// (row, start, end, component, closest) of each run.
    runs: Vec<(usize, u32, u32, ComponentId, usize)>,
    created: Vec<ComponentId>,
    extended: Vec<ComponentId>,
    /// (pose, retired, survivor) of each merge.
    merged: Vec<(usize, ComponentId, ComponentId)>,
    loop_duration_s: f64,
}

/// `point` as `dim` coordinates.
fn point_of(py: Python<'_>, point: &Bound<'_, PyAny>, dim: usize) -> PyResult<Vec<f64>> {
    let array = real_array(py, point, "point")?;
    if array.shape.len() > 1 || array.values.len() != dim {
        let shape: Vec<String> = array.shape.iter().map(ToString::to_string).collect();
        let shape = if shape.len() == 1 { format!("({},)", shape[0]) } else { format!("({})", shape.join(", ")) };
        return Err(value_error(format!(
            "point must have the engine's {dim} coordinate(s), shape ({dim},), got shape {shape}"
        )));
    }
    Ok(array.values)
}

impl OnlineLoops {
    fn from_engine(engine: Engine) -> Self {
        Self { engine: Shared::new(engine) }
    }
}

#[pymethods]
impl OnlineLoops {
    #[new]
    #[pyo3(signature = (*, gamma, dim, metric=None))]
    fn new(gamma: f64, dim: usize, metric: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let spec = MetricArg::spec_from_py(metric, "OnlineLoops")?;
        let inner = loops_core::online::OnlineLoops::new(spec, dim, gamma).map_err(Failure::from)?;
        Ok(Self::from_engine(Engine { inner, rebuilt_len: 0 }))
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get().engine.lock(slf.py())?;
        let state = OnlineState {
            metric: this.inner.metric().to_string(),
            dim: this.inner.dim(),
            gamma: this.inner.gamma(),
            rebuilt_len: this.rebuilt_len,
            timestamps_s: this.inner.timestamps_s().to_vec(),
            coords: this.inner.trajectory().map_or_else(Vec::new, |traj| traj.coords().to_vec()),
            rebuild_count: Some(this.inner.rebuild_count()),
        };
        crate::pickling::reduce(slf.as_any(), "OnlineLoops", &state)
    }

    /// Unpickles by replaying: the same rebuild (if any), then the same poses in one batch,
    /// which gives the same components and ids (the engine is deterministic).
    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "OnlineLoops", || {
            let py = cls.py();
            let state: OnlineState = crate::pickling::restore(py, "OnlineLoops", state)?;
            let spec: loops_core::MetricSpec = state.metric.parse().map_err(Failure::from)?;
            let mut this = Engine {
                inner: loops_core::online::OnlineLoops::new(spec, state.dim, state.gamma).map_err(Failure::from)?,
                rebuilt_len: state.rebuilt_len,
            };
            let (rebuilt, dim) = (state.rebuilt_len, state.dim);
            if Some(state.coords.len()) != state.timestamps_s.len().checked_mul(dim)
                || rebuilt > state.timestamps_s.len()
            {
                return Err(crate::pickling::invalid(py, "OnlineLoops", "its poses do not fit together"));
            }
            // The clears and the rebuild that bring the count to the original's.
            let implied = u64::from(rebuilt > 0);
            let rebuild_count = state.rebuild_count.unwrap_or(implied);
            // Each clear takes a moment: a count far beyond any real engine's is a forged one.
            if rebuild_count < implied || rebuild_count - implied > 1 << 20 {
                return Err(crate::pickling::invalid(
                    py,
                    "OnlineLoops",
                    format!("its rebuild count {rebuild_count} does not fit its rebuilds"),
                ));
            }
            let inner = &mut this.inner;
            for _ in implied..rebuild_count {
                inner.clear();
            }
            detached(py, move || {
                if rebuilt > 0 {
                    let traj = loops_core::Trajectory::new(
                        state.timestamps_s[..rebuilt].to_vec(),
                        state.coords[..rebuilt * dim].to_vec(),
                        dim,
                    )?;
                    inner.rebuild(&traj)?;
                }
                inner.push_many(&state.timestamps_s[rebuilt..], &state.coords[rebuilt * dim..])?;
                Ok(())
            })?;
            Ok(Self::from_engine(this))
        })
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.engine.lock(py)?.inner.len())
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let this = self.engine.lock(py)?;
        Ok(format!(
            "OnlineLoops(gamma={}, metric={}, dim={}, {} poses, {} components)",
            this.inner.gamma(),
            this.inner.metric(),
            this.inner.dim(),
            this.inner.len(),
            this.inner.components().count()
        ))
    }

    /// Adds the pose at time ``t`` (seconds, after the last pose's) with ``point`` (``dim``
    /// coordinates): row n of the plane, its pairs with every earlier pose. Takes microseconds;
    /// the GIL is held.
    ///
    /// Args:
    ///     t: its time, seconds.
    ///     point: its coordinates, shape ``(dim,)`` (a list or numpy array).
    ///
    /// Returns:
    ///     :class:`Update`.
    ///
    /// Raises:
    ///     InvalidTrajectoryError: a time or coordinate NaN or infinite, a time not after the
    ///         last pose's, a quaternion that is not unit (for the se3 metrics); the message
    ///         names the pose's index. Nothing changes then.
    ///     ValueError: a point of another number of coordinates.
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=1.0, dim=2)
    ///     >>> online.push(0.0, [0.0, 0.0]).created.tolist(), online.push(1.0, [0.5, 0.0]).pose
    ///     ([0], 1)
    fn push(&self, py: Python<'_>, t: f64, point: &Bound<'_, PyAny>) -> PyResult<Update> {
        // Converted first: the conversion may run Python code, which must not find the engine held.
        let dim = self.engine.lock(py)?.inner.dim();
        let point = point_of(py, point, dim)?;
        let mut this = self.engine.lock(py)?;
        let update = attached(|| Ok(this.inner.push(t, &point)?))?;
        Ok(Update { inner: Arc::new(update) })
    }

    /// Adds several poses at once, as that many :meth:`push` es, with one :class:`Update`
    /// covering all of them (an :class:`OnlineSampler` gives the same candidates either way).
    /// All or nothing: on an error none is added. The GIL is released. Ctrl-C stops it before
    /// the next pose (``KeyboardInterrupt``): the poses before that one stay added, as their
    /// pushes would have left them (``len`` says how many), and no :class:`Update` covers them.
    ///
    /// Args:
    ///     timestamps: seconds, shape ``(n,)``, increasing, after the last pose's.
    ///     points: shape ``(n, dim)`` (or ``(n,)`` when ``dim`` is 1).
    ///
    /// Returns:
    ///     :class:`Update`.
    ///
    /// Raises:
    ///     InvalidTrajectoryError: as :meth:`push`, for the first bad pose, named by its index in
    ///         the whole trajectory.
    ///     ValueError: shapes that do not fit (rows, or columns other than ``dim``).
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=1.0, dim=2)
    ///     >>> update = online.push_many(np.arange(3.0), np.zeros((3, 2)))
    ///     >>> update.first_pose, update.pose, len(online)
    ///     (0, 2, 3)
    fn push_many(&self, py: Python<'_>, timestamps: &Bound<'_, PyAny>, points: &Bound<'_, PyAny>) -> PyResult<Update> {
        let (t, coords, dim) = timestamps_and_points(py, timestamps, points, "points")?;
        let mut this = self.engine.lock(py)?;
        let expected = this.inner.dim();
        if dim != expected && !t.is_empty() {
            return Err(value_error(format!(
                "points must have the engine's {expected} coordinate(s) per row, got {dim}"
            )));
        }
        let inner = &mut this.inner;
        // Interrupted after some poses, the engine counts a push: the update offered last is
        // no longer the last.
        let update = detached(py, move || Ok(inner.push_many(&t, &coords)?))?;
        Ok(Update { inner: Arc::new(update) })
    }

    /// Restarts from ``trajectory``, the poses so far as the back end corrected them after a
    /// loop closure, with one batch computation (threads as :func:`find_loops`, GIL released);
    /// later pushes continue after its last pose. Component ids restart from 0 (in order of
    /// each component's first pose); :class:`OnlineSampler` s reset themselves at their next
    /// offer, and updates from before cannot be offered.
    ///
    /// Args:
    ///     trajectory: a :class:`Trajectory` of ``dim`` coordinates.
    ///
    /// Raises:
    ///     InvalidParameterError: a metric that does not fit the trajectory.
    ///     InvalidTrajectoryError: points the metric refuses.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
    ///     >>> _ = online.push_many(np.arange(4.0), [0.0, 1.0, 1.0, 0.0])
    ///     >>> online.rebuild(il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 2.0, 3.0])))
    ///     >>> online.components["id"].tolist(), online.rebuild_count
    ///     ([0, 1, 2, 3], 1)
    fn rebuild(&self, py: Python<'_>, trajectory: &Trajectory) -> PyResult<()> {
        let traj = Arc::clone(&trajectory.inner);
        let mut this = self.engine.lock(py)?;
        let inner = &mut this.inner;
        detached(py, move || Ok(inner.rebuild(&traj)?))?;
        this.rebuilt_len = trajectory.inner.len();
        Ok(())
    }

    /// Forgets every pose: as new (ids restart too; :attr:`rebuild_count` goes up).
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=1.0, dim=1)
    ///     >>> _ = online.push(0.0, [0.0])
    ///     >>> online.clear()
    ///     >>> len(online), online.rebuild_count
    ///     (0, 1)
    fn clear(&self, py: Python<'_>) -> PyResult<()> {
        let mut this = self.engine.lock(py)?;
        this.inner.clear();
        this.rebuilt_len = 0;
        Ok(())
    }

    /// The loops of the poses so far as :func:`find_loops` gives them with ``separation=None``
    /// (the same :class:`Loops`, components numbered in the batch's order, not by online id;
    /// its warnings are in :attr:`Loops.warnings`, not issued).
    ///
    /// Raises:
    ///     InvalidTrajectoryError: fewer than two poses.
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
    ///     >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
    ///     >>> online.to_loops().components["pair_count"].tolist()
    ///     [1, 1, 4, 1]
    fn to_loops(&self, py: Python<'_>) -> PyResult<Loops> {
        let this = self.engine.lock(py)?;
        let inner = &this.inner;
        let loops = detached(py, move || Ok(inner.to_loops()?))?;
        Ok(match inner.trajectory() {
            Some(traj) => Loops::of_trajectory(loops, traj),
            None => Loops { inner: Arc::new(loops), closest: None },
        })
    }

    /// The loop duration τ of pose ``pose`` so far (paper, Eq. 6), seconds: how long the
    /// trajectory has stayed within γ of it. :meth:`Loops.loop_duration` of :meth:`to_loops`
    /// gives it for every pose.
    ///
    /// Raises:
    ///     IndexError: not a pose index.
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
    ///     >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
    ///     >>> online.loop_duration(0), online.loop_duration(1)
    ///     (1.0, 2.0)
    fn loop_duration(&self, py: Python<'_>, pose: i64) -> PyResult<f64> {
        let pose = crate::convert::pose_index(pose, "pose")?;
        Ok(self.engine.lock(py)?.inner.loop_duration_s(pose).map_err(Failure::from)?)
    }

    /// The live id that component ``id`` now belongs to, following merges (``id`` itself for a
    /// live id).
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
    ///     >>> update = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 0.8, 0.0, 0.4])
    ///     >>> update.merged["retired"].tolist(), update.merged["survivor"].tolist(), online.resolve(3)
    ///     ([3], [2], 2)
    fn resolve(&self, py: Python<'_>, id: ComponentId) -> PyResult<ComponentId> {
        Ok(self.engine.lock(py)?.inner.resolve(id))
    }

    /// The threshold γ.
    #[getter]
    fn gamma(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(self.engine.lock(py)?.inner.gamma())
    }

    /// Coordinates per pose.
    #[getter]
    fn dim(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.engine.lock(py)?.inner.dim())
    }

    /// The metric's name (its spec, e.g. ``"euclidean"``).
    #[getter]
    fn metric_name(&self, py: Python<'_>) -> PyResult<String> {
        Ok(self.engine.lock(py)?.inner.metric().to_string())
    }

    /// How many times the engine was rebuilt or cleared: ids from before mean nothing now.
    #[getter]
    fn rebuild_count(&self, py: Python<'_>) -> PyResult<u64> {
        Ok(self.engine.lock(py)?.inner.rebuild_count())
    }

    /// The times of the poses pushed, seconds (a copy).
    #[getter]
    fn timestamps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let times = self.engine.lock(py)?.inner.timestamps_s().to_vec();
        Ok(to_numpy(py, times))
    }

    /// The poses pushed so far as a :class:`Trajectory` (a copy), or ``None`` before the second.
    #[getter]
    fn trajectory(&self, py: Python<'_>) -> PyResult<Option<Trajectory>> {
        let this = self.engine.lock(py)?;
        // The metric is named only where it is not the trajectory's own default.
        let metric = Some(this.inner.metric()).filter(|&metric| metric != loops_core::MetricSpec::default());
        Ok(this.inner.trajectory().map(|traj| Trajectory::read(traj.clone(), None, metric)))
    }

    /// The live loop components so far as a :class:`~inexact_loops.Table`, one row a component,
    /// by id: the columns of :attr:`Loops.components` (``id`` is the online id; the half i ≤ j
    /// for a non-trivial component, the whole set for a trivial one) and ``first_pose`` (the
    /// pose whose row created it, the earliest of merged parts) and ``last_pose`` (the last pose
    /// whose row extended it), int64.
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online = il.OnlineLoops(gamma=0.5, dim=1)
    ///     >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
    ///     >>> table = online.components
    ///     >>> table["id"].tolist(), table["trivial"].tolist(), table["first_pose"].tolist()
    ///     ([0, 1, 2, 3], [True, True, False, True], [0, 1, 3, 3])
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let this = self.engine.lock(py)?;
        let cs: Vec<&loops_core::online::OnlineComponent> = this.inner.components().map(|(_, c)| c).collect();
        let t = this.inner.timestamps_s();
        // The columns of components.csv, in its order (less pose_pair_count, which the online
        // engine does not count), then the online ones.
        let id = loops_io::COMPONENT_COLUMNS[0];
        let [trivial, area_s2, pair_count, _pose_pair_count, run_count, holes] = loops_io::MEASURE_COLUMNS;
        let extents: Vec<_> = cs
            .iter()
            .map(|c| loops_io::ComponentExtent::new([c.i_range, c.j_range], c.closest_pair, c.closest_distance, [t; 2]))
            .collect();
        let traj = this.inner.trajectory();
        let closest = |pair: [usize; 2]| {
            traj.map_or_else(Default::default, |traj| loops_io::ClosestPositions::of_trajectory(pair, traj))
        };
        let positions: Vec<_> = cs.iter().map(|c| closest(c.closest_pair)).collect();
        let measures = [
            (id, int64_column(py, &cs, |c| c.id as usize)),
            (trivial, bool_column(py, &cs, |c| c.trivial)),
            (area_s2, float64_column(py, &cs, |c| c.area_s2)),
            (pair_count, int64_column(py, &cs, |c| c.pair_count as usize)),
            (run_count, int64_column(py, &cs, |c| c.run_count)),
            (holes, int64_column(py, &cs, |c| c.holes as usize)),
        ];
        let online = [
            ("first_pose", int64_column(py, &cs, |c| c.first_pose)),
            ("last_pose", int64_column(py, &cs, |c| c.last_pose)),
        ];
        table(
            py,
            measures
                .into_iter()
                .chain(extent_columns(py, &extents))
                .chain(closest_position_columns(py, &positions))
                .chain(online),
        )
    }
}

#[pymethods]
impl Update {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let u = &slf.get().inner;
        let state = UpdateState {
            first_pose: u.first_pose,
            pose: u.pose,
            runs: u.runs.iter().map(|r| (r.row, r.run.start, r.run.end, r.component, r.closest)).collect(),
            created: u.created.clone(),
            extended: u.extended.clone(),
            merged: u.merged.iter().map(|m| (m.pose, m.retired, m.survivor)).collect(),
            loop_duration_s: u.loop_duration_s,
        };
        crate::pickling::reduce(slf.as_any(), "Update", &state)
    }

    /// An unpickled update is data only: it names no engine, so it cannot be offered.
    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "Update", || {
            let s: UpdateState = crate::pickling::restore(cls.py(), "Update", state)?;
            let inner = loops_core::online::Update {
                first_pose: s.first_pose,
                pose: s.pose,
                runs: s
                    .runs
                    .into_iter()
                    .map(|(row, start, end, component, closest)| loops_core::online::RowRun {
                        row,
                        run: loops_core::Run { start, end },
                        component,
                        closest,
                    })
                    .collect(),
                created: s.created,
                extended: s.extended,
                merged: s
                    .merged
                    .into_iter()
                    .map(|(pose, retired, survivor)| loops_core::online::Merge { pose, retired, survivor })
                    .collect(),
                loop_duration_s: s.loop_duration_s,
                stamp: loops_core::online::PushStamp::default(),
            };
            Ok(Self { inner: Arc::new(inner) })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        self.inner == other.inner
    }

    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.inner.first_pose as u64, self.inner.pose as u64, self.inner.runs.len() as u64])
    }

    fn __repr__(&self) -> String {
        let u = &self.inner;
        format!(
            "Update(poses {}..={}, {} runs, created {:?}, extended {:?}, {} merge(s), loop_duration_s={})",
            u.first_pose,
            u.pose,
            u.runs.len(),
            u.created,
            u.extended,
            u.merged.len(),
            u.loop_duration_s
        )
    }

    /// Index of the first pose the push added.
    #[getter]
    fn first_pose(&self) -> usize {
        self.inner.first_pose
    }

    /// Index of the last pose pushed: the keyframe.
    #[getter]
    fn pose(&self) -> usize {
        self.inner.pose
    }

    /// The loop duration τ of the last pose so far, seconds.
    #[getter]
    fn loop_duration_s(&self) -> f64 {
        self.inner.loop_duration_s
    }

    /// Ids of the components the push created, in order (int64).
    #[getter]
    fn created<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.created.iter().map(|&id| i64::from(id)).collect())
    }

    /// Ids (after the push) of the components that existed before it and gained pairs,
    /// increasing (int64).
    #[getter]
    fn extended<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.extended.iter().map(|&id| i64::from(id)).collect())
    }

    /// The merges, in the order they happened, as a :class:`~inexact_loops.Table` of int64
    /// columns: ``pose`` (the row whose runs joined them), ``retired`` and ``survivor`` (the
    /// smaller id, which lives on).
    #[getter]
    fn merged<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let m = &self.inner.merged;
        table(
            py,
            [
                ("pose", int64_column(py, m, |m| m.pose)),
                ("retired", int64_column(py, m, |m| m.retired as usize)),
                ("survivor", int64_column(py, m, |m| m.survivor as usize)),
            ],
        )
    }

    /// The new rows' runs, row by row, columns increasing, as a :class:`~inexact_loops.Table`
    /// of int64 columns: ``row`` (the pose pushed), ``start`` and ``end`` (its earlier poses
    /// within γ, inclusive; the pose itself when the run reaches the diagonal), ``component``
    /// (its id once the row was added; a later row of the same batch may merge it) and
    /// ``closest`` (the run's pose closest to ``row``).
    #[getter]
    fn runs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.inner.runs;
        table(
            py,
            [
                ("row", int64_column(py, r, |r| r.row)),
                ("start", int64_column(py, r, |r| r.run.start as usize)),
                ("end", int64_column(py, r, |r| r.run.end as usize)),
                ("component", int64_column(py, r, |r| r.component as usize)),
                ("closest", int64_column(py, r, |r| r.closest)),
            ],
        )
    }
}
