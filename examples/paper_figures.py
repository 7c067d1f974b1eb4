#!/usr/bin/env python3
"""Reproduce the figures of E. Nelson, *Inexact Loops in Robotics Problems*, as PNG files.

    pip install '.[plot]'                  # from the repository root
    python examples/paper_figures.py       # writes figures/*.png
    python examples/paper_figures.py --out /tmp/figs --only fig2 fig4 --force

Figures (file names in the output folder):

- ``fig2_example_loops.png``: four trajectories in R^2 (95 % circle, double loop, spiral, a
  corridor driven out, back and out again whose trivial component has holes) and their
  pairwise distance functions with the gamma = 1 and gamma = 3 isocontours.
- ``fig4_manifold_circles.png``: a circle of radius 7 pi / 8 on the torus S^1 x S^1 and in
  SO(3) (rotation vectors), with their distance functions.
- ``fig5_real_trajectory.png``: KITTI odometry 00 (from ``--kitti``, default
  ``../shared/data/kitti_odometry/00.txt`` beside the checkout; the synthetic urban drive in
  SE(3) when absent) under the L2 metric on translations and an SE(3) metric.
- ``fig6ab_sample_zooms.png``, ``fig6c_samples_on_trajectory.png``,
  ``fig6d_loop_duration.png``, ``fig7_distance_samples.png``, ``fig8_samples_per_component.png``:
  the sampling experiment on the 2.1 h synthetic urban drive: 1 % of S_gamma drawn as
  detections, clustered with epsilon = 30 s, and 10^4 samples from each of sigma_alpha,
  sigma_rho and sigma_1.

Existing files are kept unless ``--force``. Fig. 5 needs scipy (rotation matrices to
quaternions). Takes 15-30 s.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import inexact_loops as il

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from inexact_loops import plot
except ImportError as err:
    sys.exit(f"paper_figures.py: {err}. Install the plotting extra: pip install '.[plot]'")

#: The repository's root (examples/..): the shared data sit beside it.
ROOT = Path(__file__).resolve().parents[1]
KITTI_00 = ROOT.parent / "shared" / "data" / "kitti_odometry" / "00.txt"

#: Output files of each figure, in the order they are made.
FIGURES: dict[str, list[str]] = {
    "fig2": ["fig2_example_loops.png"],
    "fig4": ["fig4_manifold_circles.png"],
    "fig5": ["fig5_real_trajectory.png"],
    "sampling": [
        "fig6ab_sample_zooms.png",
        "fig6c_samples_on_trajectory.png",
        "fig6d_loop_duration.png",
        "fig7_distance_samples.png",
        "fig8_samples_per_component.png",
    ],
}

#: The paper's samplers, in its order: sigma_alpha, sigma_rho, sigma_1.
SAMPLERS = ("alpha", "rho", "one")


# --------------------------------------------------------------------------------------------
# Fig. 2: four trajectories in R^2
# --------------------------------------------------------------------------------------------


def circle_95() -> tuple[np.ndarray, np.ndarray]:
    """95 % of a circle of radius 3 m: the gap (0.94 m) is closed at gamma = 1 and 3."""
    angle = np.linspace(0.0, 0.95 * 2 * np.pi, 400)
    return np.arange(400) * 0.1, 3.0 * np.c_[np.cos(angle), np.sin(angle)]


def double_loop() -> tuple[np.ndarray, np.ndarray]:
    """A circle of diameter 2.1 m driven twice: two loop components at gamma = 1 that merge
    into the trivial one at gamma = 3 (every pair is within the diameter)."""
    n = 361
    angle = np.arange(n) * 2 * np.pi / 180
    return np.arange(n) * 0.1, 1.05 * np.c_[np.cos(angle), np.sin(angle)]


def spiral() -> tuple[np.ndarray, np.ndarray]:
    """An outward spiral, turns 5 m apart, resampled every 0.4 m of arc: all loops simple."""
    theta = np.linspace(0.0, 2 * np.pi * 3, 100_000)
    r = 10.0 + 5.0 * theta / (2 * np.pi)
    xy = np.c_[r * np.cos(theta), r * np.sin(theta)]
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))]
    s = np.arange(0.0, arc[-1], 0.4)
    p = np.c_[np.interp(s, arc, xy[:, 0]), np.interp(s, arc, xy[:, 1])]
    return np.arange(len(p)) * 0.1, p


def corridor() -> tuple[np.ndarray, np.ndarray]:
    """Out along a 10 m corridor, back on a lane 0.8 m over, out again on a lane between.

    The legs are pairwise within gamma side by side and joined at the U-turns, so the pairs
    (leg 1 far end, leg 2 near end) are enclosed: the trivial component has holes."""
    x = np.arange(0.0, 10.05, 0.1)
    p = np.r_[
        np.c_[x, np.zeros_like(x)],
        np.c_[x[::-1], np.full_like(x, 0.8)],
        np.c_[x, np.full_like(x, 0.4)],
    ]
    return np.arange(len(p)) * 0.1, p


def path_by_time(ax, traj: il.Trajectory) -> None:
    """The path coloured by time, its start marked."""
    xy = traj.positions[:, :2]
    t = traj.timestamps - traj.timestamps[0]
    lines = LineCollection(np.stack([xy[:-1], xy[1:]], axis=1), cmap="plasma", linewidths=1.6)
    lines.set_array((t[:-1] + t[1:]) / 2)
    ax.add_collection(lines)
    ax.plot(*xy[0], "o", color="k", ms=4, label="start")
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.08 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    plt.colorbar(lines, ax=ax, label="t (s)", shrink=0.8)


def describe(loops: il.Loops) -> str:
    table = loops.components
    nontrivial = int((~table["trivial"]).sum())
    holes = int(table["holes"].sum())
    return (
        f"γ = {loops.gamma:g}: {len(table['id'])} component(s), {nontrivial} non-trivial, "
        f"{holes} hole(s)"
    )


def fig2() -> dict[str, Figure]:
    cases = {
        "(a) 95 % circle": circle_95(),
        "(b) double loop": double_loop(),
        "(c) spiral": spiral(),
        "(d) corridor: out, back, out": corridor(),
    }
    fig, axes = plt.subplots(
        2, 4, figsize=(19, 9.5), constrained_layout=True, height_ratios=[1, 1.25]
    )
    for column, (title, (t, p)) in enumerate(cases.items()):
        traj = il.Trajectory(t, p)
        by_gamma = [il.find_loops(traj, gamma=g, separation=None) for g in (1.0, 3.0)]
        if title.startswith("(d)"):
            holes = [int(loops.components["holes"][0]) for loops in by_gamma]
            assert all(h > 0 for h in holes), f"the corridor's trivial component has holes {holes}"
        path_by_time(axes[0, column], traj)
        axes[0, column].set_title(title)
        if title.startswith("(d)"):  # lanes 0.4 m apart along 10 m: stretch y to see them
            axes[0, column].set_aspect("auto")
            axes[0, column].set_ylim(-0.6, 1.4)
            axes[0, column].set_title(f"{title} (y stretched)")
        ax = plot.distance_image(traj, gamma=[1.0, 3.0], ax=axes[1, column])
        ax.set_title("\n".join(describe(loops) for loops in by_gamma), fontsize="medium", pad=24)
    fig.suptitle(
        "Fig. 2: trajectories in R² (top) and their pairwise distance π(t, t′) under L2 "
        "with the γ = 1 and γ = 3 isocontours (bottom)"
    )
    return {"fig2_example_loops.png": fig}


# --------------------------------------------------------------------------------------------
# Fig. 4: circles on the torus and in SO(3)
# --------------------------------------------------------------------------------------------


def torus_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """L2 norm of the least angular differences (radians), pairwise."""
    diff = np.remainder(a[:, None, :] - b[None, :, :] + np.pi, 2 * np.pi) - np.pi
    return np.linalg.norm(diff, axis=-1)


def rotation_matrices(quaternions_xyzw: np.ndarray) -> np.ndarray:
    """Rotation matrices (m, 3, 3) of unit quaternions in x, y, z, w order."""
    x, y, z, w = quaternions_xyzw.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def so3_chordal_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The paper's ||I - R_a R_b^T||_F = ||R_a - R_b||_F, pairwise, from quaternions."""
    ra = rotation_matrices(a).reshape(len(a), 9)
    rb = rotation_matrices(b).reshape(len(b), 9)
    diff = ra[:, None, :] - rb[None, :, :]
    return np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))


def draw_torus(ax, angles: np.ndarray, major: float = 2.0, minor: float = 1.0) -> None:
    """The torus surface and a curve of angles (theta, phi) on it."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 60), np.linspace(0, 2 * np.pi, 30))
    ring = major + minor * np.cos(v)
    ax.plot_surface(
        ring * np.cos(u), ring * np.sin(u), minor * np.sin(v), color="0.85", alpha=0.35, linewidth=0
    )
    theta, phi = angles[:, 0], angles[:, 1]
    ax.scatter(
        (major + minor * np.cos(phi)) * np.cos(theta),
        (major + minor * np.cos(phi)) * np.sin(theta),
        minor * np.sin(phi),
        c=np.arange(len(theta)),
        cmap="plasma",
        s=4,
        depthshade=False,
    )
    ax.set_box_aspect((1, 1, 0.4))
    ax.set_axis_off()


def draw_rotation_vectors(ax, vectors: np.ndarray) -> None:
    """Rotation vectors inside the ball of radius pi (the parameter space of SO(3))."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(
        np.pi * np.cos(u) * np.sin(v),
        np.pi * np.sin(u) * np.sin(v),
        np.pi * np.cos(v),
        color="0.75",
        linewidth=0.4,
    )
    ax.scatter(*vectors.T, c=np.arange(len(vectors)), cmap="plasma", s=4, depthshade=False)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (rad)")
    ax.set_ylabel("y (rad)")
    ax.set_zlabel("z (rad)")


def fig4() -> dict[str, Figure]:
    radius = 7 * np.pi / 8
    n = 400
    s = np.linspace(0.0, 2 * np.pi, n)
    t = np.arange(n) * 0.1
    circle = radius * np.c_[np.cos(s), np.sin(s)]

    torus = il.Trajectory.torus(t, circle)
    torus_loops = il.find_loops(torus, gamma=1.0, metric="torus", separation=None)
    rotations = il.Trajectory.so3_from_rotation_vectors(t, np.c_[circle, np.zeros(n)])
    so3_metric = il.metrics.SO3(rotation="chordal")
    so3_loops = il.find_loops(rotations, gamma=1.5, metric=so3_metric, separation=None)

    fig = plt.figure(figsize=(11, 10), constrained_layout=True)
    ax = fig.add_subplot(2, 2, 1, projection="3d")
    draw_torus(ax, circle)
    ax.set_title("(a) A circle in S¹ × S¹ (radius 7π/8)")
    ax = plot.distance_image(
        torus, torus_loops, ax=fig.add_subplot(2, 2, 2), metric=torus_distance, distance_unit="rad"
    )
    ax.set_title(f"(b) π(t, t′), torus metric\n{describe(torus_loops)}", pad=24)
    ax = fig.add_subplot(2, 2, 3, projection="3d")
    draw_rotation_vectors(ax, np.c_[circle, np.zeros(n)])
    ax.set_title("(c) A circle in SO(3) (rotation vectors, radius 7π/8)")
    ax = plot.distance_image(
        rotations,
        so3_loops,
        ax=fig.add_subplot(2, 2, 4),
        metric=so3_chordal_distance,
        distance_unit="",
    )
    ax.set_title(f"(d) π(t, t′), ‖I − R R′ᵀ‖_F\n{describe(so3_loops)}", pad=24)
    fig.suptitle("Fig. 4: circles of radius 7π/8 on two curved manifolds")
    return {"fig4_manifold_circles.png": fig}


# --------------------------------------------------------------------------------------------
# Fig. 5: a real trajectory under L2 and SE(3)
# --------------------------------------------------------------------------------------------


PairwiseDistance = Callable[[np.ndarray, np.ndarray], np.ndarray]


def se3_distance(rotation_weight_m_per_rad: float) -> PairwiseDistance:
    """||p_a - p_b|| + w * geodesic angle, pairwise, on (x, y, z, qx, qy, qz, qw) rows."""

    def distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        diff = a[:, None, :3] - b[None, :, :3]
        translation = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
        cosine = np.clip(np.abs(a[:, 3:] @ b[:, 3:].T), 0.0, 1.0)
        return translation + rotation_weight_m_per_rad * 2 * np.arccos(cosine)

    return distance


def kitti_se3(path: Path) -> il.Trajectory:
    """KITTI odometry poses (time + row-major 3x4 [R|t] of camera 0) as SE(3) poses."""
    from scipy.spatial.transform import Rotation

    rows = np.loadtxt(path)
    matrices = rows[:, 1:].reshape(-1, 3, 4)
    quaternions = Rotation.from_matrix(matrices[:, :, :3]).as_quat()  # x, y, z, w
    return il.Trajectory.se3(rows[:, 0], matrices[:, :, 3], quaternions, quaternion_tolerance=1e-3)


def fig5(kitti: Path) -> dict[str, Figure]:
    if kitti.is_file():
        try:
            traj = kitti_se3(kitti)
        except ImportError:
            print("  Fig. 5 needs scipy to read KITTI rotations (pip install scipy): skipped")
            return {}
        name, plane, gamma = f"KITTI odometry {kitti.stem}", (0, 2), 20.0
    else:
        print(f"  KITTI 00 not found at {kitti}: Fig. 5 uses the synthetic urban drive instead")
        traj = il.urban_drive(duration_s=900.0, seed=3, se3=True)
        name, plane, gamma = "synthetic urban drive (15 min)", (0, 1), 40.0
    weights = (0.0, 10.0)
    results = [
        il.find_loops(
            traj, gamma=gamma, metric=il.metrics.SE3(rotation_weight_m_per_rad=w), separation=None
        )
        for w in weights
    ]
    fig, axes = plt.subplots(1, 3, figsize=(20, 6.6), constrained_layout=True)
    plot.trajectory_by_duration(traj, results[0], ax=axes[0], axes=plane)
    axes[0].set_title(
        f"{name}: {len(traj)} poses, {traj.span_s:.0f} s\ncoloured by loop "
        f"duration (L2, γ = {gamma:g} m)"
    )
    titles = ("(a) π(t, t′), L2 metric on translations", "(b) π(t, t′), SE(3) metric, 10 m/rad")
    for ax, w, loops, title in zip(axes[1:], weights, results, titles, strict=True):
        plot.distance_image(traj, loops, ax=ax, metric=se3_distance(w), max_pixels=800)
        ax.set_title(f"{title}\n{describe(loops)}", pad=24)
    fig.suptitle(
        f"Fig. 5: a real trajectory with its γ = {gamma:g} m loop components outlined "
        "for two metrics: with rotation counted, revisits in the opposite direction "
        "are no longer loops"
    )
    return {"fig5_real_trajectory.png": fig}


# --------------------------------------------------------------------------------------------
# Figs. 6-8: the sampling experiment on the 2.1 h urban drive
# --------------------------------------------------------------------------------------------


def sampling_api() -> bool:
    return all(hasattr(il, name) for name in ("draw_detections", "cluster_detections", "sample"))


def stretch_box(
    traj: il.Trajectory, table: dict[str, np.ndarray], components: list[int], margin_m: float
) -> tuple[tuple[float, float], tuple[float, float]]:
    """(x range, y range) around the poses of the components (both of their stretches)."""
    rows = [
        np.r_[table["i_min"][c] : table["i_max"][c] + 1, table["j_min"][c] : table["j_max"][c] + 1]
        for c in components
    ]
    xy = traj.positions[np.concatenate(rows), :2]
    lo, hi = xy.min(axis=0) - margin_m, xy.max(axis=0) + margin_m
    half = float((hi - lo).max()) / 2  # square, so equal aspect fills the panel
    centre = (lo + hi) / 2
    return (centre[0] - half, centre[0] + half), (centre[1] - half, centre[1] + half)


def only_components(samples: object, located: np.ndarray, components: list[int]) -> dict:
    """The samples (pose index columns) that fall in the given components."""
    keep = np.isin(located, components)
    return {"i": samples.i[keep], "j": samples.j[keep]}


def sample_zooms(traj, loops, samples: dict[str, object]) -> Figure:
    """Fig. 6a-b: samples of the largest component, and of small components around one that
    sigma_alpha missed (P1), drawn between trajectory points."""
    table = loops.components
    located = {name: chosen.locate(loops).component for name, chosen in samples.items()}
    counts = {
        name: np.bincount(c[c >= 0], minlength=len(table["id"])) for name, c in located.items()
    }
    nontrivial = np.flatnonzero(~table["trivial"])
    by_area = nontrivial[np.argsort(table["area_s2"][nontrivial], kind="stable")]
    large = [int(by_area[-1])]
    small_area = float(np.quantile(table["area_s2"][nontrivial], 0.25))
    small = [int(c) for c in by_area if table["area_s2"][c] <= small_area]
    missed = [c for c in small if counts["alpha"][c] == 0 and counts["rho"][c] > 0]
    focus = missed[0] if missed else small[0]
    centre = traj.positions[int(table["closest_i"][focus]), :2]
    near = [
        c
        for c in small
        if np.abs(traj.positions[int(table["closest_i"][c]), :2] - centre).max() < 100.0
    ]
    rows = (
        (
            large,
            stretch_box(traj, table, large, 30.0),
            f"(a) the largest loop component ({table['area_s2'][large[0]]:.0f} s²)",
        ),
        (
            near,
            stretch_box(traj, table, near, 20.0),
            f"(b) {len(near)} small loop components (≤ {small_area:.0f} s² each) near one that "
            "σ_α missed",
        ),
    )
    fig = plt.figure(figsize=(15, 11), constrained_layout=True)
    for (components, (xlim, ylim), what), part in zip(rows, fig.subfigures(2, 1), strict=True):
        for ax, name in zip(part.subplots(1, 3), SAMPLERS, strict=True):
            chosen = only_components(samples[name], located[name], components)
            plot.sample_pairs(traj, {name: chosen}, ax=ax, linewidth=1.0, alpha=0.8, legend=False)
            ax.set_xlim(*xlim)
            ax.set_ylim(*ylim)
            covered = sum(counts[name][c] > 0 for c in components)
            ax.set_title(
                f"{plot.PAPER_SAMPLERS[name][1]}: {len(chosen['i'])} samples, "
                f"{covered}/{len(components)} components",
                color="k",
            )
        part.suptitle(what)
    fig.suptitle(
        "Fig. 6a-b: samples in loop components with large (top) and small (bottom) "
        "loop areas, drawn between trajectory points",
        fontweight="bold",
    )
    return fig


def sampling_figures() -> dict[str, Figure]:
    gamma, epsilon_s, budget = 40.0, 30.0, 10_000
    traj = il.urban_drive(duration_s=7560.0, seed=0)
    loops = il.find_loops(traj, gamma=gamma, separation=None)
    table = loops.components
    nontrivial = np.flatnonzero(~table["trivial"])
    figures: dict[str, Figure] = {}

    fig, ax = plt.subplots(figsize=(7.5, 6.5), constrained_layout=True)
    plot.trajectory_by_duration(traj, loops, ax=ax, linewidth=1.0)
    ax.set_title(
        f"Fig. 6d: ξ(t) coloured by loop duration (γ = {gamma:g} m)\n"
        f"2.1 h urban drive, {len(traj)} poses"
    )
    figures["fig6d_loop_duration.png"] = fig

    samples: dict[str, object] = {}
    detections = None
    if sampling_api():
        detections = il.draw_detections(loops, rate=0.01, seed=0)
        clusters = il.cluster_detections(detections, epsilon_s=epsilon_s)
        samples = {name: il.sample(clusters, name, budget=budget, seed=0) for name in SAMPLERS}
        for name, chosen in samples.items():
            quality = il.sample_quality(chosen, loops)
            print(
                f"  {name}: {len(chosen)} samples, {quality.nontrivial_covered} of "
                f"{quality.nontrivial_components} non-trivial components covered"
            )
    else:
        print(
            "  the sampling API (il.draw_detections, il.cluster_detections, il.sample) is "
            "missing: Figs. 6a-c, 7 (samples) and 8 skipped"
        )

    if samples:
        fig, axes = plt.subplots(1, 3, figsize=(18, 7), constrained_layout=True)
        for ax, name in zip(axes, SAMPLERS, strict=True):
            plot.sample_pairs(traj, {name: samples[name]}, ax=ax)
        fig.suptitle(
            f"Fig. 6c: samples drawn between points on ξ(t), {budget} per sampler, "
            f"from 1 % of S_γ (γ = {gamma:g} m) clustered with ε = {epsilon_s:g} s"
        )
        figures["fig6c_samples_on_trajectory.png"] = fig
        figures["fig6ab_sample_zooms.png"] = sample_zooms(traj, loops, samples)

    fig, axes = plt.subplots(
        1, 2, figsize=(15, 7.5), constrained_layout=True, width_ratios=[1.15, 1]
    )
    plot.distance_image(traj, loops, ax=axes[0], samples=samples or None, sample_size=0.5)
    largest = int(nontrivial[np.argmax(table["area_s2"][nontrivial])])
    window = zoom_window(table, largest)
    (a, b), (c, d) = window
    axes[0].add_patch(Rectangle((a, c), b - a, d - c, fill=False, ec="red", lw=1.5))
    axes[0].set_title(f"Fig. 7a: π(t, t′), the γ = {gamma:g} m components outlined", pad=40)
    plot.distance_image(
        traj,
        loops,
        ax=axes[1],
        samples=samples or None,
        window_s=window,
        sample_size=8.0,
        max_pixels=600,
    )
    axes[1].set_title(
        "Fig. 7b: the boxed region" + (", sampled inexact loops" if samples else ""), pad=40
    )
    figures["fig7_distance_samples.png"] = fig

    if samples:
        top, _ = plot.samples_per_component(loops, samples, available=detections)
        top.set_title(f"Fig. 8: samples per loop component ({budget} per sampler)")
        figures["fig8_samples_per_component.png"] = top.figure
    return figures


def zoom_window(table: dict[str, np.ndarray], component: int, margin_s: float = 400.0):
    """A square (t, t') window around a component, widened by ``margin_s`` on each side."""
    t_lo, t_hi = table["t_min_s"][component], table["t_max_s"][component]
    u_lo, u_hi = table["t_prime_min_s"][component], table["t_prime_max_s"][component]
    side = max(t_hi - t_lo, u_hi - u_lo) / 2 + margin_s
    t0 = table["t_min_s"][0]  # the trivial component starts at the first pose
    tc, uc = (t_lo + t_hi) / 2 - t0, (u_lo + u_hi) / 2 - t0
    return (tc - side, tc + side), (uc - side, uc + side)


# --------------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--out", type=Path, default=Path("figures"), help="output folder (default: figures/)"
    )
    parser.add_argument("--force", action="store_true", help="overwrite existing files")
    parser.add_argument(
        "--only",
        nargs="+",
        choices=sorted(FIGURES),
        metavar="FIG",
        help=f"only these figures: {', '.join(FIGURES)}",
    )
    parser.add_argument(
        "--kitti",
        type=Path,
        default=KITTI_00,
        help="KITTI odometry poses for Fig. 5 (default: %(default)s)",
    )
    args = parser.parse_args(argv)

    chosen = args.only or list(FIGURES)
    planned = [args.out / name for key in chosen for name in FIGURES[key]]
    existing = [str(path) for path in planned if path.exists()]
    if existing and not args.force:
        print(
            f"paper_figures.py: would overwrite {', '.join(existing)}; pass --force",
            file=sys.stderr,
        )
        return 2
    args.out.mkdir(parents=True, exist_ok=True)

    makers: dict[str, Callable[[], dict[str, Figure]]] = {
        "fig2": fig2,
        "fig4": fig4,
        "fig5": lambda: fig5(args.kitti),
        "sampling": sampling_figures,
    }
    for key in chosen:
        start = time.perf_counter()
        print(f"{key}:")
        for name, figure in makers[key]().items():
            path = args.out / name
            figure.savefig(path, dpi=110)
            plt.close(figure)
            print(f"  wrote {path}")
        print(f"  ({time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
