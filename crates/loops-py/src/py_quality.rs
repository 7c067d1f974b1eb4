//! `SampleQuality` (paper, Sec. 5.2: P1, P2 and P3 of a sample) and `sample_quality`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;

use crate::convert::{bool_column, float64_column, id_column, int64_column, table, to_numpy};
use crate::detached;
use crate::py_loops::Loops;
use crate::py_samples::Samples;

/// P1, P2 and P3 of a sample (paper, Sec. 5.2), measured against the exact loop components of
/// S_γ. Returned by :func:`sample_quality`.
///
/// Components count when they hold a pair (i, j) with i < j (a lone diagonal cell cannot be
/// sampled).
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
///     >>> loops = il.find_loops(traj, gamma=4.0, separation=None)
///     >>> samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
///     >>> quality = il.sample_quality(samples, loops, epsilon_s=1.0)
///     >>> quality.covered, quality.components, quality.coverage, quality.per_component.tolist()
///     (2, 2, 1.0, [1, 1])
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, PartialEq)]
pub(crate) struct SampleQuality {
    inner: loops_core::SampleQuality,
}

/// Measures how representative ``samples`` are of the loops (paper, Sec. 5.2): P1 (every loop
/// component covered), P2 (no redundant samples), P3 (more samples for bigger components),
/// against the exact components of ``loops`` — never against the detection clusters. Samples
/// given only by times are placed on the nearest poses.
///
/// Args:
///     samples: :class:`Samples`.
///     loops: the :class:`Loops` to measure against (same trajectory).
///     epsilon_s: the P2 radius, seconds: a sample with another sample of its component
///         within ε in the (t, t′) plane is redundant; ``None`` takes the library default
///         (30 s, the paper's).
///
/// Raises:
///     InvalidParameterError: ε not positive and finite, samples of another trajectory, a
///         sample time outside its span.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> traj = il.urban_drive(duration_s=900.0)
///     >>> loops = il.find_loops(traj, gamma=40.0, separation=None)
///     >>> samples = il.sample(loops, "one", budget=500, seed=0, trajectory=traj)
///     >>> quality = il.sample_quality(samples, loops, epsilon_s=30.0)
///     >>> quality.covered == quality.components, quality.missed["id"].tolist()
///     (True, [])
#[pyfunction]
#[pyo3(signature = (samples, loops, *, epsilon_s=None))]
pub(crate) fn sample_quality(
    py: Python<'_>,
    samples: &Samples,
    loops: &Loops,
    epsilon_s: Option<f64>,
) -> PyResult<SampleQuality> {
    let epsilon_s = epsilon_s.unwrap_or(loops_core::DEFAULT_EPSILON_S);
    let (samples, loops) = (Arc::clone(&samples.inner), Arc::clone(&loops.inner));
    let inner = detached(py, move || Ok(loops_core::sample_quality(&samples, &loops, epsilon_s)?))?;
    Ok(SampleQuality { inner })
}

crate::pickling::pickled!(SampleQuality, loops_core::SampleQuality, |value| Ok(Self { inner: value }));

#[pymethods]
impl SampleQuality {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[self.inner.samples as u64, self.inner.covered as u64, self.inner.components as u64])
    }

    fn __repr__(&self) -> String {
        let q = &self.inner;
        let optional = |v: Option<f64>| v.map_or("None".to_owned(), |v| format!("{v:.3}"));
        format!(
            "SampleQuality(P1: {}/{} components covered ({}/{} non-trivial); P2: {}/{} redundant within {} s, \
             median spacing {} s; P3 slope {})",
            q.covered,
            q.components,
            q.nontrivial_covered,
            q.nontrivial_components,
            q.redundant,
            q.samples,
            q.epsilon_s,
            optional(q.median_spacing_s),
            optional(q.p3_slope)
        )
    }

    /// Number of samples.
    #[getter]
    fn samples(&self) -> usize {
        self.inner.samples
    }

    /// Samples outside S_γ (δ > γ: false detections).
    #[getter]
    fn outside(&self) -> usize {
        self.inner.outside
    }

    /// Loop components that can be sampled.
    #[getter]
    fn components(&self) -> usize {
        self.inner.components
    }

    /// P1: components with at least one sample.
    #[getter]
    fn covered(&self) -> usize {
        self.inner.covered
    }

    /// Non-trivial components (revisits proper) that can be sampled.
    #[getter]
    fn nontrivial_components(&self) -> usize {
        self.inner.nontrivial_components
    }

    /// P1 over the non-trivial components.
    #[getter]
    fn nontrivial_covered(&self) -> usize {
        self.inner.nontrivial_covered
    }

    /// P1 as a fraction: covered / components (1 without components).
    #[getter]
    fn coverage(&self) -> f64 {
        self.inner.coverage()
    }

    /// P1: the components without a sample, largest area first, as a
    /// :class:`~inexact_loops.Table`: ``id`` (int64), ``trivial`` (bool), ``area_s2``
    /// (float64, s²), ``pair_count`` (int64).
    #[getter]
    fn missed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let missed = &self.inner.missed;
        table(
            py,
            [
                ("id", int64_column(py, missed, |m| m.id)),
                ("trivial", bool_column(py, missed, |m| m.trivial)),
                ("area_s2", float64_column(py, missed, |m| m.area_s2)),
                ("pair_count", int64_column(py, missed, |m| m.pair_count as usize)),
            ],
        )
    }

    /// The ε of P2, seconds.
    #[getter]
    fn epsilon_s(&self) -> f64 {
        self.inner.epsilon_s
    }

    /// P2: samples with another sample of the same component within ε.
    #[getter]
    fn redundant(&self) -> usize {
        self.inner.redundant
    }

    /// P2 as a fraction: redundant / samples (0 without samples).
    #[getter]
    fn redundancy(&self) -> f64 {
        self.inner.redundancy()
    }

    /// P2: median distance from a sample to the nearest other sample of its component,
    /// seconds; ``None`` when no component has two samples.
    #[getter]
    fn median_spacing_s(&self) -> Option<f64> {
        self.inner.median_spacing_s
    }

    /// P3: least-squares slope of ln(samples) on ln(area) across the covered components (≈ 0
    /// for σ_1, ≈ 1 for σ_α); ``None`` with fewer than two distinct areas.
    #[getter]
    fn p3_slope(&self) -> Option<f64> {
        self.inner.p3_slope
    }

    /// Number of components in the P3 fit.
    #[getter]
    fn p3_components(&self) -> usize {
        self.inner.p3_components
    }

    /// Samples per component, int64, by component id: one entry per row of
    /// :attr:`Loops.components`, so it can be added to that table as a column.
    ///
    /// Example:
    ///     >>> import numpy as np, inexact_loops as il
    ///     >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
    ///     >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
    ///     >>> loops = il.find_loops(traj, gamma=4.0, separation=None)
    ///     >>> samples = il.sample(loops, "alpha", budget=5, seed=0, trajectory=traj)
    ///     >>> table = loops.components
    ///     >>> table["samples"] = il.sample_quality(samples, loops).per_component
    ///     >>> int(table["samples"].sum()), table.num_rows
    ///     (5, 2)
    #[getter]
    fn per_component<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.per_component.iter().map(|&k| k as i64).collect())
    }

    /// The exact component of each sample, int64, in the samples' order; −1 outside S_γ.
    #[getter]
    fn sample_components<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        id_column(py, self.inner.sample_components.iter().copied())
    }

    /// Each sample's distance to the nearest other sample of its component, seconds, in the
    /// samples' order; NaN when alone in its component or outside S_γ.
    #[getter]
    fn nearest_spacing_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        to_numpy(py, self.inner.nearest_spacing_s.iter().map(|s| s.unwrap_or(f64::NAN)).collect())
    }
}
