#!/usr/bin/env python3
"""Do the samples make better maps of a fleet? The joint and inter-session errors of a
multi-session pose graph against the budget, for every sampler, sampling every component or
only those between sessions.

Usage::

    nice -n 15 python benches/fleet_map_eval.py [--data ../shared/data]
        [--out benches/fleet_map_eval] [--datasets urban,kaist] [--seeds 3]
        [--budgets 10,100,1000] [--first-seed 0] [--known-starts-only] [--report-only]
        [--no-write] [--output BENCHMARKS.md]

Needs the ``inexact_loops`` wheel with the ``maps`` extra (GTSAM) and matplotlib. A modest grid
(about 45 minutes on 2 busy cores): every run appends its row to ``OUT/rows.csv``, a second
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

Without ground truth (the second part): the candidates chosen on the sessions' drifted
estimates (``FleetRule(on="estimate")``, gamma inflated 2x, pairs between sessions only where
they share a frame), all at once or in 3 rounds (:class:`FleetRounds`: each round on the
estimates the matches before it corrected), against the same samplers on the references, at
the budgets of ``ESTIMATE_BUDGETS`` (within ``--budgets``), with no wrong matches and with
10 %, for the default sampler and the best rules of the first part (``ESTIMATE_RULES``), a seed
at a time (``--known-starts-only`` runs these cells alone). There every session's
odometry starts at its reference's first pose (``known_starts``, as with a fix at the start):
with unknown starts the estimates of two sessions share no frame before a match between them,
which place recognition, not a sampler on poses, has to find; the default sampler in rounds
with unknown starts (no wrong matches) shows what that costs.
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

#: The second part's rules (sampler, between_only): the default sampler, and the best rules of
#: the first part at 100 and 1000 matches; run in this order.
ESTIMATE_RULES = (
    (il.DEFAULT_SAMPLER, False),
    ("closest-first", True),
    ("rho-dispersed", False),
)
ESTIMATE_BUDGETS = (100, 1000)
#: (starts, on, rounds) of the second part; the last for the default sampler only.
CONDITIONS = (("known", "reference", 1), ("known", "estimate", 1), ("known", "estimate", 3))
UNKNOWN_ROUNDS = ("unknown", "estimate", 3)
#: The first part's condition.
FIRST = ("unknown", "reference", 1)


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
    seeds = range(args.first_seed, args.first_seed + args.seeds)
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
        lambda r: (
            r["dataset"],
            int(r["seed"]),
            float(r["outlier_rate"]),
            (r["starts"], r["on"], int(r["rounds"])),
            r["sampler"],
            r["between_only"],
        ),
        lambda r: (r["dataset"], int(r["seed"]), r["starts"]),
    )

    def block(
        name: str,
        seed: int,
        outlier_rate: float,
        condition: tuple[str, str, int],
        samplers: tuple[str, ...],
        budgets: list[int],
        modes: tuple[bool, ...] = MODES,
    ) -> None:
        """The runs of ``samplers`` in ``modes`` (between_only) not all in the rows yet, under
        one condition."""
        starts, on, rounds = condition
        todo = [
            s
            for s in samplers
            if any((name, seed, outlier_rate, condition, s, m) not in runs.done for m in modes)
        ]
        references = sessions[name]
        if not todo or references is None or not budgets:
            return
        runs.block(
            ev.evaluate_fleet,
            references,
            dataset=name,
            seed=seed,
            outlier_rate=outlier_rate,
            what=f", {starts} starts, on the {on}, {rounds} round(s), {', '.join(todo)} {modes}",
            odometry=(name, seed, starts),
            budgets=budgets,
            gamma=DATASETS[name][1],
            samplers=todo,
            between_only=modes,
            on=(on,),
            rounds=rounds,
            known_starts=starts == "known",
        )

    if not args.known_starts_only:
        for seed in seeds:
            for name in names:
                for outlier_rate in OUTLIER_RATES:
                    block(name, seed, outlier_rate, FIRST, SAMPLERS, runs.budgets)
    second = [b for b in runs.budgets if b in ESTIMATE_BUDGETS]
    # A seed at a time, each rule's three conditions together: a grid cut short leaves cells
    # whose estimates and references have the same seeds.
    for seed in seeds:
        for outlier_rate in OUTLIER_RATES:
            for sampler, between in ESTIMATE_RULES:
                for name in names:
                    for condition in CONDITIONS:
                        block(name, seed, outlier_rate, condition, (sampler,), second, (between,))
    if args.known_starts_only:
        return
    # Last: the default sampler with unknown starts, on the references and in rounds.
    for seed in seeds:
        for name in names:
            for condition in (FIRST, UNKNOWN_ROUNDS):
                block(name, seed, 0.0, condition, (il.DEFAULT_SAMPLER,), second, (False,))


# ---------------------------------------------------------------------------------------------
# Tables and figure
# ---------------------------------------------------------------------------------------------


def label(sampler: str, between: bool) -> str:
    if sampler == "odometry":
        return "odometry alone"
    return il.sampler_symbol(sampler) + (" (between sessions only)" if between else "")


def datasets_of(results: ev.FleetResults) -> list[str]:
    return [n for n in DATASETS if any(r["dataset"] == n for r in results.rows)]


def condition(r: dict) -> tuple[str, str, int]:
    """The (starts, on, rounds) of a row or summary row; the odometry alone's is its starts'
    with the first part's rest."""
    if r["sampler"] == "odometry":
        return (r["starts"], "reference", 1)
    return (r["starts"], r["on"], int(r["rounds"]))


def first_part(results: ev.FleetResults) -> ev.FleetResults:
    """The rows of the first part (unknown starts, candidates on the references)."""
    return ev.FleetResults([r for r in results.rows if condition(r) == FIRST])


def table(
    results: ev.FleetResults, summary: list[dict], outlier_rate: float, budgets: list[int]
) -> list[str]:
    """A row per sampler and mode, a column per dataset and budget: the median joint ATE over
    the seeds [min–max], then the median inter-session error."""
    names = datasets_of(results)
    cells_of = {
        (s["dataset"], s["sampler"], s["between_only"], s["budget"]): s
        for s in summary
        if s["outlier_rate"] == outlier_rate
        and s["sampler"] != "odometry"
        and condition(s) == FIRST
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
    summary = [s for s in results.summary() if s["sampler"] in SAMPLERS and condition(s) == FIRST]
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
        sub = ev.FleetResults([r for r in first_part(results).rows if r["dataset"] == n])
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


def estimate_tables(results: ev.FleetResults, budgets: list[int]) -> list[str]:
    """The second part: per outlier rate, rule (``ESTIMATE_RULES``), dataset and budget, the
    median joint ATE [min–max] on the references, then on the estimates at once and in 3 rounds
    with their ratios to the references' (known starts); then the default sampler in rounds
    with unknown starts against the same on the references. Nothing before the second part has
    run."""
    summary = {
        (
            s["dataset"],
            s["sampler"],
            s["between_only"],
            s["budget"],
            condition(s),
            s["outlier_rate"],
        ): s
        for s in results.summary()
        if s["sampler"] != "odometry"
    }
    if all(k[4] == FIRST for k in summary):
        return []
    names = datasets_of(results)
    columns = [(n, b) for n in names for b in budgets if b in ESTIMATE_BUDGETS]
    header = "| sampler | candidates on | " + " | ".join(
        f"{DATASETS[n][0]}, {b}" for n, b in columns
    )

    def row(
        sampler: str,
        between: bool,
        text: str,
        cond: tuple,
        base: tuple | None,
        rate: float,
        ratios: dict[tuple, list[float]],
    ) -> str:
        """A table row: per column the cell of ``cond`` at the outlier rate ``rate``, with its
        ratio to ``base``'s (added to ``ratios``)."""
        cells = []
        for n, b in columns:
            s = summary.get((n, sampler, between, b, cond, rate))
            if s is None:
                cells.append("–")
                continue
            cell = f"{s['ate_median_m']:.2f} [{s['ate_min_m']:.2f}–{s['ate_max_m']:.2f}]"
            r = summary.get((n, sampler, between, b, base, rate)) if base else None
            if r is not None:
                ratio = s["ate_median_m"] / r["ate_median_m"]
                ratios.setdefault(cond, []).append(ratio)
                cell += f" (**{ratio:.2f}×**)"
            cells.append(cell)
        return f"| {label(sampler, between)} | {text} | " + " | ".join(cells) + " |"

    def seeds_text(rate: float, conditions: tuple) -> str:
        """The number of seeds of the cells of ``conditions`` at ``rate``: one, or a range."""
        counts = sorted(
            {s["seeds"] for k, s in summary.items() if k[4] in conditions and k[5] == rate}
        )
        return f"{counts[0]}" if counts[0] == counts[-1] else f"{counts[0]}–{counts[-1]}"

    lines = [
        "**Without ground truth: candidates on the estimates.** Every session's odometry starts "
        "at its reference's first pose and the back end holds it there (known starts, as with "
        "a fix at the start: no match moves a session); candidates on "
        "the references, or on the drifted estimates (γ inflated 2×, pairs between sessions only "
        "where they share a frame) all at once or in 3 rounds (`ev.FleetRounds`: each round "
        "chosen on the estimates the matches before it corrected), the same total budget; no "
        "wrong matches, then 10 %. Cells: the median joint ATE in metres over the seeds "
        "[min–max] and, on the estimates, its ratio to the same rule's on the references.",
        "",
    ]
    for rate in OUTLIER_RATES:
        if not any(k[4] in CONDITIONS[1:] and k[5] == rate for k in summary):
            continue
        ratios: dict[tuple, list[float]] = {}
        title = f"{rate:.0%} wrong matches" if rate else "No wrong matches"
        lines += [
            f"**{title}** ({seeds_text(rate, CONDITIONS)} seeds a cell)",
            "",
            header + " |",
            "|---|---|" + "---|" * len(columns),
        ]
        for sampler, between in ESTIMATE_RULES:
            on_refs = CONDITIONS[0]
            lines += [
                row(sampler, between, "references", on_refs, None, rate, ratios),
                row(sampler, between, "estimates, at once", CONDITIONS[1], on_refs, rate, ratios),
                row(sampler, between, "estimates, 3 rounds", CONDITIONS[2], on_refs, rate, ratios),
            ]
        overall = []
        for cond, text in ((CONDITIONS[1], "at once"), (CONDITIONS[2], "in 3 rounds")):
            r = ratios.get(cond, [])
            if r:
                overall.append(
                    f"{text}, median {np.median(r):.2f}×, worst {max(r):.2f}×, "
                    f"{sum(x <= 1.5 for x in r)} of {len(r)} cells within 1.5×"
                )
        lines += [
            "",
            f"Estimates over references ({title.lower()}): " + "; ".join(overall) + ".",
            "",
        ]
    unknown_ratios: dict[tuple, list[float]] = {}
    unknown = [
        header + " |",
        "|---|---|" + "---|" * len(columns),
        row(il.DEFAULT_SAMPLER, False, "references", FIRST, None, 0.0, unknown_ratios),
        row(
            il.DEFAULT_SAMPLER,
            False,
            "estimates, 3 rounds",
            UNKNOWN_ROUNDS,
            FIRST,
            0.0,
            unknown_ratios,
        ),
    ]
    return [
        *lines,
        "With unknown starts (only the first session's known), the estimates of two sessions "
        "share no frame before a match between them, which place recognition has to find: the "
        "default sampler in 3 rounds finds pairs within sessions only, and the other sessions "
        "stay where their own frames put them (no wrong matches; ratio to the same on the "
        "references):",
        "",
        *unknown,
        "",
    ]


def section(results: ev.FleetResults, budgets: list[int], command: str) -> str:
    estimate = estimate_tables(results, budgets)
    runs = [r for r in results.rows if r["sampler"] != "odometry"]

    def seeds(rows: list[dict]) -> str:
        return ", ".join(map(str, sorted({r["seed"] for r in rows}))) or "none"

    minutes = sum(r["seconds"] for r in results.rows) / 60
    results = first_part(results)
    summary = results.summary()
    lines = [
        "## Do the samples make better maps? The fleet case",
        "",
        f"Generated by `{command}` (the grid, then the report from "
        "`benches/fleet_map_eval/rows.csv`); do not edit by hand. The method is in the script's "
        "docstring and in the documentation "
        "([Evaluate on your own poses](docs/how-to/evaluate.md)).",
        "",
        *machine_facts(("numpy", "gtsam")),
        f"- {len(runs)} runs: seed(s) {seeds([r for r in runs if condition(r) == FIRST])} with "
        "unknown starts, seed(s) "
        f"{seeds([r for r in runs if r['starts'] == 'known'])} with known starts; "
        f"{minutes:.1f} min of runs on a 2-core machine shared with other jobs (`nice -n 15` to "
        "`nice -n 19`).",
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
        *estimate,
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
    def extra(parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "--first-seed", type=int, default=0, help="the first seed run (then --seeds of them)"
        )
        parser.add_argument(
            "--known-starts-only",
            action="store_true",
            help="run only the cells of known starts (candidates on the references and on the "
            "estimates), not the first part nor the default sampler with unknown starts",
        )

    common.main(
        __doc__,
        SECTION,
        list(DATASETS),
        seeds=3,
        budgets="10,100,1000",
        run=run,
        report=report,
        extra=extra,
    )


if __name__ == "__main__":
    main()
