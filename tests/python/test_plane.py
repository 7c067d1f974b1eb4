"""The (t, t') plane from Python (``PlaneGrid``, ``distance_image``, ``Loops.label_image``,
outlines, isocontours, pairs and nearest poses) against brute force: scipy's ``Rotation`` for
SE(3) and SO(3) distances, ``scipy.ndimage.label`` of the dense matrix for the labels, numpy
for the rest; and ``inexact_loops.plot.distance_image`` drawing the same for SE(3) and SO(3).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation

import inexact_loops as il


def rotations(n: int, seed: int) -> Rotation:
    """A smooth random walk of rotations that comes back near its start."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0, 2 * np.pi, n)
    vectors = np.c_[np.cos(s), np.sin(s), 0.3 * np.sin(2 * s)] * 1.2
    return Rotation.from_rotvec(vectors + rng.normal(scale=0.01, size=(n, 3)))


def so3_brute(r: Rotation) -> np.ndarray:
    """Geodesic angles |log(R_i⁻¹ R_j)| of every pair, radians."""
    return np.array([(r[k].inv() * r).magnitude() for k in range(len(r))])


def se3_case(n: int = 60, weight: float = 10.0):
    r = rotations(n, 1)
    s = np.linspace(0, 2 * np.pi, n)
    p = 5.0 * np.c_[np.cos(s), np.sin(s), np.zeros(n)]
    traj = il.Trajectory.se3(np.arange(n) * 0.5, p, r.as_quat())
    # The se3 metric: ‖p_i − p_j‖ + w · angle(R_i⁻¹ R_j).
    brute = cdist(p, p) + weight * so3_brute(r)
    return traj, f"se3(rotation_weight_m_per_rad={weight:g})", brute


def test_grid_of_every_pose_and_of_evenly_spaced_pixels():
    t = np.array([0.0, 1.0, 2.0, 10.0])
    traj = il.Trajectory(t, np.zeros(4))
    grid = il.PlaneGrid(traj, 10)
    assert grid.columns.tolist() == grid.rows.tolist() == [0, 1, 2, 3]
    assert grid.column_edges_s.tolist() == [-0.5, 0.5, 1.5, 6.0, 14.0]
    assert (grid.width, grid.height, grid.poses) == (4, 4, 4)
    coarse = il.PlaneGrid(traj, 3)  # centres at 1.67, 5 and 8.33 s: nearest poses 2, 2, 3
    assert coarse.columns.tolist() == [2, 2, 3]
    np.testing.assert_allclose(coarse.row_edges_s, np.linspace(0, 10, 4))
    zoom = il.PlaneGrid(traj, 10, window_s=((0.5, 2.5), (9.0, 11.0)))
    assert zoom.columns.tolist() == [1, 2] and zoom.rows.tolist() == [3]
    assert "PlaneGrid(2 × 1 pixels of 4 poses)" == repr(zoom)
    with pytest.raises(il.InvalidParameterError, match="no pose"):
        il.PlaneGrid(traj, 10, window_s=((3.0, 9.0), (0.0, 1.0)))
    with pytest.raises(il.InvalidParameterError, match="max_pixels"):
        il.PlaneGrid(traj, 0)
    with pytest.raises(TypeError, match="Trajectory or Loops"):
        il.PlaneGrid(t, 3)


def test_so3_and_se3_distance_images_equal_scipy_rotations():
    r = rotations(50, 2)
    so3 = il.Trajectory.so3(np.arange(50) * 0.2, r.as_quat())
    image = il.distance_image(so3, il.PlaneGrid(so3, 100), metric="so3")
    np.testing.assert_allclose(image, so3_brute(r), atol=1e-9)
    traj, spec, brute = se3_case()
    grid = il.PlaneGrid(traj, 100)
    np.testing.assert_allclose(il.distance_image(traj, grid, metric=spec), brute, atol=1e-9)
    metric = il.metrics.SE3(rotation_weight_m_per_rad=10)
    np.testing.assert_allclose(il.distance_image(traj, grid, metric=metric), brute, atol=1e-9)
    # A zoomed, downsampled grid: the same distances at its poses.
    zoom = il.PlaneGrid(traj, 7, window_s=((2.0, 20.0), (0.0, 29.5)))
    image = il.distance_image(traj, zoom, metric=spec, threads=1)
    assert image.shape == (7, 7)
    np.testing.assert_allclose(image, brute[np.ix_(zoom.rows, zoom.columns)], atol=1e-9)
    # The slow path: a callable per pair.
    slow = il.distance_image(
        so3, il.PlaneGrid(so3, 10), metric=lambda a, b: float(abs(a - b).sum())
    )
    q = so3.positions[il.PlaneGrid(so3, 10).columns]
    np.testing.assert_allclose(slow, cdist(q, q, "cityblock"), atol=1e-12)
    with pytest.raises(il.InvalidParameterError, match="grid was made for 4 poses"):
        il.distance_image(traj, il.PlaneGrid(il.Trajectory(np.arange(4.0), np.zeros(4)), 4))


def test_label_image_is_the_dense_labelling_folded():
    rng = np.random.default_rng(4)
    p = np.cumsum(rng.normal(size=(300, 2)), axis=0)
    traj = il.Trajectory(np.cumsum(rng.uniform(0.05, 0.2, 300)), p)
    loops = il.find_loops(traj, gamma=3.0, separation=None)
    full, _ = ndimage.label(cdist(p, p) <= 3.0)
    folded = np.where(full > 0, np.minimum(full, full.T), 0)
    for grid in (
        il.PlaneGrid(loops, 1000),
        il.PlaneGrid(traj, 70),
        il.PlaneGrid(loops, 40, window_s=((1.0, 30.0), (5.0, 40.0))),
    ):
        labels = loops.label_image(grid)
        assert labels.shape == (grid.height, grid.width) and labels.dtype == np.int64
        dense = folded[np.ix_(grid.rows, grid.columns)]
        assert ((labels < 0) == (dense == 0)).all()
        # One component id for each scipy label, and the other way round.
        pairs = np.unique(np.c_[labels[labels >= 0], dense[dense > 0]], axis=0)
        assert len(np.unique(pairs[:, 0])) == len(np.unique(pairs[:, 1])) == len(pairs)
        ids = loops.components_of_pairs(
            grid.columns[None, :].repeat(grid.height, 0).ravel(), grid.rows.repeat(grid.width)
        )
        np.testing.assert_array_equal(ids.reshape(labels.shape), labels)


def test_components_of_pairs_and_counts():
    traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
    loops = il.find_loops(traj, gamma=0.5, separation=None)
    i, j = np.array([3, 0, 0, 1, 2]), np.array([0, 3, 1, 2, 1])
    ids = loops.components_of_pairs(i, j)
    assert ids.tolist() == [
        -1 if loops.component_of(a, b) is None else loops.component_of(a, b)
        for a, b in zip(i, j, strict=True)
    ]
    counts = loops.pair_counts_per_component(i, j)
    np.testing.assert_array_equal(
        counts, np.bincount(ids[ids >= 0], minlength=len(loops.components["id"]))
    )
    assert loops.components_of_pairs([], []).tolist() == []
    with pytest.raises(IndexError, match="pose index 4"):
        loops.components_of_pairs([4], [0])
    with pytest.raises(IndexError, match="negative"):
        loops.pair_counts_per_component([-1], [0])
    with pytest.raises(ValueError, match="i has 1 values but j has 2"):
        loops.components_of_pairs([0], [1, 2])
    with pytest.raises(TypeError, match="pose indices"):
        loops.components_of_pairs([0.5], [1])


def test_nearest_poses_are_the_argmin():
    rng = np.random.default_rng(6)
    t = np.cumsum(rng.uniform(0.1, 1.0, 80))
    traj = il.Trajectory(t, np.zeros(80))
    times = rng.uniform(t[0], t[-1], 500)
    expected = np.abs(times[:, None] - t[None, :]).argmin(axis=1)
    np.testing.assert_array_equal(traj.nearest_poses(times), expected)
    with pytest.raises(il.InvalidParameterError, match="outside the trajectory's time span"):
        traj.nearest_poses([t[-1] + 1.0])


def test_outlines_are_the_pixel_sides_between_labels():
    rng = np.random.default_rng(7)
    labels = rng.integers(-1, 3, size=(9, 13))
    for border in ("closed", "open"):
        edges, sides = il.outline_segments(labels, border=border)
        padded = (
            np.pad(labels, 1, constant_values=-1)
            if border == "closed"
            else np.pad(labels, 1, mode="edge")
        )
        vertical = np.argwhere(padded[1:-1, :-1] != padded[1:-1, 1:])  # (row b, corner x)
        horizontal = np.argwhere(padded[:-1, 1:-1] != padded[1:, 1:-1])  # (corner y, column a)
        expected = {((x, b), (x, b + 1)) for b, x in vertical} | {
            ((a, y), (a + 1, y)) for y, a in horizontal
        }
        assert {tuple(map(tuple, e)) for e in edges.tolist()} == expected
        assert len(edges) == len(expected) and (sides[:, 0] != sides[:, 1]).all()
        outlines = il.component_outlines(labels, border=border)
        assert sorted(outlines) == sorted(set(labels[labels >= 0].ravel().tolist()))
        for c, lines in outlines.items():
            own = {
                tuple(map(tuple, e))
                for e, s in zip(edges.tolist(), sides.tolist(), strict=True)
                if c in s
            }
            drawn = {
                tuple(sorted(map(tuple, w)))
                for line in lines
                for w in zip(line[:-1].tolist(), line[1:].tolist(), strict=True)
            }
            assert drawn == own
            if border == "closed":
                assert all((line[0] == line[-1]).all() for line in lines)
    with pytest.raises(il.InvalidParameterError, match="border"):
        il.outline_segments(labels, border="ajar")
    with pytest.raises(TypeError, match="integer labels"):
        il.component_outlines(labels.astype(float))
    with pytest.raises(ValueError, match="2-dimensional"):
        il.outline_segments(labels.ravel())


def test_chain_polylines_use_every_edge_once():
    lines = il.chain_polylines(np.array([[0, 1], [2, 3], [1, 2], [3, 0], [5, 6]]))
    assert [line.tolist() for line in lines] == [[0, 1, 2, 3, 0], [5, 6]]
    edges, _ = il.outline_segments(np.array([[1, 1], [1, -1]]))
    (line,) = il.chain_polylines(edges)
    assert line.shape == (len(edges) + 1, 2) and (line[0] == line[-1]).all()
    with pytest.raises(ValueError, match=r"\(k, 2\)"):
        il.chain_polylines(np.zeros((3, 3), int))


def test_isocontour_crosses_between_pixel_centres():
    b, a = np.mgrid[0:5, 0:5]
    ramp = a.astype(float)  # the level 1.5 lies halfway between columns 1 and 2
    (line,) = il.isocontour(ramp, 1.5)
    np.testing.assert_allclose(line[:, 0], 2.0)
    assert sorted(line[:, 1].tolist()) == [0.5, 1.5, 2.5, 3.5, 4.5]
    assert il.isocontour(ramp, 10.0) == []
    with pytest.raises(ValueError, match="2-dimensional"):
        il.isocontour(np.zeros(4), 1.0)


def test_sampler_symbols_come_from_the_core():
    assert [il.sampler_symbol(n) for n in ("one", "rho", "alpha")] == ["σ_1", "σ_ρ", "σ_α"]
    assert il.sampler_symbol("hdl-graph-slam") == "hdl_graph_slam"
    with pytest.raises(il.InvalidParameterError, match="one, rho"):
        il.sampler_symbol("sigma")


@pytest.mark.parametrize("manifold", ["se3", "so3"])
def test_plot_distance_image_for_se3_and_so3_equals_scipy(manifold):
    plot = pytest.importorskip("inexact_loops.plot")
    import matplotlib.pyplot as plt

    if manifold == "se3":
        traj, spec, brute = se3_case()
        loops = il.find_loops(traj, gamma=6.0, metric=spec, separation=None)
    else:
        r = rotations(60, 3)
        traj = il.Trajectory.so3(np.arange(60) * 0.5, r.as_quat())
        brute = so3_brute(r)
        loops = il.find_loops(traj, gamma=0.3, metric="so3", separation=None)
    ax = plot.distance_image(traj, loops, distance_unit="")
    np.testing.assert_allclose(np.asarray(ax.images[0].get_array()), brute, atol=1e-9)
    # The outlines are those of the exact components (every pose shows).
    full, _ = ndimage.label(brute <= loops.gamma)
    padded = np.pad(np.minimum(full, full.T), 1, mode="edge")
    count = (padded[1:-1, :-1] != padded[1:-1, 1:]).sum() + (
        padded[:-1, 1:-1] != padded[1:, 1:-1]
    ).sum()
    (outlines,) = [c for c in ax.collections if type(c).__name__ == "LineCollection"]
    assert len(outlines.get_segments()) == count > 0
    # Downsampled: the image at the grid's poses.
    ax = plot.distance_image(traj, loops, max_pixels=17)
    grid = il.PlaneGrid(traj, 17)
    np.testing.assert_allclose(
        np.asarray(ax.images[0].get_array()), brute[np.ix_(grid.rows, grid.columns)], atol=1e-9
    )
    plt.close("all")
