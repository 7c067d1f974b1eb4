#!/usr/bin/env python3
"""Do the samples make better maps? ATE against the budget for every sampler and baseline, on
the 2.1 h urban drive, KITTI 00, 05, 08 and MulRan KAIST 01 (issue 20).

Usage::

    nice -n 15 python benches/map_eval.py [--data ../shared/data] [--out benches/map_eval]
        [--datasets urban,kitti00,kitti05,kitti08,kaist01] [--seeds 5]
        [--budgets 100,1000,10000] [--report-only] [--markdown FILE]

Needs the ``inexact_loops`` wheel with the ``maps`` extra (GTSAM) and matplotlib. The full grid
is this one command; every run appends its row to ``OUT/rows.csv`` as it finishes, and a second
invocation skips the blocks already there, so an interrupted run resumes where it stopped.
``--report-only`` redraws the tables and the figure from ``rows.csv``: ``OUT/tables.md`` (also
printed, and written to ``--markdown`` when given), ``OUT/summary.csv`` (median and spread
over the seeds per condition) and ``docs/map_eval.png``.

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
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("RAYON_NUM_THREADS", "1")  # the machine is shared: one engine thread

import inexact_loops as il  # noqa: E402
from inexact_loops import evaluate as ev  # noqa: E402

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


def tables(results: ev.Results, budgets: list[int]) -> str:
    summary = results.summary()
    names = [n for n in DATASETS if any(s["dataset"] == n for s in summary)]
    lines: list[str] = []
    seeds = sorted({r["seed"] for r in results.rows})
    lines.append(
        f"Median ATE (m) over {len(seeds)} seed(s), [min–max]; each cell one sampler at one budget "
        "(matches tried). Odometry alone is the first row."
    )
    for on in ON:
        for separation in (True, False):
            for outlier_rate in OUTLIER_RATES:
                title = (
                    f"**Candidates on the {on}"
                    + (" (γ × 2)" if on == "estimate" else "")
                    + (", revisits only (separation 4γ)" if separation else ", S_γ (no separation)")
                    + (
                        f", {outlier_rate:.0%} wrong matches"
                        if outlier_rate
                        else ", no wrong matches"
                    )
                    + "**"
                )
                header = "| sampler | budget | " + " | ".join(DATASETS[n][0] for n in names) + " |"
                body = []
                odo = {
                    n: np.median(
                        [
                            r["ate_m"]
                            for r in results.rows
                            if r["dataset"] == n and r["sampler"] == "odometry"
                        ]
                    )
                    for n in names
                }
                body.append(
                    "| odometry alone | – | " + " | ".join(f"{odo[n]:.2f}" for n in names) + " |"
                )
                keys = sorted(
                    {(s["sampler"], s["source"]) for s in summary if s["sampler"] != "odometry"},
                    key=lambda k: (ORDER.index(k[0]), k[1]),
                )
                for sampler, source in keys:
                    for budget in budgets:
                        cells = []
                        for n in names:
                            match = [
                                s
                                for s in summary
                                if s["dataset"] == n
                                and s["sampler"] == sampler
                                and s["source"] == source
                                and s["on"] == on
                                and s["separation"] == separation
                                and s["outlier_rate"] == outlier_rate
                                and s["budget"] == budget
                            ]
                            cells.append(fmt(match[0]) if match else "–")
                        if all(c == "–" for c in cells):
                            continue
                        body.append(
                            f"| {label(sampler, source)} | {budget} | " + " | ".join(cells) + " |"
                        )
                if len(body) > 1:
                    lines += ["", title, "", header, "|---|---|" + "---|" * len(names), *body]
    return "\n".join(lines) + "\n"


def winners(results: ev.Results, budgets: list[int]) -> str:
    """Per condition and budget: the sampler with the lowest median ATE, counted over datasets."""
    summary = [s for s in results.summary() if s["sampler"] != "odometry"]
    names = sorted({s["dataset"] for s in summary}, key=list(DATASETS).index)
    lines = [
        "",
        "**Best sampler per dataset** (lowest median ATE; separation on, candidates on the "
        "reference)",
        "",
    ]
    lines.append("| wrong matches | budget | " + " | ".join(DATASETS[n][0] for n in names) + " |")
    lines.append("|---|---|" + "---|" * len(names))
    for outlier_rate in OUTLIER_RATES:
        for budget in budgets:
            cells = []
            for n in names:
                pool = [
                    s
                    for s in summary
                    if s["dataset"] == n
                    and s["separation"]
                    and s["on"] == "reference"
                    and s["outlier_rate"] == outlier_rate
                    and s["budget"] == budget
                ]
                if not pool:
                    cells.append("–")
                    continue
                best = min(pool, key=lambda s: s["ate_median_m"])
                cells.append(f"{label(best['sampler'], best['source'])} {best['ate_median_m']:.2f}")
            lines.append(f"| {outlier_rate:.0%} | {budget} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def figure(results: ev.Results, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n in DATASETS if any(r["dataset"] == n for r in results.rows)]
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 3.3 * len(names)), squeeze=False)
    for row, n in enumerate(names):
        for col, outlier_rate in enumerate(OUTLIER_RATES):
            sub = ev.Results([r for r in results.rows if r["dataset"] == n])
            ev.plot_error_vs_matches(
                sub,
                ax=axes[row][col],
                select={"separation": True, "on": "reference", "outlier_rate": outlier_rate},
                title=f"{DATASETS[n][0]}, revisits, candidates on the reference, "
                + (f"{outlier_rate:.0%} wrong matches" if outlier_rate else "no wrong matches"),
            )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(args: argparse.Namespace) -> None:
    out = Path(args.out)
    results = ev.Results(read_rows(out / "rows.csv"))
    if not results.rows:
        print(f"map_eval: no rows in {out / 'rows.csv'}", file=sys.stderr)
        return
    budgets = sorted({r["budget"] for r in results.rows if r["budget"]})
    text = tables(results, budgets) + winners(results, budgets)
    (out / "tables.md").write_text(text)
    summary = results.summary()
    with open(out / "summary.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)
    if args.markdown:
        Path(args.markdown).write_text(text)
    print(text)
    figure(results, ROOT / "docs" / "map_eval.png")
    seconds = sum(r["seconds"] for r in results.rows)
    print(f"map_eval: {len(results.rows)} runs, {seconds / 3600:.2f} h of runs", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    parser.add_argument("--out", default=str(ROOT / "benches" / "map_eval"))
    parser.add_argument("--datasets", default=",".join(DATASETS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--budgets", default="100,1000,10000")
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument("--markdown", help="also write the tables to this file")
    args = parser.parse_args()
    if not args.report_only:
        run(args)
    report(args)


if __name__ == "__main__":
    main()
