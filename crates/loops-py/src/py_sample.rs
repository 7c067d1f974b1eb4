//! Detections, their ε-graph clusters, the samplers and the quality of a sample (paper, Sec. 5):
//! `Detections`, `draw_detections`, `cluster_detections`, `sample`, `sample_quality`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArrayDescrMethods, PyReadonlyArray1, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyIndexError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::IntoPyDict;

use crate::convert::{real_array, table, to_numpy};
use crate::detached;
use crate::error::{Failure, invalid_parameter, value_error};
use crate::py_loops::Loops;
use crate::py_metric::MetricArg;
use crate::py_trajectory::Trajectory;
use loops_core::{
    BaselineParams, Cartographer, HdlGraphSlam, LioSam, Metric, MetricSpec, SampleSize, Sampler, SamplerKind, TimeGap,
    Timeline,
};

// ---------------------------------------------------------------------------------------------
// Conversions.
// ---------------------------------------------------------------------------------------------

/// A 1-D array of real numbers.
fn real_column(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let array = real_array(py, obj, name)?;
    if array.shape.len() != 1 {
        return Err(value_error(format!("{name} must be 1-dimensional (n,), got shape {:?}", array.shape)));
    }
    Ok(array.values)
}

/// A 1-D array of pose indices (any integer dtype; an empty list too).
///
/// # Errors
/// `TypeError` for a non-integer dtype, `ValueError` for a wrong shape, `IndexError` for a
/// negative index.
fn index_column(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<usize>> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (obj,))?;
    let untyped = array
        .cast::<PyUntypedArray>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an array of pose indices")))?;
    if untyped.ndim() != 1 {
        return Err(value_error(format!("{name} must be 1-dimensional (n,), got shape {:?}", untyped.shape())));
    }
    if untyped.len() == 0 {
        return Ok(Vec::new());
    }
    let kind = untyped.dtype().kind();
    let as_dtype = |dtype: &str| numpy.call_method("asarray", (&array,), Some(&[("dtype", dtype)].into_py_dict(py)?));
    match kind {
        b'u' => {
            let view: PyReadonlyArray1<'_, u64> = as_dtype("uint64")?.extract()?;
            let values = view.as_array();
            Ok(values.iter().map(|&v| usize::try_from(v).unwrap_or(usize::MAX)).collect())
        }
        b'i' => {
            let view: PyReadonlyArray1<'_, i64> = as_dtype("int64")?.extract()?;
            let values = view.as_array();
            if let Some((k, v)) = values.iter().enumerate().find(|(_, v)| **v < 0) {
                return Err(PyIndexError::new_err(format!("{name}[{k}] = {v} is not a pose index (negative)")));
            }
            Ok(values.iter().map(|&v| v as usize).collect())
        }
        _ => Err(PyTypeError::new_err(format!(
            "{name} must hold pose indices (an integer dtype), got dtype {}",
            untyped.dtype().str()?
        ))),
    }
}

/// An optional column as a numpy array, `None` when no row has a value.
fn optional_column<'py, T: numpy::Element + Copy>(
    py: Python<'py>,
    values: impl Iterator<Item = Option<T>>,
    missing: T,
) -> Option<Bound<'py, PyArray1<T>>> {
    let mut any = false;
    let column: Vec<T> = values
        .map(|v| {
            any |= v.is_some();
            v.unwrap_or(missing)
        })
        .collect();
    any.then(|| to_numpy(py, column))
}

/// Ids as int64, −1 where there is none.
fn id_column<'py>(py: Python<'py>, values: impl Iterator<Item = Option<usize>>) -> Bound<'py, PyArray1<i64>> {
    to_numpy(py, values.map(|v| v.map_or(-1, |v| v as i64)).collect())
}

/// Something detections can be placed on: a `Trajectory` or the `Loops` found on one.
enum TimelineArg {
    Trajectory(Arc<loops_core::Trajectory>),
    Loops(Arc<loops_core::Loops>),
}

impl TimelineArg {
    fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(trajectory) = obj.cast::<Trajectory>() {
            Ok(Self::Trajectory(Arc::clone(&trajectory.get().inner)))
        } else if let Ok(loops) = obj.cast::<Loops>() {
            Ok(Self::Loops(Arc::clone(&loops.get().inner)))
        } else {
            Err(PyTypeError::new_err(format!(
                "trajectory_or_loops must be a Trajectory or Loops, got {}",
                obj.get_type().name()?
            )))
        }
    }

    fn timeline(&self) -> &dyn Timeline {
        match self {
            Self::Trajectory(trajectory) => trajectory.as_ref(),
            Self::Loops(loops) => loops.as_ref(),
        }
    }
}

/// Rate or budget, exactly one of them (the core's rule).
fn sample_size(rate: Option<f64>, budget: Option<usize>) -> PyResult<SampleSize> {
    Ok(SampleSize::from_rate_or_budget(rate, budget).map_err(Failure::from)?)
}

/// Runs `f` with the metric `metric` stands for, without the GIL: a spec on `threads` threads,
/// a Python callable on one (it takes the GIL for every distance).
fn with_metric<T: Send>(
    py: Python<'_>,
    metric: MetricArg,
    threads: Option<usize>,
    f: impl FnOnce(&dyn Metric) -> loops_core::Result<T> + Send,
) -> PyResult<T> {
    match metric {
        MetricArg::Spec(spec) => detached(py, move || Ok(loops_core::with_threads(threads, || f(spec.as_metric()))??)),
        MetricArg::Callable(callable) => {
            let result = detached(py, || Ok(loops_core::with_threads(Some(1), || f(&callable))??));
            if let Some(error) = callable.take_error() {
                return Err(error);
            }
            result
        }
    }
}

/// The metric to sample `loops` under: the one given, or the one the loops were found with.
fn loops_metric(metric: Option<&Bound<'_, PyAny>>, loops: &loops_core::Loops) -> PyResult<MetricArg> {
    if metric.is_some() {
        return MetricArg::from_py(metric);
    }
    match loops.metric_name().parse::<MetricSpec>() {
        Ok(spec) => Ok(MetricArg::Spec(spec)),
        Err(_) => Err(invalid_parameter(format!(
            "the loops were found with the metric {:?}, which is not a metric name: pass metric= (the same callable)",
            loops.metric_name()
        ))),
    }
}

// ---------------------------------------------------------------------------------------------
// Detections.
// ---------------------------------------------------------------------------------------------

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
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Detections {
    inner: Arc<loops_core::Detections>,
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

#[pymethods]
impl Detections {
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
        let columns = [
            Some(("t", self.t(py).into_any())),
            Some(("t_prime", self.t_prime(py).into_any())),
            self.i(py).map(|column| ("i", column.into_any())),
            self.j(py).map(|column| ("j", column.into_any())),
            self.score(py).map(|column| ("score", column.into_any())),
        ];
        table(py, columns.into_iter().flatten())?.call_method0("to_pandas")
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
///         budget of 0 or above the pairs available, an empty draw.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> loops = il.find_loops(il.urban_drive(duration_s=600.0), gamma=40.0)
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
    let size = sample_size(rate, budget)?;
    let loops = Arc::clone(&loops.inner);
    Detections::wrap(py, move || loops_core::Detections::draw(&loops, size, seed))
}

// ---------------------------------------------------------------------------------------------
// Clusters.
// ---------------------------------------------------------------------------------------------

/// The connected components of the ε graph of a detection set: approximations of the loop
/// components. Returned by :func:`cluster_detections`.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([0.0, 20.0, 500.0], [100.0, 100.0, 900.0])
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> len(clusters), clusters.labels.tolist(), clusters.clusters["t_max_s"].tolist()
///     (2, [0, 0, 1], [20.0, 500.0])
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct DetectionClusters {
    inner: Arc<loops_core::DetectionClusters>,
    detections: Arc<loops_core::Detections>,
}

/// Clusters detections exactly: the connected components of the graph with an edge between
/// every two detections within ``epsilon_s`` seconds of each other (Euclidean in the (t, t′)
/// plane, ``<= ε``): DBSCAN with ``min_samples=1``, without enumerating the ε-pairs.
///
/// Args:
///     detections: :class:`Detections`.
///     epsilon_s: ε > 0, seconds; ``None`` takes the library default (30 s, the paper's).
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///
/// Returns:
///     :class:`DetectionClusters`; cluster ids follow each cluster's smallest (t, t′), so they
///     do not depend on the order of the detections.
///
/// Raises:
///     InvalidParameterError: ε not positive and finite (or below the floating-point
///         resolution of the detections' time range), threads = 0.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([0.0, 30.0, 60.0, 500.0], [1000.0, 1000.0, 1000.0, 900.0])
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> clusters.labels.tolist(), clusters.clusters["size"].tolist()
///     ([0, 0, 0, 1], [3, 1])
#[pyfunction]
#[pyo3(signature = (detections, *, epsilon_s=None, threads=None))]
pub(crate) fn cluster_detections(
    py: Python<'_>,
    detections: &Detections,
    epsilon_s: Option<f64>,
    threads: Option<usize>,
) -> PyResult<DetectionClusters> {
    let epsilon_s = epsilon_s.unwrap_or(loops_core::DEFAULT_EPSILON_S);
    let det = Arc::clone(&detections.inner);
    let inner =
        detached(py, || Ok(loops_core::with_threads(threads, || loops_core::cluster_detections(&det, epsilon_s))??))?;
    Ok(DetectionClusters { inner: Arc::new(inner), detections: Arc::clone(&detections.inner) })
}

#[pymethods]
impl DetectionClusters {
    /// Number of clusters.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "DetectionClusters({} clusters of {} detections, epsilon_s={})",
            self.inner.len(),
            self.detections.len(),
            self.inner.epsilon_s()
        )
    }

    /// The threshold ε, seconds.
    #[getter]
    fn epsilon_s(&self) -> f64 {
        self.inner.epsilon_s()
    }

    /// Side of the grid cells, seconds (a little less than ε/√2).
    #[getter]
    fn cell_side_s(&self) -> f64 {
        self.inner.cell_side_s()
    }

    /// The detections that were clustered.
    #[getter]
    fn detections(&self) -> Detections {
        Detections { inner: Arc::clone(&self.detections) }
    }

    /// The cluster id of each detection, int64, in the order of the detections.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.labels().iter().map(|&l| i64::from(l)).collect())
    }

    /// The clusters as a :class:`~inexact_loops.Table` (a dict of numpy columns, one row a
    /// cluster, by id; ``.to_pandas()`` for a DataFrame): ``id``, ``size`` (detections; int64),
    /// ``t_min_s``, ``t_max_s``, ``t_prime_min_s``, ``t_prime_max_s`` (extents, seconds;
    /// float64), ``cells`` (grid cells holding its detections; int64), ``area_proxy_s2``
    /// (cells × side², s²; float64), ``anchor`` (index of its smallest detection in (t, t′)
    /// order; int64).
    #[getter]
    fn clusters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let cs = self.inner.clusters();
        let ints = |f: &dyn Fn(&loops_core::DetectionCluster) -> usize| {
            to_numpy(py, cs.iter().map(|c| f(c) as i64).collect::<Vec<_>>()).into_any()
        };
        let floats =
            |f: &dyn Fn(&loops_core::DetectionCluster) -> f64| to_numpy(py, cs.iter().map(f).collect()).into_any();
        table(
            py,
            [
                ("id", ints(&|c| c.id)),
                ("size", ints(&|c| c.size)),
                ("t_min_s", floats(&|c| c.t_s[0])),
                ("t_max_s", floats(&|c| c.t_s[1])),
                ("t_prime_min_s", floats(&|c| c.t_prime_s[0])),
                ("t_prime_max_s", floats(&|c| c.t_prime_s[1])),
                ("cells", ints(&|c| c.cells)),
                ("area_proxy_s2", floats(&|c| c.area_proxy_s2)),
                ("anchor", ints(&|c| c.anchor)),
            ],
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Samples.
// ---------------------------------------------------------------------------------------------

/// The samples a sampler chose — candidate pairs for the scan matcher — in order of (t, t′),
/// as numpy columns. Returned by :func:`sample`.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([0.0, 0.0, 500.0], [100.0, 101.0, 900.0], scores=[0.2, 0.8, 0.5])
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> samples = il.sample(clusters, "rho-dispersed", budget=2, seed=0)
///     >>> samples.t_prime.tolist(), samples.cluster.tolist(), samples.score.tolist()
///     ([101.0, 900.0], [0, 1], [0.8, 0.5])
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Samples {
    inner: Arc<loops_core::Samples>,
}

fn measured(
    py: Python<'_>,
    samples: loops_core::Samples,
    trajectory: &Trajectory,
    metric: Option<&Bound<'_, PyAny>>,
) -> PyResult<loops_core::Samples> {
    let traj = Arc::clone(&trajectory.inner);
    with_metric(py, MetricArg::from_py(metric)?, None, move |metric| {
        let mut samples = samples;
        samples.measure(&traj, metric)?;
        Ok(samples)
    })
}

/// Samples inexact loops (paper, Sec. 5): from detection clusters, or straight from the exact
/// loop components of S_γ.
///
/// Args:
///     source: :class:`DetectionClusters` (from :func:`cluster_detections`: groups are the
///         clusters, picks are detections) or :class:`Loops` (from :func:`find_loops`: groups
///         are the exact components, picks are pairs (i, j), i < j, of S_γ; needs
///         ``trajectory``).
///     sampler: ``"one"`` (σ_1: c per group), ``"rho"`` (σ_ρ: r per group per trajectory
///         point), ``"rho-dispersed"`` (σ_ρ's counts spread evenly along each group, each the
///         row's closest pair, or best-scored detection), ``"alpha"`` (σ_α: uniform over all
///         detections or pairs), or a baseline of a deployed SLAM system (``Loops`` only):
///         ``"lio-sam"``, ``"hdl-graph-slam"``, ``"cartographer"``, ``"time-gap"``.
///     rate: the sampler's own rate (c, r, or a probability in (0, 1] for σ_α and the
///         baselines); or
///     budget: exactly this many samples (fewer only when fewer exist, with a warning); σ_1 and
///         σ_ρ keep at least one per group whenever the budget allows it (P1). Give one.
///     seed: the seed (ChaCha8): the same samples on every machine and thread count.
///     trajectory: the :class:`Trajectory` the loops were found on (required for ``Loops``);
///         with clusters, optional: the samples are then placed on it and their distances
///         measured.
///     metric: as in :func:`find_loops`; ``None`` takes the loops' own metric (for clusters,
///         the default metric).
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///     skip_trivial: leave out the trivial loop components (``Loops`` with σ_1, σ_ρ or σ_α):
///         their pairs are simple loops (the next poses, a stop) that odometry already ties
///         together, and σ_ρ would otherwise spend a large share of the budget on them.
///     lio_sam_keyframe_step, lio_sam_period_s, lio_sam_min_age_s, hdl_keyframe_step,
///     hdl_min_travel, hdl_edge_spacing, cartographer_min_gap_s, time_gap_s: parameters of
///         the baselines (metric units and seconds); ``None`` takes the library default.
///
/// Returns:
///     :class:`Samples`.
///
/// Raises:
///     InvalidParameterError: an unknown sampler (the message lists the names), a baseline on
///         clusters, rate and budget both or neither, a budget of 0, a rate out of range, a
///         trajectory that is not the loops', ``skip_trivial`` with clusters or a baseline.
///     TypeError: ``Loops`` without ``trajectory``.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=900.0)
///     >>> loops = il.find_loops(traj, gamma=40.0)
///     >>> samples = il.sample(loops, "rho", budget=200, seed=1, trajectory=traj)
///     >>> len(samples), samples.sampler, set(samples.component.tolist()) == set(range(len(loops.components["id"])))
///     (200, 'rho', True)
///     >>> det = il.draw_detections(loops, rate=0.01, seed=0)
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> samples = il.sample(clusters, "one", budget=len(clusters), seed=0)
///     >>> sorted(samples.cluster.tolist()) == list(range(len(clusters)))
///     True
#[pyfunction]
#[pyo3(signature = (source, sampler, *, rate=None, budget=None, seed, trajectory=None, metric=None, threads=None,
    skip_trivial=false, lio_sam_keyframe_step=None, lio_sam_period_s=None, lio_sam_min_age_s=None, hdl_keyframe_step=None,
    hdl_min_travel=None, hdl_edge_spacing=None, cartographer_min_gap_s=None, time_gap_s=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    sampler: &str,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: u64,
    trajectory: Option<&Trajectory>,
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
) -> PyResult<Samples> {
    let kind: SamplerKind = sampler.parse().map_err(Failure::from)?;
    let size = sample_size(rate, budget)?;
    let d = BaselineParams::default();
    let baseline = BaselineParams {
        lio_sam: LioSam {
            keyframe_step: lio_sam_keyframe_step.unwrap_or(d.lio_sam.keyframe_step),
            period_s: lio_sam_period_s.unwrap_or(d.lio_sam.period_s),
            min_age_s: lio_sam_min_age_s.unwrap_or(d.lio_sam.min_age_s),
        },
        hdl_graph_slam: HdlGraphSlam {
            keyframe_step: hdl_keyframe_step.unwrap_or(d.hdl_graph_slam.keyframe_step),
            min_travel: hdl_min_travel.or(d.hdl_graph_slam.min_travel),
            edge_spacing: hdl_edge_spacing.or(d.hdl_graph_slam.edge_spacing),
        },
        cartographer: Cartographer { min_gap_s: cartographer_min_gap_s.unwrap_or(d.cartographer.min_gap_s) },
        time_gap: TimeGap { gap_s: time_gap_s.unwrap_or(d.time_gap.gap_s) },
    };
    let spec = Sampler { kind, size, seed, baseline, skip_trivial };
    if let Ok(clusters) = source.cast::<DetectionClusters>() {
        let clusters = Arc::clone(&clusters.get().inner);
        let samples =
            detached(py, || Ok(loops_core::with_threads(threads, || loops_core::sample_clusters(&clusters, &spec))??))?;
        let samples = match (trajectory, metric) {
            (Some(trajectory), _) => measured(py, samples, trajectory, metric)?,
            (None, Some(_)) => {
                return Err(PyTypeError::new_err("metric= needs trajectory=: distances are measured on a trajectory"));
            }
            (None, None) => samples,
        };
        return Ok(Samples { inner: Arc::new(samples) });
    }
    if let Ok(loops) = source.cast::<Loops>() {
        let loops = Arc::clone(&loops.get().inner);
        let Some(trajectory) = trajectory else {
            return Err(PyTypeError::new_err(
                "sampling the exact components of Loops needs trajectory=, the Trajectory they were found on",
            ));
        };
        let traj = Arc::clone(&trajectory.inner);
        let metric = loops_metric(metric, &loops)?;
        let samples =
            with_metric(py, metric, threads, move |metric| loops_core::sample_loops(&traj, metric, &loops, &spec))?;
        return Ok(Samples { inner: Arc::new(samples) });
    }
    Err(PyTypeError::new_err(format!(
        "source must be DetectionClusters (from cluster_detections) or Loops (from find_loops), got {}",
        source.get_type().name()?
    )))
}

#[pymethods]
impl Samples {
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        let warnings = self.inner.warnings().len();
        format!(
            "Samples({} samples, sampler={:?}, {} groups, {} candidates{})",
            self.inner.len(),
            self.inner.sampler().name(),
            self.inner.groups(),
            self.inner.available(),
            if warnings == 0 { String::new() } else { format!(", {warnings} warning(s)") }
        )
    }

    /// The sampler's name (``"one"``, ``"rho"``, ...).
    #[getter]
    fn sampler(&self) -> &'static str {
        self.inner.sampler().name()
    }

    /// Number of groups sampled from (clusters, or components with a pair; 0 for σ_α and the
    /// baselines, which do not group).
    #[getter]
    fn groups(&self) -> usize {
        self.inner.groups()
    }

    /// Number of candidates the sampler chose from (detections, pairs, or a rule's pairs).
    #[getter]
    fn available(&self) -> u64 {
        self.inner.available()
    }

    /// Number of poses of the trajectory the pairs index, or ``None``.
    #[getter]
    fn poses(&self) -> Option<usize> {
        self.inner.poses()
    }

    /// Warnings (a budget below the number of groups, or above the candidates), as sentences.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings().iter().map(ToString::to_string).collect()
    }

    /// The earlier time of each sample, seconds.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.rows().iter().map(|s| s.t_s).collect())
    }

    /// The later time of each sample, seconds.
    #[getter]
    fn t_prime<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.rows().iter().map(|s| s.t_prime_s).collect())
    }

    /// Pose index i of each sample, int64, or ``None`` when not placed on a trajectory.
    #[getter]
    fn i<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<i64>>> {
        optional_column(py, self.inner.rows().iter().map(|s| s.pair.map(|p| p[0] as i64)), -1)
    }

    /// Pose index j ≥ i of each sample, int64, or ``None`` when not placed on a trajectory.
    #[getter]
    fn j<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<i64>>> {
        optional_column(py, self.inner.rows().iter().map(|s| s.pair.map(|p| p[1] as i64)), -1)
    }

    /// The exact loop component of each sample, int64; −1 when unknown (samples of clusters
    /// before :meth:`locate`) or outside S_γ.
    #[getter]
    fn component<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        id_column(py, self.inner.rows().iter().map(|s| s.component))
    }

    /// The detection cluster each sample was drawn from, int64; −1 for samples of ``Loops``.
    #[getter]
    fn cluster<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        id_column(py, self.inner.rows().iter().map(|s| s.cluster))
    }

    /// The index of the detection each sample is, int64; −1 for samples of ``Loops``.
    #[getter]
    fn detection<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        id_column(py, self.inner.rows().iter().map(|s| s.detection))
    }

    /// δ(x_i, x_j) of each sample in the metric's unit; NaN where not measured.
    #[getter]
    fn distance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.rows().iter().map(|s| s.distance.unwrap_or(f64::NAN)).collect())
    }

    /// The detection's score of each sample, or ``None`` when the detections had none.
    #[getter]
    fn score<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        optional_column(py, self.inner.rows().iter().map(|s| s.score), f64::NAN)
    }

    /// The same samples placed on the poses of ``loops``' trajectory (where not yet), with the
    /// exact loop component of each (:attr:`component`).
    ///
    /// Raises:
    ///     InvalidParameterError: the samples index another trajectory, or a time lies outside
    ///         its span.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5)
    ///     >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
    ///     >>> il.sample(clusters, "alpha", rate=1.0, seed=0).locate(loops).component.tolist()
    ///     [1]
    fn locate(&self, py: Python<'_>, loops: &Loops) -> PyResult<Self> {
        let (samples, loops) = (Arc::clone(&self.inner), Arc::clone(&loops.inner));
        let inner = detached(py, move || {
            let mut samples = samples.as_ref().clone();
            samples.locate(&loops)?;
            Ok(samples)
        })?;
        Ok(Self { inner: Arc::new(inner) })
    }

    /// The same samples placed on ``trajectory`` (where not yet), with the distance
    /// δ(x_i, x_j) of each (:attr:`distance`) under ``metric`` (as in :func:`find_loops`;
    /// ``None`` is the default metric).
    ///
    /// Raises:
    ///     InvalidParameterError: the samples index another trajectory, or a time lies outside
    ///         its span.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.5]))
    ///     >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
    ///     >>> il.sample(clusters, "alpha", rate=1.0, seed=0).measure(traj).distance.tolist()
    ///     [0.5]
    #[pyo3(signature = (trajectory, *, metric=None))]
    fn measure(&self, py: Python<'_>, trajectory: &Trajectory, metric: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let samples = self.inner.as_ref().clone();
        Ok(Self { inner: Arc::new(measured(py, samples, trajectory, metric)?) })
    }

    /// The samples as a ``pandas.DataFrame``, one row a sample in order of (t, t′): columns
    /// ``t``, ``t_prime`` (float64, seconds), ``i``, ``j`` (int64; only when placed on a
    /// trajectory), ``component``, ``cluster``, ``detection`` (int64, −1 where none),
    /// ``distance`` (float64, NaN where not measured) and ``score`` (float64; only when the
    /// detections had scores) — the getters of the same names.
    ///
    /// Raises:
    ///     ImportError: pandas is not installed (it is not a dependency of the library).
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> clusters = il.cluster_detections(il.Detections([0.0, 500.0], [3.0, 900.0]), epsilon_s=1.0)
    ///     >>> frame = il.sample(clusters, "one", budget=2, seed=0).to_pandas()
    ///     >>> list(frame.columns), frame["cluster"].tolist()
    ///     (['t', 't_prime', 'component', 'cluster', 'detection', 'distance'], [0, 1])
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let columns = [
            Some(("t", self.t(py).into_any())),
            Some(("t_prime", self.t_prime(py).into_any())),
            self.i(py).map(|column| ("i", column.into_any())),
            self.j(py).map(|column| ("j", column.into_any())),
            Some(("component", self.component(py).into_any())),
            Some(("cluster", self.cluster(py).into_any())),
            Some(("detection", self.detection(py).into_any())),
            Some(("distance", self.distance(py).into_any())),
            self.score(py).map(|column| ("score", column.into_any())),
        ];
        table(py, columns.into_iter().flatten())?.call_method0("to_pandas")
    }

    /// Writes the samples as CSV: a header ``t_s,t_prime_s,i,j,component,cluster,detection,
    /// distance,score,sampler``, then one line a sample; unknown values are empty fields.
    /// Atomic (a temporary file renamed into place).
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    ///
    /// Example:
    ///     >>> import os, tempfile, inexact_loops as il
    ///     >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
    ///     >>> samples = il.sample(clusters, "alpha", rate=1.0, seed=0)
    ///     >>> path = os.path.join(tempfile.mkdtemp(), "samples.csv")
    ///     >>> samples.to_csv(path)
    ///     >>> open(path).read().splitlines()[1]
    ///     '0,3,,,,0,0,,,alpha'
    #[pyo3(signature = (path, *, overwrite=false))]
    fn to_csv(&self, py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<()> {
        self.write(py, path, loops_io::SamplesFormat::Csv, overwrite)
    }

    /// Writes the samples as one JSON object: ``sampler``, ``count``, ``groups``,
    /// ``available``, ``poses``, ``warnings`` and ``samples`` (a list of objects with the CSV's
    /// columns; ``null`` for unknown values). Atomic, as :meth:`to_csv`.
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    ///
    /// Example:
    ///     >>> import json, os, tempfile, inexact_loops as il
    ///     >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
    ///     >>> path = os.path.join(tempfile.mkdtemp(), "samples.json")
    ///     >>> il.sample(clusters, "alpha", rate=1.0, seed=0).to_json(path)
    ///     >>> json.load(open(path))["samples"][0]["t_prime_s"]
    ///     3.0
    #[pyo3(signature = (path, *, overwrite=false))]
    fn to_json(&self, py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<()> {
        self.write(py, path, loops_io::SamplesFormat::Json, overwrite)
    }
}

impl Samples {
    fn write(&self, py: Python<'_>, path: PathBuf, format: loops_io::SamplesFormat, overwrite: bool) -> PyResult<()> {
        let samples = Arc::clone(&self.inner);
        detached(py, move || Ok(loops_io::write_samples(&path, &samples, format, overwrite)?))
    }
}

// ---------------------------------------------------------------------------------------------
// Quality.
// ---------------------------------------------------------------------------------------------

/// P1, P2 and P3 of a sample (paper, Sec. 5.2), measured against the exact loop components of
/// S_γ. Returned by :func:`sample_quality`.
///
/// Components count when they hold a pair (i, j) with i < j (a lone diagonal cell cannot be
/// sampled).
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
///     >>> loops = il.find_loops(traj, gamma=4.0)
///     >>> samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
///     >>> quality = il.sample_quality(samples, loops, epsilon_s=1.0)
///     >>> quality.covered, quality.components, quality.coverage, quality.per_component.tolist()
///     (2, 2, 1.0, [1, 1])
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct SampleQuality {
    inner: loops_core::SampleQuality,
}

/// Measures how representative ``samples`` are of the loops (paper, Sec. 5.2): P1 (every loop
/// component covered), P2 (no redundant samples), P3 (more samples for bigger components),
/// against the exact components of ``loops`` — never against the detection clusters. Samples
/// given only by times are placed on the nearest poses.
///
/// Args:
///     samples: :class:`Samples`.
///     loops: the :class:`Loops` to measure against (same trajectory).
///     epsilon_s: the P2 radius, seconds: a sample with another sample of its component
///         within ε in the (t, t′) plane is redundant; ``None`` takes the library default
///         (30 s, the paper's).
///
/// Raises:
///     InvalidParameterError: ε not positive and finite, samples of another trajectory, a
///         sample time outside its span.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=900.0)
///     >>> loops = il.find_loops(traj, gamma=40.0)
///     >>> samples = il.sample(loops, "one", budget=500, seed=0, trajectory=traj)
///     >>> quality = il.sample_quality(samples, loops, epsilon_s=30.0)
///     >>> quality.covered == quality.components, quality.missed["id"].tolist()
///     (True, [])
#[pyfunction]
#[pyo3(signature = (samples, loops, *, epsilon_s=None))]
pub(crate) fn sample_quality(
    py: Python<'_>,
    samples: &Samples,
    loops: &Loops,
    epsilon_s: Option<f64>,
) -> PyResult<SampleQuality> {
    let epsilon_s = epsilon_s.unwrap_or(loops_core::DEFAULT_EPSILON_S);
    let (samples, loops) = (Arc::clone(&samples.inner), Arc::clone(&loops.inner));
    let inner = detached(py, move || Ok(loops_core::sample_quality(&samples, &loops, epsilon_s)?))?;
    Ok(SampleQuality { inner })
}

#[pymethods]
impl SampleQuality {
    fn __repr__(&self) -> String {
        let q = &self.inner;
        let optional = |v: Option<f64>| v.map_or("None".to_owned(), |v| format!("{v:.3}"));
        format!(
            "SampleQuality(P1: {}/{} components covered ({}/{} non-trivial); P2: {}/{} redundant within {} s, \
             median spacing {} s; P3 slope {})",
            q.covered,
            q.components,
            q.nontrivial_covered,
            q.nontrivial_components,
            q.redundant,
            q.samples,
            q.epsilon_s,
            optional(q.median_spacing_s),
            optional(q.p3_slope)
        )
    }

    /// Number of samples.
    #[getter]
    fn samples(&self) -> usize {
        self.inner.samples
    }

    /// Samples outside S_γ (δ > γ: false detections).
    #[getter]
    fn outside(&self) -> usize {
        self.inner.outside
    }

    /// Loop components that can be sampled.
    #[getter]
    fn components(&self) -> usize {
        self.inner.components
    }

    /// P1: components with at least one sample.
    #[getter]
    fn covered(&self) -> usize {
        self.inner.covered
    }

    /// Non-trivial components (revisits proper) that can be sampled.
    #[getter]
    fn nontrivial_components(&self) -> usize {
        self.inner.nontrivial_components
    }

    /// P1 over the non-trivial components.
    #[getter]
    fn nontrivial_covered(&self) -> usize {
        self.inner.nontrivial_covered
    }

    /// P1 as a fraction: covered / components (1 without components).
    #[getter]
    fn coverage(&self) -> f64 {
        self.inner.coverage()
    }

    /// P1: the components without a sample, largest area first, as a
    /// :class:`~inexact_loops.Table`: ``id`` (int64), ``trivial`` (bool), ``area_s2``
    /// (float64, s²), ``pair_count`` (int64).
    #[getter]
    fn missed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let missed = &self.inner.missed;
        table(
            py,
            [
                ("id", to_numpy(py, missed.iter().map(|m| m.id as i64).collect()).into_any()),
                ("trivial", to_numpy(py, missed.iter().map(|m| m.trivial).collect()).into_any()),
                ("area_s2", to_numpy(py, missed.iter().map(|m| m.area_s2).collect()).into_any()),
                ("pair_count", to_numpy(py, missed.iter().map(|m| m.pair_count as i64).collect()).into_any()),
            ],
        )
    }

    /// The ε of P2, seconds.
    #[getter]
    fn epsilon_s(&self) -> f64 {
        self.inner.epsilon_s
    }

    /// P2: samples with another sample of the same component within ε.
    #[getter]
    fn redundant(&self) -> usize {
        self.inner.redundant
    }

    /// P2 as a fraction: redundant / samples (0 without samples).
    #[getter]
    fn redundancy(&self) -> f64 {
        self.inner.redundancy()
    }

    /// P2: median distance from a sample to the nearest other sample of its component,
    /// seconds; ``None`` when no component has two samples.
    #[getter]
    fn median_spacing_s(&self) -> Option<f64> {
        self.inner.median_spacing_s
    }

    /// P3: least-squares slope of ln(samples) on ln(area) across the covered components (≈ 0
    /// for σ_1, ≈ 1 for σ_α); ``None`` with fewer than two distinct areas.
    #[getter]
    fn p3_slope(&self) -> Option<f64> {
        self.inner.p3_slope
    }

    /// Number of components in the P3 fit.
    #[getter]
    fn p3_components(&self) -> usize {
        self.inner.p3_components
    }

    /// Samples per component, int64, by component id: one entry per row of
    /// :attr:`Loops.components`, so it can be added to that table as a column.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
    ///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
    ///     >>> loops = il.find_loops(traj, gamma=4.0)
    ///     >>> samples = il.sample(loops, "alpha", budget=5, seed=0, trajectory=traj)
    ///     >>> table = loops.components
    ///     >>> table["samples"] = il.sample_quality(samples, loops).per_component
    ///     >>> int(table["samples"].sum()), table.num_rows
    ///     (5, 2)
    #[getter]
    fn per_component<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.per_component.iter().map(|&k| k as i64).collect())
    }

    /// The exact component of each sample, int64, in the samples' order; −1 outside S_γ.
    #[getter]
    fn sample_components<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        id_column(py, self.inner.sample_components.iter().copied())
    }

    /// Each sample's distance to the nearest other sample of its component, seconds, in the
    /// samples' order; NaN when alone in its component or outside S_γ.
    #[getter]
    fn nearest_spacing_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.nearest_spacing_s.iter().map(|s| s.unwrap_or(f64::NAN)).collect())
    }
}
