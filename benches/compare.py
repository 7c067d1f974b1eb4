#!/usr/bin/env python3
"""Side-by-side comparison of inexact-loops with scipy; regenerates ``BENCHMARKS.md``.

Usage::

    python benches/compare.py [--quick] [--repeat N] [--skip-lattice] [--output PATH]

Scenario: the reference urban drive (``il.urban_drive()``: 2.1 h at 10 Hz,
75,600 poses, seed 0) and a 30 min drive (18,000 poses) that every contender finishes; γ = 40 m
on the 3-D positions. Contenders:

1. inexact-loops: ``find_loops`` + ``components`` + ``loop_duration`` (1 and 2 threads);
2. scipy ``cKDTree.query_pairs(r=γ, output_type="ndarray")`` (tree built inside the timing);
3. the scipy lattice pipeline: query_pairs, add the diagonal, 4-neighbour edges between the
   cells of the upper half found with ``np.searchsorted``, ``csgraph.connected_components``.

Every repetition of a contender runs in a fresh subprocess (this script, re-invoked with a
hidden ``--worker`` flag) under an address-space cap and a timeout; repetitions go in rounds,
every contender once per round, so that the ratios see the same machine load. In the
subprocess, one call on a 1 min drive comes first (one-time costs such as lazy imports count
for no one), then the baseline RSS is read, the peak (``VmHWM``) is reset to it through
``/proc/self/clear_refs``, and one timed call on the input runs. Wall time is the best
repetition, memory the largest peak minus baseline. A contender stops repeating once its
repetitions add up to ``--budget-s`` seconds, or at its first failure.

The lattice worker checks, after its measurements, that its components are ours: the same
cells, the same number of components, and a bijection between our component ids and its
labels. The harness exits with status 1 and does not write the report if anything differs.

It owns the text of ``BENCHMARKS.md`` before the first marker line ``<!-- name -->`` and keeps
the sections from there on (other scripts' sections, e.g. ``benches/scale.py``'s); see
``benches/harness.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import harness

REPO = Path(__file__).resolve().parent.parent
GAMMA_M = 40.0
FULL_DURATION_S = None  # the generator's default: 2.1 h
SMALL_DURATION_S = 1800.0
WARM_UP_DURATION_S = 60.0

REFERENCE = "inexact-loops"
CONTENDERS = {
    "ours-1": "inexact-loops (1 thread)",
    "ours-2": "inexact-loops (2 threads)",
    "query-pairs": "scipy cKDTree.query_pairs",
    "lattice": "scipy lattice pipeline",
}
COMPUTES = {
    "ours-1": "S_γ as runs, exact components (areas, holes, extents, closest pairs), τ",
    "ours-2": "the same, rows split over 2 threads",
    "query-pairs": "the list of pairs i < j with δ ≤ γ only (no components)",
    "lattice": "component label of every cell of S_γ's upper half (no measures)",
}


# --------------------------------------------------------------------------------------------
# Worker side: runs one contender in this process and prints one JSON line.
# --------------------------------------------------------------------------------------------


def make_drive(duration_s: float | None):
    import inexact_loops as il

    return il.urban_drive() if duration_s is None else il.urban_drive(duration_s=duration_s)


def ours(traj, gamma_m: float, threads: int):
    import inexact_loops as il

    loops = il.find_loops(traj, gamma=gamma_m, threads=threads, separation=None)
    components = loops.components
    tau = loops.loop_duration()
    return loops, components, tau


def query_pairs(positions, gamma_m: float):
    from scipy.spatial import cKDTree

    tree = cKDTree(positions)
    return tree.query_pairs(r=gamma_m, output_type="ndarray")


def lattice_components(positions, gamma_m: float):
    """Exact components the obvious way: every cell of S_γ's upper half is a graph node.

    Returns (sorted cell keys i * n + j, label per cell, number of components, pairs i < j).
    """
    import numpy as np
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    n = len(positions)
    pairs = query_pairs(positions, gamma_m)
    pair_count = len(pairs)
    diagonal = np.arange(n, dtype=np.int64)
    keys = np.concatenate([pairs[:, 0].astype(np.int64) * n + pairs[:, 1], diagonal * n + diagonal])
    del pairs
    keys.sort()
    cells = len(keys)
    sources, targets = [], []
    # Right neighbour (i, j + 1), key + 1, and lower neighbour (i + 1, j), key + n. Neither can
    # alias a wrong cell: key + 1 of (i, n - 1) is (i + 1, 0) and key + n of (n - 1, j) is past
    # the lattice, and neither is in the upper half.
    for step in (1, n):
        neighbour = keys + step
        where = np.searchsorted(keys, neighbour)
        np.minimum(where, cells - 1, out=where)
        hit = keys[where] == neighbour
        del neighbour
        sources.append(np.flatnonzero(hit))
        targets.append(where[hit])
        del where, hit
    rows = np.concatenate(sources)
    cols = np.concatenate(targets)
    del sources, targets
    graph = coo_array((np.ones(len(rows), dtype=np.float64), (rows, cols)), shape=(cells, cells))
    del rows, cols
    graph = graph.tocsr()
    count, labels = connected_components(graph, directed=False)
    del graph
    return keys, labels, count, pair_count


def check_lattice(traj, gamma_m: float, keys, labels, count: int, pair_count: int) -> dict:
    """Whether the lattice partition equals ours; run after the measurements."""
    import numpy as np

    n = len(traj)
    loops, runs, ours_count = harness.reference_loops(traj, gamma_m)
    ours_pairs = (loops.pair_count - n) // 2
    problems = []
    if pair_count != ours_pairs:
        problems.append(f"pairs i < j: scipy {pair_count}, ours {ours_pairs}")
    if count != ours_count:
        problems.append(f"components: scipy {count}, ours {ours_count}")
    row, start, end, component = (runs[k] for k in ("row", "start", "end", "component"))
    length = end - start + 1
    if int(length.sum()) != len(keys):
        problems.append(f"cells of the upper half: scipy {len(keys)}, ours {int(length.sum())}")
    else:
        first = row * n + start
        order = np.argsort(first, kind="stable")
        first, length, component = first[order], length[order], component[order]
        last = first + length - 1
        where = np.searchsorted(keys, first)
        inside = where + length <= len(keys)
        clipped = np.where(inside, where, 0)
        found = inside & (keys[clipped] == first) & (keys[clipped + length - 1] == last)
        if not found.all():
            bad = int(np.flatnonzero(~found)[0])
            problems.append(f"run {bad} (cells {first[bad]}..={last[bad]}) is not in scipy's set")
        else:
            # Every run is a contiguous block of the sorted keys and the blocks cover them all.
            label_of_run = labels[where]
            if not np.array_equal(np.repeat(label_of_run, length), labels):
                problems.append("one of our runs spans two scipy labels")
            mapping = np.full(ours_count, -1, dtype=np.int64)
            mapping[component] = label_of_run
            if not np.array_equal(mapping[component], label_of_run):
                problems.append("one of our components spans two scipy labels")
            elif len(np.unique(mapping)) != ours_count or (mapping < 0).any():
                problems.append("two of our components share a scipy label")
    return {"components": int(count), "cells": len(keys), "problems": problems}


def worker(args: argparse.Namespace) -> None:
    harness.cap_address_space(args.mem_limit_gb)
    import numpy as np  # noqa: F401  (imported before the baseline, like the contenders' own)
    import scipy.sparse.csgraph  # noqa: F401
    import scipy.spatial  # noqa: F401

    duration_s = None if args.duration_s < 0 else args.duration_s
    warm_up = make_drive(WARM_UP_DURATION_S)
    traj = make_drive(duration_s)
    positions = traj.positions
    if args.worker.startswith("ours"):
        threads = int(args.worker.split("-")[1])

        def run(drive):
            return ours(drive, args.gamma_m, threads)

    elif args.worker == "query-pairs":

        def run(drive):
            return query_pairs(drive.positions if drive is warm_up else positions, args.gamma_m)

    elif args.worker == "lattice":

        def run(drive):
            return lattice_components(
                drive.positions if drive is warm_up else positions, args.gamma_m
            )

    else:
        raise SystemExit(f"unknown worker {args.worker!r}")

    # One call on a 1 min drive first, so that one-time costs (lazy imports, first use of the
    # numpy C API, thread pools) count in no contender's time or memory.
    run(warm_up)
    result, measured = harness.measure(lambda: run(traj))
    report: dict = {"status": "ok", "poses": len(traj)}
    report.update((key, measured[key]) for key in ("time_s", "peak_above_baseline_mb"))
    report.update((key, measured[key]) for key in ("baseline_mb", "peak_reset"))
    if args.worker.startswith("ours"):
        loops, components, _ = result
        report.update(harness.result_facts(loops, components, len(traj)))
    elif args.worker == "query-pairs":
        report.update(pairs_upper=len(result))
    else:
        keys, labels, count, pair_count = result
        result = None
        report.update(pairs_upper=pair_count)
        if not args.skip_check:
            report.update(check=check_lattice(traj, args.gamma_m, keys, labels, count, pair_count))
    print(json.dumps(report), flush=True)


# --------------------------------------------------------------------------------------------
# Driver side: runs the workers, checks the results against each other, writes the report.
# --------------------------------------------------------------------------------------------


@dataclass
class Outcome:
    contender: str
    status: str
    times_s: list[float] = field(default_factory=list)
    peak_mb: float | None = None
    data: dict = field(default_factory=dict)
    match: str = "n/a"

    @property
    def best_s(self) -> float | None:
        return min(self.times_s) if self.status == "ok" and self.times_s else None


def run_worker(
    contender: str, duration_s: float | None, args: argparse.Namespace, *, first: bool
) -> Outcome:
    """One repetition of `contender` in a fresh subprocess."""
    options = [
        "--worker",
        contender,
        "--duration-s",
        str(-1.0 if duration_s is None else duration_s),
    ]
    options += ["--gamma-m", str(args.gamma_m), *([] if first else ["--skip-check"])]
    status, report, stderr = harness.run_worker(__file__, CONTENDERS[contender], options, args)
    if status != "ok":
        if status.startswith("failed"):
            sys.stderr.write("failed\n" + stderr)
        else:
            print(status, file=sys.stderr)
        return Outcome(contender, status)
    outcome = Outcome(contender, "ok", [report["time_s"]], report["peak_above_baseline_mb"], report)
    print(f"{report['time_s']:.3f} s, {outcome.peak_mb:.0f} MB", file=sys.stderr)
    return outcome


def run_scenario(scenario: Scenario, contenders: list[str], args: argparse.Namespace) -> None:
    """Repetitions in rounds (every contender once per round), so that ratios see the same load.

    A contender stops after `--budget-s` seconds of timed runs or at its first failure; time is
    the best repetition, memory the largest peak.
    """
    outcomes = scenario.outcomes
    for round_index in range(args.repeat):
        print(f"{scenario.title}, round {round_index + 1}/{args.repeat}:", file=sys.stderr)
        for name in contenders:
            done = outcomes.get(name)
            if done is not None and (done.status != "ok" or sum(done.times_s) >= args.budget_s):
                continue
            new = run_worker(name, scenario.duration_s, args, first=done is None)
            if done is None or new.status != "ok":
                outcomes[name] = new
            else:
                done.times_s += new.times_s
                done.peak_mb = max(done.peak_mb, new.peak_mb)


@dataclass
class Scenario:
    title: str
    duration_s: float | None
    outcomes: dict[str, Outcome] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)


def check(scenario: Scenario) -> None:
    """Compares every contender with inexact-loops (1 thread); fills `match` and `problems`."""
    reference = scenario.outcomes["ours-1"]
    if reference.status != "ok":
        scenario.problems.append(f"inexact-loops (1 thread): {reference.status}")
        return
    reference.match = "reference"
    for name, outcome in scenario.outcomes.items():
        if name == "ours-1" or outcome.status != "ok":
            continue
        data = outcome.data
        if data["pairs_upper"] != reference.data["pairs_upper"]:
            scenario.problems.append(
                f"{CONTENDERS[name]}: {data['pairs_upper']} pairs i < j, "
                f"inexact-loops {reference.data['pairs_upper']}"
            )
            outcome.match = "**NO**: pair count differs"
        elif name == "ours-2":
            same = data["digest"] == reference.data["digest"]
            outcome.match = "yes (identical runs and table)" if same else "**NO**"
            if not same:
                scenario.problems.append("2 threads: runs or component table differ from 1 thread")
        elif name == "query-pairs":
            outcome.match = "n/a (pair count matches)"
        elif name == "lattice":
            problems = data["check"]["problems"]
            scenario.problems += [f"{CONTENDERS[name]}: {problem}" for problem in problems]
            outcome.match = (
                "**NO**: " + "; ".join(problems)
                if problems
                else (
                    f"yes ({data['check']['components']} components, same cells, bijective labels)"
                )
            )


def format_row(name: str, outcome: Outcome, reference_s: float | None) -> str:
    best = outcome.best_s
    if best is None:
        time_cell, reps, ratio, memory = outcome.status, "–", "–", "–"
    else:
        time_cell = f"{best:.3f}" if best < 10 else f"{best:.1f}"
        reps = str(len(outcome.times_s))
        ratio = (
            "–"
            if reference_s is None
            else f"{best / reference_s:.2f}×"
            if (best / reference_s < 10)
            else f"{best / reference_s:.0f}×"
        )
        memory = f"{outcome.peak_mb:.0f}" if outcome.peak_mb >= 10 else f"{outcome.peak_mb:.1f}"
    return (
        f"| {CONTENDERS[name]} | {COMPUTES[name]} | {time_cell} | {reps} | {ratio} | "
        f"{memory} | {outcome.match} |"
    )


def scenario_section(scenario: Scenario) -> list[str]:
    reference = scenario.outcomes["ours-1"]
    lines = [f"## {scenario.title}", ""]
    if reference.status == "ok":
        data = reference.data
        lines += [
            f"{data['poses']:,} poses, γ = {GAMMA_M:g} m: S_γ has {data['cells_upper']:,} cells in "
            f"the upper half j ≥ i ({data['pairs_upper']:,} pairs i < j) in {data['runs']:,} "
            f"runs, and {data['components']} loop components ({data['nontrivial']} non-trivial).",
            "",
        ]
    lines += [
        "| Contender | Computes | Wall time (s) | Reps | Time vs inexact-loops (1 thread) | "
        "Peak RSS above baseline (MB) | Components match |",
        "|---|---|---:|---:|---:|---:|---|",
    ]
    lines += [
        format_row(name, outcome, reference.best_s) for name, outcome in scenario.outcomes.items()
    ]
    return [*lines, ""]


def targets_section(scenario: Scenario) -> list[str]:
    ours1 = scenario.outcomes["ours-1"]
    if ours1.best_s is None:
        return []

    def verdict(ok: bool) -> str:
        return "met" if ok else "**not met**"

    rows = [
        f"| ≤ 0.3 s on one core | {ours1.best_s:.3f} s | {verdict(ours1.best_s <= 0.3)} |",
        f"| ≤ 50 MB above baseline | {ours1.peak_mb:.1f} MB | {verdict(ours1.peak_mb <= 50)} |",
    ]
    for name, factor in (("query-pairs", 5), ("lattice", 50)):
        outcome = scenario.outcomes.get(name)
        if outcome is None:
            continue
        if outcome.best_s is None:
            rows.append(
                f"| ≥ {factor}× faster than {CONTENDERS[name]} | {outcome.status} | "
                "met (the peer did not finish) |"
            )
        else:
            speedup = outcome.best_s / ours1.best_s
            rows.append(
                f"| ≥ {factor}× faster than {CONTENDERS[name]} | {speedup:.1f}× | "
                f"{verdict(speedup >= factor)} |"
            )
    return [
        "## Targets (reference 2.1 h drive, inexact-loops on 1 thread)",
        "",
        "| Target | Measured | |",
        "|---|---:|---|",
        *rows,
        "",
    ]


def report(scenarios: list[Scenario], args: argparse.Namespace, loads: tuple[str, str]) -> str:
    lines = [
        "# Benchmarks",
        "",
        "Generated by `python benches/compare.py` "
        f"(this run: `{' '.join(['python', 'benches/compare.py', *sys.argv[1:]])}`); "
        "do not edit by hand, rerun the script.",
        "",
        *harness.machine_facts(),
        "",
        "## Method",
        "",
        "Input: the seeded urban drive (`il.urban_drive()`, seed 0; 1 km² "
        "Manhattan grid, 10 Hz), 3-D positions, γ = 40 m, Euclidean metric. Every repetition "
        "of a contender runs in a fresh subprocess, after one untimed call on a 1 min drive "
        "(so that one-time costs such as lazy imports count for no one). Repetitions go in "
        "rounds, every contender once per round, so that all see the same machine load. "
        f"**Wall time** is the best of up to {args.repeat} "
        f"repetition{'s' if args.repeat > 1 else ''} (*Reps*; a contender stops once its "
        f"repetitions add up to {args.budget_s:g} s). **Ratios** are measured side by side in "
        "the same run, which is what to trust on a noisy machine; the absolute times are not. "
        "**Memory** is the peak resident set (`VmHWM`) minus the resident set (`VmRSS`) after "
        "the imports, the warm-up call and the input trajectory, with the peak reset at that "
        "baseline (`/proc/self/clear_refs`); the largest over the repetitions. The load average "
        f"(1 min) was {loads[0]} at the start and {loads[1]} at the end of the run, on "
        f"{os.cpu_count()} CPUs. "
        f"All contenders run under a {args.mem_limit_gb:g} GB address-space cap and a "
        f"{args.timeout_s:.0f} s timeout.",
        "",
        "What each contender computes:",
        "",
        "- **inexact-loops**: `il.find_loops(traj, gamma=40.0, threads=1, separation=None)`, then "
        "`loops.components` and `loops.loop_duration()`: the whole sublevel set S_γ as runs by "
        "arc-length skipping, its exact 4-connected loop components by "
        "union-find over runs with area, pairs, holes, extents and closest pair each, and the "
        "loop duration τ of every pose. The 2-thread row splits the rows over two threads; the "
        "harness checks that its runs and component table are identical.",
        "- **scipy cKDTree.query_pairs**: builds a KD-tree and lists every pair i < j with "
        "‖x_i − x_j‖ ≤ γ as an (m, 2) array. This is only the input of a component analysis: it "
        "neither groups the pairs nor measures anything. The harness checks that its pair count "
        "equals ours, `(loops.pair_count − n) / 2`.",
        "- **scipy lattice pipeline**: the obvious exact way to get components. query_pairs, "
        "plus the diagonal, gives every cell (i, j), i ≤ j, of S_γ; cells are encoded as int64 "
        "keys i·n + j and sorted; the 4-neighbours (i, j + 1) and (i + 1, j) are found with "
        "`np.searchsorted`; `scipy.sparse.csgraph.connected_components` labels the graph. It "
        "materialises every cell, hence its memory. The harness checks (outside the measurement) "
        "that its cells are our runs' cells, that the component counts agree and that every one "
        "of our runs lies in one scipy label, with our component ids and its labels in bijection.",
        "",
    ]
    for scenario in scenarios:
        lines += scenario_section(scenario)
    reference = next((s for s in scenarios if s.duration_s is None), None)
    if reference is not None:
        lines += targets_section(reference)
    return "\n".join(lines).rstrip() + "\n"


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick", action="store_true", help="only the 30 min drive, one repetition (a smoke test)"
    )
    harness.add_contender_options(
        parser,
        repeat_help="repetitions per contender; the best counts (default 3)",
        output_help="where to write the report (default: BENCHMARKS.md at the repo root)",
        budget_s=120.0,
    )
    parser.add_argument(
        "--skip-lattice",
        action="store_true",
        help="leave out the scipy lattice pipeline (slow, several GB)",
    )
    parser.add_argument("--gamma-m", type=float, default=GAMMA_M, help=argparse.SUPPRESS)
    parser.add_argument("--worker", choices=sorted(CONTENDERS), help=argparse.SUPPRESS)
    parser.add_argument("--duration-s", type=float, default=-1.0, help=argparse.SUPPRESS)
    parser.add_argument("--skip-check", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.quick and "--repeat" not in sys.argv:
        args.repeat = 1
    return args


def main() -> int:
    return harness.run_script(parse_args(), worker, drive)


def drive(args: argparse.Namespace) -> int:
    """Runs the contenders on each scenario in workers, checks their results against each other and
    writes the head of the report."""
    load_at_start = harness.load_average()
    build_at_start = harness.build_stamp()
    scenarios = (
        [] if args.quick else [Scenario("Urban drive, 2.1 h (reference scenario)", FULL_DURATION_S)]
    )
    scenarios.append(Scenario("Urban drive, 30 min", SMALL_DURATION_S))
    contenders = [name for name in CONTENDERS if not (args.skip_lattice and name == "lattice")]
    for scenario in scenarios:
        run_scenario(scenario, contenders, args)
        check(scenario)
    text = report(scenarios, args, (load_at_start, harness.load_average()))
    print(text)
    problems = [f"{s.title}: {problem}" for s in scenarios for problem in s.problems]
    if harness.refused(problems + harness.rebuild_problems(build_at_start), args.output):
        return 1
    harness.write_head(args.output, text)
    print(f"wrote {args.output} (the text before its first <!-- ... --> marker)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
