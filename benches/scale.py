#!/usr/bin/env python3
"""Scale benchmark: inexact-loops from 2,000 to 10⁷ poses against every peer.

Usage::

    python benches/scale.py [--quick] [--sizes KEY,...] [--timeout-s S] [--output PATH]
                            [--repeat N] [--budget-s S] [--mem-limit-gb GB]

Writes the section of ``BENCHMARKS.md`` under the marker line ``<!-- scale -->`` (up to the next
marker line or the end of the file) and keeps everything else; see ``benches/harness.py``.

Scenarios (``il.urban_drive(duration_s=..., city_size_m=..., district_m=..., seed=0)``, 10 Hz,
γ = 40 m on the 3-D positions): the 1 km² city for 200 s, 10 min, 2.1 h, 6 h and 28 h (2,000 to
1,008,000 poses); the 10 × 10 km city worked one 1 km² district at a time (2.8 h each, snake
order), where revisits stay bounded, for 10⁵, 10⁶ and 10⁷ poses; and, for contrast, the same city
roamed at random, where they do not. ``--quick`` leaves out 28 h and 10⁷.

Contenders, each repetition in a fresh subprocess under an address-space cap and a timeout
(the worker side of ``benches/harness.py``, as in ``compare.py``):

1. inexact-loops ``find_loops`` + ``components`` + ``loop_duration``, 1 and 2 threads;
2. scipy ``cKDTree.query_pairs`` (the pairs only);
3. the scipy lattice pipeline of ``compare.py`` (every cell a graph node);
4. dense ``scipy.ndimage.label`` of the full n × n boolean matrix (n ≤ 20,000);
5. the paper's route: 1% of the off-diagonal pairs of S_γ drawn as detections (from our runs,
   every pair independently, seeded), then DBSCAN(eps = 30 s, min_samples = 1) on their
   (t, t′) points, with scikit-learn and with the ``dbscan`` package; only the clustering is
   timed.

A peer that ran out of memory or time at a size is skipped at every later size at least as
large (in poses and in cells of S_γ); a peer whose unavoidable arrays cannot fit under the cap,
or whose peak per pair, cell or detection at its largest finished size extrapolates to more
than ``EXTRAPOLATION_MARGIN`` times the cap, is skipped with that reason.

For inexact-loops the worker also samples, during the timed call, how long each of its threads
ran and how long it was ready but waiting for a core (``/proc/self/task/*/schedstat``): the
parallelism the work offered, apart from what the load let it have.

Reference checks (the script exits with status 1 and writes nothing if one fails): for
n ≤ 20,000 our partition equals dense ``ndimage.label``'s; where the lattice pipeline finishes,
its cells and partition equal ours; at every size, random windows of rows [a, a + w) have our
runs equal to the sets of ``cKDTree.query_ball_point(x_i, r=γ)`` (j ≥ i), and the components of
the window's runs (4-adjacency, ``csgraph.connected_components``) each lie in one of ours; the
2-thread runs and component table are identical to the 1-thread ones; query_pairs' pair count
equals ours.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import harness

MARKER_NAME = "scale"
GAMMA_M = 40.0
EPSILON_S = 30.0
DETECTION_RATE = 0.01
DETECTION_SEED = 1
WINDOW_SEED = 2
WINDOWS = 5
WINDOW_ROWS = 400
DENSE_MAX_POSES = 20_000
WARM_UP_DURATION_S = 60.0
WARM_UP_DETECTIONS = 2_000
# Bytes that a peer cannot do without, to skip it where it clearly cannot fit under the cap:
# query_pairs' (m, 2) int64 output; the lattice's int64 cell keys beside that output; the dense
# boolean matrix and its int32 labels.
QUERY_PAIRS_BYTES_PER_PAIR = 16
LATTICE_BYTES_PER_CELL = 24
DENSE_BYTES_PER_CELL = 5
# A peer whose memory per unit of work (cells, pairs, detections), measured at its largest
# finished size, extrapolates to more than this times the cap is skipped.
EXTRAPOLATION_MARGIN = 1.4


@dataclass(frozen=True)
class Size:
    key: str
    city: str
    city_size_m: float | None
    duration_s: float
    label: str
    long: bool = False  # left out by --quick
    district_m: float | None = None  # work the city one district at a time

    @property
    def poses(self) -> int:
        return round(self.duration_s * 10)


# Time in each district of the district drive, seconds: 10⁵ poses, 2.8 h.
DISTRICT_DWELL_S = 10_000.0
# The large city, worked one 1 km² district at a time (the scenario: revisits stay
# bounded), or roamed at random (revisits grow with the drive).
DISTRICTS = "10 × 10 km, by district"
ROAMING = "10 × 10 km, roaming"
# In the order they run: growing in poses and in cells, so that a failure skips the sizes after.
SIZES = [
    Size("1km-200s", "1 km²", None, 200.0, "200 s"),
    Size("1km-10min", "1 km²", None, 600.0, "10 min"),
    Size("10km-1e5", ROAMING, 10_000.0, 10_000.0, "2.8 h (10⁵)"),
    Size("10km-d-1e5", DISTRICTS, 10_000.0, 10_000.0, "2.8 h (10⁵)", district_m=1000.0),
    Size("1km-2.1h", "1 km²", None, 7_560.0, "2.1 h"),
    Size("1km-6h", "1 km²", None, 21_600.0, "6 h"),
    Size("10km-1e6", ROAMING, 10_000.0, 100_000.0, "28 h (10⁶)"),
    Size("10km-d-1e6", DISTRICTS, 10_000.0, 100_000.0, "28 h (10⁶)", district_m=1000.0),
    Size("1km-28h", "1 km²", None, 100_800.0, "28 h", long=True),
    Size("10km-1e7", ROAMING, 10_000.0, 1_000_000.0, "278 h (10⁷)", long=True),
    Size(
        "10km-d-1e7", DISTRICTS, 10_000.0, 1_000_000.0, "278 h (10⁷)", long=True, district_m=1000.0
    ),
]
SIZE_BY_KEY = {size.key: size for size in SIZES}
# The sizes of the scaling series, for the growth exponents.
FIT_MIN_POSES = 75_000

CONTENDERS = {
    "ours-1": "inexact-loops, 1 thread",
    "ours-2": "inexact-loops, 2 threads",
    "query-pairs": "cKDTree.query_pairs",
    "lattice": "scipy lattice pipeline",
    "dense": "dense ndimage.label",
    "dbscan-sklearn": "1% + DBSCAN (scikit-learn)",
    "dbscan-pkg": "1% + DBSCAN (`dbscan`)",
}
DBSCAN_PACKAGES = {"dbscan-sklearn": "scikit-learn", "dbscan-pkg": "dbscan"}


# --------------------------------------------------------------------------------------------
# Worker side: one contender on one size in this process; prints one JSON line.
# --------------------------------------------------------------------------------------------


def make_drive(size: Size, duration_s: float | None = None):
    import inexact_loops as il

    return il.urban_drive(
        duration_s=size.duration_s if duration_s is None else duration_s,
        city_size_m=size.city_size_m,
        district_m=size.district_m,
        district_dwell_s=None if size.district_m is None else DISTRICT_DWELL_S,
        seed=0,
    )


def dense_label(positions, gamma_m: float):
    """The full n × n boolean matrix δ ≤ γ (built in row blocks) and its 4-connected labels."""
    import numpy as np
    from scipy import ndimage
    from scipy.spatial.distance import cdist

    n = len(positions)
    inside = np.empty((n, n), dtype=bool)
    block = max(1, 2**24 // max(n, 1))
    for lo in range(0, n, block):
        inside[lo : lo + block] = cdist(positions[lo : lo + block], positions) <= gamma_m
    labels, count = ndimage.label(inside)  # default structure: 4-connectivity
    return inside, labels, count


def check_dense(traj, gamma_m: float, inside, labels) -> dict:
    """Whether our partition of S_γ's upper half equals that of dense ``ndimage.label``."""
    import numpy as np

    n = len(traj)
    loops, runs, k = harness.reference_loops(traj, gamma_m)
    problems = []
    if loops.pair_count != int(inside.sum()):
        problems.append(f"pairs of S_γ: dense {int(inside.sum())}, ours {loops.pair_count}")
    row, start, end, component = (runs[key] for key in ("row", "start", "end", "component"))
    diff = np.zeros((n, n + 1), dtype=np.int32)
    np.add.at(diff, (row, start), component + 1)
    np.add.at(diff, (row, end + 1), -(component + 1))
    ours = np.cumsum(diff, axis=1, dtype=np.int32)[:, :n] - 1  # -1 outside our runs
    del diff
    upper = np.triu(inside)
    if not np.array_equal(ours >= 0, upper):
        problems.append("our runs do not cover exactly the upper half of the dense matrix")
    else:
        our_ids = ours[upper].astype(np.int64)
        their = labels[upper].astype(np.int64)
        pairs = np.unique(our_ids * (int(labels.max()) + 1) + their)
        if not (len(pairs) == k == len(np.unique(their)) == len(np.unique(our_ids))):
            problems.append(
                f"partitions differ: {k} components, {len(np.unique(their))} dense labels on "
                f"the upper half, {len(pairs)} (component, label) pairs"
            )
    return {"components": k, "labels_full_plane": int(labels.max()), "problems": problems}


def window_check(positions, runs, gamma_m: float, windows: int, width: int, seed: int) -> dict:
    """Our runs in random windows of rows against ``cKDTree.query_ball_point``.

    For rows i in [a, a + w): the columns j ≥ i with ‖x_i − x_j‖ ≤ γ, from the KD-tree, cut
    into maximal runs of consecutive columns, must equal our runs of row i exactly. Then the
    runs of the window are joined when 4-adjacent (rows i and i + 1 sharing a column) and
    labelled with ``csgraph.connected_components``: each such local group must lie in one of
    our components (ours may join groups through cells outside the window).
    """
    import numpy as np
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    n = len(positions)
    width = min(width, n)
    rng = np.random.default_rng(seed)
    firsts = np.sort(rng.integers(0, n - width + 1, size=windows))
    tree = cKDTree(positions)
    row, start, end, component = (runs[key] for key in ("row", "start", "end", "component"))
    problems: list[str] = []
    cells = groups = 0
    for a in firsts.tolist():
        lo, hi = np.searchsorted(row, [a, a + width])
        neighbours = tree.query_ball_point(positions[a : a + width], r=gamma_m, return_sorted=True)
        ref_start, ref_end, ref_row = [], [], []
        for offset, found in enumerate(neighbours):
            i = a + offset
            columns = np.asarray(found, dtype=np.int64)
            columns = columns[columns >= i]
            breaks = np.flatnonzero(np.diff(columns) != 1)
            ref_start.append(columns[np.r_[0, breaks + 1]])
            ref_end.append(columns[np.r_[breaks, len(columns) - 1]])
            ref_row.append(np.full(len(breaks) + 1, i, dtype=np.int64))
        got = (row[lo:hi], start[lo:hi], end[lo:hi])
        expected = tuple(np.concatenate(parts) for parts in (ref_row, ref_start, ref_end))
        if not all(np.array_equal(x, y) for x, y in zip(got, expected, strict=True)):
            for i in range(a, a + width):
                mine = np.c_[got[1], got[2]][got[0] == i]
                theirs = np.c_[expected[1], expected[2]][expected[0] == i]
                if not np.array_equal(mine, theirs):
                    problems.append(
                        f"row {i}: our runs {mine.tolist()[:5]} differ from query_ball_point's "
                        f"{theirs.tolist()[:5]}"
                    )
                    break
            continue
        w_row, w_start, w_end = got
        w_component = component[lo:hi]
        cells += int((w_end - w_start + 1).sum())
        # 4-adjacency between runs of consecutive rows: the runs of row i - 1 overlapping run m
        # of row i are a contiguous block, found by binary search on keys row·(n + 1) + column.
        stride = np.int64(n + 1)
        key_start = w_row * stride + w_start
        key_end = w_row * stride + w_end
        previous = (w_row - 1) * stride
        first = np.searchsorted(key_end, previous + w_start, side="left")
        last = np.searchsorted(key_start, previous + w_end, side="right")
        count = np.maximum(last - first, 0)
        sources = np.repeat(np.arange(len(w_row)), count)
        targets = np.repeat(first - np.cumsum(count) + count, count) + np.arange(count.sum())
        graph = coo_array(
            (np.ones(len(sources)), (sources, targets)), shape=(len(w_row), len(w_row))
        )
        local_count, local = connected_components(graph, directed=False)
        groups += local_count
        pairs = np.unique(local.astype(np.int64) * (int(w_component.max()) + 1) + w_component)
        if len(pairs) != local_count:
            problems.append(
                f"rows {a}..{a + width - 1}: a group of 4-adjacent runs spans two of our components"
            )
    return {
        "windows": len(firsts),
        "rows": int(len(firsts) * width),
        "cells": cells,
        "groups": groups,
        "problems": problems,
    }


def draw_detections(timestamps, runs, rate: float, seed: int):
    """Every off-diagonal pair (i < j) of our runs independently with probability `rate`.

    Returns the (m, 2) array of their times (t_i, t_j), row-major. Runs go in chunks; in each,
    a binomial count of distinct offsets is drawn uniformly into the chunk's pairs.
    """
    import numpy as np

    row = runs["row"]
    start = np.maximum(runs["start"], row + 1)  # the diagonal (i, i) is no detection
    end = runs["end"]
    keep = end >= start
    row, start, end = row[keep], start[keep], end[keep]
    rng = np.random.default_rng(seed)
    parts = []
    chunk = 1 << 22
    for lo in range(0, len(row), chunk):
        lengths = end[lo : lo + chunk] - start[lo : lo + chunk] + 1
        cumulative = np.cumsum(lengths)
        total = int(cumulative[-1])
        picks = np.sort(rng.choice(total, size=rng.binomial(total, rate), replace=False))
        which = np.searchsorted(cumulative, picks, side="right")
        columns = start[lo : lo + chunk][which] + picks - (cumulative[which] - lengths[which])
        rows = row[lo : lo + chunk][which]
        parts.append(np.c_[timestamps[rows], timestamps[columns]])
    return np.concatenate(parts) if parts else np.empty((0, 2))


def partition_digest(labels) -> str:
    """A fingerprint of a partition, independent of how its labels are numbered."""
    import numpy as np

    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return harness.table_digest({"labels": rank[inverse.ravel()]})


def detections_path(workdir: str, size: Size) -> Path:
    return Path(workdir) / f"detections-{size.key}.npy"


class ThreadTimes:
    """Running and waiting time of this process's threads while the `with` block runs.

    Reads ``/proc/self/task/*/schedstat`` (time on a CPU, time runnable but waiting for one, in
    ns) every `interval_s` from a thread of its own, so that threads which start and end inside
    the block (a rayon pool made for one call) are counted too, up to the last interval. Time
    waiting for a core is what other work on the machine takes; a thread blocked on a lock or
    idle for lack of work counts in neither. So ``(running + waiting) / wall`` is how many threads
    the work kept ready, whatever the load: what the speed-up would be with a core each.
    """

    def __init__(self, interval_s: float = 0.02) -> None:
        self.interval_s = interval_s
        self.running_s = self.waiting_s = self.wall_s = 0.0

    @staticmethod
    def _read() -> dict[str, tuple[int, int]]:
        times = {}
        for tid in os.listdir("/proc/self/task"):
            try:
                with open(f"/proc/self/task/{tid}/schedstat") as stat:
                    running, waiting = stat.read().split()[:2]
            except (OSError, ValueError):
                continue  # the thread ended
            times[tid] = (int(running), int(waiting))
        return times

    def _sample(self) -> None:
        while not self._stop.wait(self.interval_s):
            self._latest.update(self._read())

    def __enter__(self) -> ThreadTimes:
        import threading

        self._stop = threading.Event()
        self._start = self._read()
        self._latest = dict(self._start)
        self._sampler = threading.Thread(target=self._sample, daemon=True)
        self._sampler.start()
        self._own = str(self._sampler.native_id)
        self._started = time.perf_counter()
        return self

    def __exit__(self, *_) -> None:
        self.wall_s = time.perf_counter() - self._started
        self._latest.update(self._read())
        self._stop.set()
        self._sampler.join()
        for tid, (running, waiting) in self._latest.items():
            if tid == self._own:
                continue
            running0, waiting0 = self._start.get(tid, (0, 0))
            self.running_s += (running - running0) / 1e9
            self.waiting_s += (waiting - waiting0) / 1e9


def worker(args: argparse.Namespace) -> None:
    import json

    harness.cap_address_space(args.mem_limit_gb)
    import compare
    import numpy as np
    import scipy.ndimage  # noqa: F401  (imported before the baseline)
    import scipy.sparse.csgraph  # noqa: F401
    import scipy.spatial  # noqa: F401

    size = SIZE_BY_KEY[args.size]
    name = args.worker
    traj = None
    if name.startswith("dbscan"):
        points = np.load(detections_path(args.workdir, size))
        warm_up = np.ascontiguousarray(points[:WARM_UP_DETECTIONS])
        if name == "dbscan-sklearn":
            from sklearn.cluster import DBSCAN

            def run(data):
                return DBSCAN(eps=EPSILON_S, min_samples=1).fit(data).labels_

        else:
            import dbscan

            def run(data):
                return dbscan.DBSCAN(data, eps=EPSILON_S, min_samples=1)[0]

        data = points
    else:
        warm_up_traj = make_drive(size, WARM_UP_DURATION_S)
        traj = make_drive(size)
        if name.startswith("ours"):
            threads = int(name.split("-")[1])
            warm_up, data = warm_up_traj, traj

            def run(drive):
                return compare.ours(drive, args.gamma_m, threads)

        else:
            warm_up, data = warm_up_traj.positions, traj.positions
            function = {
                "query-pairs": compare.query_pairs,
                "lattice": compare.lattice_components,
                "dense": dense_label,
            }[name]

            def run(positions):
                return function(positions, args.gamma_m)

    # One untimed call on small input first: one-time costs count for no one.
    run(warm_up)
    thread_times = ThreadTimes()

    def timed():
        with thread_times:
            return run(data)

    result, measured = harness.measure(timed)
    report: dict = {"status": "ok", "poses": size.poses, **measured}
    if name.startswith("ours"):
        loops, components, _ = result
        del result
        runs = loops.runs()
        report.update(
            threads_ready=(thread_times.running_s + thread_times.waiting_s) / thread_times.wall_s,
            threads_waiting=thread_times.waiting_s / thread_times.wall_s,
        )
        report.update(
            poses=len(traj),
            **harness.result_facts(loops, components, len(traj)),
            path_km=float(np.linalg.norm(np.diff(traj.positions, axis=0), axis=1).sum() / 1000),
        )
        if name == "ours-1" and not args.skip_check:
            report["windows"] = window_check(
                traj.positions, runs, args.gamma_m, WINDOWS, WINDOW_ROWS, WINDOW_SEED
            )
            points = draw_detections(traj.timestamps, runs, DETECTION_RATE, DETECTION_SEED)
            np.save(detections_path(args.workdir, size), points)
            report["detections"] = len(points)
    elif name == "query-pairs":
        report["pairs_upper"] = len(result)
    elif name == "lattice":
        keys, labels, count, pair_count = result
        del result
        report["pairs_upper"] = pair_count
        if not args.skip_check:
            report["check"] = compare.check_lattice(
                traj, args.gamma_m, keys, labels, count, pair_count
            )
    elif name == "dense":
        inside, labels, _ = result
        del result
        if not args.skip_check:
            report["check"] = check_dense(traj, args.gamma_m, inside, labels)
    else:
        report.update(
            detections=len(data),
            clusters=len(np.unique(result)),
            partition=partition_digest(result),
        )
    print(json.dumps(report), flush=True)


# --------------------------------------------------------------------------------------------
# Driver side.
# --------------------------------------------------------------------------------------------


@dataclass
class Outcome:
    status: str
    times_s: list[float] = field(default_factory=list)
    peak_mb: float = 0.0  # above the baseline, the largest over the repetitions
    absolute_peak_mb: float = 0.0
    # Of the fastest repetition: cores busy (CPU time / wall time), and for inexact-loops the
    # threads kept ready (running or waiting for a core) and waiting, per unit of wall time.
    cpu_per_wall: float = 0.0
    data: dict = field(default_factory=dict)
    threads_ready: float = 0.0
    threads_waiting: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def best_s(self) -> float | None:
        return min(self.times_s) if self.ok and self.times_s else None

    @property
    def failed(self) -> bool:
        """Ran out of memory or time (not skipped, not a crash)."""
        return self.status.startswith(("out of memory", "killed", "timeout"))


@dataclass
class Result:
    size: Size
    outcomes: dict[str, Outcome] = field(default_factory=dict)
    checks: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)

    @property
    def reference(self) -> dict:
        ours = self.outcomes.get("ours-1")
        return ours.data if ours is not None and ours.ok else {}


def run_worker(name: str, size: Size, args: argparse.Namespace, *, first: bool) -> Outcome:
    options = ["--worker", name, "--size", size.key, "--workdir", args.workdir]
    options += ["--gamma-m", str(args.gamma_m), *([] if first else ["--skip-check"])]
    started = time.perf_counter()
    status, report, stderr = harness.run_worker(__file__, CONTENDERS[name], options, args)
    took = time.perf_counter() - started
    if status != "ok":
        print(f"{status} (after {took:.0f} s)", file=sys.stderr)
        if status.startswith("failed"):
            sys.stderr.write(stderr)
        return Outcome(status)
    print(
        f"{report['time_s']:.3f} s, {report['peak_above_baseline_mb']:.0f} MB "
        f"(worker {took:.0f} s)",
        file=sys.stderr,
    )
    return Outcome(
        "ok",
        [report["time_s"]],
        report["peak_above_baseline_mb"],
        report["peak_mb"],
        report["cpu_s"] / report["time_s"] if report["time_s"] > 0 else 0.0,
        report,
        report.get("threads_ready", 0.0),
        report.get("threads_waiting", 0.0),
    )


@dataclass
class History:
    """What earlier sizes taught about each peer, to skip it where it cannot finish."""

    # name -> (size, reference data, status) of its first failure (memory or time)
    failures: dict[str, tuple[Size, dict, str]] = field(default_factory=dict)
    # name -> (size, work, peak MB) at its largest finished size
    largest: dict[str, tuple[Size, float, float]] = field(default_factory=dict)

    def record(self, result: Result) -> None:
        for name, outcome in result.outcomes.items():
            if outcome.failed:
                self.failures.setdefault(name, (result.size, result.reference, outcome.status))
            amount = work(name, result.size, result.reference)
            if outcome.ok and amount:
                self.largest[name] = (result.size, amount, outcome.peak_mb)


# What a peer's memory grows with, and its name.
WORK_UNITS = {
    "query-pairs": ("pairs_upper", "pair"),
    "lattice": ("cells_upper", "cell"),
    "dbscan-sklearn": ("detections", "detection"),
    "dbscan-pkg": ("detections", "detection"),
}


def work(name: str, size: Size, reference: dict) -> float | None:
    if name == "dense":
        return float(size.poses) ** 2
    key = WORK_UNITS.get(name, (None,))[0]
    return float(reference[key]) if key and reference.get(key) else None


def skip_reason(name: str, size: Size, reference: dict, history: History, args) -> str | None:
    """Why `name` is not run at `size`, if it is not."""
    cap = args.mem_limit_gb * 2**30
    if not reference:
        return "skipped: inexact-loops did not finish"
    failed = history.failures.get(name)
    if failed is not None:
        at, data, status = failed
        if size.poses >= at.poses and reference["cells_upper"] >= data.get("cells_upper", 0):
            what = "out of memory" if status.startswith(("out", "killed")) else "timed out"
            return f"skipped: {what} at n = {at.poses:,}"
    if name.startswith("dbscan") and not detections_path(args.workdir, size).exists():
        return "skipped: no detections drawn"
    if name == "dbscan-pkg" and harness.package_version("dbscan") == "not installed":
        return "skipped: `dbscan` not installed (`pip install dbscan`)"
    # Arrays it cannot do without.
    needs = {
        "query-pairs": (QUERY_PAIRS_BYTES_PER_PAIR * reference["pairs_upper"], "its output"),
        "lattice": (LATTICE_BYTES_PER_CELL * reference["cells_upper"], "cell keys + pairs"),
        "dense": (DENSE_BYTES_PER_CELL * size.poses**2, "n × n matrix + labels"),
    }.get(name)
    if needs is not None and needs[0] > cap:
        return f"skipped: needs ≥ {needs[0] / 2**30:.0f} GB ({needs[1]})"
    if name == "dense" and size.poses > DENSE_MAX_POSES:
        return f"skipped: n > {DENSE_MAX_POSES:,}"
    # Its memory per unit of work at its largest finished size, well past the cap here.
    expected = expected_peak(name, size, reference, history)
    if expected is not None and expected[0] > EXTRAPOLATION_MARGIN * cap:
        return f"skipped: ≈ {expected[0] / 2**30:.0f} GB expected ({expected[1]})"
    return None


def expected_peak(
    name: str, size: Size, reference: dict, history: History
) -> tuple[float, str] | None:
    """A peer's peak memory here, bytes, extrapolated from its peak per unit of work (cells,
    pairs, detections) at its largest finished size; and that rate as text."""
    amount = work(name, size, reference)
    before = history.largest.get(name)
    if not amount or before is None:
        return None
    at, done, peak_mb = before
    unit = WORK_UNITS[name][1] if name in WORK_UNITS else "cell"
    rate = peak_mb * 2**20 / done
    return rate * amount, f"{rate:.0f} B a {unit} at n = {at.poses:,}"


def run_size(size: Size, args: argparse.Namespace, history: History) -> Result:
    result = Result(size)
    outcomes = result.outcomes
    print(f"{size.city}, {size.label} ({size.poses:,} poses):", file=sys.stderr)
    for round_index in range(args.repeat):
        for name in CONTENDERS:
            done = outcomes.get(name)
            if done is None:
                reason = (
                    None
                    if name == "ours-1"
                    else skip_reason(name, size, result.reference, history, args)
                )
                if reason is not None:
                    outcomes[name] = Outcome(reason)
                    print(f"  {CONTENDERS[name]}: {reason}", file=sys.stderr)
                    continue
            elif not done.ok or sum(done.times_s) >= args.budget_s:
                continue
            new = run_worker(name, size, args, first=done is None)
            if new.status.startswith("crashed"):
                # A crash says nothing of why; what its memory would have been is a fact.
                expected = expected_peak(name, size, result.reference, history)
                if expected is not None:
                    new.status += (
                        f"; ≈ {expected[0] / 2**30:.0f} GB expected ({expected[1]}), "
                        f"cap {args.mem_limit_gb:g} GB"
                    )
            if done is None or not new.ok:
                outcomes[name] = new
            else:
                if new.times_s[0] < min(done.times_s):
                    done.cpu_per_wall = new.cpu_per_wall
                    done.threads_ready = new.threads_ready
                    done.threads_waiting = new.threads_waiting
                done.times_s += new.times_s
                done.peak_mb = max(done.peak_mb, new.peak_mb)
                done.absolute_peak_mb = max(done.absolute_peak_mb, new.absolute_peak_mb)
        print(f"  (round {round_index + 1}/{args.repeat} done)", file=sys.stderr)
    history.record(result)
    check(result)
    return result


def check(result: Result) -> None:
    """Cross-checks the outcomes of one size; fills `checks` and `problems`."""
    outcomes, reference = result.outcomes, result.reference
    if not reference:
        result.problems.append(f"inexact-loops (1 thread): {outcomes['ours-1'].status}")
        return
    windows = reference["windows"]
    result.problems += [f"windows: {problem}" for problem in windows["problems"]]
    result.checks.append(
        f"{windows['windows']} windows × {windows['rows'] // windows['windows']} rows: runs = "
        f"query_ball_point's ({windows['cells']:,} cells), {windows['groups']:,} local groups "
        "each in one component"
    )
    ours2 = outcomes["ours-2"]
    if ours2.ok:
        if ours2.data["digest"] == reference["digest"]:
            result.checks.append("2 threads = 1 thread")
        else:
            result.problems.append("2 threads: runs or component table differ from 1 thread")
    pairs = outcomes["query-pairs"]
    if pairs.ok:
        if pairs.data["pairs_upper"] == reference["pairs_upper"]:
            result.checks.append("pair count = query_pairs'")
        else:
            result.problems.append(
                f"query_pairs: {pairs.data['pairs_upper']} pairs i < j, ours "
                f"{reference['pairs_upper']}"
            )
    for name, what in (("dense", "dense ndimage.label"), ("lattice", "lattice")):
        outcome = outcomes[name]
        if not outcome.ok:
            continue
        problems = outcome.data["check"]["problems"]
        result.problems += [f"{what}: {problem}" for problem in problems]
        if not problems:
            result.checks.append(
                f"**{what}: same partition** ({outcome.data['check']['components']:,} components)"
            )
    clusters = {name: outcomes[name].data for name in DBSCAN_PACKAGES if outcomes[name].ok}
    if len(clusters) == 2:
        same = clusters["dbscan-sklearn"]["partition"] == clusters["dbscan-pkg"]["partition"]
        result.checks.append(
            "both DBSCANs: same partition" if same else "the two DBSCANs' partitions differ"
        )


# --------------------------------------------------------------------------------------------
# The report.
# --------------------------------------------------------------------------------------------


def seconds(value: float) -> str:
    if value < 0.01:
        return f"{value:.2g}"
    return f"{value:.3f}" if value < 10 else f"{value:.1f}" if value < 100 else f"{value:.0f}"


def megabytes(value: float) -> str:
    if value >= 10_000:
        return f"{value / 1024:.1f} GB"
    return f"{value:.0f} MB" if value >= 10 else f"{value:.1f} MB"


def cell(outcome: Outcome | None, args: argparse.Namespace) -> str:
    if outcome is None:
        return "–"
    if outcome.ok:
        return f"{seconds(outcome.best_s)} s · {megabytes(outcome.peak_mb)}"
    status = outcome.status
    if status.startswith("timeout"):
        minutes = args.timeout_s / 60
        return f"> {minutes:g} min" if args.timeout_s >= 60 else f"> {args.timeout_s:g} s"
    if status.startswith("out of memory"):
        return f"out of memory (> {args.mem_limit_gb:g} GB)"
    return status


def street_km(size: Size) -> float:
    """Length of the city's streets: (L / block + 1) lines each way, L long (100 m blocks)."""
    side_m = size.city_size_m or 1000.0
    return 2 * (math.floor(side_m / 100.0) + 1) * side_m / 1000


def growth(results: list[Result]) -> list[str]:
    """The slopes table and, per city, what the counts say about them."""
    import numpy as np

    rows, notes = [], []
    for city in dict.fromkeys(result.size.city for result in results):
        series = [
            r
            for r in results
            if r.size.city == city and r.size.poses >= FIT_MIN_POSES and r.reference
        ]
        if len(series) < 2:
            continue
        n = [r.reference["poses"] for r in series]

        def slope(values, against) -> float | None:
            if any(v is None or v <= 0 for v in [*values, *against]):
                return None
            x, y = (np.log(np.array(v, dtype=float)) for v in (against, values))
            return float(np.polyfit(x, y, 1)[0])

        def shown(value: float | None) -> str:
            return "–" if value is None else f"{value:.2f}"

        one = [r.outcomes["ours-1"].best_s for r in series]
        two = [r.outcomes["ours-2"].best_s for r in series]
        runs = [r.reference["runs"] for r in series]
        cells = [r.reference["cells_upper"] for r in series]
        steps = list(zip(series, one, runs, strict=True))
        local = ", ".join(
            f"{a.size.label} → {b.size.label}: "
            f"{math.log(tb / ta) / math.log(b.size.poses / a.size.poses):.2f} in n, "
            f"{math.log(tb / ta) / math.log(kb / ka):.2f} in runs"
            for (a, ta, ka), (b, tb, kb) in zip(steps, steps[1:], strict=False)
            if ta and tb
        )
        fitted = ", ".join(f"{poses:,}" for poses in n)
        rows.append(
            f"| {city} | {fitted} | {shown(slope(runs, n))} | {shown(slope(cells, n))} | "
            f"{shown(slope(one, n))} | {shown(slope(two, n))} | {shown(slope(one, runs))} | "
            f"{shown(slope(two, runs))} | {local} |"
        )
        per_pose = ", ".join(f"{k / poses:.2f}" for k, poses in zip(runs, n, strict=True))
        per_run = ", ".join(
            f"{1e9 * t / k:.0f} ns" for t, k in zip(one, runs, strict=True) if t is not None
        )
        district_m = series[0].size.district_m
        if district_m is not None:
            dwell_poses = round(DISTRICT_DWELL_S * 10)
            districts = (series[0].size.city_size_m / district_m) ** 2
            story = (
                f"the drive works one {district_m / 1000:g} km² district at a time "
                f"({dwell_poses:,} poses each, snake order, {districts:.0f} districts), so "
                "a place is revisited only while its district is worked, whatever n: runs per "
                f"pose {per_pose} at the fitted sizes. The answer grows as n (runs as "
                f"n^{shown(slope(runs, n))}), and so does our time"
            )
        else:
            streets = street_km(series[0].size)
            coverage = [r.reference["path_km"] / streets for r in series]
            covered = ", ".join(
                f"{c:.2g}× at n = {poses:,}" for c, poses in zip(coverage, n, strict=True)
            )
            revisits = (
                "A city of fixed size roamed at random cannot keep the revisits per pose "
                f"bounded once the drive is longer than its streets (here {coverage[-1]:.2g}× at "
                "the largest n), so the answer, S_γ's runs, grows faster than n"
                if coverage[-1] > 1
                else "The drive is shorter than the streets, so revisits per pose stay few"
            )
            story = (
                f"{streets:,.0f} km of streets, covered {covered}. {revisits}: runs per pose "
                f"{per_pose}, runs as n^{shown(slope(runs, n))}, cells as "
                f"n^{shown(slope(cells, n))} (n¹ is a bounded number of revisits per pose, n² "
                "revisits growing as n)"
            )
        notes.append(
            f"- **{city}**: {story}. Our time follows the answer (cost per row "
            "≈ passes through the γ-ball × log), so judge it against the runs: time grows as "
            f"runs^{shown(slope(one, runs))} on 1 thread (n^{shown(slope(one, n))}); 1.00 is "
            f"a constant time per run. Time per run (1 thread): {per_run}."
        )
    if not rows:
        return [f"(Needs two sizes with n ≥ {FIT_MIN_POSES:,} in one city.)"]
    return [
        "| City | Poses n (fitted) | Runs in n | Cells in n | Time in n, 1 thread | "
        "Time in n, 2 threads | Time in runs, 1 thread | Time in runs, 2 threads | "
        "Time between sizes (1 thread) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|",
        *rows,
        "",
        *notes,
    ]


def autogroup_note() -> str:
    """What the scheduler does to a 2-thread run on a shared machine."""
    try:
        enabled = Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip() == "1"
    except OSError:
        enabled = False
    if not enabled:
        return "Other work on the machine takes cores from either run; compare within a row."
    return (
        "This kernel shares the CPUs equally between sessions, not between threads "
        "(`kernel.sched_autogroup_enabled = 1`), so while other sessions keep the machine busy "
        "a 2-thread run gets about the one core a 1-thread run gets (cores busy near 1, threads "
        "ready near 2, much waiting for a core) and no speed-up: then compare the threads ready "
        "with 2 rather than the speed-up."
    )


def parallelism(results: list[Result]) -> list[str]:
    """1 thread against 2 threads, with how many threads the work kept ready."""
    rows = []
    for result in results:
        one, two = (result.outcomes.get(name) for name in ("ours-1", "ours-2"))
        if not (one and two and one.ok and two.ok) or one.best_s < 0.5:
            continue
        rows.append(
            f"| {result.size.city}, {result.size.label} | {seconds(one.best_s)} s | "
            f"{one.cpu_per_wall:.2f} | {seconds(two.best_s)} s | {two.cpu_per_wall:.2f} | "
            f"{two.threads_ready:.2f} | {two.threads_waiting:.2f} | "
            f"{one.best_s / two.best_s:.2f} |"
        )
    if not rows:
        return ["(No size took 0.5 s or more.)"]
    return [
        "| Scenario | 1 thread | cores busy | 2 threads | cores busy | threads ready | "
        "waiting for a core | speed-up |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
        *rows,
    ]


def targets(results: list[Result]) -> list[str]:
    by_key = {result.size.key: result for result in results}
    goals = [
        ("1km-6h", "216,000 poses, 1 km² city: ≤ 2 s", 2.0, None),
        ("1km-28h", "10⁶ poses, 1 km² city: ≤ 60 s and ≤ 4 GB", 60.0, 4.0),
        ("10km-d-1e7", "10⁷ poses, 10 × 10 km city by district: ≤ 5 min and ≤ 4 GB", 300.0, 4.0),
        ("10km-1e7", "10⁷ poses, 10 × 10 km city roamed: ≤ 5 min and ≤ 4 GB", 300.0, 4.0),
    ]
    rows = []
    for key, text, limit_s, limit_gb in goals:
        result = by_key.get(key)
        if result is None:
            rows.append(f"| {text} | not run | not run | – |")
            continue
        measured, verdicts = [], []
        for name in ("ours-1", "ours-2"):
            outcome = result.outcomes.get(name)
            if outcome is None or not outcome.ok:
                measured.append(outcome.status if outcome else "not run")
                verdicts.append(False)
                continue
            text_cell = (
                f"{seconds(outcome.best_s)} s; peak {megabytes(outcome.peak_mb)} above baseline, "
                f"{megabytes(outcome.absolute_peak_mb)} in all"
            )
            ok = outcome.best_s <= limit_s
            if limit_gb is not None:
                ok = ok and outcome.absolute_peak_mb <= limit_gb * 1024
            measured.append(text_cell)
            verdicts.append(ok)
        verdict = (
            "met (both thread counts)"
            if all(verdicts)
            else "met on 2 threads"
            if verdicts[1]
            else "met on 1 thread"
            if verdicts[0]
            else "**not met**"
        )
        rows.append(f"| {text} | {measured[0]} | {measured[1]} | {verdict} |")
    return [
        "| Target | inexact-loops, 1 thread | inexact-loops, 2 threads | |",
        "|---|---|---|---|",
        *rows,
    ]


def section(results: list[Result], args: argparse.Namespace, loads: tuple[str, str]) -> str:
    command = " ".join(["python", "benches/scale.py", *sys.argv[1:]])
    cities = ["1 km²", DISTRICTS, ROAMING]
    ordered = sorted(results, key=lambda r: (cities.index(r.size.city), r.size.poses))
    lines = [
        "## Scale: from one drive to days of driving",
        "",
        f"Generated by `python benches/scale.py` (this run: `{command}`; it owns the text from "
        "its marker line to the next); do not edit by hand, rerun the script.",
        "",
        *harness.machine_facts(("numpy", "scipy", "scikit-learn", "dbscan")),
        "",
        "Input: `il.urban_drive(duration_s, city_size_m, district_m, seed=0)` (10 Hz; 1 km² "
        "Manhattan grid of 100 m blocks, or a 10 × 10 km one, either worked one 1 km² district "
        "at a time for 2.8 h each, in snake order, so that revisits stay bounded, or roamed at "
        "random), 3-D positions, γ = 40 m, Euclidean metric. Every "
        "repetition of a contender runs in a fresh subprocess after one untimed call on small "
        "input (a 1 min drive, or the first 2,000 detections); **time** is the best of up to "
        f"{args.repeat} repetition{'s' if args.repeat > 1 else ''} (fewer once they add up to "
        f"{args.budget_s:g} s), **memory** "
        "the peak resident set above the baseline after imports, warm-up and input (`VmHWM` "
        "reset through `/proc/self/clear_refs`), the largest over the repetitions. Every "
        f"contender runs under a {args.mem_limit_gb:g} GB address-space cap and a "
        f"{args.timeout_s:.0f} s timeout. Machine load (1 min average) {loads[0]} at the start, "
        f"{loads[1]} at the end, on {os.cpu_count()} CPUs; other work shared the machine (a "
        "2-thread run then gets less than 2 cores: see the cores busy below), so compare "
        "within a row rather than across runs.",
        "",
        "- **inexact-loops**: `find_loops(traj, gamma=40.0, threads=1 or 2, separation=None)`, "
        "`.components`, "
        "`.loop_duration()`: all of S_γ as runs, its exact loop components with their measures, "
        "and τ per pose.",
        "- **cKDTree.query_pairs**: the pairs i < j within γ as an (m, 2) array, nothing more; "
        "its int64 output alone needs 16 bytes a pair.",
        "- **scipy lattice pipeline** (`compare.py`): exact components with every cell of S_γ's "
        "upper half a graph node.",
        "- **dense ndimage.label**: the n × n boolean matrix δ ≤ γ (built by `cdist` in row "
        "blocks) and `scipy.ndimage.label` (4-connected), timed together; for n ≤ "
        f"{DENSE_MAX_POSES:,}.",
        "- **1% + DBSCAN**: the paper's route. 1% of the off-diagonal pairs of S_γ, each "
        f"independently (seed {DETECTION_SEED}, drawn from our exact runs as "
        "`Detections::draw` does), stand in for place-recognition detections; DBSCAN(eps = "
        f"{EPSILON_S:g} s, min_samples = 1) clusters their (t, t′) points, by scikit-learn "
        "(`sklearn.cluster.DBSCAN`, one thread) and by the `dbscan` package. Only the "
        "clustering is timed. Its clusters approximate the loop components (see the counts "
        "below); they are not exact.",
        "",
        "A peer that ran out of memory or time at one size is skipped at every later size with "
        "at least as many poses and cells; so is one whose unavoidable arrays exceed the cap "
        "(query_pairs' output: 16 B a pair; the lattice's keys and pairs: 24 B a cell; the "
        "dense matrix and labels: 5 B a cell), and one whose peak per pair, cell or detection "
        "at its largest finished size extrapolates to more than "
        f"{EXTRAPOLATION_MARGIN:g}× the cap; the table gives the reason. Cells: time (s) · "
        "peak memory above baseline.",
        "",
        "| Scenario | Poses n | " + " | ".join(CONTENDERS.values()) + " |",
        "|---|---:|" + "---:|" * len(CONTENDERS),
    ]
    for result in ordered:
        cells = " | ".join(cell(result.outcomes.get(name), args) for name in CONTENDERS)
        lines.append(
            f"| {result.size.city}, {result.size.label} | {result.size.poses:,} | {cells} |"
        )
    lines += [
        "",
        "What each scenario holds (S_γ's upper half j ≥ i, from inexact-loops), the "
        "approximation the paper's route gives, and the reference checks that passed. Brute "
        f"force (dense) is the reference up to n = {DENSE_MAX_POSES:,}, the lattice pipeline "
        "where it fits; at every size, "
        f"{WINDOWS} random windows of {WINDOW_ROWS} consecutive rows i (seed {WINDOW_SEED}) "
        "are checked against a second, independent method: in each, our runs of row i must "
        "equal the columns j ≥ i of `cKDTree.query_ball_point(x_i, r=γ)` cut into maximal "
        "runs, and every group of 4-adjacent runs of the window (joined by "
        "`csgraph.connected_components`) must lie in one of our components. 2 threads must give "
        "the same runs and component table, byte for byte, as 1 thread; query_pairs the same "
        "pair count. The script fails, and writes nothing, on any difference.",
        "",
        "| Scenario | Cells of S_γ | Runs | Loop components (non-trivial) | 1% detections | "
        "DBSCAN clusters | Checks (all passed) |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    for result in ordered:
        data = result.reference
        if not data:
            lines.append(f"| {result.size.city}, {result.size.label} | – | – | – | – | – | – |")
            continue
        found = [result.outcomes[n].data for n in DBSCAN_PACKAGES if result.outcomes[n].ok]
        clusters = ", ".join(sorted({f"{d['clusters']:,}" for d in found})) or "–"
        lines.append(
            f"| {result.size.city}, {result.size.label} | {data['cells_upper']:,} | "
            f"{data['runs']:,} | {data['components']:,} ({data['nontrivial']:,}) | "
            f"{data.get('detections', 0):,} | {clusters} | {'; '.join(result.checks)} |"
        )
    largest = max(results, key=lambda r: r.size.poses)
    cpu = [
        f"{CONTENDERS[name]} {outcome.cpu_per_wall:.1f}"
        for name, outcome in largest.outcomes.items()
        if outcome.ok and outcome.best_s >= 0.5
    ]
    lines += [
        "",
        f"Cores busy (CPU time / wall time) at the largest size ({largest.size.city}, "
        f"{largest.size.label}), where the time is ≥ 0.5 s: " + (", ".join(cpu) or "–") + ".",
        "",
        "### 1 thread against 2 threads",
        "",
        "Per scenario that takes at least 0.5 s, from the fastest repetition of each. *Cores "
        "busy* is CPU time / wall time: what the run got. *Threads ready* adds, over the "
        "process's threads, the time each spent running or runnable but waiting for a core "
        "(`/proc/self/task/*/schedstat`, sampled every 20 ms), per unit of wall time; "
        "*waiting for a core* is the waiting part alone. A serial phase leaves a thread idle, "
        "which counts in neither, so threads ready is how many cores the work could have "
        "used, whatever the load: about the speed-up it would get with a core per thread. "
        f"{autogroup_note()}",
        "",
        *parallelism(ordered),
        "",
        "### Growth of our time in n and in the answer",
        "",
        "Least-squares slope of log time (or log count) against log n, and of log time against "
        "log runs (the size of the answer), over the scaling sizes "
        f"(n ≥ {FIT_MIN_POSES:,}); the last column gives the slopes between consecutive sizes.",
        "",
        *growth(ordered),
        "",
        "### Targets",
        "",
        "Memory here is the peak resident set of the whole process (`VmHWM`: interpreter, "
        "trajectory and result) besides the peak above the baseline.",
        "",
        *targets(ordered),
    ]
    return "\n".join(lines) + "\n"


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="leave out the 28 h and 10⁷ sizes")
    parser.add_argument(
        "--sizes",
        metavar="KEY,...",
        help="only these sizes: " + ", ".join(SIZE_BY_KEY),
    )
    harness.add_contender_options(
        parser,
        repeat_help="default 3",
        output_help="the report whose <!-- scale --> section to write (default BENCHMARKS.md)",
        budget_s=60.0,
    )
    parser.add_argument("--gamma-m", type=float, default=GAMMA_M, help=argparse.SUPPRESS)
    parser.add_argument("--worker", choices=sorted(CONTENDERS), help=argparse.SUPPRESS)
    parser.add_argument("--size", choices=sorted(SIZE_BY_KEY), help=argparse.SUPPRESS)
    parser.add_argument("--workdir", help=argparse.SUPPRESS)
    parser.add_argument("--skip-check", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.sizes:
        unknown = [key for key in args.sizes.split(",") if key not in SIZE_BY_KEY]
        if unknown:
            parser.error(f"unknown sizes {unknown}; choose from {', '.join(SIZE_BY_KEY)}")
    return args


def main() -> int:
    return harness.run_script(parse_args(), worker, drive)


def drive(args: argparse.Namespace) -> int:
    """Runs the contenders at each size in workers, checks their results against each other and
    writes the section of the report."""
    chosen = args.sizes.split(",") if args.sizes else None
    sizes = [
        size for size in SIZES if (size.key in chosen if chosen else not (args.quick and size.long))
    ]
    load_at_start = harness.load_average()
    build_at_start = harness.build_stamp()
    started = time.perf_counter()
    history = History()
    results = []
    with tempfile.TemporaryDirectory(prefix="inexact-loops-scale-") as workdir:
        args.workdir = workdir
        for size in sizes:
            results.append(run_size(size, args, history))
            print(f"  ({time.perf_counter() - started:.0f} s so far)", file=sys.stderr)
    text = section(results, args, (load_at_start, harness.load_average()))
    print(text)
    problems = [f"{r.size.city}, {r.size.label}: {p}" for r in results for p in r.problems]
    if harness.refused(problems + harness.rebuild_problems(build_at_start), args.output):
        return 1
    # A new section goes right after compare.py's head: both are about the engine against peers.
    harness.write_section(args.output, MARKER_NAME, text, first=True)
    print(
        f"wrote the <!-- {MARKER_NAME} --> section of {args.output} "
        f"({time.perf_counter() - started:.0f} s)",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
