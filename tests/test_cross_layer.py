"""The same input through the CLI, the Python API and the file reader gives the same answer."""

import json
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
