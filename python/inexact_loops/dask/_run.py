"""The fleet's loops from tiles: :func:`find_fleet_loops_dask`."""

from __future__ import annotations

import operator
import time
from collections.abc import Callable, Sequence
from typing import Any

from .. import _core
from ..errors import InvalidParameterError
from ..tiles import SessionBlocks, plan_tiles
from . import _settings
from ._cache import READ_OPTIONS, as_hashable, load_session, read_uncached
from ._scheduling import FleetRun, Runner, one_line
from ._tasks import (
    Failed,
    auto_block,
    describe_session,
    interleaved,
    merge_parts,
    named_sources,
    reduce_tree,
    scan_session_tiles,
    session_times,
    shipped_separation,
    tile_groups,
    tile_share,
)


def find_fleet_loops_dask(
    sessions: Any,
    gamma: float,
    *,
    client: Any = None,
    block: int | None = None,
    separation: Any = "auto",
    metric: Any = None,
    fan_in: int = _settings.DEFAULT_FAN_IN,
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
    named = named_sources(sessions)
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
        (key, as_hashable(read[key]))
        for key in READ_OPTIONS
        if read[key] is not None and read[key] is not False
    )
    shipped = shipped_separation(separation)
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
    runner = Runner(client)
    stats: dict[str, Any] = {
        "workers": 0 if client is None else len(client.scheduler_info()["workers"])
    }
    started = time_started = clock_s()
    worker_bytes_before = runner.worker_bytes()
    if client is None:
        # In this process: read each session once.
        loaded: list[Any] = []
        for _, source in named:
            try:
                loaded.append(
                    load_session(source, options)
                    if not isinstance(source, str | tuple)
                    else read_uncached(source, options)
                )
            except (OSError, ValueError, TypeError) as error:
                loaded.append(Failed(error))
        sources_all = loaded
    else:
        sources_all = [source for _, source in named]
    # Each session is read first where its row blocks will be scanned (it stays kept there).
    unit = _settings.DEFAULT_BLOCK if block is None else block
    readers = [runner.worker_for(k, len(sources_all)) for k in range(len(sources_all))]
    describing: list[Any] = list(sources_all)  # a Failed stays as it is
    for k in interleaved(list(range(len(sources_all))), readers):
        if not isinstance(sources_all[k], Failed):
            describing[k] = runner.submit(
                "describe-session",
                describe_session,
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
        if isinstance(d, Failed):
            if on_error == "raise":
                raise d.error
            failures.append((name, shown, one_line(d.error)))
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
            failures.append((name, shown, one_line(error)))
            continue
        kept.append(k)
    if not kept:
        raise next(d.error for d in described if isinstance(d, Failed))
    names = [named[k][0] for k in kept]
    blocks = [described[k][0] for k in kept]
    sources = [sources_all[k] for k in kept]
    if block is None:
        block = auto_block(max(b.poses for b in blocks))
        if block > unit:
            blocks = [b.coarsened(block // unit) for b in blocks]
    stats["block"] = block
    stats["read_s"] = clock_s() - started
    started = clock_s()
    tiles = plan_tiles(blocks, gamma=gamma, metric=metric)
    starts = _starts(blocks)
    metric_name = blocks[0].metric_name
    stats["plan_s"] = clock_s() - started
    stats["tiles"] = len(tiles)
    stats["sessions"] = len(kept)
    stats["poses"] = sum(b.poses for b in blocks)
    task_threads = threads if client is None else (1 if threads is None else threads)
    started = clock_s()
    groups = tile_groups(tiles, block)
    workers = [
        runner.worker_for(kept[tiles[group[0]].sessions[0]], len(sources_all)) for group in groups
    ]
    scans: list[Any] = [None] * len(groups)
    for g in interleaved(list(range(len(groups))), workers):
        group = groups[g]
        held = []
        for t in group:
            a, b = tiles[t].sessions
            held.append(
                (tiles[t], (sources[a], None if a == b else sources[b]), (starts[a], starts[b]))
            )
        scans[g] = runner.submit(
            "scan-tiles",
            scan_session_tiles,
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
            runner.submit("tile-duration", tile_share, scan, k)
            for scan, group in zip(scans, groups, strict=True)
            for k in range(len(group))
        ]
    else:
        summaries, shares = scans, []

    def merge(parts: list[Any]) -> Any:
        return runner.submit("merge-tiles", merge_parts, *parts)

    final = runner.gather([reduce_tree(summaries, merge, fan_in)])[0]
    loops = final.finish(blocks, names=names)
    stats["scan_merge_s"] = clock_s() - started
    times = _session_times_getter(runner, sources, options)
    tau: dict[str, Any] | None = {} if loop_duration else None
    stats["total_s"] = clock_s() - time_started
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


def clock_s() -> float:
    return time.perf_counter()


def _session_times_getter(
    runner: Runner, sources: list[Any], options: tuple[tuple[str, Any], ...]
) -> Callable[[int], Any]:
    def times(k: int) -> Any:
        return runner.gather([runner.submit("session-times", session_times, sources[k], options)])[
            0
        ]

    return times


def _starts(blocks: Sequence[SessionBlocks]) -> list[int]:
    """The sessions' first fleet indices."""
    starts, total = [], 0
    for b in blocks:
        starts.append(total)
        total += b.poses
    return starts
