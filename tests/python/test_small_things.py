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


def test_sampler_names_and_default_budget_come_from_the_core(loops_cli):
    import inexact_loops as il
    from inexact_loops.dask import _cli as dask_cli

    traj = il.urban_drive(duration_s=300.0, seed=3)
    loops = il.find_loops(traj, gamma=40.0)
    assert set(il.SAMPLER_NAMES).isdisjoint(il.BASELINE_NAMES)
    for name in il.SAMPLER_NAMES + il.BASELINE_NAMES:
        il.sample(loops, name, budget=5, seed=0, trajectory=traj)
    with pytest.raises(il.errors.LoopsError) as refused:
        il.sample(loops, "no-such-sampler", budget=5, seed=0)
    listed = re.findall(r"[a-z][a-z-]+", str(refused.value).split("expected", 1)[-1])
    assert set(il.SAMPLER_NAMES + il.BASELINE_NAMES) <= set(listed), str(refused.value)
    assert il.DEFAULT_SAMPLER in il.SAMPLER_NAMES

    # loops-dask's help lists the samplers that draw from tiles, with the core's default budget.
    helps = {a.dest: a.help for a in dask_cli._parser()._actions}
    assert all(name in helps["sampler"] for name in il.SAMPLER_NAMES)
    assert not any(name in helps["sampler"] for name in il.BASELINE_NAMES)
    assert f"default: {il.DEFAULT_BUDGET} " in helps["budget"]

    # The command line draws DEFAULT_BUDGET samples when given neither a rate nor a budget.
    cli = subprocess.run(
        [loops_cli, "sample", "--help"], capture_output=True, text=True, check=True
    )
    assert f"[default: {il.DEFAULT_BUDGET}" in " ".join(cli.stdout.split()), cli.stdout
