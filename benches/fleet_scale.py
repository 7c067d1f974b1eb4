#!/usr/bin/env python3
"""Fleets at scale: time and peak memory of the fleet engine, its two prunings, the
single-trajectory engine on the same poses, and scipy's ``cKDTree.query_pairs``.

Usage::

    python benches/fleet_scale.py [--quick] [--timeout-s S] [--output PATH]

Builds ``benches/examples/fleet_scale.rs`` in release and runs it once per case and engine, each
in its own process (so its peak resident set is its own). Writes the section of
``BENCHMARKS.md`` under the marker line ``<!-- fleets -->`` and keeps everything else.

Fleets (``loops_core::UrbanFleet``, 10 Hz, γ = 40 m, no revisit separation, seed 0):

- dense: 30 vehicles roaming the 1 km² city for 5 to 60 minutes: every pair of vehicles meets;
- sparse: 100 to 1,000 vehicles roaming the 10 × 10 km city for 10 minutes: most pairs never
  meet;
- districts: 100 vehicles × 10 minutes, each working its own 1 km² district of the 10 × 10 km
  city: vehicles meet only at district borders;
- sessions: 10⁴ vehicles × 1 minute in the 10 × 10 km city: the pruning alone.

Engines: the fleet with the KD-tree over chunk balls (the default for Euclidean positions) and
with the time-ordered ball hierarchy; ``find_loops`` on the fleet's joint trajectory (the same
poses as one drive); ``cKDTree.query_pairs`` on the same positions (the pairs only, no
components), where its pair list fits in memory. The exponent is the least-squares slope of
log time against log runs (the answer's size) over the KD-tree rows.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import write_section  # noqa: E402

BINARY = REPO / "target" / "release" / "examples" / "fleet_scale"
MARKER_NAME = "fleets"
GAMMA_M = 40.0
QUERY_PAIRS_MAX_PAIRS = 150_000_000  # 16 bytes a pair: 2.4 GB

LINE = re.compile(
    r"sessions\s+(?P<sessions>\d+) poses\s+(?P<poses>\d+) runs\s+(?P<runs>\d+)"
    r" cells\s+(?P<cells>\d+) components\s+(?P<components>\d+)"
    r" between\s+(?P<between>\S+) meeting\s+(?P<meeting>\S+)"
    r" time\s+(?P<time>[\d.]+) s peak\s+(?P<peak>[\d.]+) MB"
)


def cases(quick: bool) -> list[tuple[str, str, int, float, float]]:
    """(label, case, vehicles, minutes, city side in metres)."""
    dense = [
        ("dense", "roam", 30, m, 1000.0) for m in ([5, 10, 20] if quick else [5, 10, 20, 40, 60])
    ]
    sparse = [
        ("sparse", "roam", v, 10, 10_000.0) for v in ([100, 300] if quick else [100, 300, 1000])
    ]
    districts = [("districts", "districts", 100, 10, 10_000.0)]
    sessions = [] if quick else [("sessions", "roam", 10_000, 1, 10_000.0)]
    return dense + sparse + districts + sessions


def run(
    case: str,
    vehicles: int,
    minutes: float,
    city: float,
    engine: str,
    timeout_s: float,
    poses_path: str | None,
):
    env = dict(os.environ)
    if poses_path:
        env["FLEET_SCALE_POSES"] = poses_path
    cmd = [str(BINARY), case, str(vehicles), str(minutes), str(city), engine, "1"]
    try:
        out = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout_s, env=env, check=True
        ).stdout
    except subprocess.TimeoutExpired:
        return None
    match = LINE.search(out)
    if not match:
        raise SystemExit(f"unexpected output of {' '.join(cmd)}: {out!r}")
    return match.groupdict()


def query_pairs(path: str, expected_pairs: int, timeout_s: float) -> tuple[str, str]:
    """Seconds and peak MB of cKDTree.query_pairs in a fresh process, or why not."""
    if expected_pairs > QUERY_PAIRS_MAX_PAIRS:
        return (
            "—",
            f"skipped: {expected_pairs:,} pairs would need {expected_pairs * 16 / 1e9:.1f} GB",
        )
    code = (
        "import numpy as np, time, resource\n"
        "from scipy.spatial import cKDTree\n"
        f"x = np.fromfile({path!r}, dtype='<f8').reshape(-1, 3)\n"
        "t = time.perf_counter()\n"
        f"pairs = cKDTree(x).query_pairs(r={GAMMA_M}, output_type='ndarray')\n"
        "t = time.perf_counter() - t\n"
        "print(t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, len(pairs))\n"
    )
    try:
        out = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            timeout=timeout_s,
            check=True,
        )
    except subprocess.TimeoutExpired:
        return f"> {timeout_s:.0f}", "timed out"
    seconds, peak, count = out.stdout.split()
    return f"{float(seconds):.2f}", f"{float(peak):.0f} MB, {int(count):,} pairs"


def ratio(other: dict | None, reference_s: float) -> str:
    """An engine's seconds and its ratio to the reference."""
    if other is None:
        return "timed out"
    seconds = float(other["time"])
    return f"{seconds:.2f} ({seconds / reference_s:.1f}×)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="smaller fleets only")
    parser.add_argument("--timeout-s", type=float, default=900.0, help="per engine and case")
    parser.add_argument("--output", type=Path, default=REPO / "BENCHMARKS.md")
    args = parser.parse_args()
    subprocess.run(
        ["cargo", "build", "-q", "--release", "-p", "loops-benches", "--example", "fleet_scale"],
        cwd=REPO,
        check=True,
    )
    rows = []
    fits = []
    started = time.time()
    for label, case, vehicles, minutes, city in cases(args.quick):
        with tempfile.TemporaryDirectory() as tmp:
            poses_path = os.path.join(tmp, "poses.f64")
            kd = run(case, vehicles, minutes, city, "kd-tree", args.timeout_s, poses_path)
            if kd is None:
                rows.append(f"| {label} | {vehicles} × {minutes} min | timed out | | | | | | | | |")
                continue
            hierarchy = run(case, vehicles, minutes, city, "hierarchy", args.timeout_s, None)
            single = (
                run(case, vehicles, minutes, city, "single", args.timeout_s, None)
                if label != "sessions"
                else None
            )
            # Pairs i < j within γ: the runs' cells are the upper half, diagonal included.
            qp_time, qp_note = (
                ("—", "not run at 10⁴ sessions")
                if label == "sessions"
                else query_pairs(poses_path, int(kd["cells"]) - int(kd["poses"]), args.timeout_s)
            )
        t_kd = float(kd["time"])
        fits.append((math.log(int(kd["runs"])), math.log(t_kd)))

        cells = [
            label,
            f"{vehicles} × {minutes:g} min, {city / 1000:g} km city",
            f"{int(kd['poses']):,}",
            f"{int(kd['runs']):,}",
            f"{int(kd['components']):,}",
            f"{int(kd['between']):,}",
            f"{int(kd['meeting']):,}",
            f"{t_kd:.2f}",
            f"{float(kd['peak']):.0f}",
            ratio(hierarchy, t_kd),
            "—" if label == "sessions" else ratio(single, t_kd),
            f"{qp_time} ({qp_note})",
        ]
        rows.append("| " + " | ".join(cells) + " |")
        print(rows[-1], flush=True)
    slope = float("nan")
    if len(fits) >= 2:
        mx = sum(x for x, _ in fits) / len(fits)
        my = sum(y for _, y in fits) / len(fits)
        slope = sum((x - mx) * (y - my) for x, y in fits) / sum((x - mx) ** 2 for x, _ in fits)
    load = open("/proc/loadavg").read().split()[:3]
    commit = subprocess.run(
        ["git", "describe", "--always", "--dirty"], capture_output=True, text=True, cwd=REPO
    ).stdout
    script = f"python benches/fleet_scale.py{' --quick' if args.quick else ''}"
    date = f"{dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M UTC}"
    body = "\n".join(
        [
            "## Fleets",
            "",
            f"Generated by `{script}` (it owns the text from its marker line to the next);"
            " do not edit by hand, rerun the script.",
            "",
            f"- Date: {date}; `nproc`: {os.cpu_count()}; load average at the end: {' '.join(load)};"
            f" git {commit.strip()}; {time.time() - started:.0f} s in all",
            "- One thread per engine, one process per case and engine; γ = 40 m, 10 Hz, seed 0;"
            " times are the engine alone (the fleet's generation excluded); peak is the"
            " process's VmHWM.",
            "",
            "| fleet | sessions | poses | runs | components | between sessions"
            " | session pairs meeting | kd-tree (s) | peak (MB) | hierarchy (s, ×kd)"
            " | single trajectory (s, ×kd) | query_pairs (s) |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
            *rows,
            "",
            f"Fitted exponent of the KD-tree time against the number of runs: **{slope:.2f}**"
            f" (least squares of log time on log runs over the {len(fits)} rows).",
            "",
        ]
    )
    write_section(args.output, MARKER_NAME, body)
    print(f"wrote the {MARKER_NAME} section of {args.output}")


if __name__ == "__main__":
    main()
