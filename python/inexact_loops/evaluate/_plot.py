"""The plot of the error against the number of matches."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np

from .._core import (
    sampler_symbol,
)
from ._candidates import BASELINES, SAMPLERS
from ._grid import Results

# ---------------------------------------------------------------------------------------------
# The plot
# ---------------------------------------------------------------------------------------------

#: Colours of the samplers in :func:`plot_error_vs_matches`.
COLOURS: Mapping[str, str] = {
    "one": "deepskyblue",
    "rho": "forestgreen",
    "rho-dispersed": "darkorange",
    "closest-first": "crimson",
    "closest-then-spread": "black",
    "nearest-then-uniform": "teal",
    "alpha": "magenta",
    "lio-sam": "0.35",
    "hdl-graph-slam": "sienna",
    "cartographer": "slateblue",
    "time-gap": "olive",
}


def plot_error_vs_matches(
    results: Results,
    *,
    ax: Any = None,
    select: Mapping[str, Any] | None = None,
    metric: Literal["ate", "rpe"] = "ate",
    title: str | None = None,
    legend: bool = True,
) -> Any:
    """The error against the number of matches (the budget, log scale), one curve per sampler
    (dashed: on detections): the median over the seeds, and for ATE a band over the middle half
    of them (first to third quartile); the odometry alone as a dotted line. ``select`` keeps the
    rows whose columns have these values (e.g. ``{"separation": True, "outlier_rate": 0.0}``).
    ``legend=False`` leaves the legend to the caller (``ax.get_legend_handles_labels()``).
    Needs matplotlib.
    """
    ax, select, curves = error_curves(results, ax, select, "source")
    column = "ate" if metric == "ate" else "rpe"
    for (name, source), points in curves:
        x = [s["budget"] for s in points]
        y = [s[f"{column}_median_m"] for s in points]
        label = sampler_symbol(name) + (" (detections)" if source == "detections" else "")
        style = "--" if source == "detections" else "-"
        colour = COLOURS.get(name)
        ax.plot(
            x,
            y,
            style,
            marker="o",
            ms=3,
            color=colour,
            label=label,
            lw=1.5 if name in SAMPLERS else 1.0,
        )
        if column == "ate":
            ax.fill_between(
                x,
                [s["ate_q25_m"] for s in points],
                [s["ate_q75_m"] for s in points],
                color=colour,
                alpha=0.1,
            )
    odometry = [
        r[f"{column}_m"]
        for r in results.rows
        if r["sampler"] == "odometry"
        and ("dataset" not in select or r["dataset"] == select["dataset"])
    ]
    finish_axes(ax, odometry, "ATE (m)" if column == "ate" else "RPE (m)", title, legend)
    return ax


def error_curves(
    results: Any, ax: Any, select: Mapping[str, Any] | None, style: str
) -> tuple[Any, dict[str, Any], list[tuple[tuple[str, Any], list[dict[str, Any]]]]]:
    """What a plot of the error against the budget draws: the axes (new ones when ``ax`` is
    None), the selection as a dict, and the summary rows (not the odometry's) that ``select``
    keeps, per (sampler, the value of ``style``), in the order of :data:`SAMPLERS` and
    :data:`BASELINES`, each curve's points by budget."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2))
    select = dict(select or {})
    curves: dict[tuple[str, Any], list[dict[str, Any]]] = {}
    for s in results.summary():
        if s["sampler"] != "odometry" and all(s.get(k) == v for k, v in select.items()):
            curves.setdefault((s["sampler"], s[style]), []).append(s)
    order = {name: k for k, name in enumerate(SAMPLERS + BASELINES)}
    for points in curves.values():
        points.sort(key=lambda s: s["budget"])
    ranked = sorted(curves.items(), key=lambda kv: (order.get(kv[0][0], 99), kv[0][1]))
    return ax, select, ranked


def finish_axes(
    ax: Any, odometry: Sequence[float], ylabel: str, title: str | None, legend: bool
) -> None:
    """Log scales, the odometry alone as a dotted line (the median of ``odometry``, when
    any), the labels, the title, the grid and the legend."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    if odometry:
        level = float(np.median(odometry))
        low, high = ax.get_ylim()
        ax.axhline(level, color="k", ls=":", lw=1, label="odometry alone")
        ax.set_ylim(low, max(high, 1.5 * level))
    ax.set_xlabel("matches tried (budget)")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if legend:
        ax.legend(fontsize=7, ncol=2)
