"""Plots of inexact loops with matplotlib: the paper's figures for your own trajectories.

Needs matplotlib (``pip install '.[plot]'`` in a checkout); ``import inexact_loops`` does not
import it, ``inexact_loops.plot`` (or ``import inexact_loops.plot``) does.

- :func:`distance_image`: the pairwise distance function pi(t, t') as an image, with gamma
  isocontours, loop component outlines and samples (paper, Figs. 2, 4, 5, 7).
- :func:`trajectory_by_duration`: the trajectory coloured by loop duration tau (Fig. 6d).
- :func:`sample_pairs`: sampled loops drawn as lines between trajectory points (Fig. 6a-c).
- :func:`samples_per_component`: samples per loop component, components sorted by area,
  as a percentage and cumulatively (Fig. 8).
- :func:`overlap_matrix`: a fleet's overlap matrix, alpha between every two sessions, as a heat
  map with the session names on the axes.
- :func:`fleet_trajectories`: a fleet's sessions overlaid, coloured by session, with the places
  where two sessions overlap marked at their closest pairs.

Every function draws into ``ax`` (a new figure when ``None``) and returns the Axes. Times are
seconds from the trajectory's first timestamp.

The maps (:func:`trajectory_by_duration`, :func:`sample_pairs`) draw a plane of two position
axes, ``axes=(a, b)`` with 0 = x, 1 = y, 2 = z (e.g. ``(0, 2)`` for KITTI's ground plane), and
label each axis with its name. A trajectory read on a plane (``read_trajectory(path,
axes=(0, 2))``) remembers it (:attr:`~inexact_loops.Trajectory.plane_axes`): it is drawn and
labelled in that plane by default, and ``axes`` names the same axes of the file.

*Samples* are given as an ``(m, 2)`` integer array of pose index pairs (i, j); a mapping with
``i`` and ``j`` index columns (or ``t`` and ``t_prime`` times in seconds, mapped to the
nearest poses) and optionally ``component``; or an object with such attributes, e.g.
:class:`~inexact_loops.Samples` (from :func:`~inexact_loops.sample`) or
:class:`~inexact_loops.Detections`. Several samplers are passed as a dict
``{name: samples}``; the paper's names ``"alpha"``, ``"rho"`` and ``"one"`` get the paper's
colours and labels, and a :class:`~inexact_loops.Samples` is named by its ``sampler``.

Example:
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np, inexact_loops as il
    >>> from inexact_loops import plot
    >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
    >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
    >>> loops = il.find_loops(traj, gamma=4.0, separation=None)
    >>> ax = plot.distance_image(traj, loops, gamma=[1.0, 4.0])
    >>> ax.get_xlabel()
    't (s)'
    >>> import matplotlib.pyplot as plt; plt.close("all")
"""

from __future__ import annotations

import numbers
import operator
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

try:
    import matplotlib  # noqa: F401  (fail here, with the extra's name, not deep in a call)
except ImportError as err:  # pragma: no cover - exercised only without matplotlib
    raise ImportError(
        "inexact_loops.plot needs matplotlib: install it with "
        "pip install '.[plot]' in a checkout (or pip install matplotlib)"
    ) from err

from . import metrics as _metrics
from ._core import Fleet, FleetLoops, Loops, PlaneGrid, Trajectory, outline_segments, sampler_symbol
from ._core import distance_image as _core_distance_image
from .errors import InvalidParameterError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "PAPER_SAMPLERS",
    "distance_image",
    "fleet_trajectories",
    "overlap_matrix",
    "sample_pairs",
    "samples_per_component",
    "trajectory_by_duration",
]

#: Colour and legend label of the paper's samplers (Figs. 6-8), by sampler name: the core's
#: symbol (:func:`~inexact_loops.sampler_symbol`) and the sampler's order of growth.
PAPER_SAMPLERS: dict[str, tuple[str, str]] = {
    "alpha": ("magenta", f"{sampler_symbol('alpha')} ∈ O(α)"),
    "rho": ("forestgreen", f"{sampler_symbol('rho')} ∈ O(ρ)"),
    "one": ("deepskyblue", f"{sampler_symbol('one')} ∈ O(1)"),
    "rho-dispersed": ("darkorange", sampler_symbol("rho-dispersed")),
}

#: Colours of successive gamma isocontours.
_GAMMA_COLORS = ("#ff7f0e", "white", "#e377c2", "#17becf")

#: A pairwise distance: ``f(A, B)`` -> ``(len(A), len(B))`` distances between point arrays.
PairwiseMetric = Callable[[np.ndarray, np.ndarray], npt.ArrayLike]
#: One sampler's samples; see the module docstring.
SamplesLike = npt.ArrayLike | Mapping[str, npt.ArrayLike] | object
_Side = Literal["both", "begin", "end"]


# --------------------------------------------------------------------------------------------
# Public functions
# --------------------------------------------------------------------------------------------


def distance_image(
    traj: Trajectory,
    loops: Loops | None = None,
    *,
    gamma: float | Sequence[float] | None = None,
    ax: Axes | None = None,
    max_pixels: int = 1000,
    metric: str | _metrics.Metric | PairwiseMetric | None = None,
    samples: SamplesLike | Mapping[str, SamplesLike] | None = None,
    outlines: bool | None = None,
    cmap: str = "viridis",
    colorbar: bool = True,
    distance_unit: str = "m",
    legend: bool = True,
    outline_color: str = "white",
    sample_size: float = 4.0,
    window_s: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> Axes:
    """The pairwise distance function pi(t, t') = delta(xi(t), xi(t')) as an image.

    The image is the core's, as the command line's report draws it: on a
    :class:`~inexact_loops.PlaneGrid` of at most ``max_pixels`` pixels per side (every pose
    when there are fewer; otherwise pixels evenly spaced in time, each showing the pose nearest
    its centre), the distance of each pixel's pair under any metric
    (:func:`~inexact_loops.distance_image`), so it costs O(max_pixels²) whatever the
    trajectory's length. Drawn on it: the gamma isocontours, the outlines of the loop
    components of ``loops`` (each pixel labelled with its pair's component,
    :meth:`~inexact_loops.Loops.label_image`, outlined by
    :func:`~inexact_loops.outline_segments`: with every pose, the lattice of the exact
    components; a component smaller than a pixel may hold no pixel's pair and show no
    outline), and samples as points at (t_i, t_j).

    Args:
        traj: the trajectory.
        loops: the result of :func:`~inexact_loops.find_loops` on ``traj``; gives the
            component outlines and the default ``gamma``.
        gamma: one or more thresholds whose isocontours are drawn; default ``loops.gamma``
            when the outlines are not drawn (they are its isocontour, on the lattice), none
            without ``loops``.
        ax: the Axes to draw into; a new figure when ``None``.
        max_pixels: largest image side, pixels (>= 2).
        metric: ``None`` (the metric of ``loops``; without ``loops``, the trajectory's own,
            :attr:`~inexact_loops.Trajectory.metric_name`), a metric
            name such as ``"so3"`` or an :mod:`inexact_loops.metrics` object, computed by the
            core for any metric; or, a slow path, a callable ``f(A, B)`` returning the
            ``(len(A), len(B))`` distances between two arrays of points (rows of
            ``traj.positions``), e.g. ``scipy.spatial.distance.cdist``.
        samples: samples to overlay (see the module docstring), or ``{name: samples}``.
        outlines: draw component outlines; default: when ``loops`` is given.
        cmap: the image's colormap.
        colorbar: add a colorbar labelled with ``distance_unit``.
        distance_unit: the metric's unit, for the colorbar and the legend (``"m"``, ``"rad"``;
            ``""`` for none).
        legend: add a legend (gamma, outlines, samplers).
        outline_color: colour of the component outlines.
        sample_size: marker size of the samples, points².
        window_s: ``((t_min, t_max), (t_prime_min, t_prime_max))``, seconds from the first
            timestamp: draw only this window (a zoom, with up to ``max_pixels`` per side of
            it); default the whole plane.

    Returns:
        The Axes: x is t, y is t', seconds from the first timestamp.

    Raises:
        TypeError: ``traj`` or ``loops`` of the wrong type, ``metric`` neither a name, a
            metric object nor a callable, ``max_pixels`` not an integer, ``window_s`` not two
            intervals, samples that are not index pairs.
        ValueError: ``loops`` of another trajectory, ``outlines=True`` without ``loops``, loops
            found with a callable metric and no ``metric`` given, a callable returning the
            wrong shape, gamma not positive, ``max_pixels < 2``, an empty or reversed window,
            sample indices out of range, sample times outside the trajectory's span
            (:class:`~inexact_loops.InvalidParameterError` for an unknown metric name, a
            window without poses, or a trajectory the metric cannot take).

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import numpy as np, inexact_loops as il
        >>> from inexact_loops.plot import distance_image
        >>> s = np.linspace(0, 4 * np.pi, 300)  # a circle driven twice
        >>> traj = il.Trajectory(s, 1.05 * np.c_[np.cos(s), np.sin(s)])
        >>> loops = il.find_loops(traj, gamma=1.0, separation=None)
        >>> ax = distance_image(traj, loops, gamma=[1.0, 3.0], samples=np.array([[0, 150]]))
        >>> len(ax.images), len(ax.collections) >= 3  # image; contours, outlines, samples
        (1, True)
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    _check_trajectory(traj)
    if loops is not None:
        _check_loops(loops, traj)
    if outlines is None:
        outlines = loops is not None
    elif outlines and loops is None:
        raise ValueError("outlines=True needs loops (the result of find_loops on traj)")
    gammas = _gammas(gamma, None if outlines else loops)
    if not isinstance(max_pixels, numbers.Integral) or isinstance(max_pixels, bool):
        raise TypeError(f"max_pixels must be an integer, got {type(max_pixels).__name__}")
    if max_pixels < 2:
        raise ValueError(f"max_pixels must be at least 2, got {max_pixels}")
    sample_sets = _named_samples(samples)

    grid = PlaneGrid(
        loops if loops is not None else traj, int(max_pixels), window_s=_window(window_s)
    )
    image = _distance_image(traj, grid, metric, loops)
    x_edges, y_edges = grid.column_edges_s, grid.row_edges_s
    x, y = _centres(x_edges), _centres(y_edges)

    import matplotlib.pyplot as plt
    from matplotlib import patheffects
    from matplotlib.collections import LineCollection
    from matplotlib.image import NonUniformImage
    from matplotlib.lines import Line2D

    ax = _axes(ax)
    extent = (x_edges[0], x_edges[-1], y_edges[0], y_edges[-1])
    picture = NonUniformImage(ax, interpolation="nearest", cmap=cmap, extent=extent)
    picture.set_data(x, y, image)
    ax.add_image(picture)
    ax.set_xlim(x_edges[0], x_edges[-1])
    ax.set_ylim(y_edges[0], y_edges[-1])
    ax.set_aspect("equal")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("t′ (s)")
    unit = f" {distance_unit}" if distance_unit else ""
    if colorbar:
        label = f"π(t, t′) ({distance_unit})" if distance_unit else "π(t, t′)"
        plt.colorbar(picture, ax=ax, label=label, shrink=0.85)

    handles: list[Any] = []
    # A thin dark edge keeps light lines visible on light pixels and in the legend.
    edge = [patheffects.Stroke(linewidth=2.2, foreground="0.1"), patheffects.Normal()]
    if gammas:
        colors = [_GAMMA_COLORS[k % len(_GAMMA_COLORS)] for k in range(len(gammas))]
        drawn = sorted(set(gammas))
        if min(image.shape) >= 2 and image.min() < drawn[-1] and image.max() > drawn[0]:
            contours = ax.contour(
                x,
                y,
                image,
                levels=drawn,
                linewidths=1.2,
                colors=[colors[gammas.index(g)] for g in drawn],
            )
            contours.set(path_effects=edge)
        for k, g in enumerate(gammas):
            handles.append(
                Line2D([], [], color=colors[k], lw=1.2, path_effects=edge, label=f"γ = {g:g}{unit}")
            )
    if outlines:
        assert loops is not None
        # Pixel corners (pixel units) to seconds: corner k of an axis is its k-th pixel edge.
        edges, _ = outline_segments(loops.label_image(grid), border="open")
        segments = np.stack([x_edges[edges[..., 0]], y_edges[edges[..., 1]]], axis=-1)
        ax.add_collection(
            LineCollection(segments, colors=outline_color, linewidths=0.8, path_effects=edge)
        )
        handles.append(
            Line2D(
                [],
                [],
                color=outline_color,
                lw=0.8,
                path_effects=edge,
                label=f"components (γ = {loops.gamma:g}{unit})",
            )
        )
    timestamps = traj.timestamps
    for k, (name, value) in enumerate(sample_sets):
        i, j = _sample_pairs(value, len(traj), traj)
        color, label = _sampler_style(name, k)
        t0 = timestamps[0]
        ax.scatter(
            timestamps[i] - t0,
            timestamps[j] - t0,
            s=sample_size,
            color=color,
            label=label,
            linewidths=0,
            zorder=3,
        )
        handles.append(Line2D([], [], color=color, marker="o", ls="none", label=label))
    if legend and handles:
        _legend_above(ax, handles=handles)
    return ax


def trajectory_by_duration(
    traj: Trajectory,
    loops: Loops,
    *,
    ax: Axes | None = None,
    side: _Side = "both",
    components: list[int] | None = None,
    normalized: bool = False,
    axes: tuple[int, int] | None = None,
    cmap: str = "viridis",
    linewidth: float = 1.5,
    colorbar: bool = True,
    position_unit: str = "m",
) -> Axes:
    """The trajectory's path coloured by loop duration tau(t) (paper, Eq. 6 and Fig. 6d).

    Each segment between consecutive poses takes the mean tau of its two ends; segments are
    drawn in increasing tau, so where the path passes several times the longest loop duration
    shows.

    Args:
        traj: the trajectory; two position axes are drawn.
        loops: the result of :func:`~inexact_loops.find_loops` on ``traj``.
        ax: the Axes to draw into; a new figure when ``None``.
        side, components, normalized: as :meth:`Loops.loop_duration`.
        axes: the plane drawn, two position axes across and up (e.g. ``(0, 2)`` for KITTI's x-z
            ground plane), labelled with their names; by default the plane ``traj`` was read
            on (:attr:`~inexact_loops.Trajectory.plane_axes`), else x-y.
        cmap: the colormap of tau.
        linewidth: line width, points.
        colorbar: add a colorbar of tau.
        position_unit: unit of the coordinates, for the axis labels.

    Returns:
        The Axes, equal aspect, with one LineCollection.

    Raises:
        TypeError: ``traj`` or ``loops`` of the wrong type.
        ValueError: ``loops`` of another trajectory, ``axes`` not two axes ``traj`` holds.
        InvalidParameterError: a bad ``side`` or component id (from :meth:`Loops.loop_duration`).

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import inexact_loops as il
        >>> from inexact_loops.plot import trajectory_by_duration
        >>> traj = il.urban_drive(duration_s=300.0, seed=1)
        >>> loops = il.find_loops(traj, gamma=40.0, separation=None)
        >>> ax = trajectory_by_duration(traj, loops, side="begin")
        >>> len(ax.collections)
        1
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    _check_trajectory(traj)
    _check_loops(loops, traj)
    xy, names = _plane(traj, axes)
    tau = loops.loop_duration(side=side, components=components, normalized=normalized)

    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    ax = _axes(ax)
    segment_tau = (tau[:-1] + tau[1:]) / 2
    order = np.argsort(segment_tau, kind="stable")
    segments = np.stack([xy[:-1], xy[1:]], axis=1)[order]
    lines = LineCollection(segments, cmap=cmap, linewidths=linewidth, capstyle="round")
    lines.set_array(segment_tau[order])
    lines.set_clim(0.0, max(float(tau.max()), np.finfo(float).tiny))
    ax.add_collection(lines)
    _frame(ax, xy, names, position_unit)
    if colorbar:
        unit = "fraction of the span" if normalized else "s"
        what = {"both": "τ", "begin": "τ (loops that begin)", "end": "τ (loops that end)"}
        label = f"loop duration {what.get(side, 'τ')} ({unit})"
        plt.colorbar(lines, ax=ax, label=label, shrink=0.85)
    return ax


def sample_pairs(
    traj: Trajectory,
    samples: SamplesLike | Mapping[str, SamplesLike],
    *,
    ax: Axes | None = None,
    axes: tuple[int, int] | None = None,
    color: str | None = None,
    trajectory_color: str = "0.65",
    linewidth: float = 0.6,
    alpha: float = 0.6,
    legend: bool = True,
    position_unit: str = "m",
) -> Axes:
    """Sampled loops drawn as straight lines between their two trajectory points (Fig. 6).

    Args:
        traj: the trajectory, drawn underneath in ``trajectory_color``.
        samples: the samples (see the module docstring), or ``{name: samples}`` for several
            samplers, each in its colour.
        ax: the Axes to draw into; a new figure when ``None``.
        axes: the plane drawn, as in :func:`trajectory_by_duration`.
        color: colour of the sample lines for a single sampler (default from its name).
        trajectory_color: colour of the path.
        linewidth: width of the sample lines, points.
        alpha: opacity of the sample lines.
        legend: add a legend naming the samplers.
        position_unit: unit of the coordinates, for the axis labels.

    Returns:
        The Axes: the path (one line), and per sampler one LineCollection of samples and one
        collection of dots at their ends (so that pairs shorter than a line width show).

    Raises:
        TypeError: ``traj`` not a Trajectory; samples that are not index pairs.
        ValueError: sample indices out of range; ``axes`` not two axes ``traj`` holds.

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import numpy as np, inexact_loops as il
        >>> from inexact_loops.plot import sample_pairs
        >>> s = np.linspace(0, 2 * np.pi, 100)
        >>> traj = il.Trajectory(s, np.c_[np.cos(s), np.sin(s)])
        >>> ax = sample_pairs(traj, {"rho": np.array([[0, 99], [1, 98]]), "one": [[2, 97]]})
        >>> len(ax.lines), len(ax.collections)
        (1, 4)
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    _check_trajectory(traj)
    xy, names = _plane(traj, axes)
    sample_sets = _named_samples(samples)
    if not sample_sets:
        raise ValueError("no samples given")

    from matplotlib.collections import LineCollection

    ax = _axes(ax)
    ax.plot(xy[:, 0], xy[:, 1], color=trajectory_color, lw=0.8, zorder=1, label="trajectory")
    for k, (name, value) in enumerate(sample_sets):
        i, j = _sample_pairs(value, len(traj), traj)
        default_color, label = _sampler_style(name, k)
        line_color = color if (color is not None and len(sample_sets) == 1) else default_color
        segments = np.stack([xy[i], xy[j]], axis=1)
        ax.add_collection(
            LineCollection(
                segments,
                colors=line_color,
                linewidths=linewidth,
                alpha=alpha,
                zorder=2,
                label=f"{label} ({len(i)})",
            )
        )
        # A dot at both ends: a pair whose poses lie within a line width of each other (a
        # revisit found at its closest) is a dot, not an invisible line.
        ends = np.concatenate([xy[i], xy[j]])
        ax.scatter(
            ends[:, 0],
            ends[:, 1],
            s=(2.5 * linewidth) ** 2,
            color=line_color,
            alpha=alpha,
            zorder=2,
        )
    _frame(ax, xy, names, position_unit)
    if legend:
        _legend_above(ax)
    return ax


def samples_per_component(
    loops: Loops,
    samples_by_sampler: Mapping[str, SamplesLike],
    *,
    axes: tuple[Axes, Axes] | None = None,
    available: npt.ArrayLike | None = None,
    include_trivial: bool = False,
    log_scale: bool = True,
) -> tuple[Axes, Axes]:
    """Samples per loop component by sampler, components sorted by area (paper, Fig. 8).

    Top: the percentage of each component's available pairs that a sampler kept; components it
    missed (P1) are ticks along the foot of the axes. Bottom: the cumulative number of
    samples, summed over the components from the smallest up: a sampler that oversamples
    large components climbs steeply on the right.

    Args:
        loops: the result of :func:`~inexact_loops.find_loops`; its components are the x axis.
        samples_by_sampler: ``{name: samples}`` (see the module docstring). A sample's
            component is the ``component`` column of a mapping when given, otherwise the
            component of its pair (i, j) in ``loops``; samples outside S_gamma are not counted.
        axes: two Axes (top, bottom); a new figure with two rows when ``None``.
        available: what the samplers chose from, per component: the detections they were
            drawn from (any samples-like value, e.g. :class:`~inexact_loops.Detections`, as in
            the paper), or a count per component id; default ``loops.components["pair_count"]``,
            the pairs of S_gamma (the half t <= t' of a non-trivial component).
        include_trivial: count the trivial components (simple loops) too.
        log_scale: a logarithmic percentage axis (the percentages span orders of magnitude).

    Returns:
        The two Axes (top, bottom).

    Raises:
        TypeError: ``loops`` not a Loops, samples that are not index pairs.
        ValueError: no samplers, ``available`` of the wrong length, ``axes`` not two Axes,
            component ids out of range, no component to show.

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import numpy as np, inexact_loops as il
        >>> from inexact_loops.plot import samples_per_component
        >>> s = np.linspace(0, 4 * np.pi, 300)
        >>> traj = il.Trajectory(s, 1.05 * np.c_[np.cos(s), np.sin(s)])
        >>> loops = il.find_loops(traj, gamma=1.0, separation=None)
        >>> top, bottom = samples_per_component(loops, {"one": [[0, 150], [0, 299]]})
        >>> len(top.lines), len(bottom.lines)
        (1, 1)
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    if not isinstance(loops, Loops):
        raise TypeError(f"loops must be an inexact_loops.Loops, got {type(loops).__name__}")
    sample_sets = _named_samples(samples_by_sampler)
    if not sample_sets:
        raise ValueError("samples_by_sampler is empty")
    table = loops.components
    k = len(table["id"])
    if available is None:
        pool = np.asarray(table["pair_count"], dtype=float)
    elif isinstance(available, (np.ndarray, list, tuple)) and np.ndim(available) == 1:
        pool = np.asarray(available, dtype=float)
        if pool.shape != (k,):
            raise ValueError(
                f"available must have one value per component ({k}), got shape {pool.shape}"
            )
    else:
        pool = _counts_per_component(available, loops, k)
    shown = np.ones(k, dtype=bool) if include_trivial else ~np.asarray(table["trivial"])
    shown &= pool > 0
    if not shown.any():
        raise ValueError("no loop component to show (all trivial or without available pairs)")
    order = np.flatnonzero(shown)[np.argsort(table["area_s2"][shown], kind="stable")]
    rank = np.arange(1, len(order) + 1)

    if axes is None:
        import matplotlib.pyplot as plt

        _, pair = plt.subplots(2, 1, sharex=True, figsize=(8.0, 6.4), constrained_layout=True)
        top, bottom = pair[0], pair[1]
    else:
        if len(axes) != 2:
            raise ValueError(f"axes must be two Axes (top, bottom), got {len(axes)}")
        top, bottom = axes

    missed = []
    for index, (name, value) in enumerate(sample_sets):
        counts = _counts_per_component(value, loops, k)
        color, label = _sampler_style(name, index)
        kept = counts[order]
        percent = 100.0 * kept / pool[order]
        total = int(kept.sum())
        covered = int((kept > 0).sum())
        top.plot(
            rank,
            np.where(percent > 0, percent, np.nan),
            ".",
            ms=3,
            color=color,
            label=f"{label}: {total} samples in {covered}/{len(order)} components",
        )
        bottom.step(rank, np.cumsum(kept), where="post", color=color, lw=1.4, label=label)
        missed.append((rank[kept == 0], color))
    # Components a sampler missed (P1), as ticks along the bottom of the top axes.
    blend = top.get_xaxis_transform()
    for index, (where, color) in enumerate(missed):
        if len(where):
            top.plot(
                where,
                np.full(len(where), 0.03 + 0.04 * index),
                "|",
                ms=6,
                mew=1.2,
                color=color,
                transform=blend,
                clip_on=False,
            )
    handles, _ = top.get_legend_handles_labels()
    if any(len(where) for where, _ in missed):
        from matplotlib.lines import Line2D

        handles.append(
            Line2D(
                [],
                [],
                color="0.3",
                marker="|",
                ls="none",
                ms=6,
                mew=1.2,
                label="ticks: components without a sample",
            )
        )
    if log_scale:
        top.set_yscale("log")
    bottom.set_ylim(bottom=0)
    what = "detections" if available is not None else "pairs"
    top.set_ylabel(f"samples / {what} (%)")
    bottom.set_ylabel("cumulative samples")
    bottom.set_xlabel("loop components, sorted by area (smallest → largest)")
    top.legend(handles=handles, loc="upper right", fontsize="small", framealpha=0.8)
    for a in (top, bottom):
        a.grid(True, which="major", alpha=0.3)
        a.set_xlim(0.5, len(order) + 0.5)
    return top, bottom


def overlap_matrix(
    loops: FleetLoops,
    *,
    ax: Axes | None = None,
    cmap: str = "magma_r",
    log_scale: bool = True,
    diagonal: bool = True,
    colorbar: bool = True,
    max_labels: int = 40,
) -> Axes:
    """A fleet's overlap matrix as a heat map: the loop area alpha(a, b) between every two
    sessions (:meth:`~inexact_loops.FleetLoops.overlap_matrix`, s²), session names on both
    axes in the fleet's order. Session pairs that never come within gamma are left blank.

    Args:
        loops: the result of :func:`~inexact_loops.find_fleet_loops`.
        ax: the Axes to draw into; a new figure when ``None``.
        cmap: the colormap of alpha.
        log_scale: colour by log alpha (overlaps span orders of magnitude).
        diagonal: show each session's alpha alone on the diagonal; ``False`` leaves it blank
            (it often dwarfs the overlaps between sessions).
        colorbar: add a colorbar of alpha.
        max_labels: name every session on the axes when there are at most this many;
            otherwise ticks are thinned to about this many.

    Returns:
        The Axes: one image, row a and column b the sessions' alpha (symmetric).

    Raises:
        TypeError: ``loops`` not a FleetLoops.

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import inexact_loops as il
        >>> from inexact_loops.plot import overlap_matrix
        >>> fleet = il.urban_fleet(vehicles=4, duration_s=300.0, seed=2)
        >>> ax = overlap_matrix(il.find_fleet_loops(fleet, gamma=20.0))
        >>> [label.get_text() for label in ax.get_xticklabels()][:2]
        ['car0-day0', 'car1-day0']
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    if not isinstance(loops, FleetLoops):
        raise TypeError(f"loops must be an inexact_loops.FleetLoops, got {type(loops).__name__}")
    names = loops.names
    n = len(names)
    alpha = np.asarray(loops.overlap_matrix(), dtype=float)
    blank = alpha <= 0
    if not diagonal:
        blank |= np.eye(n, dtype=bool)
    shown = np.ma.masked_array(alpha, mask=blank)

    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm, Normalize

    ax = _axes(ax)
    values = alpha[~blank]
    if log_scale and len(values):
        norm: Normalize = LogNorm(vmin=float(values.min()), vmax=float(values.max()))
    else:
        norm = Normalize(vmin=0.0, vmax=float(values.max()) if len(values) else 1.0)
    colormap = plt.get_cmap(cmap).with_extremes(bad="white")
    image = ax.imshow(shown, cmap=colormap, norm=norm, interpolation="nearest", origin="upper")
    step = max(1, int(np.ceil(n / max(int(max_labels), 1))))
    ticks = np.arange(0, n, step)
    ax.set_xticks(ticks, [names[k] for k in ticks], rotation=90, fontsize="small")
    ax.set_yticks(ticks, [names[k] for k in ticks], fontsize="small")
    ax.set_xlabel("session b")
    ax.set_ylabel("session a")
    if colorbar:
        plt.colorbar(image, ax=ax, label="overlap α (s²)", shrink=0.85)
    return ax


def fleet_trajectories(
    fleet: Fleet,
    loops: FleetLoops | None = None,
    *,
    ax: Axes | None = None,
    axes: tuple[int, int] | None = None,
    cmap: str | None = None,
    linewidth: float = 1.0,
    marker_color: str = "black",
    marker_size: float = 36.0,
    legend: bool | None = None,
    position_unit: str = "m",
) -> Axes:
    """A fleet's sessions overlaid in one plane, each in its own colour; with ``loops``, every
    loop component between two sessions marked at its closest pair: a cross midway between
    the two poses and a line joining them.

    Args:
        fleet: the :class:`~inexact_loops.Fleet`.
        loops: the result of :func:`~inexact_loops.find_fleet_loops` on ``fleet``, or ``None``
            for the paths alone.
        ax: the Axes to draw into; a new figure when ``None``.
        axes: the plane drawn, as in :func:`trajectory_by_duration` (default: the plane the
            sessions were read on, else x-y).
        cmap: the colormap the sessions' colours are drawn from; default ``"tab10"`` up to 10
            sessions, ``"tab20"`` up to 20, else ``"turbo"``.
        linewidth: width of the paths, points.
        marker_color: colour of the marks of the components between sessions.
        marker_size: size of those marks, points².
        legend: name the sessions (and the marks) in a legend; default when there are at most
            12 sessions.
        position_unit: unit of the coordinates, for the axis labels.

    Returns:
        The Axes: one line per session, then (with ``loops``) a LineCollection of closest
        pairs and the marks.

    Raises:
        TypeError: ``fleet`` or ``loops`` of the wrong type.
        ValueError: ``loops`` of another fleet; ``axes`` not two axes the sessions hold.

    Example:
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import inexact_loops as il
        >>> from inexact_loops.plot import fleet_trajectories
        >>> fleet = il.urban_fleet(vehicles=3, duration_s=300.0, seed=2)
        >>> ax = fleet_trajectories(fleet, il.find_fleet_loops(fleet, gamma=20.0))
        >>> len(ax.lines), ax.get_legend().get_texts()[0].get_text()
        (3, 'car0-day0')
        >>> import matplotlib.pyplot as plt; plt.close("all")
    """
    if not isinstance(fleet, Fleet):
        raise TypeError(f"fleet must be an inexact_loops.Fleet, got {type(fleet).__name__}")
    if loops is not None:
        if not isinstance(loops, FleetLoops):
            raise TypeError(
                f"loops must be an inexact_loops.FleetLoops, got {type(loops).__name__}"
            )
        if loops.names != fleet.names or loops.fleet.poses != fleet.poses:
            raise ValueError(
                "loops were found on another fleet: "
                "pass the result of find_fleet_loops on this fleet"
            )
    n = len(fleet)
    planes = [_plane(fleet.session(a), axes) for a in range(n)]
    names = planes[0][1]

    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    if cmap is None:
        cmap = "tab10" if n <= 10 else "tab20" if n <= 20 else "turbo"
    colormap = plt.get_cmap(cmap)
    qualitative = getattr(colormap, "N", 256) <= 20
    colors = [
        colormap(a % colormap.N) if qualitative else colormap(a / max(n - 1, 1)) for a in range(n)
    ]

    ax = _axes(ax)
    for a, (xy, _) in enumerate(planes):
        ax.plot(xy[:, 0], xy[:, 1], color=colors[a], lw=linewidth, label=fleet.names[a], zorder=1)
    handles: list[Any] = []
    if loops is not None:
        table = loops.components
        between = table["session_a"] != table["session_b"]
        a, b = table["session_a"][between], table["session_b"][between]
        i, j = table["closest_i"][between], table["closest_j"][between]
        first = np.array([planes[s][0][p] for s, p in zip(a, i, strict=True)]).reshape(-1, 2)
        second = np.array([planes[s][0][p] for s, p in zip(b, j, strict=True)]).reshape(-1, 2)
        ax.add_collection(
            LineCollection(
                np.stack([first, second], axis=1), colors=marker_color, linewidths=1.0, zorder=3
            )
        )
        middle = (first + second) / 2
        ax.scatter(
            middle[:, 0],
            middle[:, 1],
            s=marker_size,
            marker="x",
            color=marker_color,
            linewidths=1.2,
            zorder=4,
        )
        handles.append(
            Line2D(
                [],
                [],
                color=marker_color,
                marker="x",
                ls="none",
                label=f"between sessions ({len(middle)} components, γ = {loops.gamma:g})",
            )
        )
    _frame(ax, np.concatenate([xy for xy, _ in planes]), names, position_unit)
    if legend is None:
        legend = n <= 12
    if legend:
        lines, _ = ax.get_legend_handles_labels()
        _legend_above(ax, handles=[*lines, *handles])
    return ax


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def _check_trajectory(traj: object) -> None:
    if not isinstance(traj, Trajectory):
        raise TypeError(f"traj must be an inexact_loops.Trajectory, got {type(traj).__name__}")


def _check_loops(loops: object, traj: Trajectory) -> None:
    if not isinstance(loops, Loops):
        raise TypeError(f"loops must be an inexact_loops.Loops, got {type(loops).__name__}")
    if len(loops) != len(traj):
        raise ValueError(
            f"loops has {len(loops)} poses but the trajectory {len(traj)}: "
            "pass the result of find_loops on this trajectory"
        )


def _legend_above(ax: Axes, **handles: Any) -> None:
    """The legend in two columns above the axes, outside the data."""
    ax.legend(
        **handles,
        loc="lower left",
        bbox_to_anchor=(0.0, 1.01),
        ncol=2,
        fontsize="small",
        frameon=False,
        borderaxespad=0.0,
    )


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, new = plt.subplots(constrained_layout=True)
    return new


def _gammas(gamma: float | Sequence[float] | None, loops: Loops | None) -> list[float]:
    if gamma is None:
        return [loops.gamma] if loops is not None else []
    values = [gamma] if isinstance(gamma, numbers.Real) else list(gamma)
    out = []
    for g in values:
        if not isinstance(g, numbers.Real) or isinstance(g, bool):
            raise TypeError(f"gamma must be a number or a sequence of numbers, got {g!r}")
        if not (np.isfinite(g) and g > 0):
            raise ValueError(f"gamma must be positive and finite, got {g}")
        out.append(float(g))
    return out


def _distance_image(
    traj: Trajectory, grid: PlaneGrid, metric: object, loops: Loops | None
) -> np.ndarray:
    """The image ``(height, width)``: by the core for a metric name or object (default the
    loops' metric, else the trajectory's), or the slow path, a callable ``f(A, B)`` on the
    grid's points."""
    if metric is None or isinstance(metric, (str, _metrics.Metric)):
        name = loops.metric_name if (metric is None and loops is not None) else metric
        try:
            return _core_distance_image(traj, grid, metric=name)
        except InvalidParameterError as err:
            if metric is None and loops is not None and "metric" in str(err):
                raise ValueError(
                    f"these loops use the metric {loops.metric_name!r}, which is not one the "
                    "library knows by name: pass metric=f(A, B) returning the pairwise "
                    "distances between two arrays of points"
                ) from err
            raise
    if callable(metric):
        positions = traj.positions
        image = np.asarray(metric(positions[grid.rows], positions[grid.columns]), dtype=float)
        if image.shape != (grid.height, grid.width):
            raise ValueError(
                f"metric returned shape {image.shape}, expected {(grid.height, grid.width)}: "
                "it must give the pairwise distances between two arrays of points"
            )
        return image
    raise TypeError(
        "metric must be None, a metric name or inexact_loops.metrics object, or a callable "
        f"f(A, B), got {type(metric).__name__}"
    )


def _window(
    window_s: tuple[tuple[float, float], tuple[float, float]] | None,
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """((t_lo, t_hi), (t'_lo, t'_hi)) in seconds from the first timestamp, as floats."""
    if window_s is None:
        return None
    try:
        (a, b), (c, d) = window_s
        box = (float(a), float(b)), (float(c), float(d))
    except (TypeError, ValueError) as err:
        raise TypeError(
            f"window_s must be ((t_min, t_max), (t_prime_min, t_prime_max)), got {window_s!r}"
        ) from err
    for lo, hi in box:
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"window_s: each interval must be finite with min < max, got {box}")
    return box


def _centres(edges: np.ndarray) -> np.ndarray:
    """Pixel centres whose midpoints are the pixels' ``edges`` (NonUniformImage puts a pixel's
    boundaries midway between centres): the poses' times on an axis of every pose, the middle
    of each even step on a downsampled one."""
    centres = np.empty(len(edges) - 1)
    centres[0] = (edges[0] + edges[1]) / 2
    for k in range(1, len(centres)):
        centres[k] = 2 * edges[k] - centres[k - 1]
    return centres


def _axis_name(axis: int) -> str:
    """A position axis by name: x, y, z, then x3, x4, ..."""
    return "xyz"[axis] if axis < 3 else f"x{axis}"


def _plane(traj: Trajectory, axes: tuple[int, int] | None) -> tuple[np.ndarray, list[str]]:
    """The points of the plane ``axes`` (position axes), shape ``(n, 2)``, and the axes' names.

    A trajectory read on a plane holds only that plane's axes, as its first two coordinates.
    """
    plane = traj.plane_axes
    if axes is None:
        axes = plane if plane is not None else (0, 1)
    try:
        a, b = (operator.index(k) for k in axes)
    except (TypeError, ValueError) as err:
        raise ValueError(
            f"axes must be two position axes (0 = x, 1 = y, 2 = z), got {axes!r}"
        ) from err
    if plane is not None:
        held = {plane[0]: 0, plane[1]: 1}
        if a not in held or b not in held or a == b:
            names = "-".join(_axis_name(k) for k in plane)
            raise ValueError(
                f"axes must be two different axes of the plane {names} {tuple(plane)!r} this "
                f"trajectory was read on, got {axes!r}: read it with axes={axes!r} (or none) to "
                "draw another plane"
            )
        return traj.positions[:, [held[a], held[b]]], [_axis_name(a), _axis_name(b)]
    if not (0 <= a < traj.dim and 0 <= b < traj.dim) or a == b:
        raise ValueError(
            f"axes must be two different coordinates of the {traj.dim}-dimensional "
            f"positions, got {axes!r}"
        )
    return traj.positions[:, [a, b]], [_axis_name(a), _axis_name(b)]


def _frame(ax: Axes, xy: np.ndarray, names: list[str], unit: str) -> None:
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.03 * max(float((hi - lo).max()), 1e-9)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{names[0]} ({unit})")
    ax.set_ylabel(f"{names[1]} ({unit})")


def _sampler_style(name: str | None, index: int) -> tuple[str, str]:
    """Colour and label: the paper's for its samplers, else the core's symbol of a sampler it
    knows (``"lio-sam"``: LIO-SAM), else the name given."""
    if name is not None and name in PAPER_SAMPLERS:
        return PAPER_SAMPLERS[name]
    color = f"C{index % 10}"
    if name is None:
        return color, "samples"
    try:
        return color, sampler_symbol(name)
    except InvalidParameterError:
        return color, name


_INDEX_KEYS = ("i", "j")
_TIME_KEYS = (("t", "t_prime"), ("t_s", "t_prime_s"))


def _looks_like_samples(value: Mapping[Any, Any]) -> bool:
    """Whether a mapping is one sampler's columns rather than ``{name: samples}``."""
    keys = [_INDEX_KEYS, *_TIME_KEYS]
    return any(all(key in value for key in pair) for pair in keys)


def _named_samples(samples: object) -> list[tuple[str | None, object]]:
    """``[(name, samples), ...]`` from one sampler's samples or a dict of them."""
    if samples is None:
        return []
    if isinstance(samples, Mapping) and not _looks_like_samples(samples):
        for key in samples:
            if not isinstance(key, str):
                raise TypeError(f"sampler names must be strings, got {key!r}")
        return list(samples.items())
    name = getattr(samples, "sampler", None)
    return [(name if isinstance(name, str) else None, samples)]


def _field(samples: object, key: str) -> Any:
    """A column of a mapping or an attribute of a samples object (``None`` when absent)."""
    if isinstance(samples, Mapping):
        return samples.get(key)
    if isinstance(samples, (np.ndarray, list, tuple)):
        return None
    return getattr(samples, key, None)


def _sample_pairs(
    samples: object, n: int, traj: Trajectory | None
) -> tuple[np.ndarray, np.ndarray]:
    """Pose indices (i, j) of one sampler's samples, checked against ``n`` poses.

    From ``i`` and ``j`` columns (or attributes), else from ``t`` and ``t_prime`` times mapped
    to the nearest poses of ``traj`` (:meth:`~inexact_loops.Trajectory.nearest_poses`), else
    from an (m, 2) integer array."""
    i, j = _field(samples, "i"), _field(samples, "j")
    if i is not None and j is not None:
        i, j = _indices(i, "i"), _indices(j, "j")
    else:
        times = next(
            (
                (_field(samples, a), _field(samples, b))
                for a, b in _TIME_KEYS
                if _field(samples, a) is not None and _field(samples, b) is not None
            ),
            None,
        )
        if times is not None:
            if traj is None:
                raise ValueError(
                    "samples have times but no pose indices: place them on the trajectory "
                    "first (e.g. samples.locate(loops))"
                )
            i = traj.nearest_poses(np.asarray(times[0], dtype=float).ravel())
            j = traj.nearest_poses(np.asarray(times[1], dtype=float).ravel())
        elif isinstance(samples, Mapping) or not isinstance(samples, (np.ndarray, list, tuple)):
            raise TypeError(
                "samples must be an (m, 2) array of pose index pairs, or have 'i' and 'j' (pose "
                "indices) or 't' and 't_prime' (seconds) columns; got "
                f"{type(samples).__name__}"
            )
        else:
            pairs = np.asarray(samples)
            if pairs.size == 0:
                pairs = pairs.reshape(0, 2)
            if pairs.ndim != 2 or pairs.shape[1] != 2:
                raise TypeError(
                    f"samples must be an (m, 2) array of pose index pairs, got shape {pairs.shape}"
                )
            i, j = _indices(pairs[:, 0], "i"), _indices(pairs[:, 1], "j")
    if len(i) != len(j):
        raise ValueError(f"samples: {len(i)} values of i but {len(j)} of j")
    for name, values in (("i", i), ("j", j)):
        if len(values) and (values.min() < 0 or values.max() >= n):
            raise ValueError(f"samples: {name} out of range for a trajectory of {n} poses")
    return i, j


def _indices(values: object, name: str) -> np.ndarray:
    array = np.asarray(values)
    if array.size == 0:
        return np.zeros(0, dtype=np.int64)
    if array.dtype.kind not in "iu":
        raise TypeError(f"samples: {name} must be integer pose indices, got dtype {array.dtype}")
    return array.astype(np.int64).ravel()


def _counts_per_component(samples: object, loops: Loops, k: int) -> np.ndarray:
    """Number of samples in each component id (samples outside S_gamma are not counted).

    A mapping's ``component`` column is used as given; otherwise the core counts the pairs
    (i, j) per component (:meth:`~inexact_loops.Loops.pair_counts_per_component`)."""
    given = samples.get("component") if isinstance(samples, Mapping) else None
    if given is not None:
        component = np.asarray(given)
        if component.size and component.dtype.kind not in "iu":
            raise TypeError(f"samples: component ids must be integers, got {component.dtype}")
        component = component.astype(np.int64).ravel()
    else:
        i, j = _sample_pairs(samples, len(loops), None)
        return loops.pair_counts_per_component(i, j).astype(float)
    inside = component[component >= 0]
    if len(inside) and inside.max() >= k:
        raise ValueError(f"samples: component id {inside.max()} out of range ({k} components)")
    return np.bincount(inside, minlength=k).astype(float)
