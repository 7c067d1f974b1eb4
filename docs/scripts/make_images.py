#!/usr/bin/env python3
"""Draws the figures of the documentation site into ``docs/images/`` with the library's own
plots (``inexact_loops.plot``), so every picture on the site is what the code draws today.

    python docs/scripts/make_images.py            # every figure; existing files replaced
    python docs/scripts/make_images.py --only concepts

The concept figures use the built-in synthetic trajectories. The tutorial figures use the public
data sets in ``../shared/data`` beside the checkout (KITTI 00 and its loop labels, TUM RGB-D
fr2/desk, MulRan KAIST 01 and 02); without it they are left as they are, saying so. The figures
are small PNGs (96 dpi); the data itself is never copied into the repository.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import inexact_loops as il  # noqa: E402
from inexact_loops import plot  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "images"
DATA = ROOT.parent / "shared" / "data"
DPI = 96


def save(fig: plt.Figure, name: str) -> None:
    fig.tight_layout()
    fig.savefig(OUT / name, dpi=DPI)
    plt.close(fig)
    print(f"wrote docs/images/{name}")


def corridor() -> il.Trajectory:
    """Out along a corridor, back, and out again, with a detour: S_gamma has a trivial
    component with holes and revisits off the diagonal."""
    t = np.arange(0.0, 300.0, 0.5)
    x = np.interp(t, [0, 100, 200, 300], [0, 50, 0, 50])
    y = 4.0 * np.sin(np.pi * np.clip((t - 100.0) / 100.0, 0.0, 1.0))
    return il.Trajectory(t, np.c_[x, y])


def concepts() -> None:
    traj = corridor()
    paper = il.find_loops(traj, gamma=3.0, separation=None)
    revisits = il.find_loops(traj, gamma=3.0)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    axes[0].plot(*traj.positions.T, color="0.3")
    axes[0].set(title="the path: out, back, out again", xlabel="x (m)", ylabel="y (m)")
    axes[0].set_aspect("equal", adjustable="datalim")
    plot.distance_image(traj, paper, ax=axes[1])
    axes[1].set_title(f"S_γ (γ = 3 m): {len(paper.components['id'])} components", pad=30)
    plot.distance_image(traj, revisits, ax=axes[2])
    axes[2].set_title(f"revisits (path ≥ 4γ): {len(revisits.components['id'])} components", pad=30)
    save(fig, "concepts_sublevel_set.png")

    drive = il.urban_drive(duration_s=1800.0, seed=1)
    loops = il.find_loops(drive, gamma=40.0)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    plot.trajectory_by_duration(drive, loops, ax=axes[0])
    axes[0].set_title("loop duration τ along a 30 min drive", pad=30)
    plot.distance_image(drive, loops, ax=axes[1], outlines=True)
    axes[1].set_title("its revisit components in the (t, t′) plane", pad=30)
    save(fig, "concepts_tau.png")

    samples = {
        name: il.sample(loops, name, budget=300, seed=0, trajectory=drive)
        for name in ("alpha", "rho", "one")
    }
    fig = plt.figure(figsize=(12, 5.2))
    grid = fig.add_gridspec(2, 2)
    image = fig.add_subplot(grid[:, 0])
    plot.distance_image(drive, loops, ax=image, samples=samples, colorbar=False)
    image.set_title("300 samples of σ_α, σ_ρ and σ_1", pad=30)
    top, bottom = fig.add_subplot(grid[0, 1]), fig.add_subplot(grid[1, 1])
    plot.samples_per_component(loops, samples, axes=(top, bottom))
    top.set_title("samples per component, smallest to largest (P1-P3)", pad=30)
    save(fig, "concepts_samplers.png")


def kitti() -> None:
    from scipy.io import loadmat

    traj = il.read_trajectory(DATA / "kitti_odometry" / "00.txt", axes=(0, 2))
    loops = il.find_loops(traj, gamma=6.0)
    truth = loadmat(DATA / "kitti_loop_gt" / "kitti00GroundTruth.mat")["truth"]
    j, i = np.nonzero(truth)  # strictly lower triangular: row j > column i
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    plot.trajectory_by_duration(traj, loops, ax=axes[0])
    axes[0].set_title("KITTI 00: loop duration τ (γ = 6 m)", pad=30)
    labelled = {"labelled pairs": np.c_[j, i][:: max(1, len(i) // 2000)]}
    plot.distance_image(traj, loops, ax=axes[1], samples=labelled, sample_size=1.0)
    axes[1].set_title(f"{len(loops.components['id'])} revisit components and the labels", pad=30)
    save(fig, "tutorial_kitti00.png")


def rosbag2() -> None:
    path = DATA / "tum_rgbd" / "fr2_desk_groundtruth.txt"
    traj = il.read_trajectory(path, drop_duplicate_stamps=True)
    loops = il.find_loops(traj, gamma=0.3)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    plot.trajectory_by_duration(traj, loops, ax=axes[0])
    axes[0].set_title("fr2/desk: loop duration τ (γ = 0.3 m)", pad=30)
    samples = il.sample(loops, il.DEFAULT_SAMPLER, budget=200, seed=0, trajectory=traj)
    plot.distance_image(traj, loops, ax=axes[1], samples=samples)
    axes[1].set_title("revisit components and 200 candidate pairs", pad=30)
    save(fig, "tutorial_rosbag2.png")


def mulran() -> None:
    folder = DATA / "mulran_kaist"
    fleet = il.Fleet(
        {
            "kaist01": folder / "kaist01_localization_poses01_seq02asmap.txt",
            "kaist02": folder / "kaist02_localization_poses02_seq02asmap.txt",
        },
        rate_hz=10.0,
    )
    loops = il.find_fleet_loops(fleet, gamma=15.0)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    plot.fleet_trajectories(fleet, loops, ax=axes[0])
    axes[0].set_title("MulRan KAIST 01 and 02: where the drives meet", pad=30)
    plot.overlap_matrix(loops, ax=axes[1])
    axes[1].set_title("overlap matrix α (s²)")
    save(fig, "tutorial_mulran.png")


FIGURES = {"concepts": concepts, "kitti": kitti, "rosbag2": rosbag2, "mulran": mulran}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=sorted(FIGURES), default=list(FIGURES))
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    for name in args.only:
        if name != "concepts" and not DATA.is_dir():
            print(f"skipping {name}: no data at {DATA} (the public data sets beside the checkout)")
            continue
        FIGURES[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
