#!/usr/bin/env python3
"""The revisit table: which minimum separation L between the two poses of a loop keeps the
loops a SLAM engineer labels and removes the band of pairs that odometry already ties together.

Usage::

    python benches/revisit_table.py [--data ../shared/data] [--out FILE.md] [--threads N]

Needs the ``inexact_loops`` wheel (``pip install .``) and scipy. Datasets whose files are absent
from ``--data`` are skipped with a message. The tables go to stdout as Markdown, and to
``--out`` when given. Nothing is hard-coded: every figure is measured on the run.

For each trajectory and each separation L ∈ {none, 1, 2, 4, 8, 16} × γ (a path length:
``il.find_loops(traj, gamma=γ, separation=il.Separation(path=L))``, or ``separation=None``)
the first tables give, with X = S_γ with no separation and the pairs at least L apart along
the path otherwise:

- **revisits**: the non-trivial loop components of X (with L > 0 all are), of all components;
- **band**: the share of X's cells (i, j), i ≤ j, on which the robot never left the γ-ball
  around the first pose, i.e. δ(ξ_i, ξ_k) ≤ γ for every k in i..j: pairs that odometry ties
  together (the diagonal band, stops). Computed in numpy from the positions, independently of
  the engine;
- **short revisits**: revisit components on none of whose cells the robot got farther than 2γ
  from the first pose in between (pieces of the band a separation cuts off, or small loops);
- **labelled in revisits**: the share of labelled pairs (i, j) that lie in a revisit component
  of X, and the same share among the labelled pairs on which the robot *did* leave the γ-ball
  ("left-ball" labels: revisits rather than neighbours);
- for KITTI, the share of X's cells that are labelled (the KITTI labels are exhaustive: every
  pair within 6 m in the x–z plane, temporal neighbours excluded);
- per multiple, the worst case over the trajectories, and the smallest multiple that leaves no
  cell of the band on any trajectory while keeping 95% of each one's left-ball labels.

Then comes the KITTI acceptance table (00, 02, 05, 06, 07, 08, 09, γ = 6 m, x–z
plane) with the default separation ``il.Separation.for_gamma(6)``: the share of labelled pairs
inside revisit components and the share of revisit cells that are labelled, beside the same
figures for the paper's S_γ (no separation: its non-trivial components); and a list of the
revisit components of TUC Corridor at γ = 1 m with the default separation and checks that the
default sampler (σ_ρ, budget 1000, seed 0: what ``loops sample`` does) covers each (P1).

Datasets and their labels (see ``../shared/data/README.md``):

- KITTI odometry 00, 05, 07 (and 02, 06, 08, 09 for the acceptance table): ground-truth poses
  ``kitti_odometry/XX.txt``, one line a pose: the time, then the row-major 3×4 ``[R|t]`` of
  camera 0 (12 numbers; without the time column the poses are at 10 Hz). The ground plane is
  x–z (y points down): the positions are (t_x, t_z), columns 3 and 11 of the 12 pose numbers.
  They are built in numpy and given to ``il.Trajectory`` (``il.read_trajectory(...,
  format="kitti", axes=(0, 2))`` reads the same plane; the tests check that both agree).
  Labels: ``kitti_loop_gt/kittiXXGroundTruth.mat``, matrix ``truth`` (N × N, strictly lower
  triangular, 1 where frames i > j are within 6 m in x–z and are not temporal neighbours).
  ``gnd_kittiXX.mat`` holds the same pairs as 1-based, symmetric lists (``gnd(i).ok``); we use
  ``truth`` because it is 0-based, one entry per pair, and the one the issue names, and check
  on the run that both files hold the same pairs. γ = 6 m, the labels' radius.
- TUC SLAM Corridor and Lecture Hall: ``tuc/SLAM/*_GT.txt`` lines ``point2 t x y …`` (the
  ground truth, 5 Hz); ``*_Input.txt`` lines ``loop t1 t2 score`` are real place-recognition
  detections, true and false mixed. A labelled pair is a detection whose two times (placed on
  the nearest ground-truth poses; detections outside the ground truth's span are dropped and
  counted) are within γ = 1 m in the ground truth; duplicates count once.
- INTEL and FR079 pose graphs (``pose_graphs/input_INTEL_g2o.g2o``, ``FR079_P_toro.graph``):
  their vertices are odometry guesses (INTEL's loop-closure edges join vertices up to 31 m
  apart, though the edges measure at most 3 m), so the trajectory is the graph's least-squares
  solution (Gauss–Newton on the SE(2) edge residuals, unit weights, vertex 0 fixed; a few
  iterations from the odometry guess), pose i at i seconds. Labelled pairs: the loop-closure
  edges (|i − j| > 1) whose endpoints are within γ on that solution. γ: FR079 1 m (its
  loop-closure edges measure at most 1.6 m, 97% within 1 m; odometry steps ~0.45 m, as TUC's
  indoor runs); INTEL 2 m, the upper end of the 1–2 m its scale suggests (steps ~0.6 m, a
  27 m × 27 m building), because its closures are scan matches up to 3 m apart: 143 of 256
  lie within 2 m on the solution, 50 within 1 m.
- The built-in urban drive (``il.urban_drive()``: 2.1 h, 10 Hz, x, y, z), γ = 40 m; it has no
  labels, so only components and the band are reported.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io

import inexact_loops as il

REPO = Path(__file__).resolve().parent.parent
MULTIPLES = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0)  # 0: no separation (the paper's S_γ)
KITTI_GAMMA_M = 6.0
KITTI_TABLE = ("00", "05", "07")
KITTI_ACCEPTANCE = ("00", "02", "05", "06", "07", "08", "09")
KITTI_RATE_HZ = 10.0
TUC_GAMMA_M = 1.0
POSE_GRAPHS = {"INTEL": ("input_INTEL_g2o.g2o", 2.0), "FR079": ("FR079_P_toro.graph", 1.0)}
URBAN_GAMMA_M = 40.0
SAMPLER, BUDGET, SEED = "rho", 1000, 0  # what `loops sample` does by default


@dataclass
class Dataset:
    """A trajectory with its γ and, when it has them, labelled pairs (i < j)."""

    name: str
    traj: il.Trajectory
    gamma: float
    labels: np.ndarray | None  # (m, 2) int64, i < j, unique
    exhaustive: bool = False  # labels are every pair within γ (KITTI): report X's labelled share
    note: str = ""


def skip(message: str) -> None:
    print(f"skipped: {message}", file=sys.stderr)


# --- loading ---------------------------------------------------------------------------------


def kitti_xz(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(times, x–z positions) of a KITTI pose file: 12 numbers a line (10 Hz), or a time and 12."""
    rows = np.loadtxt(path, ndmin=2)
    if rows.shape[1] == 13:
        times, pose = rows[:, 0], rows[:, 1:]
    elif rows.shape[1] == 12:
        times, pose = np.arange(len(rows)) / KITTI_RATE_HZ, rows
    else:
        raise ValueError(f"{path}: {rows.shape[1]} numbers a line, expected 12 or 13")
    return times, pose[:, [3, 11]]  # row-major [R|t]: t_x, t_z


def kitti_labels(folder: Path, seq: str, n: int) -> np.ndarray:
    """Labelled pairs (i < j) of ``kittiXXGroundTruth.mat``, checked against ``gnd_kittiXX.mat``."""
    truth = scipy.io.loadmat(folder / f"kitti{seq}GroundTruth.mat")["truth"]
    truth = truth.toarray() if hasattr(truth, "toarray") else np.asarray(truth)
    if truth.shape != (n, n) or np.triu(truth).any():
        raise ValueError(f"kitti{seq}GroundTruth.mat: not a strictly lower triangular {n}x{n}")
    later, earlier = np.nonzero(truth)
    gnd_path = folder / f"gnd_kitti{seq}.mat"
    if gnd_path.is_file():
        gnd = scipy.io.loadmat(gnd_path)["gnd"]
        listed = {(k, int(v) - 1) for k in range(gnd.shape[0]) for v in np.ravel(gnd[k, 0]["ok"])}
        pairs = set(zip(later.tolist(), earlier.tolist(), strict=True))
        if listed != pairs | {(b, a) for a, b in pairs}:
            raise ValueError(f"gnd_kitti{seq}.mat and kitti{seq}GroundTruth.mat disagree")
    return np.c_[earlier, later].astype(np.int64)


def load_kitti(data: Path, seq: str) -> Dataset | None:
    poses = data / "kitti_odometry" / f"{seq}.txt"
    truth = data / "kitti_loop_gt" / f"kitti{seq}GroundTruth.mat"
    if not (poses.is_file() and truth.is_file()):
        skip(f"KITTI {seq}: {poses} or {truth} is absent")
        return None
    times, xz = kitti_xz(poses)
    labels = kitti_labels(truth.parent, seq, len(times))
    traj = il.Trajectory(times, xz)
    return Dataset(f"KITTI {seq}", traj, KITTI_GAMMA_M, labels, exhaustive=True)


def read_tuc_ground_truth(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(times, x–y positions) of the ``point2 t x y …`` lines of a TUC ``*_GT.txt``."""
    rows = [line.split() for line in path.read_text().splitlines() if line.startswith("point2")]
    values = np.array([[float(r[1]), float(r[2]), float(r[3])] for r in rows])
    return values[:, 0], values[:, 1:]


def read_tuc_detections(path: Path) -> np.ndarray:
    """``(m, 2)`` times of the ``loop t1 t2 score`` lines of a TUC ``*_Input.txt``."""
    rows = [line.split() for line in path.read_text().splitlines() if line.startswith("loop")]
    return np.array([[float(r[1]), float(r[2])] for r in rows]).reshape(-1, 2)


def tuc_labels(traj: il.Trajectory, detections: np.ndarray, gamma: float) -> tuple[np.ndarray, int]:
    """(labelled pairs i < j, detections dropped for lying outside the span)."""
    times = traj.timestamps
    inside = np.all((detections >= times[0]) & (detections <= times[-1]), axis=1)
    poses = traj.nearest_poses(detections[inside].ravel()).reshape(-1, 2)
    pairs = np.unique(np.sort(poses, axis=1), axis=0)
    pairs = pairs[pairs[:, 0] < pairs[:, 1]]
    xy = traj.positions
    within = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1) <= gamma
    return pairs[within].astype(np.int64), int((~inside).sum())


def load_tuc(data: Path, name: str) -> Dataset | None:
    gt = data / "tuc" / "SLAM" / f"{name}_GT.txt"
    inputs = data / "tuc" / "SLAM" / f"{name}_Input.txt"
    if not (gt.is_file() and inputs.is_file()):
        skip(f"TUC {name}: {gt} or {inputs} is absent")
        return None
    traj = il.Trajectory(*read_tuc_ground_truth(gt))
    detections = read_tuc_detections(inputs)
    labels, dropped = tuc_labels(traj, detections, TUC_GAMMA_M)
    note = (
        f"{len(detections)} detections, {dropped} outside the ground truth's span; "
        f"{len(labels)} distinct pose pairs within {TUC_GAMMA_M:g} m"
    )
    return Dataset(f"TUC {name.replace('_', ' ')}", traj, TUC_GAMMA_M, labels, note=note)


def read_pose_graph(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices ``(n, 3)`` x, y, θ by id 0..n−1, edges ``(m, 5)`` i, j, dx, dy, dθ) of a TORO
    (``VERTEX2``/``EDGE2``) or g2o (``VERTEX_SE2``/``EDGE_SE2``) 2-D pose graph."""
    vertices: dict[int, list[float]] = {}
    edges = []
    for line in path.read_text().splitlines():
        fields = line.split()
        if fields and fields[0] in ("VERTEX2", "VERTEX_SE2"):
            vertices[int(fields[1])] = [float(v) for v in fields[2:5]]
        elif fields and fields[0] in ("EDGE2", "EDGE_SE2"):
            edges.append([float(v) for v in fields[1:6]])
    ids = sorted(vertices)
    if ids != list(range(len(ids))):
        raise ValueError(f"{path}: vertex ids are not 0..n-1")
    return np.array([vertices[k] for k in ids]), np.array(edges)


def wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def solve_pose_graph(vertices: np.ndarray, edges: np.ndarray, iterations: int = 50) -> np.ndarray:
    """The least-squares poses (x, y, θ) of a 2-D pose graph: Gauss–Newton on the residuals
    R(θ_i)ᵀ(p_j − p_i) − d_ij and wrap(θ_j − θ_i − dθ_ij), unit weights, vertex 0 fixed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    i, j = edges[:, 0].astype(int), edges[:, 1].astype(int)
    d = edges[:, 2:5]
    m, n = len(edges), len(vertices)
    x = vertices.astype(float).copy()
    rows3 = 3 * np.arange(m)
    for _ in range(iterations):
        c, s = np.cos(x[i, 2]), np.sin(x[i, 2])
        dx, dy = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1]
        r = np.c_[c * dx + s * dy - d[:, 0], -s * dx + c * dy - d[:, 1]]
        r = np.c_[r, wrap(x[j, 2] - x[i, 2] - d[:, 2])].ravel()
        one = np.ones(m)
        entries = [  # (residual row, variable column, derivative)
            (0, 3 * i, -c), (0, 3 * i + 1, -s), (0, 3 * i + 2, -s * dx + c * dy),
            (0, 3 * j, c), (0, 3 * j + 1, s),
            (1, 3 * i, s), (1, 3 * i + 1, -c), (1, 3 * i + 2, -c * dx - s * dy),
            (1, 3 * j, -s), (1, 3 * j + 1, c),
            (2, 3 * i + 2, -one), (2, 3 * j + 2, one),
        ]  # fmt: skip
        jac = coo_matrix(
            (
                np.concatenate([v for _, _, v in entries]),
                (
                    np.concatenate([rows3 + k for k, _, _ in entries]),
                    np.concatenate([col for _, col, _ in entries]),
                ),
            ),
            shape=(3 * m, 3 * n),
        ).tocsc()[:, 3:]
        step = spsolve((jac.T @ jac).tocsc(), -(jac.T @ r))
        x[1:] += step.reshape(-1, 3)
        x[:, 2] = wrap(x[:, 2])
        if np.abs(step).max() < 1e-10:
            return x
    raise RuntimeError(f"the pose graph did not converge in {iterations} Gauss-Newton steps")


def load_pose_graph(data: Path, name: str) -> Dataset | None:
    file, gamma = POSE_GRAPHS[name]
    path = data / "pose_graphs" / file
    if not path.is_file():
        skip(f"{name}: {path} is absent")
        return None
    vertices, edges = read_pose_graph(path)
    poses = solve_pose_graph(vertices, edges)
    i, j = edges[:, 0].astype(int), edges[:, 1].astype(int)
    closure = np.abs(i - j) > 1
    pairs = np.unique(np.sort(np.c_[i, j][closure], axis=1), axis=0)
    xy = poses[:, :2]
    distance = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1)
    guess = np.linalg.norm(vertices[pairs[:, 0], :2] - vertices[pairs[:, 1], :2], axis=1)
    labels = pairs[distance <= gamma].astype(np.int64)
    note = (
        f"{len(pairs)} loop-closure edges, {len(labels)} within {gamma:g} m on the solved graph "
        f"(at most {distance.max():.2f} m apart there, {guess.max():.2f} m on the odometry guess)"
    )
    traj = il.Trajectory(np.arange(len(xy), dtype=float), xy)
    return Dataset(name, traj, gamma, labels, note=note)


def load_urban() -> Dataset:
    traj = il.urban_drive()
    return Dataset("urban drive", traj, URBAN_GAMMA_M, None, note=f"{len(traj)} poses, no labels")


# --- measuring -------------------------------------------------------------------------------


def first_exit(positions: np.ndarray, gamma: float) -> np.ndarray:
    """f_i = the first k > i with δ(ξ_i, ξ_k) > γ (n when the robot never leaves the γ-ball
    around ξ_i again): (i, j) lies in the band iff j < f_i."""
    n = len(positions)
    exit_ = np.full(n, n, dtype=np.int64)
    active = np.arange(n)
    step = 1
    while active.size:
        active = active[active + step < n]
        far = np.linalg.norm(positions[active + step] - positions[active], axis=1) > gamma
        exit_[active[far]] = active[far] + step
        active = active[~far]
        step += 1
    return exit_


def locate(runs: dict, n: int, pairs: np.ndarray) -> np.ndarray:
    """The component of each pair (i, j), i ≤ j, in the runs; −1 where it is not in X."""
    row, start, end = runs["row"], runs["start"], runs["end"]
    keys = row * n + start
    query = pairs[:, 0] * n + pairs[:, 1]
    k = np.searchsorted(keys, query, side="right") - 1
    ok = k >= 0
    k = np.maximum(k, 0)
    ok &= (row[k] == pairs[:, 0]) & (end[k] >= pairs[:, 1])
    return np.where(ok, runs["component"][k], -1)


@dataclass
class Measure:
    components: int
    revisits: int
    cells: int
    revisit_cells: int
    band_cells: int
    short: int  # revisit components on none of whose pairs the robot got 2γ away
    labelled_in_revisits: int
    left_ball_in_revisits: int
    seconds: float


def measure(data: Dataset, separation, exits: tuple, threads: int | None) -> Measure:
    """X at one separation; ``exits`` = (first_exit at γ, first_exit at 2γ)."""
    exit_, exit2 = exits
    start_s = time.perf_counter()
    loops = il.find_loops(data.traj, gamma=data.gamma, separation=separation, threads=threads)
    seconds = time.perf_counter() - start_s
    runs = {key: np.asarray(value) for key, value in loops.runs().items()}
    trivial = np.asarray(loops.components["trivial"], dtype=bool)
    lengths = runs["end"] - runs["start"] + 1
    revisit_run = ~trivial[runs["component"]]
    band = np.clip(np.minimum(runs["end"], exit_[runs["row"]] - 1) - runs["start"] + 1, 0, None)
    away = np.clip(runs["end"] - np.maximum(runs["start"], exit2[runs["row"]]) + 1, 0, None)
    away_per_component = np.bincount(runs["component"], weights=away, minlength=len(trivial))
    labelled = left = 0
    if data.labels is not None and len(data.labels):
        comp = locate(runs, len(data.traj), data.labels)
        inside = (comp >= 0) & ~trivial[np.maximum(comp, 0)]
        labelled = int(inside.sum())
        left = int((inside & (data.labels[:, 1] >= exit_[data.labels[:, 0]])).sum())
    return Measure(
        components=len(trivial),
        revisits=int((~trivial).sum()),
        cells=int(lengths.sum()),
        revisit_cells=int(lengths[revisit_run].sum()),
        band_cells=int(band.sum()),
        short=int(((away_per_component == 0) & ~trivial).sum()),
        labelled_in_revisits=labelled,
        left_ball_in_revisits=left,
        seconds=seconds,
    )


def share(part: int, whole: int) -> str:
    return f"{100 * part / whole:.1f}%" if whole else "–"


def separation_for(multiple: float, gamma: float):
    return None if multiple == 0 else il.Separation(path=multiple * gamma)


def separation_table(datasets: list[Dataset], threads: int | None) -> tuple[list[str], dict]:
    """Measures every dataset at every separation; three tables, one column per L."""
    results: dict = {}
    for data in datasets:
        exits = (
            first_exit(data.traj.positions, data.gamma),
            first_exit(data.traj.positions, 2 * data.gamma),
        )
        exit_ = exits[0]
        labels = data.labels
        n_labels = 0 if labels is None else len(labels)
        n_left = 0 if labels is None else int((labels[:, 1] >= exit_[labels[:, 0]]).sum())
        for multiple in MULTIPLES:
            m = measure(data, separation_for(multiple, data.gamma), exits, threads)
            results[(data.name, multiple)] = (m, n_labels, n_left)
            print(f"  {data.name:16} L = {multiple:2g}γ {m.seconds:6.2f} s", file=sys.stderr)

    head = (
        "| dataset | γ | "
        + " | ".join("none" if k == 0 else f"L = {k:g}γ" for k in MULTIPLES)
        + " |"
    )
    rule = "|---|---|" + "---|" * len(MULTIPLES)
    lines = [
        "Revisit components (with no separation: non-trivial components of all components), "
        "and in brackets the band: the share of X's cells on which the robot never left the "
        "γ-ball around the first pose; and the short revisits: revisit components on none of "
        "whose pairs the robot got farther than 2γ from the first pose in between (pieces of "
        "the band a separation cuts off, or small loops).",
        "",
        head,
        rule,
    ]
    for data in datasets:
        cells = []
        for k in MULTIPLES:
            m = results[(data.name, k)][0]
            count = f"{m.revisits} of {m.components}" if k == 0 else f"{m.revisits}"
            cells.append(f"{count} ({share(m.band_cells, m.cells)}; {m.short})")
        lines.append(f"| {data.name} | {data.gamma:g} m | " + " | ".join(cells) + " |")
    if not any(d.labels is not None for d in datasets):
        return lines, results
    lines += [
        "",
        "Labelled pairs inside revisit components: share of all labelled pairs / share of "
        "those on which the robot left the γ-ball (the labels that are revisits, not "
        "neighbours). In brackets, how many labelled pairs there are of each kind.",
        "",
        head,
        rule,
    ]
    for data in datasets:
        if data.labels is None:
            continue
        _, n_labels, n_left = results[(data.name, 0.0)]
        cells = []
        for k in MULTIPLES:
            m = results[(data.name, k)][0]
            cells.append(
                f"{share(m.labelled_in_revisits, n_labels)} / "
                f"{share(m.left_ball_in_revisits, n_left)}"
            )
        name = f"{data.name} ({n_labels} / {n_left})"
        lines.append(f"| {name} | {data.gamma:g} m | " + " | ".join(cells) + " |")
    if not any(d.exhaustive for d in datasets):
        return lines, results
    lines += [
        "",
        "KITTI: the share of X's cells (i ≤ j; revisit cells and the trivial component alike) "
        "that are labelled, and how many cells X has.",
        "",
        head,
        rule,
    ]
    for data in datasets:
        if not data.exhaustive:
            continue
        cells = []
        for k in MULTIPLES:
            m = results[(data.name, k)][0]
            cells.append(f"{share(m.labelled_in_revisits, m.cells)} of {m.cells}")
        lines.append(f"| {data.name} | {data.gamma:g} m | " + " | ".join(cells) + " |")
    return lines, results


def recommendation(datasets: list[Dataset], results: dict) -> list[str]:
    """Per multiple, the worst case over the trajectories: the share of left-ball labels kept
    (of the most any separation keeps), the band left, the short revisits left; and the
    smallest multiple that leaves no cell of the band on any trajectory and keeps 95% of each
    one's left-ball labels. Short revisits are reported, not part of the rule: indoors they
    include small loops the paper counts too (INTEL has 12 among S_γ's non-trivial
    components)."""
    lines = [
        "| L / γ | fewest left-ball labels kept (of the most any L keeps) | most band left "
        "| most short revisits left |",
        "|---|---|---|---|",
    ]
    choice = None
    for multiple in MULTIPLES[1:]:
        kept, band, short = [], [], []
        for data in datasets:
            m, _, n_left = results[(data.name, multiple)]
            band.append((m.band_cells / m.cells if m.cells else 0.0, m.band_cells, data.name))
            short.append((m.short / m.revisits if m.revisits else 0.0, m.short, data.name))
            if data.labels is not None and n_left:
                best = max(results[(data.name, k)][0].left_ball_in_revisits for k in MULTIPLES)
                kept.append((m.left_ball_in_revisits / best if best else 1.0, data.name))
        worst_kept, worst_band, worst_short = min(kept, default=(1.0, "–")), max(band), max(short)

        def worst(value: tuple, unit: str) -> str:
            if value[1] == 0:
                return "none"
            return f"{100 * value[0]:.2f}% ({value[2]}: {value[1]} {unit})"

        who = "no labels" if not kept else "all" if worst_kept[0] == 1.0 else worst_kept[1]
        lines.append(
            f"| {multiple:g} | {100 * worst_kept[0]:.1f}% ({who}) "
            f"| {worst(worst_band, 'cells')} | {worst(worst_short, 'components')} |"
        )
        if choice is None and worst_kept[0] >= 0.95 and worst_band[1] == 0:
            choice = multiple
    lines.append("")
    if choice is None:
        lines.append("No multiple removes the band and keeps 95% of the left-ball labels.")
    else:
        lines.append(
            "Smallest multiple that leaves no cell of the band on any trajectory and keeps at "
            f"least 95% of each one's left-ball labels: **{choice:g}γ** "
            f"(the library's default is {il.Separation.DEFAULT_GAMMAS:g}γ)."
        )
    return lines


def kitti_acceptance(data: Path, threads: int | None) -> list[str]:
    default = il.Separation.for_gamma(KITTI_GAMMA_M)
    lines = [
        f"KITTI, γ = {KITTI_GAMMA_M:g} m in the x–z plane, default separation "
        f"(path ≥ {default.path:g} m) against `kittiXXGroundTruth.mat`; in brackets the paper's "
        "S_γ (no separation: its non-trivial components).",
        "",
        "| sequence | poses | labelled pairs | of them in revisits | revisit cells (labelled) "
        "| revisits | (none) labelled in non-trivial | (none) non-trivial cells labelled |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for seq in KITTI_ACCEPTANCE:
        dataset = load_kitti(data, seq)
        if dataset is None:
            continue
        positions = dataset.traj.positions
        exits = first_exit(positions, dataset.gamma), first_exit(positions, 2 * dataset.gamma)
        m = measure(dataset, default, exits, threads)
        p = measure(dataset, None, exits, threads)
        n = len(dataset.labels)
        lines.append(
            f"| {seq} | {len(dataset.traj)} | {n} "
            f"| {m.labelled_in_revisits} ({share(m.labelled_in_revisits, n)}) "
            f"| {m.revisit_cells} ({share(m.labelled_in_revisits, m.revisit_cells)}) "
            f"| {m.revisits} "
            f"| ({share(p.labelled_in_revisits, n)}) "
            f"| ({share(p.labelled_in_revisits, p.revisit_cells)}) |"
        )
    return lines if len(lines) > 4 else []


def corridor_listing(data: Path, threads: int | None) -> list[str]:
    dataset = load_tuc(data, "Corridor")
    if dataset is None:
        return []
    traj, gamma = dataset.traj, dataset.gamma
    plain = il.find_loops(traj, gamma=gamma, separation=None, threads=threads)
    loops = il.find_loops(traj, gamma=gamma, threads=threads)  # the default separation
    samples = il.sample(loops, SAMPLER, budget=BUDGET, seed=SEED, trajectory=traj, threads=threads)
    quality = il.sample_quality(samples, loops)
    table = loops.components
    comp = locate(
        {key: np.asarray(value) for key, value in loops.runs().items()}, len(traj), dataset.labels
    )
    per_component = np.bincount(np.asarray(samples.component), minlength=len(table["id"]))
    t0 = traj.timestamps[0]
    plain_table = plain.components
    lines = [
        f"TUC Corridor, γ = {gamma:g} m: with no separation {len(plain_table['id'])} component(s), "
        f"{int((~np.asarray(plain_table['trivial'])).sum())} non-trivial; with the default "
        f"separation ({loops.separation.path:g} m of path) {len(table['id'])} revisit "
        f"components. σ_ρ, budget {BUDGET}, seed {SEED}: {len(samples)} samples, "
        f"P1 {'holds' if quality.covered == quality.components else 'FAILS'} "
        f"({quality.covered} of {quality.components} components covered).",
        "",
        "| id | t (s) | t′ (s) | pairs | holes | closest (m) | labelled pairs | samples |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for c in table["id"]:
        lines.append(
            f"| {c} | {table['t_min_s'][c] - t0:.0f}–{table['t_max_s'][c] - t0:.0f} "
            f"| {table['t_prime_min_s'][c] - t0:.0f}–{table['t_prime_max_s'][c] - t0:.0f} "
            f"| {table['pair_count'][c]} | {table['holes'][c]} "
            f"| {table['closest_distance'][c]:.3f} | {int((comp == c).sum())} "
            f"| {per_component[c]} |"
        )
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--data", type=Path, default=REPO / ".." / "shared" / "data", help="the data folder"
    )
    parser.add_argument("--out", type=Path, help="also write the tables to this Markdown file")
    parser.add_argument("--threads", type=int, default=None, help="worker threads (all cores)")
    args = parser.parse_args()
    data = args.data
    if not data.is_dir():
        skip(f"no data folder at {data.resolve()}: only the urban drive is measured")

    loaders = [
        *(lambda seq=seq: load_kitti(data, seq) for seq in KITTI_TABLE),
        lambda: load_tuc(data, "Corridor"),
        lambda: load_tuc(data, "Lecture_Hall"),
        *(lambda name=name: load_pose_graph(data, name) for name in POSE_GRAPHS),
        load_urban,
    ]
    datasets = [d for d in (load() for load in loaders) if d is not None]
    out = [
        f"Measured with inexact-loops {il.__version__}; default separation "
        f"{il.Separation.DEFAULT_GAMMAS:g}γ.",
        "",
    ]
    out += [f"- {d.name}: {d.note}" for d in datasets if d.note]
    out.append("")
    lines, results = separation_table(datasets, args.threads)
    out += lines + [""] + recommendation(datasets, results) + [""]
    out += kitti_acceptance(data, args.threads) + [""]
    out += corridor_listing(data, args.threads)
    text = "\n".join(out) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
