"""The command line's report and ``inexact_loops.plot`` draw the same component outlines on the
(t, t') plane, because both draw the core's: on one urban drive, the outline paths of the
report's distance figure (report.html) and the outline segments of ``plot.distance_image``, each
brought back to pixel corners, equal the edges ``outline_segments`` gives for the core's label
image on the same grid (the report closes outlines along the border, the plot leaves them open),
and so equal each other inside the image. Either surface deriving labels or outlines on its own
(another label rule, another grid) fails this.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

#: The report's largest image side (crates/loops-cli/src/report/distance.rs, MAX_GRID).
REPORT_PIXELS = 400

Edge = tuple[tuple[int, int], tuple[int, int]]


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path) -> tuple[Path, Path]:
    """A 20 min drive through `loops run`: the log and the report."""
    root = tmp_path_factory.mktemp("surfaces")
    log = root / "drive.mcap"
    subprocess.run([loops_cli, "synth", log, "--duration-s", "1200", "--seed", "5"], check=True)
    out = root / "results"
    run = [loops_cli, "run", log, "--gamma", "40", "--budget", "300", "--out", out]
    subprocess.run(run, check=True, capture_output=True)
    return log, out / log.stem / "report.html"


def unit_edges(start: tuple[int, int], end: tuple[int, int]) -> list[Edge]:
    """The unit edges of the lattice along an axis-parallel segment, each ordered."""
    (x0, y0), (x1, y1) = start, end
    if y0 == y1:
        return [((x, y0), (x + 1, y0)) for x in range(min(x0, x1), max(x0, x1))]
    assert x0 == x1, (start, end)
    return [((x0, y), (x0, y + 1)) for y in range(min(y0, y1), max(y0, y1))]


def report_outline_edges(page: str) -> tuple[set[Edge], float]:
    """The unit edges the report's outline paths draw, in pixel units, and the pixel side."""
    n = r"([-\d.]+)"
    group = re.search(
        rf'<g transform="matrix\({n} 0 0 {n} {n} {n}\)" class="pixels">(.*?)</g>', page, re.S
    )
    assert group, "the distance figure's pixel group"
    cell, flipped, body = float(group.group(1)), float(group.group(2)), group.group(5)
    assert flipped == -cell, "t' upwards"
    edges: set[Edge] = set()
    paths = re.findall(r'<path d="([^"]*)"[^>]*class="outline(?: trivial)?"', body)
    assert paths, "outlines drawn"
    for d in paths:
        at = start = (0, 0)
        for op, a, b in re.findall(r"([Mhvz])(-?\d+)?(?: (-?\d+))?", d):
            if op == "M":
                at = start = (int(a), int(b))
            elif op == "h":
                nxt = (at[0] + int(a), at[1])
                edges.update(unit_edges(at, nxt))
                at = nxt
            elif op == "v":
                nxt = (at[0], at[1] + int(a))
                edges.update(unit_edges(at, nxt))
                at = nxt
            else:
                assert at == start, "closed outlines end where they start"
    return edges, cell


def core_edges(labels: np.ndarray, border: str) -> set[Edge]:
    edges, _ = il.outline_segments(labels, border=border)
    return {((a, b), (c, d)) for (a, b), (c, d) in edges.tolist()}


def test_the_report_and_the_plot_draw_the_cores_outlines(drive: tuple[Path, Path]) -> None:
    plot = pytest.importorskip("inexact_loops.plot")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    log, report = drive
    traj = il.read_trajectory(log)
    loops = il.find_loops(traj, gamma=40.0)
    grid = il.PlaneGrid(loops, REPORT_PIXELS)
    assert grid.width == grid.height == REPORT_PIXELS < len(traj), "a downsampled grid"
    labels = loops.label_image(grid)

    # The report: closed outlines of the core's labels, on a grid of the same size, drawn under
    # the affine map of pixel corners onto the grid's even time edges.
    drawn, cell = report_outline_edges(report.read_text())
    assert round(440.0 / cell) == grid.width
    np.testing.assert_allclose(grid.column_edges_s, np.linspace(0, traj.span_s, grid.width + 1))
    assert drawn == core_edges(labels, "closed")

    # The plot: the same grid (max_pixels), open outlines, in seconds; back to pixel corners.
    ax = plot.distance_image(traj, loops, max_pixels=REPORT_PIXELS)
    (outlines,) = [c for c in ax.collections if isinstance(c, LineCollection)]
    segments = np.asarray(outlines.get_segments())
    x = np.searchsorted(grid.column_edges_s, segments[..., 0])
    y = np.searchsorted(grid.row_edges_s, segments[..., 1])
    np.testing.assert_array_equal(grid.column_edges_s[x], segments[..., 0])
    np.testing.assert_array_equal(grid.row_edges_s[y], segments[..., 1])
    plotted = {
        tuple(sorted(((a, b), (c, d))))
        for (a, c), (b, d) in zip(x.tolist(), y.tolist(), strict=True)
    }
    assert plotted == core_edges(labels, "open")
    plt.close("all")

    # So the two surfaces agree inside the image (the border is where open and closed differ).
    side = grid.width

    def inside(edge: Edge) -> bool:
        (x0, y0), (x1, y1) = edge
        return not ((x0 == x1 and x0 in (0, side)) or (y0 == y1 and y0 in (0, side)))

    assert {e for e in drawn if inside(e)} == plotted
    # A rule of a surface's own would show: the report's former one gives other outlines.
    assert core_edges(runs_claim_pixels(traj, loops, grid.width), "open") != plotted


def runs_claim_pixels(traj: il.Trajectory, loops: il.Loops, m: int) -> np.ndarray:
    """The report's former label rule: every run of S_gamma claims the pixels its cells fall in
    (m pixels evenly over the span), a non-trivial component over a trivial one, then the
    larger area."""
    t = traj.timestamps - traj.timestamps[0]
    pixel = np.minimum((t / t[-1] * m).astype(np.int64), m - 1)
    runs, table = loops.runs(), loops.components
    rank = np.lexsort((table["area_s2"], ~table["trivial"]))
    order = np.argsort(np.argsort(rank)[runs["component"]], kind="stable")
    row, start, end, comp = (
        np.asarray(runs[k])[order] for k in ("row", "start", "end", "component")
    )
    first, last = pixel[start], pixel[end]
    length = last - first + 1
    b = (
        np.repeat(first, length)
        + np.arange(length.sum())
        - np.repeat(np.cumsum(length) - length, length)
    )
    a, c = np.repeat(pixel[row], length), np.repeat(comp, length)
    labels = np.full((m, m), -1, dtype=np.int64)
    labels[b, a] = c  # the last claim wins: runs go in increasing rank
    labels[a, b] = c
    return labels
