"""The results in robotics viewers: Foxglove, RViz and Rerun.

- :func:`to_mcap`: an MCAP file for Foxglove (and, through ``ros2 bag play``, RViz), with the
  Foxglove layout beside it; ``loops run --mcap`` and ``loops fleet --mcap`` write the same.
- :func:`to_rerun`: a Rerun recording (``.rrd``) of the same entities; needs ``rerun-sdk``
  (``pip install '.[rerun]'`` in a checkout).
- Live, while the log plays: ``loops replay LOG --serve`` serves the online engine's keyframes
  over Foxglove's WebSocket protocol on the topics below (the plane every 100 poses and at the
  end); from Python, :func:`serve` starts the same server for the keyframes of an
  :class:`~inexact_loops.OnlineLoops` you push (a log's poses, or a robot's as they come).

Both draw one :class:`~inexact_loops._core.Scene`, built in Rust (:func:`scene`): a path per
session with τ along it as a colour, every loop component (its two stretches of path and its
closest pair, a colour each), the sampled candidate pairs, and the (t, t′) plane as an image.

MCAP topics:

======================  ====================================  ==================================
topic                   schema                                holds
======================  ====================================  ==================================
``/loops/trajectory``   ``foxglove.PosesInFrame``             the path so far, as the log plays
``/loops/tau``          ``foxglove.SceneUpdate``              the path so far coloured by τ
``/loops/components``   ``foxglove.SceneUpdate``              ``component/<id>``: 3 lines each
``/loops/candidates``   ``foxglove.SceneUpdate``              one line a candidate pair
``/loops/plane``        ``foxglove.RawImage``                 the (t, t′) plane, rgb8
``/loops/markers``      ``visualization_msgs/msg/MarkerArray``  the same for RViz (ROS 2 CDR)
======================  ====================================  ==================================

In the file, each session's path and τ grow as the log plays: up to 100 messages a session,
each at a pose's time with every pose up to it, the last with the whole path (a long path gets
fewer, so that the repeated poses stay within about 200,000 a session).

Rerun entities: ``loops/trajectory/<session>`` (points), ``loops/tau/<session>`` (points
coloured by τ), ``loops/components/<id>`` (line strips and the components.csv values),
``loops/candidates`` (one strip a pair) and ``loops/plane`` (image), all static.

Example:
    >>> import os, tempfile, inexact_loops as il
    >>> from inexact_loops import viewers
    >>> traj = il.urban_drive(duration_s=600.0)
    >>> loops = il.find_loops(traj, gamma=40.0)
    >>> samples = il.sample(loops, "one", budget=20, seed=0, trajectory=traj)
    >>> folder = tempfile.mkdtemp()
    >>> viewers.to_mcap(loops, samples, os.path.join(folder, "results.mcap"), trajectory=traj)
    >>> sorted(os.listdir(folder))
    ['foxglove-layout.json', 'results.mcap']
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

from ._core import LiveServer, Scene, scene, write_file

__all__ = ["LAYOUT_FILE", "LiveServer", "Scene", "scene", "serve", "to_mcap", "to_rerun"]

#: The name of the Foxglove layout file written beside an MCAP file.
LAYOUT_FILE = "foxglove-layout.json"


def to_mcap(
    loops: Any,
    samples: Any,
    path: str | os.PathLike[str],
    *,
    trajectory: Any = None,
    name: str = "trajectory",
    overwrite: bool = False,
) -> None:
    """Write ``loops`` and ``samples`` as an MCAP file for Foxglove and RViz, and the Foxglove
    layout (:data:`LAYOUT_FILE`) beside it.

    Args:
        loops: a :class:`~inexact_loops.Loops` (with ``trajectory``) or a
            :class:`~inexact_loops.FleetLoops`.
        samples: its :class:`~inexact_loops.Samples` (:class:`~inexact_loops.FleetSamples`).
        path: the MCAP file.
        trajectory: the :class:`~inexact_loops.Trajectory` of ``loops`` (not for a fleet).
        name: the trajectory's session name.
        overwrite: replace existing files.

    Raises:
        FileExistsError: ``path`` or the layout file exists and ``overwrite`` is false (nothing
            is written then).
    """
    path = Path(path)
    layout = path.with_name(LAYOUT_FILE)
    if not overwrite:
        for existing in (path, layout):
            if os.path.lexists(existing):
                raise FileExistsError(f"{existing} exists; pass overwrite=True to replace it")
    made = scene(loops, samples, trajectory, name=name)
    made.to_mcap(path, overwrite=overwrite)
    write_file(layout, made.foxglove_layout.encode(), overwrite=overwrite)


def serve(address: str = "127.0.0.1:0", *, name: str = "live") -> LiveServer:
    """Start a live server for Foxglove, as ``loops replay --serve`` does, and return it.

    Connect Foxglove to ``ws://`` + :attr:`LiveServer.address` (Open connection, Foxglove
    WebSocket). Push poses into an :class:`~inexact_loops.OnlineLoops` and hand each update, with
    an :class:`~inexact_loops.OnlineSampler`'s candidates, to :meth:`LiveServer.send`; Foxglove
    shows the path, τ, the components and the candidates as they come, on the topics of the
    module's table. Stopping the server (:meth:`LiveServer.close`, or leaving the ``with``
    block) tells the clients and closes its port.

    Args:
        address: ``HOST:PORT`` to listen on; port 0 picks a free port.
        name: the log's name (the τ entity's id, ``tau/<name>``).

    Raises:
        ValueError: an address that is not ``HOST:PORT``.
        OSError: the address cannot be bound (a port taken, or not this machine's).

    Example:
        >>> import inexact_loops as il
        >>> from inexact_loops import viewers
        >>> traj = il.urban_drive(duration_s=60.0)
        >>> online = il.OnlineLoops(gamma=40.0, dim=traj.dim)
        >>> sampler = il.OnlineSampler()
        >>> with viewers.serve("127.0.0.1:0", name="drive") as server:
        ...     _ = server.wait_for_client(timeout_s=0.0)  # no Foxglove here: start at once
        ...     for t, point in zip(traj.timestamps, traj.positions):
        ...         update = online.push(t, point)
        ...         server.send(online, update, sampler.offer(online, update))
        ...     server.send_plane(online)
        >>> server.closed
        True
    """
    return LiveServer(address, name=name)


def to_rerun(
    loops: Any,
    samples: Any,
    path: str | os.PathLike[str],
    *,
    trajectory: Any = None,
    name: str = "trajectory",
    overwrite: bool = False,
) -> None:
    """Write ``loops`` and ``samples`` as a Rerun recording (``.rrd``): the entities of the
    module's table, all static, for ``rerun path.rrd``. Arguments as :func:`to_mcap`.

    The file is written beside ``path`` under a temporary name, then moved into place.

    Raises:
        FileExistsError: ``path`` exists and ``overwrite`` is false.
        ImportError: ``rerun-sdk`` is not installed.
    """
    try:
        import rerun as rr
    except ImportError as err:  # pragma: no cover - exercised only without rerun-sdk
        raise ImportError(
            "to_rerun needs rerun-sdk: pip install rerun-sdk "
            "(or, in a checkout, pip install '.[rerun]')"
        ) from err
    path = Path(path)
    if not overwrite and os.path.lexists(path):
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    made = scene(loops, samples, trajectory, name=name)
    with tempfile.TemporaryDirectory(prefix="loops-rerun-") as scratch:
        partial = Path(scratch) / "recording.rrd"
        rec = rr.RecordingStream("inexact-loops", recording_id=f"loops-{path.stem}")
        rec.save(partial)
        _log_scene(rr, rec, made)
        rec.flush()
        rec.disconnect()
        write_file(path, partial.read_bytes(), overwrite=overwrite)


def _log_scene(rr: Any, rec: Any, made: Scene) -> None:
    """Logs every entity of ``made`` into ``rec``, static."""
    import numpy as np

    paths = made.paths
    for p in paths:
        rec.log(f"loops/trajectory/{p['name']}", rr.Points3D(p["positions"]), static=True)
        rec.log(
            f"loops/tau/{p['name']}",
            rr.Points3D(p["positions"], colors=p["tau_rgba"]),
            rr.AnyValues(loop_duration_s=p["loop_duration_s"]),
            static=True,
        )
    for c in made.components:
        (a, b), ((i0, i1), (j0, j1)), (ci, cj) = c["sessions"], c["poses"], c["closest_pair"]
        strips = [
            paths[a]["positions"][i0 : i1 + 1],
            paths[b]["positions"][j0 : j1 + 1],
            np.stack([paths[a]["positions"][ci], paths[b]["positions"][cj]]),
        ]
        values = {
            key: c[key] for key in ("id", "trivial", "closest_distance", "area_s2", "pair_count")
        }
        rec.log(
            f"loops/components/{c['id']}",
            rr.LineStrips3D(strips, colors=[c["rgba"]] * 3),
            rr.AnyValues(
                **values, i_min=i0, i_max=i1, j_min=j0, j_max=j1, closest_i=ci, closest_j=cj
            ),
            static=True,
        )
    cand = made.candidates
    pairs = [
        np.stack([paths[a]["positions"][i], paths[b]["positions"][j]])
        for a, b, i, j in zip(
            cand["session_a"], cand["session_b"], cand["i"], cand["j"], strict=True
        )
    ]
    rec.log("loops/candidates", rr.LineStrips3D(pairs, colors=[[1.0, 1.0, 1.0, 0.9]]), static=True)
    rec.log("loops/plane", rr.Image(made.plane), static=True)
