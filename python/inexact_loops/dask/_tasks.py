"""The tasks a worker runs: read a session's blocks, scan a tile, draw a tile's samples,
merge summaries; each result depends on its inputs alone."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidParameterError
from ..tiles import Tile, draw_tile, merge_tiles, scan_tiles, session_blocks, session_loop_duration
from . import _settings
from ._cache import keep_runs, kept_runs, load_session
from ._parquet import atomic, import_pyarrow


class Failed:
    """A session that could not be read or does not fit the fleet: its error, as data."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


def describe_session(
    source: Any, options: tuple[tuple[str, Any], ...], block: int, metric: Any
) -> Any:
    """Task: read one session, return what planning needs of it (or its error, as data)."""
    try:
        traj = load_session(source, options)
        return session_blocks(traj, block=block, metric=metric), traj.manifold, traj.dim
    except (OSError, ValueError, TypeError) as error:
        return Failed(error)


def _separation(value: Any) -> Any:
    """A separation as shipped (``"auto"``, ``None``, a path length or ``(path, time_s)``), for
    :func:`inexact_loops.tiles.scan_tile`."""
    if isinstance(value, tuple):
        return _core.Separation(path=value[0], time_s=value[1])
    return value


def _sessions_of(
    sources: tuple[Any, Any], options: tuple[tuple[str, Any], ...]
) -> tuple[_core.Trajectory, _core.Trajectory | None]:
    a = load_session(sources[0], options)
    return a, None if sources[1] is None else load_session(sources[1], options)


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


def scan_session_tiles(
    tiles: list[tuple[Tile, tuple[Any, Any], tuple[int, int]]],
    options: tuple[tuple[str, Any], ...],
    gamma: float,
    metric: str,
    separation: Any,
    threads: int | None,
    duration: bool,
    run_id: str,
    group: int,
) -> Any:
    """Task: scan a few tiles (each with its sessions' sources and first fleet indices) together
    without the GIL (:func:`inexact_loops.tiles.scan_tiles`: a session's balls made once for
    the group) and merge them: their :class:`TileMerge`; with ``duration``, also each tile's share
    of tau, in order. Keeps each tile's runs under ``(run_id, tile)`` for its draws, as scanned
    by the task of ``group``."""
    jobs = [(tile, *_sessions_of(sources, options), starts) for tile, sources, starts in tiles]
    scans = scan_tiles(
        jobs,
        gamma=gamma,
        metric=metric,
        separation=_separation(separation),
        threads=threads,
        duration=True,
        runs=True,
    )
    summaries, shares = [], []
    for (tile, _, _), (summary, share, runs) in zip(tiles, scans, strict=True):
        keep_runs((run_id, tile), group, runs)
        summaries.append(summary)
        shares.append(share)
    if not duration:
        return merge_tiles(summaries)
    return merge_tiles(summaries), shares


def draw_session_tiles(
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
        draw_tile(
            request,
            **_tile_kwargs(sources, options, starts, gamma, metric, separation, threads),
            runs=kept_runs((run_id, request.tile)),
        )
        for request, sources, starts in requests
    ]


def auto_block(longest: int) -> int:
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

    >>> auto_block(100_000), auto_block(120_000), auto_block(10**8), auto_block(10)
    (100000, 150000, 1000000, 50000)
    """
    units = max(
        1,
        min(
            -(-longest // _settings.DEFAULT_BLOCK),
            _settings.MAX_AUTO_BLOCK // _settings.DEFAULT_BLOCK,
        ),
    )
    return units * _settings.DEFAULT_BLOCK


def interleaved(items: list[Any], workers: list[Any]) -> list[Any]:
    """``items`` (each meant for the worker at the same place of ``workers``) in the order to
    submit them: each worker's first, then each one's second, and so on, so that every worker
    starts at once. Submitted in list order, the first worker's tasks would come first, the
    others would steal them (Dask's work stealing moves tasks with loose restrictions) and read
    their sessions, or rescan their runs, a second time.

    >>> interleaved(["a1", "a2", "a3", "b1"], ["A", "A", "A", "B"])
    ['a1', 'b1', 'a2', 'a3']
    """
    queues: dict[Any, list[Any]] = {}
    for item, worker in zip(items, workers, strict=True):
        queues.setdefault(worker, []).append(item)
    out = []
    for round_ in range(max((len(q) for q in queues.values()), default=0)):
        out += [q[round_] for q in queues.values() if round_ < len(q)]
    return out


def tile_groups(tiles: Sequence[Tile], block: int) -> list[list[int]]:
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


def tile_share(scan: Any, k: int) -> Any:
    """Task: the share of tau of the ``k``-th tile of a scan task."""
    return scan[1][k]


def merge_parts(*parts: Any) -> Any:
    """Task: one merge of the tree."""
    return merge_tiles(list(parts))


def session_tau(
    session: int, start: int, poses: int, folder: str | None, name: str, t_s: Any, *parts: Any
) -> Any:
    """Task: a session's tau from its tiles' shares; written as Parquet into ``folder`` (on
    the worker: the poses' tau never travels) or returned."""
    own, other = session_loop_duration(session, start=start, poses=poses, parts=list(parts))
    if folder is None:
        return own, other
    pa = import_pyarrow()
    table = pa.table(
        {
            "pose": np.arange(poses, dtype=np.int64),
            "t_s": np.asarray(t_s, dtype=np.float64),
            "own_s": own,
            "other_s": other,
        }
    )
    atomic(Path(folder) / f"{name}.parquet", lambda tmp: pa.parquet.write_table(table, tmp))
    return poses


def session_times(source: Any, options: tuple[tuple[str, Any], ...]) -> Any:
    """Task: a session's timestamps (for its tau table, on the worker that writes it)."""
    return np.asarray(load_session(source, options).timestamps)


def named_sources(sessions: Any) -> list[tuple[str, Any]]:
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


def shipped_separation(separation: Any) -> Any:
    """A separation in a form every worker can unpickle."""
    if isinstance(separation, _core.Separation):
        return (separation.path, separation.time_s)
    return separation


def reduce_tree(parts: list[Any], merge: Callable[[list[Any]], Any], fan_in: int) -> Any:
    """Merges ``parts`` in groups of ``fan_in`` consecutive ones, level by level, to one."""
    if len(parts) == 1:
        return merge(parts)
    while len(parts) > 1:
        parts = [merge(parts[k : k + fan_in]) for k in range(0, len(parts), fan_in)]
    return parts[0]
