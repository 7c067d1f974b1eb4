"""Sending tasks to the cluster (or running them here): the runner, stranded tasks, the
no-worker deadline, and :class:`FleetRun`."""

from __future__ import annotations

import contextlib
import pickle
import time
import uuid
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from .._core import DEFAULT_SAMPLER
from ..errors import InvalidParameterError, LoopsError
from ..table import Table
from . import _settings
from ._cache import kept_groups
from ._tasks import draw_session_tiles, interleaved, session_tau

#: How often, in seconds, a run waiting for its tasks asks the scheduler whether they can run.
_WAIT_POLL_S = 2.0


def one_line(error: BaseException) -> str:
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


class Runner:
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
        for address, kept in self.client.run(kept_groups, self.token, on_error="ignore").items():
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
                    f"{one_line(error)}; the run's tasks were cancelled"
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
            if now - self._stuck_since >= _settings.NO_WORKER_TIMEOUT_S:
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
            runner: Runner = c["runner"]
            mine = [
                s for s, tile in zip(c["shares"], c["tiles"], strict=True) if k in tile.sessions
            ]
            poses = c["blocks"][k].poses
            task = runner.submit(
                "session-tau", session_tau, k, c["starts"][k], poses, None, name, None, *mine
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
            sampler: a name of :data:`~inexact_loops.SAMPLER_NAMES` (the default,
                :data:`~inexact_loops.DEFAULT_SAMPLER`; the baselines run over whole
                trajectories: use :func:`sample_fleet`).
            rate, budget, seed, between_only, skip_trivial: as :func:`sample_fleet`
                (neither rate nor budget: :data:`~inexact_loops.DEFAULT_BUDGET`).

        Returns:
            :class:`Table` as :attr:`FleetSamples.table`.
        """
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
        runner: Runner = c["runner"]
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
            for g in interleaved(asked, [where[g] for g in asked]):
                futures[g] = runner.submit(
                    "draw-tiles",
                    draw_session_tiles,
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
