#!/usr/bin/env python3
"""Do the samples make better maps? ATE against the budget for every sampler and baseline, on
the 2.1 h urban drive, KITTI 00, 05, 08 and MulRan KAIST 01 (issue 20).

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
import csv
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("RAYON_NUM_THREADS", "1")  # the machine is shared: one engine thread

from harness import machine_facts, write_section  # noqa: E402

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


def block_keys(rows: list[dict]) -> set[tuple]:
    return {(r["dataset"], int(r["seed"]), float(r["outlier_rate"]), r["on"]) for r in rows}


def read_rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    return ev.Results.from_csv(path).rows


def run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows_path = out / "rows.csv"
    rows = read_rows(rows_path)
    done = block_keys(rows)
    odometry_done = {(r["dataset"], int(r["seed"])) for r in rows if r["sampler"] == "odometry"}
    new_file = not rows_path.exists()
    f = open(rows_path, "a", newline="")  # noqa: SIM115 - appended row by row, closed at the end
    writer = csv.DictWriter(f, fieldnames=list(ev.COLUMNS))
    if new_file:
        writer.writeheader()
    budgets = [int(b) for b in args.budgets.split(",")]
    names = args.datasets.split(",")
    poses = {n: load(n, Path(args.data)) for n in names}
    for n, p in poses.items():
        if p is not None:
            print(f"map_eval: {n}: {len(p)} keyframes", file=sys.stderr)
    started = time.perf_counter()

    def write(row: dict) -> None:
        writer.writerow({c: row[c] for c in ev.COLUMNS})
        f.flush()

    # Candidates on the reference first (every dataset and seed), then on the estimate: an
    # interrupted run has whole conditions rather than a few seeds of everything.
    for on in ON:
        for seed in range(args.seeds):
            for name in names:
                reference = poses[name]
                if reference is None:
                    continue
                gamma = DATASETS[name][2]
                for outlier_rate in OUTLIER_RATES:
                    if (name, seed, outlier_rate, on) in done:
                        continue
                    block_start = time.perf_counter()
                    results = ev.evaluate(
                        reference,
                        gamma=gamma,
                        samplers=ev.SAMPLERS + ev.BASELINES,
                        budgets=budgets,
                        seeds=[seed],
                        separations=(True, False),
                        sources=("exact", "detections"),
                        detection_samplers=("alpha",),
                        on=(on,),
                        outlier_rates=(outlier_rate,),
                        dataset=name,
                        include_odometry=(name, seed) not in odometry_done,
                        progress=write,
                    )
                    odometry_done.add((name, seed))
                    print(
                        f"map_eval: {name} seed {seed} outliers {outlier_rate} on {on}: "
                        f"{len(results.rows)} runs in {time.perf_counter() - block_start:.0f} s "
                        f"({(time.perf_counter() - started) / 60:.1f} min in all)",
                        file=sys.stderr,
                    )
    f.close()


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
    names = datasets_of(results)
    keys = sorted(
        {(s["sampler"], s["source"]) for s in summary},
        key=lambda k: (ORDER.index(k[0]), k[1] != "exact"),
    )
    columns = [(out, b) for out in OUTLIER_RATES for b in budgets]
    best = {
        (n, out, b): min(
            (
                s["ate_median_m"]
                for s in summary
                if (s["dataset"], s["outlier_rate"], s["budget"]) == (n, out, b)
            ),
            default=None,
        )
        for n in names
        for out, b in columns
    }
    header = "| sampler | " + " | ".join(f"{b} ({out:.0%} wrong)" for out, b in columns) + " |"
    lines = [header, "|---|" + "---:|" * len(columns)]
    for sampler, source in keys:
        cells = []
        for out, b in columns:
            ratios = [
                s["ate_median_m"] / best[(s["dataset"], out, b)]
                for s in summary
                if (s["sampler"], s["source"], s["outlier_rate"], s["budget"])
                == (sampler, source, out, b)
                and best[(s["dataset"], out, b)]
            ]
            cells.append(
                f"{math.exp(np.mean(np.log(ratios))):.2f}" if len(ratios) == len(names) else "–"
            )
        lines.append(f"| {label(sampler, source)} | " + " | ".join(cells) + " |")
    return lines


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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = datasets_of(results)
    shown = ev.Results(
        [r for r in results.rows if r["sampler"] not in ("cartographer", "time-gap")]
    )
    fig, axes = plt.subplots(len(names), 2, figsize=(10, 2.9 * len(names) + 0.8), squeeze=False)
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
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.suptitle(
        "ATE against the matches tried: candidates on the reference, revisits only "
        "(median over the seeds, band: middle half)",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0.05, 1, 0.98))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


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
        "docstring and in the README "
        "([Do the samples make better maps?](README.md#do-the-samples-make-better-maps)).",
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
    results = ev.Results(read_rows(out / "rows.csv"))
    if not results.rows:
        print(f"map_eval: no rows in {out / 'rows.csv'}", file=sys.stderr)
        return
    budgets = sorted({r["budget"] for r in results.rows if r["budget"]})
    text = tables(results, budgets)
    (out / "tables.md").write_text(text)
    summary = results.summary()
    with open(out / "summary.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(
            {k: round(v, 4) if isinstance(v, float) else v for k, v in s.items()} for s in summary
        )
    figure(results, ROOT / "docs" / "map_eval.png")
    body = section(results, budgets, "nice -n 15 python benches/map_eval.py")
    if args.no_write:
        print(body)
    else:
        write_section(Path(args.output), SECTION, body)
        print(f"map_eval: wrote the section <!-- {SECTION} --> of {args.output}", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    parser.add_argument("--out", default=str(ROOT / "benches" / "map_eval"))
    parser.add_argument("--datasets", default=",".join(DATASETS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--budgets", default="100,1000,10000")
    parser.add_argument("--report-only", action="store_true", help="no runs: the report only")
    parser.add_argument("--output", default=str(ROOT / "BENCHMARKS.md"), help="the report file")
    parser.add_argument(
        "--no-write", action="store_true", help="print the section, write no report"
    )
    args = parser.parse_args()
    if not args.report_only:
        run(args)
    report(args)


if __name__ == "__main__":
    main()
