"""Reading an MCAP log of PoseStamped messages: inexact-loops against the Python ``mcap`` reader
with ``mcap-ros2-support``, side by side in one run; writes the ``mcap_compare`` section of
BENCHMARKS.md.

    python benches/mcap_compare.py [--messages 1e6] [--repeat 3] [--output BENCHMARKS.md]

The file is written once by the official ROS 2 writer (``make_mcap_fixtures.py --bench``: zstd,
1 MiB chunks, 100 Hz) into a temporary folder. Ours is ``il.read_trajectory(path)``, which reads,
decodes and validates the poses into a trajectory; the peer decodes every message into Python
objects and collects stamps, positions and quaternions.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from pathlib import Path

import harness

import inexact_loops as il

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "crates" / "loops-io" / "tests" / "make_mcap_fixtures.py"


def load_fixtures():
    spec = importlib.util.spec_from_file_location("make_mcap_fixtures", FIXTURES)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def best_of(repeat: int, run) -> tuple[float, object]:
    best, result = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=float, default=1e6)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--output", type=Path, default=ROOT / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    fixtures = load_fixtures()
    count = int(args.messages)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "poses.mcap"
        fixtures.write_bench(path, count)
        size_mb = path.stat().st_size / 1e6
        ours, traj = best_of(args.repeat, lambda: il.read_trajectory(path))
        if len(traj) != count:
            print(f"read {len(traj)} poses, expected {count}", file=sys.stderr)
            return 1
        start = time.perf_counter()
        fixtures.read_python(path)
        peer = time.perf_counter() - start
    rows = [
        "| reader | time (s) | poses/s | vs ours |",
        "|---|---:|---:|---:|",
        f"| inexact-loops `il.read_trajectory` (best of {args.repeat}) | {ours:.2f} | "
        f"{count / ours:,.0f} | 1.0× |",
        f"| `mcap` + `mcap-ros2-support` (one run) | {peer:.1f} | {count / peer:,.0f} | "
        f"{peer / ours:.0f}× |",
    ]
    harness.publish_section(
        args.output,
        "mcap_compare",
        [
            "## Reading MCAP logs",
            "",
            f"`python benches/mcap_compare.py`: {count:,} `geometry_msgs/msg/PoseStamped` messages "
            f"({size_mb:.1f} MB, zstd chunks, written by the official ROS 2 writer), read into "
            f"poses. Load average {harness.load_average()}.",
            "",
            *rows,
            "",
        ],
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
