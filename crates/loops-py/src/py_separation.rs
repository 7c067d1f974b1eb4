//! `Separation`: how far apart along the trajectory the two poses of a loop must be, and the
//! `separation=` argument of `find_loops`.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::error::Failure;

/// The minimum separation along the trajectory between the two poses of a loop: a path length
/// (the metric's unit, e.g. metres) and a time (seconds); both must hold. With either above 0,
/// :func:`find_loops` finds *revisits*: the pairs within γ that odometry does not already tie
/// together, and no component is trivial. ``Separation()`` (both 0) is the paper's S_γ.
///
/// Args:
///     path: minimum path length between the poses, in the metric's unit (≥ 0).
///     time_s: minimum time between the poses, seconds (≥ 0).
///
/// Raises:
///     InvalidParameterError: a bound negative or not finite.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> il.Separation(path=24.0, time_s=30.0)
///     Separation(path=24.0, time_s=30.0)
///     >>> il.Separation.for_gamma(6.0)
///     Separation(path=24.0, time_s=0.0)
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Separation {
    pub(crate) inner: loops_core::Separation,
}

crate::pickling::pickled!(Separation, loops_core::Separation, |value| Ok(Self { inner: value }));

#[pymethods]
impl Separation {
    #[new]
    #[pyo3(signature = (*, path=0.0, time_s=0.0))]
    fn new(path: f64, time_s: f64) -> PyResult<Self> {
        let inner = loops_core::Separation { path, time_s };
        inner.check().map_err(Failure::from)?;
        Ok(Self { inner })
    }

    /// The default of :func:`find_loops` (``separation="auto"``) at threshold ``gamma``: a path
    /// of 4 γ, no time separation; measured on real trajectories (the guide
    /// "Choose γ and the separation").
    #[staticmethod]
    fn for_gamma(gamma: f64) -> PyResult<Self> {
        loops_core::check_gamma(gamma).map_err(Failure::from)?;
        Ok(Self { inner: loops_core::Separation::for_gamma(gamma) })
    }

    /// Minimum path length between the poses, in the metric's unit.
    #[getter]
    fn path(&self) -> f64 {
        self.inner.path
    }

    /// Minimum time between the poses, seconds.
    #[getter]
    fn time_s(&self) -> f64 {
        self.inner.time_s
    }

    /// Whether both are 0: the paper's S_γ, trivial components included.
    #[getter]
    fn is_none(&self) -> bool {
        self.inner.is_none()
    }

    fn __repr__(&self) -> String {
        format!("Separation(path={:?}, time_s={:?})", self.inner.path, self.inner.time_s)
    }

    fn __str__(&self) -> String {
        self.inner.to_string()
    }
}

/// What `find_loops(separation=...)` was given.
#[derive(Debug, Clone, Copy)]
pub(crate) enum SeparationArg {
    /// `"auto"`: [`loops_core::Separation::for_gamma`].
    Auto,
    /// `None`, `"none"`, a number (a path length) or a `Separation`.
    Given(loops_core::Separation),
}

impl SeparationArg {
    /// The separation at threshold `gamma`.
    pub(crate) fn at(self, gamma: f64) -> loops_core::Separation {
        match self {
            Self::Auto => loops_core::Separation::for_gamma(gamma),
            Self::Given(separation) => separation,
        }
    }
}

impl<'py> FromPyObject<'_, 'py> for SeparationArg {
    type Error = PyErr;

    fn extract(obj: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        if obj.is_none() {
            return Ok(Self::Given(loops_core::Separation::NONE));
        }
        if let Ok(text) = obj.cast::<PyString>() {
            return match text.to_str()? {
                "auto" => Ok(Self::Auto),
                "none" => Ok(Self::Given(loops_core::Separation::NONE)),
                other => Err(crate::error::invalid_parameter(format!(
                    "separation must be \"auto\", \"none\", None, a path length or an il.Separation, got {other:?}"
                ))),
            };
        }
        if let Ok(separation) = obj.cast::<Separation>() {
            return Ok(Self::Given(separation.get().inner));
        }
        if obj.is_instance_of::<pyo3::types::PyBool>() {
            return Err(PyTypeError::new_err(
                "separation must be \"auto\", None, a path length or an il.Separation, got bool",
            ));
        }
        match obj.extract::<f64>() {
            Ok(path) => {
                let separation = loops_core::Separation::path(path);
                separation.check().map_err(Failure::from)?;
                Ok(Self::Given(separation))
            }
            Err(_) => Err(PyTypeError::new_err(format!(
                "separation must be \"auto\", None, a path length or an il.Separation, got {}",
                obj.get_type().name()?
            ))),
        }
    }
}
