#!/usr/bin/env python3
"""ε-clustering of detections, side by side with the ``dbscan`` package and scikit-learn.

Usage::

    python benches/cluster_compare.py [--repeat N] [--sklearn-full] [--no-write] [--output PATH]

Input: detections drawn uniformly from S_γ of the reference urban drive (DESIGN.md §8:
``il.urban_drive()``, 75,600 poses, γ = 40 m) with ``il.draw_detections(loops, budget=n,
seed=0)``, for n = 1e5 and 1e6; ε = 30 s. Every contender gets the points (t, t′) and returns a
label per point; DBSCAN with ``min_samples=1`` is exactly the connected components of the ε
graph, so all must give the same partition, which the harness checks (a bijection between
label sets) before it writes anything.

Contenders:

1. inexact-loops: ``il.cluster_detections(il.Detections(t, t_prime), epsilon_s=30.0)`` and its
   ``labels`` (all cores, and one thread);
2. the ``dbscan`` package from PyPI (parallel C++, all cores): ``dbscan.DBSCAN(X, eps=30.0,
   min_samples=1)`` on the (n, 2) array X;
3. scikit-learn: ``DBSCAN(eps=30.0, min_samples=1, algorithm="kd_tree", n_jobs=-1)
   .fit_predict(X)``, at n = 1e5 only unless ``--sklearn-full``: it stores every point's
   ε-neighbourhood, about 1e9 indices at n = 1e6 (the harness estimates the count with scipy).

Each measurement runs in a fresh subprocess (this script with a hidden ``--worker`` flag) under
a timeout: the input is built, one untimed call on 1,000 of the points warms up the contender,
then the best of ``--repeat`` timed calls counts. Contenders go in rounds so that all see the
same machine load (``benches/harness.py`` runs and measures them). The report goes to stdout,
and the section ``<!-- cluster_compare -->`` of BENCHMARKS.md is replaced (up to the next
marker line or the end of the file); the rest of the file is left as it is.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from harness import (
    REPO,
    cap_address_space,
    load_average,
    machine_facts,
    measure,
    run_process,
    write_section,
)

GAMMA_M = 40.0
EPSILON_S = 30.0
SEED = 0
SIZES = (100_000, 1_000_000)
SECTION = "cluster_compare"

CONTENDERS = {
    "ours": "inexact-loops",
    "ours-1": "inexact-loops (1 thread)",
    "dbscan": "dbscan (PyPI, parallel C++)",
    "sklearn": "scikit-learn DBSCAN (kd_tree, n_jobs=-1)",
}
THREADS = {"ours": "all", "ours-1": "1", "dbscan": "all", "sklearn": "all (n_jobs=-1)"}


# --------------------------------------------------------------------------------------------
# Worker side: one contender, one n, in this process; prints one JSON line.
# --------------------------------------------------------------------------------------------


def make_detections(n: int):
    """(t, t') columns of n detections drawn uniformly from S_γ of the reference drive."""
    import inexact_loops as il

    loops = il.find_loops(il.urban_drive(), gamma=GAMMA_M)
    det = il.draw_detections(loops, budget=n, seed=SEED)
    return det.t, det.t_prime


def contender(name: str):
    """A function of the columns (t, t') and the (n, 2) array X that returns labels."""
    if name.startswith("ours"):
        import inexact_loops as il

        threads = 1 if name == "ours-1" else None

        def run(t, t_prime, _points):
            detections = il.Detections(t, t_prime)
            return il.cluster_detections(detections, epsilon_s=EPSILON_S, threads=threads).labels

        return run
    if name == "dbscan":
        import dbscan

        def run(_t, _t_prime, points):
            labels, _core = dbscan.DBSCAN(points, eps=EPSILON_S, min_samples=1)
            return labels

        return run
    if name == "sklearn":
        from sklearn.cluster import DBSCAN

        def run(_t, _t_prime, points):
            model = DBSCAN(eps=EPSILON_S, min_samples=1, algorithm="kd_tree", n_jobs=-1)
            return model.fit_predict(points)

        return run
    raise SystemExit(f"unknown contender {name!r}")


def worker(args: argparse.Namespace) -> None:
    import json

    import numpy as np

    cap_address_space(args.mem_limit_gb)
    t, t_prime = make_detections(args.n)
    points = np.ascontiguousarray(np.c_[t, t_prime])
    run = contender(args.worker)
    run(t[:1000].copy(), t_prime[:1000].copy(), points[:1000].copy())
    labels, report = measure(lambda: run(t, t_prime, points))
    np.save(args.labels, np.asarray(labels, dtype=np.int64))
    print(json.dumps(report), flush=True)


# --------------------------------------------------------------------------------------------
# Driver side.
# --------------------------------------------------------------------------------------------


def run_worker(name: str, n: int, labels: Path, args: argparse.Namespace) -> dict:
    """One measurement of `name` at `n` in a fresh subprocess."""
    command = [
        sys.executable,
        str(Path(__file__).resolve()),
        *("--worker", name, "--n", str(n), "--labels", str(labels)),
        *("--mem-limit-gb", str(args.mem_limit_gb)),
    ]
    print(f"  {CONTENDERS[name]}, n = {n:,} ...", end=" ", flush=True, file=sys.stderr)
    status, report, stderr = run_process(
        command, timeout_s=args.timeout_s, mem_limit_gb=args.mem_limit_gb
    )
    if report is None:
        print(status, file=sys.stderr)
        if status.startswith("failed"):
            sys.stderr.write(stderr)
        return {"status": status}
    print(f"{report['time_s']:.3f} s, {report['peak_above_baseline_mb']:.0f} MB", file=sys.stderr)
    return {
        "status": "ok",
        "times_s": [report["time_s"]],
        "peak_mb": report["peak_above_baseline_mb"],
    }


def same_partition(a, b) -> bool:
    """Whether two labellings put the same points together (their label pairs are a bijection)."""
    import numpy as np

    pairs = np.unique(np.c_[a, b], axis=0)
    return len(pairs) == len(np.unique(a)) == len(np.unique(b))


def neighbourhood_estimate(n: int) -> float:
    """Mean number of points within ε of a point (itself included), from 2,000 query points
    against all n with scipy's KD-tree: what DBSCAN in scikit-learn stores per point."""
    import numpy as np
    from scipy.spatial import cKDTree

    t, t_prime = make_detections(n)
    points = np.c_[t, t_prime]
    rng = np.random.default_rng(0)
    queries = points[rng.choice(n, size=2000, replace=False)]
    return float(cKDTree(points).query_ball_point(queries, r=EPSILON_S, return_length=True).mean())


def format_time(seconds: float) -> str:
    return f"{seconds:.3f}" if seconds < 10 else f"{seconds:.1f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, metavar="N", help="rounds (default 3)")
    parser.add_argument(
        "--sklearn-full", action="store_true", help="also run scikit-learn at n = 1e6 (slow, GBs)"
    )
    parser.add_argument("--timeout-s", type=float, default=600.0, metavar="SECONDS")
    parser.add_argument(
        "--mem-limit-gb", type=float, default=16.0, metavar="GB", help="address-space cap"
    )
    parser.add_argument("--output", type=Path, default=REPO / "BENCHMARKS.md", metavar="PATH")
    parser.add_argument("--no-write", action="store_true", help="print the report only")
    parser.add_argument("--worker", choices=sorted(CONTENDERS), help=argparse.SUPPRESS)
    parser.add_argument("--n", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--labels", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args)
        return 0

    import numpy as np

    try:
        import dbscan  # noqa: F401

        have_dbscan = True
    except ImportError:
        have_dbscan = False
        print("the dbscan package is not installed (pip install dbscan): left out", file=sys.stderr)

    load_at_start = load_average()
    plan = [("ours", n) for n in SIZES] + [("ours-1", n) for n in SIZES]
    if have_dbscan:
        plan += [("dbscan", n) for n in SIZES]
    plan += [("sklearn", n) for n in SIZES if n <= 100_000 or args.sklearn_full]
    results: dict[tuple[str, int], dict] = {}
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="cluster-compare-") as scratch:
        for round_index in range(args.repeat):
            print(f"round {round_index + 1}/{args.repeat}:", file=sys.stderr)
            for name, n in plan:
                done = results.get((name, n))
                if done is not None and done["status"] != "ok":
                    continue
                labels = Path(scratch) / f"{name}-{n}.npy"
                outcome = run_worker(name, n, labels, args)
                if done is None or outcome["status"] != "ok":
                    results[(name, n)] = outcome
                else:
                    done["times_s"] += outcome["times_s"]
                    done["peak_mb"] = max(done["peak_mb"], outcome["peak_mb"])
        # Partitions, against inexact-loops (all cores) at the same n.
        for (name, n), outcome in results.items():
            if outcome["status"] != "ok":
                outcome["match"] = "–"
                continue
            if name == "ours":
                outcome["match"] = "reference"
                continue
            reference = np.load(Path(scratch) / f"ours-{n}.npy")
            theirs = np.load(Path(scratch) / f"{name}-{n}.npy")
            ok = same_partition(reference, theirs)
            clusters = len(np.unique(theirs))
            outcome["match"] = f"yes ({clusters} clusters)" if ok else "**NO**"
            if not ok:
                problems.append(f"{CONTENDERS[name]} at n = {n}: the partition differs")
    load_at_end = load_average()
    full_n = SIZES[-1]
    neighbours = None if args.sklearn_full else neighbourhood_estimate(full_n)

    def best(name: str, n: int) -> float | None:
        outcome = results.get((name, n))
        return min(outcome["times_s"]) if outcome and outcome["status"] == "ok" else None

    rows = []
    for n in SIZES:
        reference = best("ours", n)
        for name in CONTENDERS:
            outcome = results.get((name, n))
            if outcome is None:
                continue
            seconds = best(name, n)
            if seconds is None:
                time_cell, ratio, memory = outcome["status"], "–", "–"
            else:
                time_cell = format_time(seconds)
                ratio = "–" if reference is None else f"{seconds / reference:.1f}×"
                memory = f"{outcome['peak_mb']:.0f}"
            rows.append(
                f"| {n:,} | {CONTENDERS[name]} | {THREADS[name]} | {time_cell} | {ratio} | "
                f"{memory} | {outcome['match']} |"
            )
        if n == full_n and ("sklearn", n) not in results and neighbours is not None:
            indices = neighbours * n
            rows.append(
                f"| {n:,} | {CONTENDERS['sklearn']} | – | not run | – | – | – (it would store "
                f"≈ {indices / 1e9:.1f}e9 neighbour indices, ≈ {indices * 8 / 1e9:.0f} GB; "
                "rerun with `--sklearn-full`) |"
            )
    targets = []
    for name, n, factor in (("dbscan", full_n, 3.0), ("sklearn", SIZES[0], 50.0)):
        ours, theirs = best("ours", n), best(name, n)
        if ours is None or theirs is None:
            status = results.get((name, n), {}).get("status", "not run")
            targets.append(
                f"| ≥ {factor:g}× faster than {CONTENDERS[name]} at n = {n:,} | {status} | – |"
            )
            continue
        speedup = theirs / ours
        verdict = "met" if speedup >= factor else "**not met**"
        targets.append(
            f"| ≥ {factor:g}× faster than {CONTENDERS[name]} at n = {n:,} | {speedup:.1f}× | "
            f"{verdict} |"
        )

    body = "\n".join(
        [
            "## ε-clustering of detections",
            "",
            "Generated by `python benches/cluster_compare.py"
            f"{' ' + ' '.join(sys.argv[1:]) if sys.argv[1:] else ''}`; do not edit by hand.",
            "",
            *machine_facts(("numpy", "scipy", "scikit-learn", "dbscan")),
            f"- Load average (1 min): {load_at_start} at the start, {load_at_end} at the end, "
            f"on {os.cpu_count()} CPUs; every contender under a {args.mem_limit_gb:g} GB "
            f"address-space cap and a {args.timeout_s:.0f} s timeout.",
            "- Input: n detections drawn uniformly from S_γ of the reference urban drive "
            "(75,600 poses, γ = 40 m; 32.7 million pairs) with `il.draw_detections(loops, "
            f"budget=n, seed={SEED})`, ε = {EPSILON_S:g} s. inexact-loops gets the columns t and "
            "t′ (`il.cluster_detections(il.Detections(t, t_prime), epsilon_s=30.0).labels`, "
            "the conversion included); the others the (n, 2) array, as they require.",
            "- Every contender runs in a fresh subprocess, warmed up on 1,000 points; *wall "
            f"time* is the best of {args.repeat} rounds (each contender once per round, so all "
            "see the same load); ratios are measured side by side and are what to trust on this "
            "shared machine. *Same partition*: a bijection between the label sets of the "
            "contender and of inexact-loops at the same n (DBSCAN with `min_samples=1` is "
            "exactly the components of the ε graph). *Memory*: peak resident set above the "
            "resident set right before the call.",
            "",
            "| n | Contender | Threads | Wall time (s) | Time vs inexact-loops | Peak RSS above "
            "baseline (MB) | Same partition |",
            "|---:|---|---|---:|---:|---:|---|",
            *rows,
            "",
            "| Target (issue 4) | Measured | |",
            "|---|---:|---|",
            *targets,
        ]
    )
    if not have_dbscan:
        body += "\n\nThe `dbscan` package could not be imported here: its rows are missing."
    print(body)
    if problems:
        print("RESULTS DIFFER; not writing " + str(args.output), file=sys.stderr)
        for problem in problems:
            print("  " + problem, file=sys.stderr)
        return 1
    if not args.no_write:
        write_section(args.output, SECTION, body)
        print(f"wrote the section <!-- {SECTION} --> of {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
