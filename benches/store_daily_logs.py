"""The daily job from pose logs, as a mapping team runs it with the command line: day 31's logs
added to a fleet store of days 1 to 30, against computing the whole fleet again from all 124
logs (into a new store, and as ``loops fleet --out`` with its report).

The fleet of ``store_days`` (4 vehicles x 31 days of 5-minute drives in a 1 km city, 5 Hz,
gamma = 10 m, blocks of 50,000 poses, sigma_rho with a budget of 500), written as MCAP logs by
``loops synth``. Each round times, in a fresh copy of the store of days 1 to 30,
``loops fleet --store COPY day-31-logs`` with the same settings (reading the 4 logs, opening
the folder, scanning the new tiles, writing the new state), then ``loops fleet --store NEW
all-logs`` and ``loops fleet --out DIR all-logs``. Prints one line a round (BENCHMARKS.md,
"Fleet store")::

    python benches/store_daily_logs.py [ROUNDS] [LOOPS] [MINUTES]

``LOOPS`` is the command line to time (default: ``loops`` on the PATH); ``MINUTES`` the length
of each drive (default 5): with short drives the fixed costs of each stored session and file
weigh most, longer drives show how the daily run grows with its new tiles.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SETTINGS = ["--gamma", "10", "--sampler", "rho", "--budget", "500", "--seed", "7"]


def run(loops: str, *args: str) -> float:
    """Seconds of one run of the command line (its output kept quiet)."""
    started = time.perf_counter()
    subprocess.run([loops, *args], check=True, capture_output=True)
    return time.perf_counter() - started


def main(rounds: int, loops: str, minutes: float = 5.0) -> None:
    root = Path(tempfile.mkdtemp())
    logs = root / "logs"
    run(loops, "synth", str(logs), "--vehicles", "4", "--days", "31",
        "--duration-s", str(60 * minutes), "--rate-hz", "5", "--city-size-m", "1000",
        "--seed", "1")  # fmt: skip
    every = sorted(str(p) for p in logs.glob("*.mcap"))
    last = [p for p in every if Path(p).stem.endswith("day30")]
    first = [p for p in every if p not in last]
    store = root / "store"
    setup = run(loops, "fleet", "--store", str(store), *first, *SETTINGS, "--block", "50000")
    print(f"{len(every)} logs; days 1-30 stored in one run: {setup:.2f} s")
    for k in range(rounds):
        copy = root / f"store-{k}"
        shutil.copytree(store, copy)
        day = run(loops, "fleet", "--store", str(copy), *last, *SETTINGS, "--block", "50000")
        fresh = root / f"fresh-{k}"
        again = run(loops, "fleet", "--store", str(fresh), *every, *SETTINGS, "--block", "50000")
        out = root / f"out-{k}"
        full = run(loops, "fleet", "--out", str(out), *every, *SETTINGS)
        print(
            f"day 31 into the store {day:.3f} s; all 31 days into a new store {again:.2f} s "
            f"(ratio {day / again:.3f}); loops fleet --out {full:.2f} s (ratio {day / full:.3f})"
        )
        for folder in (copy, fresh, out):
            shutil.rmtree(folder)
    shutil.rmtree(root)


if __name__ == "__main__":
    main(
        int(sys.argv[1]) if len(sys.argv) > 1 else 3,
        sys.argv[2] if len(sys.argv) > 2 else "loops",
        float(sys.argv[3]) if len(sys.argv) > 3 else 5.0,
    )
