//! `Trajectory`, `urban_drive` and `read_trajectory`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyType};
use pyo3::types::{PyList, PyTuple};

use crate::convert::{check_rows_equal_length, real_column, timestamps_and_points, timestamps_and_rows, to_numpy};
use crate::detached;
use crate::error::Failure;
use crate::py_metric::MetricArg;

/// A sampled trajectory: strictly increasing timestamps (seconds) and one point per timestamp.
///
/// A trajectory knows its manifold (:attr:`manifold`): built here, its points are Rⁿ positions,
/// measured by the Euclidean metric; built by :meth:`se3`, :meth:`so3`, :meth:`se2`,
/// :meth:`torus`, :meth:`sphere`, :meth:`gnss` or :meth:`descriptors`, they are measured by that
/// manifold's metric (:attr:`metric_name`) wherever no ``metric=`` is given, and a metric that does
/// not fit them raises, naming both.
///
/// Args:
///     timestamps: shape ``(n,)``, seconds, strictly increasing, finite.
///     positions: shape ``(n, d)`` (or ``(n,)`` for d = 1), finite; any real dtype and any memory
///         order (C, Fortran, strided) is read correctly.
///
/// Raises:
///     InvalidTrajectoryError: NaN or infinite values, unsorted or duplicate timestamps, fewer
///         than 2 poses; the message names the first bad index.
///     ValueError: wrong shapes. TypeError: non-numeric dtypes.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> traj = il.Trajectory(np.array([0.0, 1.0, 3.0]), np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
///     >>> len(traj), traj.dim
///     (3, 2)
///     >>> traj.cell_widths
///     array([0.5, 1.5, 1. ])
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug, Clone)]
pub(crate) struct Trajectory {
    pub(crate) inner: Arc<loops_core::Trajectory>,
    /// The position axes of the source that the first two coordinates are, for a trajectory
    /// read on a plane (`axes=`); what the maps of `inexact_loops.plot` label.
    pub(crate) plane_axes: Option<(usize, usize)>,
    /// The metric it was read or converted for (`read_trajectory(metric=...)`,
    /// `from_evo(metric=...)`), which it is then measured by; `None`: its manifold's default.
    pub(crate) metric: Option<loops_core::MetricSpec>,
}

impl Trajectory {
    /// A trajectory read from a file on the plane `plane_axes`, for `metric` when one was given.
    pub(crate) fn read(
        inner: loops_core::Trajectory,
        plane_axes: Option<(usize, usize)>,
        metric: Option<loops_core::MetricSpec>,
    ) -> Self {
        Self { inner: Arc::new(inner), plane_axes, metric }
    }

    /// The metric it is measured by when no `metric=` is given: the one it was read for, or its
    /// manifold's default (core's).
    pub(crate) fn default_metric(&self) -> loops_core::MetricSpec {
        self.metric.unwrap_or_else(|| self.inner.default_metric())
    }
}

#[pymethods]
impl Trajectory {
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get();
        crate::pickling::reduce(
            slf.as_any(),
            "Trajectory",
            &(&*this.inner, this.plane_axes, this.metric.map(|m| m.to_string())),
        )
    }

    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "Trajectory", || {
            let value: (loops_core::Trajectory, Option<(usize, usize)>, Option<String>) =
                crate::pickling::restore(cls.py(), "Trajectory", state)?;
            let (inner, plane_axes, metric) = value;
            let metric = match metric {
                None => None,
                Some(text) => {
                    let spec: loops_core::MetricSpec = text.parse().map_err(Failure::from)?;
                    spec.validate(&inner).map_err(Failure::from)?;
                    Some(spec)
                }
            };
            Ok(Self { inner: Arc::new(inner), plane_axes, metric })
        })
    }

    fn __eq__(&self, other: PyRef<'_, Self>) -> bool {
        self.inner == other.inner && self.plane_axes == other.plane_axes && self.metric == other.metric
    }

    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[
            self.inner.len() as u64,
            self.inner.dim() as u64,
            self.inner.timestamps_s()[0].to_bits(),
        ])
    }

    #[new]
    fn new(py: Python<'_>, timestamps: &Bound<'_, PyAny>, positions: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, coords, dim) = timestamps_and_points(py, timestamps, positions, "positions")?;
        wrap(py, move || loops_core::Trajectory::new(t, coords, dim))
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Trajectory({} poses, {}, dim {}, {:.3} s from t = {})",
            self.inner.len(),
            self.inner.manifold(),
            self.inner.dim(),
            self.inner.span_s(),
            self.inner.timestamps_s()[0]
        )
    }

    /// Coordinates per point.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// The plane a trajectory was read on: the position axes of its source (0 = x, 1 = y,
    /// 2 = z) that its first two coordinates are, as given to :func:`read_trajectory` or
    /// :meth:`from_evo` with ``axes=`` (Euclidean: the plane's two coordinates; ``se2``: those
    /// and the heading in the plane); ``None`` for every other trajectory, whose coordinates are
    /// its own. The maps of :mod:`inexact_loops.plot` draw and label this plane.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> il.Trajectory(np.arange(3.0), np.zeros((3, 2))).plane_axes is None
    ///     True
    #[getter]
    fn plane_axes(&self) -> Option<(usize, usize)> {
        self.plane_axes
    }

    /// The manifold of the points, as its constructor built them: ``"euclidean"`` (this class's
    /// constructor, :meth:`gnss_ecef`, unnormalised :meth:`descriptors`), ``"se3"``, ``"so3"``,
    /// ``"se2"``, ``"torus"``, ``"sphere"``, ``"gnss"`` or ``"descriptors"``.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> q = np.tile([0, 0, 0, 1.0], (2, 1))
    ///     >>> il.Trajectory.se3(np.array([0.0, 1.0]), np.zeros((2, 3)), q).manifold
    ///     'se3'
    #[getter]
    fn manifold(&self) -> &'static str {
        self.inner.manifold().name()
    }

    /// The name of the metric :func:`find_loops`, :func:`sample`, :func:`distance_image` and
    /// :meth:`Samples.measure` use when no ``metric=`` is given (as :attr:`Loops.metric_name`
    /// names the one the loops were found with): the one the trajectory was read
    /// or converted for (:func:`read_trajectory` and :meth:`from_evo` with ``metric=``), or else
    /// its manifold's — ``euclidean``; ``se3(rotation_weight_m_per_rad=0, rotation=geodesic)``
    /// and ``se2(rotation_weight_m_per_rad=0)`` (the translation, metres: a radian's weight has
    /// no universal value, so rotation counts only when asked for); ``so3(rotation=geodesic)``;
    /// ``torus``; ``sphere(radius=1)``; ``haversine(radius_m=6371008.8)`` for :meth:`gnss`;
    /// ``angular`` for normalised :meth:`descriptors`.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> il.Trajectory.so3_from_rotation_vectors(np.arange(2.0), np.zeros((2, 3))).metric_name
    ///     'so3(rotation=geodesic)'
    #[getter]
    fn metric_name(&self) -> String {
        self.default_metric().name()
    }

    /// Timestamps, seconds, shape ``(n,)`` (a copy).
    #[getter]
    fn timestamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.timestamps_s().to_vec())
    }

    /// Points, shape ``(n, d)`` (a copy).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        to_numpy(py, self.inner.coords().to_vec()).reshape([self.inner.len(), self.inner.dim()])
    }

    /// Time-cell widths w_i, seconds, shape ``(n,)``: sample i stands for the cell between the
    /// midpoints to its neighbours (half cells at the ends); they sum to ``span_s``.
    #[getter]
    fn cell_widths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.cell_widths_s().to_vec())
    }

    /// Last minus first timestamp, seconds.
    #[getter]
    fn span_s(&self) -> f64 {
        self.inner.span_s()
    }

    /// The pose nearest each time: the pose whose time cell holds it, ties to the earlier pose.
    ///
    /// Args:
    ///     times_s: times, seconds on the clock of the timestamps, shape ``(m,)``.
    ///
    /// Returns:
    ///     int64 pose indices, shape ``(m,)``.
    ///
    /// Raises:
    ///     InvalidParameterError: a time outside the trajectory's time span (or NaN), naming it.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> traj = il.Trajectory(np.array([0.0, 1.0, 3.0]), np.zeros(3))
    ///     >>> traj.nearest_poses([0.4, 0.5, 2.1, 3.0]).tolist()
    ///     [0, 0, 2, 2]
    fn nearest_poses<'py>(&self, py: Python<'py>, times_s: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        nearest_poses(py, &self.inner, times_s)
    }

    /// SE(3) poses, for the ``se3`` / ``se3_rotation`` metrics: positions ``(n, 3)`` and
    /// orientations as quaternions ``(n, 4)`` in **x, y, z, w** order (the ROS and
    /// ``scipy.spatial.transform.Rotation.as_quat()`` order). Quaternions within
    /// ``quaternion_tolerance`` (default 1e-3, as :func:`read_trajectory`) of unit length are normalised; others (zero
    /// included) raise, naming the pose: 4-decimal quaternions (TUM files) are accepted.
    ///
    /// Without ``metric=``, the poses are measured by
    /// ``se3(rotation_weight_m_per_rad=0, rotation=geodesic)``: the distance between the
    /// positions, metres; pass e.g. ``metric="se3(rotation_weight_m_per_rad=10)"`` to count
    /// rotation too. The Euclidean metric does not fit them (it would measure quaternion
    /// components as coordinates) and raises.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> q = np.array([[0, 0, 0, 1.0], [0, 0, 1.0, 0]])
    ///     >>> traj = il.Trajectory.se3(np.array([0.0, 1.0]), np.zeros((2, 3)), q)
    ///     >>> traj.positions.shape
    ///     (2, 7)
    #[staticmethod]
    #[pyo3(signature = (timestamps, positions, quaternions_xyzw, *, quaternion_tolerance=None))]
    fn se3(
        py: Python<'_>,
        timestamps: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        quaternions_xyzw: &Bound<'_, PyAny>,
        quaternion_tolerance: Option<f64>,
    ) -> PyResult<Self> {
        let (t, p) = timestamps_and_rows::<3>(py, timestamps, positions, "positions")?;
        let (_, q) = timestamps_and_rows::<4>(py, timestamps, quaternions_xyzw, "quaternions_xyzw")?;
        let tolerance = quaternion_tolerance.unwrap_or(loops_core::QUATERNION_TOLERANCE);
        wrap(py, move || loops_core::Trajectory::se3_with_tolerance(t, &p, &q, tolerance))
    }

    /// Rotations, for the ``so3`` metric (their default, geodesic angle in radians): quaternions
    /// ``(n, 4)`` in x, y, z, w order, normalised as in :meth:`se3`.
    #[staticmethod]
    #[pyo3(signature = (timestamps, quaternions_xyzw, *, quaternion_tolerance=None))]
    fn so3(
        py: Python<'_>,
        timestamps: &Bound<'_, PyAny>,
        quaternions_xyzw: &Bound<'_, PyAny>,
        quaternion_tolerance: Option<f64>,
    ) -> PyResult<Self> {
        let (t, q) = timestamps_and_rows::<4>(py, timestamps, quaternions_xyzw, "quaternions_xyzw")?;
        let tolerance = quaternion_tolerance.unwrap_or(loops_core::QUATERNION_TOLERANCE);
        wrap(py, move || loops_core::Trajectory::so3_with_tolerance(t, &q, tolerance))
    }

    /// Rotations, for the ``so3`` metric (their default), from rotation vectors ``(n, 3)``
    /// (axis × angle, radians; ``Rotation.as_rotvec()``).
    #[staticmethod]
    fn so3_from_rotation_vectors(
        py: Python<'_>,
        timestamps: &Bound<'_, PyAny>,
        rotation_vectors: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (t, v) = timestamps_and_rows::<3>(py, timestamps, rotation_vectors, "rotation_vectors")?;
        wrap(py, move || loops_core::Trajectory::so3_from_rotation_vectors(t, &v))
    }

    /// Planar poses, for the ``se2`` metric: ``(n, 3)`` rows of x, y (metres) and heading θ
    /// (radians, wrapped to (−π, π]). Without ``metric=`` they are measured by
    /// ``se2(rotation_weight_m_per_rad=0)``, the distance between the positions.
    #[staticmethod]
    fn se2(py: Python<'_>, timestamps: &Bound<'_, PyAny>, poses_xy_theta: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, p) = timestamps_and_rows::<3>(py, timestamps, poses_xy_theta, "poses_xy_theta")?;
        wrap(py, move || loops_core::Trajectory::se2(t, &p))
    }

    /// Points on a torus S¹ × … × S¹, for the ``torus`` metric (their default): angles
    /// ``(n, k)`` in radians (wrapped to (−π, π]).
    #[staticmethod]
    fn torus(py: Python<'_>, timestamps: &Bound<'_, PyAny>, angles_rad: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, angles, dim) = timestamps_and_points(py, timestamps, angles_rad, "angles_rad")?;
        wrap(py, move || loops_core::Trajectory::torus(t, &angles, dim))
    }

    /// Points on the sphere S², for the ``sphere`` metric (their default is ``sphere(radius=1)``,
    /// radians; ``angular`` fits too): non-zero vectors ``(n, 3)``, normalised.
    #[staticmethod]
    fn sphere(py: Python<'_>, timestamps: &Bound<'_, PyAny>, vectors: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, v) = timestamps_and_rows::<3>(py, timestamps, vectors, "vectors")?;
        wrap(py, move || loops_core::Trajectory::sphere(t, &v))
    }

    /// Points on the sphere S², for the ``sphere`` metric (as :meth:`sphere`), from ``(n, 2)``
    /// latitude and longitude in degrees.
    #[staticmethod]
    fn sphere_from_lat_lon(
        py: Python<'_>,
        timestamps: &Bound<'_, PyAny>,
        lat_lon_deg: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (t, p) = timestamps_and_rows::<2>(py, timestamps, lat_lon_deg, "lat_lon_deg")?;
        wrap(py, move || loops_core::Trajectory::sphere_from_lat_lon(t, &p))
    }

    /// GNSS fixes, for the ``haversine`` metric (their default, metres): ``(n, 3)`` latitude
    /// (degrees, within ±90), longitude (degrees) and height (metres). The points are stored as
    /// ``(n, 4)`` unit direction and height, which no other metric fits.
    #[staticmethod]
    fn gnss(py: Python<'_>, timestamps: &Bound<'_, PyAny>, lat_lon_height: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, p) = timestamps_and_rows::<3>(py, timestamps, lat_lon_height, "lat_lon_height")?;
        wrap(py, move || loops_core::Trajectory::gnss(t, &p))
    }

    /// GNSS fixes as WGS 84 Earth-centred positions relative to the first fix, turned into the
    /// first fix's east-north-up frame (metres east, north and up: plots and reports draw a
    /// map), for the ``euclidean`` metric; input as in :meth:`gnss`. A rotation of ECEF, so
    /// distances are the straight-line ones. A Euclidean trajectory (:attr:`manifold`).
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> traj = il.Trajectory.gnss_ecef([0.0, 1.0], [[48.0, 11.0, 500.0], [48.001, 11.0, 500.0]])
    ///     >>> east, north, up = traj.positions[1]  # 111 m north, a little down: the Earth curves
    ///     >>> round(float(north), 1), bool(abs(east) < 1e-6), bool(-0.01 < up < 0)
    ///     (111.2, True, True)
    #[staticmethod]
    fn gnss_ecef(py: Python<'_>, timestamps: &Bound<'_, PyAny>, lat_lon_height: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, p) = timestamps_and_rows::<3>(py, timestamps, lat_lon_height, "lat_lon_height")?;
        wrap(py, move || loops_core::Trajectory::gnss_ecef(t, &p))
    }

    /// Descriptor vectors (place recognition) ``(n, d)``: normalised to unit length when
    /// ``normalize`` (manifold ``"descriptors"``, measured by ``angular`` unless ``metric=``
    /// says ``euclidean``), kept as given otherwise (a Euclidean trajectory). A list of rows of
    /// unequal length raises ``ValueError`` naming the row.
    #[staticmethod]
    #[pyo3(signature = (timestamps, descriptors, *, normalize=true))]
    fn descriptors(
        py: Python<'_>,
        timestamps: &Bound<'_, PyAny>,
        descriptors: &Bound<'_, PyAny>,
        normalize: bool,
    ) -> PyResult<Self> {
        check_rows_equal_length(descriptors, "descriptors")?;
        let (t, values, dim) = timestamps_and_points(py, timestamps, descriptors, "descriptors")?;
        wrap(py, move || loops_core::Trajectory::descriptors(t, &values, dim, normalize))
    }

    /// A trajectory from an `evo <https://github.com/MichaelGrupp/evo>`_ ``PoseTrajectory3D``
    /// (or any object with its attributes ``timestamps`` ``(n,)`` seconds, ``positions_xyz``
    /// ``(n, 3)`` and ``orientations_quat_wxyz`` ``(n, 4)``, quaternions **w first**, as evo
    /// stores them). evo itself is not imported.
    ///
    /// What is built follows ``metric`` exactly as in :func:`read_trajectory`: positions
    /// (x, y, z) for Euclidean (the default), or the plane ``axes`` of them; positions and
    /// orientations for ``se3`` / ``se3_rotation`` (as :meth:`se3`); orientations for ``so3``;
    /// x, y and yaw for ``se2`` (or the plane ``axes`` and the heading in it). Quaternions within
    /// 1e-3 of unit length are normalised.
    /// The trajectory keeps ``metric`` (:attr:`metric_name`): :func:`find_loops` without
    /// ``metric=`` measures it so.
    ///
    /// Args:
    ///     trajectory: an ``evo.core.trajectory.PoseTrajectory3D``.
    ///     metric: the metric the trajectory is for, a name or :mod:`inexact_loops.metrics`
    ///         object (as in :func:`find_loops`); ``None`` is Euclidean.
    ///     axes: a plane of two position axes, e.g. ``(0, 2)``: Euclidean keeps only them, ``se2``
    ///         takes them and the heading in that plane, as in :func:`read_trajectory`
    ///         (:attr:`plane_axes`).
    ///
    /// Raises:
    ///     TypeError: ``trajectory`` lacks one of the attributes (the message names them all,
    ///         e.g. ``timestamps`` for an evo ``PosePath3D``), or holds non-numeric values.
    ///     ValueError: arrays of the wrong shape (named by attribute).
    ///     InvalidTrajectoryError: NaN, unsorted timestamps, a quaternion far from unit length,
    ///         naming the pose.
    ///     InvalidParameterError: an unknown metric, or one whose points are not poses.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> from types import SimpleNamespace  # stands in for evo's PoseTrajectory3D here
    ///     >>> evo_traj = SimpleNamespace(
    ///     ...     timestamps=np.array([0.0, 0.1, 0.2]),
    ///     ...     positions_xyz=np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]),
    ///     ...     orientations_quat_wxyz=np.tile([1.0, 0, 0, 0], (3, 1)),
    ///     ... )
    ///     >>> il.Trajectory.from_evo(evo_traj).positions[-1]
    ///     array([2., 0., 0.])
    ///     >>> poses = il.Trajectory.from_evo(evo_traj, metric="se3(rotation_weight_m_per_rad=1)")
    ///     >>> poses.dim, poses.manifold, poses.metric_name
    ///     (7, 'se3', 'se3(rotation_weight_m_per_rad=1, rotation=geodesic)')
    #[staticmethod]
    #[pyo3(signature = (trajectory, *, metric=None, axes=None))]
    fn from_evo(
        py: Python<'_>,
        trajectory: &Bound<'_, PyAny>,
        metric: Option<&Bound<'_, PyAny>>,
        axes: Option<(usize, usize)>,
    ) -> PyResult<Self> {
        const ATTRIBUTES: [&str; 3] = ["timestamps", "positions_xyz", "orientations_quat_wxyz"];
        let mut missing = Vec::new();
        for name in ATTRIBUTES {
            if !trajectory.hasattr(name)? {
                missing.push(name);
            }
        }
        if !missing.is_empty() {
            return Err(PyTypeError::new_err(format!(
                "Trajectory.from_evo takes an evo PoseTrajectory3D (an object with {}), got {} without {}",
                ATTRIBUTES.join(", "),
                trajectory.get_type().name()?,
                missing.join(" or ")
            )));
        }
        let [timestamps, positions, orientations] = ATTRIBUTES.map(|name| trajectory.getattr(name));
        let timestamps = timestamps?;
        let (t, positions) = timestamps_and_rows::<3>(py, &timestamps, &positions?, "positions_xyz")?;
        let (_, quaternions_wxyz) =
            timestamps_and_rows::<4>(py, &timestamps, &orientations?, "orientations_quat_wxyz")?;
        let spec = MetricArg::spec_from_py(metric, "Trajectory.from_evo")?;
        let table = loops_io::PoseTable {
            path: PathBuf::from("evo PoseTrajectory3D"),
            timestamps_s: t,
            timestamps_ns: None,
            positions,
            orientations_xyzw: Some(quaternions_wxyz.iter().map(|&[w, x, y, z]| [x, y, z, w]).collect()),
            dim: 3,
            source_lines: Vec::new(),
            messages: None,
        };
        // The table's own conversion picks what the metric needs, as for a file.
        let inner = detached(py, move || trajectory_for(&table, &spec, axes, Source::Memory))?;
        Ok(Self { inner: Arc::new(inner), plane_axes: axes, metric: metric.is_some().then_some(spec) })
    }
}

fn wrap(py: Python<'_>, f: impl FnOnce() -> loops_core::Result<loops_core::Trajectory> + Send) -> PyResult<Trajectory> {
    let inner = detached(py, || Ok(f()?))?;
    Ok(Trajectory { inner: Arc::new(inner), plane_axes: None, metric: None })
}

/// Where a pose table came from: errors name the file, or only poses.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    File,
    Memory,
}

/// The trajectory `spec` needs from `table` ([`loops_io::PoseTable::to_trajectory_for`]); errors
/// name the file when there is one.
pub(crate) fn trajectory_for(
    table: &loops_io::PoseTable,
    spec: &loops_core::MetricSpec,
    axes: Option<(usize, usize)>,
    source: Source,
) -> Result<loops_core::Trajectory, Failure> {
    table.to_trajectory_for(spec, axes.map(|(a, b)| [a, b])).map_err(|error| match error {
        loops_io::IoError::Trajectory { error, .. } if source == Source::Memory => Failure::Core(error),
        other => Failure::from(other),
    })
}

/// The keywords of a synthetic drive (`urban_drive`, `urban_fleet`): each `None` takes the value
/// of the defaults it is applied to.
pub(crate) struct DriveOptions {
    pub(crate) duration_s: Option<f64>,
    pub(crate) rate_hz: Option<f64>,
    pub(crate) city_size_m: Option<f64>,
    pub(crate) block_m: Option<f64>,
    pub(crate) min_speed_mps: Option<f64>,
    pub(crate) max_speed_mps: Option<f64>,
    pub(crate) stop_probability: Option<f64>,
    pub(crate) min_stop_s: Option<f64>,
    pub(crate) max_stop_s: Option<f64>,
    pub(crate) lane_offset_m: Option<f64>,
    pub(crate) lateral_noise_m: Option<f64>,
    pub(crate) seed: Option<u64>,
    pub(crate) district_m: Option<f64>,
    pub(crate) district_dwell_s: Option<f64>,
}

impl DriveOptions {
    /// The drive `d` with the options given.
    ///
    /// # Errors
    /// `district_dwell_s` without `district_m`.
    pub(crate) fn drive(self, d: loops_core::UrbanDrive) -> PyResult<loops_core::UrbanDrive> {
        let districts = match (self.district_m, self.district_dwell_s) {
            (None, None) => d.districts,
            (side, dwell) => loops_core::Districts::from_options(side, dwell).map_err(Failure::Core)?,
        };
        Ok(loops_core::UrbanDrive {
            duration_s: self.duration_s.unwrap_or(d.duration_s),
            rate_hz: self.rate_hz.unwrap_or(d.rate_hz),
            city_size_m: self.city_size_m.unwrap_or(d.city_size_m),
            block_m: self.block_m.unwrap_or(d.block_m),
            min_speed_mps: self.min_speed_mps.unwrap_or(d.min_speed_mps),
            max_speed_mps: self.max_speed_mps.unwrap_or(d.max_speed_mps),
            stop_probability: self.stop_probability.unwrap_or(d.stop_probability),
            min_stop_s: self.min_stop_s.unwrap_or(d.min_stop_s),
            max_stop_s: self.max_stop_s.unwrap_or(d.max_stop_s),
            lane_offset_m: self.lane_offset_m.unwrap_or(d.lane_offset_m),
            lateral_noise_m: self.lateral_noise_m.unwrap_or(d.lateral_noise_m),
            seed: self.seed.unwrap_or(d.seed),
            districts,
            first_district: d.first_district,
        })
    }
}

/// A seeded synthetic drive on a Manhattan grid (x, y, z in metres, 10 Hz by default).
///
/// Every argument left as ``None`` takes the library default: a 1 km² city of 100 m blocks,
/// 2.1 h at 10 Hz (75,600 poses), 5–12 m/s, stops of 5 s – 4 min at some intersections.
/// With ``se3=True`` the poses carry the heading of travel as an orientation (for the ``se3``
/// metrics); otherwise they are positions (x, y, z).
///
/// With ``district_m`` the drive works the city one square district of that side at a time,
/// ``district_dwell_s`` seconds each (default 10,000 s), in snake order: the revisits of a place
/// stay bounded however long the drive, as for a delivery or mapping vehicle. Without it the
/// drive roams the whole city.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=60.0, seed=3)
///     >>> len(traj), traj.dim
///     (600, 3)
///     >>> big = il.urban_drive(duration_s=600.0, city_size_m=10_000.0, district_m=1000.0)
///     >>> bool(big.positions[:, :2].max() < 1005.0)
///     True
#[pyfunction]
#[pyo3(signature = (*, duration_s=None, rate_hz=None, city_size_m=None, block_m=None, min_speed_mps=None,
    max_speed_mps=None, stop_probability=None, min_stop_s=None, max_stop_s=None, lane_offset_m=None,
    lateral_noise_m=None, seed=None, district_m=None, district_dwell_s=None, se3=false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn urban_drive(
    py: Python<'_>,
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
    se3: bool,
) -> PyResult<Trajectory> {
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
    let spec = options.drive(loops_core::UrbanDrive::default())?;
    wrap(py, move || {
        let drive = spec.generate()?;
        if se3 { drive.se3_trajectory() } else { Ok(drive.trajectory) }
    })
}

/// Reads a trajectory file: TUM, CSV, KITTI, EuRoC, TUC, g2o/TORO pose graphs, MCAP logs
/// (ROS 2 and Foxglove pose, odometry and transform messages), rosbag2 bags (sqlite3 or MCAP,
/// compressed or not, split or not) or ROS 1 bags — by ``format``, or told from the extension
/// and first line (a folder is a rosbag2 bag).
///
/// Reading is strict: a repeated timestamp is an error naming its line. With
/// ``drop_duplicate_stamps=True`` the later poses of a repeated stamp are dropped (the first
/// is kept), and a :class:`DroppedInputWarning` per file says how many and on which lines.
///
/// Args:
///     path: the file (or a rosbag2 bag's folder or ``metadata.yaml``), or a list of files read
///         as one trajectory: MCAP files merged by time (a recording split in parts), other
///         files joined in time order (their times must not overlap: an error names both files
///         and the stamps).
///     format: ``"tum"``, ``"csv"``, ``"kitti"``, ``"euroc"``, ``"tuc"``, ``"g2o"``,
///         ``"mcap"``, ``"rosbag2"``, ``"ros1"``, or ``None`` to tell.
///     axes: a plane of two position axes (0 = x, 1 = y, 2 = z), e.g. ``(0, 2)`` for KITTI's
///         ground plane: Euclidean keeps only these coordinates; ``se2`` takes them and the
///         heading in the plane, the rotation about its normal (on x-z, the ground of KITTI's
///         camera frame, about −y: up); ``se3`` and ``so3`` take none. The trajectory remembers
///         it (:attr:`Trajectory.plane_axes`) for the plots.
///     metric: the metric the trajectory is for (as in :func:`find_loops`): positions for
///         Euclidean (the default); positions and orientations for ``se3``; orientations for
///         ``so3``; x, y and yaw about z for ``se2`` (or the plane ``axes`` and the heading in
///         it). Quaternions within ``quaternion_tolerance`` of unit length are normalised.
///         The trajectory keeps it (:attr:`Trajectory.metric_name`): :func:`find_loops` without
///         ``metric=`` measures it so.
///     topic: the topic (MCAP, bags); ``None`` picks the one topic with poses (several: an error
///         listing them, see :func:`list_topics`).
///     time: MCAP and bag times from ``"header"`` stamps (the default), ``"log"`` or ``"publish"`` time.
///     frames: ``(parent, child)`` frame pair of a transform topic (TF); ``None`` takes the
///         topic's only pair. Frames that no one transform links are composed along the TF
///         tree, ``/tf_static`` included (``("map", "velodyne")`` through ``odom`` and
///         ``base_link``), at the stamps of the moving link nearest the child, the others
///         interpolated there.
///     rate_hz: for files without times (KITTI poses, pose graphs): pose i at i / rate_hz s.
///     times: for files without times (KITTI poses, pose graphs): a file of one time a line,
///         seconds, one per pose in order (KITTI's ``sequences/XX/times.txt``).
///     drop_duplicate_stamps: drop the poses whose timestamp repeats the one before, with a
///         warning saying how many (default: they are an error).
///     quaternion_tolerance: how far from unit length a quaternion may be and still be
///         normalised (default 1e-3: files often print 4 decimals).
///     chain_edges: for a pose graph without vertices (a list of edges), chain its odometry
///         edges into a trajectory, with a :class:`DeadReckoningWarning` (see
///         :func:`read_pose_graph`); without it such a file is an error naming this option.
///
/// Raises:
///     OSError: the file cannot be opened. LoopsIOError: a malformed line or message (the
///     message names file, line or byte offset, topic); files whose times overlap.
///     InvalidTrajectoryError: e.g. unsorted or repeated timestamps, a quaternion farther than
///     ``quaternion_tolerance`` from unit length (names the line or message).
///     InvalidParameterError: an unknown format or time source, a metric whose points are not
///     poses (named), bad axes, an empty list, both ``rate_hz`` and ``times``.
///     TypeError: ``path`` is not a str, an ``os.PathLike`` or a list of them.
///
/// Example:
///     >>> import pathlib, tempfile, warnings, inexact_loops as il
///     >>> path = pathlib.Path(tempfile.mkdtemp()) / "desk.tum"
///     >>> _ = path.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n1 2 0 0 0 0 0 1\n2 3 0 0 0 0 0 1\n")
///     >>> with warnings.catch_warnings(record=True) as caught:
///     ...     warnings.simplefilter("always")
///     ...     traj = il.read_trajectory(path, drop_duplicate_stamps=True)
///     >>> len(traj), str(caught[0].message).endswith("dropped 1 pose(s) whose timestamp repeats the one before (line 3)")
///     (3, True)
#[pyfunction]
#[pyo3(signature = (path, *, format=None, axes=None, metric=None, topic=None, time=None, frames=None, rate_hz=None,
    times=None, drop_duplicate_stamps=false, quaternion_tolerance=None, chain_edges=false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn read_trajectory(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    format: Option<String>,
    axes: Option<(usize, usize)>,
    metric: Option<&Bound<'_, PyAny>>,
    topic: Option<String>,
    time: Option<String>,
    frames: Option<(String, String)>,
    rate_hz: Option<f64>,
    times: Option<PathBuf>,
    drop_duplicate_stamps: bool,
    quaternion_tolerance: Option<f64>,
    chain_edges: bool,
) -> PyResult<Trajectory> {
    let args = ReadArgs {
        format,
        axes,
        topic,
        time,
        frames,
        rate_hz,
        times,
        drop_duplicate_stamps,
        quaternion_tolerance,
        chain_edges,
    };
    read_trajectory_with(py, path, metric, args)
}

/// The keywords of :func:`read_trajectory` besides the path and the metric: how files are read,
/// by `read_trajectory` and by every surface that reads sessions from paths (`Fleet`,
/// `FleetStore.update`, through `py_fleet::read_sessions`).
#[derive(Debug, Clone, Default)]
pub(crate) struct ReadArgs {
    pub(crate) format: Option<String>,
    pub(crate) axes: Option<(usize, usize)>,
    pub(crate) topic: Option<String>,
    pub(crate) time: Option<String>,
    pub(crate) frames: Option<(String, String)>,
    pub(crate) rate_hz: Option<f64>,
    pub(crate) times: Option<PathBuf>,
    pub(crate) drop_duplicate_stamps: bool,
    pub(crate) quaternion_tolerance: Option<f64>,
    pub(crate) chain_edges: bool,
}

impl ReadArgs {
    /// The reader's options: the one place these keywords become [`loops_io::ReadOptions`].
    ///
    /// # Errors
    /// An unknown format or time source; both `rate_hz` and `times`.
    pub(crate) fn options(self) -> Result<loops_io::ReadOptions, Failure> {
        let mut mcap = loops_io::McapOptions::default();
        if let Some(topic) = self.topic {
            mcap = mcap.topic(topic);
        }
        if let Some(time) = self.time {
            mcap = mcap.time(time.parse()?);
        }
        if let Some((parent, child)) = self.frames {
            mcap = mcap.frames(parent, child);
        }
        let mut options = loops_io::ReadOptions::default().mcap(mcap);
        if let Some(format) = self.format {
            options = options.format(format.parse()?);
        }
        Ok(options
            .timing(loops_io::Timing::given(self.rate_hz, self.times)?)
            .chain_edges(self.chain_edges)
            .drop_duplicate_stamps(self.drop_duplicate_stamps)
            .quaternion_tolerance(self.quaternion_tolerance))
    }
}

/// :func:`read_trajectory` of `path` (one path or a list) with `args`.
pub(crate) fn read_trajectory_with(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    metric: Option<&Bound<'_, PyAny>>,
    args: ReadArgs,
) -> PyResult<Trajectory> {
    let paths = paths_of(path)?;
    let spec = MetricArg::spec_from_py(metric, "read_trajectory")?;
    let axes = args.axes;
    let options = args.options()?;
    let (inner, dropped, chains) = detached(py, move || {
        let read = loops_io::read_trajectories(&paths, &options, &spec, axes.map(|(a, b)| [a, b]))?;
        let chains = read.notes.iter().filter_map(|notes| notes.chain.clone()).collect::<Vec<_>>();
        let skipped = read.notes.into_iter().filter_map(|notes| notes.skipped).collect::<Vec<_>>();
        Ok::<_, Failure>((read.trajectory, read.dropped, (chains, skipped)))
    })?;
    let (chains, skipped) = chains;
    for chain in chains {
        crate::warning::warn_dead_reckoning(py, &chain.to_string())?;
    }
    for records in skipped {
        crate::warning::warn_dropped_input(py, &records.to_string())?;
    }
    for dropped in dropped {
        warn_dropped(
            py,
            &dropped,
            "drop_duplicate_stamps=True dropped",
            "pose(s) whose timestamp repeats the one before",
        )?;
    }
    Ok(Trajectory { inner: Arc::new(inner), plane_axes: axes, metric: metric.is_some().then_some(spec) })
}

/// A `DroppedInputWarning` saying what a lenient option dropped from a file (nothing when it
/// dropped nothing): `desk.tum: drop_duplicate_stamps=True dropped 1 pose(s) whose ... (line 10863)`.
pub(crate) fn warn_dropped(py: Python<'_>, dropped: &loops_io::Dropped, option: &str, what: &str) -> PyResult<()> {
    if dropped.is_empty() {
        return Ok(());
    }
    let lines = dropped.lines_text().map_or(String::new(), |lines| format!(" ({lines})"));
    let message = format!("{}: {option} {} {what}{lines}", dropped.path.display(), dropped.count);
    crate::warning::warn_dropped_input(py, &message)
}

/// `read_trajectory`'s `path`: one path, or a non-empty list of them.
fn paths_of(path: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    if let Ok(one) = path.extract::<PathBuf>() {
        return Ok(vec![one]);
    }
    let not_a_path = |what: String, obj: &Bound<'_, PyAny>| -> PyResult<PyErr> {
        Ok(PyTypeError::new_err(format!("{what}, got {}", obj.get_type().name()?)))
    };
    if !(path.is_instance_of::<PyList>() || path.is_instance_of::<PyTuple>()) {
        return Err(not_a_path("path must be a str or an os.PathLike, or a list of them".into(), path)?);
    }
    let mut paths = Vec::new();
    for (index, item) in path.try_iter()?.enumerate() {
        let item = item?;
        match item.extract::<PathBuf>() {
            Ok(one) => paths.push(one),
            Err(_) => return Err(not_a_path(format!("path[{index}] must be a str or an os.PathLike"), &item)?),
        }
    }
    if paths.is_empty() {
        return Err(crate::error::invalid_parameter("path is an empty list: give a file, or a list of files".into()));
    }
    Ok(paths)
}

/// The name a pose log gives its session (or its folder of results): the file's stem, or a
/// rosbag2 bag's folder name however the bag is given (its folder, ``metadata.yaml`` or a storage
/// file; a storage file of a split bag adds its own stem). ``loops run``, ``loops fleet``,
/// :class:`Fleet` and ``inexact_loops.dask`` all name sessions by this one rule.
///
/// Example:
///     >>> from inexact_loops import _core
///     >>> _core.log_name("logs/monday.tum"), _core.log_name("logs/monday.db3.zstd")
///     ('monday', 'monday')
#[pyfunction]
pub(crate) fn log_name(path: PathBuf) -> String {
    loops_io::log_name(path)
}

/// The topics of an MCAP file, a rosbag2 bag (its folder, ``metadata.yaml`` or a storage
/// file) or a ROS 1 bag: one dict per topic with ``topic``, ``schema``,
/// ``encoding``, ``messages``, ``start_ns`` and ``end_ns`` (log time, ``None`` when empty) and
/// ``pose_type`` (the pose message type the library reads from it, or ``None``).
///
/// Raises:
///     OSError: the file cannot be opened. LoopsIOError: not a valid MCAP file or bag (names
///     the offset, or the sqlite row).
#[pyfunction]
pub(crate) fn list_topics<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Vec<Bound<'py, pyo3::types::PyDict>>> {
    let topics = detached(py, move || Ok(loops_io::list_topics(&path)?))?;
    topics
        .into_iter()
        .map(|info| {
            let row = pyo3::types::PyDict::new(py);
            row.set_item("topic", info.topic)?;
            row.set_item("schema", info.schema_name)?;
            row.set_item("encoding", info.message_encoding)?;
            row.set_item("messages", info.message_count)?;
            row.set_item("start_ns", info.log_time_span_ns.map(|span| span.0))?;
            row.set_item("end_ns", info.log_time_span_ns.map(|span| span.1))?;
            row.set_item("pose_type", info.pose_type.map(|t| t.schema_name()))?;
            Ok(row)
        })
        .collect()
}

/// `Trajectory.nearest_poses`: the pose nearest each time.
pub(crate) fn nearest_poses<'py>(
    py: Python<'py>,
    traj: &Arc<loops_core::Trajectory>,
    times_s: &Bound<'_, PyAny>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let times = real_column(py, times_s, "times_s")?;
    let traj = Arc::clone(traj);
    let poses = detached(py, move || Ok(traj.nearest_poses(&times)?))?;
    Ok(to_numpy(py, poses.into_iter().map(|i| i as i64).collect()))
}
