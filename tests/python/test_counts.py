"""One count of pairs everywhere: pose pairs {i, j}, i < j. The command line's summary, the
component table, Python's ``Loops`` and the samplers' candidates agree on KITTI 00 (with a
revisit separation: no trivial component) and on a synthetic drive (without one); samples that
lie in no component are said so beside P1. Skipped where ``shared/data`` is absent (KITTI)."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np

import inexact_loops as il


def cli(*args):
    done = subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", *map(str, args)],
        check=True,
        capture_output=True,
        text=True,
    )
    return done.stdout


def table_and_summary(out):
    summary = int(re.search(r"(\d+) pose pairs \(i < j\)", out).group(1))
    rows = [line.split() for line in out.splitlines() if re.match(r"\s+\d+\s+(yes|no)\s", line)]
    return summary, sum(int(row[3]) for row in rows)


def test_summary_table_and_python_count_the_same_pairs(data_dir, tmp_path):
    path = data_dir / "kitti_odometry" / "00.txt"
    summary, table = table_and_summary(cli("components", path, "--gamma", "6", "--limit", "0"))
    traj = il.read_trajectory(path)
    loops = il.find_loops(traj, gamma=6.0)
    assert summary == table == loops.pose_pair_count > 0
    assert int(loops.components["pose_pair_count"].sum()) == loops.pose_pair_count
    rho = il.sample(loops, "rho", budget=10, seed=0, trajectory=traj)
    assert rho.available == loops.pose_pair_count


def test_without_separation_trivial_components_count_alike(tmp_path):
    t = np.arange(200.0)
    xy = np.c_[np.cos(t / 20), np.sin(t / 20)] * 10
    path = tmp_path / "circle.tum"
    np.savetxt(path, np.c_[t, xy, np.zeros((200, 4)), np.ones(200)])
    summary, table = table_and_summary(
        cli("components", path, "--gamma", "1.5", "--no-separation", "--limit", "0")
    )
    loops = il.find_loops(il.read_trajectory(path), gamma=1.5, separation=None)
    assert summary == table == loops.pose_pair_count
    assert loops.pair_count == 2 * loops.pose_pair_count + len(t)


def test_samples_in_no_component_are_said(tmp_path):
    t = np.arange(200.0)
    xy = np.c_[np.cos(t / 20), np.sin(t / 20)] * 10
    path = tmp_path / "circle.tum"
    np.savetxt(path, np.c_[t, xy, np.zeros((200, 4)), np.ones(200)])
    detections = tmp_path / "det.csv"
    # One true revisit (a lap apart) and three pairs half a lap apart (20 m).
    detections.write_text("t,t_prime\n10,135.7\n10,73\n40,103\n50,113\n")
    out = cli(
        "sample",
        path,
        "--gamma",
        "1.5",
        "--detections",
        detections,
        "--epsilon-s",
        "5",
        "--sampler",
        "alpha",
        "--rate",
        "1",
    )
    assert "3 of 4 samples lie in no loop component" in out, out
