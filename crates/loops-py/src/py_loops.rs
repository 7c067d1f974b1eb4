//! `find_loops` and the `Loops` result.

use std::path::PathBuf;
use std::sync::Arc;

use loops_io::ClosestPositions;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::convert::{
    closest_position_columns, extent_columns, float64_column, id_column, index_column, int64_column, measure_columns,
    pose_index, str_column, table, to_numpy, try_column,
};
use crate::detached;
use crate::error::{Failure, value_error};
use crate::py_metric::{MetricArg, MetricRef, loops_metric};
use crate::py_separation::{Separation, SeparationArg};
use crate::py_trajectory::Trajectory;
use loops_core::{LabelledRun, PairVerdict, Scale, Selection, Side, Timeline};

/// Finds every inexact loop of ``trajectory`` at threshold ``gamma`` exactly (every pair
/// (t, t′) with δ ≤ γ, nothing subsampled) and partitions them into loop components.
///
/// By default only *revisits* count: pairs at least ``Separation.for_gamma(gamma)`` (4 γ) apart
/// along the path, the pairs a SLAM back end wants to match; pairs that odometry already ties
/// together are left out, and no component is trivial. ``separation=None`` gives the paper's
/// S_γ, with its trivial components and simple loops.
///
/// Args:
///     trajectory: a :class:`Trajectory` (for a manifold, built by the matching constructor,
///         e.g. :meth:`Trajectory.se3`).
///     gamma: the distance threshold γ > 0, in the metric's unit (metres for positions).
///     metric: ``None`` (the trajectory's own, :attr:`Trajectory.metric_name`: Euclidean for
///         positions, the manifold's metric for :meth:`Trajectory.se3` and friends, the one
///         given to :func:`read_trajectory`), a name such as ``"se3(rotation_weight_m_per_rad=10)"``, an
///         :mod:`inexact_loops.metrics` object such as ``il.metrics.SE3(rotation_weight_m_per_rad=10)``,
///         or — a slow path, one Python call per distance on one thread — any callable
///         ``f(a, b) -> float`` on two points (numpy arrays) satisfying the triangle inequality.
///     separation: ``"auto"`` (the default, ``Separation.for_gamma(gamma)``), ``None`` (the
///         paper's S_γ), a path length in the metric's unit, or a :class:`Separation` (path
///         length and/or time).
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///
/// Returns:
///     :class:`Loops`.
///
/// Raises:
///     InvalidParameterError: gamma not positive and finite, unknown metric, a metric that does
///         not fit the trajectory's manifold (e.g. ``"euclidean"`` on :meth:`Trajectory.se3`
///         poses; the message names both), a negative separation, threads = 0.
///     OutOfMemoryError: the answer does not fit in memory (a ``MemoryError``; the message
///         names the size it needs). Ctrl-C raises ``KeyboardInterrupt`` within a row.
///
/// Warns:
///     DiagonalBrokenWarning: consecutive poses farther apart than gamma (a data gap, or gamma
///         below the step): more than one trivial component.
///     NoLoopsWarning: a separation was asked for and no pair within gamma keeps it: no
///         revisit, no component. Both also in :attr:`Loops.warnings`.
///
/// Example:
///     A 95% circle of radius 10 m: its ends come within 3.1 m of each other, 60 m apart along
///     the path.
///
///     >>> import numpy as np, inexact_loops as il
///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
///     >>> loops = il.find_loops(traj, gamma=4.0)
///     >>> loops.separation, loops.components["trivial"].tolist()
///     (Separation(path=16.0, time_s=0.0), [False])
///     >>> il.find_loops(traj, gamma=4.0, separation=None).components["trivial"].tolist()
///     [True, False]
#[pyfunction]
#[pyo3(signature = (trajectory, *, gamma, metric=None, separation=SeparationArg::Auto, threads=None))]
#[pyo3(text_signature = "(trajectory, *, gamma, metric=None, separation='auto', threads=None)")]
pub(crate) fn find_loops(
    py: Python<'_>,
    trajectory: &Trajectory,
    gamma: f64,
    metric: Option<&Bound<'_, PyAny>>,
    separation: SeparationArg,
    threads: Option<usize>,
) -> PyResult<Loops> {
    let traj = Arc::clone(&trajectory.inner);
    let separation = separation.at(gamma);
    let inner =
        MetricArg::or_default(metric, trajectory.default_metric())?.run(py, threads, |metric| match metric {
            MetricRef::Spec(spec) => spec.find_loops_separated(&traj, gamma, separation),
            MetricRef::Callable(callable) => loops_core::find_loops_separated(&traj, callable, gamma, separation),
        })?;
    crate::warning::warn_loops(py, &inner)?;
    Ok(Loops::of_trajectory(inner, &trajectory.inner))
}

/// The cumulative path length of every pose under ``metric``: s_0 = 0, s_k = s_{k−1} + δ(x_{k−1},
/// x_k), in the metric's unit, summed in order (as ``numpy.cumsum`` of the steps). A path
/// :class:`Separation` bounds ``s[j] - s[i]``.
///
/// Args:
///     trajectory: a :class:`Trajectory`.
///     metric: as in :func:`find_loops` (a name or an :mod:`inexact_loops.metrics` object;
///         ``None``: the trajectory's own, :attr:`Trajectory.metric_name`).
///
/// Returns:
///     numpy.ndarray: float64, one value per pose.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> traj = il.Trajectory(np.arange(3.0), np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 4.0]]))
///     >>> il.path_length(traj).tolist()
///     [0.0, 5.0, 5.0]
#[pyfunction]
#[pyo3(signature = (trajectory, *, metric=None))]
pub(crate) fn path_length<'py>(
    py: Python<'py>,
    trajectory: &Trajectory,
    metric: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let spec = match metric {
        None => trajectory.default_metric(),
        Some(_) => MetricArg::spec_from_py(metric, "path_length")?,
    };
    let traj = Arc::clone(&trajectory.inner);
    let s = crate::detached(py, move || Ok(spec.path_length(&traj)?))?;
    Ok(PyArray1::from_vec(py, s))
}

/// The inexact loops of a trajectory at one γ: the sublevel set S_γ as runs, its loop
/// components, and the loop duration, area and density over them. Returned by
/// :func:`find_loops`.
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Loops {
    pub(crate) inner: Arc<loops_core::Loops>,
    /// Where each component's closest pair is ([`loops_io::point_position`] of its two poses on
    /// the trajectory the loops were found on), for :attr:`components`: two positions a
    /// component, not a copy of every pose's; `None` where not known (the loops of a fleet's
    /// sessions together).
    pub(crate) closest: Option<Arc<Vec<ClosestPositions>>>,
}

/// Loops compare by their result: the positions come from the same trajectory or are unknown.
impl PartialEq for Loops {
    fn eq(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}

impl Loops {
    /// `inner` found on `traj`, with its closest pairs' positions.
    pub(crate) fn of_trajectory(inner: loops_core::Loops, traj: &loops_core::Trajectory) -> Self {
        let closest: Vec<_> =
            inner.components().iter().map(|c| ClosestPositions::of_trajectory(c.closest_pair, traj)).collect();
        Self { inner: Arc::new(inner), closest: Some(Arc::new(closest)) }
    }

    /// The rows of :attr:`components` (and of `components.csv`), with the closest pairs'
    /// positions where known.
    fn component_rows(&self, samples_per_component: Option<&[u64]>) -> Vec<loops_io::ComponentRow> {
        let mut rows = loops_io::component_rows(&self.inner, None, samples_per_component);
        if let Some(closest) = &self.closest {
            for (row, &at) in rows.iter_mut().zip(closest.iter()) {
                row.positions = at;
            }
        }
        rows
    }
}

impl Loops {
    /// Runs one measure of the core without the GIL, with `side` and `normalized` parsed.
    fn measure<T: Send>(
        &self,
        py: Python<'_>,
        side: &str,
        normalized: bool,
        f: impl FnOnce(&loops_core::Loops, Side, Scale) -> loops_core::Result<T> + Send,
    ) -> PyResult<T> {
        let side = side.to_owned();
        let inner = Arc::clone(&self.inner);
        detached(py, move || {
            let (side, scale) = options(&side, normalized)?;
            Ok(f(&inner, side, scale)?)
        })
    }

    /// The pose indices `i` and `j`, checked against the trajectory.
    fn pose_pair(&self, i: i64, j: i64) -> PyResult<(usize, usize)> {
        let (i, j) = (pose_index(i, "i")?, pose_index(j, "j")?);
        for index in [i, j] {
            self.inner.check_index(index).map_err(Failure::from)?;
        }
        Ok((i, j))
    }
}

fn options(side: &str, normalized: bool) -> Result<(Side, Scale), Failure> {
    let scale = if normalized { Scale::Normalized } else { Scale::Seconds };
    Ok((side.parse()?, scale))
}

/// A closest pair's positions as a pickled `Loops` holds them: pose `closest_i`'s x, y, z, then
/// pose `closest_j`'s (NaN where unknown); [`unpickled_closest`] reads them back.
fn pickled_closest(c: &ClosestPositions) -> [f64; 6] {
    [c.closest_i_x, c.closest_i_y, c.closest_i_z, c.closest_j_x, c.closest_j_y, c.closest_j_z]
        .map(|x| x.unwrap_or(f64::NAN))
}

/// The positions that [`pickled_closest`] wrote.
fn unpickled_closest(v: &[f64; 6]) -> ClosestPositions {
    ClosestPositions::of_poses([Some([v[0], v[1], v[2]]), Some([v[3], v[4], v[5]])])
}

fn selection(components: &Option<Vec<usize>>) -> Selection<'_> {
    components.as_deref().map_or(Selection::All, Selection::Components)
}

#[pymethods]
impl Loops {
    /// Pickles as its core value's state and, when known, its closest pairs' positions (a
    /// second argument, so that a state without them reads as before; a second argument of
    /// every pose's position, as earlier versions pickled it, reads as its closest pairs').
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyBytes>, Option<Bound<'py, pyo3::types::PyBytes>>))>
    {
        let this = slf.get();
        let (from_state, (state,)) = crate::pickling::reduce(slf.as_any(), "Loops", this.inner.as_ref())?;
        let closest = match &this.closest {
            Some(closest) => {
                let values: Vec<[f64; 6]> = closest.iter().map(pickled_closest).collect();
                Some(crate::pickling::reduce(slf.as_any(), "LoopsClosestPositions", &values)?.1.0)
            }
            None => None,
        };
        Ok((from_state, (state, closest)))
    }

    #[classmethod]
    #[pyo3(signature = (state, positions=None))]
    fn _from_state(cls: &Bound<'_, pyo3::types::PyType>, state: &[u8], positions: Option<&[u8]>) -> PyResult<Self> {
        let py = cls.py();
        crate::pickling::restoring(py, "Loops", || {
            let inner: loops_core::Loops = crate::pickling::restore(py, "Loops", state)?;
            let components = inner.components();
            let closest = match positions {
                None => None,
                Some(bytes) if crate::pickling::is_of(bytes, "LoopsPositions") => {
                    // Every pose's position, as earlier versions pickled them.
                    let every: Vec<[f64; 3]> = crate::pickling::restore(py, "LoopsPositions", bytes)?;
                    if every.len() != inner.len() {
                        return Err(crate::pickling::invalid(py, "Loops", "its positions are not one per pose"));
                    }
                    Some(components.iter().map(|c| ClosestPositions::new(c.closest_pair, Some(&every))).collect())
                }
                Some(bytes) => {
                    let values: Vec<[f64; 6]> = crate::pickling::restore(py, "LoopsClosestPositions", bytes)?;
                    if values.len() != components.len() {
                        let reason = "its closest pairs' positions are not one per component";
                        return Err(crate::pickling::invalid(py, "Loops", reason));
                    }
                    Some(values.iter().map(unpickled_closest).collect())
                }
            };
            Ok(Self { inner: Arc::new(inner), closest: closest.map(Arc::new) })
        })
    }
}

#[pymethods]
impl Loops {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[
            self.inner.len() as u64,
            self.inner.gamma().to_bits(),
            self.inner.sublevel_set().runs().len() as u64,
        ])
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        let nontrivial = self.inner.components().iter().filter(|c| !c.trivial).count();
        format!(
            "Loops(gamma={}, metric={}, separation={}, {} poses, {} components ({} non-trivial), {} pairs)",
            self.inner.gamma(),
            self.inner.metric_name(),
            self.inner.separation(),
            self.inner.len(),
            self.inner.components().len(),
            nontrivial,
            self.inner.pair_count()
        )
    }

    /// The threshold γ.
    #[getter]
    fn gamma(&self) -> f64 {
        self.inner.gamma()
    }

    /// The separation the pairs keep (:class:`Separation`; both 0 for the paper's S_γ).
    #[getter]
    fn separation(&self) -> Separation {
        Separation { inner: self.inner.separation() }
    }

    /// The name of the metric the loops were found with: its spec (``"euclidean"``,
    /// ``"se3(rotation_weight_m_per_rad=10, rotation=geodesic)"``), or ``custom(NAME)`` for a
    /// callable, NAME its ``__name__``.
    #[getter]
    fn metric_name(&self) -> String {
        self.inner.metric_name().to_owned()
    }

    /// Last minus first timestamp, seconds.
    #[getter]
    fn span_s(&self) -> f64 {
        self.inner.span_s()
    }

    /// Number of lattice cells (i, j) of S_γ in the full plane, both halves and the diagonal.
    #[getter]
    fn pair_count(&self) -> u64 {
        self.inner.pair_count()
    }

    /// Number of pose pairs {i, j}, i < j, of S_γ (unordered pairs of distinct poses): the
    /// count the command line's summaries and reports print, the sum of the components'
    /// ``pose_pair_count``, and what :func:`sample` draws from.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> loops = il.find_loops(il.Trajectory(np.arange(3.0), np.zeros(3)), gamma=1.0, separation=None)
    ///     >>> loops.pair_count, loops.pose_pair_count
    ///     (9, 3)
    #[getter]
    fn pose_pair_count(&self) -> u64 {
        self.inner.pose_pair_count()
    }

    /// Warnings about the result (e.g. consecutive poses farther apart than γ), as sentences;
    /// :func:`find_loops` also issues each with :func:`warnings.warn`, in a category of
    /// :class:`LoopsWarning`.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings().iter().map(ToString::to_string).collect()
    }

    /// The loop components as a :class:`~inexact_loops.Table` (a dict of numpy columns, one row
    /// a component, by id; ``.to_pandas()`` for a DataFrame): ``id`` (int64), ``trivial``
    /// (bool), ``area_s2`` (float64, s²: the half t ≤ t′ for a non-trivial component, the whole
    /// set for a trivial one), ``pair_count`` (int64, cells, same rule), ``pose_pair_count`` (int64, pairs
    /// of distinct poses i < j: they sum to :attr:`pose_pair_count`), ``run_count``, ``holes`` (int64),
    /// ``i_min``, ``i_max``, ``j_min``, ``j_max`` (int64, index extents), ``t_min_s``, ``t_max_s``,
    /// ``t_prime_min_s``, ``t_prime_max_s`` (float64, seconds), ``closest_i``, ``closest_j``
    /// (int64) and ``closest_distance`` (float64, the metric's unit): the columns of
    /// ``components.csv``, in its order.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
    ///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
    ///     >>> table = il.find_loops(traj, gamma=4.0, separation=None).components
    ///     >>> table["id"].dtype, table["trivial"].tolist(), table["i_max"].tolist()
    ///     (dtype('int64'), [True, False], [199, 7])
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows = self.component_rows(None);
        let measures: Vec<_> = rows.iter().map(|row| row.measures).collect();
        let extents: Vec<_> = rows.iter().map(|row| row.extent).collect();
        let positions: Vec<_> = rows.iter().map(|row| row.positions).collect();
        let id = (loops_io::COMPONENT_COLUMNS[0], int64_column(py, &rows, |row| row.id));
        table(
            py,
            std::iter::once(id)
                .chain(measure_columns(py, &measures))
                .chain(extent_columns(py, &extents))
                .chain(closest_position_columns(py, &positions)),
        )
    }

    /// The runs of S_γ's upper half (j ≥ i), row by row, as a :class:`~inexact_loops.Table` of
    /// int64 columns: ``row`` i, columns ``start``..=``end`` (inclusive) and ``component`` id.
    /// For plotting.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> runs = il.find_loops(traj, gamma=0.5, separation=None).runs()
    ///     >>> {name: column.tolist() for name, column in runs.items()}
    ///     {'row': [0, 0, 1, 2, 3], 'start': [0, 3, 1, 2, 3], 'end': [0, 3, 2, 2, 3], 'component': [0, 1, 2, 2, 3]}
    fn runs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let len = self.inner.sublevel_set().runs().len();
        let column = |value: fn(LabelledRun) -> usize| {
            try_column(py, len, self.inner.runs().map(|run| value(run) as i64), "the runs table").map(Bound::into_any)
        };
        table(
            py,
            [
                ("row", column(|run| run.row)?),
                ("start", column(|run| run.start)?),
                ("end", column(|run| run.end)?),
                ("component", column(|run| run.component)?),
            ],
        )
    }

    /// The component id of the pair (i, j) (either order), or ``None`` when δ > γ or, with a
    /// separation, when the pair is not that far apart along the trajectory.
    ///
    /// Raises:
    ///     IndexError: ``i`` or ``j`` is not a pose index (negative, or past the last pose).
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
    ///     >>> loops.component_of(3, 0), loops.component_of(0, 1)
    ///     (1, None)
    fn component_of(&self, i: i64, j: i64) -> PyResult<Option<usize>> {
        let (i, j) = self.pose_pair(i, j)?;
        Ok(self.inner.component_of(i, j))
    }

    /// Whether (i, j) is a simple loop: a pair in a trivial component.
    ///
    /// Raises:
    ///     IndexError: ``i`` or ``j`` is not a pose index (negative, or past the last pose).
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
    ///     >>> loops.is_simple(1, 2), loops.is_simple(0, 3)
    ///     (True, False)
    fn is_simple(&self, i: i64, j: i64) -> PyResult<bool> {
        let (i, j) = self.pose_pair(i, j)?;
        Ok(self.inner.is_simple(i, j))
    }

    /// The loop component of every pixel of ``grid``: the component holding the pair (column
    /// pose, row pose), either order (so the image is mirrored across the diagonal), −1
    /// outside S_γ. The same pixels as :func:`distance_image`: −1 exactly where δ > γ. With a
    /// grid of every pose it is the lattice of the components itself; when the grid downsamples,
    /// a component smaller than a pixel may hold no pixel's pair (mark it at its closest pair).
    ///
    /// Args:
    ///     grid: a :class:`PlaneGrid` made for these loops (or their trajectory).
    ///
    /// Returns:
    ///     int64 array, shape ``(grid.height, grid.width)``, row 0 the earliest t′.
    ///
    /// Raises:
    ///     InvalidParameterError: a grid made for another number of poses.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 5.0, 5.0, 0.0]))  # out and back
    ///     >>> loops = il.find_loops(traj, gamma=1.0, separation=None)
    ///     >>> loops.label_image(il.PlaneGrid(loops, 10)).tolist()
    ///     [[0, -1, -1, 1], [-1, 2, 2, -1], [-1, 2, 2, -1], [1, -1, -1, 3]]
    fn label_image<'py>(&self, py: Python<'py>, grid: &PlaneGrid) -> PyResult<Bound<'py, numpy::PyArray2<i64>>> {
        label_image(py, &self.inner, grid)
    }

    /// The component id of each pair ``(i[k], j[k])`` (either order), −1 outside S_γ: what
    /// :meth:`component_of` gives, for many pairs at once (a binary search over the runs each).
    ///
    /// Args:
    ///     i, j: integer pose indices, shape ``(m,)``.
    ///
    /// Returns:
    ///     int64 array, shape ``(m,)``.
    ///
    /// Raises:
    ///     IndexError: a pose index past the last pose (or negative).
    ///     ValueError: ``i`` and ``j`` of different lengths.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
    ///     >>> loops.components_of_pairs([3, 0, 0], [0, 3, 1]).tolist()
    ///     [1, 1, -1]
    fn components_of_pairs<'py>(
        &self,
        py: Python<'py>,
        i: &Bound<'_, PyAny>,
        j: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<i64>>> {
        components_of_pairs(py, &self.inner, i, j)
    }

    /// How many of the pairs ``(i[k], j[k])`` each component holds, by component id (pairs
    /// outside S_γ are not counted).
    ///
    /// Args:
    ///     i, j: as :meth:`components_of_pairs`.
    ///
    /// Returns:
    ///     int64 array, shape ``(number of components,)``.
    ///
    /// Raises:
    ///     As :meth:`components_of_pairs`.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
    ///     >>> loops.pair_counts_per_component([3, 0, 0, 1], [0, 3, 1, 2]).tolist()
    ///     [0, 2, 1, 0]
    fn pair_counts_per_component<'py>(
        &self,
        py: Python<'py>,
        i: &Bound<'_, PyAny>,
        j: &Bound<'_, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<i64>>> {
        pair_counts_per_component(py, &self.inner, i, j)
    }

    /// Where each pair ``(i[k], j[k])`` (either order) falls, with δ: in a loop component, in a
    /// trivial one, within γ but not a revisit, or outside S_γ — for the loop-closure edges of a
    /// pose graph (:meth:`PoseGraph.edge_verdicts`), the detections of a place recognizer, any
    /// pairs.
    ///
    /// The verdicts (column ``verdict``):
    ///
    /// - ``"component"``: in a non-trivial loop component (``component`` its id): a revisit;
    /// - ``"trivial"``: in a trivial component, a simple loop (only with ``separation=None``);
    /// - ``"not-separated"``: δ ≤ γ, but the two poses are closer along the trajectory than the
    ///   loops' :class:`Separation` (path length or time, checked as the engine checks it): not
    ///   a revisit, in no component (only with a separation);
    /// - ``"outside"``: δ > γ, outside S_γ.
    ///
    /// Args:
    ///     i, j: integer pose indices, shape ``(m,)``.
    ///     trajectory: the :class:`Trajectory` the loops were found on.
    ///     metric: the metric they were found with; ``None`` takes it from the loops (pass the
    ///         same callable for loops found with one).
    ///
    /// Returns:
    ///     :class:`~inexact_loops.Table`: ``i``, ``j`` (int64, as given), ``distance``
    ///     (float64, δ in the metric's unit), ``verdict`` (str) and ``component`` (int64, −1 in
    ///     none).
    ///
    /// Raises:
    ///     IndexError: a pose index past the last pose (or negative).
    ///     ValueError: ``i`` and ``j`` of different lengths.
    ///     InvalidParameterError: another trajectory, or another metric, than the loops'.
    ///
    /// Example:
    ///     Out along a line and back: the way back revisits the way out, 3 m of path later.
    ///
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(7.0), np.array([0.0, 1, 2, 3, 2, 1, 0]))
    ///     >>> loops = il.find_loops(traj, gamma=0.5, separation=il.Separation(path=3.0))
    ///     >>> table = loops.pair_verdicts([0, 2, 0], [6, 4, 3], traj)
    ///     >>> table["verdict"].tolist(), table["component"].tolist(), table["distance"].tolist()
    ///     (['component', 'not-separated', 'outside'], [0, -1, -1], [0.0, 0.0, 3.0])
    #[pyo3(signature = (i, j, trajectory, *, metric=None))]
    fn pair_verdicts<'py>(
        &self,
        py: Python<'py>,
        i: &Bound<'_, PyAny>,
        j: &Bound<'_, PyAny>,
        trajectory: &Trajectory,
        metric: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let metric = loops_metric(metric, &self.inner)?;
        let (pairs, inner, traj) = (pairs(py, i, j)?, Arc::clone(&self.inner), Arc::clone(&trajectory.inner));
        let verdicts: Vec<PairVerdict> =
            metric.run(py, None, move |m| inner.pair_verdicts(&traj, m.as_metric(), &pairs))?;
        let v = &verdicts;
        table(
            py,
            [
                ("i", int64_column(py, v, |p| p.pair[0])),
                ("j", int64_column(py, v, |p| p.pair[1])),
                ("distance", float64_column(py, v, |p| p.distance)),
                ("verdict", str_column(py, v.iter().map(|p| p.verdict.name()))?),
                ("component", id_column(py, v.iter().map(|p| p.verdict.component())).into_any()),
            ],
        )
    }

    /// Loop duration τ(t_i) for every sample: how long the trajectory stays within γ of
    /// ξ(t_i) (paper, Eq. 6).
    ///
    /// Args:
    ///     components: component ids to restrict to; ``None`` is all of S_γ.
    ///     side: ``"both"`` (every t′), ``"begin"`` (t′ > t) or ``"end"`` (t′ < t).
    ///     normalized: fractions of the span instead of seconds.
    ///
    /// Returns:
    ///     numpy array, shape ``(n,)``.
    #[pyo3(signature = (*, components=None, side="both", normalized=false))]
    fn loop_duration<'py>(
        &self,
        py: Python<'py>,
        components: Option<Vec<usize>>,
        side: &str,
        normalized: bool,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let tau = self.measure(py, side, normalized, move |loops, side, scale| {
            loops.loop_duration(selection(&components), side, scale)
        })?;
        Ok(to_numpy(py, tau))
    }

    /// Loop area α(a, b) = ∫_a^b τ(t) dt (paper, Eq. 7), s² (or normalized units, where a and
    /// b are fractions of the span).
    ///
    /// Args: as :meth:`loop_duration`, plus the interval ``a < b`` (seconds, same clock as the
    /// timestamps).
    #[pyo3(signature = (a, b, *, components=None, side="both", normalized=false))]
    fn loop_area(
        &self,
        py: Python<'_>,
        a: f64,
        b: f64,
        components: Option<Vec<usize>>,
        side: &str,
        normalized: bool,
    ) -> PyResult<f64> {
        self.measure(py, side, normalized, move |loops, side, scale| {
            loops.loop_area(a, b, selection(&components), side, scale)
        })
    }

    /// Loop density ρ(a, b) = α(a, b) / (b − a) (paper, Eq. 8): the mean loop duration over
    /// [a, b], seconds (or normalized).
    #[pyo3(signature = (a, b, *, components=None, side="both", normalized=false))]
    fn loop_density(
        &self,
        py: Python<'_>,
        a: f64,
        b: f64,
        components: Option<Vec<usize>>,
        side: &str,
        normalized: bool,
    ) -> PyResult<f64> {
        self.measure(py, side, normalized, move |loops, side, scale| {
            loops.loop_density(a, b, selection(&components), side, scale)
        })
    }

    // Result files, as `loops run` writes them (loops-io). One naming rule with
    // `Samples.to_csv` / `Samples.to_json`: `to_<format>`, and where a class holds several
    // tables the table's name first, as loops-io names the same writers.

    /// Writes ``components.csv``, the file ``loops run`` writes: one row per component, by id,
    /// with the columns of :attr:`components` (``id, trivial, area_s2, pair_count, pose_pair_count,
    /// run_count, holes, i_min, i_max, j_min, j_max, t_min_s, t_max_s, t_prime_min_s, t_prime_max_s,
    /// closest_i, closest_j, closest_distance``) and, with ``samples_per_component``, a last
    /// column ``samples``. Numbers are printed in the shortest form that reads back as the same
    /// float. Atomic (a temporary file renamed into place).
    ///
    /// Args:
    ///     path: the file.
    ///     samples_per_component: samples per component, by id: one count per component, as
    ///         ``sample_quality(samples, loops).per_component``.
    ///     overwrite: replace an existing file.
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    ///     ValueError: ``samples_per_component`` does not hold one count per component.
    ///
    /// Example:
    ///     >>> import os, tempfile, numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> path = os.path.join(tempfile.mkdtemp(), "components.csv")
    ///     >>> il.find_loops(traj, gamma=0.5, separation=None).components_to_csv(path)
    ///     >>> open(path).read().splitlines()[2]
    ///     '1,false,0.25,1,1,1,0,0,0,3,3,0,0,3,3,0,3,0,0,0,0,0,0,0'
    #[pyo3(signature = (path, *, samples_per_component=None, overwrite=false))]
    fn components_to_csv(
        &self,
        py: Python<'_>,
        path: PathBuf,
        samples_per_component: Option<Vec<u64>>,
        overwrite: bool,
    ) -> PyResult<()> {
        let components = self.inner.components().len();
        if let Some(counts) = &samples_per_component
            && counts.len() != components
        {
            return Err(value_error(format!(
                "samples_per_component has {} counts, but there are {components} components (one count each)",
                counts.len()
            )));
        }
        let rows = self.component_rows(samples_per_component.as_deref());
        let with_samples = samples_per_component.is_some();
        detached(py, move || {
            let write = |file: &mut std::fs::File| loops_io::component_rows_to_csv(&rows, with_samples, file);
            Ok(loops_io::write_atomically(&path, overwrite, write)?)
        })
    }

    /// Writes ``loop_duration.csv``, the file ``loops run`` writes: one row per pose, ``index,
    /// t_s, x, y, z, loop_duration_s`` (τ of :meth:`loop_duration`, seconds). ``x, y, z`` are
    /// the trajectory's first three coordinates (0 for those it lacks): its positions for a
    /// trajectory of positions or of SE(3) poses, the chart's first coordinates otherwise.
    /// Atomic, as :meth:`components_to_csv`.
    ///
    /// Args:
    ///     path: the file.
    ///     trajectory: the :class:`Trajectory` these loops were found on.
    ///     overwrite: replace an existing file.
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    ///     InvalidParameterError: ``trajectory`` is not the one of these loops (other timestamps).
    ///
    /// Example:
    ///     >>> import os, tempfile, numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> path = os.path.join(tempfile.mkdtemp(), "loop_duration.csv")
    ///     >>> il.find_loops(traj, gamma=0.5, separation=None).loop_duration_to_csv(path, traj)
    ///     >>> open(path).read().splitlines()[:2]
    ///     ['index,t_s,x,y,z,loop_duration_s', '0,0,0,0,0,1']
    #[pyo3(signature = (path, trajectory, *, overwrite=false))]
    fn loop_duration_to_csv(
        &self,
        py: Python<'_>,
        path: PathBuf,
        trajectory: &Trajectory,
        overwrite: bool,
    ) -> PyResult<()> {
        let loops = Arc::clone(&self.inner);
        let traj = Arc::clone(&trajectory.inner);
        detached(py, move || {
            loops.check_trajectory(&traj)?;
            let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;
            let positions = loops_io::point_positions(&traj);
            Ok(loops_io::write_loop_duration(&path, traj.timestamps_s(), &positions, &tau, overwrite)?)
        })
    }

    /// Writes the loops as the JSON report of ``loops components --json``: ``source``,
    /// ``poses``, ``span_s``, ``gamma``, ``metric``, ``pair_count``, ``loop_density_s``,
    /// ``warnings`` and ``components`` (a list of objects with ``id``, ``trivial``,
    /// ``area_s2``, ``pair_count``, ``run_count``, ``holes``, ``t_range_s``,
    /// ``t_prime_range_s``, ``i_range``, ``j_range``, ``closest_pair``, ``closest_distance``;
    /// ranges as ``[first, last]``). Atomic, as :meth:`components_to_csv`.
    ///
    /// Args:
    ///     path: the file.
    ///     source: where the trajectory came from (a file name), or ``None`` (``null``).
    ///     overwrite: replace an existing file.
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    ///
    /// Example:
    ///     >>> import json, os, tempfile, numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    ///     >>> path = os.path.join(tempfile.mkdtemp(), "loops.json")
    ///     >>> il.find_loops(traj, gamma=0.5, separation=None).to_json(path, source="line.csv")
    ///     >>> report = json.load(open(path))
    ///     >>> report["source"], report["poses"], report["components"][1]["i_range"]
    ///     ('line.csv', 4, [0, 0])
    #[pyo3(signature = (path, *, source=None, overwrite=false))]
    fn to_json(&self, py: Python<'_>, path: PathBuf, source: Option<String>, overwrite: bool) -> PyResult<()> {
        let loops = Arc::clone(&self.inner);
        detached(py, move || {
            let report = loops_io::LoopsReport::new(source.as_deref(), &loops)?;
            Ok(loops_io::write_loops_report(&path, &report, overwrite)?)
        })
    }
}

/// Something detections can be placed on (and a `PlaneGrid` made for): a `Trajectory` or the
/// `Loops` found on one.
pub(crate) enum TimelineArg {
    Trajectory(Arc<loops_core::Trajectory>),
    Loops(Arc<loops_core::Loops>),
}

impl TimelineArg {
    pub(crate) fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
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

    pub(crate) fn timeline(&self) -> &dyn Timeline {
        match self {
            Self::Trajectory(trajectory) => trajectory.as_ref(),
            Self::Loops(loops) => loops.as_ref(),
        }
    }
}

/// The poses an image of the (t, t′) plane shows: one pose per column (time t) and one per row
/// (time t′), for :func:`distance_image` and :meth:`Loops.label_image`.
///
/// Along each axis: every pose whose time lies in the window when at most ``max_pixels`` do;
/// otherwise ``max_pixels`` pixels evenly spaced in time over the window, each showing the pose
/// nearest its centre time (ties to the earlier pose; where poses are sparser than pixels, one
/// pose shows in neighbouring pixels).
///
/// Args:
///     trajectory_or_loops: the :class:`Trajectory`, or the :class:`Loops` found on it.
///     max_pixels: the most pixels a side (at least 1).
///     window_s: ``((t_min, t_max), (t_prime_min, t_prime_max))``, seconds from the first pose;
///         ``None`` is the whole plane.
///
/// Raises:
///     InvalidParameterError: ``max_pixels`` = 0, a window side that is not finite with
///         min < max, or with no pose in it.
///     TypeError: ``trajectory_or_loops`` of another type.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> traj = il.Trajectory(np.arange(10.0), np.zeros(10))
///     >>> il.PlaneGrid(traj, 100).columns.tolist()
///     [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
///     >>> coarse = il.PlaneGrid(traj, 3)  # pixel centres at 1.5, 4.5 and 7.5 s
///     >>> coarse.columns.tolist(), coarse.column_edges_s.tolist()
///     ([1, 4, 7], [0.0, 3.0, 6.0, 9.0])
///     >>> zoom = il.PlaneGrid(traj, 100, window_s=((2.0, 4.0), (6.5, 9.0)))
///     >>> zoom.columns.tolist(), zoom.rows.tolist(), zoom.column_edges_s.tolist()
///     ([2, 3, 4], [7, 8, 9], [1.5, 2.5, 3.5, 4.5])
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, PartialEq)]
pub(crate) struct PlaneGrid {
    pub(crate) inner: Arc<loops_core::plane::PlaneGrid>,
}

crate::pickling::pickled!(PlaneGrid, loops_core::plane::PlaneGrid, |value| Ok(Self { inner: Arc::new(value) }));

#[pymethods]
impl PlaneGrid {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.inner.poses() as u64, self.inner.width() as u64, self.inner.height() as u64])
    }

    #[new]
    #[pyo3(signature = (trajectory_or_loops, max_pixels, *, window_s=None))]
    fn new(
        py: Python<'_>,
        trajectory_or_loops: &Bound<'_, PyAny>,
        max_pixels: usize,
        window_s: Option<((f64, f64), (f64, f64))>,
    ) -> PyResult<Self> {
        let timeline = TimelineArg::from_py(trajectory_or_loops)?;
        let window = window_s.map(|((a, b), (c, d))| ([a, b], [c, d]));
        let inner =
            detached(py, move || Ok(loops_core::plane::PlaneGrid::new(timeline.timeline(), window, max_pixels)?))?;
        Ok(Self { inner: Arc::new(inner) })
    }

    fn __repr__(&self) -> String {
        format!("PlaneGrid({} × {} pixels of {} poses)", self.inner.width(), self.inner.height(), self.inner.poses())
    }

    /// The pose index i of each column (time t), increasing: int64, shape ``(width,)``.
    #[getter]
    fn columns<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.columns().iter().map(|&i| i as i64).collect())
    }

    /// The pose index j of each row (time t′), increasing (row 0 is the earliest t′): int64,
    /// shape ``(height,)``.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.rows().iter().map(|&j| j as i64).collect())
    }

    /// The time each column stands for: ``width + 1`` increasing boundaries, seconds from the
    /// first pose (column a spans ``[edges[a], edges[a + 1]]``). Even steps over the window when
    /// the axis is downsampled; otherwise the midpoints between the poses' times, half a step
    /// beyond the first and the last.
    #[getter]
    fn column_edges_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.column_edges_s().to_vec())
    }

    /// The time each row stands for: ``height + 1`` increasing boundaries, seconds from the
    /// first pose, as :attr:`column_edges_s`.
    #[getter]
    fn row_edges_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.row_edges_s().to_vec())
    }

    /// Number of columns.
    #[getter]
    fn width(&self) -> usize {
        self.inner.width()
    }

    /// Number of rows.
    #[getter]
    fn height(&self) -> usize {
        self.inner.height()
    }

    /// Number of poses of the trajectory the grid was made for.
    #[getter]
    fn poses(&self) -> usize {
        self.inner.poses()
    }
}

/// `Loops.label_image`: the component of every pixel, −1 outside S_γ.
pub(crate) fn label_image<'py>(
    py: Python<'py>,
    loops: &Arc<loops_core::Loops>,
    grid: &PlaneGrid,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let (loops, plane) = (Arc::clone(loops), Arc::clone(&grid.inner));
    let labels = detached(py, move || Ok(loops.label_image(&plane)?))?;
    try_column(py, labels.len(), labels.into_iter().map(|c| c.map_or(-1, i64::from)), "the label image")?
        .reshape([grid.inner.height(), grid.inner.width()])
}

/// The pairs `(i[k], j[k])` of two index columns.
fn pairs(py: Python<'_>, i: &Bound<'_, PyAny>, j: &Bound<'_, PyAny>) -> PyResult<Vec<[usize; 2]>> {
    let (i, j) = (index_column(py, i, "i")?, index_column(py, j, "j")?);
    if i.len() != j.len() {
        return Err(value_error(format!("i has {} values but j has {}: one of each per pair", i.len(), j.len())));
    }
    Ok(i.into_iter().zip(j).map(|(i, j)| [i, j]).collect())
}

/// `Loops.components_of_pairs`: the component of each pair, −1 outside S_γ.
pub(crate) fn components_of_pairs<'py>(
    py: Python<'py>,
    loops: &Arc<loops_core::Loops>,
    i: &Bound<'_, PyAny>,
    j: &Bound<'_, PyAny>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let pairs = pairs(py, i, j)?;
    let loops = Arc::clone(loops);
    let ids = detached(py, move || Ok(loops.components_of_pairs(&pairs)?))?;
    Ok(to_numpy(py, ids.into_iter().map(|c| c.map_or(-1, |c| c as i64)).collect()))
}

/// `Loops.pair_counts_per_component`: how many of the pairs each component holds.
pub(crate) fn pair_counts_per_component<'py>(
    py: Python<'py>,
    loops: &Arc<loops_core::Loops>,
    i: &Bound<'_, PyAny>,
    j: &Bound<'_, PyAny>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let pairs = pairs(py, i, j)?;
    let loops = Arc::clone(loops);
    let counts = detached(py, move || Ok(loops.pair_counts_per_component(&pairs)?))?;
    Ok(to_numpy(py, counts.into_iter().map(|c| c as i64).collect()))
}
