"""Real trajectories from ../shared/data: KITTI 00 against its loop-closure labels, and a TUM
RGB-D file through read_trajectory against the dense reference. Skipped when the data folder is
absent (a user's clone); run with -s to see the KITTI report."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

import inexact_loops as il

KITTI_GAMMA_M = 6.0  # the labels' radius


def require(path):
    if not path.is_file():
        pytest.skip(f"{path.resolve()} is missing")
    return path


@pytest.fixture(scope="module")
def kitti00(data_dir):
    """(timestamps, x-z positions, 3-D positions, labelled pairs (i > j))."""
    poses = np.loadtxt(require(data_dir / "kitti_odometry" / "00.txt"))
    truth = scipy.io.loadmat(require(data_dir / "kitti_loop_gt" / "kitti00GroundTruth.mat"))[
        "truth"
    ]
    truth = truth.toarray() if hasattr(truth, "toarray") else np.asarray(truth)
    assert poses.shape == (4541, 13) and truth.shape == (4541, 4541)
    assert not np.triu(truth).any(), "labels are strictly lower triangular"
    i, j = np.nonzero(truth)
    # Row-major [R|t] after the time column: t_x, t_y, t_z are columns 4, 8, 12.
    return poses[:, 0], poses[:, [4, 12]], poses[:, [4, 8, 12]], i, j


def test_kitti00_labelled_pairs_are_non_trivial_loops(kitti00, check_dense):
    t, xz, xyz, li, lj = kitti00
    traj = il.Trajectory(t, xz)
    loops = il.find_loops(traj, gamma=KITTI_GAMMA_M, threads=2, separation=None)
    single = il.find_loops(traj, gamma=KITTI_GAMMA_M, threads=1, separation=None)
    for key, value in loops.runs().items():
        np.testing.assert_array_equal(value, single.runs()[key], err_msg=key)
    for key, value in loops.components.items():
        np.testing.assert_array_equal(value, single.components[key], err_msg=key)
    table = loops.components
    trivial = table["trivial"]

    d_xz = np.linalg.norm(xz[li] - xz[lj], axis=1)
    d_xyz = np.linalg.norm(xyz[li] - xyz[lj], axis=1)
    component = np.array([-1 if c is None else c for c in map(loops.component_of, li, lj)])
    in_s = component >= 0
    non_trivial = in_s & ~trivial[np.maximum(component, 0)]

    print(f"\nKITTI 00, gamma = {KITTI_GAMMA_M} m in the x-z plane, {len(t)} poses")
    print(f"  labelled pairs:                {len(li)}")
    print(f"  within 6 m in x-z (numpy):     {int((d_xz <= KITTI_GAMMA_M).sum())}")
    print(f"  within 6 m in 3-D (numpy):     {int((d_xyz <= KITTI_GAMMA_M).sum())}")
    print(f"  in S_gamma:                    {int(in_s.sum())}")
    print(f"  in non-trivial components:     {int(non_trivial.sum())}")
    print(f"  smallest labelled |i - j|:     {int(np.abs(li - lj).min())}")
    print(f"  {loops!r}")
    print("  id trivial   area_s2   pairs  i_min..i_max   j_min..j_max  holes  labelled")
    for c in table["id"]:
        print(
            f"  {c:2d} {bool(trivial[c])!s:5} {table['area_s2'][c]:9.3f}"
            f" {table['pair_count'][c]:7d}"
            f"  {table['i_min'][c]:5d}..{table['i_max'][c]:<5d}"
            f"  {table['j_min'][c]:5d}..{table['j_max'][c]:<5d} {table['holes'][c]:5d}"
            f"  {int((component == c).sum()):8d}"
        )

    # The labels use the x-z distance (91 of them are farther than 6 m in 3-D).
    assert np.all(d_xz <= KITTI_GAMMA_M)
    assert int((d_xyz > KITTI_GAMMA_M).sum()) > 0
    assert np.all(in_s) and np.all(non_trivial)
    # ... and they are exactly the non-trivial components: every pair of a non-trivial
    # component is labelled (the labels exclude the temporal neighbours, i.e. simple loops).
    runs = loops.runs()
    labelled = set(zip(lj.tolist(), li.tolist(), strict=True))  # as (i, j) with i < j
    found = set()
    for row, a, b, c in zip(
        runs["row"], runs["start"], runs["end"], runs["component"], strict=True
    ):
        if not trivial[c]:
            found.update((int(row), col) for col in range(int(a), int(b) + 1))
    assert found == labelled
    assert len(table["id"]) == 7 and int(trivial.sum()) == 1
    assert loops.warnings == []
    # And the whole result against the dense reference (4541^2 cells).
    check_dense(loops, t, xz, KITTI_GAMMA_M)


def test_kitti00_read_as_plane_matches_numpy(data_dir, tmp_path, kitti00):
    """The same ground plane through read_trajectory (a TUM file written from the poses)."""
    t, xz, xyz, _, _ = kitti00
    path = tmp_path / "kitti00.tum"
    quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    np.savetxt(path, np.c_[t, xyz, quaternion], fmt="%.9f")
    traj = il.read_trajectory(path, axes=(0, 2))
    np.testing.assert_allclose(traj.positions, xz, atol=1e-9)
    np.testing.assert_allclose(traj.timestamps, t, atol=1e-9)


def test_tum_freiburg1_xyz_equals_dense_reference(data_dir, check_dense):
    path = require(data_dir / "tum_rgbd" / "freiburg1_xyz-groundtruth.txt")
    traj = il.read_trajectory(path)
    columns = np.loadtxt(path, comments="#")  # t tx ty tz qx qy qz qw
    assert len(traj) == len(columns) == 3000 and traj.dim == 3
    np.testing.assert_array_equal(traj.timestamps, columns[:, 0])
    np.testing.assert_array_equal(traj.positions, columns[:, 1:4])
    gamma = 0.05
    loops = il.find_loops(traj, gamma=gamma, separation=None)
    check_dense(loops, columns[:, 0], columns[:, 1:4], gamma)
    assert (~loops.components["trivial"]).sum() > 0  # the camera sways back and forth
