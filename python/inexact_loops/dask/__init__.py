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
reads it and returns its pose count, span and block balls
(:class:`~inexact_loops.tiles.SessionBlocks`, a few bytes per block; the tiles' plumbing is
:mod:`inexact_loops.tiles`); the client plans the tiles from those alone; each tile's task reads its
two sessions (each worker keeps the last few it read) and returns a
:class:`~inexact_loops.tiles.TileSummary` (statistics of its provisional components and the runs on
its edges); merge tasks combine groups of summaries into :class:`~inexact_loops.tiles.TileMerge`
objects, which keep only the edge runs still facing unmerged tiles, level by level, until one
is left; the client finishes it into the components and the overlap matrix. Samples are drawn
by keys (:class:`~inexact_loops.tiles.KeyedDraw`): the client works out each component's quota from
the merged statistics, and each tile offers the few pairs asked of it
(:func:`~inexact_loops.tiles.draw_tile`) from the runs its scan kept on the worker that scanned it
(:data:`RUNS_KEPT`; the draws of a scan task's tiles are sent to that worker), rescanning the
tile only when they are gone (evicted, or the worker restarted). The samples are
:func:`~inexact_loops.sample_fleet`'s, pair for pair, whatever the tiling, the workers and
where the runs were found. Loop duration per pose (``loop_duration=True``) comes from each
tile's share (:func:`~inexact_loops.tiles.scan_tile` with ``duration=True``), added up per session.
Every task's result depends on its inputs alone (kept runs only save work), so a worker that dies
takes nothing with it: Dask reruns its tasks and the answer is the same. A run never waits for
ever: its tasks that wait for a worker are sent to the running ones, and when none can take
them for :data:`NO_WORKER_TIMEOUT_S` the run raises :class:`ClusterError` and cancels them.

A session that cannot be read (a missing or corrupt log, or one whose dimension or metric
differs from the others') is left out with a one-line error in :attr:`FleetRun.failures`; the
rest of the fleet is computed without it (``on_error="raise"`` raises instead).

:func:`run_fleet_dask` writes the tables as Parquet into an output folder (the command
``loops-dask``, :func:`main`, is its command line). :func:`update_store` updates a fleet store
(:class:`inexact_loops.FleetStore`) on a worker, which scans, merges and writes its tables
there: the client holds O(sessions) (``loops-dask --store DIR``).

The package's modules, each importing only those above it: ``_settings`` (the tunables:
:data:`DEFAULT_BLOCK`, :data:`RUNS_KEPT` ..., set here and read when used), ``_parquet``,
``_cache`` (what a worker keeps), ``_tasks``, ``_scheduling`` (:class:`FleetRun`), ``_run``
(:func:`find_fleet_loops_dask`), ``_output`` (:func:`run_fleet_dask`), ``_store``
(:func:`update_store`) and ``_cli``.

Requires ``dask[distributed]`` only with ``client=``, and pyarrow for Parquet
(``pip install '.[dask]'`` in a checkout).
"""

from __future__ import annotations

import copyreg
import importlib
import sys
import types
from typing import Any

from . import _settings
from ._cli import main
from ._output import run_fleet_dask
from ._parquet import read_pose_parquet, write_pose_parquet
from ._run import find_fleet_loops_dask
from ._scheduling import ClusterError, FleetRun, local_client
from ._store import update_store

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
    "update_store",
    "write_pose_parquet",
]

#: The tunables, set into ``_settings``, where the run reads them when used.
_TUNABLES = (
    "DEFAULT_BLOCK",
    "MAX_AUTO_BLOCK",
    "DEFAULT_FAN_IN",
    "POSES_KEPT",
    "RUNS_KEPT",
    "RUNS_KEPT_SHARE",
    "NO_WORKER_TIMEOUT_S",
)

for _obj in (
    ClusterError,
    FleetRun,
    local_client,
    find_fleet_loops_dask,
    run_fleet_dask,
    update_store,
    main,
    read_pose_parquet,
    write_pose_parquet,
):
    _obj.__module__ = __name__  # pickles and Dask name them by this module
del _obj


# Served here too; setting one here sets it there (:class:`_Package`).
DEFAULT_BLOCK = _settings.DEFAULT_BLOCK
MAX_AUTO_BLOCK = _settings.MAX_AUTO_BLOCK
DEFAULT_FAN_IN = _settings.DEFAULT_FAN_IN
POSES_KEPT = _settings.POSES_KEPT
RUNS_KEPT = _settings.RUNS_KEPT
RUNS_KEPT_SHARE = _settings.RUNS_KEPT_SHARE
NO_WORKER_TIMEOUT_S = _settings.NO_WORKER_TIMEOUT_S


class _Package(types.ModuleType):
    """This package as a module whose tunables, when set, are set where the run reads them."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _TUNABLES:
            setattr(_settings, name, value)
        super().__setattr__(name, value)


def _by_name(module: types.ModuleType) -> tuple[Any, tuple[str]]:
    """Pickles the package as a module is pickled (cloudpickle, for the closures Dask ships):
    by its name."""
    return importlib.import_module, (module.__name__,)


copyreg.pickle(_Package, _by_name)
sys.modules[__name__].__class__ = _Package
