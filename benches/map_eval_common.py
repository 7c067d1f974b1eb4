"""Shared pieces of the map evaluations, ``map_eval.py`` (one trajectory) and
``fleet_map_eval.py`` (a fleet): their command line, the rows appended as they are done, the
table of how far each sampler is from the best, and the report's ``summary.csv`` and section.

The evaluations themselves (:func:`inexact_loops.evaluate.evaluate`,
:func:`~inexact_loops.evaluate.evaluate_fleet`) and their rows' columns are the package's; the
scripts only choose the grid and write the report.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from harness import write_section

ROOT = Path(__file__).resolve().parents[1]


def arguments(
    doc: str,
    name: str,
    datasets: Sequence[str],
    *,
    seeds: int,
    budgets: str,
    extra: Callable[[argparse.ArgumentParser], None] | None = None,
):
    """The command line of the map evaluation ``name``: ``--data``, ``--out`` (default
    ``benches/<name>``), ``--datasets``, ``--seeds``, ``--budgets``, ``--report-only``,
    ``--output`` and ``--no-write``, and the options ``extra`` adds."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    parser.add_argument("--out", default=str(ROOT / "benches" / name))
    parser.add_argument("--datasets", default=",".join(datasets))
    parser.add_argument("--seeds", type=int, default=seeds)
    parser.add_argument("--budgets", default=budgets)
    parser.add_argument("--report-only", action="store_true", help="no runs: the report only")
    parser.add_argument("--output", default=str(ROOT / "BENCHMARKS.md"), help="the report file")
    parser.add_argument(
        "--no-write", action="store_true", help="print the section, write no report"
    )
    if extra is not None:
        extra(parser)
    return parser.parse_args()


def appender(path: Path, columns: Sequence[str]) -> Callable[[dict], None]:
    """A writer of rows (their ``columns``) appended to the CSV file ``path`` (its header
    written now when the file is new), each written through as it comes: an interrupted run
    keeps its rows."""
    if not path.exists():
        with open(path, "w", newline="") as f:
            csv.DictWriter(f, fieldnames=list(columns)).writeheader()

    def write(row: dict) -> None:
        with open(path, "a", newline="") as f:
            csv.DictWriter(f, fieldnames=list(columns)).writerow({c: row[c] for c in columns})

    return write


def _header(path: Path) -> list[str]:
    """The header of the CSV file ``path``."""
    with open(path, newline="") as f:
        return next(csv.reader(f), [])


def read_rows(path: Path, results_class: Any) -> list[dict]:
    """The rows of ``path`` (``results_class.from_csv``); none when it does not exist."""
    if not path.exists():
        return []
    return results_class.from_csv(path).rows


class Runs:
    """A grid under way: the rows already in ``OUT/rows.csv`` (a second invocation skips the
    blocks they hold), the writer of the new ones, and the blocks run so far.

    Attributes:
        rows: the rows read from ``OUT/rows.csv``.
        done: the blocks these rows hold (``block_key`` of each row).
        budgets: ``--budgets``.
    """

    def __init__(
        self,
        args: argparse.Namespace,
        name: str,
        results_class: Any,
        columns: Sequence[str],
        block_key: Callable[[dict], tuple],
        odometry_key: Callable[[dict], tuple] = lambda r: (r["dataset"], int(r["seed"])),
    ) -> None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        self.name = name
        self.rows = read_rows(out / "rows.csv", results_class)
        if self.rows and _header(out / "rows.csv") != list(columns):
            # Rows of an older header: rewritten with today's columns (their defaults filled
            # in by the reader), so that the new rows append below the right header.
            results_class(self.rows).to_csv(out / "rows.csv")
        self.done = {block_key(r) for r in self.rows}
        self.odometry_done = {odometry_key(r) for r in self.rows if r["sampler"] == "odometry"}
        self.write = appender(out / "rows.csv", columns)
        self.budgets = [int(b) for b in args.budgets.split(",")]
        self.started = time.perf_counter()

    def block(
        self,
        evaluate: Callable[..., Any],
        reference: Any,
        *,
        dataset: str,
        seed: int,
        outlier_rate: float,
        what: str = "",
        odometry: tuple | None = None,
        budgets: list[int] | None = None,
        **options: Any,
    ) -> None:
        """Runs ``evaluate(reference, **options)`` on one dataset, seed and outlier rate at
        every budget (``budgets``, default ``--budgets``), its rows appended as they come (the
        odometry alone once per ``odometry`` key, default the dataset and seed), and says how
        long it took (``what`` names the block further)."""
        start = time.perf_counter()
        key = odometry or (dataset, seed)
        results = evaluate(
            reference,
            budgets=budgets or self.budgets,
            seeds=[seed],
            outlier_rates=(outlier_rate,),
            dataset=dataset,
            include_odometry=key not in self.odometry_done,
            progress=self.write,
            **options,
        )
        self.odometry_done.add(key)
        print(
            f"{self.name}: {dataset} seed {seed} outliers {outlier_rate}{what}: "
            f"{len(results.rows)} runs in {time.perf_counter() - start:.0f} s "
            f"({(time.perf_counter() - self.started) / 60:.1f} min in all)",
            file=sys.stderr,
        )


def relative(
    summary: list[dict],
    names: Sequence[str],
    budgets: Sequence[int],
    outlier_rates: Sequence[float],
    key: str,
    rows: Sequence[tuple[str, Callable[[dict], bool]]],
) -> list[str]:
    """A Markdown table: per row ``(label, member)`` of ``rows`` (the summary rows ``member``
    keeps: a sampler and its options), per outlier rate and budget, the geometric mean over the
    datasets ``names`` of its median error ``key`` over the best one's on that dataset at that
    outlier rate and budget; "–" where a dataset lacks it."""
    columns = [(out, b) for out in outlier_rates for b in budgets]
    best = {
        (n, out, b): min(
            (
                s[key]
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
    for text, member in rows:
        cells = []
        for out, b in columns:
            ratios = [
                s[key] / best[(s["dataset"], out, b)]
                for s in summary
                if member(s)
                and (s["outlier_rate"], s["budget"]) == (out, b)
                and best[(s["dataset"], out, b)]
            ]
            cells.append(
                f"{math.exp(np.mean(np.log(ratios))):.2f}" if len(ratios) == len(names) else "–"
            )
        lines.append(f"| {text} | " + " | ".join(cells) + " |")
    return lines


def figure_rows(rows: int, row_height: float, margin: float) -> tuple[Any, Any]:
    """A figure (matplotlib, no display) of ``rows`` rows of two panels, 10 inches wide and
    ``row_height`` inches a row plus ``margin``: the figure and its axes, ``axes[row][col]``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(rows, 2, figsize=(10, row_height * rows + margin), squeeze=False)


def save_figure(
    fig: Any,
    axes: Any,
    path: Path,
    title: str,
    *,
    legend: tuple[int, float],
    title_size: float,
    rect: tuple[float, float, float, float],
) -> None:
    """Saves ``fig`` to ``path`` (PNG, 100 dpi) with the legend of its first panel at its foot
    (``legend``: columns, font size), the title ``title`` (font size ``title_size``), its
    panels laid out in ``rect``."""
    import matplotlib.pyplot as plt

    handles, labels = axes[0][0].get_legend_handles_labels()
    columns, size = legend
    fig.legend(handles, labels, loc="lower center", ncol=columns, fontsize=size, frameon=False)
    fig.suptitle(title, fontsize=title_size)
    fig.tight_layout(rect=rect)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_summary(path: Path, summary: list[dict[str, Any]]) -> None:
    """Writes the summary rows as CSV, their floats rounded to 4 decimals."""
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(
            {k: round(v, 4) if isinstance(v, float) else v for k, v in s.items()} for s in summary
        )


def main(
    doc: str,
    name: str,
    datasets: Sequence[str],
    *,
    seeds: int,
    budgets: str,
    run: Callable[[argparse.Namespace], None],
    report: Callable[[argparse.Namespace], None],
    extra: Callable[[argparse.ArgumentParser], None] | None = None,
) -> None:
    """The map evaluation ``name``'s command (:func:`arguments`, with the options ``extra``
    adds): ``run`` the grid (but with ``--report-only``), then ``report``."""
    args = arguments(doc, name, datasets, seeds=seeds, budgets=budgets, extra=extra)
    if not args.report_only:
        run(args)
    report(args)


def report(
    args: argparse.Namespace,
    name: str,
    results: Any,
    figure: Callable[[Any, Path], None],
    section: Callable[[Any, list[int], str], str],
) -> None:
    """The report of the map evaluation ``name`` from its ``results`` (the rows of
    ``OUT/rows.csv``): ``OUT/summary.csv``, the ``figure`` ``docs/<name>.png`` and the
    ``section`` ``<!-- name -->`` of the report file (:func:`publish`)."""
    out = Path(args.out)
    if not results.rows:
        print(f"{name}: no rows in {out / 'rows.csv'}", file=sys.stderr)
        return
    budgets = sorted({r["budget"] for r in results.rows if r["budget"]})
    write_summary(out / "summary.csv", results.summary())
    figure(results, ROOT / "docs" / f"{name}.png")
    publish(args, name, section(results, budgets, f"nice -n 15 python benches/{name}.py"))


def publish(args: argparse.Namespace, section: str, body: str) -> None:
    """Writes ``body`` as the section ``section`` of ``args.output``, or prints it with
    ``--no-write``."""
    if args.no_write:
        print(body)
    else:
        write_section(Path(args.output), section, body)
        print(f"{section}: wrote the section <!-- {section} --> of {args.output}", file=sys.stderr)
