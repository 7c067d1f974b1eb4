#!/usr/bin/env python3
"""Do the samples make better maps? ATE against the budget for every sampler and baseline, on
the 2.1 h urban drive, KITTI 00, 05, 08 and MulRan KAIST 01.

Usage::

    nice -n 15 python benches/map_eval.py [--data ../shared/data] [--out benches/map_eval]
        [--datasets urban,kitti00,kitti05,kitti08,kaist01] [--seeds 5]
        [--budgets 100,1000,10000] [--report-only] [--no-write] [--output BENCHMARKS.md]

Needs the ``inexact_loops`` wheel with the ``maps`` extra (GTSAM) and matplotlib. The full grid
is this one command; every run appends its row to ``OUT/rows.csv`` as it finishes, and a second
invocation skips the blocks already there, so an interrupted run resumes where it stopped.
``--report-only`` redraws the report from ``rows.csv``: ``OUT/tables.md`` (every condition,
median ATE and spread over the seeds), ``OUT/summary.csv`` (per condition: ATE, RPE, matches),
``docs/map_eval.png``, and the section ``<!-- map_eval -->`` of BENCHMARKS.md (``--no-write``
prints it instead).

Datasets (``../shared/data/README.md`` says where each file comes from):

- ``urban``: the built-in 2.1 h urban drive (``il.urban_drive()``, seed 0, 75,600 poses at
  10 Hz), its x-y positions headed along the motion (:meth:`Poses.from_positions`), keyframes
  every 10 m (about 4,300 nodes); gamma = 40 m, the paper's.
- ``kitti00``, ``kitti05``, ``kitti08``: KITTI odometry ground truth, SE(2) in the ground plane
  x-z (``Poses.read(path, axes=(0, 2))``), keyframes every 2 m; gamma = 15 m (LIO-SAM's loop
  search radius).
- ``kaist01``: MulRan KAIST 01 (``mulran_kaist/kaist01_localization_poses01_seq02asmap.txt``,
  no times: 10 Hz), SE(2) in x-y, keyframes every 2 m; gamma = 15 m.

Each dataset's reference is its keyframed ground truth. Per seed (0..4) the odometry is
simulated by the default :class:`DriftModel` (random walk of 2 cm and 1 mrad per sqrt(m), a
heading bias of 2e-5 rad/m); the candidates come from each sampler at each budget; the default
:class:`Verifier` (success 0.95 * 2^-(d/20 m)^2, noise 5 cm + 0.5 % of d and 2 mrad + 0.2 mrad/m)
verifies them, with no wrong matches and with 10 % of the candidates returning a wrong match;
the default :class:`BackEnd` (GTSAM Levenberg-Marquardt, Cauchy kernel of width 1) optimises the
graph; ATE is evo's APE (translation, SE(2) alignment), RPE evo's RPE over 100 m of path.

The grid, per dataset and seed: candidates chosen on the reference and on the odometry's
estimate (gamma inflated 2x); with the revisit separation (4 gamma of path) and without it (the
paper's S_gamma); sigma_1, sigma_rho, dispersed sigma_rho, closest-first and sigma_alpha from
the exact components, sigma_alpha from detections (1 % of S_gamma, epsilon-graph clusters at
30 s: the paper's experiment), and the LIO-SAM, hdl_graph_slam, Cartographer and time-gap
rules (LIO-SAM's and hdl_graph_slam's do not depend on the separation and run once); budgets
10^2, 10^3, 10^4. The odometry alone is the reference line.
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

SECTION = "map_eval"

ROOT = Path(__file__).resolve().parents[1]

#: name -> (label, loader(data) -> Poses or None, gamma, keyframe step m)
DATASETS = {
    "urban": ("2.1 h urban drive", None, 40.0, 10.0),
    "kitti00": ("KITTI 00", ("kitti_odometry/00.txt", {"axes": (0, 2)}), 15.0, 2.0),
    "kitti05": ("KITTI 05", ("kitti_odometry/05.txt", {"axes": (0, 2)}), 15.0, 2.0),
    "kitti08": ("KITTI 08", ("kitti_odometry/08.txt", {"axes": (0, 2)}), 15.0, 2.0),
    "kaist01": (
        "MulRan KAIST 01",
        ("mulran_kaist/kaist01_localization_poses01_seq02asmap.txt", {"rate_hz": 10.0}),
        15.0,
        2.0,
    ),
}

OUTLIER_RATES = (0.0, 0.1)
ON = ("reference", "estimate")


def load(name: str, data: Path) -> ev.Poses | None:
    label, source, gamma, step = DATASETS[name]
    if source is None:
        drive = il.urban_drive()
        poses = ev.Poses.from_positions(drive.timestamps, drive.positions[:, :2])
    else:
        path = data / source[0]
        if not path.exists():
            print(f"map_eval: {label}: {path} is absent, skipped", file=sys.stderr)
            return None
        poses = ev.Poses.read(path, **source[1])
    return poses.take(poses.keyframes(step))


def block_key(row: dict) -> tuple:
    return (row["dataset"], int(row["seed"]), float(row["outlier_rate"]), row["on"])


def run(args: argparse.Namespace) -> None:
    names = args.datasets.split(",")
    poses = {n: load(n, Path(args.data)) for n in names}
    for n, p in poses.items():
        if p is not None:
            print(f"map_eval: {n}: {len(p)} keyframes", file=sys.stderr)
    runs = common.Runs(args, SECTION, ev.Results, ev.COLUMNS, block_key)
    # Candidates on the reference first (every dataset and seed), then on the estimate: an
    # interrupted run has whole conditions rather than a few seeds of everything.
    for on in ON:
        for seed in range(args.seeds):
            for name in names:
                reference = poses[name]
                if reference is None:
                    continue
                for outlier_rate in OUTLIER_RATES:
                    if (name, seed, outlier_rate, on) in runs.done:
                        continue
                    runs.block(
                        ev.evaluate,
                        reference,
                        dataset=name,
                        seed=seed,
                        outlier_rate=outlier_rate,
                        what=f" on {on}",
                        gamma=DATASETS[name][2],
                        samplers=ev.SAMPLERS + ev.BASELINES,
                        separations=(True, False),
                        sources=("exact", "detections"),
                        detection_samplers=("alpha",),
                        on=(on,),
                    )


# ---------------------------------------------------------------------------------------------
# Tables and figure
# ---------------------------------------------------------------------------------------------

ORDER = ev.SAMPLERS + ev.BASELINES


def label(sampler: str, source: str) -> str:
    text = il.sampler_symbol(sampler) if sampler != "odometry" else "odometry alone"
    return text + (" (detections)" if source == "detections" else "")


def fmt(s: dict) -> str:
    return f"{s['ate_median_m']:.2f} [{s['ate_min_m']:.2f}–{s['ate_max_m']:.2f}]"


def condition_title(on: str, separation: bool, outlier_rate: float) -> str:
    return (
        f"candidates on the {on}"
        + (" (γ × 2)" if on == "estimate" else "")
        + (", revisits only (separation 4γ)" if separation else ", S_γ (no separation)")
        + (f", {outlier_rate:.0%} wrong matches" if outlier_rate else ", no wrong matches")
    )


def upper_first(text: str) -> str:
    return text[:1].upper() + text[1:]


def datasets_of(results: ev.Results) -> list[str]:
    return [n for n in DATASETS if any(r["dataset"] == n for r in results.rows)]


def table(
    results: ev.Results,
    summary: list[dict],
    condition: tuple[str, bool, float],
    budgets: list[int],
    *,
    spread: bool,
) -> list[str]:
    """One condition: a row per sampler and budget, a column per dataset."""
    on, separation, outlier_rate = condition
    names = datasets_of(results)
    odometry = {
        n: np.median(
            [r["ate_m"] for r in results.rows if r["dataset"] == n and r["sampler"] == "odometry"]
        )
        for n in names
    }
    cells_of = {
        (s["dataset"], s["sampler"], s["source"], s["budget"]): s
        for s in summary
        if (s["on"], s["separation"], s["outlier_rate"]) == condition
    }
    keys = sorted(
        {(k[1], k[2]) for k in cells_of},
        key=lambda k: (ORDER.index(k[0]), k[1] != "exact"),
    )
    body = ["| odometry alone | – | " + " | ".join(f"{odometry[n]:.2f}" for n in names) + " |"]
    for sampler, source in keys:
        for budget in budgets:
            cells = []
            for n in names:
                s = cells_of.get((n, sampler, source, budget))
                cells.append("–" if s is None else fmt(s) if spread else f"{s['ate_median_m']:.2f}")
            if any(c != "–" for c in cells):
                body.append(f"| {label(sampler, source)} | {budget} | " + " | ".join(cells) + " |")
    if len(body) == 1:
        return []
    header = "| sampler | budget | " + " | ".join(DATASETS[n][0] for n in names) + " |"
    return [header, "|---|---|" + "---|" * len(names), *body]


CONDITIONS = [(on, sep, out) for on in ON for sep in (True, False) for out in OUTLIER_RATES]


def tables(results: ev.Results, budgets: list[int]) -> str:
    """Every condition, median ATE with its spread over the seeds."""
    summary = results.summary()
    seeds = sorted({r["seed"] for r in results.rows})
    lines = [
        f"Median ATE (m) over {len(seeds)} seed(s) [min–max]; a row per sampler and budget "
        "(matches tried), a column per dataset."
    ]
    for condition in CONDITIONS:
        rows = table(results, summary, condition, budgets, spread=True)
        if rows:
            lines += ["", f"**{upper_first(condition_title(*condition))}**", "", *rows]
    return "\n".join(lines) + "\n"


def relative(results: ev.Results, budgets: list[int], on: str, separation: bool) -> list[str]:
    """Per sampler, budget and outlier rate: the geometric mean over the datasets of its median
    ATE over the best sampler's at that budget (1.00: the best everywhere)."""
    summary = [
        s
        for s in results.summary()
        if s["sampler"] != "odometry" and s["on"] == on and s["separation"] == separation
    ]
    keys = sorted(
        {(s["sampler"], s["source"]) for s in summary},
        key=lambda k: (ORDER.index(k[0]), k[1] != "exact"),
    )
    rows = [(label(*k), lambda s, k=k: (s["sampler"], s["source"]) == k) for k in keys]
    return common.relative(
        summary, datasets_of(results), budgets, OUTLIER_RATES, "ate_median_m", rows
    )


def winners(results: ev.Results, budgets: list[int]) -> list[str]:
    """Per condition and budget: the sampler with the lowest median ATE on each dataset."""
    summary = [s for s in results.summary() if s["sampler"] != "odometry"]
    names = datasets_of(results)
    lines = ["| condition | budget | " + " | ".join(DATASETS[n][0] for n in names) + " |"]
    lines.append("|---|---|" + "---|" * len(names))
    for condition in CONDITIONS:
        for budget in budgets:
            cells = []
            for n in names:
                pool = [
                    s
                    for s in summary
                    if s["dataset"] == n
                    and (s["on"], s["separation"], s["outlier_rate"]) == condition
                    and s["budget"] == budget
                ]
                if not pool:
                    cells.append("–")
                    continue
                top = min(pool, key=lambda s: s["ate_median_m"])
                cells.append(f"{label(top['sampler'], top['source'])} {top['ate_median_m']:.2f}")
            if any(c != "–" for c in cells):
                lines.append(
                    f"| {condition_title(*condition)} | {budget} | " + " | ".join(cells) + " |"
                )
    return lines


def figure(results: ev.Results, path: Path) -> None:
    """A row per dataset; candidates on the reference, revisits only; no and 10 % wrong
    matches. Cartographer and time gap are left out: with the separation they draw σ_α's
    candidates (the tables have them)."""
    names = datasets_of(results)
    shown = ev.Results(
        [r for r in results.rows if r["sampler"] not in ("cartographer", "time-gap")]
    )
    fig, axes = common.figure_rows(len(names), 2.9, 0.8)
    for row, n in enumerate(names):
        for col, outlier_rate in enumerate(OUTLIER_RATES):
            sub = ev.Results([r for r in shown.rows if r["dataset"] == n])
            ev.plot_error_vs_matches(
                sub,
                ax=axes[row][col],
                select={"separation": True, "on": "reference", "outlier_rate": outlier_rate},
                title=f"{DATASETS[n][0]} (γ = {DATASETS[n][2]:g} m), "
                + (f"{outlier_rate:.0%} wrong matches" if outlier_rate else "no wrong matches"),
                legend=False,
            )
    common.save_figure(
        fig,
        axes,
        path,
        "ATE against the matches tried: candidates on the reference, revisits only "
        "(median over the seeds, band: middle half)",
        legend=(5, 8),
        title_size=10,
        rect=(0, 0.05, 1, 0.98),
    )


def section(results: ev.Results, budgets: list[int], command: str) -> str:
    """The BENCHMARKS.md section: settings, the main tables, the comparisons, the figure."""
    summary = results.summary()
    seeds = sorted({r["seed"] for r in results.rows})
    names = datasets_of(results)
    runs = [r for r in results.rows if r["sampler"] != "odometry"]
    hours = sum(r["seconds"] for r in results.rows) / 3600
    nodes = ", ".join(f"{DATASETS[n][0]} γ = {DATASETS[n][2]:g} m" for n in names)
    lines = [
        "## Do the samples make better maps?",
        "",
        f"Generated by `{command}` (the grid, then the report from "
        "`benches/map_eval/rows.csv`); do not edit by hand. The method is in the script's "
        "docstring and in the documentation "
        "([Evaluate on your own poses](docs/how-to/evaluate.md)).",
        "",
        *machine_facts(("numpy", "gtsam", "evo")),
        f"- {len(runs)} runs over {len(seeds)} seed(s) ({', '.join(map(str, seeds))}); "
        f"{hours:.1f} h of runs on a 2-core machine shared with other jobs (`nice -n 15`); "
        f"{nodes}.",
        "- Each run: the seed's simulated odometry (`DriftModel()`), a sampler's candidates at a "
        "budget (matches tried), the default `Verifier` (10 % wrong matches where said), the "
        "default `BackEnd` (GTSAM Levenberg–Marquardt, Cauchy kernel); ATE as `evo_ape -a` "
        "(SE(2) alignment). Cells: the median ATE in metres over the seeds, [min–max].",
        "- With the separation (4γ of path: 160 m on the drive, 60 m on KITTI and MulRan) "
        "nearly every pair is farther apart in time than the Cartographer (10 s) and time-gap "
        "(30 s) rules ask, so they keep (nearly) every pair and draw σ_α's candidates: their "
        "rows repeat σ_α's, or nearly. LIO-SAM and hdl_graph_slam propose fewer pairs than the "
        "larger budgets (one per keyframe, or per stretch of travel), and σ_α from detections "
        "draws from 1 % of S_γ's pairs: fewer than 10³ on the keyframed drives; their rows "
        "stop growing where the candidates run out (`summary.csv` has the counts).",
        "",
    ]
    for condition in [("reference", True, 0.0), ("reference", True, 0.1)]:
        lines += [f"**{upper_first(condition_title(*condition))}**", ""]
        lines += table(results, summary, condition, budgets, spread=True) + [""]
    lines += [
        "**How far from the best**: per sampler, the geometric mean over the datasets of its "
        "median ATE divided by the best sampler's at the same budget (1.00 = the best on every "
        "dataset). Candidates on the reference, revisits only:",
        "",
        *relative(results, budgets, "reference", True),
        "",
    ]
    if any(r["on"] == "estimate" for r in runs):
        lines += [
            "The same, candidates chosen on the odometry's own estimate (γ × 2: no ground truth):",
            "",
            *relative(results, budgets, "estimate", True),
            "",
        ]
    if any(not r["separation"] for r in runs):
        lines += [
            "The same on the paper's S_γ (no separation), candidates on the reference:",
            "",
            *relative(results, budgets, "reference", False),
            "",
        ]
    lines += [
        "**The best sampler** per condition, budget and dataset (its median ATE, m):",
        "",
        *winners(results, budgets),
        "",
        "Every condition with its spread: "
        "[benches/map_eval/tables.md](benches/map_eval/tables.md); per condition and sampler, "
        "with RPE over 100 m and the matches: "
        "[benches/map_eval/summary.csv](benches/map_eval/summary.csv).",
        "",
        "![ATE against the number of matches](docs/map_eval.png)",
    ]
    return "\n".join(lines) + "\n"


def report(args: argparse.Namespace) -> None:
    out = Path(args.out)
    results = ev.Results(common.read_rows(out / "rows.csv", ev.Results))
    if results.rows:
        budgets = sorted({r["budget"] for r in results.rows if r["budget"]})
        (out / "tables.md").write_text(tables(results, budgets))
    common.report(args, SECTION, results, figure, section)


def main() -> None:
    common.main(
        __doc__, SECTION, list(DATASETS), seeds=5, budgets="100,1000,10000", run=run, report=report
    )


if __name__ == "__main__":
    main()
