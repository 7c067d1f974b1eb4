//! `LiveServer`: the live server of `loops replay --serve` (`loops_cli::LiveServer`, Foxglove's
//! WebSocket protocol) from Python, serving the keyframes of an `OnlineLoops` that Python
//! pushes; the messages are `loops_io::LiveScene`'s, as the command's.

use std::net::SocketAddr;
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyType;

use crate::py_online::{OnlineLoops, Update};
use crate::py_online_sampler::Candidate;

/// The most messages queued for one client (the command's own bound).
const BACKLOG: usize = 1 << 16;

/// How often :meth:`LiveServer.wait_for_client` looks at its clients and at Ctrl-C.
const POLL: Duration = Duration::from_millis(20);

/// A server of the live scene over Foxglove's WebSocket protocol, on the topics and in the
/// schemas of ``loops replay --serve`` (see :mod:`inexact_loops.viewers`); made by
/// :func:`inexact_loops.viewers.serve`. Each :meth:`send` sends one keyframe's messages to the
/// clients subscribed then (no history is kept: :meth:`wait_for_client` first).
/// :meth:`close` (or leaving a ``with`` block) stops it and closes its port.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct LiveServer {
    name: String,
    /// The poses pushed so far and the candidates sent, for the plane.
    scene: Mutex<loops_io::LiveScene>,
    address: SocketAddr,
    /// `None` once closed.
    server: Mutex<Option<loops_cli::LiveServer>>,
}

impl LiveServer {
    /// Runs `f` on the server, or says that it is closed.
    fn with_server<T>(&self, f: impl FnOnce(&loops_cli::LiveServer) -> PyResult<T>) -> PyResult<T> {
        let server = self.server.lock().unwrap_or_else(PoisonError::into_inner);
        let server = server.as_ref().ok_or_else(|| PyValueError::new_err("the live server is closed"))?;
        f(server)
    }
}

#[pymethods]
impl LiveServer {
    /// Starts serving on ``address`` (``HOST:PORT``; port 0: a free port, see
    /// :attr:`address`), the log named ``name`` (the τ entity's id, ``tau/<name>``).
    ///
    /// Raises:
    ///     ValueError: an address that is not ``HOST:PORT``.
    ///     OSError: when the address cannot be bound (taken, or not this machine's).
    #[new]
    #[pyo3(signature = (address = "127.0.0.1:0", *, name = "live"))]
    fn new(address: &str, name: &str) -> PyResult<Self> {
        let parsed: SocketAddr = address.parse().map_err(|error| {
            PyValueError::new_err(format!("address {address:?}: {error} (give HOST:PORT, e.g. 127.0.0.1:8765)"))
        })?;
        let server =
            loops_cli::LiveServer::start(parsed, BACKLOG).map_err(|error| PyOSError::new_err(format!("{error:#}")))?;
        let address = server.address();
        let scene = loops_io::LiveScene::new(name, Vec::new(), None).map_err(value_error)?;
        Ok(Self { name: name.to_owned(), scene: Mutex::new(scene), address, server: Mutex::new(Some(server)) })
    }

    /// Where it serves, ``HOST:PORT`` (the port picked for port 0); a client connects to
    /// ``ws://HOST:PORT``.
    #[getter]
    fn address(&self) -> String {
        self.address.to_string()
    }

    /// Its port.
    #[getter]
    fn port(&self) -> u16 {
        self.address.port()
    }

    /// Whether :meth:`close` was called.
    #[getter]
    fn closed(&self) -> bool {
        self.server.lock().unwrap_or_else(PoisonError::into_inner).is_none()
    }

    /// Waits until a client has subscribed to every channel, or a second after a client's first
    /// subscription (Foxglove subscribes only to what its panels show), at most ``timeout_s``
    /// seconds (``None``: no limit). The GIL is released while it waits; Ctrl-C stops it
    /// (``KeyboardInterrupt``).
    ///
    /// Returns:
    ///     ``True`` when a client is there, ``False`` after ``timeout_s``.
    #[pyo3(signature = (timeout_s = None))]
    fn wait_for_client(&self, py: Python<'_>, timeout_s: Option<f64>) -> PyResult<bool> {
        let deadline = match timeout_s {
            Some(t) if !(t >= 0.0 && t.is_finite()) => {
                return Err(PyValueError::new_err(format!("timeout_s = {t}: give seconds, 0 or more")));
            }
            Some(t) => Some(Instant::now() + Duration::from_secs_f64(t)),
            None => None,
        };
        loop {
            if self.with_server(|server| Ok(server.has_client()))? {
                return Ok(true);
            }
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return Ok(false);
            }
            py.detach(|| std::thread::sleep(POLL));
            py.check_signals()?;
        }
    }

    /// Sends the keyframe that ``update`` reports (``online``'s last push) with the
    /// ``candidates`` an :class:`OnlineSampler` offered for it: the path so far, τ along it,
    /// the components it changed, its candidates, the ROS ``MarkerArray`` of the same, and the
    /// (t, t′) plane each time the poses pass a multiple of 100. Nothing before the second pose
    /// (one pose draws nothing).
    ///
    /// Raises:
    ///     ValueError: when the server is closed, or ``update`` or ``candidates`` name a pose
    ///         ``online`` does not hold.
    #[pyo3(signature = (online, update, candidates = Vec::new()))]
    fn send(
        &self,
        py: Python<'_>,
        online: &OnlineLoops,
        update: &Update,
        candidates: Vec<PyRef<'_, Candidate>>,
    ) -> PyResult<()> {
        let candidates: Vec<loops_core::online::Candidate> = candidates.iter().map(|c| c.inner).collect();
        let engine = online.engine.lock(py)?;
        let Some(traj) = engine.inner.trajectory() else { return Ok(()) };
        let mut scene = self.scene.lock().unwrap_or_else(PoisonError::into_inner);
        scene.set_poses(loops_io::point_positions(traj), None).map_err(value_error)?;
        let messages = scene.keyframe(&engine.inner, &update.inner, &candidates).map_err(value_error)?;
        drop(scene);
        drop(engine);
        self.with_server(|server| {
            server.send(&messages);
            Ok(())
        })
    }

    /// Sends the (t, t′) plane of the poses ``online`` holds (at the end of a log: the plane
    /// of all of it), each component in its colour and the candidates sent so far white, as in
    /// the MCAP file; nothing before the second pose.
    ///
    /// Raises:
    ///     ValueError: when the server is closed.
    fn send_plane(&self, py: Python<'_>, online: &OnlineLoops) -> PyResult<()> {
        let engine = online.engine.lock(py)?;
        let Some(traj) = engine.inner.trajectory() else { return Ok(()) };
        let mut scene = self.scene.lock().unwrap_or_else(PoisonError::into_inner);
        scene.set_poses(loops_io::point_positions(traj), None).map_err(value_error)?;
        let plane = scene.plane(&engine.inner).map_err(value_error)?;
        drop(scene);
        drop(engine);
        self.with_server(|server| {
            server.send(&Vec::from_iter(plane));
            Ok(())
        })
    }

    /// Stops the server: its clients are told, its port is closed. Closing twice does nothing.
    fn close(&self, py: Python<'_>) {
        let server = self.server.lock().unwrap_or_else(PoisonError::into_inner).take();
        if let Some(server) = server {
            py.detach(|| server.close());
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (_kind = None, _value = None, _traceback = None))]
    fn __exit__(
        &self,
        py: Python<'_>,
        _kind: Option<&Bound<'_, PyType>>,
        _value: Option<&Bound<'_, PyAny>>,
        _traceback: Option<&Bound<'_, PyAny>>,
    ) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        let state = if self.closed() { "closed" } else { "serving" };
        format!("LiveServer(address={:?}, name={:?}, {state})", self.address.to_string(), self.name)
    }
}

/// A core error about the caller's input, as `ValueError`.
fn value_error(error: loops_core::Error) -> PyErr {
    PyValueError::new_err(error.to_string())
}
