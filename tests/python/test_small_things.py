"""Small things a new user hits: install lines that work from a checkout (the package is not on
a package index), a stripped extension module in release builds, pose-graph "times" that are
vertex ids said as such."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]


def test_install_lines_work_from_a_checkout():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    files += sorted((ROOT / "python" / "inexact_loops").rglob("*.py"))
    for path in files:
        for number, line in enumerate(path.read_text().splitlines(), 1):
            assert not re.search(r"pip install '?inexact-loops", line), (
                f"{path.name}:{number}: {line}"
            )


def test_release_builds_strip_the_extension_module():
    tomllib = pytest.importorskip("tomllib")
    profile = tomllib.loads((ROOT / "Cargo.toml").read_text())["profile"]
    assert profile["release"].get("strip") in ("symbols", True)


def test_graph_times_that_are_vertex_ids_are_not_seconds(tmp_path):
    path = tmp_path / "loop.g2o"
    path.write_text("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 5 1 0 0\nEDGE_SE2 0 5 1 0 0 1 0 0 1 0 1\n")
    out = subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", "info", str(path)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert "vertex ids 0 to 5 (no times" in out and " s\n" not in out.split("poses")[1], out


def test_se3_takes_the_quaternions_read_trajectory_takes(tmp_path):
    import numpy as np

    import inexact_loops as il

    q = np.array([[0.0, 0.0, 0.7071, 0.7071], [0.0, 0.0, 0.3827, 0.9239]])  # 4 decimals
    path = tmp_path / "two.tum"
    path.write_text("".join(f"{t} 0 0 0 {' '.join(map(str, row))}\n" for t, row in enumerate(q)))
    from_file = il.read_trajectory(path, metric="se3(rotation_weight_m_per_rad=1)")
    made = il.Trajectory.se3(np.arange(2.0), np.zeros((2, 3)), q)
    np.testing.assert_array_equal(made.positions, from_file.positions)
