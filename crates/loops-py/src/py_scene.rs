//! `Scene`: loops-io's results for robotics viewers (Foxglove, RViz, Rerun), built once in
//! Rust; `Scene.to_mcap` writes its MCAP file, and `inexact_loops.viewers.to_rerun` draws its
//! arrays with `rerun-sdk`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::to_numpy;
use crate::detached;
use crate::py_fleet::{FleetLoops, FleetSamples};
use crate::py_loops::Loops;
use crate::py_samples::Samples;
use crate::py_trajectory::Trajectory;

/// What robotics viewers draw of a result: a path per session with τ along it, every loop
/// component (its two stretches of path and its closest pair, a colour each), the sampled
/// candidate pairs and the (t, t′) plane as an RGB image. Made by :func:`scene`; written as
/// MCAP by :meth:`to_mcap` (Foxglove, RViz) and drawn by
/// :func:`inexact_loops.viewers.to_rerun` (Rerun).
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct Scene {
    inner: Arc<loops_io::Scene>,
}

/// The scene of a result: ``loops`` found on ``trajectory`` with ``samples`` drawn from them,
/// or a fleet's :class:`FleetLoops` with its :class:`FleetSamples` (no ``trajectory``).
/// Positions are each pose's first three coordinates.
///
/// Args:
///     loops: a :class:`Loops` or a :class:`FleetLoops`.
///     samples: its :class:`Samples` (a :class:`FleetSamples` for a fleet).
///     trajectory: the :class:`Trajectory` of ``loops`` (not for a fleet).
///     name: the trajectory's session name.
///
/// Raises:
///     TypeError: arguments of other types, or of a fleet and a single trajectory mixed.
///     InvalidParameterError: ``trajectory`` or ``samples`` are not those of ``loops``.
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> traj = il.Trajectory(np.arange(6.0), np.array([[0, 0], [5, 0], [5, 5], [0, 0], [5, 0], [5, 5.0]]))
///     >>> loops = il.find_loops(traj, gamma=0.5)
///     >>> samples = il.sample(loops, "one", budget=3, seed=0, trajectory=traj)
///     >>> scene = il.viewers.scene(loops, samples, traj)
///     >>> scene.paths[0]["positions"].shape, scene.plane.shape[2]
///     ((6, 3), 3)
#[pyfunction]
#[pyo3(signature = (loops, samples, trajectory=None, *, name="trajectory"))]
pub(crate) fn scene(
    py: Python<'_>,
    loops: &Bound<'_, PyAny>,
    samples: &Bound<'_, PyAny>,
    trajectory: Option<&Trajectory>,
    name: &str,
) -> PyResult<Scene> {
    if let Ok(fleet_loops) = loops.cast::<FleetLoops>() {
        let Ok(fleet_samples) = samples.cast::<FleetSamples>() else {
            return Err(PyTypeError::new_err("samples: a fleet's loops need its FleetSamples (sample_fleet)"));
        };
        if trajectory.is_some() {
            return Err(PyTypeError::new_err("trajectory: a fleet's scene takes its sessions from the fleet"));
        }
        let fleet_loops = fleet_loops.get();
        let loops = Arc::clone(&fleet_loops.inner);
        let fleet = Arc::clone(&fleet_loops.fleet.get().inner);
        let samples = Arc::clone(&fleet_samples.get().samples.bind(py).get().inner);
        let inner = detached(py, move || Ok(loops_io::Scene::of_fleet(&fleet, None, &loops, &samples)?))?;
        return Ok(Scene { inner: Arc::new(inner) });
    }
    let (Ok(loops), Ok(samples)) = (loops.cast::<Loops>(), samples.cast::<Samples>()) else {
        return Err(PyTypeError::new_err(
            "loops and samples: a Loops with its Samples, or a FleetLoops with its FleetSamples",
        ));
    };
    let Some(trajectory) = trajectory else {
        return Err(PyTypeError::new_err("trajectory: the Trajectory the loops were found on is needed"));
    };
    let (loops, samples) = (Arc::clone(&loops.get().inner), Arc::clone(&samples.get().inner));
    let (traj, name) = (Arc::clone(&trajectory.inner), name.to_owned());
    let inner = detached(py, move || Ok(loops_io::Scene::of_trajectory(&name, &traj, None, None, &loops, &samples)?))?;
    Ok(Scene { inner: Arc::new(inner) })
}

/// A `rows × K` float64 array of `rows`.
fn matrix<'py, const K: usize>(py: Python<'py>, rows: &[[f64; K]]) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Ok(PyArray1::from_vec(py, flat).reshape([rows.len(), K])?.into_any())
}

#[pymethods]
impl Scene {
    /// Writes the scene as MCAP for Foxglove and RViz: Foxglove's schemas on ``/loops/trajectory``
    /// (PosesInFrame), ``/loops/tau``, ``/loops/components``, ``/loops/candidates`` (SceneUpdate)
    /// and ``/loops/plane`` (RawImage), and a ROS 2 ``visualization_msgs/msg/MarkerArray`` on
    /// ``/loops/markers``. Atomic; beside it, :attr:`foxglove_layout` opens the right panels.
    ///
    /// Raises:
    ///     FileExistsError: ``path`` exists and ``overwrite`` is false.
    ///     OSError: the file cannot be written.
    #[pyo3(signature = (path, *, overwrite=false))]
    fn to_mcap(&self, py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<()> {
        let scene = Arc::clone(&self.inner);
        detached(py, move || Ok(loops_io::write_scene_mcap(&path, &scene, overwrite)?))
    }

    /// The Foxglove layout (JSON text) for the MCAP file: a 3D panel with the scene's topics
    /// and an Image panel with the plane.
    #[getter]
    fn foxglove_layout(&self) -> &'static str {
        loops_io::FOXGLOVE_LAYOUT
    }

    /// One dict per session: ``name``, ``timestamps_s`` (n), ``positions`` (n × 3),
    /// ``loop_duration_s`` (n, τ) and ``tau_rgba`` (n × 4, τ's colour in [0, 1]).
    #[getter]
    fn paths<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let max_tau = self.inner.max_loop_duration_s();
        self.inner
            .paths
            .iter()
            .map(|p| {
                let dict = PyDict::new(py);
                dict.set_item("name", &p.name)?;
                dict.set_item("timestamps_s", to_numpy(py, p.timestamps_s.clone()))?;
                dict.set_item("positions", matrix(py, &p.positions)?)?;
                dict.set_item("loop_duration_s", to_numpy(py, p.loop_duration_s.clone()))?;
                let colours: Vec<[f64; 4]> =
                    p.loop_duration_s.iter().map(|&t| loops_io::tau_rgba(t, max_tau)).collect();
                dict.set_item("tau_rgba", matrix(py, &colours)?)?;
                Ok(dict)
            })
            .collect()
    }

    /// One dict per component, in id order: ``id``, ``trivial``, ``sessions`` (a, b),
    /// ``poses`` ((i_min, i_max), (j_min, j_max)), ``closest_pair``, ``closest_distance``,
    /// ``area_s2``, ``pair_count`` and ``rgba`` (its colour in [0, 1]).
    #[getter]
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .components
            .iter()
            .map(|c| {
                let dict = PyDict::new(py);
                dict.set_item("id", c.id)?;
                dict.set_item("trivial", c.trivial)?;
                dict.set_item("sessions", (c.sessions[0], c.sessions[1]))?;
                dict.set_item("poses", ((c.poses[0][0], c.poses[0][1]), (c.poses[1][0], c.poses[1][1])))?;
                dict.set_item("closest_pair", (c.closest_pair[0], c.closest_pair[1]))?;
                dict.set_item("closest_distance", c.closest_distance)?;
                dict.set_item("area_s2", c.area_s2)?;
                dict.set_item("pair_count", c.pair_count)?;
                dict.set_item("rgba", c.rgba().to_vec())?;
                Ok(dict)
            })
            .collect()
    }

    /// The candidate pairs, in the samples' order: int64 columns ``session_a``, ``session_b``,
    /// ``i``, ``j`` (poses in their sessions) and ``component`` (−1 when unknown).
    #[getter]
    fn candidates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rows = &self.inner.candidates;
        let column = |value: &dyn Fn(&loops_io::SceneCandidate) -> i64| to_numpy(py, rows.iter().map(value).collect());
        let dict = PyDict::new(py);
        dict.set_item("session_a", column(&|c| c.sessions[0] as i64))?;
        dict.set_item("session_b", column(&|c| c.sessions[1] as i64))?;
        dict.set_item("i", column(&|c| c.poses[0] as i64))?;
        dict.set_item("j", column(&|c| c.poses[1] as i64))?;
        dict.set_item("component", column(&|c| c.component.map_or(-1, |id| id as i64)))?;
        Ok(dict)
    }

    /// The (t, t′) plane: uint8 array (height, width, 3), row 0 the latest t′ (t′ up), each
    /// component in its colour, candidates white.
    #[getter]
    fn plane<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let plane = &self.inner.plane;
        Ok(PyArray1::from_vec(py, plane.rgb.clone()).reshape([plane.height, plane.width, 3])?.into_any())
    }

    /// The frame every entity is in.
    #[getter]
    fn frame_id(&self) -> &str {
        &self.inner.frame_id
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({} session(s), {} components, {} candidates)",
            self.inner.paths.len(),
            self.inner.components.len(),
            self.inner.candidates.len()
        )
    }
}
