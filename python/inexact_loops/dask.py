"""A fleet's loops on a Dask cluster, with the answer of :func:`inexact_loops.find_fleet_loops`.

:func:`find_fleet_loops_dask` cuts the fleet's plane into tiles (blocks of rows x columns of one
session pair, only where the blocks' bounding balls come within gamma), scans each tile where
its two sessions are read, and merges the tiles' summaries in a tree of reductions. Without
``client=`` every step runs in this process (Dask is not imported); with a
``dask.distributed.Client`` the same call runs on its cluster::

    loops = find_fleet_loops_dask(paths, gamma=20.0)                 # this machine
    loops = find_fleet_loops_dask(paths, gamma=20.0, client=client)  # the cluster

What travels: the client sends paths, tiles and options, never poses. One task per session
reads it and returns its pose count, span and block balls (:class:`~inexact_loops.SessionBlocks`,
a few bytes per block); the client plans the tiles from those alone; each tile's task reads its
two sessions (each worker keeps the last few it read) and returns a
:class:`~inexact_loops.TileSummary` (statistics of its provisional components and the runs on
its edges); merge tasks combine groups of summaries into :class:`~inexact_loops.TileMerge`
objects, which keep only the edge runs still facing unmerged tiles, level by level, until one
is left; the client finishes it into the components and the overlap matrix. Every task is a
pure function of its inputs, so a worker that dies takes nothing with it: Dask reruns its
tasks and the answer is the same.

Requires ``dask[distributed]`` only with ``client=`` (``pip install 'inexact-loops[dask]'``).
"""

from __future__ import annotations

import functools
import os
import uuid
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from . import _core
from .errors import InvalidParameterError

__all__ = ["DEFAULT_BLOCK", "DEFAULT_FAN_IN", "find_fleet_loops_dask"]

#: Poses per block (the side of a tile) unless ``block=`` says otherwise: a tile of two blocks
#: of a city drive at 10 Hz scans in well under a second on one core. Not tuned by a cost model.
DEFAULT_BLOCK = 50_000

#: Summaries (or partial merges) combined by one merge task.
DEFAULT_FAN_IN = 8

#: Sessions each worker process keeps after reading them, for the next tiles that need them.
SESSIONS_KEPT = 4

_READ_OPTIONS = (
    "format",
    "axes",
    "topic",
    "time",
    "frames",
    "rate_hz",
    "drop_duplicate_stamps",
    "quaternion_tolerance",
)


def _hashable(value: Any) -> Any:
    """A read option as a hashable value (lists become tuples), for the worker's cache key."""
    if isinstance(value, list | tuple):
        return tuple(_hashable(v) for v in value)
    return value


@functools.lru_cache(maxsize=SESSIONS_KEPT)
def _read_session(source: str, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session read on the worker (kept for the worker's next tiles)."""
    return _core.read_trajectory(source, **dict(options))


def _describe_session(
    source: str, options: tuple[tuple[str, Any], ...], block: int, metric: Any
) -> _core.SessionBlocks:
    """Task: read one session, return what planning needs of it."""
    return _core.session_blocks(_read_session(source, options), block=block, metric=metric)


def _separation(value: Any) -> Any:
    """A separation as shipped (``"auto"``, ``None``, a path length or ``(path, time_s)``), for
    :func:`inexact_loops.scan_tile`."""
    if isinstance(value, tuple):
        return _core.Separation(path=value[0], time_s=value[1])
    return value


def _scan_session_tile(
    tile: _core.Tile,
    sources: tuple[str, str | None],
    options: tuple[tuple[str, Any], ...],
    starts: tuple[int, int],
    gamma: float,
    metric: str,
    separation: Any,
    threads: int | None,
) -> _core.TileSummary:
    """Task: read a tile's sessions (or find them kept), scan it without the GIL."""
    a = _read_session(sources[0], options)
    b = None if sources[1] is None else _read_session(sources[1], options)
    return _core.scan_tile(
        tile,
        a,
        b,
        starts=starts,
        gamma=gamma,
        metric=metric,
        separation=_separation(separation),
        threads=threads,
    )


def _merge(*parts: _core.TileSummary | _core.TileMerge) -> _core.TileMerge:
    """Task: one merge of the tree."""
    return _core.merge_tiles(list(parts))


def _stem_name(path: str) -> str:
    """The name a path gives its session, as :class:`inexact_loops.Fleet` names it: its file
    stem, or a rosbag2 bag's folder for ``metadata.yaml``."""
    p = Path(path)
    return p.parent.name if p.name == "metadata.yaml" else p.stem


def _named_sources(sessions: Any) -> list[tuple[str, str | _core.Trajectory]]:
    """``(name, path or Trajectory)`` per session, in order, named as ``il.Fleet`` names them."""
    if isinstance(sessions, Mapping):
        items = list(sessions.items())
        for name, _ in items:
            if not isinstance(name, str):
                raise TypeError(f"session names must be str, got {type(name).__name__} ({name!r})")
    elif isinstance(sessions, list | tuple):
        items = []
        stems: dict[str, tuple[int, str]] = {}
        for index, item in enumerate(sessions):
            if isinstance(item, tuple) and len(item) == 2:
                if not isinstance(item[0], str):
                    raise TypeError(
                        f"sessions[{index}] must be a (name, path) pair with a str name, "
                        f"got a {type(item[0]).__name__} name"
                    )
                items.append((item[0], item[1]))
            elif isinstance(item, str | os.PathLike):
                path = os.fspath(item)
                name = _stem_name(path)
                if name in stems:
                    first, other = stems[name]
                    raise InvalidParameterError(
                        f"sessions[{first}] ({other}) and sessions[{index}] ({path}) are both "
                        f"named {name!r} by their file stem: pass {{name: path}} to name them"
                    )
                stems[name] = (index, path)
                items.append((name, path))
            else:
                what = (
                    "a Trajectory without a name: pass (name, trajectory) or {name: trajectory}"
                    if isinstance(item, _core.Trajectory)
                    else f"a {type(item).__name__}"
                )
                raise TypeError(
                    f"sessions[{index}] must be a (name, path) pair or a path, got {what}"
                )
    else:
        raise TypeError(
            "sessions must be a dict {name: path}, a list of (name, path) pairs or a list of "
            f"paths, got {type(sessions).__name__}"
        )
    if not items:
        raise InvalidParameterError("a fleet needs at least one session")
    seen: set[str] = set()
    out: list[tuple[str, str | _core.Trajectory]] = []
    for name, source in items:
        if name in seen:
            raise InvalidParameterError(
                f"two sessions are named {name!r}: session names must be unique"
            )
        seen.add(name)
        if isinstance(source, _core.Trajectory):
            out.append((name, source))
        elif isinstance(source, str | os.PathLike):
            out.append((name, os.fspath(source)))
        else:
            raise TypeError(
                f"session {name!r} must be a path (or, without client=, a Trajectory), "
                f"got {type(source).__name__}"
            )
    return out


def _shipped_separation(separation: Any) -> Any:
    """A separation in a form every worker can unpickle."""
    if isinstance(separation, _core.Separation):
        return (separation.path, separation.time_s)
    return separation


def _reduce(parts: list[Any], merge: Callable[[list[Any]], Any], fan_in: int) -> Any:
    """Merges ``parts`` in groups of ``fan_in`` consecutive ones, level by level, to one."""
    if len(parts) == 1:
        return merge(parts)
    while len(parts) > 1:
        parts = [merge(parts[k : k + fan_in]) for k in range(0, len(parts), fan_in)]
    return parts[0]


def find_fleet_loops_dask(
    sessions: Any,
    gamma: float,
    *,
    client: Any = None,
    block: int = DEFAULT_BLOCK,
    separation: Any = "auto",
    metric: Any = None,
    fan_in: int = DEFAULT_FAN_IN,
    threads: int | None = None,
    format: str | None = None,
    axes: tuple[int, int] | None = None,
    topic: str | None = None,
    time: str | None = None,
    frames: tuple[str, str] | None = None,
    rate_hz: float | None = None,
    drop_duplicate_stamps: bool = False,
    quaternion_tolerance: float | None = None,
) -> _core.TiledFleetLoops:
    """Finds every inexact loop of a fleet from tiles, on this machine or on a Dask cluster:
    the components and the overlap matrix of :func:`inexact_loops.find_fleet_loops` on the same
    sessions (the same ids, sessions, poses, times, pair counts, holes and closest pairs; areas
    to rounding, a relative 1e-12).

    Args:
        sessions: a list of paths (each session named by its file stem, as :class:`Fleet`
            names it), a dict ``{name: path}`` or a list of ``(name, path)`` pairs. Without
            ``client=`` a session may also be a :class:`Trajectory`; with it, workers read every
            session from its path, which they must reach.
        gamma: the distance threshold gamma > 0, in the metric's unit.
        client: a ``dask.distributed.Client``: the tasks run on its cluster. ``None``: in this
            process, without Dask.
        block: poses per block, the side of a tile: the unit of work and of a task's memory.
            The result does not depend on it.
        separation: within each session, as in :func:`find_fleet_loops` (``"auto"``: 4 gamma of
            path; ``None``: the paper's S_gamma).
        metric: a metric name or an ``inexact_loops.metrics`` object (not a callable);
            ``None``: the sessions' own, which must agree.
        fan_in: summaries combined by one merge task (at least 2).
        threads: threads of each tile's scan; ``None``: one per core in this process, one per
            task on a cluster (Dask's worker threads share the cores).
        format, axes, topic, time, frames, rate_hz, drop_duplicate_stamps,
            quaternion_tolerance: how the paths are read, as in :func:`read_trajectory`.

    Returns:
        :class:`TiledFleetLoops`: ``components``, ``session_pairs()``, ``overlap_matrix()``.

    Raises:
        InvalidParameterError: no session, two sessions of one name, sessions measured with
            different metrics, a block of 0 poses, a fan-in below 2, and as
            :func:`find_fleet_loops`.
        TypeError: a session of another type; a Trajectory with ``client=``.
        OSError, LoopsIOError, InvalidTrajectoryError: a session that cannot be read, as
            :func:`read_trajectory`.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> from inexact_loops.dask import find_fleet_loops_dask
        >>> x = np.arange(21) * 0.5
        >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
        >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
        >>> sessions = {"monday": monday, "tuesday": tuesday}
        >>> tiled = find_fleet_loops_dask(sessions, 1.0, block=8, separation=None)
        >>> tiled.overlap_matrix()  # as il.find_fleet_loops(il.Fleet(sessions), ...) gives it
        array([[93.5, 57.5],
               [57.5, 93.5]])
    """
    if fan_in < 2:
        raise InvalidParameterError(f"fan_in = {fan_in} is invalid: a merge takes at least 2 parts")
    named = _named_sources(sessions)
    names = [name for name, _ in named]
    read = {
        "format": format,
        "axes": axes,
        "topic": topic,
        "time": time,
        "frames": frames,
        "rate_hz": rate_hz,
        "drop_duplicate_stamps": drop_duplicate_stamps,
        "quaternion_tolerance": quaternion_tolerance,
    }
    options = tuple(
        (key, _hashable(read[key]))
        for key in _READ_OPTIONS
        if read[key] is not None and read[key] is not False
    )
    shipped = _shipped_separation(separation)
    if metric is not None and not isinstance(metric, str) and hasattr(metric, "spec"):
        metric = metric.spec  # an inexact_loops.metrics object, as the text every worker parses
    if client is None:
        return _in_process(named, names, options, gamma, block, shipped, metric, fan_in, threads)
    trajectories = [name for name, source in named if isinstance(source, _core.Trajectory)]
    if trajectories:
        raise TypeError(
            f"session {trajectories[0]!r} is a Trajectory: with client=, workers read every "
            "session from a path (the client ships no poses): write it to a file, or run "
            "without client="
        )
    sources = [str(source) for _, source in named]
    token = uuid.uuid4().hex[:12]
    described = [
        client.submit(
            _describe_session, source, options, block, metric, key=f"describe-session-{token}-{k}"
        )
        for k, source in enumerate(sources)
    ]
    blocks = client.gather(described)
    tiles = _core.plan_tiles(blocks, gamma=gamma, metric=metric)
    starts = _starts(blocks)
    metric_name = blocks[0].metric_name
    scans = []
    for k, tile in enumerate(tiles):
        a, b = tile.sessions
        scans.append(
            client.submit(
                _scan_session_tile,
                tile,
                (sources[a], None if a == b else sources[b]),
                options,
                (starts[a], starts[b]),
                gamma,
                metric_name,
                shipped,
                1 if threads is None else threads,
                key=f"scan-tile-{token}-{k}",
            )
        )
    level = iter(range(1 << 30))

    def merge_on_cluster(parts: list[Any]) -> Any:
        return client.submit(_merge, *parts, key=f"merge-tiles-{token}-{next(level)}")

    final = client.gather(_reduce(scans, merge_on_cluster, fan_in))
    return final.finish(blocks, names=names)


def _starts(blocks: Sequence[_core.SessionBlocks]) -> list[int]:
    """The sessions' first fleet indices."""
    starts, total = [], 0
    for b in blocks:
        starts.append(total)
        total += b.poses
    return starts


def _in_process(
    named: list[tuple[str, str | _core.Trajectory]],
    names: list[str],
    options: tuple[tuple[str, Any], ...],
    gamma: float,
    block: int,
    separation: Any,
    metric: Any,
    fan_in: int,
    threads: int | None,
) -> _core.TiledFleetLoops:
    """The steps of the cluster, in this process: each session read once, tiles one by one."""
    trajectories = [
        source
        if isinstance(source, _core.Trajectory)
        else _core.read_trajectory(source, **dict(options))
        for _, source in named
    ]
    blocks = [_core.session_blocks(t, block=block, metric=metric) for t in trajectories]
    tiles = _core.plan_tiles(blocks, gamma=gamma, metric=metric)
    starts = _starts(blocks)
    metric_name = blocks[0].metric_name
    summaries = []
    for tile in tiles:
        a, b = tile.sessions
        summaries.append(
            _core.scan_tile(
                tile,
                trajectories[a],
                None if a == b else trajectories[b],
                starts=(starts[a], starts[b]),
                gamma=gamma,
                metric=metric_name,
                separation=_separation(separation),
                threads=threads,
            )
        )
    final = _reduce(summaries, _core.merge_tiles, fan_in)
    return final.finish(blocks, names=names)
