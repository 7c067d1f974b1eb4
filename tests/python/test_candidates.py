"""Candidates a front end can use: each sampled pair carries the relative pose the trajectory
predicts between its poses (the scan matcher's initial guess), checked against GTSAM's
``Pose3.between`` on KITTI 00 and evo's ``relative_se3`` on TUM RGB-D, through the Python
table and the ``loops sample`` CSV, JSON and g2o files. Skipped where ``shared/data`` is absent."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import inexact_loops as il

Rotation = pytest.importorskip("scipy.spatial.transform").Rotation

COLUMNS = ["dx", "dy", "dz", "dqx", "dqy", "dqz", "dqw", "dtheta_rad"]


def kitti_matrices(path):
    """KITTI's rows as 4x4 matrices, read by numpy alone (time, then a row-major 3x4 block)."""
    rows = np.loadtxt(path)
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :] = rows[:, 1:].reshape(-1, 3, 4)
    return poses


def assert_guesses(guesses, pairs, between, what):
    """``guesses`` (n x 8) equal ``between(i, j)`` (a 4x4 matrix) for every pair ``(i, j)``."""
    assert len(guesses) == len(pairs) > 0, what
    for (i, j), guess in zip(pairs, guesses, strict=True):
        expected = between(i, j)
        np.testing.assert_allclose(guess[:3], expected[:3, 3], atol=1e-6, err_msg=f"{what} {i} {j}")
        rotation = Rotation.from_quat(guess[3:7])
        error = (rotation.inv() * Rotation.from_matrix(expected[:3, :3])).magnitude()
        assert error < 1e-6, f"{what} {i} {j}: rotation off by {error} rad"


def test_guesses_are_gtsams_between_on_kitti(data_dir, tmp_path):
    gtsam = pytest.importorskip("gtsam")
    path = data_dir / "kitti_odometry" / "00.txt"
    matrices = kitti_matrices(path)

    def between(i, j):
        # Pose3 wants an orthonormal rotation: the file prints 6 digits.
        def pose(m):
            rotation = Rotation.from_matrix(m[:3, :3]).as_matrix()
            return gtsam.Pose3(gtsam.Rot3(rotation), m[:3, 3])

        return pose(matrices[i]).between(pose(matrices[j])).matrix()

    traj = il.read_trajectory(path, metric="se3(rotation_weight_m_per_rad=0)")
    loops = il.find_loops(traj, gamma=6.0)
    samples = il.sample(loops, "rho", budget=300, seed=0, trajectory=traj)
    pairs = list(zip(samples.i.tolist(), samples.j.tolist(), strict=True))
    assert_guesses(samples.relative_poses, pairs, between, "python")
    assert np.isnan(samples.relative_poses[:, 7]).all(), "dtheta is for SE(2) only"
    frame = samples.to_pandas()
    np.testing.assert_array_equal(frame[COLUMNS[:7]].to_numpy(), samples.relative_poses[:, :7])

    # The command line, on the positions (its default metric), gives the same guesses from the
    # orientations it keeps, in its CSV, JSON and g2o files.
    csv, js, g2o = tmp_path / "pairs.csv", tmp_path / "pairs.json", tmp_path / "pairs.g2o"
    subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", "sample", str(path), "--gamma", "6"]
        + ["--sampler", "rho", "--budget", "300", "--seed", "0"]
        + ["--csv", str(csv), "--json", str(js), "--g2o", str(g2o)],
        check=True,
        capture_output=True,
    )
    pandas = pytest.importorskip("pandas")
    rows = pandas.read_csv(csv)
    pairs = list(zip(rows["i"].tolist(), rows["j"].tolist(), strict=True))
    from_csv = rows[COLUMNS].to_numpy(dtype=float)
    assert_guesses(from_csv, pairs, between, "csv")
    document = json.loads(js.read_text())
    from_json = np.array(
        [[s[c] if s[c] is not None else np.nan for c in COLUMNS] for s in document["samples"]]
    )
    np.testing.assert_array_equal(from_json, from_csv)
    edges = [
        line.split() for line in g2o.read_text().splitlines() if line.startswith("EDGE_SE3:QUAT")
    ]
    from_g2o = np.array([[float(v) for v in edge[3:10]] for edge in edges])
    np.testing.assert_array_equal(from_g2o, from_csv[:, :7])


def test_guesses_are_evos_relative_se3_on_tum(data_dir):
    lie = pytest.importorskip("evo.core.lie_algebra")
    file_interface = pytest.importorskip("evo.tools.file_interface")
    path = data_dir / "tum_rgbd" / "freiburg1_xyz-groundtruth.txt"
    reference = file_interface.read_tum_trajectory_file(str(path)).poses_se3
    traj = il.read_trajectory(path, metric="se3(rotation_weight_m_per_rad=0.1)")
    loops = il.find_loops(traj, gamma=0.05)
    samples = il.sample(loops, "one", budget=200, seed=1, trajectory=traj)
    pairs = list(zip(samples.i.tolist(), samples.j.tolist(), strict=True))
    assert_guesses(
        samples.relative_poses,
        pairs,
        lambda i, j: lie.relative_se3(reference[i], reference[j]),
        "evo",
    )


def test_positions_alone_give_differences_and_detections_none():
    traj = il.Trajectory(np.arange(4.0), np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.2], [0.1, 0.3]]))
    loops = il.find_loops(traj, gamma=0.5, separation=None)
    samples = il.sample(loops, "alpha", rate=1.0, seed=0, trajectory=traj)
    for (i, j), guess in zip(
        zip(samples.i, samples.j, strict=True), samples.relative_poses, strict=True
    ):
        np.testing.assert_array_equal(guess[:3], [*(traj.positions[j] - traj.positions[i]), 0.0])
        assert np.isnan(guess[3:]).all()
    clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
    unplaced = il.sample(clusters, "alpha", rate=1.0, seed=0)
    assert np.isnan(unplaced.relative_poses).all()
    np.testing.assert_allclose(
        unplaced.measure(traj).relative_poses[0, :2], traj.positions[3] - traj.positions[0]
    )
