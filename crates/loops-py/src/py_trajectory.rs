//! `Trajectory`, `urban_drive` and `read_trajectory`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::convert::{timestamps_and_points, to_numpy};
use crate::detached;

/// A sampled trajectory: strictly increasing timestamps (seconds) and one point per timestamp.
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
}

#[pymethods]
impl Trajectory {
    #[new]
    fn new(py: Python<'_>, timestamps: &Bound<'_, PyAny>, positions: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (t, coords, dim) = timestamps_and_points(py, timestamps, positions, "positions")?;
        let inner = detached(py, || Ok(loops_core::Trajectory::new(t, coords, dim)?))?;
        Ok(Self { inner: Arc::new(inner) })
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Trajectory({} poses, dim {}, {:.3} s from t = {})",
            self.inner.len(),
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
}

/// A seeded synthetic drive on a Manhattan grid (x, y, z in metres, 10 Hz by default).
///
/// Every argument left as ``None`` takes the library default: a 1 km² city of 100 m blocks,
/// 2.1 h at 10 Hz (75,600 poses), 5–12 m/s, stops of 5 s – 4 min at some intersections.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=60.0, seed=3)
///     >>> len(traj), traj.dim
///     (600, 3)
#[pyfunction]
#[pyo3(signature = (*, duration_s=None, rate_hz=None, city_size_m=None, block_m=None, min_speed_mps=None,
    max_speed_mps=None, stop_probability=None, min_stop_s=None, max_stop_s=None, lane_offset_m=None,
    lateral_noise_m=None, seed=None))]
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
) -> PyResult<Trajectory> {
    let d = loops_core::UrbanDrive::default();
    let spec = loops_core::UrbanDrive {
        duration_s: duration_s.unwrap_or(d.duration_s),
        rate_hz: rate_hz.unwrap_or(d.rate_hz),
        city_size_m: city_size_m.unwrap_or(d.city_size_m),
        block_m: block_m.unwrap_or(d.block_m),
        min_speed_mps: min_speed_mps.unwrap_or(d.min_speed_mps),
        max_speed_mps: max_speed_mps.unwrap_or(d.max_speed_mps),
        stop_probability: stop_probability.unwrap_or(d.stop_probability),
        min_stop_s: min_stop_s.unwrap_or(d.min_stop_s),
        max_stop_s: max_stop_s.unwrap_or(d.max_stop_s),
        lane_offset_m: lane_offset_m.unwrap_or(d.lane_offset_m),
        lateral_noise_m: lateral_noise_m.unwrap_or(d.lateral_noise_m),
        seed: seed.unwrap_or(d.seed),
    };
    let drive = detached(py, || Ok(spec.generate()?))?;
    Ok(Trajectory { inner: Arc::new(drive.trajectory) })
}

/// Reads a trajectory file: TUM (``t x y z qx qy qz qw``) or CSV (``t,x,y[,z]``, header
/// optional), chosen by ``format`` or guessed from the extension (``.csv`` is CSV, anything
/// else TUM).
///
/// Args:
///     path: the file.
///     format: ``"tum"``, ``"csv"`` or ``None`` to guess.
///     axes: keep only these position axes, e.g. ``(0, 2)`` for KITTI's ground plane; ``None``
///         keeps all.
///
/// Raises:
///     OSError: the file cannot be opened. LoopsIOError: a malformed line (the message names
///     file, line and column). InvalidTrajectoryError: e.g. unsorted timestamps (names the line).
#[pyfunction]
#[pyo3(signature = (path, *, format=None, axes=None))]
pub(crate) fn read_trajectory(
    py: Python<'_>,
    path: PathBuf,
    format: Option<String>,
    axes: Option<(usize, usize)>,
) -> PyResult<Trajectory> {
    let inner = detached(py, || {
        let format = format.map(|name| name.parse::<loops_io::Format>()).transpose()?;
        let table = loops_io::read_trajectory(&path, format)?;
        Ok(match axes {
            None => table.to_trajectory()?,
            Some((a, b)) => table.to_trajectory_plane([a, b])?,
        })
    })?;
    Ok(Trajectory { inner: Arc::new(inner) })
}
