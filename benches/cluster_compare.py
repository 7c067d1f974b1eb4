#!/usr/bin/env python3
"""ε-clustering of detections, side by side with the ``dbscan`` package and scikit-learn.

Usage::

    python benches/cluster_compare.py [--repeat N] [--sklearn-full] [--no-write] [--output PATH]

Two workloads, each n detections drawn uniformly from the off-diagonal pairs of S_γ (γ = 40 m)
of a drive with ``il.draw_detections(loops, budget=n, seed=0)``; ε = 30 s:

- *dense*: the reference urban drive (``il.urban_drive()``, 1 km², 2.1 h,
  75,600 poses), n = 1e5 and 1e6. At n = 1e6, 3% of S_γ's 32.7 million pairs are drawn and a
  detection has ≈ 2,700 others within ε;
- *sparse*: the 10 × 10 km city for 28 h (``il.urban_drive(duration_s=100_000,
  city_size_m=10_000, seed=0)``, 10⁶ poses, as in ``benches/scale.py``), n = 1e6: 0.25% of
  its 394 million pairs, ≈ 300 detections within ε of a detection.

Every contender gets the points (t, t′) and returns a label per point; DBSCAN with
``min_samples=1`` is exactly the connected components of the ε graph, so all must give the same
partition, which the harness checks (a bijection between label sets) before it writes anything.

Contenders:

1. inexact-loops: ``il.cluster_detections(il.Detections(t, t_prime), epsilon_s=30.0)`` and its
   ``labels`` (all cores, and one thread);
2. the ``dbscan`` package from PyPI (parallel C++, all cores): ``dbscan.DBSCAN(X, eps=30.0,
   min_samples=1)`` on the (n, 2) array X;
3. scikit-learn: ``DBSCAN(eps=30.0, min_samples=1, algorithm="kd_tree", n_jobs=-1)
   .fit_predict(X)``. It stores every point's ε-neighbourhood (8-byte indices), so above
   n = 1e5 it runs only where the estimate of that storage (the mean neighbourhood of 2,000
   points, counted with scipy's KD-tree, times n) is at most ``SKLEARN_MAX_ESTIMATE_GB``: on the
   sparse workload (≈ 2.5 GB), not on the dense one (≈ 22 GB), unless ``--sklearn-full``.

Each measurement runs in a fresh subprocess (this script with a hidden ``--worker`` flag) under
a timeout and an address-space cap: the input is built, one untimed call on 1,000 of the points
warms up the contender, then the timed call. Contenders go in rounds so that all see the same
machine load (``benches/harness.py`` runs and measures them); the best of ``--repeat`` rounds
counts. The report goes to stdout, and the section ``<!-- cluster_compare -->`` of
BENCHMARKS.md is replaced (up to the next marker line or the end of the file); the rest of the
file is left as it is. Nothing is written when a partition differs or when the compiled module
changed during the run (a rebuild).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import harness

GAMMA_M = 40.0
EPSILON_S = 30.0
SEED = 0
SECTION = "cluster_compare"
# scikit-learn runs above this n only where its stored neighbourhoods (8-byte indices) are
# estimated at no more than this: well under the ≈ 8 GB that this shared machine can spare,
# since its peak goes above the final storage. The address-space cap stays in force.
SKLEARN_ALWAYS_MAX_N = 100_000
SKLEARN_MAX_ESTIMATE_GB = 4.0


@dataclass(frozen=True)
class Workload:
    key: str
    label: str
    drive: str  # for the report
    duration_s: float | None  # None: the library default (the reference drive)
    city_size_m: float | None
    sizes: tuple[int, ...]

    def make_drive(self):
        import inexact_loops as il

        if self.duration_s is None:
            return il.urban_drive()
        return il.urban_drive(duration_s=self.duration_s, city_size_m=self.city_size_m, seed=0)


WORKLOADS = (
    Workload("dense", "dense", "reference drive, 1 km², 2.1 h", None, None, (100_000, 1_000_000)),
    Workload("sparse", "sparse", "10 × 10 km city, 28 h", 100_000.0, 10_000.0, (1_000_000,)),
)
WORKLOAD_BY_KEY = {workload.key: workload for workload in WORKLOADS}
CASES = [(workload.key, n) for workload in WORKLOADS for n in workload.sizes]

CONTENDERS = {
    "ours": "inexact-loops",
    "ours-1": "inexact-loops (1 thread)",
    "dbscan": "dbscan (PyPI, parallel C++)",
    "sklearn": "scikit-learn DBSCAN (kd_tree, n_jobs=-1)",
}
THREADS = {"ours": "all", "ours-1": "1", "dbscan": "all", "sklearn": "all (n_jobs=-1)"}


# --------------------------------------------------------------------------------------------
# Worker side: one contender, one workload and n, in this process; prints one JSON line.
# --------------------------------------------------------------------------------------------


def make_loops(workload: Workload):
    """The drive's S_γ (``il.find_loops``) and its number of poses."""
    import inexact_loops as il

    trajectory = workload.make_drive()
    return il.find_loops(trajectory, gamma=GAMMA_M, separation=None), len(trajectory)


def make_detections(workload: Workload, n: int, loops=None):
    """(t, t') columns of n detections drawn uniformly from S_γ of the workload's drive."""
    import inexact_loops as il

    if loops is None:
        loops, _poses = make_loops(workload)
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

    harness.cap_address_space(args.mem_limit_gb)
    t, t_prime = make_detections(WORKLOAD_BY_KEY[args.workload], args.n)
    points = np.ascontiguousarray(np.c_[t, t_prime])
    run = contender(args.worker)
    run(t[:1000].copy(), t_prime[:1000].copy(), points[:1000].copy())
    labels, report = harness.measure(lambda: run(t, t_prime, points))
    np.save(args.labels, np.asarray(labels, dtype=np.int64))
    print(json.dumps(report), flush=True)


# --------------------------------------------------------------------------------------------
# Driver side.
# --------------------------------------------------------------------------------------------


def run_worker(name: str, workload: str, n: int, labels: Path, args: argparse.Namespace) -> dict:
    """One measurement of `name` on `workload` at `n` in a fresh subprocess."""
    options = ["--worker", name, "--workload", workload, "--n", str(n), "--labels", str(labels)]
    label = f"{CONTENDERS[name]}, {workload}, n = {n:,}"
    status, report, stderr = harness.run_worker(__file__, label, options, args)
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


def describe_workload(workload: Workload) -> dict:
    """Poses and off-diagonal pairs of the drive's S_γ, and for each n the mean number of
    detections within ε of a detection (itself included), from 2,000 query points against all
    n with scipy's KD-tree: what DBSCAN in scikit-learn stores per point."""
    import numpy as np
    from scipy.spatial import cKDTree

    loops, poses = make_loops(workload)
    facts = {"poses": poses, "pairs": (loops.pair_count - poses) // 2, "neighbours": {}}
    for n in workload.sizes:
        t, t_prime = make_detections(workload, n, loops)
        points = np.c_[t, t_prime]
        rng = np.random.default_rng(0)
        queries = points[rng.choice(n, size=2000, replace=False)]
        counts = cKDTree(points).query_ball_point(queries, r=EPSILON_S, return_length=True)
        facts["neighbours"][n] = float(counts.mean())
    return facts


def format_time(seconds: float) -> str:
    return f"{seconds:.3f}" if seconds < 10 else f"{seconds:.1f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sklearn-full",
        action="store_true",
        help="run scikit-learn at every n, also where it is estimated to need many GB",
    )
    harness.add_contender_options(
        parser,
        repeat_help="rounds (default 3)",
        output_help="the report whose <!-- cluster_compare --> section to write",
    )
    parser.add_argument("--no-write", action="store_true", help="print the report only")
    parser.add_argument("--worker", choices=sorted(CONTENDERS), help=argparse.SUPPRESS)
    parser.add_argument("--workload", choices=sorted(WORKLOAD_BY_KEY), help=argparse.SUPPRESS)
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

    build_at_start = harness.build_stamp()
    print("estimating neighbourhoods with scipy ...", file=sys.stderr)
    facts = {workload.key: describe_workload(workload) for workload in WORKLOADS}

    def sklearn_estimate_gb(workload: str, n: int) -> float:
        return facts[workload]["neighbours"][n] * n * 8 / 1e9

    def sklearn_runs(workload: str, n: int) -> bool:
        return (
            n <= SKLEARN_ALWAYS_MAX_N
            or args.sklearn_full
            or sklearn_estimate_gb(workload, n) <= SKLEARN_MAX_ESTIMATE_GB
        )

    load_at_start = harness.load_average()
    plan = [("ours", *case) for case in CASES] + [("ours-1", *case) for case in CASES]
    if have_dbscan:
        plan += [("dbscan", *case) for case in CASES]
    plan += [("sklearn", *case) for case in CASES if sklearn_runs(*case)]
    results: dict[tuple[str, str, int], dict] = {}
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="cluster-compare-") as scratch:

        def labels_path(name: str, workload: str, n: int) -> Path:
            return Path(scratch) / f"{name}-{workload}-{n}.npy"

        for round_index in range(args.repeat):
            print(f"round {round_index + 1}/{args.repeat}:", file=sys.stderr)
            for key in plan:
                done = results.get(key)
                if done is not None and done["status"] != "ok":
                    continue
                outcome = run_worker(*key, labels_path(*key), args)
                if done is None or outcome["status"] != "ok":
                    results[key] = outcome
                else:
                    done["times_s"] += outcome["times_s"]
                    done["peak_mb"] = max(done["peak_mb"], outcome["peak_mb"])
        # Partitions, against inexact-loops (all cores) on the same workload and n.
        for (name, workload, n), outcome in results.items():
            if outcome["status"] != "ok":
                outcome["match"] = "–"
                continue
            if name == "ours":
                outcome["match"] = "reference"
                continue
            reference = np.load(labels_path("ours", workload, n))
            theirs = np.load(labels_path(name, workload, n))
            ok = same_partition(reference, theirs)
            clusters = len(np.unique(theirs))
            outcome["match"] = f"yes ({clusters:,} clusters)" if ok else "**NO**"
            if not ok:
                problems.append(f"{CONTENDERS[name]}, {workload}, n = {n}: the partition differs")
    load_at_end = harness.load_average()
    if harness.build_stamp() != build_at_start:
        print(
            "the compiled module inexact_loops._core changed during the run (a rebuild): "
            f"not writing {args.output}; run again",
            file=sys.stderr,
        )
        return 1

    def best(name: str, workload: str, n: int) -> float | None:
        outcome = results.get((name, workload, n))
        return min(outcome["times_s"]) if outcome and outcome["status"] == "ok" else None

    rows = []
    for workload, n in CASES:
        reference = best("ours", workload, n)
        first = f"| {WORKLOAD_BY_KEY[workload].label} | {n:,} |"
        for name in CONTENDERS:
            outcome = results.get((name, workload, n))
            if outcome is None:
                continue
            seconds = best(name, workload, n)
            if seconds is None:
                time_cell, ratio, memory = outcome["status"], "–", "–"
            else:
                time_cell = format_time(seconds)
                ratio = "–" if reference is None else f"{seconds / reference:.1f}×"
                memory = f"{outcome['peak_mb']:.0f}"
            rows.append(
                f"{first} {CONTENDERS[name]} | {THREADS[name]} | {time_cell} | {ratio} | "
                f"{memory} | {outcome['match']} |"
            )
        if ("sklearn", workload, n) not in results:
            estimate = sklearn_estimate_gb(workload, n)
            indices = facts[workload]["neighbours"][n] * n
            rows.append(
                f"{first} {CONTENDERS['sklearn']} | – | not run | – | – | – (it would store "
                f"≈ {indices / 1e9:.1f}e9 neighbour indices, ≈ {estimate:.0f} GB, more than "
                f"this shared machine can spare; rerun with `--sklearn-full`) |"
            )

    def speedup(name: str, workload: str, n: int) -> str:
        ours, theirs = best("ours", workload, n), best(name, workload, n)
        return "not measured" if ours is None or theirs is None else f"{theirs / ours:.1f}×"

    summary = (
        f"Which workload gives which ratio: at n = 1,000,000, inexact-loops is "
        f"{speedup('dbscan', 'dense', 1_000_000)} faster than the `dbscan` package on the dense "
        f"workload and {speedup('dbscan', 'sparse', 1_000_000)} on the sparse one; it is "
        f"{speedup('sklearn', 'sparse', 1_000_000)} faster than scikit-learn on the sparse "
        "workload, the one where scikit-learn fits in memory at n = 1,000,000, and "
        f"{speedup('sklearn', 'dense', 100_000)} on the dense workload at n = 100,000."
    )

    targets = []
    for name, workload, n, factor in (
        ("dbscan", "dense", 1_000_000, 3.0),
        ("dbscan", "sparse", 1_000_000, 3.0),
        ("sklearn", "sparse", 1_000_000, 50.0),
        ("sklearn", "dense", 100_000, 50.0),
    ):
        goal = f"| ≥ {factor:g}× faster than {CONTENDERS[name]} | {workload} | {n:,} |"
        ours, theirs = best("ours", workload, n), best(name, workload, n)
        if ours is None or theirs is None:
            status = results.get((name, workload, n), {}).get("status", "not run")
            targets.append(f"{goal} {status} | – |")
            continue
        speedup = theirs / ours
        verdict = "met" if speedup >= factor else "**not met**"
        targets.append(f"{goal} {speedup:.1f}× | {verdict} |")

    def workload_line(workload: Workload) -> str:
        fact = facts[workload.key]
        sizes = " and ".join(f"{n:,}" for n in workload.sizes)
        densities = "; ".join(
            f"n = {n:,}: {n / fact['pairs']:.2%} of the pairs drawn, "
            f"≈ {fact['neighbours'][n]:,.0f} detections within ε of a detection"
            for n in workload.sizes
        )
        return (
            f"  - *{workload.label}*: {workload.drive} (`{workload_call(workload)}`, "
            f"{fact['poses']:,} poses; S_γ has {fact['pairs'] / 1e6:,.1f} million off-diagonal "
            f"pairs), n = {sizes}. {densities}."
        )

    body = "\n".join(
        [
            "## ε-clustering of detections",
            "",
            "Generated by `python benches/cluster_compare.py"
            f"{' ' + ' '.join(sys.argv[1:]) if sys.argv[1:] else ''}`; do not edit by hand.",
            "",
            *harness.machine_facts(("numpy", "scipy", "scikit-learn", "dbscan")),
            f"- Load average (1 min): {load_at_start} at the start, {load_at_end} at the end, "
            f"on {os.cpu_count()} CPUs; every contender under a {args.mem_limit_gb:g} GB "
            f"address-space cap and a {args.timeout_s:.0f} s timeout.",
            "- Input: n detections drawn uniformly from the off-diagonal pairs of S_γ (γ = 40 m) "
            f"of a drive with `il.draw_detections(loops, budget=n, seed={SEED})`, ε = "
            f"{EPSILON_S:g} s, on two workloads (neighbour counts: the mean over 2,000 "
            "detections, counted with scipy's KD-tree, itself included; this is what "
            "scikit-learn stores per point):",
            *(workload_line(workload) for workload in WORKLOADS),
            "- inexact-loops gets the columns t and t′ (`il.cluster_detections(il.Detections(t, "
            "t_prime), epsilon_s=30.0).labels`, the conversion included); the others the (n, 2) "
            "array, as they require. scikit-learn runs above n = "
            f"{SKLEARN_ALWAYS_MAX_N:,} only where its neighbour storage is estimated at ≤ "
            f"{SKLEARN_MAX_ESTIMATE_GB:g} GB (8-byte indices).",
            "- Every contender runs in a fresh subprocess, warmed up on 1,000 points; *wall "
            f"time* is the best of {args.repeat} round{'s' if args.repeat != 1 else ''} (each "
            "contender once per round, so all "
            "see the same load); ratios are measured side by side and are what to trust on this "
            "shared machine. *Same partition*: a bijection between the label sets of the "
            "contender and of inexact-loops on the same workload and n (DBSCAN with "
            "`min_samples=1` is exactly the components of the ε graph). *Memory*: peak resident "
            "set above the resident set right before the call.",
            "",
            "| Workload | n | Contender | Threads | Wall time (s) | Time vs inexact-loops | "
            "Peak RSS above baseline (MB) | Same partition |",
            "|---|---:|---|---|---:|---:|---:|---|",
            *rows,
            "",
            "| Target | Workload | n | Measured | |",
            "|---|---|---:|---:|---|",
            *targets,
            "",
            summary,
        ]
    )
    if not have_dbscan:
        body += "\n\nThe `dbscan` package could not be imported here: its rows are missing."
    print(body)
    if harness.refused(problems, args.output):
        return 1
    if not args.no_write:
        harness.write_section(args.output, SECTION, body)
        print(f"wrote the section <!-- {SECTION} --> of {args.output}", file=sys.stderr)
    return 0


def workload_call(workload: Workload) -> str:
    if workload.duration_s is None:
        return "il.urban_drive()"
    return (
        f"il.urban_drive(duration_s={workload.duration_s:_.0f}, "
        f"city_size_m={workload.city_size_m:_.0f}, seed=0)"
    )


if __name__ == "__main__":
    sys.exit(main())
