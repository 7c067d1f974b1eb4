"""What a worker process keeps between tasks: the sessions it read and the runs of the
tiles it scanned, each within its budget (:data:`POSES_KEPT`, :data:`RUNS_KEPT`)."""

from __future__ import annotations

import collections
import os
import sys
import threading
from typing import Any

from .. import _core
from ..tiles import TileRuns
from . import _settings
from ._parquet import read_pose_parquet

#: The tiles' runs a worker keeps, most recently used last: (run id, tile) -> (the scan task's
#: group, TileRuns).
_runs: collections.OrderedDict[Any, tuple[int, TileRuns]] = collections.OrderedDict()
_runs_held = 0
#: This process's draws of a tile from kept runs ("hits") and from rescans ("misses").
_runs_counts = {"hits": 0, "misses": 0}
_runs_lock = threading.Lock()

#: The sessions a worker keeps, most recently used last: (source, options) -> Trajectory.
_kept: collections.OrderedDict[Any, _core.Trajectory] = collections.OrderedDict()
_kept_lock = threading.Lock()

READ_OPTIONS = (
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
def as_hashable(value: Any) -> Any:
    """A read option as a hashable value (lists become tuples), for the worker's cache key."""
    if isinstance(value, list | tuple):
        return tuple(as_hashable(v) for v in value)
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
    traj = read_uncached(source, options)
    with _kept_lock:
        _kept[key] = traj
        total = sum(len(t) for t in _kept.values())
        while total > _settings.POSES_KEPT and len(_kept) > 1:
            _, dropped = _kept.popitem(last=False)
            total -= len(dropped)
    return traj


def keep_runs(key: Any, group: int, runs: TileRuns) -> None:
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
    if _settings.RUNS_KEPT is not None:
        return _settings.RUNS_KEPT
    memory = None
    if "distributed" in sys.modules:
        try:
            memory = sys.modules["distributed"].get_worker().memory_manager.memory_limit
        except (ValueError, AttributeError):
            memory = None  # not in a worker, or a worker without a limit
    if not memory:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    return int(_settings.RUNS_KEPT_SHARE * memory)


def kept_runs(key: Any) -> TileRuns | None:
    """A tile's kept runs, or ``None``; counted as a hit or a miss."""
    with _runs_lock:
        kept = _runs.get(key)
        if kept is not None:
            _runs.move_to_end(key)
        _runs_counts["hits" if kept is not None else "misses"] += 1
        return None if kept is None else kept[1]


def kept_groups(run_id: str) -> dict[int, int]:
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


def read_uncached(source: Any, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session read in this process (not kept)."""
    read = dict(options)
    if _is_parquet(source, read):
        return read_pose_parquet(source, axes=read.get("axes"))
    if isinstance(source, tuple):
        source = list(source)
    return _core.read_trajectory(source, **read)


def load_session(source: Any, options: tuple[tuple[str, Any], ...]) -> _core.Trajectory:
    """A session: itself when in memory, else read (or found kept)."""
    if isinstance(source, _core.Trajectory):
        return source
    return _read_session(source, options)
