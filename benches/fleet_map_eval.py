#!/usr/bin/env python3
"""Do the samples make better maps of a fleet? The joint and inter-session errors of a
multi-session pose graph against the budget, for every sampler, sampling every component or
only those between sessions.

Usage::

    nice -n 15 python benches/fleet_map_eval.py [--data ../shared/data]
        [--out benches/fleet_map_eval] [--datasets urban,kaist] [--seeds 3]
        [--budgets 10,100,1000] [--report-only] [--no-write] [--output BENCHMARKS.md]

Needs the ``inexact_loops`` wheel with the ``maps`` extra (GTSAM) and matplotlib. A modest grid
(about 10 minutes on 2 busy cores): every run appends its row to ``OUT/rows.csv``, a second
invocation skips the blocks already there, and ``--report-only`` redraws the report:
``OUT/summary.csv``, ``docs/fleet_map_eval.png`` and the section ``<!-- fleet_map_eval -->``
of BENCHMARKS.md (``--no-write`` prints it instead).

Datasets:

- ``urban``: ``il.urban_fleet(vehicles=6, duration_s=600, seed=0)``: six 10-minute drives in
  the 1 km² city of :func:`urban_drive`, their x-y positions headed along the motion, keyframes
  every 10 m (about 2,000 nodes in all); gamma = 20 m.
- ``kaist``: MulRan KAIST 01 and 02 (``mulran_kaist/kaist0{1,2}_localization_poses0{1,2}_
  seq02asmap.txt``: both in the frame of sequence 02's map, no times: 10 Hz), SE(2) in x-y,
  keyframes every 10 m (about 1,160 nodes); gamma = 15 m (LIO-SAM's loop search radius).

Per seed (0..2) each session's odometry is simulated by the default :class:`DriftModel` with
its own seed and starts at the identity of its own frame; the first session is the anchor (its
start known), the others have only a weak prior (1 km, pi rad) at their initial guess, which
the matches between sessions place (:func:`place_sessions`). Candidates come from
``il.sample_fleet`` on the references at each budget, over every component (within and between
sessions) and between sessions only (``between_only``), for sigma_1, sigma_rho, dispersed
sigma_rho, closest-first and sigma_alpha, the revisit separation within sessions (4 gamma of
path); the default :class:`Verifier` verifies them, with no wrong matches and with 10 % of the
candidates returning a wrong match; the default :class:`BackEnd` (GTSAM Levenberg-Marquardt,
Cauchy kernel of width 1) optimises the multi-session graph (``gtsam.Symbol`` keys a, b, ... per
session). Errors (:func:`fleet_errors`): the joint ATE (one alignment of all sessions), the
sessions' own ATEs (RMS over the sessions), and the inter-session error (evo's RPE over the
pose pairs of two sessions within gamma of each other). The odometry alone is the reference
line.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("RAYON_NUM_THREADS", "1")  # the machine is shared: one engine thread

import map_eval_common as common  # noqa: E402
from harness import machine_facts  # noqa: E402

import inexact_loops as il  # noqa: E402
from inexact_loops import evaluate as ev  # noqa: E402

SECTION = "fleet_map_eval"

ROOT = Path(__file__).resolve().parents[1]

KAIST = "mulran_kaist/kaist0{k}_localization_poses0{k}_seq02asmap.txt"

#: name -> (label, gamma, keyframe step m)
DATASETS = {
    "urban": ("urban fleet, 6 × 10 min", 20.0, 10.0),
    "kaist": ("MulRan KAIST 01 + 02", 15.0, 10.0),
}

SAMPLERS = ("one", "rho", "rho-dispersed", "closest-first", "alpha")
OUTLIER_RATES = (0.0, 0.1)
MODES = (False, True)  # between_only


def load(name: str, data: Path) -> dict[str, ev.Poses] | None:
    label, _, step = DATASETS[name]
    if name == "urban":
        sessions = ev.fleet_references(il.urban_fleet(vehicles=6, duration_s=600.0, seed=0))
    else:
        paths = {f"kaist0{k}": data / KAIST.format(k=k) for k in (1, 2)}
        missing = [str(p) for p in paths.values() if not p.exists()]
        if missing:
            print(f"fleet_map_eval: {label}: {missing[0]} is absent, skipped", file=sys.stderr)
            return None
        sessions = {n: ev.Poses.read(p, rate_hz=10.0) for n, p in paths.items()}
    return {n: p.take(p.keyframes(step)) for n, p in sessions.items()}


def run(args: argparse.Namespace) -> None:
    names = args.datasets.split(",")
    sessions = {n: load(n, Path(args.data)) for n in names}
    for n, s in sessions.items():
        if s is not None:
            sizes = ", ".join(f"{k} {len(p)}" for k, p in s.items())
            print(f"fleet_map_eval: {n}: keyframes {sizes}", file=sys.stderr)
    runs = common.Runs(
        args,
        SECTION,
        ev.FleetResults,
        ev.FLEET_COLUMNS,
        lambda r: (r["dataset"], int(r["seed"]), float(r["outlier_rate"])),
    )
    for seed in range(args.seeds):
        for name in names:
            references = sessions[name]
            if references is None:
                continue
            for outlier_rate in OUTLIER_RATES:
                if (name, seed, outlier_rate) in runs.done:
                    continue
                runs.block(
                    ev.evaluate_fleet,
                    references,
                    dataset=name,
                    seed=seed,
                    outlier_rate=outlier_rate,
                    gamma=DATASETS[name][1],
                    samplers=SAMPLERS,
                    between_only=MODES,
                )


# ---------------------------------------------------------------------------------------------
# Tables and figure
# ---------------------------------------------------------------------------------------------


def label(sampler: str, between: bool) -> str:
    if sampler == "odometry":
        return "odometry alone"
    return il.sampler_symbol(sampler) + (" (between sessions only)" if between else "")


def datasets_of(results: ev.FleetResults) -> list[str]:
    return [n for n in DATASETS if any(r["dataset"] == n for r in results.rows)]


def table(
    results: ev.FleetResults, summary: list[dict], outlier_rate: float, budgets: list[int]
) -> list[str]:
    """A row per sampler and mode, a column per dataset and budget: the median joint ATE over
    the seeds [min–max], then the median inter-session error."""
    names = datasets_of(results)
    cells_of = {
        (s["dataset"], s["sampler"], s["between_only"], s["budget"]): s
        for s in summary
        if s["outlier_rate"] == outlier_rate and s["sampler"] != "odometry"
    }
    odometry = {
        n: [r for r in results.rows if r["dataset"] == n and r["sampler"] == "odometry"]
        for n in names
    }
    columns = [(n, b) for n in names for b in budgets]
    header = "| sampler | " + " | ".join(f"{DATASETS[n][0]}, {b}" for n, b in columns) + " |"
    lines = [header, "|---|" + "---|" * len(columns)]
    alone = []
    for n, _ in columns:
        a = np.median([r["ate_m"] for r in odometry[n]])
        i = np.median([r["inter_m"] for r in odometry[n]])
        alone.append(f"{a:.1f} / {i:.1f}")
    lines.append("| odometry alone | " + " | ".join(alone) + " |")
    for sampler in SAMPLERS:
        for between in MODES:
            cells = []
            for n, b in columns:
                s = cells_of.get((n, sampler, between, b))
                cells.append(
                    "–"
                    if s is None
                    else f"{s['ate_median_m']:.2f} [{s['ate_min_m']:.2f}–{s['ate_max_m']:.2f}] / "
                    f"{s['inter_median_m']:.2f}"
                )
            if any(c != "–" for c in cells):
                lines.append(f"| {label(sampler, between)} | " + " | ".join(cells) + " |")
    return lines


def relative(results: ev.FleetResults, budgets: list[int], column: str) -> list[str]:
    """Per sampler and mode, budget and outlier rate: the geometric mean over the datasets of
    its median error (``column``: ate or inter) over the best one's at that budget."""
    summary = [s for s in results.summary() if s["sampler"] != "odometry"]
    rows = [
        (
            label(sampler, between),
            lambda s, k=(sampler, between): (s["sampler"], s["between_only"]) == k,
        )
        for sampler in SAMPLERS
        for between in MODES
    ]
    return common.relative(
        summary, datasets_of(results), budgets, OUTLIER_RATES, f"{column}_median_m", rows
    )


def figure(results: ev.FleetResults, path: Path) -> None:
    """A row per dataset: the joint ATE and the inter-session error, no wrong matches."""
    names = datasets_of(results)
    fig, axes = common.figure_rows(len(names), 3.1, 0.9)
    for row, n in enumerate(names):
        sub = ev.FleetResults([r for r in results.rows if r["dataset"] == n])
        for col, metric in enumerate(("ate", "inter")):
            ev.plot_fleet_error_vs_matches(
                sub,
                ax=axes[row][col],
                metric=metric,  # type: ignore[arg-type]
                select={"outlier_rate": 0.0},
                title=f"{DATASETS[n][0]} (γ = {DATASETS[n][1]:g} m): "
                + ("joint ATE" if metric == "ate" else "inter-session error"),
                legend=False,
            )
    common.save_figure(
        fig,
        axes,
        path,
        "A fleet's map against the matches tried, no wrong matches\n(median over the seeds, "
        "band: middle half; dashed: the budget spent between sessions only)",
        legend=(4, 7.5),
        title_size=9.5,
        rect=(0, 0.08, 1, 0.95),
    )


def section(results: ev.FleetResults, budgets: list[int], command: str) -> str:
    summary = results.summary()
    seeds = sorted({r["seed"] for r in results.rows})
    runs = [r for r in results.rows if r["sampler"] != "odometry"]
    minutes = sum(r["seconds"] for r in results.rows) / 60
    lines = [
        "## Do the samples make better maps? The fleet case",
        "",
        f"Generated by `{command}` (the grid, then the report from "
        "`benches/fleet_map_eval/rows.csv`); do not edit by hand. The method is in the script's "
        "docstring and in the documentation "
        "([Evaluate on your own poses](docs/how-to/evaluate.md)).",
        "",
        *machine_facts(("numpy", "gtsam")),
        f"- {len(runs)} runs over {len(seeds)} seed(s) ({', '.join(map(str, seeds))}); "
        f"{minutes:.1f} min of runs on a 2-core machine shared with other jobs (`nice -n 15`).",
        "- Each run: per session the seed's simulated odometry (`DriftModel()`), starting in its "
        "own frame (only the first session's start is known); candidates from `il.sample_fleet` "
        "on the references at a budget (matches tried, over the whole fleet), over every "
        "component or between sessions only; the default `Verifier` (10 % wrong matches where "
        "said); the default `BackEnd` (GTSAM Levenberg–Marquardt, Cauchy kernel) on the "
        "multi-session graph. Cells: the median joint ATE in metres over the seeds [min–max] / "
        "the median inter-session error (m: evo's RPE over pose pairs of two sessions within γ).",
        "",
    ]
    for outlier_rate in OUTLIER_RATES:
        title = f"{outlier_rate:.0%} wrong matches" if outlier_rate else "No wrong matches"
        lines += [f"**{title}**", "", *table(results, summary, outlier_rate, budgets), ""]
    lines += [
        "**How far from the best**: per sampler, the geometric mean over the datasets of its "
        "median error divided by the best one's at the same budget (1.00 = the best on every "
        "dataset). Joint ATE:",
        "",
        *relative(results, budgets, "ate"),
        "",
        "Inter-session error:",
        "",
        *relative(results, budgets, "inter"),
        "",
        "Per condition and sampler, with the sessions' own ATEs and the matches within and "
        "between sessions: "
        "[benches/fleet_map_eval/summary.csv](benches/fleet_map_eval/summary.csv).",
        "",
        "![A fleet's errors against the number of matches](docs/fleet_map_eval.png)",
    ]
    return "\n".join(lines) + "\n"


def report(args: argparse.Namespace) -> None:
    results = ev.FleetResults(common.read_rows(Path(args.out) / "rows.csv", ev.FleetResults))
    common.report(args, SECTION, results, figure, section)


def main() -> None:
    common.main(
        __doc__, SECTION, list(DATASETS), seeds=3, budgets="10,100,1000", run=run, report=report
    )


if __name__ == "__main__":
    main()
