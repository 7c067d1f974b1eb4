//! numpy arrays in and out.

use numpy::{PyArray1, PyArrayDescrMethods, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods};
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
    let values = match view.as_slice() {
        Ok(slice) if view.is_c_contiguous() => slice.to_vec(),
        _ => view.as_array().iter().copied().collect(),
    };
    Ok(Real { values, shape })
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
    let t = real_array(py, timestamps, "timestamps")?;
    if t.shape.len() != 1 {
        return Err(value_error(format!("timestamps must be 1-dimensional (n,), got shape {:?}", t.shape)));
    }
    let p = real_array(py, points, points_name)?;
    let dim = match p.shape.as_slice() {
        [_] => 1,
        [_, d] => *d,
        shape => {
            return Err(value_error(format!("{points_name} must have shape (n,) or (n, d), got shape {shape:?}")));
        }
    };
    if p.shape[0] != t.shape[0] {
        return Err(value_error(format!("timestamps has {} rows but {points_name} has {}", t.shape[0], p.shape[0])));
    }
    Ok((t.values, p.values, dim))
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
