"""Reading bags of PoseStamped messages: inexact-loops against ``rosbags`` (pure Python), side by
side in one run, for a rosbag2 sqlite3 bag and a ROS 1 bag; writes the ``bag_compare`` section
of BENCHMARKS.md.

    python benches/bag_compare.py [--messages 1e6] [--repeat 3] [--output BENCHMARKS.md]

The bags are written once by ``rosbags`` (``make_bag_fixtures.py --bench``: one topic, 10 Hz;
the sqlite3 bag uncompressed, the ROS 1 bag with uncompressed chunks) into
``benches/results/bag-fixtures-N`` and kept there for reruns. Ours is
``il.read_trajectory(path)``, which reads, decodes and validates the poses into a trajectory;
the peer reads every message with ``rosbags``' reader and deserialises it
(``deserialize_cdr`` / ``deserialize_ros1``) into Python objects, collecting stamp and position.
Each contender runs in a fresh process (``--timeout-s``, ``--mem-limit-gb``), best of
``--repeat`` runs, timed inside the process (imports excluded).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import harness

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "crates" / "loops-io" / "tests" / "make_bag_fixtures.py"


def worker(path: Path) -> None:
    """Ours, in this process: prints the JSON report as the last line."""
    import inexact_loops as il

    start = time.perf_counter()
    trajectory = il.read_trajectory(path)
    seconds = time.perf_counter() - start
    print(json.dumps({"messages": len(trajectory), "seconds": seconds}))


def best(command: list[str], args, expected: int) -> tuple[str, float | None]:
    """The best time of `args.repeat` runs of `command`, or the status of the first failure."""
    times = []
    for _ in range(args.repeat):
        status, report, stderr = harness.run_process(
            command, timeout_s=args.timeout_s, mem_limit_gb=args.mem_limit_gb
        )
        if status != "ok" or report is None:
            print(stderr, file=sys.stderr)
            return status, None
        if report["messages"] != expected:
            return f"read {report['messages']} messages, expected {expected}", None
        times.append(report["seconds"])
    return "ok", min(times)


def main(argv: list[str]) -> int:
    if argv[:1] == ["--worker"]:
        worker(Path(argv[1]))
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=float, default=1e6)
    harness.add_contender_options(
        parser,
        repeat_help="runs of each contender; the best counts (default 3)",
        output_help="the file whose bag_compare section is written (default BENCHMARKS.md)",
    )
    args = parser.parse_args(argv)
    count = int(args.messages)
    folder = ROOT / "benches" / "results" / f"bag-fixtures-{count}"
    bags = {"rosbag2 sqlite3": folder / "bench-sqlite3", "ROS 1": folder / "bench.bag"}
    if not all(path.exists() for path in bags.values()):
        print(f"writing {count:,} messages with rosbags into {folder} ...", file=sys.stderr)
        subprocess.run(
            [sys.executable, str(FIXTURES), "--bench", str(count), str(folder)], check=True
        )
    rows = [
        "| bag | size (MB) | inexact-loops (s) | poses/s | rosbags (s) | messages/s | ratio |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, path in bags.items():
        size = sum(p.stat().st_size for p in ([path] if path.is_file() else path.iterdir()))
        status_ours, ours = best([sys.executable, __file__, "--worker", str(path)], args, count)
        status_peer, peer = best([sys.executable, str(FIXTURES), "--read", str(path)], args, count)
        cell = lambda t, status: f"{t:.2f}" if t is not None else status  # noqa: E731
        rate = lambda t: f"{count / t:,.0f}" if t else "-"  # noqa: E731
        ratio = f"{peer / ours:.0f}×" if ours and peer else "-"
        rows.append(
            f"| {name} | {size / 1e6:.0f} | {cell(ours, status_ours)} | {rate(ours)} | "
            f"{cell(peer, status_peer)} | {rate(peer)} | {ratio} |"
        )
        print(rows[-1], file=sys.stderr)
    harness.publish_section(
        args.output,
        "bag_compare",
        [
            "## Reading rosbag2 and ROS 1 bags",
            "",
            f"`python benches/bag_compare.py`: {count:,} `geometry_msgs/PoseStamped` messages "
            "written by `rosbags` "
            f"{harness.package_version('rosbags')}, read into poses: ours with "
            "`il.read_trajectory(path)` (read, decode, validate into a trajectory), `rosbags` "
            "reading and deserialising every message into Python objects. Best of "
            f"{args.repeat} runs each, each in a fresh process. Load average "
            f"{harness.load_average()}.",
            "",
            *rows,
            "",
            *harness.machine_facts(("numpy", "rosbags")),
            "",
        ],
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
