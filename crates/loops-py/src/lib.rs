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
//! `FleetLoops`, `FleetSamples`, `find_fleet_loops`, `sample_fleet`, `urban_fleet`) and `py_tile`
//! (`SessionBlocks`, `Tile`, `TileSummary`, `TileMerge`, `TiledFleetLoops`: a fleet's tiles for a
//! cluster), `py_online` (`OnlineLoops`, `Update`: loops while poses arrive) and
//! `py_online_sampler` (`OnlineSampler`, `Candidate`: loop-closure candidates per keyframe);
//! `py_out_dir` (`OutDir`, `refuse_output_on_input`, `write_file`: loops-io's output folder, for
//! `inexact_loops.dask`); `py_scene` (`Scene`, `scene`: the results for Foxglove, RViz and
//! Rerun).
//! Below them:
//! `convert` (arguments to Rust
//! buffers, results to numpy columns and tables), `py_metric` (metric arguments), `error`
//! (the one mapping of errors to exceptions), `warning` (the one mapping of the engine's
//! warnings to Python warning categories) and `shared` (the value of a class whose methods
//! change it, used by one thread at a time). Beside them, `cli` (`run_cli`): the `loops` command
//! of `loops-cli`, for the wheel's console script.

mod cli;
mod convert;
mod error;
mod pickling;
mod py_clusters;
mod py_detections;
mod py_fleet;
mod py_graph;
mod py_live;
mod py_loops;
mod py_metric;
mod py_online;
mod py_online_sampler;
mod py_out_dir;
mod py_plane;
mod py_quality;
mod py_samples;
mod py_scene;
mod py_separation;
mod py_store;
mod py_tile;
mod py_tile_draw;
mod py_tile_merge;
mod py_tile_scan;
mod py_trajectory;
mod shared;
mod warning;

use std::sync::{Condvar, Mutex, PoisonError};
use std::time::Duration;

use pyo3::prelude::*;

/// How often the calling thread looks for Python signals (Ctrl-C) while Rust computes.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `f` without the GIL and turns its error, or a panic, into a Python exception: the way
/// bindings call into the core. A call too short to be worth releasing the GIL (a push of one
/// pose) goes through [`attached`] instead; both stop a panic with [`guarded`].
///
/// `f` runs on a worker thread under a [`loops_core::Interrupt`] while the calling thread waits
/// without the GIL and, every 50 ms, lets Python run its signal handlers
/// (`PyErr_CheckSignals`). When a handler raises (Ctrl-C: `KeyboardInterrupt`), the token is
/// interrupted, the engine stops at its next check (within a block of rows), and the handler's
/// exception is raised. A Python metric callable run by `f` takes the GIL from the worker thread.
/// `f` runs on the process's default rayon pool, so that a child of `fork` computes too.
pub(crate) fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, error::Failure> + Send) -> PyResult<T> {
    let interrupt = loops_core::Interrupt::new();
    let done = Done::default();
    std::thread::scope(|scope| {
        let work = {
            let (interrupt, done) = (&interrupt, &done);
            move || {
                // On the process's default pool, which a forked child makes anew (see
                // `loops_core::with_threads`).
                let result = interrupt.run(|| loops_core::with_threads(None, || guarded(f)));
                done.finish();
                result.unwrap_or_else(|error| Err(error::Failure::from(error)))
            }
        };
        let worker = std::thread::Builder::new()
            .name("inexact-loops".to_owned())
            .spawn_scoped(scope, work)
            .map_err(|e| error::Failure::Panic(format!("could not start a worker thread: {e}")))?;
        let mut signal = Ok(());
        while !py.detach(|| done.wait(SIGNAL_POLL)) {
            if let Err(raised) = py.check_signals() {
                interrupt.interrupt();
                signal = Err(raised);
                break;
            }
        }
        // After an interrupt the engine stops at its next check; its result is dropped.
        let result = py.detach(|| worker.join());
        let result = result.unwrap_or_else(|payload| Err(error::Failure::Panic(panic_message(payload.as_ref()))));
        signal?;
        result.map_err(PyErr::from)
    })
}

/// Runs `f` with the GIL held and turns its error, or a panic, into a Python exception: for the
/// calls that take microseconds (an online push, an offer to the online sampler), where
/// releasing the GIL and starting a worker would cost more than the call. Anything longer goes
/// through [`detached`], so that Ctrl-C and other Python threads are not held up.
pub(crate) fn attached<T>(f: impl FnOnce() -> Result<T, error::Failure>) -> PyResult<T> {
    guarded(f).map_err(PyErr::from)
}

/// Runs `f`, turning a panic into [`error::Failure::Panic`]: the one guard under [`detached`]
/// and [`attached`], so that no panic reaches Python.
fn guarded<T>(f: impl FnOnce() -> Result<T, error::Failure>) -> Result<T, error::Failure> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .unwrap_or_else(|payload| Err(error::Failure::Panic(panic_message(payload.as_ref()))))
}

/// Whether the worker of [`detached`] has finished, and a way to wait for it.
#[derive(Default)]
struct Done {
    finished: Mutex<bool>,
    changed: Condvar,
}

impl Done {
    fn finish(&self) {
        *self.finished.lock().unwrap_or_else(PoisonError::into_inner) = true;
        self.changed.notify_all();
    }

    /// Waits up to `timeout` for the worker; whether it has finished.
    fn wait(&self, timeout: Duration) -> bool {
        let finished = self.finished.lock().unwrap_or_else(PoisonError::into_inner);
        let (finished, _) = self
            .changed
            .wait_timeout_while(finished, timeout, |finished| !*finished)
            .unwrap_or_else(PoisonError::into_inner);
        *finished
    }
}

/// The text of a panic's payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_owned())
}

#[pymodule]
fn _core(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    module.add("DEFAULT_SAMPLER", loops_core::SamplerKind::DEFAULT.name())?;
    module.add("DEFAULT_BUDGET", loops_core::SampleSize::DEFAULT_BUDGET)?;
    let names = |baseline: bool| {
        let kinds = loops_core::SamplerKind::ALL.into_iter().filter(|k| k.is_baseline() == baseline);
        pyo3::types::PyTuple::new(module.py(), kinds.map(loops_core::SamplerKind::name).collect::<Vec<_>>())
    };
    module.add("SAMPLER_NAMES", names(false)?)?;
    module.add("BASELINE_NAMES", names(true)?)?;
    module.add_class::<py_trajectory::Trajectory>()?;
    module.add_class::<py_loops::Loops>()?;
    module.add_class::<py_separation::Separation>()?;
    module.add_function(wrap_pyfunction!(py_loops::path_length, module)?)?;
    module.add_function(wrap_pyfunction!(py_loops::find_loops, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::urban_drive, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::read_trajectory, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::list_topics, module)?)?;
    module.add_function(wrap_pyfunction!(py_trajectory::log_name, module)?)?;
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
    module.add_class::<py_store::FleetStore>()?;
    module.add_class::<py_store::StoreUpdatePlan>()?;
    module.add_class::<py_fleet::FleetSamples>()?;
    module.add_function(wrap_pyfunction!(py_fleet::find_fleet_loops, module)?)?;
    module.add_function(wrap_pyfunction!(py_fleet::sample_fleet, module)?)?;
    module.add_function(wrap_pyfunction!(py_fleet::urban_fleet, module)?)?;
    module.add_class::<py_tile::SessionBlocks>()?;
    module.add_class::<py_tile::Tile>()?;
    module.add_class::<py_tile::TileSummary>()?;
    module.add_class::<py_tile_merge::TileMerge>()?;
    module.add_class::<py_tile_merge::TiledFleetLoops>()?;
    module.add_function(wrap_pyfunction!(py_tile::session_blocks, module)?)?;
    module.add_function(wrap_pyfunction!(py_tile::plan_tiles, module)?)?;
    module.add_function(wrap_pyfunction!(py_tile_scan::scan_tile, module)?)?;
    module.add_function(wrap_pyfunction!(py_tile_scan::scan_tiles, module)?)?;
    module.add_function(wrap_pyfunction!(py_tile_merge::merge_tiles, module)?)?;
    module.add_class::<py_tile_draw::KeyedDraw>()?;
    module.add_class::<py_tile_draw::TileDrawRequest>()?;
    module.add_class::<py_tile_draw::DrawCandidates>()?;
    module.add_class::<py_tile_scan::TileDuration>()?;
    module.add_function(wrap_pyfunction!(py_tile_draw::draw_tile, module)?)?;
    module.add_function(wrap_pyfunction!(py_tile_draw::session_loop_duration, module)?)?;
    module.add_class::<py_tile_scan::TileRuns>()?;
    module.add_function(wrap_pyfunction!(cli::run_cli, module)?)?;
    module.add_class::<py_graph::PoseGraph>()?;
    module.add_function(wrap_pyfunction!(py_graph::read_pose_graph, module)?)?;
    module.add_class::<py_online::OnlineLoops>()?;
    module.add_class::<py_online::Update>()?;
    module.add_class::<py_online_sampler::OnlineSampler>()?;
    module.add_class::<py_live::LiveServer>()?;
    module.add_class::<py_online_sampler::Candidate>()?;
    module.add_class::<py_out_dir::OutDir>()?;
    module.add_function(wrap_pyfunction!(py_out_dir::refuse_output_on_input, module)?)?;
    module.add_function(wrap_pyfunction!(py_out_dir::write_file, module)?)?;
    module.add_class::<py_scene::Scene>()?;
    module.add_function(wrap_pyfunction!(py_scene::scene, module)?)?;
    Ok(())
}
