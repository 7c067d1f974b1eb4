"""A fleet's loops on a Dask cluster, with the answer of :func:`inexact_loops.find_fleet_loops`.

:func:`find_fleet_loops_dask` cuts the fleet's plane into tiles (blocks of rows x columns of one
session pair, only where the blocks' bounding balls come within gamma), scans each tile where
its two sessions are read, and merges the tiles' summaries in a tree of reductions. Without
``client=`` every step runs in this process (Dask is not imported); with a
``dask.distributed.Client`` the same call runs on its cluster::

    loops = find_fleet_loops_dask(paths, gamma=20.0)                 # this machine
    loops = find_fleet_loops_dask(paths, gamma=20.0, client=client)  # the cluster
    samples = loops.sample(budget=500, seed=0)                       # sample_fleet's samples

What travels: the client sends paths, tiles and options, never poses. One task per session
reads it and returns its pose count, span and block balls (:class:`~inexact_loops.SessionBlocks`,
a few bytes per block); the client plans the tiles from those alone; each tile's task reads its
two sessions (each worker keeps the last few it read) and returns a
:class:`~inexact_loops.TileSummary` (statistics of its provisional components and the runs on
its edges); merge tasks combine groups of summaries into :class:`~inexact_loops.TileMerge`
objects, which keep only the edge runs still facing unmerged tiles, level by level, until one
is left; the client finishes it into the components and the overlap matrix. Samples are drawn
by keys (:class:`~inexact_loops.KeyedDraw`): the client works out each component's quota from
the merged statistics, and each tile offers the few pairs asked of it
(:func:`~inexact_loops.draw_tile`) from the runs its scan kept on the worker that scanned it
(:data:`RUNS_KEPT`; the draws of a scan task's tiles are sent to that worker), rescanning the
tile only when they are gone (evicted, or the worker restarted). The samples are
:func:`~inexact_loops.sample_fleet`'s, pair for pair, whatever the tiling, the workers and
where the runs were found. Loop duration per pose (``loop_duration=True``) comes from each
tile's share (:func:`~inexact_loops.scan_tile_with_duration`), added up per session. Every
task's result depends on its inputs alone (kept runs only save work), so a worker that dies
takes nothing with it: Dask reruns its tasks and the answer is the same. A run never waits for
ever: its tasks that wait for a worker are sent to the running ones, and when none can take
them for :data:`NO_WORKER_TIMEOUT_S` the run raises :class:`ClusterError` and cancels them.

A session that cannot be read (a missing or corrupt log, or one whose dimension or metric
differs from the others') is left out with a one-line error in :attr:`FleetRun.failures`; the
rest of the fleet is computed without it (``on_error="raise"`` raises instead).

:func:`run_fleet_dask` writes the tables as Parquet into an output folder (the command
``loops-dask``, :func:`main`, is its command line).

Requires ``dask[distributed]`` only with ``client=``, and pyarrow for Parquet
(``pip install '.[dask]'`` in a checkout).
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import json
import operator
import os
import pickle
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import _console, _core
from ._core import DEFAULT_SAMPLER
from .errors import InvalidParameterError, LoopsError, LoopsIOError
from .table import Table

__all__ = [
    "DEFAULT_BLOCK",
    "DEFAULT_FAN_IN",
    "NO_WORKER_TIMEOUT_S",
    "ClusterError",
    "FleetRun",
    "find_fleet_loops_dask",
    "local_client",
    "main",
    "read_pose_parquet",
    "run_fleet_dask",
    "write_pose_parquet",
]

#: The smallest block ``block=None`` chooses, and the unit each session is first cut into:
#: a tile of two such blocks of a city drive at 10 Hz scans in well under a second on one core
#: (BENCHMARKS.md, "Dask"). The core's constant (:attr:`inexact_loops.FleetStore.DEFAULT_BLOCK`),
#: so that a store and a Dask run cut sessions alike.
DEFAULT_BLOCK: int = _core.FleetStore.DEFAULT_BLOCK

#: The largest block ``block=None`` chooses: a tile's memory (its piece of poses and its
#: runs) grows with the block.
MAX_AUTO_BLOCK = 1_000_000

#: Summaries (or partial merges) combined by one merge task.
DEFAULT_FAN_IN = 8

#: Poses each worker process keeps of the sessions it has read, for the next tiles that need
#: them (a pose takes 32-40 bytes: 3 * 10^7 poses are ~1.2 GB); the least recently used go
#: first, and the last one read is always kept. Enough for the sessions of ~25 vehicles of
#: 28 h: a worker that scans consecutive sessions then reads each of its sessions and their
#: neighbours about once (with 10^7, a fleet of 10^8 poses spent half its scan tasks' time
#: reading sessions again).
POSES_KEPT = 30_000_000

#: Bytes of runs each worker process keeps of the tiles it scanned, for their draws (a run
#: takes 16 bytes, a row 8: :attr:`TileRuns.nbytes`); the least recently used tiles go first.
#: A draw of a tile whose runs are not kept (evicted, scanned elsewhere, or the worker
#: restarted) rescans the tile: the samples are the same. 0: keep none. ``None``:
#: :data:`RUNS_KEPT_SHARE` of the Dask worker's memory limit (of the machine's memory outside
#: a worker). A district fleet's runs take 66-73 bytes a pose (BENCHMARKS.md, "Dask"): a
#: worker of a 10 GB limit keeps those of ~7 * 10^7 poses.
RUNS_KEPT: int | None = None

#: The share of a worker's memory limit :data:`RUNS_KEPT` ``= None`` keeps runs in (Dask
#: spills its own data from 60% and pauses the worker at 80%; the runs are not Dask's data).
RUNS_KEPT_SHARE = 0.5

#: How long, in seconds, the tasks of a run may wait with no worker to run them (Dask's
#: "no-worker" state: every worker gone, restarting or paused) before the run gives up with
#: :class:`ClusterError`. A worker the cluster restarts takes a few seconds.
NO_WORKER_TIMEOUT_S = 120.0

#: How often, in seconds, a run waiting for its tasks asks the scheduler whether they can run.
_WAIT_POLL_S = 2.0

#: The tiles' runs a worker keeps, most recently used last: (run id, tile) -> (the scan task's
#: group, TileRuns).
_runs: collections.OrderedDict[Any, tuple[int, _core.TileRuns]] = collections.OrderedDict()
_runs_held = 0
#: This process's draws of a tile from kept runs ("hits") and from rescans ("misses").
_runs_counts = {"hits": 0, "misses": 0}
_runs_lock = threading.Lock()

#: The sessions a worker keeps, most recently used last: (source, options) -> Trajectory.
_kept: collections.OrderedDict[Any, _core.Trajectory] = collections.OrderedDict()
_kept_lock = threading.Lock()

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

#: The columns of a Parquet pose store.
_PARQUET_TIME = "t"
_PARQUET_POSITION = ("x", "y", "z")
_PARQUET_QUATERNION = ("qx", "qy", "qz", "qw")


def _pyarrow() -> Any:
    try:
        import pyarrow  # type: ignore[import-untyped, import-not-found, unused-ignore]
        import pyarrow.parquet  # type: ignore[import-untyped, import-not-found, unused-ignore]
    except ImportError as error:
        raise ImportError(
            "Parquet needs pyarrow, which is not installed: pip install '.[dask]' in a checkout "
            f"(or pip install pyarrow) ({error})"
        ) from error
    return pyarrow


def read_pose_parquet(path: str | os.PathLike[str], *, axes: tuple[int, int] | None = None) -> Any:
    """Reads a session from a Parquet pose store: a column ``t`` (seconds, increasing), the
    position ``x``, ``y`` and optionally ``z``, and optionally the orientation ``qx``, ``qy``,
    ``qz``, ``qw`` (then an SE(3) trajectory, measured by its translation unless a metric says
    otherwise). Read with pyarrow, only those columns.

    Args:
        path: the ``.parquet`` file.
        axes: a plane of two position axes (0 = x, 1 = y, 2 = z), as :func:`read_trajectory`.

    Returns:
        :class:`Trajectory`.

    Raises:
        LoopsIOError: a missing column, a null or non-numeric value, naming the file and column.
        InvalidTrajectoryError: times not increasing, non-finite values (naming the pose).
        ImportError: without pyarrow.

    Example:
        >>> import tempfile, pathlib, numpy as np, inexact_loops as il
        >>> from inexact_loops.dask import read_pose_parquet, write_pose_parquet
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "drive.parquet"
        >>> write_pose_parquet(path, il.Trajectory(np.arange(3.0), np.eye(3)))
        >>> len(read_pose_parquet(path))
        3
    """
    pa = _pyarrow()
    path = os.fspath(path)
    try:
        schema = pa.parquet.read_schema(path)
    except FileNotFoundError:
        raise
    except Exception as error:  # pyarrow's own errors: not a Parquet file, corrupt footer
        raise LoopsIOError(f"{path}: not a Parquet pose store: {error}") from error
    names = set(schema.names)
    missing = [c for c in (_PARQUET_TIME, "x", "y") if c not in names]
    if missing:
        raise LoopsIOError(
            f"{path}: a Parquet pose store needs the columns t, x, y (z, qx, qy, qz, qw optional); "
            f"missing {', '.join(missing)} (columns: {', '.join(schema.names)})"
        )
    position = [c for c in _PARQUET_POSITION if c in names]
    orientation = all(c in names for c in _PARQUET_QUATERNION)
    columns = [_PARQUET_TIME, *position, *(_PARQUET_QUATERNION if orientation else ())]
    try:
        table = pa.parquet.read_table(path, columns=columns)
    except Exception as error:
        raise LoopsIOError(f"{path}: cannot read the Parquet pose store: {error}") from error

    def column(name: str) -> np.ndarray:
        data = table.column(name)
        if data.null_count:
            raise LoopsIOError(f"{path}: column {name} has {data.null_count} null value(s)")
        try:
            return np.ascontiguousarray(data.to_numpy(), dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise LoopsIOError(f"{path}: column {name} is not numeric ({data.type})") from error

    t = column(_PARQUET_TIME)
    xyz = np.column_stack([column(c) for c in position])
    if orientation:
        if len(position) != 3:
            raise LoopsIOError(
                f"{path}: an orientation (qx, qy, qz, qw) needs the position x, y, z"
            )
        q = np.column_stack([column(c) for c in _PARQUET_QUATERNION])
        traj = _core.Trajectory.se3(t, xyz, q)
    else:
        traj = _core.Trajectory(t, xyz)
    if axes is not None:
        a, b = axes
        if max(a, b) >= xyz.shape[1] or a == b or min(a, b) < 0:
            raise InvalidParameterError(
                f"axes {axes} do not name two position axes of {path} ({xyz.shape[1]} coordinates)"
            )
        traj = _core.Trajectory(t, xyz[:, [a, b]])
    return traj


def write_pose_parquet(path: str | os.PathLike[str], trajectory: Any) -> None:
    """Writes a trajectory's times and positions (the first three coordinates, or two) as a
    Parquet pose store that :func:`read_pose_parquet` reads: columns ``t``, ``x``, ``y`` (and
    ``z``). Written to a temporary file beside ``path``, then renamed.

    Raises:
        ImportError: without pyarrow.
    """
    pa = _pyarrow()
    points = np.asarray(trajectory.positions)
    columns = {_PARQUET_TIME: np.asarray(trajectory.timestamps)}
    for k, name in enumerate(_PARQUET_POSITION[: min(3, points.shape[1])]):
        columns[name] = np.ascontiguousarray(points[:, k])
    table = pa.table(columns)
    _atomic(Path(path), lambda tmp: pa.parquet.write_table(table, tmp))


def _atomic(path: Path, write: Callable[[str], None]) -> None:
    """Writes ``path`` through a temporary file in its folder (``.NAME.XXXXXX.tmp``), renamed
    into place: a reader sees the old file or the new one, never half of one."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def _hashable(value: Any) -> Any:
    """A read option as a hashable value (lists become tuples), for the worker's cache key."""
    if isinstance(value, list | tuple):
        return tuple(_hashable(v) for v in value)
    return value


def _is_parquet(source: Any, options: dict[str, Any]) -> bool:
    if options.get("format") == "parquet":
        return True
    return isinstance(source, str) and source.lower().endswith(".parquet")


def _read_session(source: Any, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session read on the worker, kept for the worker's next tiles (up to
    :data:`POSES_KEPT` poses in all)."""
    key = (source, options)
    with _kept_lock:
        if key in _kept:
            _kept.move_to_end(key)
            return _kept[key]
    traj = _read_uncached(source, options)
    with _kept_lock:
        _kept[key] = traj
        total = sum(len(t) for t in _kept.values())
        while total > POSES_KEPT and len(_kept) > 1:
            _, dropped = _kept.popitem(last=False)
            total -= len(dropped)
    return traj


def _keep_runs(key: Any, group: int, runs: _core.TileRuns) -> None:
    """Keeps a tile's runs (scanned by the task of ``group``) for its draws (up to
    :data:`RUNS_KEPT` bytes in all)."""
    global _runs_held
    with _runs_lock:
        if key in _runs:
            _runs_held -= _runs.pop(key)[1].nbytes
        limit = _runs_limit()
        if runs.nbytes > limit:
            return
        _runs[key] = (group, runs)
        _runs_held += runs.nbytes
        while _runs_held > limit:
            _, (_, dropped) = _runs.popitem(last=False)
            _runs_held -= dropped.nbytes


def _runs_limit() -> int:
    """:data:`RUNS_KEPT` in bytes, worked out when it is ``None``."""
    if RUNS_KEPT is not None:
        return RUNS_KEPT
    memory = None
    if "distributed" in sys.modules:
        try:
            memory = sys.modules["distributed"].get_worker().memory_manager.memory_limit
        except (ValueError, AttributeError):
            memory = None  # not in a worker, or a worker without a limit
    if not memory:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    return int(RUNS_KEPT_SHARE * memory)


def _kept_runs(key: Any) -> _core.TileRuns | None:
    """A tile's kept runs, or ``None``; counted as a hit or a miss."""
    with _runs_lock:
        kept = _runs.get(key)
        if kept is not None:
            _runs.move_to_end(key)
        _runs_counts["hits" if kept is not None else "misses"] += 1
        return None if kept is None else kept[1]


def _kept_groups(run_id: str) -> dict[int, int]:
    """Of run ``run_id``: the scan tasks' groups whose tiles' runs this process keeps, and how
    many tiles of each."""
    with _runs_lock:
        return dict(collections.Counter(g for (r, _), (g, _) in _runs.items() if r == run_id))


def _forget_runs() -> dict[str, int]:
    """Drops every kept run of this process; returns the draws' hits and misses so far."""
    global _runs_held
    with _runs_lock:
        _runs.clear()
        _runs_held = 0
        return dict(_runs_counts)


def _read_uncached(source: Any, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session read in this process (not kept)."""
    read = dict(options)
    if _is_parquet(source, read):
        return read_pose_parquet(source, axes=read.get("axes"))
    if isinstance(source, tuple):
        source = list(source)
    return _core.read_trajectory(source, **read)


def _load(source: Any, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session: itself when in memory, else read (or found kept)."""
    if isinstance(source, _core.Trajectory):
        return source
    return _read_session(source, options)


class _Failed:
    """A session that could not be read or does not fit the fleet: its error, as data."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


def _describe_session(
    source: Any, options: tuple[tuple[str, Any], ...], block: int, metric: Any
) -> Any:
    """Task: read one session, return what planning needs of it (or its error, as data)."""
    try:
        traj = _load(source, options)
        return _core.session_blocks(traj, block=block, metric=metric), traj.manifold, traj.dim
    except (OSError, ValueError, TypeError) as error:
        return _Failed(error)


def _separation(value: Any) -> Any:
    """A separation as shipped (``"auto"``, ``None``, a path length or ``(path, time_s)``), for
    :func:`inexact_loops.scan_tile`."""
    if isinstance(value, tuple):
        return _core.Separation(path=value[0], time_s=value[1])
    return value


def _sessions_of(
    sources: tuple[Any, Any], options: tuple[tuple[str, Any], ...]
) -> tuple[_core.Trajectory, _core.Trajectory | None]:
    a = _load(sources[0], options)
    return a, None if sources[1] is None else _load(sources[1], options)


def _tile_kwargs(
    sources: tuple[Any, Any],
    options: tuple[tuple[str, Any], ...],
    starts: tuple[int, int],
    gamma: float,
    metric: str,
    separation: Any,
    threads: int | None,
) -> dict[str, Any]:
    """What a tile's scan or draw takes besides the tile: its sessions (read, or found kept) and
    the run's parameters."""
    a, b = _sessions_of(sources, options)
    return {
        "session_a": a,
        "session_b": b,
        "starts": starts,
        "gamma": gamma,
        "metric": metric,
        "separation": _separation(separation),
        "threads": threads,
    }


def _scan_session_tiles(
    tiles: list[tuple[_core.Tile, tuple[Any, Any], tuple[int, int]]],
    options: tuple[tuple[str, Any], ...],
    gamma: float,
    metric: str,
    separation: Any,
    threads: int | None,
    duration: bool,
    run_id: str,
    group: int,
) -> Any:
    """Task: scan a few tiles (each with its sessions' sources and first fleet indices) without
    the GIL and merge them: their :class:`TileMerge`; with ``duration``, also each tile's share
    of tau, in order. Keeps each tile's runs under ``(run_id, tile)`` for its draws, as scanned
    by the task of ``group``."""
    summaries, shares = [], []
    for tile, sources, starts in tiles:
        kwargs = _tile_kwargs(sources, options, starts, gamma, metric, separation, threads)
        summary, share, runs = _core.scan_tile_kept(tile, **kwargs)
        _keep_runs((run_id, tile), group, runs)
        summaries.append(summary)
        shares.append(share)
    if not duration:
        return _core.merge_tiles(summaries)
    return _core.merge_tiles(summaries), shares


def _draw_session_tiles(
    requests: list[tuple[Any, tuple[Any, Any], tuple[int, int]]],
    options: tuple[tuple[str, Any], ...],
    gamma: float,
    metric: str,
    separation: Any,
    threads: int | None,
    run_id: str,
) -> list[Any]:
    """Task: offer a few tiles' pairs to a pass of a keyed draw (an offer per request, in
    order), from the runs their scan kept in this process under ``(run_id, tile)``, or from a
    rescan where they are not kept."""
    return [
        _core.draw_tile(
            request,
            **_tile_kwargs(sources, options, starts, gamma, metric, separation, threads),
            runs=_kept_runs((run_id, request.tile)),
        )
        for request, sources, starts in requests
    ]


def _auto_block(longest: int) -> int:
    """The block ``block=None`` chooses for a fleet whose longest session has ``longest``
    poses: that session, rounded up to a multiple of :data:`DEFAULT_BLOCK`, and at most
    :data:`MAX_AUTO_BLOCK` (rounded down to a multiple).

    Why whole sessions: a vehicle that works one area for hours comes back to every part of
    its session, so a row block meets every block of its own session, and each tile queries
    its rows again: the scans cost more the more blocks a session is cut into. Measured on one
    core, tiles in one process against the engine on the same fleet (BENCHMARKS.md, "Dask"):
    25 sessions of 10^5 poses, 1.13x the engine in blocks of 10^5, 1.30x in blocks of 50,000;
    9 sessions of 10^6 poses, 1.16x in blocks of 10^6, 1.24x in blocks of 500,000 (and 14x
    in blocks of 50,000 on 4 such sessions).

    >>> _auto_block(100_000), _auto_block(120_000), _auto_block(10**8), _auto_block(10)
    (100000, 150000, 1000000, 50000)
    """
    units = max(1, min(-(-longest // DEFAULT_BLOCK), MAX_AUTO_BLOCK // DEFAULT_BLOCK))
    return units * DEFAULT_BLOCK


def _interleaved(items: list[Any], workers: list[Any]) -> list[Any]:
    """``items`` (each meant for the worker at the same place of ``workers``) in the order to
    submit them: each worker's first, then each one's second, and so on, so that every worker
    starts at once. Submitted in list order, the first worker's tasks would come first, the
    others would steal them (Dask's work stealing moves tasks with loose restrictions) and read
    their sessions, or rescan their runs, a second time.

    >>> _interleaved(["a1", "a2", "a3", "b1"], ["A", "A", "A", "B"])
    ['a1', 'b1', 'a2', 'a3']
    """
    queues: dict[Any, list[Any]] = {}
    for item, worker in zip(items, workers, strict=True):
        queues.setdefault(worker, []).append(item)
    out = []
    for round_ in range(max((len(q) for q in queues.values()), default=0)):
        out += [q[round_] for q in queues.values() if round_ < len(q)]
    return out


def _tile_groups(tiles: Sequence[_core.Tile], block: int) -> list[list[int]]:
    """The tiles of a plan in tasks: consecutive tiles of one row block (the plan lists a row
    block's tiles together), so that a task reads the row session once and the scheduler sees
    a task per block rather than per tile."""
    groups: list[list[int]] = []
    last: tuple[int, int] | None = None
    for t, tile in enumerate(tiles):
        key = (tile.sessions[0], tile.rows[0] // block)
        if key != last:
            groups.append([])
            last = key
        groups[-1].append(t)
    return groups


def _share(scan: Any, k: int) -> Any:
    """Task: the share of tau of the ``k``-th tile of a scan task."""
    return scan[1][k]


def _merge(*parts: Any) -> Any:
    """Task: one merge of the tree."""
    return _core.merge_tiles(list(parts))


def _session_tau(
    session: int, start: int, poses: int, folder: str | None, name: str, t_s: Any, *parts: Any
) -> Any:
    """Task: a session's tau from its tiles' shares; written as Parquet into ``folder`` (on
    the worker: the poses' tau never travels) or returned."""
    own, other = _core.session_loop_duration(session, start=start, poses=poses, parts=list(parts))
    if folder is None:
        return own, other
    pa = _pyarrow()
    table = pa.table(
        {
            "pose": np.arange(poses, dtype=np.int64),
            "t_s": np.asarray(t_s, dtype=np.float64),
            "own_s": own,
            "other_s": other,
        }
    )
    _atomic(Path(folder) / f"{name}.parquet", lambda tmp: pa.parquet.write_table(table, tmp))
    return poses


def _session_times(source: Any, options: tuple[tuple[str, Any], ...]) -> Any:
    """Task: a session's timestamps (for its tau table, on the worker that writes it)."""
    return np.asarray(_load(source, options).timestamps)


def _named_sources(sessions: Any) -> list[tuple[str, Any]]:
    """``(name, path, paths or Trajectory)`` per session, in order, named as ``il.Fleet``
    names them."""
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
                name = _core.log_name(path)
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
    out: list[tuple[str, Any]] = []
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
        elif (
            isinstance(source, list | tuple)
            and source
            and all(isinstance(p, str | os.PathLike) for p in source)
        ):
            # Several files read as one trajectory, as read_trajectory reads a list.
            out.append((name, tuple(os.fspath(p) for p in source)))
        else:
            raise TypeError(
                f"session {name!r} must be a path, a list of paths (or, without client=, a "
                f"Trajectory), got {type(source).__name__}"
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


def _one_line(error: BaseException) -> str:
    """An error as one line: its type and the first line of its message."""
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0] if text else ''}".rstrip(": ")


class ClusterError(LoopsError, RuntimeError):
    """The Dask cluster could not run a run's tasks: none of its workers could take them for
    :data:`NO_WORKER_TIMEOUT_S` seconds, or the workers running one of them died again and
    again (Dask's ``KilledWorker``, after ``distributed.scheduler.allowed-failures``). The
    run's tasks are cancelled: the cluster is free for the next run once it has workers."""


def _dispatch_stranded(token: str, dask_scheduler: Any = None) -> tuple[list[str], int, int]:
    """On the scheduler: sends the run ``token``'s tasks that wait in Dask's "no-worker" state
    to its running workers; returns the keys of the run's tasks that still cannot run (in
    "no-worker", or not done while no worker runs), the number of running workers and of all
    workers.

    A task with a preferred worker (``workers=``, ``allow_other_workers=True``) goes to
    "no-worker" when no worker is running at the moment it needs one (its worker was killed
    while the others were restarting or paused). Dask reconsiders it only when a worker joins
    at one of its preferred addresses, never for a new worker elsewhere (a restarted worker
    has a new address): without this it would wait for ever."""
    running = len(dask_scheduler.running)
    stranded = [
        key
        for key, task in dask_scheduler.tasks.items()
        if task.state == "no-worker" and token in str(key)
    ]
    if stranded and running:
        dask_scheduler.transitions(
            dict.fromkeys(stranded, "processing"), stimulus_id=f"stranded-{token}-{time.time()}"
        )
    stuck = [
        str(key)
        for key, task in dask_scheduler.tasks.items()
        if token in str(key)
        and (task.state == "no-worker" or (running == 0 and task.state not in ("memory", "erred")))
    ]
    return stuck, running, len(dask_scheduler.workers)


class _Runner:
    """Where tasks run: in this process (values), or on a Dask cluster (futures)."""

    def __init__(self, client: Any) -> None:
        self.client = client
        self.token = uuid.uuid4().hex[:12]
        self.count = 0
        self.sent = 0  # bytes of task arguments shipped from the client
        self.received = 0  # bytes of results gathered by the client
        self._workers: list[Any] | None = None
        #: Since when some of this run's tasks found no worker (None: they all have one).
        self._stuck_since: float | None = None

    def submit(self, name: str, fn: Callable[..., Any], *args: Any, worker: Any = None) -> Any:
        """``fn(*args)`` as a task; on ``worker`` (an address) if it can, else anywhere."""
        if self.client is None:
            return fn(*args)
        self.count += 1
        self.sent += len(pickle.dumps([a for a in args if not _is_future(a)], protocol=5))
        where = {} if worker is None else {"workers": [worker], "allow_other_workers": True}
        key = f"{name}-{self.token}-{self.count}"
        return self.client.submit(fn, *args, key=key, pure=False, **where)

    def worker_for(self, k: int, sessions: int) -> Any:
        """The worker that reads session ``k`` of ``sessions`` and scans its row blocks
        (``None`` without a cluster): the workers in address order take consecutive sessions,
        so that each session is read by one worker and kept there for its tiles, and the
        sessions next to it in the list (often the vehicles or days next to it) by few. Tasks
        go elsewhere when their worker is gone or busy (``allow_other_workers``, and Dask's
        work stealing)."""
        if self.client is None:
            return None
        if self._workers is None:
            self._workers = sorted(self.client.scheduler_info()["workers"])
        if not self._workers:
            return None
        return self._workers[k * len(self._workers) // max(sessions, 1)]

    def holders(self, groups: int) -> list[Any]:
        """For each of ``groups`` scan tasks, the worker that keeps the most of its tiles' runs
        (``None``: none, or no cluster)."""
        if self.client is None:
            return [None] * groups
        best: list[tuple[int, Any]] = [(0, None)] * groups
        # A worker that died meanwhile keeps nothing.
        for address, kept in self.client.run(_kept_groups, self.token, on_error="ignore").items():
            for g, tiles in kept.items():
                if tiles > best[g][0]:
                    best[g] = (tiles, address)
        return [address for _, address in best]

    def gather(self, items: list[Any]) -> list[Any]:
        """The values of ``items`` (futures or values), once their tasks are done.

        Raises:
            ClusterError: as :meth:`wait`; the task's own error when one failed.
        """
        if self.client is None:
            return items
        import distributed

        futures = [item for item in items if _is_future(item)]
        self._stuck_since = None
        try:
            self.wait(futures)
            values = [self._value(item) if _is_future(item) else item for item in items]
        except BaseException as error:
            # Nothing of this run is left to wait in the cluster for a worker.
            self.client.cancel(futures)
            if isinstance(error, distributed.KilledWorker):
                raise ClusterError(
                    f"workers died running a task of this run, again and again: "
                    f"{_one_line(error)}; the run's tasks were cancelled"
                ) from error
            raise
        self.received += sum(len(pickle.dumps(v, protocol=5)) for v in values)
        return values

    def _value(self, future: Any) -> Any:
        """The value of ``future``, done. A value lost before it arrives (its worker died) is
        computed again by Dask: it is waited for again (:meth:`wait`), and given twice the time
        to arrive at each try, so that a large one is not cut short for ever."""
        import distributed

        arrival_s = 4 * _WAIT_POLL_S
        while True:
            try:
                return future.result(timeout=arrival_s)
            except distributed.TimeoutError:
                arrival_s *= 2
                self.wait([future])

    def wait(self, futures: list[Any]) -> None:
        """Waits until ``futures`` are done (finished, failed or cancelled). Every few seconds
        it sends this run's tasks that wait for a worker to the running workers
        (:func:`_dispatch_stranded`), and counts how long some found none (over the calls of
        one :meth:`gather`).

        Raises:
            ClusterError: the run's tasks found no worker for :data:`NO_WORKER_TIMEOUT_S`.
        """
        import distributed

        pending = futures
        while pending:
            try:
                distributed.wait(pending, timeout=_WAIT_POLL_S)
                return
            except distributed.TimeoutError:
                pass
            pending = [f for f in pending if not f.done()]
            stuck, running, workers = self.client.run_on_scheduler(_dispatch_stranded, self.token)
            if not stuck:
                self._stuck_since = None
                continue
            now = time.monotonic()
            self._stuck_since = now if self._stuck_since is None else self._stuck_since
            if now - self._stuck_since >= NO_WORKER_TIMEOUT_S:
                raise ClusterError(
                    f"{len(stuck)} task(s) of this run (e.g. {stuck[0]!r}) found no worker "
                    f"to run on for {now - self._stuck_since:.0f} s ({running} of {workers} "
                    "worker(s) running): the cluster lost its workers, or they are paused "
                    "(memory); the run's tasks were cancelled"
                )

    def worker_bytes(self) -> int:
        """Bytes the workers sent each other so far (Dask's own count)."""
        if self.client is None:
            return 0
        # A worker that died meanwhile counts for nothing.
        totals = self.client.run(
            lambda dask_worker: dask_worker.transfer_outgoing_bytes_total, on_error="ignore"
        )
        return int(sum(totals.values()))


def _is_future(value: Any) -> bool:
    return type(value).__name__ == "Future"


class FleetRun:
    """A fleet's loops found from tiles (:func:`find_fleet_loops_dask`): the tables of
    :class:`FleetLoops` that tiles give (``components``, ``session_pairs()``,
    ``overlap_matrix()``, ``between_sessions()``), tau per session with
    ``loop_duration=True``, samples drawn by keys (:meth:`sample`), the sessions left out
    (:attr:`failures`), and the timings and bytes of the run (:attr:`stats`). It holds the
    run's connection (the client, the sessions' sources) for :meth:`sample`: pickle its tables
    as :attr:`loops` (a :class:`TiledFleetLoops`)."""

    def __init__(self, **fields: Any) -> None:
        self._loops: Any = fields["loops"]
        self.names: list[str] = fields["names"]
        #: ``(name, source, one-line error)`` of each session left out.
        self.failures: list[tuple[str, str, str]] = fields["failures"]
        #: Timings (seconds) and counts of the run: tiles, bytes shipped.
        self.stats: dict[str, Any] = fields["stats"]
        self._tau: dict[str, tuple[np.ndarray, np.ndarray]] | None = fields["tau"]
        self._context: dict[str, Any] = fields["context"]

    def __repr__(self) -> str:
        left = f", {len(self.failures)} session(s) left out" if self.failures else ""
        return f"FleetRun({self._loops!r}{left})"

    @property
    def loops(self) -> Any:
        """The :class:`TiledFleetLoops`."""
        return self._loops

    @property
    def components(self) -> Table:
        """The loop components, as :attr:`FleetLoops.components`."""
        return self._loops.components  # type: ignore[no-any-return]

    def session_pairs(self) -> Table:
        """The sparse overlap matrix as a table, as :meth:`FleetLoops.session_pairs`."""
        return self._loops.session_pairs()  # type: ignore[no-any-return]

    def overlap_matrix(self, *, sparse: bool = False) -> Any:
        """The overlap matrix, as :meth:`FleetLoops.overlap_matrix`."""
        return self._loops.overlap_matrix(sparse=sparse)

    def between_sessions(self) -> np.ndarray:
        """The ids of the components between two sessions, as
        :meth:`FleetLoops.between_sessions`."""
        return self._loops.between_sessions()  # type: ignore[no-any-return]

    def loop_duration(self, session: str | int) -> Table:
        """Tau per pose of one session, as :meth:`FleetLoops.loop_duration` gives it:
        ``session``, ``pose``, ``t_s``, ``own_s``, ``other_s`` (to rounding: the same widths
        added in another order).

        Raises:
            InvalidParameterError: without ``loop_duration=True``; an unknown session.
        """
        if self._tau is None:
            raise InvalidParameterError(
                "loop duration was not computed: pass loop_duration=True to find_fleet_loops_dask"
            )
        k = session if isinstance(session, int) else self._index(session)
        name = self.names[k]
        if name not in self._tau:
            # Added up where the tiles' shares are, brought here on first use.
            c = self._context
            runner: _Runner = c["runner"]
            mine = [
                s for s, tile in zip(c["shares"], c["tiles"], strict=True) if k in tile.sessions
            ]
            poses = c["blocks"][k].poses
            task = runner.submit(
                "session-tau", _session_tau, k, c["starts"][k], poses, None, name, None, *mine
            )
            self._tau[name] = runner.gather([task])[0]
        own, other = self._tau[name]
        times = self._context["times"](k)
        out = Table()
        out["session"] = np.full(len(own), k, dtype=np.int64)
        out["pose"] = np.arange(len(own), dtype=np.int64)
        out["t_s"] = np.asarray(times, dtype=np.float64)
        out["own_s"] = own
        out["other_s"] = other
        return out

    def _index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise InvalidParameterError(
                f"no session named {name!r} (sessions: {', '.join(self.names)})"
            ) from None

    def sample(
        self,
        sampler: str = DEFAULT_SAMPLER,
        *,
        rate: float | None = None,
        budget: int | None = None,
        seed: int = 0,
        between_only: bool = False,
        skip_trivial: bool = False,
    ) -> Table:
        """Samples drawn from the tiles by keys, where the tiles were scanned: the samples of
        :func:`sample_fleet` with the same arguments, pair for pair (see
        :class:`KeyedDraw`). Each pass (one, rarely two) asks the tiles' runs kept by their
        scan on its worker, and rescans a tile only where they are gone (:data:`RUNS_KEPT`).

        Args:
            sampler: ``"one"``, ``"rho"``, ``"rho-dispersed"``, ``"alpha"``,
                ``"closest-first"`` or ``"closest-then-spread"`` (the default,
                :data:`~inexact_loops.DEFAULT_SAMPLER`; the baselines run over whole
                trajectories: use :func:`sample_fleet`).
            rate, budget, seed, between_only, skip_trivial: as :func:`sample_fleet`
                (neither rate nor budget: a budget of 1000).

        Returns:
            :class:`Table` as :attr:`FleetSamples.table`.
        """
        if rate is None and budget is None:
            budget = 1000
        started = time.perf_counter()
        draw = self._loops.draw(
            sampler,
            rate=rate,
            budget=budget,
            seed=seed,
            between_only=between_only,
            skip_trivial=skip_trivial,
        )
        c = self._context
        runner: _Runner = c["runner"]
        tiles = self._loops.tiles
        passes = 0
        # The scan task that held each tile (tiles by value: the merge may list them in
        # another order than the plan).
        group_of = {c["tiles"][t]: g for g, members in enumerate(c["groups"]) for t in members}
        # Where each scan task's tiles' runs are kept: its draws go there.
        where = runner.holders(len(c["groups"]))
        while not draw.done:
            passes += 1
            # The requests of the tiles that one scan task held, in one task.
            grouped: dict[int, list[Any]] = {}
            for t, request in draw.requests():
                a, b = tiles[t].sessions
                sources = (c["sources"][a], None if a == b else c["sources"][b])
                grouped.setdefault(group_of[tiles[t]], []).append(
                    (request, sources, (c["starts"][a], c["starts"][b]))
                )
            asked = list(grouped)
            futures: dict[int, Any] = {}
            for g in _interleaved(asked, [where[g] for g in asked]):
                futures[g] = runner.submit(
                    "draw-tiles",
                    _draw_session_tiles,
                    grouped[g],
                    c["options"],
                    c["gamma"],
                    c["metric"],
                    c["separation"],
                    c["threads"],
                    runner.token,
                    worker=where[g],
                )
            offered = runner.gather([futures[g] for g in asked])
            draw.absorb([offer for offers in offered for offer in offers])
        self.stats["sample_s"] = time.perf_counter() - started
        self.stats["sample_passes"] = passes
        return draw.table()  # type: ignore[no-any-return]


@contextlib.contextmanager
def local_client(workers: int = 2, **cluster: Any) -> Iterator[Any]:
    """A ``dask.distributed`` client of a ``LocalCluster`` on this machine: ``workers`` processes
    of one thread each, quiet (errors only, no dashboard); the cluster of the tests and of
    BENCHMARKS.md. Closes both on leaving.

    Args:
        workers: worker processes.
        cluster: more ``LocalCluster`` arguments (``memory_limit="10GB"``, ...).

    Example:
        >>> from inexact_loops.dask import find_fleet_loops_dask, local_client
        >>> with local_client() as client:  # doctest: +SKIP
        ...     run = find_fleet_loops_dask(["a.parquet", "b.parquet"], 20.0, client=client)
    """
    import logging

    import distributed

    options = {
        "n_workers": workers,
        "processes": True,
        "threads_per_worker": 1,
        "dashboard_address": None,
        "silence_logs": logging.ERROR,
        **cluster,
    }
    with distributed.LocalCluster(**options) as local, distributed.Client(local) as client:
        yield client


def find_fleet_loops_dask(
    sessions: Any,
    gamma: float,
    *,
    client: Any = None,
    block: int | None = None,
    separation: Any = "auto",
    metric: Any = None,
    fan_in: int = DEFAULT_FAN_IN,
    threads: int | None = None,
    loop_duration: bool = False,
    on_error: str = "skip",
    format: str | None = None,
    axes: tuple[int, int] | None = None,
    topic: str | None = None,
    time: str | None = None,
    frames: tuple[str, str] | None = None,
    rate_hz: float | None = None,
    drop_duplicate_stamps: bool = False,
    quaternion_tolerance: float | None = None,
) -> FleetRun:
    """Finds every inexact loop of a fleet from tiles, on this machine or on a Dask cluster:
    the components and the overlap matrix of :func:`inexact_loops.find_fleet_loops` on the same
    sessions (the same ids, sessions, poses, times, pair counts, holes and closest pairs; areas
    to rounding, a relative 1e-12); samples with :meth:`FleetRun.sample`.

    Args:
        sessions: a list of paths (each session named by its file stem, as :class:`Fleet`
            names it), a dict ``{name: path}`` (a path may be a list of files, read as one
            trajectory) or a list of ``(name, path)`` pairs. A ``.parquet`` path is a pose
            store (:func:`read_pose_parquet`). Without ``client=`` a session may also be a
            :class:`Trajectory`; with it, workers read every session from its path, which they
            must reach.
        gamma: the distance threshold gamma > 0, in the metric's unit.
        client: a ``dask.distributed.Client``: the tasks run on its cluster. ``None``: in this
            process, without Dask.
        block: poses per block, the side of a tile: the unit of work and of a task's memory.
            The result does not depend on it. ``None``: the longest session, between
            :data:`DEFAULT_BLOCK` and :data:`MAX_AUTO_BLOCK` poses (in
            :attr:`FleetRun.stats` as ``"block"``): a session cut into many blocks scans
            each row once per block it comes back to.
        separation: within each session, as in :func:`find_fleet_loops` (``"auto"``: 4 gamma of
            path; ``None``: the paper's S_gamma).
        metric: a metric name or an ``inexact_loops.metrics`` object (not a callable);
            ``None``: the sessions' own, which must agree.
        fan_in: summaries combined by one merge task (at least 2).
        threads: threads of each tile's scan; ``None``: one per core in this process, one per
            task on a cluster (Dask's worker threads share the cores).
        loop_duration: also tau per pose (:meth:`FleetRun.loop_duration`): each tile's task
            keeps its share where it ran, and a session's tau is added up there when asked.
        on_error: ``"skip"``: a session that cannot be read, or does not fit the first one
            read (dimension, manifold), is left out with its error in :attr:`FleetRun.failures`
            (when every session fails, the first error is raised); ``"raise"``: raise it.
        format, axes, topic, time, frames, rate_hz, drop_duplicate_stamps,
            quaternion_tolerance: how the paths are read, as in :func:`read_trajectory`
            (``format="parquet"`` for a pose store without the suffix).

    Returns:
        :class:`FleetRun`.

    Raises:
        InvalidParameterError: no session, two sessions of one name, a block of 0 poses, a
            fan-in below 2, an unknown ``on_error``, and as :func:`find_fleet_loops`.
        TypeError: a session of another type; a Trajectory with ``client=``.
        OSError, LoopsIOError, InvalidTrajectoryError: with ``on_error="raise"``, or when every
            session fails, as :func:`read_trajectory`.

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
        >>> len(tiled.sample("one", budget=3, seed=0)["i"])
        3
    """
    if fan_in < 2:
        raise InvalidParameterError(f"fan_in = {fan_in} is invalid: a merge takes at least 2 parts")
    if on_error not in ("skip", "raise"):
        raise InvalidParameterError(f"on_error = {on_error!r} is invalid: 'skip' or 'raise'")
    if block is not None and block < 1:
        raise InvalidParameterError(f"block = {block} is invalid: at least 1 pose per block")
    named = _named_sources(sessions)
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
    if client is not None:
        trajectories = [name for name, source in named if isinstance(source, _core.Trajectory)]
        if trajectories:
            raise TypeError(
                f"session {trajectories[0]!r} is a Trajectory: with client=, workers read every "
                "session from a path (the client ships no poses): write it to a file, or run "
                "without client="
            )
    runner = _Runner(client)
    stats: dict[str, Any] = {
        "workers": 0 if client is None else len(client.scheduler_info()["workers"])
    }
    started = time_started = _now()
    worker_bytes_before = runner.worker_bytes()
    if client is None:
        # In this process: read each session once.
        loaded: list[Any] = []
        for _, source in named:
            try:
                loaded.append(
                    _load(source, options)
                    if not isinstance(source, str | tuple)
                    else _read_uncached(source, options)
                )
            except (OSError, ValueError, TypeError) as error:
                loaded.append(_Failed(error))
        sources_all = loaded
    else:
        sources_all = [source for _, source in named]
    # Each session is read first where its row blocks will be scanned (it stays kept there).
    unit = DEFAULT_BLOCK if block is None else block
    readers = [runner.worker_for(k, len(sources_all)) for k in range(len(sources_all))]
    describing: list[Any] = list(sources_all)  # a _Failed stays as it is
    for k in _interleaved(list(range(len(sources_all))), readers):
        if not isinstance(sources_all[k], _Failed):
            describing[k] = runner.submit(
                "describe-session",
                _describe_session,
                sources_all[k],
                options,
                unit,
                metric,
                worker=readers[k],
            )
    described = runner.gather(describing)
    failures: list[tuple[str, str, str]] = []
    kept: list[int] = []
    first: tuple[str, str, int] | None = None
    for k, (name, source) in enumerate(named):
        d = described[k]
        shown = (
            source
            if isinstance(source, str)
            else (",".join(source) if isinstance(source, tuple) else "(in memory)")
        )
        if isinstance(d, _Failed):
            if on_error == "raise":
                raise d.error
            failures.append((name, shown, _one_line(d.error)))
            continue
        blocks, manifold, dim = d
        if first is None:
            first = (name, manifold, dim)
        elif (manifold, dim) != first[1:]:
            error = InvalidParameterError(
                f"session {name!r} has {dim} coordinates on {manifold}, the first session "
                f"({first[0]!r}) {first[2]} on {first[1]}: a fleet's sessions must agree"
            )
            if on_error == "raise":
                raise error
            failures.append((name, shown, _one_line(error)))
            continue
        kept.append(k)
    if not kept:
        raise next(d.error for d in described if isinstance(d, _Failed))
    names = [named[k][0] for k in kept]
    blocks = [described[k][0] for k in kept]
    sources = [sources_all[k] for k in kept]
    if block is None:
        block = _auto_block(max(b.poses for b in blocks))
        if block > unit:
            blocks = [b.coarsened(block // unit) for b in blocks]
    stats["block"] = block
    stats["read_s"] = _now() - started
    started = _now()
    tiles = _core.plan_tiles(blocks, gamma=gamma, metric=metric)
    starts = _starts(blocks)
    metric_name = blocks[0].metric_name
    stats["plan_s"] = _now() - started
    stats["tiles"] = len(tiles)
    stats["sessions"] = len(kept)
    stats["poses"] = sum(b.poses for b in blocks)
    task_threads = threads if client is None else (1 if threads is None else threads)
    started = _now()
    groups = _tile_groups(tiles, block)
    workers = [
        runner.worker_for(kept[tiles[group[0]].sessions[0]], len(sources_all)) for group in groups
    ]
    scans: list[Any] = [None] * len(groups)
    for g in _interleaved(list(range(len(groups))), workers):
        group = groups[g]
        held = []
        for t in group:
            a, b = tiles[t].sessions
            held.append(
                (tiles[t], (sources[a], None if a == b else sources[b]), (starts[a], starts[b]))
            )
        scans[g] = runner.submit(
            "scan-tiles",
            _scan_session_tiles,
            held,
            options,
            gamma,
            metric_name,
            shipped,
            task_threads,
            loop_duration,
            runner.token,
            g,
            worker=workers[g],
        )
    if loop_duration:
        summaries = [runner.submit("tiles-merge", operator.getitem, s, 0) for s in scans]
        shares = [
            runner.submit("tile-duration", _share, scan, k)
            for scan, group in zip(scans, groups, strict=True)
            for k in range(len(group))
        ]
    else:
        summaries, shares = scans, []

    def merge(parts: list[Any]) -> Any:
        return runner.submit("merge-tiles", _merge, *parts)

    final = runner.gather([_reduce(summaries, merge, fan_in)])[0]
    loops = final.finish(blocks, names=names)
    stats["scan_merge_s"] = _now() - started
    times = _session_times_getter(runner, sources, options)
    tau: dict[str, Any] | None = {} if loop_duration else None
    stats["total_s"] = _now() - time_started
    stats["bytes_sent"] = runner.sent
    stats["bytes_received"] = runner.received
    stats["bytes_between_workers"] = runner.worker_bytes() - worker_bytes_before
    context = {
        "runner": runner,
        "sources": sources,
        "options": options,
        "starts": starts,
        "gamma": gamma,
        "metric": metric_name,
        "separation": shipped,
        "threads": task_threads,
        "times": times,
        "tiles": tiles,
        "groups": groups,
        "shares": shares,
        "blocks": blocks,
    }
    return FleetRun(
        loops=loops, names=names, failures=failures, stats=stats, tau=tau, context=context
    )


def _now() -> float:
    return time.perf_counter()


def _session_times_getter(
    runner: _Runner, sources: list[Any], options: tuple[tuple[str, Any], ...]
) -> Callable[[int], Any]:
    def times(k: int) -> Any:
        return runner.gather([runner.submit("session-times", _session_times, sources[k], options)])[
            0
        ]

    return times


def _starts(blocks: Sequence[_core.SessionBlocks]) -> list[int]:
    """The sessions' first fleet indices."""
    starts, total = [], 0
    for b in blocks:
        starts.append(total)
        total += b.poses
    return starts


# ---------------------------------------------------------------------------------------------
# The output folder
# ---------------------------------------------------------------------------------------------

# The marker (``loops-dask.json``), the scratch folder and the files of the folder are
# loops-io's ``out_dir::DASK``, reached through :class:`_core.OutDir`.


def _write_entry(out: _core.OutDir, name: str, write: Callable[[str], None]) -> None:
    """Writes the file ``name`` of ``out`` through ``write(path)`` into the folder's scratch
    folder, then moves it into place (listed in the marker first; see :class:`_core.OutDir`)."""
    staged = out.staging_path()
    try:
        write(str(staged))
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(staged)
        raise
    out.place(staged, name)


def _path_inputs(sessions: Any) -> list[str]:
    """The files and folders among ``sessions`` (a mapping or list of paths, lists of paths or
    trajectories): what the output must not be written onto."""
    values = sessions.values() if isinstance(sessions, Mapping) else sessions
    paths: list[str] = []
    for value in values:
        for item in value if isinstance(value, list | tuple) else [value]:
            if isinstance(item, str | os.PathLike):
                paths.append(os.fspath(item))
    return paths


def _write_table(out: _core.OutDir, name: str, table: Mapping[str, Any]) -> None:
    pa = _pyarrow()
    arrow = pa.table({k: np.asarray(v) for k, v in table.items()})
    _write_entry(out, name, lambda tmp: pa.parquet.write_table(arrow, tmp))


def run_fleet_dask(
    sessions: Any,
    gamma: float,
    *,
    out: str | os.PathLike[str],
    force: bool = False,
    sampler: str | None = DEFAULT_SAMPLER,
    rate: float | None = None,
    budget: int | None = None,
    seed: int = 0,
    between_only: bool = False,
    skip_trivial: bool = False,
    loop_duration: bool = True,
    client: Any = None,
    **options: Any,
) -> dict[str, Any]:
    """:func:`find_fleet_loops_dask`, samples and tau, with the tables written as Parquet into
    the folder ``out``: ``components.parquet``, ``session_pairs.parquet``,
    ``samples.parquet`` (with a sampler), ``failures.parquet`` (the sessions left out: name,
    source, error), ``loop_duration/<session>.parquet`` (pose, t_s, own_s, other_s; written
    by the workers where the tiles' shares are, never sent to the client) and
    ``summary.json``. Each file is written to a temporary file and renamed; ``out`` is kept as
    ``loops fleet`` keeps its ``--out`` (``loops-dask.json`` lists what this tool wrote there,
    ``force`` replaces only that, one run holds the folder at a time). With ``client=``, the
    workers must reach ``out`` (a shared file system) for tau.

    Args:
        sessions, gamma, client: as :func:`find_fleet_loops_dask`; ``options`` its other
            keywords (``block``, ``separation``, ``metric``, read options, ...).
        out: the output folder (made if missing).
        force: replace what an earlier run of this tool wrote into ``out``.
        sampler, rate, budget, seed, between_only, skip_trivial: as :meth:`FleetRun.sample`
            (``sampler=None``: no samples).
        loop_duration: write tau per session.

    Returns:
        The summary (as ``summary.json``): counts, the sessions and those left out, timings,
        bytes.

    Raises:
        InvalidParameterError: ``out`` not empty without ``force``; a file in ``out`` that this
            tool did not write; ``out`` on an input (a session's file, a folder holding one);
            as :func:`find_fleet_loops_dask`.
    """
    _core.refuse_output_on_input("out", Path(out), _path_inputs(sessions))
    folder = _core.OutDir(Path(out), force=force, tool="loops-dask")
    try:
        run = find_fleet_loops_dask(
            sessions, gamma, client=client, loop_duration=loop_duration, **options
        )
        components = run.components
        _write_table(folder, "components.parquet", components)
        _write_table(folder, "session_pairs.parquet", run.session_pairs())
        failures = Table()
        failures["session"] = np.array([f[0] for f in run.failures] or [], dtype=str)
        failures["source"] = np.array([f[1] for f in run.failures] or [], dtype=str)
        failures["error"] = np.array([f[2] for f in run.failures] or [], dtype=str)
        _write_table(folder, "failures.parquet", failures)
        samples = None
        if sampler is not None:
            samples = run.sample(
                sampler,
                rate=rate,
                budget=budget,
                seed=seed,
                between_only=between_only,
                skip_trivial=skip_trivial,
            )
            _write_table(folder, "samples.parquet", samples)
        else:
            folder.remove("samples.parquet")
        if loop_duration:
            started = _now()
            staging = folder.staging_path()
            staging.mkdir()
            c = run._context
            runner: _Runner = c["runner"]
            futures = []
            for k, b in enumerate(c["blocks"]):
                source = c["sources"][k]
                t_s = runner.submit("session-times", _session_times, source, c["options"])
                mine = [
                    s for s, tile in zip(c["shares"], c["tiles"], strict=True) if k in tile.sessions
                ]
                futures.append(
                    runner.submit(
                        "session-tau",
                        _session_tau,
                        k,
                        c["starts"][k],
                        b.poses,
                        str(staging),
                        run.names[k],
                        t_s,
                        *mine,
                    )
                )
            runner.gather(futures)
            folder.place(staging, "loop_duration")
            run.stats["loop_duration_s"] = _now() - started
        else:
            folder.remove("loop_duration")
        between = int(np.sum(components["session_a"] != components["session_b"]))
        summary = {
            "gamma": gamma,
            "sessions": [
                {"name": n, "poses": int(b.poses), "span_s": float(b.span_s)}
                for n, b in zip(run.names, run._context["blocks"], strict=True)
            ],
            "failures": [{"session": n, "source": s, "error": e} for n, s, e in run.failures],
            "components": len(components["id"]),
            "between_sessions": between,
            "session_pairs": len(run.session_pairs()["components"]),
            "samples": None if samples is None else len(samples["i"]),
            "sampler": sampler,
            "stats": run.stats,
        }
        text = json.dumps(summary, indent=2, default=float) + "\n"
        _write_entry(folder, "summary.json", lambda tmp: Path(tmp).write_text(text))
        return summary
    finally:
        folder.close()


# ---------------------------------------------------------------------------------------------
# The command line: loops-dask
# ---------------------------------------------------------------------------------------------


def _parser() -> argparse.ArgumentParser:
    p = _console.ArgumentParser(
        prog="loops-dask",
        description=(
            "Find the loops of several pose logs as one fleet, from tiles, on this machine or "
            "on a Dask cluster (--scheduler): the components, the session-overlap matrix, "
            "samples and loop duration, written as Parquet into --out. The options are those "
            "of `loops fleet`; the Rust command has no Dask option, this one is its switch."
        ),
        epilog=(
            "examples:\n"
            "  loops-dask fleet/*.mcap --gamma 40 --out results\n"
            "  loops-dask fleet/*.mcap --gamma 40 --scheduler tcp://10.0.0.5:8786 \\\n"
            "      --out /shared/results\n"
            "\nIn --out: components.parquet, session_pairs.parquet, samples.parquet,\n"
            "failures.parquet (sessions left out, with their error),\n"
            "loop_duration/<session>.parquet, summary.json.\n"
            "Exit code 0; 1 when a session was left out; 2 on an error."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "logs",
        nargs="*",
        metavar="LOG",
        help="the pose logs, one session each, named by the file's stem",
    )
    p.add_argument(
        "--session",
        action="append",
        default=[],
        metavar="NAME=FILE[,FILE...]",
        help="a session of several files, or a name of your choice",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a Dask scheduler (tcp://host:8786); without it: this machine, no Dask needed",
    )
    p.add_argument(
        "--format",
        help="file format (as `loops fleet`), or parquet for a pose store "
        "(t, x, y[, z][, qx, qy, qz, qw])",
    )
    p.add_argument("--topic", help="topic to read from MCAP files and bags")
    p.add_argument(
        "--time", help="time of each pose from MCAP files and bags: header, log or publish"
    )
    p.add_argument(
        "--frames", metavar="PARENT,CHILD", help="parent and child frame of a transform topic"
    )
    p.add_argument(
        "--rate-hz", type=float, help="for files without times: pose i at i / RATE_HZ seconds"
    )
    p.add_argument(
        "--axes", metavar="A,B", help="a plane of two position axes (0 = x, 1 = y, 2 = z)"
    )
    p.add_argument(
        "--drop-duplicate-stamps",
        action="store_true",
        help="drop poses whose timestamp repeats the one before",
    )
    p.add_argument(
        "--quaternion-tolerance",
        type=float,
        metavar="TOLERANCE",
        help="how far from unit length a quaternion may be",
    )
    p.add_argument(
        "--gamma", type=float, required=True, help="the distance threshold γ, in the metric's unit"
    )
    p.add_argument("--metric", help="the metric (as `loops fleet`); default: the sessions' own")
    p.add_argument(
        "--separation-path",
        type=float,
        metavar="LENGTH",
        help="revisits only: pairs at least this path length apart [default: 4 x gamma]",
    )
    p.add_argument(
        "--separation-time",
        type=float,
        metavar="SECONDS",
        help="revisits only: pairs at least this many seconds apart [default: 0]",
    )
    p.add_argument(
        "--no-separation", action="store_true", help="the paper's S_gamma: no separation"
    )
    p.add_argument(
        "--threads",
        type=int,
        help="threads of each tile's scan (default: one per core here, one per task on a cluster)",
    )
    p.add_argument(
        "--sampler",
        default=DEFAULT_SAMPLER,
        help="one, rho, rho-dispersed, alpha, closest-first or closest-then-spread "
        f"[default: {DEFAULT_SAMPLER}]; none for no samples",
    )
    p.add_argument(
        "--budget", type=int, help="exactly this many samples [default: 1000 without --rate]"
    )
    p.add_argument("--rate", type=float, help="the sampler's rate instead of a budget")
    p.add_argument("--seed", type=int, default=0, help="seed of the random choices [default: 0]")
    p.add_argument(
        "--skip-trivial", action="store_true", help="leave out the trivial loop components"
    )
    p.add_argument(
        "--between-only", action="store_true", help="sample only pairs of two different sessions"
    )
    p.add_argument("--no-loop-duration", action="store_true", help="do not write loop_duration/")
    p.add_argument(
        "--block",
        type=int,
        default=None,
        help=(
            "poses per block, the side of a tile [default: the longest session, "
            f"{DEFAULT_BLOCK:,} to {MAX_AUTO_BLOCK:,}]"
        ),
    )
    p.add_argument(
        "--fan-in",
        type=int,
        default=DEFAULT_FAN_IN,
        help=f"summaries per merge task [default: {DEFAULT_FAN_IN}]",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="the folder for the results")
    p.add_argument(
        "--force",
        action="store_true",
        help="replace the results of an earlier loops-dask in --out (only what it wrote there)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    p.add_argument(
        "--json",
        metavar="FILE",
        help="also write summary.json to FILE; - prints it instead of the table",
    )
    return p


def _pair(text: str | None, what: str, kind: Callable[[str], Any]) -> Any:
    if text is None:
        return None
    parts = text.split(",")
    if len(parts) != 2:
        raise InvalidParameterError(f"--{what} {text!r}: give two values separated by a comma")
    return tuple(kind(p) for p in parts)


def main(argv: Sequence[str] | None = None) -> int:
    """The command ``loops-dask`` (``[project.scripts]``): ``loops fleet``'s options plus
    ``--scheduler ADDRESS``. Returns the exit code: 0, 1 when a session was left out, 2 on an
    error."""
    args = _parser().parse_intermixed_args(argv)
    try:
        sessions: dict[str, Any] = {}
        for log in args.logs:
            name = _core.log_name(log)
            if name in sessions:
                raise InvalidParameterError(
                    f"{sessions[name]} and {log} are both named {name!r} by their file stem: "
                    "use --session NAME=FILE to name them"
                )
            sessions[name] = log
        for spec in args.session:
            name, eq, files = spec.partition("=")
            if not eq or not name or not files:
                raise InvalidParameterError(f"--session {spec!r}: give NAME=FILE[,FILE...]")
            if name in sessions:
                raise InvalidParameterError(f"two sessions are named {name!r}")
            parts = files.split(",")
            sessions[name] = parts[0] if len(parts) == 1 else parts
        if not sessions:
            raise InvalidParameterError("no sessions: give LOG files or --session NAME=FILE")
        if args.no_separation:
            separation: Any = None
        elif args.separation_path is not None or args.separation_time is not None:
            separation = _core.Separation(
                path=args.separation_path or 0.0, time_s=args.separation_time or 0.0
            )
        else:
            separation = "auto"
        sampler = None if args.sampler == "none" else args.sampler
        if args.json and args.json != "-":
            _core.refuse_output_on_input("--json", Path(args.json), _path_inputs(sessions))
            if os.path.lexists(args.json) and not args.force:
                raise InvalidParameterError(
                    f"--json {args.json} exists; pass --force to replace it"
                )
        client = None
        if args.scheduler:
            try:
                from distributed import Client  # type: ignore[import-untyped, import-not-found, unused-ignore]
            except ImportError as error:
                raise InvalidParameterError(
                    "--scheduler needs dask.distributed: "
                    f"pip install '.[dask]' in a checkout ({error})"
                ) from None
            client = Client(args.scheduler)
        try:
            summary = run_fleet_dask(
                sessions,
                args.gamma,
                out=args.out,
                force=args.force,
                sampler=sampler,
                rate=args.rate,
                budget=args.budget,
                seed=args.seed,
                between_only=args.between_only,
                skip_trivial=args.skip_trivial,
                loop_duration=not args.no_loop_duration,
                client=client,
                block=args.block,
                fan_in=args.fan_in,
                separation=separation,
                metric=args.metric,
                threads=args.threads,
                format=args.format,
                axes=_pair(args.axes, "axes", int),
                topic=args.topic,
                time=args.time,
                frames=_pair(args.frames, "frames", str),
                rate_hz=args.rate_hz,
                drop_duplicate_stamps=args.drop_duplicate_stamps,
                quaternion_tolerance=args.quaternion_tolerance,
            )
        finally:
            if client is not None:
                client.close()
    except (OSError, ValueError, TypeError, ImportError, MemoryError) as error:
        print(f"loops-dask: error: {_one_line(error).split(': ', 1)[-1]}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _console.interrupted("loops-dask")
    text = json.dumps(summary, indent=2, default=float)
    if args.json == "-":
        print(text)
    elif args.json:
        _atomic(Path(args.json), lambda tmp: Path(tmp).write_text(text + "\n"))
    for f in summary["failures"]:
        print(
            f"loops-dask: session {f['session']} ({f['source']}) left out: {f['error']}",
            file=sys.stderr,
        )
    if not args.quiet and args.json != "-":
        where = args.scheduler or "this machine"
        stats = summary["stats"]
        print(
            f"loops-dask: {len(summary['sessions'])} session(s), {stats['poses']} poses, "
            f"{stats['tiles']} tiles of {stats['block']} poses on {where}: "
            f"{summary['components']} components "
            f"({summary['between_sessions']} between sessions), "
            f"{summary['samples'] if summary['samples'] is not None else 'no'} samples; "
            f"results in {args.out} ({stats['total_s']:.1f} s)"
        )
    return 1 if summary["failures"] else 0


if __name__ == "__main__":
    # Run by `python -m inexact_loops.dask`: the tasks must be the module's functions (the
    # workers import them by name), not this __main__'s copies.
    from inexact_loops.dask import main as _main

    sys.exit(_main())
