"""inexact_loops.plot and examples/paper_figures.py: every plot function on small inputs, its
error cases, and the example script run end to end (each PNG written and not blank).

The drawn data are checked against independent computations: distances from scipy's
``cdist``, loop durations and component boundaries from a dense matrix labelled by
``scipy.ndimage.label``.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip(
    "matplotlib", reason="matplotlib is not installed: pip install '.[plot]' in a checkout"
)
matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PathCollection  # noqa: E402
from scipy import ndimage  # noqa: E402
from scipy.spatial.distance import cdist  # noqa: E402

import inexact_loops as il  # noqa: E402
from inexact_loops import plot  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "paper_figures.py"


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def double_loop(n_per_lap: int = 90) -> tuple[np.ndarray, np.ndarray]:
    """A circle of radius 1.05 m driven twice: S_gamma at gamma = 1 has a trivial band and two
    non-trivial components."""
    n = 2 * n_per_lap + 1
    angle = np.arange(n) * 2 * np.pi / n_per_lap
    return np.arange(n) * 0.1, 1.05 * np.c_[np.cos(angle), np.sin(angle)]


@pytest.fixture
def loop2():
    t, p = double_loop()
    traj = il.Trajectory(t, p)
    return traj, il.find_loops(traj, gamma=1.0, separation=None)


def cell_widths(t: np.ndarray) -> np.ndarray:
    steps = np.diff(t)
    return np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2


def line_collections(ax) -> list[LineCollection]:
    return [c for c in ax.collections if isinstance(c, LineCollection)]


def boundary_edges(labels: np.ndarray) -> int:
    """Pixel edges between cells of different labels (the border continues the outer pixels)."""
    padded = np.pad(labels, 1, mode="edge")
    vertical = padded[1:-1, :-1] != padded[1:-1, 1:]
    horizontal = padded[:-1, 1:-1] != padded[1:, 1:-1]
    return int(vertical.sum() + horizontal.sum())


# --------------------------------------------------------------------------------------------
# distance_image
# --------------------------------------------------------------------------------------------


def test_distance_image_draws_the_distances_isocontours_outlines_and_samples(loop2):
    traj, loops = loop2
    t, p = traj.timestamps, traj.positions
    ax = plot.distance_image(traj, loops, gamma=[1.0, 1.5], samples=np.array([[0, 90], [3, 95]]))
    assert len(ax.images) == 1
    image = np.asarray(ax.images[0].get_array())
    np.testing.assert_allclose(image, cdist(p, p), atol=1e-12)  # every pose: n < max_pixels
    assert ax.get_xlabel() == "t (s)" and ax.get_ylabel() == "t′ (s)"
    assert ax.get_xlim() == pytest.approx((-0.05, t[-1] + 0.05))
    assert len(ax.figure.axes) == 2, "a colorbar"
    assert "π(t, t′) (m)" in ax.figure.axes[1].get_ylabel()
    # Outlines: one segment per pixel edge between different components (or S_gamma and
    # its complement), as scipy labels the dense matrix.
    labels, _ = ndimage.label(cdist(p, p) <= 1.0)
    outlines = line_collections(ax)
    assert len(outlines) == 1
    assert len(outlines[0].get_segments()) == boundary_edges(labels)
    # Samples at (t_i, t_j).
    points = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert len(points) == 1
    np.testing.assert_allclose(points[0].get_offsets(), [[t[0], t[90]], [t[3], t[95]]])
    # The gamma isocontours (one ContourSet with both levels) and the legend.
    contours = [c for c in ax.collections if hasattr(c, "levels")]
    assert len(contours) == 1 and list(contours[0].levels) == [1.0, 1.5]
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert legend == ["γ = 1 m", "γ = 1.5 m", "components (γ = 1 m)", "samples"]


def test_distance_image_defaults(loop2):
    traj, loops = loop2
    ax = plot.distance_image(traj)  # no loops: the image only
    assert len(ax.images) == 1 and not ax.collections and ax.get_legend() is None
    ax = plot.distance_image(traj, gamma=1.0, colorbar=False, legend=False)
    assert len(ax.figure.axes) == 1 and ax.get_legend() is None
    assert len([c for c in ax.collections if hasattr(c, "levels")]) == 1
    ax = plot.distance_image(traj, loops, outlines=False)  # the loops' gamma as a contour
    assert [list(c.levels) for c in ax.collections if hasattr(c, "levels")] == [[1.0]]
    ax = plot.distance_image(traj, loops)  # outlines, and no contour of the same gamma
    assert len(line_collections(ax)) == 1
    assert not [c for c in ax.collections if hasattr(c, "levels")]


def test_distance_image_downsamples_long_trajectories():
    rng = np.random.default_rng(3)
    n = 2500
    p = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    t = np.cumsum(rng.uniform(0.05, 0.15, n))  # uneven clock
    traj = il.Trajectory(t, p)
    loops = il.find_loops(traj, gamma=4.0, separation=None)
    ax = plot.distance_image(traj, loops, max_pixels=300)
    image = np.asarray(ax.images[0].get_array())
    assert image.shape == (300, 300)
    # 300 pixels evenly spaced in time, each showing the pose nearest its centre.
    relative = t - t[0]
    centres = (np.arange(300) + 0.5) * relative[-1] / 300
    grid = np.abs(relative[None, :] - centres[:, None]).argmin(axis=1)
    np.testing.assert_allclose(image, cdist(p[grid], p[grid]), atol=1e-9)
    span = t[-1] - t[0]
    lo, hi = ax.get_xlim()
    assert lo <= 0 < span <= hi and hi - span < span / 100
    # The outlines are of the exact components (labelled at full resolution, a component and
    # its mirror folded together), sampled on the grid; not of the grid's own mask.
    full, _ = ndimage.label(cdist(p, p) <= 4.0)
    folded = np.minimum(full, full.T)
    expected = boundary_edges(folded[np.ix_(grid, grid)])
    assert len(line_collections(ax)[0].get_segments()) == expected
    coarse, _ = ndimage.label(cdist(p[grid], p[grid]) <= 4.0)
    assert expected != boundary_edges(coarse), "the test should tell the two apart"


def test_distance_image_window_is_a_zoom_at_full_resolution(loop2):
    traj, loops = loop2
    t, p = traj.timestamps, traj.positions
    ax = plot.distance_image(traj, loops, window_s=((1.0, 5.0), (8.0, 12.0)))
    image = np.asarray(ax.images[0].get_array())
    ix = np.flatnonzero((t >= 1.0 - 1e-9) & (t <= 5.0 + 1e-9))
    iy = np.flatnonzero((t >= 8.0 - 1e-9) & (t <= 12.0 + 1e-9))
    np.testing.assert_allclose(image, cdist(p[iy], p[ix]), atol=1e-12)
    lo, hi = ax.get_xlim()
    assert 0.9 < lo < 1.0 and 5.0 < hi < 5.1
    full, _ = ndimage.label(cdist(p, p) <= 1.0)
    assert len(line_collections(ax)[0].get_segments()) == boundary_edges(full[np.ix_(iy, ix)])


def test_distance_image_with_a_callable_metric():
    n = 200
    s = np.linspace(0, 2 * np.pi, n)
    angles = 7 * np.pi / 8 * np.c_[np.cos(s), np.sin(s)]
    traj = il.Trajectory.torus(np.arange(n) * 0.1, angles)
    loops = il.find_loops(traj, gamma=1.0, metric="torus", separation=None)

    def torus(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = np.remainder(a[:, None] - b[None] + np.pi, 2 * np.pi) - np.pi
        return np.linalg.norm(d, axis=-1)

    ax = plot.distance_image(traj, loops, metric=torus, distance_unit="rad")
    image = np.asarray(ax.images[0].get_array())
    np.testing.assert_allclose(image, torus(angles, angles), atol=1e-12)
    labels, _ = ndimage.label(image <= 1.0)
    assert len(line_collections(ax)[0].get_segments()) == boundary_edges(labels)
    assert "π(t, t′) (rad)" in ax.figure.axes[1].get_ylabel()
    # Any metric is computed by the core: the loops' own, a name or a metric object.
    for ax in (
        plot.distance_image(traj, loops),
        plot.distance_image(traj, metric="torus"),
        plot.distance_image(traj, metric=il.metrics.Torus()),
    ):
        np.testing.assert_allclose(ax.images[0].get_array(), torus(angles, angles), atol=1e-12)
    with pytest.raises(TypeError, match="metric must be"):
        plot.distance_image(traj, metric=42)
    with pytest.raises(ValueError, match="metric returned shape"):
        plot.distance_image(traj, metric=lambda a, b: np.zeros(3))
    # The Euclidean metric by name or object is accepted.
    euclid = il.Trajectory(np.arange(n) * 0.1, angles)
    for metric in ("euclidean", il.metrics.Euclidean()):
        ax = plot.distance_image(euclid, metric=metric)
        np.testing.assert_allclose(ax.images[0].get_array(), cdist(angles, angles), atol=1e-12)


def test_distance_image_samples_in_every_form(loop2):
    traj, loops = loop2
    t = traj.timestamps
    pairs = np.array([[0, 90], [10, 100]])
    forms = {
        "alpha": pairs,
        "rho": {"i": pairs[:, 0], "j": pairs[:, 1]},
        "one": {"t": t[pairs[:, 0]] + 0.01, "t_prime": t[pairs[:, 1]] - 0.01},  # nearest poses
        "mine": pairs.tolist(),
    }
    ax = plot.distance_image(traj, loops, samples=forms)
    points = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert len(points) == 4
    for collection in points:
        np.testing.assert_allclose(collection.get_offsets(), t[pairs])
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels[-4:] == ["σ_α ∈ O(α)", "σ_ρ ∈ O(ρ)", "σ_1 ∈ O(1)", "mine"]
    for collection, name in zip(points, ("alpha", "rho", "one"), strict=False):
        colour = matplotlib.colors.to_rgb(plot.PAPER_SAMPLERS[name][0])
        np.testing.assert_allclose(collection.get_facecolor()[0][:3], colour)


def test_distance_image_errors(loop2):
    traj, loops = loop2
    other = il.Trajectory(np.arange(10.0), np.zeros((10, 2)))
    with pytest.raises(TypeError, match="Trajectory"):
        plot.distance_image(traj.positions)
    with pytest.raises(TypeError, match="Loops"):
        plot.distance_image(traj, "loops")
    with pytest.raises(ValueError, match="find_loops on this trajectory"):
        plot.distance_image(other, loops)
    with pytest.raises(ValueError, match="outlines=True needs loops"):
        plot.distance_image(traj, outlines=True)
    for gamma in (0.0, -1.0, float("nan"), [1.0, float("inf")]):
        with pytest.raises(ValueError, match="gamma must be positive"):
            plot.distance_image(traj, gamma=gamma)
    with pytest.raises(TypeError, match="gamma must be a number"):
        plot.distance_image(traj, gamma=["1"])
    with pytest.raises(ValueError, match="max_pixels"):
        plot.distance_image(traj, max_pixels=1)
    with pytest.raises(TypeError, match="max_pixels"):
        plot.distance_image(traj, max_pixels=2.5)
    with pytest.raises(TypeError, match="integer pose indices"):
        plot.distance_image(traj, samples=np.array([[0.0, 1.5]]))
    with pytest.raises(TypeError, match=r"\(m, 2\)"):
        plot.distance_image(traj, samples=np.arange(3))
    with pytest.raises(ValueError, match="out of range"):
        plot.distance_image(traj, samples=[[0, len(traj)]])
    with pytest.raises(ValueError, match="out of range"):
        plot.distance_image(traj, samples=[[-1, 3]])
    with pytest.raises(TypeError, match="'i' and 'j'"):
        plot.distance_image(traj, samples=object())
    with pytest.raises(TypeError, match="sampler names"):
        plot.distance_image(traj, samples={1: [[0, 1]]})
    with pytest.raises(ValueError, match="no pose"):
        plot.distance_image(traj, window_s=((100.0, 200.0), (0.0, 1.0)))
    with pytest.raises(ValueError, match="min < max"):
        plot.distance_image(traj, window_s=((2.0, 1.0), (0.0, 1.0)))
    with pytest.raises(TypeError, match="window_s"):
        plot.distance_image(traj, window_s=(1.0, 2.0))


# --------------------------------------------------------------------------------------------
# trajectory_by_duration
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("side", ["both", "begin", "end"])
def test_trajectory_by_duration_colours_by_the_dense_loop_duration(loop2, side):
    traj, loops = loop2
    t, p = traj.timestamps, traj.positions
    ax = plot.trajectory_by_duration(traj, loops, side=side)
    (lines,) = line_collections(ax)
    # tau_i = sum_j w_j [d_ij <= gamma], over j > i (begin) or j < i (end), half the diagonal.
    inside = (cdist(p, p) <= 1.0).astype(float)
    w = cell_widths(t)
    tau = {
        "both": inside @ w,
        "begin": np.triu(inside, 1) @ w + w / 2,
        "end": np.tril(inside, -1) @ w + w / 2,
    }[side]
    segment_tau = (tau[:-1] + tau[1:]) / 2
    drawn = np.asarray(lines.get_array())
    assert np.all(np.diff(drawn) >= 0), "drawn in increasing tau: the longest on top"
    # The same (segment, tau) rows, whatever the order among equal taus.
    segments = np.asarray(lines.get_segments()).reshape(-1, 4)
    got = np.round(np.c_[segments, drawn], 9)
    want = np.round(np.c_[p[:-1], p[1:], segment_tau], 9)
    np.testing.assert_allclose(got[np.lexsort(got.T)], want[np.lexsort(want.T)], atol=1e-8)
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    assert "loop duration" in ax.figure.axes[1].get_ylabel()
    assert np.isclose(lines.get_clim()[1], tau.max())


def test_trajectory_by_duration_options_and_errors(loop2):
    traj, loops = loop2
    ax = plot.trajectory_by_duration(
        traj, loops, components=[1], normalized=True, axes=(1, 0), colorbar=False
    )
    assert len(ax.figure.axes) == 1
    assert ax.get_xlabel() == "y (m)"
    np.testing.assert_allclose(
        np.sort(line_collections(ax)[0].get_array()),
        np.sort(
            np.convolve(loops.loop_duration(components=[1], normalized=True), [0.5, 0.5], "valid")
        ),
    )
    with pytest.raises(TypeError, match="Loops"):
        plot.trajectory_by_duration(traj, None)
    with pytest.raises(TypeError, match="Trajectory"):
        plot.trajectory_by_duration(loops, loops)
    with pytest.raises(ValueError, match="find_loops on this trajectory"):
        plot.trajectory_by_duration(il.Trajectory(np.arange(5.0), np.zeros((5, 2))), loops)
    for axes in ((0, 2), (0, 0), (0,), "xy"):
        with pytest.raises(ValueError, match="axes"):
            plot.trajectory_by_duration(traj, loops, axes=axes)
    with pytest.raises(il.InvalidParameterError):
        plot.trajectory_by_duration(traj, loops, side="sideways")
    with pytest.raises(il.InvalidParameterError):
        plot.trajectory_by_duration(traj, loops, components=[99])


# --------------------------------------------------------------------------------------------
# sample_pairs
# --------------------------------------------------------------------------------------------


def test_sample_pairs_draws_lines_between_trajectory_points(loop2):
    traj, _ = loop2
    p = traj.positions
    pairs = np.array([[0, 90], [5, 170], [20, 40]])
    ax = plot.sample_pairs(traj, {"alpha": pairs, "rho": pairs[:1]})
    assert len(ax.lines) == 1, "the path"
    np.testing.assert_allclose(ax.lines[0].get_xydata(), p)
    first, second = line_collections(ax)
    np.testing.assert_allclose(
        np.asarray(first.get_segments()), np.stack([p[pairs[:, 0]], p[pairs[:, 1]]], 1)
    )
    assert len(second.get_segments()) == 1
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels == ["trajectory", "σ_α ∈ O(α) (3)", "σ_ρ ∈ O(ρ) (1)"]
    ax = plot.sample_pairs(traj, pairs, color="red", legend=False)
    (lines,) = line_collections(ax)
    assert tuple(lines.get_color()[0][:3]) == (1.0, 0.0, 0.0)
    assert ax.get_legend() is None


def test_sample_pairs_errors(loop2):
    traj, _ = loop2
    with pytest.raises(ValueError, match="no samples"):
        plot.sample_pairs(traj, {})
    with pytest.raises(ValueError, match="no samples"):
        plot.sample_pairs(traj, None)
    with pytest.raises(TypeError, match="Trajectory"):
        plot.sample_pairs(None, [[0, 1]])
    with pytest.raises(ValueError, match="out of range"):
        plot.sample_pairs(traj, [[0, 10**6]])
    with pytest.raises(TypeError, match="integer pose indices"):
        plot.sample_pairs(traj, {"i": [0.5], "j": [1.0]})
    with pytest.raises(ValueError, match="1 values of i but 2 of j"):
        plot.sample_pairs(traj, {"i": [0], "j": [1, 2]})
    with pytest.raises(ValueError, match="axes"):
        plot.sample_pairs(traj, [[0, 1]], axes=(0, 5))


# --------------------------------------------------------------------------------------------
# samples_per_component
# --------------------------------------------------------------------------------------------


def test_samples_per_component_counts_by_component_sorted_by_area(loop2):
    traj, loops = loop2
    table = loops.components
    nontrivial = np.flatnonzero(~table["trivial"])
    by_area = nontrivial[np.argsort(table["area_s2"][nontrivial], kind="stable")]
    # Pairs in known components (found by component_of) and one outside S_gamma.
    lap = loops.component_of(0, 90)
    corner = loops.component_of(0, 180)
    outside = (0, 45)
    assert loops.component_of(*outside) is None
    samples = {
        "alpha": np.array([[0, 90], [1, 91], [2, 92], [0, 180], list(outside)]),
        "one": np.array([[0, 180]]),
    }
    top, bottom = plot.samples_per_component(loops, samples, log_scale=False)
    assert top.figure is bottom.figure
    counts = {"alpha": {lap: 3, corner: 1}, "one": {corner: 1}}
    for index, name in enumerate(samples):
        expected = np.array([counts[name].get(c, 0) for c in by_area], dtype=float)
        percent = 100 * expected / table["pair_count"][by_area]
        x, y = top.lines[index].get_data()
        np.testing.assert_array_equal(x, np.arange(1, len(by_area) + 1))
        np.testing.assert_allclose(np.nan_to_num(y), percent)
        np.testing.assert_allclose(bottom.lines[index].get_ydata(), np.cumsum(expected))
    assert "sorted by area" in bottom.get_xlabel()
    assert top.get_ylabel() == "samples / pairs (%)"
    assert bottom.get_ylabel() == "cumulative samples"
    legend = [text.get_text() for text in top.get_legend().get_texts()]
    assert legend == [
        "σ_α ∈ O(α): 4 samples in 2/2 components",
        "σ_1 ∈ O(1): 1 samples in 1/2 components",
        "ticks: components without a sample",
    ]
    # sigma_1 missed the lap component: one tick at its rank (P1).
    assert len(top.lines) == 3
    np.testing.assert_array_equal(top.lines[2].get_xdata(), [list(by_area).index(lap) + 1])


def test_samples_per_component_available_and_component_columns(loop2):
    traj, loops = loop2
    table = loops.components
    k = len(table["id"])
    lap = loops.component_of(0, 90)
    detections = {"i": np.array([0, 1, 2, 3, 0]), "j": np.array([90, 91, 92, 93, 180])}
    samples = {"rho": {"i": [0], "j": [90], "component": [lap]}}
    fig, axes = plt.subplots(2, 1)
    top, bottom = plot.samples_per_component(
        loops, samples, axes=tuple(axes), available=detections, include_trivial=True
    )
    assert (top, bottom) == tuple(axes)
    assert top.get_ylabel() == "samples / detections (%)"
    _, y = top.lines[0].get_data()
    assert np.nanmax(y) == pytest.approx(100 * 1 / 4), "1 sample of the lap's 4 detections"
    # Counts per component id are accepted as well.
    counts = np.zeros(k)
    counts[lap] = 8
    top, _ = plot.samples_per_component(loops, samples, available=counts)
    assert np.nanmax(top.lines[0].get_ydata()) == pytest.approx(100 / 8)


def test_pair_lookup_equals_component_of():
    rng = np.random.default_rng(5)
    p = np.cumsum(rng.normal(size=(400, 2)), axis=0)
    loops = il.find_loops(il.Trajectory(np.arange(400) * 0.1, p), gamma=3.0, separation=None)
    i, j = rng.integers(0, 400, 3000), rng.integers(0, 400, 3000)
    expected = [loops.component_of(int(a), int(b)) for a, b in zip(i, j, strict=True)]
    found = loops.components_of_pairs(i, j)
    assert found.tolist() == [-1 if c is None else c for c in expected]


def test_samples_per_component_errors(loop2):
    traj, loops = loop2
    good = {"one": [[0, 90]]}
    with pytest.raises(TypeError, match="Loops"):
        plot.samples_per_component(traj, good)
    with pytest.raises(ValueError, match="empty"):
        plot.samples_per_component(loops, {})
    with pytest.raises(ValueError, match="one value per component"):
        plot.samples_per_component(loops, good, available=[1.0, 2.0, 3.0, 4.0, 5.0])
    with pytest.raises(ValueError, match="two Axes"):
        plot.samples_per_component(loops, good, axes=(plt.gca(),))
    with pytest.raises(ValueError, match="component id 7 out of range"):
        plot.samples_per_component(loops, {"one": {"i": [0], "j": [1], "component": [7]}})
    with pytest.raises(TypeError, match="component ids must be integers"):
        plot.samples_per_component(loops, {"one": {"i": [0], "j": [1], "component": [0.5]}})
    with pytest.raises(ValueError, match="no pose indices"):
        plot.samples_per_component(loops, {"one": {"t": [0.0], "t_prime": [9.0]}})
    with pytest.raises(ValueError, match="out of range"):
        plot.samples_per_component(loops, {"one": [[0, 10**6]]})
    spiral = il.Trajectory(np.arange(50.0), np.c_[np.arange(50.0), np.zeros(50)])
    with pytest.raises(ValueError, match="no loop component to show"):
        plot.samples_per_component(
            il.find_loops(spiral, gamma=2.0, separation=None), {"one": [[0, 1]]}
        )


@pytest.mark.skipif(not hasattr(il, "sample"), reason="the sampling API is not built")
def test_plots_take_the_sampling_api_results():
    traj = il.urban_drive(duration_s=900.0, seed=2)
    loops = il.find_loops(traj, gamma=40.0, separation=None)
    detections = il.draw_detections(loops, rate=0.05, seed=1)
    clusters = il.cluster_detections(detections, epsilon_s=30.0)
    samples = {name: il.sample(clusters, name, budget=200, seed=1) for name in ("alpha", "one")}
    ax = plot.distance_image(traj, loops, samples=samples)
    points = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert [len(c.get_offsets()) for c in points] == [len(s) for s in samples.values()]
    ax = plot.sample_pairs(traj, samples["alpha"])  # named by its sampler
    assert ax.get_legend().get_texts()[1].get_text().startswith("σ_α")
    top, bottom = plot.samples_per_component(loops, samples, available=detections)
    quality = il.sample_quality(samples["one"], loops)
    nontrivial = ~loops.components["trivial"]
    assert bottom.lines[1].get_ydata()[-1] == quality.per_component[nontrivial].sum()


# --------------------------------------------------------------------------------------------
# The module: lazy import, missing matplotlib
# --------------------------------------------------------------------------------------------


def run_python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )


def test_importing_the_package_does_not_import_matplotlib():
    done = run_python(
        "import sys, inexact_loops as il\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported by inexact_loops'\n"
        "assert 'plot' in dir(il)\n"
        "il.plot.distance_image\n"
        "assert 'matplotlib' in sys.modules\n"
    )
    assert done.returncode == 0, done.stderr


def test_without_matplotlib_the_error_names_the_extra():
    done = run_python(
        "import sys; sys.modules['matplotlib'] = None\n"
        "import inexact_loops as il\n"
        "try:\n"
        "    import inexact_loops.plot\n"
        "except ImportError as err:\n"
        "    print(err)\n"
    )
    assert done.returncode == 0, done.stderr
    assert "pip install '.[plot]' in a checkout" in done.stdout


# --------------------------------------------------------------------------------------------
# examples/paper_figures.py
# --------------------------------------------------------------------------------------------


def load_example():
    spec = importlib.util.spec_from_file_location("paper_figures", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_example(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, str(EXAMPLE), *args],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env=env,
    )


@pytest.fixture(scope="module")
def figures(tmp_path_factory) -> tuple[Path, subprocess.CompletedProcess[str]]:
    out = tmp_path_factory.mktemp("figures")
    return out, run_example("--out", str(out))


def expected_figures() -> list[str]:
    example = load_example()
    names = [name for group in example.FIGURES.values() for name in group]
    if not example.sampling_api():
        names = [
            n
            for n in names
            if n in ("fig6d_loop_duration.png", "fig7_distance_samples.png")
            or not n.startswith(("fig6", "fig7", "fig8"))
        ]
    if importlib.util.find_spec("scipy") is None and example.KITTI_00.is_file():
        names.remove("fig5_real_trajectory.png")
    return names


def test_paper_figures_are_written_and_not_blank(figures):
    out, done = figures
    assert done.returncode == 0, done.stderr
    names = expected_figures()
    assert {"fig2_example_loops.png", "fig4_manifold_circles.png"} <= set(names)
    written = sorted(path.name for path in out.glob("*.png"))
    assert written == sorted(names), done.stdout
    for name in names:
        pixels = plt.imread(out / name)
        assert pixels.ndim == 3 and min(pixels.shape[:2]) > 300, name
        assert float(pixels[..., :3].std()) > 0.05, f"{name} is blank"
        assert f"wrote {out / name}" in done.stdout


def test_paper_figures_keep_existing_files_unless_forced(figures):
    out, done = figures
    assert done.returncode == 0, done.stderr
    target = out / "fig2_example_loops.png"
    before = target.stat().st_mtime_ns
    again = run_example("--out", str(out), "--only", "fig2")
    assert again.returncode == 2
    assert "--force" in again.stderr and str(target) in again.stderr
    assert target.stat().st_mtime_ns == before
    forced = run_example("--out", str(out), "--only", "fig2", "--force")
    assert forced.returncode == 0, forced.stderr
    assert target.stat().st_mtime_ns > before


def test_paper_figures_rejects_unknown_figures(tmp_path):
    done = run_example("--out", str(tmp_path), "--only", "fig3")
    assert done.returncode == 2 and "invalid choice" in done.stderr
    assert not list(tmp_path.glob("*.png"))


def test_sample_pairs_show_pairs_shorter_than_a_line(loop2):
    """A pair at its closest approach (both poses at one place) is drawn as dots at its ends."""
    traj, _ = loop2
    p = traj.positions
    pairs = np.array([[0, 0], [5, 5]])  # zero-length segments
    ax = plot.sample_pairs(traj, pairs)
    dots = [c for c in ax.collections if not isinstance(c, LineCollection)]
    assert len(dots) == 1, ax.collections
    np.testing.assert_allclose(
        dots[0].get_offsets(), np.concatenate([p[pairs[:, 0]], p[pairs[:, 1]]])
    )
    assert dots[0].get_sizes()[0] > 0
