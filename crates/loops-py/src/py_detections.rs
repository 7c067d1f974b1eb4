//! `Detections` (paper, Sec. 5: the pairs place recognition proposes) and `draw_detections`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;

use crate::convert::{data_frame, index_column, real_column, to_numpy};
use crate::detached;
use crate::error::Failure;
use crate::py_loops::{Loops, TimelineArg};
use loops_core::SampleSize;

/// Reads detections from a file: rows of ``t, t_prime[, score]`` (commas, semicolons, tabs or
/// spaces; a header row and ``#`` comments allowed), or the TUC datasets' ``loop t1 t2 score``
/// lines (other keyword lines skipped).
///
/// Placing them on a trajectory (``trajectory_or_loops``) is strict: a detection outside its
/// time span is an error naming the line. With ``drop_outside_span=True`` such detections are
/// dropped, and a :class:`DroppedInputWarning` says how many and on which lines (the TUC Corridor's input
/// has 39 of its 10,019 detections 0.4 s past the end of the ground truth).
///
/// Args:
///     path: the file.
///     trajectory_or_loops: a :class:`Trajectory` (or the :class:`Loops` found on it) to place
///         the detections on (filling :attr:`Detections.i` and :attr:`Detections.j`), or
///         ``None`` to keep times only.
///     drop_outside_span: drop the detections outside the trajectory's time span, with a
///         warning saying how many (needs ``trajectory_or_loops``).
///
/// Raises:
///     OSError: the file cannot be opened. LoopsIOError: a malformed row, no detection, a
///     detection outside the trajectory's time span (naming file and line).
///     InvalidParameterError: ``drop_outside_span`` without a trajectory.
///
/// Example:
///     >>> import pathlib, tempfile, warnings, inexact_loops as il
///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "input.txt"
///     >>> _ = path.write_text("odom2 0 0 0 0\nloop 2.5 0.5 1\nloop 9.5 1.0 0.5\n")
///     >>> traj = il.Trajectory([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
///     >>> il.read_detections(path).t.tolist()
///     [0.5, 1.0]
///     >>> with warnings.catch_warnings(record=True) as caught:
///     ...     warnings.simplefilter("always")
///     ...     det = il.read_detections(path, traj, drop_outside_span=True)
///     >>> det.i.tolist(), det.j.tolist(), str(caught[0].message).endswith("(line 3)")
///     ([0], [2], True)
#[pyfunction]
#[pyo3(signature = (path, trajectory_or_loops=None, *, drop_outside_span=false))]
pub(crate) fn read_detections(
    py: Python<'_>,
    path: std::path::PathBuf,
    trajectory_or_loops: Option<&Bound<'_, PyAny>>,
    drop_outside_span: bool,
) -> PyResult<Detections> {
    let timeline = trajectory_or_loops.map(TimelineArg::from_py).transpose()?;
    if drop_outside_span && timeline.is_none() {
        return Err(crate::error::invalid_parameter(
            "drop_outside_span needs the trajectory (or loops) to place the detections on".into(),
        ));
    }
    let (detections, dropped) = detached(py, move || {
        let mut table = loops_io::read_detections(&path)?;
        match &timeline {
            None => {
                let detections = table.to_unplaced()?;
                Ok((detections, None))
            }
            Some(timeline) => {
                let dropped = drop_outside_span.then(|| table.drop_outside_span(timeline.timeline()));
                Ok((table.to_detections(timeline.timeline())?, dropped))
            }
        }
    })?;
    if let Some(dropped) = dropped {
        crate::py_trajectory::warn_dropped(
            py,
            &dropped,
            "drop_outside_span=True dropped",
            "detection(s) outside the trajectory's time span",
        )?;
    }
    Ok(Detections { inner: Arc::new(detections) })
}

/// A set of detections D: unordered pairs of times (t, t′), seconds, at which the trajectory is
/// believed to come back to itself (place recognition), with optional scores and, once placed
/// on a trajectory, the pose indices (i, j) of each pair.
///
/// A pair given as (t′, t) with t′ > t is stored as (t, t′): loop components are reported on
/// the half t ≤ t′. Rows keep the order they were given in; duplicates are allowed.
///
/// Args:
///     t, t_prime: shape ``(n,)``, seconds, finite, n ≥ 1; either order within a pair.
///     scores: shape ``(n,)``, finite (higher is more confident), or ``None``.
///
/// Raises:
///     InvalidParameterError: no detections, columns of different lengths, a NaN or infinite
///         value (the message names the detection).
///     ValueError: wrong shapes. TypeError: non-numeric dtypes.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([30.0, 100.0], [10.0, 400.0], scores=[0.9, 0.4])
///     >>> det.t.tolist(), det.t_prime.tolist(), len(det)
///     ([10.0, 100.0], [30.0, 400.0], 2)
///     >>> det.i is None  # not placed on a trajectory
///     True
///     >>> traj = il.Trajectory([0.0, 1.0, 2.0], [0.0, 5.0, 0.0])
///     >>> by_index = il.Detections.from_indices(traj, [2], [0])
///     >>> by_index.t.tolist(), by_index.t_prime.tolist(), by_index.i.tolist()
///     ([0.0], [2.0], [0])
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, PartialEq)]
pub(crate) struct Detections {
    pub(crate) inner: Arc<loops_core::Detections>,
}

impl Detections {
    fn wrap(py: Python<'_>, f: impl FnOnce() -> loops_core::Result<loops_core::Detections> + Send) -> PyResult<Self> {
        Ok(Self { inner: Arc::new(detached(py, || Ok(f()?))?) })
    }
}

fn with_scores(
    detections: loops_core::Detections,
    scores: Option<Vec<f64>>,
) -> loops_core::Result<loops_core::Detections> {
    match scores {
        Some(scores) => detections.with_scores(scores),
        None => Ok(detections),
    }
}

crate::pickling::pickled!(Detections, loops_core::Detections, |value| Ok(Self { inner: Arc::new(value) }));

#[pymethods]
impl Detections {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.inner.len() as u64, self.inner.t_s()[0].to_bits()])
    }

    #[new]
    #[pyo3(signature = (t, t_prime, scores=None))]
    fn new(
        py: Python<'_>,
        t: &Bound<'_, PyAny>,
        t_prime: &Bound<'_, PyAny>,
        scores: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let t = real_column(py, t, "t")?;
        let t_prime = real_column(py, t_prime, "t_prime")?;
        let scores = scores.map(|s| real_column(py, s, "scores")).transpose()?;
        Self::wrap(py, move || with_scores(loops_core::Detections::new(t, t_prime)?, scores))
    }

    /// Detections from pose indices (i, j) of a trajectory, either order within a pair; the
    /// times are the poses' timestamps.
    ///
    /// Args:
    ///     trajectory_or_loops: the :class:`Trajectory`, or the :class:`Loops` found on it.
    ///     i, j: shape ``(n,)``, integer pose indices.
    ///     scores: shape ``(n,)`` or ``None``.
    ///
    /// Raises:
    ///     IndexError: an index past the last pose (or negative), naming the detection.
    ///     InvalidParameterError: no detections, columns of different lengths.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> det = il.Detections.from_indices(traj, [3, 1], [0, 2])
    ///     >>> det.i.tolist(), det.j.tolist(), det.t_prime.tolist()
    ///     ([0, 1], [3, 2], [3.0, 2.0])
    #[staticmethod]
    #[pyo3(signature = (trajectory_or_loops, i, j, scores=None))]
    fn from_indices(
        py: Python<'_>,
        trajectory_or_loops: &Bound<'_, PyAny>,
        i: &Bound<'_, PyAny>,
        j: &Bound<'_, PyAny>,
        scores: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let timeline = TimelineArg::from_py(trajectory_or_loops)?;
        let i = index_column(py, i, "i")?;
        let j = index_column(py, j, "j")?;
        let scores = scores.map(|s| real_column(py, s, "scores")).transpose()?;
        Self::wrap(py, move || with_scores(loops_core::Detections::from_indices(timeline.timeline(), &i, &j)?, scores))
    }

    /// The same detections placed on a trajectory: each time goes to the nearest pose (the
    /// pose whose time cell holds it; ties to the earlier), filling :attr:`i` and :attr:`j`.
    /// The times are kept as given.
    ///
    /// Raises:
    ///     InvalidParameterError: a time outside the trajectory's time span, naming the
    ///         detection.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> det = il.Detections([0.1, 2.2], [2.9, 1.4]).locate(traj)
    ///     >>> det.i.tolist(), det.j.tolist()
    ///     ([0, 1], [3, 2])
    fn locate(&self, py: Python<'_>, trajectory_or_loops: &Bound<'_, PyAny>) -> PyResult<Self> {
        let timeline = TimelineArg::from_py(trajectory_or_loops)?;
        let detections = Arc::clone(&self.inner);
        Self::wrap(py, move || detections.as_ref().clone().locate(timeline.timeline()))
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        let placed = self.inner.poses().map_or(String::new(), |poses| format!(", placed on {poses} poses"));
        let scored = if self.inner.scores().is_some() { ", with scores" } else { "" };
        format!("Detections({} pairs{placed}{scored})", self.inner.len())
    }

    /// The earlier time t of each pair, seconds, shape ``(n,)``.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.t_s().to_vec())
    }

    /// The later time t′ ≥ t of each pair, seconds, shape ``(n,)``.
    #[getter]
    fn t_prime<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.t_prime_s().to_vec())
    }

    /// Pose index i (of t) of each pair, int64, or ``None`` when not placed on a trajectory.
    #[getter]
    fn i<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<i64>>> {
        self.inner.pairs().map(|pairs| to_numpy(py, pairs.iter().map(|p| i64::from(p[0])).collect()))
    }

    /// Pose index j ≥ i (of t′) of each pair, int64, or ``None`` when not placed.
    #[getter]
    fn j<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<i64>>> {
        self.inner.pairs().map(|pairs| to_numpy(py, pairs.iter().map(|p| i64::from(p[1])).collect()))
    }

    /// The score of each pair, or ``None`` without scores.
    #[getter]
    fn score<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.scores().map(|scores| to_numpy(py, scores.to_vec()))
    }

    /// Number of poses of the trajectory the detections are placed on, or ``None``.
    #[getter]
    fn poses(&self) -> Option<usize> {
        self.inner.poses()
    }

    /// The detections as a ``pandas.DataFrame``, one row a detection in the order given:
    /// columns ``t``, ``t_prime`` (float64, seconds), then ``i``, ``j`` (int64) once placed on
    /// a trajectory and ``score`` (float64) when there are scores.
    ///
    /// Raises:
    ///     ImportError: pandas is not installed (it is not a dependency of the library).
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> traj = il.Trajectory([0.0, 1.0, 2.0], [0.0, 5.0, 0.0])
    ///     >>> frame = il.Detections([2.0], [0.1], scores=[0.5]).locate(traj).to_pandas()
    ///     >>> list(frame.columns), frame.loc[0, "j"]
    ///     (['t', 't_prime', 'i', 'j', 'score'], np.int64(2))
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        data_frame(
            py,
            [
                Some(("t", self.t(py).into_any())),
                Some(("t_prime", self.t_prime(py).into_any())),
                self.i(py).map(|column| ("i", column.into_any())),
                self.j(py).map(|column| ("j", column.into_any())),
                self.score(py).map(|column| ("score", column.into_any())),
            ],
        )
    }
}

/// Detections drawn uniformly from the exact S_γ of ``loops``, without materialising it: the
/// off-diagonal pairs (i, j), i < j, of its runs, placed on the trajectory, in row-major order.
///
/// Args:
///     loops: from :func:`find_loops`.
///     rate: every pair independently with this probability, in (0, 1]; or
///     budget: exactly this many distinct pairs (at most the pairs of S_γ). Give one of them.
///     seed: the seed (ChaCha8): the same seed gives the same detections on every machine.
///
/// Raises:
///     InvalidParameterError: rate and budget both or neither, a rate outside (0, 1], a
///         budget of 0 or above the pairs available, an empty draw, more than 5,000,000
///         detections (refused before anything is drawn).
///
/// Example:
///     >>> import inexact_loops as il
///     >>> loops = il.find_loops(il.urban_drive(duration_s=600.0), gamma=40.0, separation=None)
///     >>> det = il.draw_detections(loops, budget=1000, seed=7)
///     >>> len(det), all(loops.component_of(i, j) is not None for i, j in zip(det.i, det.j))
///     (1000, True)
#[pyfunction]
#[pyo3(signature = (loops, *, rate=None, budget=None, seed))]
pub(crate) fn draw_detections(
    py: Python<'_>,
    loops: &Loops,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: u64,
) -> PyResult<Detections> {
    let size = SampleSize::from_rate_or_budget(rate, budget).map_err(Failure::from)?;
    let loops = Arc::clone(&loops.inner);
    Detections::wrap(py, move || loops_core::Detections::draw(&loops, size, seed))
}
