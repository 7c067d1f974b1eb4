//! Python bindings of inexact-loops: the module `inexact_loops._core`.
//!
//! Thin adapters only: convert numpy arrays, release the GIL, call `loops-core` / `loops-io`,
//! map errors. No algorithm, validation rule or default of their own.
//!
//! One module per class, with the functions that return it, in the paper's order:
//! `py_trajectory` (`Trajectory`, `urban_drive`, `read_trajectory`, `list_topics`), `py_loops`
//! (`Loops`, `find_loops`, `path_length`), `py_separation` (`Separation`), `py_detections`
//! (`Detections`, `draw_detections`, `read_detections`), `py_clusters` (`DetectionClusters`,
//! `cluster_detections`), `py_samples` (`Samples`, `sample`), `py_quality` (`SampleQuality`,
//! `sample_quality`), `py_graph` (`PoseGraph`, `read_pose_graph`) and `py_fleet` (`Fleet`,
//! `FleetLoops`, `FleetSamples`, `find_fleet_loops`, `sample_fleet`, `urban_fleet`). Below them:
//! `convert` (arguments to Rust
//! buffers, results to numpy columns and tables), `py_metric` (metric arguments), `error`
//! (the one mapping of errors to exceptions) and `warning` (the one mapping of the engine's
//! warnings to Python warning categories). Beside them, `cli` (`run_cli`): the `loops` command
//! of `loops-cli`, for the wheel's console script.

mod cli;
mod convert;
mod error;
mod py_clusters;
mod py_detections;
mod py_fleet;
mod py_graph;
mod py_loops;
mod py_metric;
mod py_plane;
mod py_quality;
mod py_samples;
mod py_separation;
mod py_trajectory;
mod warning;

use pyo3::prelude::*;

/// Runs `f` without the GIL and turns its error, or a panic, into a Python exception: the one
/// way bindings call into Rust.
pub(crate) fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, error::Failure> + Send) -> PyResult<T> {
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|payload| {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_owned());
            Err(error::Failure::Panic(message))
        })
    })
    .map_err(PyErr::from)
}

#[pymodule]
fn _core(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    module.add_class::<py_trajectory::Trajectory>()?;
    module.add_class::<py_loops::Loops>()?;
    module.add_class::<py_separation::Separation>()?;
    module.add_function(wrap_pyfunction!(py_loops::path_length, module)?)?;
    module.add_function(wrap_pyfunction!(py_loops::find_loops, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::urban_drive, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::read_trajectory, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::list_topics, module)?)?;
    module.add_class::<py_detections::Detections>()?;
    module.add_class::<py_clusters::DetectionClusters>()?;
    module.add_class::<py_samples::Samples>()?;
    module.add_class::<py_quality::SampleQuality>()?;
    module.add_function(wrap_pyfunction!(py_detections::draw_detections, module)?)?;
    module.add_function(wrap_pyfunction!(py_detections::read_detections, module)?)?;
    module.add_function(wrap_pyfunction!(py_clusters::cluster_detections, module)?)?;
    module.add_function(wrap_pyfunction!(py_samples::sample, module)?)?;
    module.add_function(wrap_pyfunction!(py_quality::sample_quality, module)?)?;
    module.add_class::<py_loops::PlaneGrid>()?;
    module.add_function(wrap_pyfunction!(py_plane::distance_image, module)?)?;
    module.add_function(wrap_pyfunction!(py_plane::outline_segments, module)?)?;
    module.add_function(wrap_pyfunction!(py_plane::component_outlines, module)?)?;
    module.add_function(wrap_pyfunction!(py_plane::chain_polylines, module)?)?;
    module.add_function(wrap_pyfunction!(py_plane::isocontour, module)?)?;
    module.add_function(wrap_pyfunction!(py_plane::sampler_symbol, module)?)?;
    module.add_class::<py_fleet::Fleet>()?;
    module.add_class::<py_fleet::FleetLoops>()?;
    module.add_class::<py_fleet::FleetSamples>()?;
    module.add_function(wrap_pyfunction!(py_fleet::find_fleet_loops, module)?)?;
    module.add_function(wrap_pyfunction!(py_fleet::sample_fleet, module)?)?;
    module.add_function(wrap_pyfunction!(py_fleet::urban_fleet, module)?)?;
    module.add_function(wrap_pyfunction!(cli::run_cli, module)?)?;
    module.add_class::<py_graph::PoseGraph>()?;
    module.add_function(wrap_pyfunction!(py_graph::read_pose_graph, module)?)?;
    Ok(())
}
