//! Metrics from Python: a spec (text or an `inexact_loops.metrics` object) or, as a slow path,
//! any callable `f(a, b) -> float`.

use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::detached;
use crate::error::Failure;

/// What `find_loops(metric=...)` was given.
pub(crate) enum MetricArg {
    Spec(loops_core::MetricSpec),
    Callable(PyCallableMetric),
}

impl MetricArg {
    /// `None` → the default; a `str` or an object with a `spec` string → parsed by the core; any
    /// other callable → the slow path.
    pub(crate) fn from_py(metric: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(metric) = metric else { return Ok(Self::Spec(loops_core::MetricSpec::default())) };
        let text: Option<String> = if let Ok(text) = metric.cast::<PyString>() {
            Some(text.to_str()?.to_owned())
        } else if let Ok(spec) = metric.getattr("spec") {
            Some(spec.extract()?)
        } else {
            None
        };
        match text {
            Some(text) => Ok(Self::Spec(text.parse::<loops_core::MetricSpec>().map_err(Failure::from)?)),
            None if metric.is_callable() => {
                Ok(Self::Callable(PyCallableMetric { function: metric.clone().unbind(), error: Mutex::new(None) }))
            }
            None => Err(PyTypeError::new_err(format!(
                "metric must be a name, an inexact_loops.metrics object or a callable f(a, b) -> float, got {}",
                metric.get_type().name()?
            ))),
        }
    }

    /// As [`from_py`](Self::from_py), with `None` → `default`: the metric the trajectory a job
    /// runs on is measured by (`Trajectory::default_metric`, the one it was read for or its
    /// manifold's).
    pub(crate) fn or_default(metric: Option<&Bound<'_, PyAny>>, default: loops_core::MetricSpec) -> PyResult<Self> {
        match metric {
            None => Ok(Self::Spec(default)),
            Some(_) => Self::from_py(metric),
        }
    }

    /// A metric name or object for `function`, which builds points for it (and so cannot take
    /// a callable).
    pub(crate) fn spec_from_py(metric: Option<&Bound<'_, PyAny>>, function: &str) -> PyResult<loops_core::MetricSpec> {
        match Self::from_py(metric)? {
            Self::Spec(spec) => Ok(spec),
            Self::Callable(_) => {
                Err(crate::error::value_error(format!("{function} takes a metric name or object, not a callable")))
            }
        }
    }
}

/// The metric to sample or classify pairs of `loops` under: the one given, or the one the
/// loops were found with.
pub(crate) fn loops_metric(metric: Option<&Bound<'_, PyAny>>, loops: &loops_core::Loops) -> PyResult<MetricArg> {
    if metric.is_some() {
        return MetricArg::from_py(metric);
    }
    match loops.metric_name().parse::<loops_core::MetricSpec>() {
        Ok(spec) => Ok(MetricArg::Spec(spec)),
        Err(_) => Err(crate::error::invalid_parameter(format!(
            "the loops were found with the metric {:?}, which is not a metric name: pass metric= (the same callable)",
            loops.metric_name()
        ))),
    }
}

/// The metric a job runs under, as [`MetricArg::run`] hands it over.
pub(crate) enum MetricRef<'a> {
    /// A core metric: jobs that have a `MetricSpec` method keep the engine's loops monomorphic.
    Spec(&'a loops_core::MetricSpec),
    Callable(&'a PyCallableMetric),
}

impl MetricRef<'_> {
    /// The metric as a trait object (dispatched per distance).
    pub(crate) fn as_metric(&self) -> &dyn loops_core::Metric {
        match self {
            Self::Spec(spec) => spec.as_metric(),
            Self::Callable(callable) => *callable,
        }
    }
}

impl MetricArg {
    /// Runs `f` under this metric without the GIL: a spec on `threads` threads (`None`: one
    /// per core), a Python callable on one (it takes the GIL for every distance). An exception
    /// the callable raised is the result, before any error of `f`.
    pub(crate) fn run<T: Send>(
        self,
        py: Python<'_>,
        threads: Option<usize>,
        f: impl FnOnce(MetricRef<'_>) -> loops_core::Result<T> + Send,
    ) -> PyResult<T> {
        match self {
            Self::Spec(spec) => {
                detached(py, move || Ok(loops_core::with_threads(threads, || f(MetricRef::Spec(&spec)))??))
            }
            Self::Callable(callable) => {
                let result =
                    detached(py, || Ok(loops_core::with_threads(Some(1), || f(MetricRef::Callable(&callable)))??));
                if let Some(error) = callable.take_error() {
                    return Err(error);
                }
                result
            }
        }
    }
}

/// A Python function as a metric: called with the GIL for every distance (one thread), so it
/// is slow — a documented escape hatch for metrics the library does not have. It must satisfy
/// the triangle inequality, or pairs may be missed.
pub(crate) struct PyCallableMetric {
    function: Py<PyAny>,
    /// The first exception the function raised; later calls return +∞ at once.
    error: Mutex<Option<PyErr>>,
}

impl PyCallableMetric {
    /// The exception the function raised during a run, if any.
    pub(crate) fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut slot| slot.take())
    }

    fn fail(&self, error: PyErr) -> f64 {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(error);
        }
        f64::INFINITY
    }
}

impl loops_core::Metric for PyCallableMetric {
    fn name(&self) -> String {
        Python::attach(|py| {
            self.function
                .bind(py)
                .getattr("__name__")
                .and_then(|name| name.extract::<String>())
                .unwrap_or_else(|_| "python callable".to_owned())
        })
    }

    fn check_dim(&self, _dim: usize) -> loops_core::Result<()> {
        Ok(())
    }

    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        if self.error.lock().map(|slot| slot.is_some()).unwrap_or(true) {
            return f64::INFINITY;
        }
        Python::attach(|py| {
            let args = (PyArray1::from_slice(py, a), PyArray1::from_slice(py, b));
            let value = match self.function.bind(py).call1(args) {
                Ok(value) => value,
                Err(error) => return self.fail(error),
            };
            match value.extract::<f64>() {
                Ok(d) if d.is_finite() && d >= 0.0 => d,
                Ok(d) => self.fail(loops_core_error(d)),
                Err(_) => {
                    let type_name = value.get_type().name().map_or_else(|_| "?".to_owned(), |name| name.to_string());
                    self.fail(PyTypeError::new_err(format!("the metric callable must return a float, got {type_name}")))
                }
            }
        })
    }
}

fn loops_core_error(d: f64) -> PyErr {
    crate::error::value_error(format!("the metric callable returned {d}: distances must be finite and ≥ 0"))
}
