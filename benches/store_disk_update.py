"""A fleet store in a folder, as ``loops fleet --store`` keeps it: the last day added to the
other 30, against the whole fleet computed in memory.

The fleet of ``store_days`` (4 vehicles x 31 days of 5-minute drives in a 1 km city, 5 Hz,
gamma = 10 m, blocks of 50,000 poses, sigma_rho with a budget of 500): days 1 to 30 are stored
in one update, then, in a fresh copy of that folder each round, day 31 is added
(``FleetStore.open`` and ``update``: the state read, pose files read back, tiles scanned, the
new state's tables and tile part written, the stored parts linked) and timed against
``find_fleet_loops`` + ``sample_fleet`` of all 31 days in memory. Prints one line a round and
the sizes of the state's tables (BENCHMARKS.md, "Fleet store")::

    python benches/store_disk_update.py [ROUNDS]
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import inexact_loops as il

SETTINGS = {"gamma": 10.0, "separation": None, "sampler": "rho", "budget": 500, "seed": 7}


def main(rounds: int) -> None:
    # A budget below the number of components, as in store_days: most get no sample, on purpose.
    warnings.simplefilter("ignore", il.SampleBudgetWarning)
    fleet = il.urban_fleet(
        vehicles=4, days=31, duration_s=300.0, rate_hz=5.0, city_size_m=1000.0, seed=1
    )
    sessions = {name: fleet.session(k) for k, name in enumerate(fleet.names)}
    last = [name for name in sessions if name.endswith("day30")]
    folder = Path(tempfile.mkdtemp()) / "city"
    started = time.perf_counter()
    il.FleetStore.open(folder).update(
        add=[(n, t) for n, t in sessions.items() if n not in last], **SETTINGS
    )
    print(f"days 1-30 in one update: {time.perf_counter() - started:.3f} s")
    for k in range(rounds):
        copy = folder.with_name(f"city-{k}")
        shutil.copytree(folder, copy)
        started = time.perf_counter()
        store = il.FleetStore.open(copy)
        opened = time.perf_counter() - started
        update = store.update(add=[(n, sessions[n]) for n in last])
        day = time.perf_counter() - started
        started = time.perf_counter()
        loops = il.find_fleet_loops(il.Fleet(sessions), gamma=10.0, separation=None)
        il.sample_fleet(loops, "rho", budget=500, seed=7)
        in_memory = time.perf_counter() - started
        print(
            f"day 31 in the folder {day:.3f} s (opening it {opened:.3f} s; "
            f"{update['tiles_scanned']} tiles scanned, "
            f"{update['tiles_kept']} kept); in memory {in_memory:.3f} s; "
            f"ratio {day / in_memory:.3f}"
        )
    state = max(copy.glob("state-*"))
    tables = [*state.glob("*.parquet"), *state.glob("tiles/*.parquet")]
    for table in sorted(tables, key=lambda p: p.stat().st_size):
        print(f"{table.relative_to(state)}: {table.stat().st_size / 1e6:.1f} MB")
    shutil.rmtree(folder.parent)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
