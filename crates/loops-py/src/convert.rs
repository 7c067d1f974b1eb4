//! numpy arrays in and out: the one place the bindings turn Python arguments into Rust buffers
//! and Rust results into numpy columns and `Table`s.

use numpy::{
    PyArray1, PyArrayDescrMethods, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyIndexError, PyTypeError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{IntoPyDict, PyType};

use crate::error::value_error;

/// A real-valued array of any memory order, copied to row-major `f64`, with its shape.
pub(crate) struct Real {
    pub values: Vec<f64>,
    pub shape: Vec<usize>,
}

/// Reads `obj` (a numpy array or anything `numpy.asarray` takes) as real numbers, in logical
/// (row-major) order whatever its memory layout: Fortran-ordered and strided arrays are read
/// element by element, never reinterpreted.
///
/// # Errors
/// `TypeError` for non-numeric, boolean or complex dtypes, naming `name` and the dtype.
pub(crate) fn real_array(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Real> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (obj,))?;
    let untyped = array
        .cast::<PyUntypedArray>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an array of real numbers")))?;
    let dtype = untyped.dtype();
    if !matches!(dtype.kind(), b'f' | b'i' | b'u') {
        return Err(PyTypeError::new_err(format!(
            "{name} must hold real numbers (float or integer dtype), got dtype {}",
            dtype.str()?
        )));
    }
    let as_f64 = numpy.call_method("asarray", (array,), Some(&[("dtype", "float64")].into_py_dict(py)?))?;
    let view: PyReadonlyArrayDyn<'_, f64> = as_f64.extract()?;
    let shape = view.shape().to_vec();
    // The copy grows with the input: allocated fallibly, an `OutOfMemoryError` and not an abort.
    let mut values = Vec::new();
    if values.try_reserve_exact(view.len()).is_err() {
        let bytes = (view.len() as u128 * 8).min(u64::MAX as u128) as u64;
        return Err(
            crate::error::Failure::from(loops_core::Error::OutOfMemory { what: "a copy of an array", bytes }).into()
        );
    }
    match view.as_slice() {
        Ok(slice) if view.is_c_contiguous() => values.extend_from_slice(slice),
        _ => values.extend(view.as_array().iter().copied()),
    }
    Ok(Real { values, shape })
}

/// A 1-D array of real numbers.
pub(crate) fn real_column(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
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
pub(crate) fn index_column(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<usize>> {
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

/// Timestamps `(n,)` and points `(n,)` or `(n, d)` as flat buffers and a dimension.
///
/// # Errors
/// `ValueError` for wrong numbers of dimensions or mismatched lengths; `TypeError` for dtypes.
pub(crate) fn timestamps_and_points(
    py: Python<'_>,
    timestamps: &Bound<'_, PyAny>,
    points: &Bound<'_, PyAny>,
    points_name: &str,
) -> PyResult<(Vec<f64>, Vec<f64>, usize)> {
    let t = real_column(py, timestamps, "timestamps")?;
    let p = real_array(py, points, points_name)?;
    let dim = match p.shape.as_slice() {
        [_] => 1,
        [_, d] => *d,
        shape => {
            return Err(value_error(format!("{points_name} must have shape (n,) or (n, d), got shape {shape:?}")));
        }
    };
    if p.shape[0] != t.len() {
        return Err(value_error(format!("timestamps has {} rows but {points_name} has {}", t.len(), p.shape[0])));
    }
    Ok((t, p.values, dim))
}

/// Timestamps and points of exactly `D` coordinates each, as fixed-size rows.
///
/// # Errors
/// As [`timestamps_and_points`]; `ValueError` when rows do not have `D` columns.
pub(crate) fn timestamps_and_rows<const D: usize>(
    py: Python<'_>,
    timestamps: &Bound<'_, PyAny>,
    points: &Bound<'_, PyAny>,
    points_name: &str,
) -> PyResult<(Vec<f64>, Vec<[f64; D]>)> {
    let (t, values, dim) = timestamps_and_points(py, timestamps, points, points_name)?;
    if dim != D {
        return Err(value_error(format!("{points_name} must have shape (n, {D}), got {dim} columns")));
    }
    let (rows, _) = values.as_chunks::<D>();
    Ok((t, rows.to_vec()))
}

/// For a Python list (not an array) of rows: `ValueError` naming the first row whose length
/// differs from the first row's, before numpy reports a shapeless "inhomogeneous" error.
pub(crate) fn check_rows_equal_length(rows: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    if rows.cast::<PyUntypedArray>().is_ok() {
        return Ok(());
    }
    let Ok(iter) = rows.try_iter() else { return Ok(()) };
    let mut first: Option<usize> = None;
    for (index, row) in iter.enumerate() {
        let Ok(len) = row?.len() else { return Ok(()) };
        match first {
            None => first = Some(len),
            Some(expected) if expected != len => {
                return Err(value_error(format!(
                    "{name} row {index} has {len} values but row 0 has {expected}: rows must be of equal length"
                )));
            }
            Some(_) => {}
        }
    }
    Ok(())
}

/// A Python int as a pose index, before it is checked against a trajectory.
///
/// # Errors
/// `IndexError` naming `name` and the value when it is negative.
pub(crate) fn pose_index(value: i64, name: &str) -> PyResult<usize> {
    usize::try_from(value)
        .map_err(|_| PyIndexError::new_err(format!("{name} = {value} is not a pose index (negative)")))
}

/// A new 1-D numpy array.
pub(crate) fn to_numpy<'py, T: numpy::Element>(py: Python<'py>, values: Vec<T>) -> Bound<'py, PyArray1<T>> {
    PyArray1::from_vec(py, values)
}

/// A numpy column of the first `len` of `values`, allocated fallibly: a column too big for
/// memory is an `OutOfMemoryError` naming `what` and its size, not an abort.
pub(crate) fn try_column<'py, T: numpy::Element>(
    py: Python<'py>,
    len: usize,
    values: impl Iterator<Item = T>,
    what: &'static str,
) -> PyResult<Bound<'py, PyArray1<T>>> {
    let mut column = Vec::new();
    if column.try_reserve_exact(len).is_err() {
        let bytes = (len as u128 * size_of::<T>() as u128).min(u64::MAX as u128) as u64;
        return Err(crate::error::Failure::from(loops_core::Error::OutOfMemory { what, bytes }).into());
    }
    column.extend(values.take(len));
    Ok(to_numpy(py, column))
}

/// An optional column as a numpy array, `None` when no row has a value.
pub(crate) fn optional_column<'py, T: numpy::Element + Copy>(
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
pub(crate) fn id_column<'py>(
    py: Python<'py>,
    values: impl Iterator<Item = Option<usize>>,
) -> Bound<'py, PyArray1<i64>> {
    to_numpy(py, values.map(|v| v.map_or(-1, |v| v as i64)).collect())
}

/// A table column of `rows`, one value each, as int64 (ids, indices and counts).
pub(crate) fn int64_column<'py, R>(py: Python<'py>, rows: &[R], value: impl Fn(&R) -> usize) -> Bound<'py, PyAny> {
    to_numpy(py, rows.iter().map(|row| value(row) as i64).collect()).into_any()
}

/// A table column of `rows`, one value each, as float64.
pub(crate) fn float64_column<'py, R>(py: Python<'py>, rows: &[R], value: impl Fn(&R) -> f64) -> Bound<'py, PyAny> {
    to_numpy(py, rows.iter().map(value).collect()).into_any()
}

/// A table column of `rows`, one value each, as bool.
pub(crate) fn bool_column<'py, R>(py: Python<'py>, rows: &[R], value: impl Fn(&R) -> bool) -> Bound<'py, PyAny> {
    to_numpy(py, rows.iter().map(value).collect()).into_any()
}

/// A table column of names as a numpy array of `str` (dtype `<U…`; `<U1` when empty).
pub(crate) fn str_column<'py, 'a>(
    py: Python<'py>,
    values: impl IntoIterator<Item = &'a str>,
) -> PyResult<Bound<'py, PyAny>> {
    let list = pyo3::types::PyList::new(py, values)?;
    let numpy = py.import("numpy")?;
    if list.is_empty() {
        return numpy.call_method1("array", (list, "<U1"));
    }
    numpy.call_method1("array", (list,))
}

/// The Python class of tabular results (`inexact_loops/table.py`: a `dict` of numpy columns with
/// `to_pandas()`), imported once.
static TABLE: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// A `Table` holding `columns` in the order given.
pub(crate) fn table<'py>(
    py: Python<'py>,
    columns: impl IntoIterator<Item = (&'static str, Bound<'py, PyAny>)>,
) -> PyResult<Bound<'py, PyAny>> {
    let table = TABLE.import(py, "inexact_loops.table", "Table")?.call0()?;
    for (name, column) in columns {
        table.set_item(name, column)?;
    }
    Ok(table)
}

/// A `pandas.DataFrame` of `columns` in the order given (columns that are `None` are left out).
///
/// # Errors
/// `ImportError` when pandas is not installed.
pub(crate) fn data_frame<'py>(
    py: Python<'py>,
    columns: impl IntoIterator<Item = Option<(&'static str, Bound<'py, PyAny>)>>,
) -> PyResult<Bound<'py, PyAny>> {
    table(py, columns.into_iter().flatten())?.call_method0("to_pandas")
}

/// The measure columns of a components table ([`loops_io::MEASURE_COLUMNS`], named and ordered
/// as in `components.csv`) of `rows`.
pub(crate) fn measure_columns<'py>(
    py: Python<'py>,
    rows: &[loops_io::ComponentMeasures],
) -> [(&'static str, Bound<'py, PyAny>); 6] {
    let [trivial, area_s2, pair_count, pose_pair_count, run_count, holes] = loops_io::MEASURE_COLUMNS;
    [
        (trivial, bool_column(py, rows, |m| m.trivial)),
        (area_s2, float64_column(py, rows, |m| m.area_s2)),
        (pair_count, int64_column(py, rows, |m| m.pair_count as usize)),
        (pose_pair_count, int64_column(py, rows, |m| m.pose_pair_count as usize)),
        (run_count, int64_column(py, rows, |m| m.run_count)),
        (holes, int64_column(py, rows, |m| m.holes as usize)),
    ]
}

/// The closest pair's position columns of a components table
/// ([`loops_io::CLOSEST_POSITION_COLUMNS`], named and ordered as in `components.csv`) of `rows`,
/// float64, NaN where unknown.
pub(crate) fn closest_position_columns<'py>(
    py: Python<'py>,
    rows: &[loops_io::ClosestPositions],
) -> [(&'static str, Bound<'py, PyAny>); 6] {
    let [ix, iy, iz, jx, jy, jz] = loops_io::CLOSEST_POSITION_COLUMNS;
    let value = |v: Option<f64>| v.unwrap_or(f64::NAN);
    [
        (ix, float64_column(py, rows, |p| value(p.closest_i_x))),
        (iy, float64_column(py, rows, |p| value(p.closest_i_y))),
        (iz, float64_column(py, rows, |p| value(p.closest_i_z))),
        (jx, float64_column(py, rows, |p| value(p.closest_j_x))),
        (jy, float64_column(py, rows, |p| value(p.closest_j_y))),
        (jz, float64_column(py, rows, |p| value(p.closest_j_z))),
    ]
}

/// The extent columns of a components table ([`loops_io::EXTENT_COLUMNS`], named and ordered
/// as in `components.csv`) of `rows`.
pub(crate) fn extent_columns<'py>(
    py: Python<'py>,
    rows: &[loops_io::ComponentExtent],
) -> [(&'static str, Bound<'py, PyAny>); 11] {
    let [
        i_min,
        i_max,
        j_min,
        j_max,
        t_min_s,
        t_max_s,
        t_prime_min_s,
        t_prime_max_s,
        closest_i,
        closest_j,
        closest_distance,
    ] = loops_io::EXTENT_COLUMNS;
    [
        (i_min, int64_column(py, rows, |e| e.i_min)),
        (i_max, int64_column(py, rows, |e| e.i_max)),
        (j_min, int64_column(py, rows, |e| e.j_min)),
        (j_max, int64_column(py, rows, |e| e.j_max)),
        (t_min_s, float64_column(py, rows, |e| e.t_min_s)),
        (t_max_s, float64_column(py, rows, |e| e.t_max_s)),
        (t_prime_min_s, float64_column(py, rows, |e| e.t_prime_min_s)),
        (t_prime_max_s, float64_column(py, rows, |e| e.t_prime_max_s)),
        (closest_i, int64_column(py, rows, |e| e.closest_i)),
        (closest_j, int64_column(py, rows, |e| e.closest_j)),
        (closest_distance, float64_column(py, rows, |e| e.closest_distance)),
    ]
}
