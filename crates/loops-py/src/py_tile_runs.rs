//! A tile's runs kept where it was scanned (`TileRuns`): `scan_tile_kept` (`py_tile_draw`)
//! returns them with the summary and the share of τ, and `draw_tile(runs=...)` offers a draw's
//! pairs from them without rescanning the tile.

use std::sync::Arc;

use pyo3::prelude::*;

use crate::error::invalid_parameter;
use crate::py_tile::Tile;
use loops_core::MetricSpec;

/// One tile's runs as its scan made them (:func:`scan_tile_kept`), with their provisional
/// labels: what :func:`draw_tile` reads of the tile when given them instead of rescanning it.
/// About 16 bytes a run; it holds no poses. Lives in the process that scanned the tile (it
/// does not pickle): a worker keeps it for the draws of its tiles.
#[pyclass(frozen, module = "inexact_loops._core")]
pub(crate) struct TileRuns {
    pub(crate) inner: Arc<loops_core::TileRuns>,
    pub(crate) metric: MetricSpec,
}

#[pymethods]
impl TileRuns {
    fn __repr__(&self) -> String {
        format!("TileRuns({:?}, {} runs)", self.inner.tile(), self.inner.run_count())
    }

    /// Its runs.
    fn __len__(&self) -> usize {
        self.inner.run_count()
    }

    /// The bytes it holds (its runs, 16 bytes each, and 8 bytes a row).
    #[getter]
    fn nbytes(&self) -> usize {
        self.inner.heap_bytes()
    }

    /// The tile.
    #[getter]
    fn tile(&self) -> Tile {
        Tile { inner: self.inner.tile().clone() }
    }

    /// The metric's name the tile was scanned with.
    #[getter]
    fn metric_name(&self) -> String {
        self.metric.name()
    }
}

/// The runs to draw `tile` from, checked against the draw's tile and metric.
pub(crate) fn runs_for(
    runs: &TileRuns,
    tile: &loops_core::Tile,
    metric: MetricSpec,
) -> PyResult<Arc<loops_core::TileRuns>> {
    if runs.inner.tile() != tile {
        return Err(invalid_parameter(format!(
            "draw_tile: the runs are of tile {:?}, the request of tile {tile:?}",
            runs.inner.tile()
        )));
    }
    if runs.metric != metric {
        return Err(invalid_parameter(format!(
            "draw_tile: the runs were scanned with metric {}, the draw asks {}",
            runs.metric.name(),
            metric.name()
        )));
    }
    Ok(runs.inner.clone())
}
