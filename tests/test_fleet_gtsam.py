"""samples.g2o of `loops fleet`, read by GTSAM: every edge is a `BetweenFactorPose3` whose keys
are `gtsam.symbol(letter, pose)` of its row of samples.csv (robot letter a, b, ... for the
sessions in fleet order, the pose's index in its session), and whose measurement is the pose of
the later session's pose in the frame of the earlier's, as GTSAM computes it from the sessions'
TUM files. Skipped, saying so, when gtsam is not installed (`pip install gtsam`).
"""

from __future__ import annotations

import csv
import subprocess
from pathlib import Path

import numpy as np
import pytest


def test_fleet_g2o_keys_and_measurements_are_gtsams(tmp_path: Path, loops_cli: Path) -> None:
    gtsam = pytest.importorskip(
        "gtsam", reason="GTSAM's Python bindings are not installed (pip install gtsam)"
    )
    logs = tmp_path / "logs"
    synth = [loops_cli, "synth", logs, "--vehicles", "2", "--days", "2", "--duration-s", "300"]
    subprocess.run([*synth, "--format", "tum"], check=True, capture_output=True)
    files = sorted(logs.glob("*.tum"))
    out = tmp_path / "out"
    args = [loops_cli, "fleet", *files, "--gamma", "40", "--budget", "200", "--between-only"]
    subprocess.run([*args, "--out", out, "--quiet"], check=True, capture_output=True)

    with (out / "samples.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 200
    poses = [np.loadtxt(file) for file in files]  # t x y z qx qy qz qw, in fleet order

    def pose(session: int, index: int):
        _, x, y, z, qx, qy, qz, qw = poses[session][index]
        return gtsam.Pose3(gtsam.Rot3.Quaternion(qw, qx, qy, qz), gtsam.Point3(x, y, z))

    graph, initial = gtsam.readG2o(str(out / "samples.g2o"), True)
    assert graph.size() == len(rows) and initial.size() == 0
    for k, row in enumerate(rows):
        a, b, i, j = (int(row[name]) for name in ("session_a", "session_b", "i", "j"))
        assert a != b, "between sessions only"
        factor = graph.at(k)
        keys = [gtsam.symbol(chr(ord("a") + a), i), gtsam.symbol(chr(ord("a") + b), j)]
        assert list(factor.keys()) == keys, (row, [gtsam.Symbol(key).string() for key in keys])
        symbol = gtsam.Symbol(factor.keys()[1])
        assert (chr(symbol.chr()), symbol.index()) == (chr(ord("a") + b), j)
        expected = pose(a, i).between(pose(b, j))
        assert factor.measured().equals(expected, 1e-9), (row, factor.measured(), expected)
