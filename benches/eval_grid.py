#!/usr/bin/env python3
"""Which sampler makes the best map in every cell of a grid? The ratio of each sampler's median
ATE to the best one's, per cell (dataset, candidates on the reference or the estimate, verifier
model, wrong matches, budget), and whether the default sampler meets the bar: within 1.10x of
the best and below the LIO-SAM and hdl_graph_slam rules.

Usage::

    nice -n 10 python benches/eval_grid.py --out benches/eval_grid/small \\
        [--datasets urban,kitti00] [--budgets 100,1000] [--seeds 3] \\
        [--on reference,estimate,rounds] [--rounds 3] \\
        [--verifiers distance-aware,steep,blind] [--outliers 0,0.1] \\
        [--samplers default,closest-first,...] [--contenders NAME,...] [--existing-blocks]
        [--first-seed N] [--report-only] [--most-seeds] [--paired]

Datasets are those of ``map_eval.py`` (``urban``, ``kitti00``, ``kitti05``, ``kitti08``,
``kaist01``: the same keyframes and gamma), plus ``urbanN``: the urban drive of seed N (a drive
the benchmarks never use). ``--on rounds`` is ``on="estimate"`` with the budget spent in
``--rounds`` rounds (:class:`inexact_loops.evaluate.Rounds`; ``--rounds-order time``: round r
on the pairs whose later pose is in the r-th stretch of the path). Verifier models are
:data:`inexact_loops.evaluate.VERIFIER_MODELS`. Every run appends its row to ``OUT/rows.csv``
as it finishes and a second invocation skips the samplers of a block already there (so that
adding a sampler to ``--samplers`` runs that one alone); the table goes to
``OUT/ratios.md`` (``--report-only``: the table alone, from ``rows.csv``; ``--also DIR,...``
adds the rows of other grids to the table). Each of ``--contenders`` (default: the default
sampler and closest-then-spread, the default before it) gets its ratio to the best and to the
nearer of the LIO-SAM and hdl_graph_slam rules per cell, and whether it meets the bar, side by
side ("–" in a cell it did not run, which its count leaves out). A cell's medians are over
the seeds every sampler of the cell ran; with ``--most-seeds``, over the seeds the contenders
and the two rules all ran (more seeds added for some samplers only, ``--first-seed 3 --seeds 2
--samplers ...``), the samplers without all of them left out of that cell. ``--paired`` adds
the first contender against each sampler seed by seed (:func:`paired_table`).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

import numpy as np

os.environ.setdefault("RAYON_NUM_THREADS", "1")  # the machine is shared: one engine thread

import map_eval_common as common  # noqa: E402
from map_eval import DATASETS  # noqa: E402
from map_eval import load as load_dataset  # noqa: E402

import inexact_loops as il  # noqa: E402
from inexact_loops import evaluate as ev  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = il.DEFAULT_SAMPLER
#: The sampler the table sets beside the default: the default before it.
PREVIOUS = "closest-then-spread"
#: The rules the default must beat in every cell.
RIVALS = ("lio-sam", "hdl-graph-slam")
#: The bar: the default's median ATE at most this many times the best one's.
WITHIN = 1.10


def load(name: str, data: Path) -> tuple[ev.Poses | None, float]:
    """The keyframed reference of dataset ``name`` and its gamma."""
    if name.startswith("urban") and name[5:].isdigit():
        drive = il.urban_drive(seed=int(name[5:]))
        poses = ev.Poses.from_positions(drive.timestamps, drive.positions[:, :2])
        return poses.take(poses.keyframes(DATASETS["urban"][3])), DATASETS["urban"][2]
    return load_dataset(name, data), DATASETS[name][2]


def cell_key(row: dict) -> tuple:
    on = "rounds" if row["on"] == "estimate" and int(row["rounds"]) > 1 else row["on"]
    return (row["dataset"], on, row["verifier"], float(row["outlier_rate"]), int(row["budget"]))


def block_key(row: dict) -> tuple:
    d, on, verifier, outliers, _ = cell_key(row)
    return (d, on, verifier, outliers, int(row["seed"]))


def arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    parser.add_argument("--out", required=True, help="folder for rows.csv and ratios.md")
    parser.add_argument("--datasets", default="urban,kitti00")
    parser.add_argument("--budgets", default="100,1000")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--first-seed", type=int, default=0, help="seeds FIRST..FIRST+SEEDS-1")
    parser.add_argument("--on", default="reference,estimate")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of --on rounds")
    parser.add_argument(
        "--rounds-order",
        choices=("any", "time"),
        default="any",
        help="--on rounds: each round over the whole estimate (any), or round r on the pairs "
        "whose later pose is in the r-th stretch of the path (time, as an online front end)",
    )
    parser.add_argument("--verifiers", default="distance-aware")
    parser.add_argument("--outliers", default="0")
    parser.add_argument("--samplers", default=",".join(ev.SAMPLERS + ev.BASELINES))
    parser.add_argument(
        "--contenders",
        default=",".join(dict.fromkeys([DEFAULT, PREVIOUS])),
        help="samplers whose ratios and bar the table shows, side by side",
    )
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument(
        "--brief", action="store_true", help="the best sampler's name, not every sampler's ratio"
    )
    parser.add_argument(
        "--existing-blocks",
        action="store_true",
        help="run only blocks rows.csv has already (to add a sampler to a grid)",
    )
    parser.add_argument(
        "--most-seeds",
        action="store_true",
        help="per cell, the seeds the contenders and the rules all ran, and only the samplers "
        "that ran them all",
    )
    parser.add_argument(
        "--also", default="", help="comma-separated folders whose rows.csv join the table"
    )
    parser.add_argument(
        "--paired",
        action="store_true",
        help="also, per cell, the first contender against each sampler seed by seed: the mean "
        "of log(ATE ratio) over the seeds and its t statistic",
    )
    return parser.parse_args()


def run(args: argparse.Namespace, rows_path: Path) -> None:
    done: dict[tuple, set[str]] = defaultdict(set)
    for r in common.read_rows(rows_path, ev.Results):
        done[block_key(r)].add(r["sampler"])
    write = common.appender(rows_path, ev.COLUMNS)
    samplers = list(dict.fromkeys(args.samplers.replace("default", DEFAULT).split(",")))
    budgets = [int(b) for b in args.budgets.split(",")]
    outliers = [float(o) for o in args.outliers.split(",")]
    for name in args.datasets.split(","):
        reference, gamma = load(name, Path(args.data))
        if reference is None:
            continue
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            for on in args.on.split(","):
                for verifier in args.verifiers.split(","):
                    for rate in outliers:
                        have = done.get((name, on, verifier, rate, seed), set())
                        todo = [s for s in samplers if s not in have]
                        if not todo or (args.existing_blocks and not have):
                            continue
                        print(
                            f"eval_grid: {name} seed {seed} {on} {verifier} {rate}", file=sys.stderr
                        )
                        ev.evaluate(
                            reference,
                            gamma=gamma,
                            samplers=todo,
                            budgets=budgets,
                            seeds=[seed],
                            on=["reference" if on == "reference" else "estimate"],
                            rounds=args.rounds if on == "rounds" else 1,
                            rounds_order=args.rounds_order,
                            outlier_rates=[rate],
                            verifier=verifier,
                            dataset=name,
                            include_odometry=False,
                            progress=write,
                        )


def report(
    rows: list[dict],
    contenders: list[str],
    *,
    brief: bool = False,
    most_seeds: bool = False,
    paired: bool = False,
) -> str:
    """The markdown table: per cell (over the seeds all its samplers ran), the best median ATE
    and the ratio of each sampler's to it;
    then, per contender, its ratio to the best and to the nearer rival rule, and whether it
    meets the bar; the cells each contender meets. ``brief``: the best sampler's name instead
    of every sampler's ratio. ``most_seeds``: per cell, the seeds the contenders and the rules
    all ran, and only the samplers that ran them all (the columns "samplers" and "of" say how
    many that leaves, of how many). ``paired``: the table of :func:`paired_table` after it."""
    by_seed: dict[tuple, dict[str, dict[int, float]]] = defaultdict(lambda: defaultdict(dict))
    for r in rows:
        if r["sampler"] != "odometry":
            by_seed[cell_key(r)][r["sampler"]][int(r["seed"])] = float(r["ate_m"])
    # Per cell, the seeds every sampler of the cell has: the medians compare like with like.
    ate: dict[tuple, dict[str, list[float]]] = {}
    compared: dict[tuple, int] = {}
    for key, runs in by_seed.items():
        if most_seeds:
            core = [set(runs[n]) for n in [*contenders, *RIVALS] if n in runs]
            seeds = set.intersection(*core) if core else set()
            compared[key] = len(runs)
            runs = {n: v for n, v in runs.items() if seeds <= set(v)}
        common = set.intersection(*(set(v) for v in runs.values()))
        ate[key] = {n: [v[s] for s in sorted(common)] for n, v in runs.items()}
    names = [n for n in ev.SAMPLERS + ev.BASELINES if any(n in c for c in ate.values())]
    contenders = [c for c in contenders if c in names]
    head = ["dataset", "on", "verifier", "wrong", "budget", "seeds"]
    head += ["samplers", "of"] if most_seeds else []
    head += ["best (m)"]
    tail = [f"{c}: {what}" for c in contenders for what in ("best", "rules", "meets")]
    middle = ["best sampler"] if brief else [il.sampler_symbol(n) for n in names]
    lines = [
        "| " + " | ".join(head + middle + tail) + " |",
        "|" + "---|" * (len(head) + len(middle) + len(tail)),
    ]
    met = dict.fromkeys(contenders, 0)
    ran = dict.fromkeys(contenders, 0)
    # Per cell, each contender's verdict (None where it did not run): the summary's counts.
    verdict_of: dict[tuple, dict[str, bool | None]] = {}
    for key in sorted(ate):
        medians = {n: float(np.median(v)) for n, v in ate[key].items()}
        best = min(medians.values())
        seeds = min(len(v) for v in ate[key].values())
        rival = min(medians.get(r, np.inf) for r in RIVALS)
        cells = [f"{medians[n] / best:.2f}" if n in medians else "–" for n in names]
        cells = [f"**{c}**" if n in contenders else c for n, c in zip(names, cells, strict=True)]
        if brief:
            cells = [il.sampler_symbol(min(medians, key=lambda n: medians[n]))]
        verdicts = []
        verdict_of[key] = dict.fromkeys(contenders)
        for c in contenders:
            if c not in medians:
                # A contender the cell did not run: no verdict, and not counted.
                verdicts += ["–", "–", "–"]
                continue
            mine = medians[c]
            # A cell without either rule (left out by --most-seeds) cannot be met.
            ok = mine <= WITHIN * best and mine < rival < np.inf
            met[c] += ok
            ran[c] += 1
            verdict_of[key][c] = bool(ok)
            rules = f"{mine / rival:.2f}" if rival < np.inf else "–"
            verdicts += [f"{mine / best:.2f}", rules, "yes" if ok else "no"]
        d, on, verifier, outlier_rate, budget = key
        of = f"{len(medians)} | {compared[key]} | " if most_seeds else ""
        lines.append(
            f"| {d} | {on} | {verifier} | {outlier_rate:.0%} | {budget} | {seeds} | "
            + f"{of}{best:.2f} | "
            + " | ".join(cells + verdicts)
            + " |"
        )
    lines.append("")
    for c in contenders:
        lines.append(
            f"{c}{' (the default)' if c == DEFAULT else ''} meets the bar (at most {WITHIN:.2f}x "
            f"the best median ATE, below the LIO-SAM and hdl_graph_slam rules) in {met[c]} of "
            f"the {ran[c]} cells it ran (of {len(ate)})."
        )
    lines.append("")
    lines.append(
        '"rules": the ratio to the nearer of the LIO-SAM and hdl_graph_slam rules (below 1: ahead).'
    )
    lines += ["", *summary(verdict_of, contenders)]
    if paired and contenders:
        lines += ["", *paired_table(ate, contenders[0], names)]
    return "\n".join(lines) + "\n"


def paired_table(
    ate: dict[tuple, dict[str, list[float]]], mine: str, names: list[str]
) -> list[str]:
    """Per cell, ``mine`` against each other sampler on the same seeds (the same blocks, drift
    and verifier draws): the geometric mean of its ATE over the other's, exp(mean log ratio),
    and the t statistic of the mean log ratio (mean over its standard error; |t| > 2: a
    difference the seeds resolve). A ratio of medians (the table above) moves with a few
    seeds; the paired mean says whether a gap is more than the seeds' noise. Then the count of
    comparisons where ``mine`` is behind (t > 2) and ahead (t < -2), of all."""
    others = [n for n in names if n != mine]
    head = ["dataset", "on", "verifier", "wrong", "budget", "seeds"]
    head += [il.sampler_symbol(n) for n in others]
    lines = [
        f"{mine} against each sampler, seed by seed: exp(mean log ratio) (t).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    behind = ahead = compared = 0
    for key in sorted(ate):
        runs = ate[key]
        if mine not in runs:
            continue
        cells = []
        for n in others:
            if n not in runs or len(runs[n]) < 2:
                cells.append("–")
                continue
            logs = np.log(np.asarray(runs[mine]) / np.asarray(runs[n]))
            error = logs.std(ddof=1) / np.sqrt(len(logs))
            t = logs.mean() / error if error > 0 else 0.0
            behind += t > 2
            ahead += t < -2
            compared += 1
            cells.append(f"{np.exp(logs.mean()):.3f} ({t:+.1f})")
        d, on, verifier, outlier_rate, budget = key
        lines.append(
            f"| {d} | {on} | {verifier} | {outlier_rate:.0%} | {budget} | {len(runs[mine])} | "
            + " | ".join(cells)
            + " |"
        )
    lines += [
        "",
        f"{mine} is behind by more than the seeds' noise (t > 2) in {behind} of {compared} "
        f"comparisons, ahead (t < -2) in {ahead}.",
    ]
    return lines


def summary(verdict_of: dict[tuple, dict[str, bool | None]], contenders: list[str]) -> list[str]:
    """The cells each contender meets, of those it ran, in all and by budget, dataset,
    candidates' source and verifier model: a markdown table."""
    groups: list[tuple[str, Callable[[tuple], bool]]] = [("all", lambda k: True)]
    names: list[tuple[int, Callable[[object], str]]] = [
        (4, lambda v: f"budget {v}"),
        (0, str),
        (1, lambda v: "candidates in rounds" if v == "rounds" else f"candidates on the {v}"),
        (2, lambda v: f"{v} verifier"),
        (3, lambda v: f"{v:.0%} wrong matches"),
    ]
    for i, name in names:
        for value in sorted({k[i] for k in verdict_of}):
            groups.append((name(value), lambda k, i=i, v=value: k[i] == v))
    head = "| cells meeting the bar (of those run) | " + " | ".join(
        f"{c}{' (the default)' if c == DEFAULT else ''}" for c in contenders
    )
    lines = [head + " |", "|---|" + "---|" * len(contenders)]
    for label, inside in groups:
        counts = []
        for c in contenders:
            run = [v[c] for k, v in verdict_of.items() if inside(k) and v[c] is not None]
            counts.append(f"{sum(run)} of {len(run)}")
        lines.append(f"| {label} | " + " | ".join(counts) + " |")
    return lines


def main() -> None:
    args = arguments()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows_path = out / "rows.csv"
    if not args.report_only:
        run(args, rows_path)
    rows = common.read_rows(rows_path, ev.Results)
    for folder in filter(None, args.also.split(",")):
        rows += common.read_rows(Path(folder) / "rows.csv", ev.Results)
    text = report(
        rows,
        args.contenders.split(","),
        brief=args.brief,
        most_seeds=args.most_seeds,
        paired=args.paired,
    )
    (out / "ratios.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
