"""A fleet store kept up to date on a Dask cluster: :func:`update_store`."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from .. import _core
from ..errors import InvalidParameterError
from ._cache import READ_OPTIONS


def update_store(
    path: str | os.PathLike[str],
    *,
    add: Any = None,
    remove: Any = None,
    client: Any = None,
    groups: int | None = None,
    **options: Any,
) -> dict[str, Any]:
    """Adds, replaces and removes sessions of the fleet store in the folder ``path``
    (:meth:`inexact_loops.FleetStore.update`), on a worker of a Dask cluster or in this process.

    The update is the store's own (:meth:`~inexact_loops.FleetStore.update`: it scans only the
    tiles that hold an added or replaced session, merges them into the kept session pairs, draws
    the samples from the kept runs, and writes the new state atomically), in its three steps
    (:class:`~inexact_loops.StoreUpdatePlan`); this function only says where each runs. With
    ``client=``, a task plans the update from the store's small tables, one task per group of
    tiles scans them (spread over the workers, each reading only the logs and pose files its
    tiles hold), and one task applies the scans and writes every table. The scanned tiles go
    from worker to worker: the client sends paths and names and gets back the number of tiles
    to scan and the summary below, O(sessions), never the components, the tiles or the
    poses. A worker that dies during the update leaves the store as it was (the state is
    swapped in one rename), and Dask runs its tasks again on another worker: the store ends in
    the new state.

    Args:
        path: the store's folder (missing or empty: the first update makes the store there).
        add: sessions as :meth:`~inexact_loops.FleetStore.update` takes them. With ``client=``
            they must be paths the workers reach (a dict ``{name: path}``, ``(name, path)``
            pairs or paths named by their stem), as in :func:`find_fleet_loops_dask`.
        remove: names of stored sessions to remove.
        client: a ``dask.distributed.Client``; ``None``: in this process, without Dask.
        groups: with ``client=``, the number of scan tasks (tiles are grouped by session pair,
            each group about as many tiles); ``None``: four per worker.
        options: the settings, sampler, ``threads`` and reading keywords of
            :meth:`~inexact_loops.FleetStore.update` (``threads=None``: one per core of the
            worker).

    Returns:
        ``{"path", "state_path", "names", "components", "added_components", "samples",
        "last_update"}``: the store's folder and current state, its sessions' names, its
        component count, the components of the sessions the update added or replaced, the
        sample count, and what the update did (as
        :attr:`~inexact_loops.FleetStore.last_update` holds it; ``"changed"`` False for an
        update that changes nothing, which writes nothing).

    Raises:
        TypeError: a :class:`~inexact_loops.Trajectory` in ``add`` with ``client=``.
        InvalidParameterError, OSError, LoopsIOError: as
            :meth:`~inexact_loops.FleetStore.update` (a corrupt log, a setting other than the
            store's ...), raised here from the worker; the store is then unchanged.

    Example:
        >>> import numpy as np, tempfile, inexact_loops as il
        >>> from inexact_loops.dask import update_store
        >>> x = np.arange(21) * 0.5
        >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
        >>> folder = tempfile.mkdtemp() + "/store"
        >>> summary = update_store(folder, add={"monday": monday}, gamma=1.0, block=8)
        >>> summary["names"], summary["last_update"]["added"]
        (['monday'], ['monday'])
    """
    if client is not None:
        values = add.values() if isinstance(add, Mapping) else (add or [])
        for value in values:
            item = value[1] if isinstance(value, tuple) and len(value) == 2 else value
            if isinstance(item, _core.Trajectory):
                raise TypeError(
                    "a session of add= is a Trajectory: with client=, workers read every "
                    "session from a path (the client ships no poses): write it to a file, or "
                    "run without client="
                )
    if remove is not None and isinstance(remove, str):
        raise InvalidParameterError(f"remove = {remove!r} is invalid: give a list of session names")
    if groups is not None and (
        isinstance(groups, bool) or not isinstance(groups, int) or groups < 1
    ):
        raise InvalidParameterError(
            f"groups = {groups!r} is invalid: give a positive number of scan tasks"
        )
    folder = os.fspath(path)
    if client is None:
        return store_update_task(folder, add, remove, options)
    if groups is None:
        groups = 4 * max(1, len(client.scheduler_info().get("workers", {})))
    plan_options = _plan_options(options)
    scan_options = {k: v for k, v in options.items() if k in _SCAN_KEYWORDS}
    plan = client.submit(store_plan_task, folder, add, remove, plan_options, pure=False)
    # The client learns only how many scan tasks to submit (each finds its own tiles) and the
    # names the update changes (O(sessions)).
    count, changes = client.submit(plan_summary, plan, pure=False).result()
    count = min(groups, count)
    # Spread the groups over the workers in turn: left to data locality, every scan would go
    # to the worker that holds the plan. A preference, not a rule, so that a worker lost
    # meanwhile leaves its groups to the others.
    workers = sorted(client.scheduler_info().get("workers", {}))

    def placed(g: int) -> dict[str, Any]:
        """Where group ``g`` prefers to run: nowhere in particular while no worker is known."""
        if not workers:
            return {}
        return {"workers": [workers[g % len(workers)]], "allow_other_workers": True}

    scans = [
        client.submit(store_scan_task, plan, g, count, add, scan_options, pure=False, **placed(g))
        for g in range(count)
    ]
    apply = client.submit(
        store_update_task, folder, add, remove, options, scans, changes, pure=False
    )
    return apply.result()


def _plan_options(options: dict[str, Any]) -> dict[str, Any]:
    """The keywords of :meth:`~inexact_loops.FleetStore.update` that a plan takes (all but the
    threads)."""
    return {k: v for k, v in options.items() if k != "threads"}


def plan_summary(plan: Any) -> tuple[int, dict[str, list[str]]]:
    """Task: the number of tiles a plan scans, and the sessions it adds, replaces and removes."""
    update = plan.last_update
    return len(plan), {k: list(update[k]) for k in _CHANGES}


#: What an update changes, by name (the keys of :attr:`StoreUpdatePlan.last_update`).
_CHANGES = ("added", "replaced", "removed")


#: The keywords of :meth:`~inexact_loops.FleetStore.update` that a scan takes (how the new
#: sessions are read, and the threads).
_SCAN_KEYWORDS = frozenset(("metric", "threads", *READ_OPTIONS))


def store_plan_task(folder: str, add: Any, remove: Any, options: dict[str, Any]) -> Any:
    """Task: the update's plan, from the store's small tables (O(sessions + tiles to scan))."""
    from .._core import StoreUpdatePlan

    return StoreUpdatePlan(folder, add=add, remove=remove, **options)


def tile_group(plan: Any, group: int, count: int) -> list[int]:
    """The tiles of group ``group`` of ``count``: the plan's tiles ordered by session pair (so
    that a group reads few sessions), cut into ``count`` runs of about as many tiles."""
    order = sorted(range(len(plan)), key=lambda k: (plan.tile_sessions[k], k))
    return order[group * len(order) // count : (group + 1) * len(order) // count]


def store_scan_task(
    plan: Any, group: int, count: int, add: Any, options: dict[str, Any]
) -> list[bytes]:
    """Task: the scans of the plan's tiles of group ``group`` of ``count`` (reading only the
    sessions they hold)."""
    return plan.scan(tile_group(plan, group, count), add=add, **options)


def store_update_task(
    folder: str,
    add: Any,
    remove: Any,
    options: dict[str, Any],
    scans: list[list[bytes]] | None = None,
    changes: dict[str, list[str]] | None = None,
) -> dict[str, Any]:
    """Task: the update, where it runs (its tiles scanned here, or given as the scan tasks'
    results), and its summary (O(sessions)).

    An update that changes nothing writes nothing, and its summary says so
    (``last_update["changed"]`` False): the store's rule (:meth:`FleetStore.update`).

    ``changes``: the sessions the plan adds, replaces and removes. When they are already in
    the store as the update leaves them, this task is a run again of one whose result was lost
    with its worker after it wrote the new state (the scheduler recomputes a lost result): it
    writes nothing, and the summary is that of the update it repeats, not of an empty update
    that would mark no component as added."""
    from .._core import FleetStore, StoreUpdatePlan

    store = FleetStore.open(folder)
    if changes is not None and any(changes.values()) and _maybe_done(store, changes):
        # The removals are done (by the names); the rest changes nothing when the sessions
        # given are the stored ones (the store's own rule, which also writes nothing for it).
        now = StoreUpdatePlan(folder, add=add, **_plan_options(options)).last_update
        if not now["changed"]:
            return _summary(store, dict(store.last_update))
    scanned = None if scans is None else [tile for group in scans for tile in group]
    update = store.update(add=add, remove=remove, scanned=scanned, **options)
    return _summary(store, dict(update))


def _maybe_done(store: Any, changes: dict[str, list[str]]) -> bool:
    """Whether the store holds every session the update adds or replaces and none it removes
    (from the names alone; the plan then compares their content)."""
    names = set(store.names)
    kept = [*changes["added"], *changes["replaced"]]
    return all(n in names for n in kept) and not any(n in names for n in changes["removed"])


def _summary(store: Any, update: dict[str, Any]) -> dict[str, Any]:
    """The summary of ``update`` on ``store`` as it now is (O(sessions))."""
    return {
        "path": os.fspath(store.path),
        "state_path": os.fspath(store.state_path),
        "names": list(store.names),
        "components": len(store.components["id"]),
        "added_components": len(store.added),
        "samples": len(store.samples["i"]) if store.sampler is not None else None,
        "last_update": update,
    }
