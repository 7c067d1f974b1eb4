//! The (t, t′) plane of `loops_core::plane`: `distance_image`, the outlines and isocontours of
//! images, and `sampler_symbol`. What belongs to a class lives with it, below this module in
//! the crate's order: `PlaneGrid` and `Loops.label_image`, `Loops.components_of_pairs`,
//! `Loops.pair_counts_per_component` in `py_loops`, `Trajectory.nearest_poses` in
//! `py_trajectory`.
//!
//! Images are numpy arrays of shape `(height, width)`, row 0 the earliest t′ (the core's
//! row-major order); label images are int64 with −1 where a pixel has no component.

use std::sync::Arc;

use numpy::{PyArray2, PyArray3, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{real_array, to_numpy};
use crate::detached;
use crate::error::{Failure, value_error};
use crate::py_loops::PlaneGrid;
use crate::py_metric::{MetricArg, MetricRef};
use crate::py_trajectory::Trajectory;
use loops_core::{SamplerKind, plane::Border};

/// The pairwise distance π(t, t′) = δ(ξ(t), ξ(t′)) on a grid: ``image[b, a]`` is δ between the
/// column pose ``grid.columns[a]`` and the row pose ``grid.rows[b]``, in the metric's unit, for
/// any metric (SE(3), SO(3), ...). Rows are computed in parallel without the GIL; the cost is one
/// distance per pixel, whatever the trajectory's length.
///
/// Args:
///     trajectory: the :class:`Trajectory`.
///     grid: a :class:`PlaneGrid` made for it.
///     metric: as :func:`find_loops`: ``None`` (the trajectory's own, :attr:`Trajectory.metric_name`),
///         a name such as ``"so3"``, an :mod:`inexact_loops.metrics` object, or — slow, one
///         Python call per pixel on one thread — a callable ``f(a, b) -> float``.
///     threads: worker threads; ``None`` uses one per core.
///
/// Returns:
///     float64 array, shape ``(grid.height, grid.width)``.
///
/// Raises:
///     InvalidParameterError: a grid made for another number of poses, an unknown metric.
///     InvalidTrajectoryError: a trajectory the metric cannot take (e.g. not unit quaternions).
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> s = np.sqrt(0.5)  # rotations about z by 0, 90° and 180°
///     >>> traj = il.Trajectory.so3(np.arange(3.0), [[0, 0, 0, 1.0], [0, 0, s, s], [0, 0, 1.0, 0]])
///     >>> image = il.distance_image(traj, il.PlaneGrid(traj, 8), metric="so3")
///     >>> np.round(image / np.pi, 6).tolist()
///     [[0.0, 0.5, 1.0], [0.5, 0.0, 0.5], [1.0, 0.5, 0.0]]
#[pyfunction]
#[pyo3(signature = (trajectory, grid, *, metric=None, threads=None))]
pub(crate) fn distance_image<'py>(
    py: Python<'py>,
    trajectory: &Trajectory,
    grid: &PlaneGrid,
    metric: Option<&Bound<'_, PyAny>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (traj, plane) = (Arc::clone(&trajectory.inner), Arc::clone(&grid.inner));
    let image =
        MetricArg::or_default(metric, trajectory.default_metric())?.run(py, threads, |metric| match metric {
            MetricRef::Spec(spec) => spec.distance_image(&traj, &plane),
            MetricRef::Callable(callable) => loops_core::plane::distance_image(&traj, callable, &plane),
        })?;
    to_numpy(py, image).reshape([grid.inner.height(), grid.inner.width()])
}

/// A 2-D array `(height, width)` of numbers: its values row-major, its width and height.
fn image(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str, integers: bool) -> PyResult<(Vec<f64>, usize, usize)> {
    if integers {
        let numpy = py.import("numpy")?;
        let array = numpy.call_method1("asarray", (obj,))?;
        let kind = array.cast::<PyUntypedArray>().map(|a| a.dtype().kind()).ok();
        if !matches!(kind, Some(b'i' | b'u')) {
            return Err(PyTypeError::new_err(format!("{name} must be an array of integer labels")));
        }
    }
    let array = real_array(py, obj, name)?;
    match array.shape[..] {
        [height, width] => Ok((array.values, width, height)),
        _ => Err(value_error(format!("{name} must be 2-dimensional (height, width), got shape {:?}", array.shape))),
    }
}

/// A label image from Python: negative values are no component.
fn labels(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<Option<u32>>, usize, usize)> {
    let (values, width, height) = image(py, obj, "labels", true)?;
    let labels = values
        .into_iter()
        .map(|v| match v {
            v if v < 0.0 => Ok(None),
            v if v <= f64::from(u32::MAX) => Ok(Some(v as u32)),
            v => Err(value_error(format!("labels: {v} is not a component id (at most {})", u32::MAX))),
        })
        .collect::<PyResult<_>>()?;
    Ok((labels, width, height))
}

/// The edges of [`outline_segments`]: their vertices `(k, 2, 2)` and the labels on their sides
/// `(k, 2)`.
type EdgesAndSides<'py> = (Bound<'py, PyArray3<i64>>, Bound<'py, PyArray2<i64>>);

/// The edges of the pixel lattice where the label changes: the outlines ∂Ω of the components
/// of a label image (as :meth:`Loops.label_image` gives), vertical edges first (row by row,
/// left to right), then horizontal ones (bottom to top). In pixel units: column a spans
/// x ∈ [a, a + 1], row b spans y ∈ [b, b + 1].
///
/// Args:
///     labels: integer array ``(height, width)``, negative where a pixel has no component.
///     border: ``"closed"`` (nothing lies outside the image: components touching the border
///         are closed along it) or ``"open"`` (the image continues its outermost pixels: no
///         edges along the border, a component cut by a zoom window stays open).
///
/// Returns:
///     ``(edges, sides)``: int64 arrays ``(k, 2, 2)``, each edge's two vertices ``[x, y]`` (the
///     second one up or to the right of the first), and ``(k, 2)``, the labels on its two sides
///     (left and right of a vertical edge, below and above a horizontal one; −1 for none).
///
/// Raises:
///     ValueError: ``labels`` not 2-dimensional. TypeError: not integers.
///     InvalidParameterError: an unknown ``border``.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> labels = np.full((3, 3), -1)
///     >>> labels[1, 1] = 7  # one pixel: its four sides
///     >>> edges, sides = il.outline_segments(labels)
///     >>> edges.shape, sides.tolist()
///     ((4, 2, 2), [[-1, 7], [7, -1], [-1, 7], [7, -1]])
///     >>> edges[0].tolist()  # the left side of the pixel, upwards
///     [[1, 1], [1, 2]]
///     >>> len(il.outline_segments(np.ones((2, 2), int), border="open")[0])
///     0
#[pyfunction]
#[pyo3(signature = (labels, *, border="closed"))]
pub(crate) fn outline_segments<'py>(
    py: Python<'py>,
    labels: &Bound<'_, PyAny>,
    border: &str,
) -> PyResult<EdgesAndSides<'py>> {
    let border: Border = border.parse().map_err(Failure::from)?;
    let (labels, width, height) = self::labels(py, labels)?;
    let edges = detached(py, move || Ok(loops_core::plane::outline_segments(&labels, width, height, border)?))?;
    let vertices = edges.iter().flat_map(|e| [e.start, e.end]).flatten().map(i64::from).collect();
    let sides = edges.iter().flat_map(|e| e.sides).map(|c| c.map_or(-1, i64::from)).collect();
    Ok((to_numpy(py, vertices).reshape([edges.len(), 2, 2])?, to_numpy(py, sides).reshape([edges.len(), 2])?))
}

/// The outline of each component of a label image as polylines of pixel corners: the edges of
/// :func:`outline_segments` with that component on either side, joined by
/// :func:`chain_polylines`. With ``border="closed"`` every polyline is closed (its last vertex
/// is its first), so it can be filled (even-odd: holes stay empty).
///
/// Args:
///     labels, border: as :func:`outline_segments`.
///
/// Returns:
///     ``{component id: [polyline, ...]}``, each polyline an int64 array ``(m, 2)`` of
///     vertices ``[x, y]`` in pixel units; ids in increasing order.
///
/// Raises:
///     As :func:`outline_segments`.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> labels = np.array([[4, 4, -1], [-1, -1, -1]])  # a 2 × 1 component, bottom left
///     >>> outlines = il.component_outlines(labels)
///     >>> list(outlines), outlines[4][0].tolist()
///     ([4], [[0, 0], [0, 1], [1, 1], [2, 1], [2, 0], [1, 0], [0, 0]])
#[pyfunction]
#[pyo3(signature = (labels, *, border="closed"))]
pub(crate) fn component_outlines<'py>(
    py: Python<'py>,
    labels: &Bound<'_, PyAny>,
    border: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let border: Border = border.parse().map_err(Failure::from)?;
    let (labels, width, height) = self::labels(py, labels)?;
    let outlines = detached(py, move || Ok(loops_core::plane::component_outlines(&labels, width, height, border)?))?;
    let dict = PyDict::new(py);
    for (id, lines) in outlines {
        let lines = lines.into_iter().map(|line| points(py, &line)).collect::<PyResult<Vec<_>>>()?;
        dict.set_item(id, lines)?;
    }
    Ok(dict)
}

/// Vertices `[x, y]` as an int64 array `(m, 2)`.
fn points<'py>(py: Python<'py>, line: &[[u32; 2]]) -> PyResult<Bound<'py, PyArray2<i64>>> {
    to_numpy(py, line.iter().flatten().map(|&v| i64::from(v)).collect()).reshape([line.len(), 2])
}

/// Joins edges into polylines, each edge used once; a closed polyline ends with its first
/// vertex. Deterministic: a polyline starts at the first unused edge in input order and is
/// extended forwards, then backwards, each time along the first unused edge at its end.
///
/// Args:
///     edges: integer array ``(k, 2)`` of vertex ids, or ``(k, 2, 2)`` of vertices ``[x, y]``
///         (the edges of :func:`outline_segments`), either direction.
///
/// Returns:
///     A list of int64 arrays: ``(m,)`` vertex ids, or ``(m, 2)`` vertices.
///
/// Raises:
///     ValueError: another shape. TypeError: not integers.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> [line.tolist() for line in il.chain_polylines([[0, 1], [2, 3], [1, 2], [3, 0], [5, 6]])]
///     [[0, 1, 2, 3, 0], [5, 6]]
#[pyfunction]
pub(crate) fn chain_polylines<'py>(py: Python<'py>, edges: &Bound<'_, PyAny>) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (edges,))?;
    let untyped = array.cast::<PyUntypedArray>().map_err(|_| PyTypeError::new_err("edges must be an array"))?;
    let shape = untyped.shape().to_vec();
    let kind = untyped.dtype().kind();
    if !(matches!(kind, b'i' | b'u') || untyped.len() == 0) {
        return Err(PyTypeError::new_err("edges must hold integers (vertex ids or vertices)"));
    }
    let values = real_array(py, &array, "edges")?.values;
    let vertex = |v: f64| v as i64;
    match shape[..] {
        [_, 2] => {
            let edges: Vec<[i64; 2]> = values.chunks_exact(2).map(|e| [vertex(e[0]), vertex(e[1])]).collect();
            let lines = detached(py, move || Ok(loops_core::plane::chain_polylines(&edges)))?;
            Ok(lines.into_iter().map(|line| to_numpy(py, line).into_any()).collect())
        }
        [_, 2, 2] => {
            let edges: Vec<[[i64; 2]; 2]> =
                values.chunks_exact(4).map(|e| [[vertex(e[0]), vertex(e[1])], [vertex(e[2]), vertex(e[3])]]).collect();
            let lines = detached(py, move || Ok(loops_core::plane::chain_polylines(&edges)))?;
            lines
                .into_iter()
                .map(|line| {
                    Ok(to_numpy(py, line.iter().flatten().copied().collect()).reshape([line.len(), 2])?.into_any())
                })
                .collect()
        }
        _ => Err(value_error(format!("edges must have shape (k, 2) or (k, 2, 2), got {shape:?}"))),
    }
}

/// The ``level`` isocontour of an image by marching squares on the pixel centres (pixel
/// (a, b) at (a + ½, b + ½)), as polylines of points ``[x, y]`` in pixel units, crossings placed
/// by linear interpolation; saddles resolved by the mean of the cell's corners, NaN counted as
/// above the level. For the γ isocontour of π, pass a :func:`distance_image` and γ.
///
/// Args:
///     values: real array ``(height, width)``.
///     level: the level.
///
/// Returns:
///     A list of float64 arrays ``(m, 2)``; a closed line ends with its first point.
///
/// Raises:
///     ValueError: ``values`` not 2-dimensional. TypeError: not real numbers.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> b, a = np.mgrid[0:9, 0:9]
///     >>> cone = np.hypot(a - 4.0, b - 4.0)  # 0 at the pixel centre (4.5, 4.5)
///     >>> (line,) = il.isocontour(cone, 2.5)
///     >>> bool((line[0] == line[-1]).all()), bool(np.allclose(np.hypot(*(line - 4.5).T), 2.5, atol=0.3))
///     (True, True)
#[pyfunction]
pub(crate) fn isocontour<'py>(
    py: Python<'py>,
    values: &Bound<'_, PyAny>,
    level: f64,
) -> PyResult<Vec<Bound<'py, PyArray2<f64>>>> {
    let (values, width, height) = image(py, values, "values", false)?;
    let lines = detached(py, move || Ok(loops_core::plane::isocontour(&values, width, height, level)?))?;
    lines
        .into_iter()
        .map(|line| to_numpy(py, line.iter().flatten().copied().collect()).reshape([line.len(), 2]))
        .collect()
}

/// The symbol of a sampler in the paper (``"σ_1"``, ``"σ_ρ"``, ``"σ_α"``), or the name of the
/// system whose rule a baseline follows (``"LIO-SAM"``, ...): for figures and reports.
///
/// Args:
///     sampler: a sampler's name, as :func:`sample` takes it (``"one"``, ``"rho"``, ...).
///
/// Raises:
///     InvalidParameterError: an unknown sampler (the message lists the names).
///
/// Example:
///     >>> import inexact_loops as il
///     >>> il.sampler_symbol("rho"), il.sampler_symbol("lio-sam")
///     ('σ_ρ', 'LIO-SAM')
#[pyfunction]
pub(crate) fn sampler_symbol(sampler: &str) -> PyResult<&'static str> {
    let kind: SamplerKind = sampler.parse().map_err(Failure::from)?;
    Ok(kind.symbol())
}
