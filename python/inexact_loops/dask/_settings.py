"""The run's tunables, read when used: set them on :mod:`inexact_loops.dask` (which
forwards them here), e.g. ``inexact_loops.dask.RUNS_KEPT = 0``."""

from __future__ import annotations

from .. import _core

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
