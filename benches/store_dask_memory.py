"""The client's memory while a fleet store is updated on Dask, against the number of components.

For each fleet size, a store is made on a ``LocalCluster`` of 2 worker processes from all the
days but the last (one update), then the last day is added (timed and measured): the client's
Python peak over the update (tracemalloc), its resident set before and after, and the bytes of
the summary it receives, against the store's components. Prints a Markdown table
(BENCHMARKS.md, "Fleet store")::

    python benches/store_dask_memory.py [DAYS ...]
"""

from __future__ import annotations

import os
import pickle
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

import inexact_loops as il
from inexact_loops.dask import local_client, update_store

VEHICLES = 4
SETTINGS = {"gamma": 10.0, "block": 50_000, "sampler": "rho", "budget": 500, "seed": 0}


def rss_mb() -> float:
    """The resident set now, MB (Linux)."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def write_logs(folder: Path, days: int) -> dict[int, dict[str, str]]:
    """The fleet's sessions as TUM files, by day."""
    fleet = il.urban_fleet(vehicles=VEHICLES, days=days, duration_s=300.0, seed=1)
    by_day: dict[int, dict[str, str]] = {}
    for name in fleet.names:
        t = fleet.session(name)
        n = len(t)
        rows = np.c_[t.timestamps, t.positions[:, :2], np.zeros((n, 4)), np.ones(n)]
        path = folder / f"{name}.tum"
        np.savetxt(path, rows, fmt="%.17g")
        day = int(name.rsplit("day", 1)[1])
        by_day.setdefault(day, {})[name] = str(path)
    return by_day


def main() -> None:
    sizes = [int(a) for a in sys.argv[1:]] or [4, 8, 16, 31]
    print(
        "| days | sessions | poses | components | client peak, Python (MB) "
        "| client RSS before / after (MB) | summary (bytes) | last day's update (s) |"
    )
    print("|---:|---:|---:|---:|---:|---|---:|---:|")
    with local_client() as client, tempfile.TemporaryDirectory() as tmp:
        for days in sizes:
            folder = Path(tmp) / f"d{days}"
            folder.mkdir()
            by_day = write_logs(folder, days)
            store = folder / "store"
            earlier = {k: v for d in range(days - 1) for k, v in by_day[d].items()}
            update_store(store, add=earlier, client=client, **SETTINGS)
            before = rss_mb()
            tracemalloc.start()
            started = time.perf_counter()
            summary = update_store(store, add=by_day[days - 1], client=client)
            seconds = time.perf_counter() - started
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            after = rss_mb()
            poses = sum(len(il.read_trajectory(p)) for d in by_day.values() for p in d.values())
            print(
                f"| {days} | {len(summary['names'])} | {poses:,} | {summary['components']:,} | "
                f"{peak / 1e6:.2f} | {before:.0f} / {after:.0f} | "
                f"{len(pickle.dumps(summary)):,} | {seconds:.1f} |",
                flush=True,
            )
    maxrss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
    print(f"\nclient max RSS over the whole run: {maxrss:.0f} MB")


if __name__ == "__main__":
    main()
