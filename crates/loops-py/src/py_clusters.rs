//! `DetectionClusters` (paper, Sec. 5.1: the ε graph of a detection set) and `cluster_detections`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;

use crate::convert::{float64_column, int64_column, table, to_numpy};
use crate::detached;
use crate::py_detections::Detections;

/// The connected components of the ε graph of a detection set: approximations of the loop
/// components. Returned by :func:`cluster_detections`.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([0.0, 20.0, 500.0], [100.0, 100.0, 900.0])
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> len(clusters), clusters.labels.tolist(), clusters.clusters["t_max_s"].tolist()
///     (2, [0, 0, 1], [20.0, 500.0])
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, PartialEq)]
pub(crate) struct DetectionClusters {
    pub(crate) inner: Arc<loops_core::DetectionClusters>,
    detections: Arc<loops_core::Detections>,
}

/// Clusters detections exactly: the connected components of the graph with an edge between
/// every two detections within ``epsilon_s`` seconds of each other (Euclidean in the (t, t′)
/// plane, ``<= ε``): DBSCAN with ``min_samples=1``, without enumerating the ε-pairs.
///
/// Args:
///     detections: :class:`Detections`.
///     epsilon_s: ε > 0, seconds; ``None`` takes the library default (30 s, the paper's).
///     threads: worker threads; ``None`` uses one per core. Results do not depend on it.
///
/// Returns:
///     :class:`DetectionClusters`; cluster ids follow each cluster's smallest (t, t′), so they
///     do not depend on the order of the detections.
///
/// Raises:
///     InvalidParameterError: ε not positive and finite (or below the floating-point
///         resolution of the detections' time range), threads = 0.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> det = il.Detections([0.0, 30.0, 60.0, 500.0], [1000.0, 1000.0, 1000.0, 900.0])
///     >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
///     >>> clusters.labels.tolist(), clusters.clusters["size"].tolist()
///     ([0, 0, 0, 1], [3, 1])
#[pyfunction]
#[pyo3(signature = (detections, *, epsilon_s=None, threads=None))]
pub(crate) fn cluster_detections(
    py: Python<'_>,
    detections: &Detections,
    epsilon_s: Option<f64>,
    threads: Option<usize>,
) -> PyResult<DetectionClusters> {
    let epsilon_s = epsilon_s.unwrap_or(loops_core::DEFAULT_EPSILON_S);
    let det = Arc::clone(&detections.inner);
    let inner =
        detached(py, || Ok(loops_core::with_threads(threads, || loops_core::cluster_detections(&det, epsilon_s))??))?;
    Ok(DetectionClusters { inner: Arc::new(inner), detections: Arc::clone(&detections.inner) })
}

crate::pickling::pickled!(DetectionClusters, loops_core::DetectionClusters, |value| Ok(Self {
    detections: Arc::new(value.detections().clone()),
    inner: Arc::new(value)
}));

#[pymethods]
impl DetectionClusters {
    fn __hash__(&self) -> u64 {
        crate::pickling::hash_of(&[
            self.inner.len() as u64,
            self.inner.epsilon_s().to_bits(),
            self.inner.detections().len() as u64,
        ])
    }

    /// Number of clusters.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "DetectionClusters({} clusters of {} detections, epsilon_s={})",
            self.inner.len(),
            self.detections.len(),
            self.inner.epsilon_s()
        )
    }

    /// The threshold ε, seconds.
    #[getter]
    fn epsilon_s(&self) -> f64 {
        self.inner.epsilon_s()
    }

    /// Side of the grid cells, seconds (a little less than ε/√2).
    #[getter]
    fn cell_side_s(&self) -> f64 {
        self.inner.cell_side_s()
    }

    /// The detections that were clustered.
    #[getter]
    fn detections(&self) -> Detections {
        Detections { inner: Arc::clone(&self.detections) }
    }

    /// The cluster id of each detection, int64, in the order of the detections.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        to_numpy(py, self.inner.labels().iter().map(|&l| i64::from(l)).collect())
    }

    /// The clusters as a :class:`~inexact_loops.Table` (a dict of numpy columns, one row a
    /// cluster, by id; ``.to_pandas()`` for a DataFrame): ``id``, ``size`` (detections; int64),
    /// ``t_min_s``, ``t_max_s``, ``t_prime_min_s``, ``t_prime_max_s`` (extents, seconds;
    /// float64), ``cells`` (grid cells holding its detections; int64), ``area_proxy_s2``
    /// (cells × side², s²; float64), ``anchor`` (index of its smallest detection in (t, t′)
    /// order; int64).
    #[getter]
    fn clusters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let cs = self.inner.clusters();
        table(
            py,
            [
                ("id", int64_column(py, cs, |c| c.id)),
                ("size", int64_column(py, cs, |c| c.size)),
                ("t_min_s", float64_column(py, cs, |c| c.t_s[0])),
                ("t_max_s", float64_column(py, cs, |c| c.t_s[1])),
                ("t_prime_min_s", float64_column(py, cs, |c| c.t_prime_s[0])),
                ("t_prime_max_s", float64_column(py, cs, |c| c.t_prime_s[1])),
                ("cells", int64_column(py, cs, |c| c.cells)),
                ("area_proxy_s2", float64_column(py, cs, |c| c.area_proxy_s2)),
                ("anchor", int64_column(py, cs, |c| c.anchor)),
            ],
        )
    }
}
