//! `Samples` (paper, Sec. 5: the pairs a sampler hands the scan matcher) and `sample`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::convert::{data_frame, id_column, optional_column, to_numpy};

/// The columns of :attr:`Samples.relative_poses`, as the samples' CSV names them.
const RELATIVE_POSE_COLUMNS: [&str; 8] = ["dx", "dy", "dz", "dqx", "dqy", "dqz", "dqw", "dtheta_rad"];
use crate::detached;
use crate::error::Failure;
use crate::py_clusters::DetectionClusters;
use crate::py_loops::Loops;
use crate::py_metric::{MetricArg, loops_metric};
use crate::py_trajectory::Trajectory;
use loops_core::{BaselineParams, Cartographer, HdlGraphSlam, LioSam, SampleSize, Sampler, SamplerKind, TimeGap};

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
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, PartialEq)]
pub(crate) struct Samples {
    pub(crate) inner: Arc<loops_core::Samples>,
}

/// `samples` placed on `trajectory`, with their distances under `metric` (`None`: the
/// trajectory's).
fn measured(
    py: Python<'_>,
    samples: loops_core::Samples,
    trajectory: &Trajectory,
    metric: Option<&Bound<'_, PyAny>>,
) -> PyResult<loops_core::Samples> {
    let traj = Arc::clone(&trajectory.inner);
    MetricArg::or_default(metric, trajectory.default_metric())?.run(py, None, move |metric| {
        let mut samples = samples;
        samples.measure(&traj, metric.as_metric())?;
        let positions = loops_io::point_positions(&traj);
        samples.set_positions(|k| positions.get(k).copied());
        Ok(samples)
    })
}

/// The sampler named `sampler` (parsed; `None`: the library's default,
/// [`SamplerKind::DEFAULT`]).
pub(crate) fn sampler_kind(sampler: Option<&str>) -> PyResult<SamplerKind> {
    Ok(sampler.map(str::parse).transpose().map_err(Failure::from)?.unwrap_or(SamplerKind::DEFAULT))
}

/// The sampler named `sampler` ([`sampler_kind`]), drawing `rate` or `budget` (at most one of
/// them; neither: [`SampleSize::DEFAULT_BUDGET`], as on the command line) with
/// `seed`, from the keywords of the functions that sample; the baselines' parameters are the
/// library defaults.
pub(crate) fn sampler_of(
    sampler: Option<&str>,
    rate: Option<f64>,
    budget: Option<usize>,
    seed: u64,
    skip_trivial: bool,
) -> PyResult<Sampler> {
    let kind = sampler_kind(sampler)?;
    let size = SampleSize::or_default(rate, budget).map_err(Failure::from)?;
    Ok(Sampler { skip_trivial, ..Sampler::new(kind, size, seed) })
}

/// The baselines' parameters from the keywords of `sample` (and `sample_fleet`): each `None`
/// takes the library default.
#[allow(clippy::too_many_arguments)]
pub(crate) fn baseline_params(
    lio_sam_keyframe_step: Option<f64>,
    lio_sam_period_s: Option<f64>,
    lio_sam_min_age_s: Option<f64>,
    hdl_keyframe_step: Option<f64>,
    hdl_min_travel: Option<f64>,
    hdl_edge_spacing: Option<f64>,
    cartographer_min_gap_s: Option<f64>,
    time_gap_s: Option<f64>,
) -> BaselineParams {
    let d = BaselineParams::default();
    BaselineParams {
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
    }
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
///         detections or pairs), ``"closest-first"`` (each group's closest pair, or best-scored
///         detection, first; the rest as ``"rho-dispersed"``), ``"closest-then-spread"`` (σ_ρ's
///         counts, each group's first pick its closest pair, the rest as ``"rho-dispersed"``),
///         ``"nearest-then-uniform"`` (the default, :data:`DEFAULT_SAMPLER`: each group's
///         closest pair, then rows' closest pairs up to one row in six, the rest uniform over
///         the pairs), or a baseline of a deployed SLAM system (``Loops`` only): ``"lio-sam"``,
///         ``"hdl-graph-slam"``, ``"cartographer"``, ``"time-gap"``.
///     rate: the sampler's own rate (c, r, or a probability in (0, 1] for σ_α and the
///         baselines); or
///     budget: exactly this many samples (fewer only when fewer exist, with a warning); every
///         sampler but σ_α and the baselines keeps at least one per group whenever the budget
///         allows it (P1). Give at most one; neither draws :data:`DEFAULT_BUDGET`.
///     seed: the seed (ChaCha8): the same samples on every machine and thread count.
///     trajectory: the :class:`Trajectory` the loops were found on (required for ``Loops``);
///         with clusters, optional: the samples are then placed on it and their distances
///         measured.
///     metric: as in :func:`find_loops`; ``None`` takes the loops' own metric (for clusters,
///         the trajectory's, :attr:`Trajectory.metric_name`).
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///     skip_trivial: leave out the trivial loop components (``Loops``, not with a baseline):
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
///         clusters, both rate and budget, a budget of 0, a rate out of range, a
///         trajectory that is not the loops', ``skip_trivial`` with clusters or a baseline; a
///         budget or rate that makes more than 5,000,000 samples (the message says how many
///         and how much memory they would take), refused before anything is drawn.
///     OutOfMemoryError: the samples do not fit in memory.
///     TypeError: ``Loops`` without ``trajectory``.
///
/// Warns:
///     EmptySampleWarning: no samples (no candidates, e.g. ``skip_trivial`` on loops whose
///         every component is trivial, or a rate that kept none).
///     SampleBudgetWarning: fewer candidates than the budget (all are returned), or a budget
///         below the number of groups (P1 cannot hold). Both also in :attr:`Samples.warnings`.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=900.0)
///     >>> loops = il.find_loops(traj, gamma=40.0, separation=None)
///     >>> samples = il.sample(loops, "rho", budget=200, seed=1, trajectory=traj)
///     >>> len(samples), samples.sampler, set(samples.component.tolist()) == set(range(len(loops.components["id"])))
///     (200, 'rho', True)
///     >>> det = il.draw_detections(loops, rate=0.01, seed=0)
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> samples = il.sample(clusters, "one", budget=len(clusters), seed=0)
///     >>> sorted(samples.cluster.tolist()) == list(range(len(clusters)))
///     True
#[pyfunction]
#[pyo3(signature = (source, sampler=None, *, rate=None, budget=None, seed, trajectory=None, metric=None, threads=None,
    skip_trivial=false, lio_sam_keyframe_step=None, lio_sam_period_s=None, lio_sam_min_age_s=None, hdl_keyframe_step=None,
    hdl_min_travel=None, hdl_edge_spacing=None, cartographer_min_gap_s=None, time_gap_s=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    sampler: Option<&str>,
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
        crate::warning::warn_samples(py, &samples, skip_trivial)?;
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
        let samples = metric.run(py, threads, move |metric| {
            let mut samples = loops_core::sample_loops(&traj, metric.as_metric(), &loops, &spec)?;
            let positions = loops_io::point_positions(&traj);
            samples.set_positions(|k| positions.get(k).copied());
            Ok(samples)
        })?;
        crate::warning::warn_samples(py, &samples, skip_trivial)?;
        return Ok(Samples { inner: Arc::new(samples) });
    }
    Err(PyTypeError::new_err(format!(
        "source must be DetectionClusters (from cluster_detections) or Loops (from find_loops), got {}",
        source.get_type().name()?
    )))
}

crate::pickling::pickled!(Samples, loops_core::Samples, |value| Ok(Self { inner: Arc::new(value) }));

#[pymethods]
impl Samples {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.inner.len() as u64, self.inner.available()])
    }

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

    /// Warnings (a budget below the number of groups, or above the candidates), as sentences;
    /// :func:`sample` also issues each with :func:`warnings.warn`, in a category of
    /// :class:`LoopsWarning`.
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

    /// The relative pose the trajectory predicts from pose ``i`` to pose ``j`` of each sample:
    /// the scan matcher's initial guess, shape ``(n, 8)``, columns ``dx, dy, dz, dqx, dqy, dqz,
    /// dqw, dtheta_rad``: ``T_i⁻¹ T_j`` for SE(3) and SE(2) trajectories (translation in the
    /// frame of pose ``i``; ``dtheta_rad`` for SE(2) only), the coordinate difference for
    /// positions alone (up to 3 columns; no rotation). NaN where there is none (no pose pair;
    /// other manifolds). No uncertainty: trajectories hold no covariance.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.5]))
    ///     >>> loops = il.find_loops(traj, gamma=0.6, separation=None)
    ///     >>> il.sample(loops, "alpha", rate=1.0, seed=0, trajectory=traj).relative_poses[:, 0].tolist()
    ///     [0.5, 0.0, -0.5, -0.5]
    #[getter]
    fn relative_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = self
            .inner
            .rows()
            .iter()
            .map(|s| {
                let guess = s.relative_pose;
                let rotation = guess.and_then(|g| g.rotation_xyzw);
                let mut row = vec![f64::NAN; 8];
                if let Some(g) = guess {
                    row[..3].copy_from_slice(&g.translation);
                }
                if let Some(q) = rotation {
                    row[3..7].copy_from_slice(&q);
                }
                row[7] = guess.and_then(|g| g.rotation_rad).unwrap_or(f64::NAN);
                row
            })
            .collect();
        to_numpy(py, rows.concat()).reshape([self.inner.len(), RELATIVE_POSE_COLUMNS.len()])
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
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
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
    /// ``None`` is the trajectory's own, :attr:`Trajectory.metric_name`).
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
    /// ``distance`` (float64, NaN where not measured), ``score`` (float64; only when the
    /// detections had scores) — the getters of the same names — and, when any sample has one,
    /// the relative pose ``dx, dy, dz, dqx, dqy, dqz, dqw, dtheta_rad`` (:attr:`relative_poses`)
    /// and where the two poses are, ``i_x, i_y, i_z, j_x, j_y, j_z`` (the trajectory's first three
    /// coordinates, as ``samples.csv`` has them).
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
        let guesses = self.inner.rows().iter().any(|s| s.relative_pose.is_some());
        let relative = if guesses { Some(self.relative_poses(py)?) } else { None };
        let placed = self.inner.rows().iter().any(|s| s.positions.is_some());
        let position_columns = loops_io::SAMPLE_POSITION_COLUMNS.into_iter().enumerate().map(|(k, name)| {
            placed.then(|| {
                let at = |s: &loops_core::Sample| s.positions.map_or(f64::NAN, |p| p[k / 3][k % 3]);
                (name, to_numpy(py, self.inner.rows().iter().map(at).collect()).into_any())
            })
        });
        let relative_columns = RELATIVE_POSE_COLUMNS.iter().enumerate().map(|(k, &name)| {
            relative.as_ref().map(|matrix| {
                let values: Vec<f64> = matrix.readonly().as_array().column(k).to_vec();
                (name, to_numpy(py, values).into_any())
            })
        });
        data_frame(
            py,
            [
                Some(("t", self.t(py).into_any())),
                Some(("t_prime", self.t_prime(py).into_any())),
                self.i(py).map(|column| ("i", column.into_any())),
                self.j(py).map(|column| ("j", column.into_any())),
                Some(("component", self.component(py).into_any())),
                Some(("cluster", self.cluster(py).into_any())),
                Some(("detection", self.detection(py).into_any())),
                Some(("distance", self.distance(py).into_any())),
                self.score(py).map(|column| ("score", column.into_any())),
            ]
            .into_iter()
            .chain(relative_columns)
            .chain(position_columns),
        )
    }

    /// Writes the samples as CSV: a header ``t_s,t_prime_s,i,j,component,cluster,detection,
    /// distance,score,sampler,dx,dy,dz,dqx,dqy,dqz,dqw,dtheta_rad,i_x,i_y,i_z,j_x,j_y,j_z`` (then
    /// the relative pose, :attr:`relative_poses`, and where the two poses are), then one line a
    /// sample; unknown values are empty fields.
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
    ///     '0,3,,,,0,0,,,alpha,,,,,,,,,,,,,,'
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
