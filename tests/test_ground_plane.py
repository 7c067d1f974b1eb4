"""The plane the user chose: SE(2) on a 3-D pose file takes the plane's two coordinates and the
rotation about its normal, from Python and the command line, and the plot maps draw and label
the plane a trajectory was read on.

The headings are checked against scipy's Euler angles of the same rotations: on x-z, KITTI's
ground plane (camera frame: x right, y down, z forward), the heading is the rotation about the
plane's normal x × z = −y (up), minus the first intrinsic Y-Z-X angle; on x-y the yaw about z,
the first intrinsic Z-Y-X angle. The KITTI tests read ../shared/data and skip without it.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import inexact_loops as il

ROOT = Path(__file__).resolve().parents[1]
KITTI00 = ROOT / ".." / "shared" / "data" / "kitti_odometry" / "00.txt"
WEIGHT = 5.0  # m/rad
SE2 = f"se2(rotation_weight_m_per_rad={WEIGHT:g})"
GAMMA = 6.0


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles into (-π, π]."""
    return np.pi - np.mod(np.pi - angle, 2 * np.pi)


def heading_in_xz(rotations: Rotation) -> np.ndarray:
    """The rotation about -y (the normal of x-z, up in KITTI's camera frame), by scipy."""
    return wrap(-rotations.as_euler("YZX")[:, 0])


def write_tum(path: Path, t: np.ndarray, positions: np.ndarray, rotations: Rotation) -> Path:
    np.savetxt(path, np.c_[t, positions, rotations.as_quat()], fmt="%.17g")
    return path


def se2_pair_count(positions: np.ndarray, heading: np.ndarray, gamma: float) -> int:
    """Pairs (i, j) of the full plane with |p_i - p_j| + W |wrap(θ_i - θ_j)| <= gamma, dense."""
    count = 0
    for start in range(0, len(positions), 512):
        rows = slice(start, start + 512)
        step = np.linalg.norm(positions[rows, None, :] - positions[None, :, :], axis=2)
        turn = np.abs(wrap(heading[rows, None] - heading[None, :]))
        count += int(np.count_nonzero(step + WEIGHT * turn <= gamma))
    return count


@pytest.fixture(scope="module")
def kitti00() -> tuple[np.ndarray, np.ndarray, Rotation]:
    """KITTI 00: times, positions (x, y, z) and rotations of camera 0."""
    if not KITTI00.is_file():
        pytest.skip(f"KITTI odometry not found at {KITTI00.resolve()} (not in a user's clone)")
    rows = np.loadtxt(KITTI00)
    matrices = rows[:, 1:].reshape(-1, 3, 4)
    return rows[:, 0], matrices[:, :, 3], Rotation.from_matrix(matrices[:, :, :3])


def test_se2_on_a_plane_takes_the_rotation_about_its_normal():
    """Random tilted poses: x-z headings against scipy's Euler angles, x-y as before, and the
    other planes of the same rule (e_a × e_b the normal)."""
    rng = np.random.default_rng(14)
    n = 200
    rotations = Rotation.from_euler(
        "YXZ", np.c_[rng.uniform(-np.pi, np.pi, n), rng.uniform(-0.3, 0.3, (n, 2))]
    )
    positions = rng.normal(scale=10.0, size=(n, 3))
    t = np.arange(n) * 0.1
    evo = type("Evo", (), {})()
    evo.timestamps, evo.positions_xyz = t, positions
    evo.orientations_quat_wxyz = np.roll(rotations.as_quat(), 1, axis=1)

    xz = il.Trajectory.from_evo(evo, metric=SE2, axes=(0, 2))
    assert xz.plane_axes == (0, 2) and xz.dim == 3
    np.testing.assert_array_equal(xz.positions[:, :2], positions[:, [0, 2]])
    np.testing.assert_allclose(wrap(xz.positions[:, 2] - heading_in_xz(rotations)), 0, atol=1e-12)
    # The yaw about z of the same poses is another angle: the plane is not ignored.
    yaw = rotations.as_euler("ZYX")[:, 0]
    assert np.abs(wrap(xz.positions[:, 2] - yaw)).max() > 1.0

    xy = il.Trajectory.from_evo(evo, metric=SE2)
    assert xy.plane_axes is None
    np.testing.assert_allclose(wrap(xy.positions[:, 2] - yaw), 0, atol=1e-12)
    # z-x: the heading of z measured towards x, about +y: the first intrinsic Y-X-Z angle.
    zx = il.Trajectory.from_evo(evo, metric=SE2, axes=(2, 0))
    np.testing.assert_array_equal(zx.positions[:, :2], positions[:, [2, 0]])
    first_about_y = rotations.as_euler("YXZ")[:, 0]
    np.testing.assert_allclose(wrap(zx.positions[:, 2] - first_about_y), 0, atol=1e-12)

    # se3 and so3 measure whole poses (no plane); axes the poses do not have are refused.
    with pytest.raises(il.InvalidParameterError, match="euclidean and se2"):
        il.Trajectory.from_evo(evo, metric="so3", axes=(0, 2))
    with pytest.raises(il.InvalidParameterError, match="plane axis"):
        il.Trajectory.from_evo(evo, metric=SE2, axes=(0, 3))


def test_kitti00_se2_on_x_z_equals_the_dense_reference(kitti00, loops_cli):
    """KITTI 00 read as SE(2) on its ground plane (read_trajectory and `loops components`):
    x, z and the rotation about y, and the pairs within γ equal a dense count over scipy's
    headings."""
    t, positions, rotations = kitti00
    heading = heading_in_xz(rotations)
    traj = il.read_trajectory(KITTI00, metric=SE2, axes=(0, 2))
    assert traj.plane_axes == (0, 2)
    np.testing.assert_array_equal(traj.timestamps, t)
    np.testing.assert_array_equal(traj.positions[:, :2], positions[:, [0, 2]])
    # The file's 3x4 matrices are printed to ~7 digits: scipy and the reader orthonormalise
    # them differently.
    np.testing.assert_allclose(wrap(traj.positions[:, 2] - heading), 0, atol=1e-5)
    # KITTI's camera turns about y: its yaw about z (the x-y default) is not its heading.
    assert np.abs(wrap(traj.positions[:, 2] - rotations.as_euler("ZYX")[:, 0])).max() > 1.0

    loops = il.find_loops(traj, gamma=GAMMA, metric=SE2, separation=None)  # the paper's S_γ
    ground = positions[:, [0, 2]]
    # Pairs closer to γ than the headings' agreement could go either way: bound, then expect.
    low = se2_pair_count(ground, heading, GAMMA - 1e-4)
    high = se2_pair_count(ground, heading, GAMMA + 1e-4)
    assert low <= loops.pair_count <= high, (low, loops.pair_count, high)
    assert (~loops.components["trivial"]).sum() > 0, "KITTI 00 revisits its streets"

    args = [loops_cli, "components", KITTI00, "--metric", SE2, "--axes", "0,2", "--no-separation"]
    out = subprocess.run(
        [*args, "--gamma", str(GAMMA), "--json", "-"], check=True, capture_output=True, text=True
    ).stdout
    assert json.loads(out)["pair_count"] == loops.pair_count


def test_maps_draw_and_label_the_plane_a_trajectory_was_read_on(tmp_path):
    matplotlib = pytest.importorskip(
        "matplotlib", reason="matplotlib is not installed: pip install '.[plot]' in a checkout"
    )
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from inexact_loops import plot

    # A loop on the ground of KITTI's camera frame (x-z), 1.6 m below the origin.
    angle = np.linspace(0, 1.9 * np.pi, 120)
    positions = np.c_[20 * np.cos(angle), np.full(120, 1.6), 10 * np.sin(angle)]
    rotations = Rotation.from_euler("Y", -angle[:, None])
    path = write_tum(tmp_path / "ground.tum", np.arange(120) * 0.1, positions, rotations)

    def coloured(ax) -> np.ndarray:
        """The first points of the coloured path's segments (drawn in order of tau)."""
        return np.array([segment[0] for segment in ax.collections[0].get_segments()])

    def same_points(a: np.ndarray, b: np.ndarray) -> None:
        """The same points in any order."""
        a, b = a[np.lexsort(a.T[::-1])], b[np.lexsort(b.T[::-1])]
        np.testing.assert_allclose(a, b, atol=1e-9)

    try:
        for metric in (None, SE2):
            traj = il.read_trajectory(path, axes=(0, 2), metric=metric)
            loops = il.find_loops(traj, gamma=3.0, metric=metric)
            assert traj.plane_axes == (0, 2)
            ax = plot.trajectory_by_duration(traj, loops)
            assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "z (m)")
            same_points(coloured(ax), positions[:-1, [0, 2]])
            ax = plot.trajectory_by_duration(traj, loops, axes=(2, 0), colorbar=False)
            assert (ax.get_xlabel(), ax.get_ylabel()) == ("z (m)", "x (m)")
            same_points(coloured(ax), positions[:-1, [2, 0]])
            ax = plot.sample_pairs(traj, [[0, 100]], axes=(0, 2))
            assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "z (m)")
            np.testing.assert_allclose(ax.lines[0].get_xydata(), positions[:, [0, 2]], atol=1e-9)
            # The plane the trajectory holds is the only one it can draw, and says so.
            for axes in ((0, 1), (1, 2), (0, 0)):
                with pytest.raises(ValueError, match=r"plane x-z \(0, 2\)"):
                    plot.trajectory_by_duration(traj, loops, axes=axes)
        # A trajectory of every axis draws any plane of them, labelled by name.
        full = il.read_trajectory(path)
        assert full.plane_axes is None
        loops = il.find_loops(full, gamma=3.0)
        ax = plot.trajectory_by_duration(full, loops, axes=(0, 2))
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "z (m)")
        same_points(coloured(ax), positions[:-1, [0, 2]])
        ax = plot.sample_pairs(full, [[0, 100]])
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)")
        with pytest.raises(ValueError, match="axes"):
            plot.sample_pairs(full, [[0, 100]], axes=(0, 2.0))
    finally:
        plt.close("all")
