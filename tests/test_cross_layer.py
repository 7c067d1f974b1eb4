"""The same input through the CLI, the Python API and the file reader gives the same answer."""

import csv
import json
import math
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def loops_binary(loops_cli: Path) -> Path:
    """The debug `loops` binary (the shared ``loops_cli`` fixture of conftest.py)."""
    return loops_cli


def write_tum(path: Path, traj: il.Trajectory) -> None:
    """A TUM file holding `traj` exactly (repr round-trips float64)."""
    lines = ["# timestamp tx ty tz qx qy qz qw"]
    for t, (x, y, z) in zip(traj.timestamps.tolist(), traj.positions.tolist(), strict=True):
        lines.append(f"{t!r} {x!r} {y!r} {z!r} 0 0 0 1")
    path.write_text("\n".join(lines) + "\n")


def test_cli_json_equals_python_api(tmp_path: Path, loops_binary: Path) -> None:
    traj = il.urban_drive(duration_s=900.0, seed=11)
    tum = tmp_path / "drive.tum"
    write_tum(tum, traj)
    out = tmp_path / "loops.json"
    subprocess.run(
        [loops_binary, "components", tum, "--gamma", "40", "--json", out, "--limit", "0"],
        check=True,
        capture_output=True,
    )
    report = json.loads(out.read_text())

    read = il.read_trajectory(tum)
    np.testing.assert_array_equal(read.timestamps, traj.timestamps)
    np.testing.assert_array_equal(read.positions, traj.positions)

    loops = il.find_loops(read, gamma=40.0)
    table = loops.components
    assert report["poses"] == len(traj)
    assert report["pair_count"] == loops.pair_count
    assert len(report["components"]) == len(table["id"]) > 1
    for row, c in enumerate(report["components"]):
        assert c["id"] == table["id"][row]
        assert c["trivial"] == table["trivial"][row]
        assert c["area_s2"] == pytest.approx(table["area_s2"][row], rel=1e-12)
        assert c["pair_count"] == table["pair_count"][row]
        assert c["holes"] == table["holes"][row]
        assert c["i_range"] == [table["i_min"][row], table["i_max"][row]]
        assert c["j_range"] == [table["j_min"][row], table["j_max"][row]]
        assert c["closest_pair"] == [table["closest_i"][row], table["closest_j"][row]]
        assert c["closest_distance"] == pytest.approx(table["closest_distance"][row], abs=1e-12)
    density = loops.loop_density(traj.timestamps[0], traj.timestamps[-1])
    assert report["loop_density_s"] == pytest.approx(density, rel=1e-12)


def test_cli_error_is_one_line(tmp_path: Path, loops_binary: Path) -> None:
    bad = tmp_path / "bad.tum"
    bad.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n1 2 0 0 0 0 0 1\n")
    result = subprocess.run(
        [loops_binary, "components", bad, "--gamma", "1"], capture_output=True, text=True
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1
    assert "line 3" in result.stderr
    with pytest.raises(il.InvalidTrajectoryError, match="line 3"):
        il.read_trajectory(bad)


MCAP_FIXTURES = ROOT / "crates" / "loops-io" / "tests" / "make_mcap_fixtures.py"


def test_mcap_through_python_and_cli(tmp_path: Path, loops_binary: Path) -> None:
    """An MCAP written by the official writers: topics listed alike by Python and `loops info`,
    poses read by topic, and an ambiguous read names the topics."""
    pytest.importorskip("mcap_ros2")
    out = tmp_path / "fixtures"
    subprocess.run([sys.executable, MCAP_FIXTURES, out], check=True, capture_output=True)
    path = out / "ros2_chunked.mcap"
    topics = il.list_topics(path)
    readable = [t["topic"] for t in topics if t["pose_type"] is not None]
    assert len(readable) >= 2
    info = subprocess.run([loops_binary, "info", path], check=True, capture_output=True, text=True)
    for topic in readable:
        assert topic in info.stdout
    with pytest.raises(il.LoopsIOError, match=readable[0]):
        il.read_trajectory(path)
    read = 0
    for topic in readable:
        try:
            traj = il.read_trajectory(path, topic=topic, time="log")
        except il.LoopsIOError as error:  # a TF topic with several frame pairs names them
            assert "frame pairs" in str(error)
            traj = il.read_trajectory(path, topic=topic, frames=("odom", "base_link"))
        assert len(traj) >= 2
        assert np.all(np.diff(traj.timestamps) > 0)
        read += 1
    assert read == len(readable)


def _write_drive(path: Path, t0: float, n: int, *, repeat: int, stretch: int) -> None:
    """A TUM file of `n` poses on a circle from `t0`, pose `repeat` written twice (its stamp
    repeated, the copy elsewhere) and the quaternion of pose `stretch` 0.4 % off unit length."""
    lines = ["# timestamp tx ty tz qx qy qz qw"]
    for k in range(n):
        t, a = t0 + 0.5 * k, 0.3 * (t0 + k)
        q = [0.0, 0.0, math.sin(a / 2), math.cos(a / 2)]
        if k == stretch:
            q = [1.004 * v for v in q]
        row = [t, 10 * math.cos(a), 10 * math.sin(a), 0.01 * k, *q]
        lines.append(" ".join(repr(float(v)) for v in row))
        if k == repeat:
            lines.append(f"{t!r} 99 99 99 0 0 0 1")
    path.write_text("\n".join(lines) + "\n")


def _cli_poses(folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """The times and positions of a session as the CLI read them (its loop_duration.csv)."""
    rows = np.genfromtxt(folder / "loop_duration.csv", delimiter=",", names=True)
    return rows["t_s"], np.c_[rows["x"], rows["y"], rows["z"]]


def test_cli_and_python_read_the_same_poses(tmp_path: Path, loops_binary: Path) -> None:
    """The read options through both surfaces give the same poses: two files joined in time
    order (given out of order), a repeated stamp dropped, a quaternion normalised within the
    given tolerance, the SE(3) metric that needs the orientations, and a KITTI file by format,
    rate and plane."""
    early, late = tmp_path / "early.tum", tmp_path / "late.tum"
    _write_drive(early, 0.0, 40, repeat=5, stretch=7)
    _write_drive(late, 100.0, 40, repeat=30, stretch=3)
    kitti = tmp_path / "poses.txt"
    steps = np.linspace(0.0, 2 * np.pi, 30)
    kitti.write_text(
        "".join(
            f"1 0 0 {10 * math.cos(a)!r} 0 1 0 {0.5 * a!r} 0 0 1 {10 * math.sin(a)!r}\n"
            for a in steps.tolist()
        )
    )
    metric = "se3(rotation_weight_m_per_rad=1)"
    out = tmp_path / "out"
    subprocess.run(
        [
            loops_binary,
            "fleet",
            "--session",
            f"joined={late},{early}",
            "--gamma",
            "3",
            "--out",
            out,
            "--drop-duplicate-stamps",
            "--quaternion-tolerance",
            "0.01",
            "--metric",
            metric,
        ],
        check=True,
        capture_output=True,
    )
    with pytest.warns(il.DroppedInputWarning):
        read = il.read_trajectory(
            [late, early], drop_duplicate_stamps=True, quaternion_tolerance=0.01, metric=metric
        )
    times, positions = _cli_poses(out / "joined")
    assert len(read) == len(times) == 80
    np.testing.assert_array_equal(read.timestamps, times)
    np.testing.assert_array_equal(read.positions[:, :3], positions)  # then the quaternion
    np.testing.assert_allclose(np.linalg.norm(read.positions[:, 3:], axis=1), 1.0, atol=1e-12)
    with pytest.raises(il.LoopsError, match="line 10"):  # the stretched quaternion, by default
        il.read_trajectory(early, drop_duplicate_stamps=True, metric=metric)

    out = tmp_path / "kitti"
    subprocess.run(
        [
            loops_binary,
            "run",
            kitti,
            "--gamma",
            "3",
            "--out",
            out,
            "--format",
            "kitti",
            "--rate-hz",
            "10",
            "--axes",
            "0,2",
        ],
        check=True,
        capture_output=True,
    )
    read = il.read_trajectory(kitti, format="kitti", rate_hz=10.0, axes=(0, 2))
    times, positions = _cli_poses(out / "poses")
    np.testing.assert_array_equal(read.timestamps, times)
    np.testing.assert_array_equal(read.positions, positions[:, [0, 2]])  # the plane x-z
    np.testing.assert_array_equal(read.positions[:, 1], 10 * np.sin(steps))


def _header(path: Path) -> list[str]:
    return path.read_text().splitlines()[0].split(",")


def test_cli_csv_headers_are_the_python_columns(tmp_path: Path, loops_binary: Path) -> None:
    """Each result table has one column list: the CLI's CSV header is the Python table's
    columns, in order (less ``samples``, a count only the files carry; a fleet's components less
    the joint component's ``pose_pair_count`` and ``run_count``, which a store or a tile merge
    does not keep; a fleet's samples less ``sampler``, the samples' own attribute)."""
    monday, tuesday = tmp_path / "monday.tum", tmp_path / "tuesday.tum"
    write_tum(monday, il.urban_drive(duration_s=300.0, seed=1))
    write_tum(tuesday, il.urban_drive(duration_s=300.0, seed=2))
    out = tmp_path / "fleet"
    subprocess.run(
        [loops_binary, "fleet", monday, tuesday, "--gamma", "30", "--out", out],
        check=True,
        capture_output=True,
    )
    traj = il.read_trajectory(monday)
    loops = il.find_loops(traj, gamma=30.0)
    fleet = il.Fleet([monday, tuesday])
    fleet_loops = il.find_fleet_loops(fleet, gamma=30.0)
    joint_only = {"pose_pair_count", "run_count", "samples"}

    assert list(loops.components) == [
        c for c in _header(out / "monday" / "components.csv") if c != "samples"
    ]
    assert list(fleet_loops.components) == [
        c for c in _header(out / "components.csv") if c not in joint_only
    ]
    assert list(fleet_loops.session_pairs()) == _header(out / "session_pairs.csv")
    fleet_samples = il.sample_fleet(fleet_loops, budget=10, seed=0)
    assert list(fleet_samples.table) == [c for c in _header(out / "samples.csv") if c != "sampler"]
    online = il.OnlineLoops(gamma=30.0, dim=traj.dim)
    online.push_many(traj.timestamps, traj.positions)
    online_columns = [c for c in online.components if c not in ("first_pose", "last_pose")]
    assert online_columns == [
        c
        for c in _header(out / "monday" / "components.csv")
        if c not in ("pose_pair_count", "samples")
    ]


def test_closest_pairs_and_samples_are_placed_on_their_poses(
    tmp_path: Path, loops_binary: Path
) -> None:
    """``components.csv`` has the positions of each closest pair's poses and ``samples.csv``
    those of each sample's, read off the log itself; Python's tables give the same values, and a
    pickled result keeps them."""
    traj = il.urban_drive(duration_s=900.0, seed=11)
    tum = tmp_path / "drive.tum"
    write_tum(tum, traj)
    out = tmp_path / "out"
    subprocess.run(
        [loops_binary, "run", tum, "--gamma", "40", "--out", out],
        check=True,
        capture_output=True,
    )
    xyz = np.loadtxt(tum)[:, 1:4]
    with open(next(out.rglob("components.csv"))) as file:
        components = list(csv.DictReader(file))
    with open(next(out.rglob("samples.csv"))) as file:
        samples = list(csv.DictReader(file))
    assert components and samples
    axes = "xyz"
    for row in components:
        for end in "ij":
            pose = int(row[f"closest_{end}"])
            placed = [float(row[f"closest_{end}_{a}"]) for a in axes]
            np.testing.assert_array_equal(placed, xyz[pose], err_msg=str(row))
    for row in samples:
        for end in "ij":
            placed = [float(row[f"{end}_{a}"]) for a in axes]
            np.testing.assert_array_equal(placed, xyz[int(row[end])], err_msg=str(row))
    loops = il.find_loops(il.read_trajectory(tum), gamma=40.0)
    table = loops.components
    for end in "ij":
        for k, a in enumerate(axes):
            column = f"closest_{end}_{a}"
            np.testing.assert_array_equal(
                table[column], xyz[table[f"closest_{end}"], k], err_msg=column
            )
            np.testing.assert_array_equal(
                pickle.loads(pickle.dumps(loops)).components[column], table[column]
            )
    frame = il.sample(loops, trajectory=il.read_trajectory(tum), budget=50, seed=1).to_pandas()
    for end in "ij":
        placed = frame[[f"{end}_{a}" for a in axes]].to_numpy()
        np.testing.assert_array_equal(placed, xyz[frame[end].to_numpy()])


def test_fleet_closest_pairs_are_placed_on_their_sessions_poses(
    tmp_path: Path, loops_binary: Path
) -> None:
    """A fleet's ``components.csv`` and :attr:`FleetLoops.components` place each closest pair on
    its two sessions' poses, read off the logs themselves: pose ``closest_i`` of session
    ``session_a``, pose ``closest_j`` of session ``session_b``."""
    logs = [tmp_path / "monday.tum", tmp_path / "tuesday.tum"]
    for seed, log in enumerate(logs, start=1):
        write_tum(log, il.urban_drive(duration_s=600.0, seed=seed))
    out = tmp_path / "fleet"
    subprocess.run(
        [loops_binary, "fleet", *logs, "--gamma", "30", "--out", out],
        check=True,
        capture_output=True,
    )
    xyz = [np.loadtxt(log)[:, 1:4] for log in logs]
    with open(out / "components.csv") as file:
        rows = list(csv.DictReader(file))
    assert any(row["session_a"] != row["session_b"] for row in rows), "loops between sessions"
    axes = "xyz"
    for row in rows:
        for end, side in (("i", "a"), ("j", "b")):
            pose = xyz[int(row[f"session_{side}"])][int(row[f"closest_{end}"])]
            placed = [float(row[f"closest_{end}_{a}"]) for a in axes]
            np.testing.assert_array_equal(placed, pose, err_msg=str(row))
    table = il.find_fleet_loops(il.Fleet(logs), gamma=30.0).components
    for end, side in (("i", "a"), ("j", "b")):
        poses = zip(table[f"session_{side}"], table[f"closest_{end}"], strict=True)
        expected = np.array([xyz[session][pose] for session, pose in poses])
        for k, a in enumerate(axes):
            column = f"closest_{end}_{a}"
            np.testing.assert_array_equal(table[column], expected[:, k], err_msg=column)
