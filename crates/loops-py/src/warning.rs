//! The engine's warnings as Python warnings: the one table from each warning of `loops-core` to
//! its category (the classes of `inexact_loops/errors.py`), and the calls that issue them.
//!
//! A result that is correct but deserves a second look (a broken diagonal, no revisit, a sample
//! smaller than asked or empty, input a lenient reading option dropped) keeps its warnings as sentences (`Loops.warnings`, `Samples.warnings`) and
//! issues each with `warnings.warn` in its category, so users can filter them
//! (`warnings.simplefilter("error", il.LoopsWarning)` makes them exceptions). The functions that
//! issue them are compiled, so the frame on top of the stack is the caller's: stack level 1
//! attributes the warning to the user's line.
//!
//! A new warning of the core gets its category with one row in [`category`]: a class in
//! `errors.py` (exported from the package), its `import_exception!` here, and the match arm.
//! Until then it is issued as the base `LoopsWarning`: the core's warning enums are
//! `#[non_exhaustive]`, so the table ends with that fallback.

use std::ffi::CString;

use loops_core::{SampleWarning, Warning};
use pyo3::prelude::*;
use pyo3::types::PyType;
use pyo3::{PyTypeInfo, import_exception};

import_exception!(inexact_loops.errors, LoopsWarning);
import_exception!(inexact_loops.errors, DiagonalBrokenWarning);
import_exception!(inexact_loops.errors, NoLoopsWarning);
import_exception!(inexact_loops.errors, EmptySampleWarning);
import_exception!(inexact_loops.errors, SampleBudgetWarning);
import_exception!(inexact_loops.errors, DroppedInputWarning);
import_exception!(inexact_loops.errors, DeadReckoningWarning);

/// A warning about a result, from the core or (for an empty sample) from the bindings.
enum EngineWarning<'a> {
    /// A warning of [`loops_core::find_loops`].
    Loops(&'a Warning),
    /// A warning of a sampler.
    Sample(&'a SampleWarning),
    /// A sample with no rows that no warning of the sampler explains.
    NoSamples,
    /// Input a lenient reading option dropped (loops-io's `Dropped`).
    Dropped,
    /// Poses chained from a pose graph's odometry edges (loops-io's `EdgeChain`).
    DeadReckoning,
}

/// The category of each warning: the one table.
fn category<'py>(py: Python<'py>, warning: &EngineWarning<'_>) -> Bound<'py, PyType> {
    use EngineWarning as E;
    match warning {
        E::Loops(Warning::DiagonalBroken { .. }) => DiagonalBrokenWarning::type_object(py),
        E::Loops(Warning::NoLoops { .. }) => NoLoopsWarning::type_object(py),
        E::Sample(SampleWarning::BudgetAboveAvailable { available: 0, .. }) | E::NoSamples => {
            EmptySampleWarning::type_object(py)
        }
        E::Sample(SampleWarning::BudgetAboveAvailable { .. } | SampleWarning::BudgetBelowGroups { .. }) => {
            SampleBudgetWarning::type_object(py)
        }
        E::Dropped => DroppedInputWarning::type_object(py),
        E::DeadReckoning => DeadReckoningWarning::type_object(py),
        _ => LoopsWarning::type_object(py),
    }
}

/// Issues `message` in `warning`'s category, attributed to the caller's line. Under an "error"
/// filter this is the warning as an exception.
fn issue(py: Python<'_>, warning: &EngineWarning<'_>, message: &str) -> PyResult<()> {
    let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, category(py, warning).as_any(), &message, 1)
}

/// Issues the warnings of `loops` (from `find_loops`).
pub(crate) fn warn_loops(py: Python<'_>, loops: &loops_core::Loops) -> PyResult<()> {
    for warning in loops.warnings() {
        issue(py, &EngineWarning::Loops(warning), &warning.to_string())?;
    }
    Ok(())
}

/// Issues the warnings of `samples` (from `sample`), and an empty sample's when none of them
/// says it is empty. `skip_trivial` is named in that message when it was asked for.
pub(crate) fn warn_samples(py: Python<'_>, samples: &loops_core::Samples, skip_trivial: bool) -> PyResult<()> {
    let (sampler, available) = (samples.sampler(), samples.available());
    warn_sample_warnings(py, samples.warnings(), samples.is_empty(), sampler, available, skip_trivial)
}

/// [`warn_samples`] from its parts (a keyed draw's).
pub(crate) fn warn_sample_warnings(
    py: Python<'_>,
    warnings: &[loops_core::SampleWarning],
    is_empty: bool,
    sampler: loops_core::SamplerKind,
    available: u64,
    skip_trivial: bool,
) -> PyResult<()> {
    let empty = EmptySampleWarning::type_object(py);
    let mut said_empty = false;
    for warning in warnings {
        let engine = EngineWarning::Sample(warning);
        said_empty |= category(py, &engine).is(&empty);
        issue(py, &engine, &warning.to_string())?;
    }
    if is_empty && !said_empty {
        let hint = if skip_trivial { " (skip_trivial left out the trivial loop components)" } else { "" };
        let message = format!("no samples: the {sampler} sampler kept none of its {available} candidate(s){hint}");
        issue(py, &EngineWarning::NoSamples, &message)?;
    }
    Ok(())
}

/// Issues `message`, saying what a lenient reading option (`drop_duplicate_stamps`,
/// `drop_outside_span`) dropped from a file.
pub(crate) fn warn_dropped_input(py: Python<'_>, message: &str) -> PyResult<()> {
    issue(py, &EngineWarning::Dropped, message)
}

/// Issues `message`, saying that a pose graph's poses were chained from its odometry edges
/// (`chain_edges=True`): dead reckoning.
pub(crate) fn warn_dead_reckoning(py: Python<'_>, message: &str) -> PyResult<()> {
    issue(py, &EngineWarning::DeadReckoning, message)
}
