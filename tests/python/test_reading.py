"""What a newcomer hits reading real files from Python, and the options that read them:
``read_trajectory(..., drop_duplicate_stamps=True)``, ``times=`` for KITTI poses,
``quaternion_tolerance=``, several files as one trajectory, and ``read_detections`` with
``drop_outside_span=True``. Each lenient option is checked against numpy doing the same, warns
once per file with the count and the lines, and leaves strict reading the default. Real files
are skipped, saying so, when ../shared/data is absent."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il


def raises(error: type[BaseException], *named: str):
    """``pytest.raises(error)`` whose message must contain each of ``named`` literally."""
    return pytest.raises(error, match="".join(f"(?=.*{re.escape(text)})" for text in named))


def write_tum(path: Path, t, xyz, q=None) -> Path:
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)) if q is None else q
    rows = [
        " ".join(repr(float(v)) for v in (ti, *p, *qi)) for ti, p, qi in zip(t, xyz, q, strict=True)
    ]
    path.write_text("# timestamp tx ty tz qx qy qz qw\n" + "\n".join(rows) + "\n")
    return path


def square_laps(t0: float, laps: int) -> tuple[np.ndarray, np.ndarray]:
    """A 40 m square driven ``laps`` times at 1 m/s, one pose a second, from ``t0``."""
    k = np.arange(160 * laps)
    s = (k % 160).astype(float)
    side = (k % 160) // 40
    x = np.select([side == 0, side == 1, side == 2], [s, 40.0, 120.0 - s], 0.0)
    y = np.select([side == 0, side == 1, side == 2], [0.0, s - 40.0, 40.0], 160.0 - s)
    return t0 + k.astype(float), np.c_[x, y, np.zeros_like(x)]


def caught(call):
    """(result, [warning messages]) of ``call()``, every warning recorded."""
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always")
        result = call()
    return result, [(r.category, str(r.message)) for r in records]


# --- repeated timestamps ------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(5))
def test_drop_duplicate_stamps_keeps_the_first_pose_of_each_stamp(tmp_path, seed):
    rng = np.random.default_rng(seed)
    stamps = np.repeat(np.arange(30.0) * 0.5, rng.integers(1, 4, size=30))
    xyz = rng.normal(size=(len(stamps), 3))
    path = write_tum(tmp_path / "dups.tum", stamps, xyz)
    # numpy: the first row of each stamp.
    first = np.r_[True, np.diff(stamps) != 0]
    lines = np.flatnonzero(~first) + 2  # a header line, then one line a pose
    if lines.size:
        with raises(il.InvalidTrajectoryError, f"line {lines[0]}", "drop_duplicate_stamps=True"):
            il.read_trajectory(path)
    traj, messages = caught(lambda: il.read_trajectory(path, drop_duplicate_stamps=True))
    np.testing.assert_array_equal(traj.timestamps, stamps[first])
    np.testing.assert_array_equal(traj.positions, xyz[first])
    if lines.size:
        assert len(messages) == 1 and messages[0][0] is il.DroppedInputWarning
        assert messages[0][1].startswith(
            f"{path}: drop_duplicate_stamps=True dropped {lines.size} pose(s) whose timestamp "
            "repeats the one before (line"
        ), messages
        assert f"{lines[0]}" in messages[0][1]
    else:
        assert messages == []


def test_fr2_desk_reads_once_its_repeated_stamp_is_dropped(data_dir):
    path = data_dir / "tum_rgbd" / "fr2_desk_groundtruth.txt"
    with raises(il.InvalidTrajectoryError, "line 10863", "drop_duplicate_stamps=True"):
        il.read_trajectory(path)
    metric = "se3(rotation_weight_m_per_rad=0.5)"
    traj, messages = caught(
        lambda: il.read_trajectory(path, metric=metric, drop_duplicate_stamps=True)
    )
    assert len(traj) == 20956
    assert messages == [
        (
            il.DroppedInputWarning,
            f"{path}: drop_duplicate_stamps=True dropped 1 pose(s) whose timestamp repeats the one "
            "before (line 10863)",
        )
    ]
    raw = np.loadtxt(path)
    keep = np.r_[True, np.diff(raw[:, 0]) != 0]
    np.testing.assert_array_equal(traj.timestamps, raw[keep, 0])
    np.testing.assert_array_equal(traj.positions[:, :3], raw[keep, 1:4])


# --- KITTI times --------------------------------------------------------------------------------


def test_kitti_poses_take_a_times_file(tmp_path):
    t = 0.1037 * np.arange(25)
    poses = np.zeros((25, 12))
    poses[:, [0, 5, 10]] = 1.0
    poses[:, 3], poses[:, 11] = np.cos(t), np.sin(t)
    kitti = tmp_path / "00.txt"
    np.savetxt(kitti, poses)
    times = tmp_path / "times.txt"
    np.savetxt(times, t)
    traj = il.read_trajectory(kitti, times=times, axes=(0, 2))
    np.testing.assert_array_equal(traj.timestamps, np.loadtxt(times))
    np.testing.assert_array_equal(traj.positions, poses[:, [3, 11]])
    with raises(il.LoopsIOError, "00.txt line 1", "rate_hz", "times"):
        il.read_trajectory(kitti)
    with raises(il.InvalidParameterError, "rate_hz and times"):
        il.read_trajectory(kitti, times=times, rate_hz=10.0)
    short = tmp_path / "short.txt"
    np.savetxt(short, t[:-1])
    with raises(il.InvalidTrajectoryError, "short.txt", "24 timestamps but 25 poses"):
        il.read_trajectory(kitti, times=short)


def test_kitti_00_from_poses_and_times_equals_the_file_with_times(tmp_path, data_dir):
    path = data_dir / "kitti_odometry" / "00.txt"
    raw = np.loadtxt(path)
    lines = path.read_text().splitlines()
    (tmp_path / "00.txt").write_text("\n".join(line.split(" ", 1)[1] for line in lines) + "\n")
    (tmp_path / "times.txt").write_text("\n".join(line.split(" ", 1)[0] for line in lines) + "\n")
    traj = il.read_trajectory(tmp_path / "00.txt", times=tmp_path / "times.txt", axes=(0, 2))
    expected = il.read_trajectory(path, axes=(0, 2))
    np.testing.assert_array_equal(traj.timestamps, raw[:, 0])
    np.testing.assert_array_equal(traj.positions, expected.positions)
    # The KITTI tutorial's 7 components of the paper's S_γ (no separation): 6 revisits, 1 trivial.
    assert len(il.find_loops(traj, gamma=6.0, separation=None).components["id"]) == 7


# --- quaternions --------------------------------------------------------------------------------


def test_quaternion_tolerance_is_named_and_taken(tmp_path):
    t, xyz = square_laps(0.0, 1)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    q[7, 3] = 1.02
    path = write_tum(tmp_path / "q.tum", t, xyz, q)
    metric = "se3(rotation_weight_m_per_rad=1)"
    with raises(il.InvalidTrajectoryError, "line 9", "norm 1.02", "quaternion_tolerance"):
        il.read_trajectory(path, metric=metric)
    traj = il.read_trajectory(path, metric=metric, quaternion_tolerance=0.05)
    np.testing.assert_allclose(traj.positions[7, 3:], [0, 0, 0, 1], atol=0)
    with raises(il.InvalidTrajectoryError, "line 9", "quaternion_tolerance"):
        il.read_trajectory(path, metric=metric, quaternion_tolerance=0.01)
    # The constructor names the same option.
    with raises(il.InvalidTrajectoryError, "quaternion of pose 7", "quaternion_tolerance"):
        il.Trajectory.se3(t, xyz, q)
    assert len(il.Trajectory.se3(t, xyz, q, quaternion_tolerance=0.05)) == len(t)


# --- several files ------------------------------------------------------------------------------


def test_several_files_are_one_trajectory_in_time_order(tmp_path):
    t, xyz = square_laps(100.0, 3)
    whole = il.read_trajectory(write_tum(tmp_path / "whole.tum", t, xyz))
    parts = [
        write_tum(tmp_path / f"{name}.tum", t[a:b], xyz[a:b])
        for name, a, b in (("a", 0, 100), ("b", 100, 300), ("c", 300, 480))
    ]
    for order in ([0, 1, 2], [2, 0, 1], [1, 2, 0]):
        joined = il.read_trajectory([parts[k] for k in order])
        np.testing.assert_array_equal(joined.timestamps, whole.timestamps)
        np.testing.assert_array_equal(joined.positions, whole.positions)
    reference = il.find_loops(whole, gamma=2.0).components
    joined = il.find_loops(il.read_trajectory(parts[::-1]), gamma=2.0).components
    for column in ("area_s2", "pair_count", "i_min", "j_max"):
        np.testing.assert_array_equal(joined[column], reference[column])
    overlapping = write_tum(tmp_path / "late.tum", t[250:320], xyz[250:320])
    with raises(il.LoopsIOError, "late.tum: overlaps", "b.tum", "line 2, 350 s", "line 201, 399 s"):
        il.read_trajectory([parts[1], overlapping])


# --- detections ---------------------------------------------------------------------------------


def test_read_detections_drops_outside_the_span_on_request(tmp_path):
    t, xyz = square_laps(0.0, 2)
    traj = il.Trajectory(t, xyz)
    rng = np.random.default_rng(3)
    pairs = rng.uniform(-20.0, 340.0, size=(40, 2))
    scores = rng.uniform(size=40)
    path = tmp_path / "input.txt"
    path.write_text(
        "odom2 0 0 0 0\n"
        + "".join(
            f"loop {a!r} {b!r} {s!r}\n"
            for (a, b), s in zip(pairs.tolist(), scores.tolist(), strict=True)
        )
    )
    unplaced = il.read_detections(path)
    np.testing.assert_array_equal(unplaced.t, pairs.min(axis=1))
    np.testing.assert_array_equal(unplaced.score, scores)
    assert unplaced.i is None
    inside = ((pairs >= t[0]) & (pairs <= t[-1])).all(axis=1)
    assert 0 < inside.sum() < 40
    first_outside = int(np.flatnonzero(~inside)[0]) + 2
    with raises(il.LoopsIOError, f"input.txt line {first_outside}", "drop_outside_span=True"):
        il.read_detections(path, traj)
    det, messages = caught(lambda: il.read_detections(path, traj, drop_outside_span=True))
    expected = il.Detections(pairs[inside, 0], pairs[inside, 1], scores=scores[inside]).locate(traj)
    for column in ("t", "t_prime", "i", "j", "score"):
        np.testing.assert_array_equal(getattr(det, column), getattr(expected, column))
    assert len(messages) == 1 and messages[0][0] is il.DroppedInputWarning
    assert messages[0][1].startswith(
        f"{path}: drop_outside_span=True dropped {int((~inside).sum())} detection(s) outside the "
        f"trajectory's time span (lines {first_outside}, "
    ), messages
    # On loops as on the trajectory; nothing dropped, nothing said.
    loops = il.find_loops(traj, gamma=2.0)
    _, messages = caught(lambda: il.read_detections(path, loops, drop_outside_span=True))
    assert len(messages) == 1
    inside_only = tmp_path / "inside.txt"
    inside_only.write_text("t,t_prime\n10,170\n")
    _, messages = caught(lambda: il.read_detections(inside_only, traj, drop_outside_span=True))
    assert messages == []
    with raises(il.InvalidParameterError, "drop_outside_span needs the trajectory"):
        il.read_detections(path, drop_outside_span=True)
    with raises(TypeError, "Trajectory or Loops"):
        il.read_detections(path, 5)
    with raises(FileNotFoundError, "nope.txt"):
        il.read_detections(tmp_path / "nope.txt")


def test_corridor_has_39_detections_past_its_ground_truth(data_dir):
    traj = il.read_trajectory(data_dir / "tuc" / "SLAM" / "Corridor_GT.txt")
    path = data_dir / "tuc" / "SLAM" / "Corridor_Input.txt"
    with raises(
        il.LoopsIOError, "Corridor_Input.txt line 32673", "outside the trajectory's time span"
    ):
        il.read_detections(path, traj)
    det, messages = caught(lambda: il.read_detections(path, traj, drop_outside_span=True))
    assert len(det) == 10_019 - 39
    assert len(messages) == 1 and " dropped 39 detection(s) " in messages[0][1]
    assert det.t_prime.max() <= traj.timestamps[-1]
