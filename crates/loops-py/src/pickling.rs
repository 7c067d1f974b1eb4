//! Pickling: every class of the module pickles as `(Class._from_state, (state,))`, where the
//! state is one MessagePack byte string `["inexact_loops", format, class name, value]` of the
//! core's serde form of the value (`loops-core`'s `serde` feature). Unpickling reads the header
//! first, so a state of another format or class is refused naming both; the value is then
//! checked by the core as it is read (`Error::InvalidState`, or the constructor's own errors).
//! Every `_from_state` runs in [`restoring`], so a corrupt or forged state raises
//! `pickle.UnpicklingError` naming the class and what is wrong, whatever the check that found
//! it, never a panic. A class that holds another object of the module — `FleetLoops` and `FleetSamples`
//! their `Fleet`, `PoseGraph` its `Trajectory` — passes it as a second argument,
//! `(Class._from_state, (state, obj))`: pickle writes it once for all the objects pickled
//! together that hold it (the loops and the samples of one fleet share it again when unpickled),
//! and `_from_state` checks that the state fits it. The loops of the 2.1 h drive at γ = 40 m
//! (75,600 poses, 155,812 runs) pickle to 3.9 MB in about 5 ms and unpickle, checked, in about
//! 5 ms.
//!
//! The tile objects a cluster ships between machines pickle instead as
//! `(Class._from_state, args)`, their constructor's arguments, read by the constructor in
//! [`restoring`]: `TileSummary`, `TileMerge`, `DrawCandidates` and `TileDuration` as
//! `(Class._from_state, (bytes,))`, their core value's own `to_bytes` (a tag, the tile format
//! version, MessagePack), the same bytes a worker can send without pickle
//! ([`pickled_as_bytes!`]); `SessionBlocks` (its bytes and its metric's name),
//! `TileDrawRequest` (its tile, labels and request) and `Tile` (its ranges) by their own
//! `__reduce__`, as their constructors take more.

use pyo3::PyClass;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde::Serialize;
use serde::de::{DeserializeOwned, IgnoredAny};

/// The first element of every state.
const MAGIC: &str = "inexact_loops";

/// The version of the state layout. Raise it when a serialised type changes shape; a state of
/// a version outside [`OLDEST_FORMAT`]`..=FORMAT` is then refused with a message naming both.
/// Format 2 packs long arrays of numbers (a sublevel set's runs) as bytes; format 1's arrays
/// of numbers are still read.
const FORMAT: u32 = 2;

/// The oldest state layout this version reads.
const OLDEST_FORMAT: u32 = 1;

/// `(Class._from_state, (state,))` for `obj`, whose value `value` is serialised under `class`.
pub(crate) fn reduce<'py, T: Serialize + ?Sized>(
    obj: &Bound<'py, PyAny>,
    class: &str,
    value: &T,
) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
    let py = obj.py();
    let bytes = rmp_serde::to_vec(&(MAGIC, FORMAT, class, value))
        .map_err(|e| crate::error::Failure::Panic(format!("pickling a {class}: {e}")))?;
    Ok((obj.get_type().getattr("_from_state")?, (PyBytes::new(py, &bytes),)))
}

/// The pickling methods of a class that holds its core value `$core` in a field `inner` (as
/// the value or in an `Arc`): `__reduce__` gives the value's state under the class's name and
/// `_from_state` reads it back, checked, and makes the class with `$build` (`$value` names the
/// value read). They are a `#[pymethods]` block of their own (pyo3's `multiple-pymethods`), so
/// each class names only its core type and how a value becomes the class; equality is the
/// class's `#[pyclass(eq)]`.
macro_rules! pickled {
    ($class:ident, $core:ty, |$value:ident| $build:expr) => {
        #[pyo3::pymethods]
        impl $class {
            fn __reduce__<'py>(
                slf: &pyo3::Bound<'py, Self>,
            ) -> pyo3::PyResult<(pyo3::Bound<'py, pyo3::PyAny>, (pyo3::Bound<'py, pyo3::types::PyBytes>,))> {
                let value: &$core = &slf.get().inner;
                crate::pickling::reduce(slf.as_any(), stringify!($class), value)
            }

            #[classmethod]
            fn _from_state(cls: &pyo3::Bound<'_, pyo3::types::PyType>, state: &[u8]) -> pyo3::PyResult<Self> {
                crate::pickling::restoring(cls.py(), stringify!($class), || {
                    let $value: $core = crate::pickling::restore(cls.py(), stringify!($class), state)?;
                    $build
                })
            }
        }
    };
}
pub(crate) use pickled;

/// The pickling methods of a tile object that a cluster ships between machines as its own
/// bytes: a class whose only field `inner` holds a core value `$core` with `to_bytes()` and
/// `from_bytes(&[u8])` (the bytes carry their own tag and format version, so they are not
/// wrapped in a [`reduce`] state). Emits the constructor from those bytes (decoded without the
/// GIL; `InvalidParameterError` for bytes of something else, of another format version, or
/// corrupt), `to_bytes` (docstring `$to_bytes_doc`), `__reduce__` as
/// `(Class._from_state, (bytes,))` and `_from_state`, the constructor in [`restoring`]; given
/// `from_bytes`, also the static method `from_bytes`, as the constructor. `$what` names
/// the value in the docstrings. A `#[pymethods]` block of its own, as [`pickled!`]'s.
macro_rules! pickled_as_bytes {
    ($class:ident, $core:ty, $what:literal, $to_bytes_doc:literal $(, $from_bytes:ident)?) => {
        #[pyo3::pymethods]
        impl $class {
            #[doc = concat!("The ", $what, " from :meth:`to_bytes` (what pickling stores).")]
            ///
            /// Raises:
            ///     InvalidParameterError: bytes of something else, of another format version, or corrupt
            ///         (the message says which).
            #[new]
            fn new(py: pyo3::Python<'_>, data: &[u8]) -> pyo3::PyResult<Self> {
                let inner = crate::detached(py, || Ok(<$core>::from_bytes(data)?))?;
                Ok(Self { inner })
            }

            #[doc = $to_bytes_doc]
            fn to_bytes<'py>(&self, py: pyo3::Python<'py>) -> pyo3::Bound<'py, pyo3::types::PyBytes> {
                pyo3::types::PyBytes::new(py, &self.inner.to_bytes())
            }

            fn __reduce__<'py>(
                slf: &pyo3::Bound<'py, Self>,
            ) -> pyo3::PyResult<(pyo3::Bound<'py, pyo3::PyAny>, (pyo3::Bound<'py, pyo3::types::PyBytes>,))> {
                Ok((slf.get_type().getattr("_from_state")?, (slf.get().to_bytes(slf.py()),)))
            }

            #[classmethod]
            fn _from_state(cls: &pyo3::Bound<'_, pyo3::types::PyType>, data: &[u8]) -> pyo3::PyResult<Self> {
                crate::pickling::restoring(cls.py(), stringify!($class), || Self::new(cls.py(), data))
            }
        }

        $(
            #[pyo3::pymethods]
            impl $class {
                #[doc = concat!("The ", $what, " from :meth:`to_bytes`; as the constructor.")]
                #[staticmethod]
                fn $from_bytes(py: pyo3::Python<'_>, data: &[u8]) -> pyo3::PyResult<Self> {
                    Self::new(py, data)
                }
            }
        )?
    };
}
pub(crate) use pickled_as_bytes;

/// What [`reduce_with`] returns: `(Class._from_state, (state, obj))`.
pub(crate) type ReducedWith<'py, C> = (Bound<'py, PyAny>, (Bound<'py, PyBytes>, Py<C>));

/// `(Class._from_state, (state, companion))` for `obj`, whose own value `value` is serialised
/// under `class` and which holds `companion`, another object of the module pickled by itself.
pub(crate) fn reduce_with<'py, T: Serialize + ?Sized, C>(
    obj: &Bound<'py, PyAny>,
    class: &str,
    value: &T,
    companion: Py<C>,
) -> PyResult<ReducedWith<'py, C>> {
    let (restore, (state,)) = reduce(obj, class, value)?;
    Ok((restore, (state, companion)))
}

/// Runs `f`, the body of `class`'s `_from_state`, turning any exception it raises into
/// `pickle.UnpicklingError` ([`crate::error::unpickling`]).
pub(crate) fn restoring<T>(py: Python<'_>, class: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    f().map_err(|error| crate::error::unpickling(py, class, error))
}

/// The value of a state made by [`reduce`] for `class`.
///
/// # Errors
/// `pickle.UnpicklingError` for a state that is not one, of another format or class, or whose
/// value is corrupt or does not fit together.
pub(crate) fn restore<T: DeserializeOwned>(py: Python<'_>, class: &str, state: &[u8]) -> PyResult<T> {
    let fail = |reason: String| crate::error::unpickling_error(py, class, reason);
    let header: (String, u32, String, IgnoredAny) =
        rmp_serde::from_slice(state).map_err(|_| fail("not a pickled inexact_loops state".to_owned()))?;
    match header {
        (magic, _, _, _) if magic != MAGIC => Err(fail("not a pickled inexact_loops state".to_owned())),
        (_, format, _, _) if !(OLDEST_FORMAT..=FORMAT).contains(&format) => Err(fail(format!(
            "it was pickled in state format {format} (by another version of inexact_loops); this version \
             reads formats {OLDEST_FORMAT} to {FORMAT}"
        ))),
        (_, _, other, _) if other != class => Err(fail(format!("the state is of a {other}"))),
        _ => {
            let (_, _, _, value): (IgnoredAny, IgnoredAny, IgnoredAny, T) =
                rmp_serde::from_slice(state).map_err(|e| fail(e.to_string()))?;
            Ok(value)
        }
    }
}

/// Whether `state` is a state of `class` by its header (its value unread): for a second
/// argument whose class changed between versions.
pub(crate) fn is_of(state: &[u8], class: &str) -> bool {
    let header: Result<(String, u32, String, IgnoredAny), _> = rmp_serde::from_slice(state);
    header.is_ok_and(|(magic, _, of, _)| magic == MAGIC && of == class)
}

/// `pickle.UnpicklingError("cannot unpickle {class}: {reason}")`: a state that does not fit
/// together or does not fit the object it came with.
pub(crate) fn invalid(py: Python<'_>, class: &str, reason: impl std::fmt::Display) -> PyErr {
    crate::error::unpickling_error(py, class, reason)
}

/// The object of class `T` that a state came with (`what` names it in the message).
///
/// # Errors
/// `pickle.UnpicklingError` when it is of another type.
pub(crate) fn companion<'a, 'py, T: PyClass>(
    obj: &'a Bound<'py, PyAny>,
    class: &str,
    what: &str,
) -> PyResult<&'a Bound<'py, T>> {
    obj.cast::<T>().map_err(|_| {
        let got = obj.get_type().name().map_or_else(|_| "?".to_owned(), |n| n.to_string());
        invalid(obj.py(), class, format!("its {what} is a {got}, not a {}", T::NAME))
    })
}

/// A hash of the few values given, for `__hash__` of classes whose equality compares whole
/// arrays: equal objects give equal hashes, and the hash costs nothing.
pub(crate) fn hash_of(values: &[u64]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut hasher = std::hash::DefaultHasher::new();
    values.hash(&mut hasher);
    hasher.finish()
}
