"""Pose graphs from Python: vertices and edges (relative pose, information) as tables, checked
against an independent parse of the files; where loop-closure edges fall
(``PoseGraph.edge_verdicts``, ``Loops.pair_verdicts``) against a brute force (δ of the two
poses, the separation on the path length, ``scipy.ndimage.label`` of the dense distance
matrix) and the command line's CSV; edge-only files chained with ``chain_edges=True`` against
an independent composition with ``scipy.spatial.transform.Rotation``.
"""

from __future__ import annotations

import csv
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation

import inexact_loops as il

from .conftest import DATA_DIR

GRAPHS = DATA_DIR / "pose_graphs"
NAMES = [
    "input_INTEL_g2o.g2o",
    "input_M3500_g2o.g2o",
    "input_MITb_g2o.g2o",
    "CSAIL_P_toro.graph",
    "FR079_P_toro.graph",
    "FRH_P_toro.graph",
]


def num(value: float) -> str:
    """A number as text that reads back as the same float."""
    return repr(float(value))


def needs_graphs() -> None:
    if not GRAPHS.is_dir():
        pytest.skip(f"no pose graphs at {GRAPHS} (they live beside the checkout in CI)")


def parse(path: Path) -> tuple[dict[int, list[float]], list[list[float]]]:
    """Vertices {id: [x, y, theta]} and edges [i, j, dx, dy, dtheta, info (g2o order)...] of a
    2-D graph, by splitting lines: TORO's EDGE2 writes xx xy yy tt xt yt."""
    vertices: dict[int, list[float]] = {}
    edges: list[list[float]] = []
    for line in path.read_text().splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] in ("VERTEX2", "VERTEX_SE2"):
            vertices[int(words[1])] = [float(w) for w in words[2:5]]
        elif words[0] in ("EDGE2", "EDGE_SE2"):
            numbers = [float(w) for w in words[1:]]
            info = numbers[5:11]
            if words[0] == "EDGE2":
                xx, xy, yy, tt, xt, yt = info
                info = [xx, xy, xt, yy, yt, tt]
            edges.append(numbers[:5] + info)
    return vertices, edges


@pytest.mark.parametrize("name", NAMES)
def test_real_graphs_vertices_and_edges_as_written(name: str) -> None:
    needs_graphs()
    path = GRAPHS / name
    vertices, edges = parse(path)
    graph = il.read_pose_graph(path)
    ids = sorted(vertices)
    assert graph.dim == 2 and graph.vertex_ids.tolist() == ids and not graph.chained
    v = graph.vertices
    expected = np.array([vertices[k] for k in ids])
    np.testing.assert_array_equal(np.c_[v["x"], v["y"]], expected[:, :2])
    wrapped = np.angle(np.exp(1j * expected[:, 2]))
    np.testing.assert_allclose(v["theta"], wrapped, atol=1e-15)
    np.testing.assert_array_equal(v["t"], ids)
    np.testing.assert_array_equal(graph.trajectory.positions, expected[:, :2])

    e = graph.edges
    want = np.array(edges)
    assert e.num_rows == len(edges)
    np.testing.assert_array_equal(e["from_id"], want[:, 0])
    np.testing.assert_array_equal(e["to_id"], want[:, 1])
    index = {k: row for row, k in enumerate(ids)}
    np.testing.assert_array_equal(e["i"], [index[int(k)] for k in want[:, 0]])
    np.testing.assert_array_equal(np.c_[e["dx"], e["dy"], e["dtheta"]], want[:, 2:5])
    names = ["info_00", "info_01", "info_02", "info_11", "info_12", "info_22"]
    np.testing.assert_array_equal(np.c_[tuple(e[n] for n in names)], want[:, 5:11])
    np.testing.assert_array_equal(e["loop_closure"], np.abs(want[:, 0] - want[:, 1]) > 1)
    if name == "input_INTEL_g2o.g2o":
        assert int(e["loop_closure"].sum()) == 256
    # The information matrices are positive semi-definite (TORO's only once reordered).
    info = np.zeros((e.num_rows, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            info[:, a, b] = info[:, b, a] = e[f"info_{a}{b}"]
    assert np.linalg.eigvalsh(info).min(axis=1).min() >= -1e-9 * np.abs(info).max()
    assert e.to_pandas().shape == (len(edges), 6 + 3 + 6)


def test_tables_of_a_3d_graph(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    positions, rotations = random_se3(rng, 4)
    quats = rotations.as_quat()
    lines = [
        f"VERTEX_SE3:QUAT {10 * k} " + " ".join(num(v) for v in [*p, *q])
        for k, (p, q) in enumerate(zip(positions, quats, strict=True))
    ]
    upper = " ".join(str(v) for v in range(1, 22))
    lines += [
        "EDGE_SE3:QUAT 0 10 1 2 3 0 0 0.6 0.8 " + upper,
        "EDGE_SE3:QUAT 30 0 0 0 0 0 0 0 1",
    ]
    path = tmp_path / "tiny3d.g2o"
    path.write_text("# a 3-D graph\n" + "\n".join(lines) + "\n")
    graph = il.read_pose_graph(path, rate_hz=10.0)
    assert repr(graph) == "PoseGraph(4 vertices, 2 edges, 2 loop closures, 3-D)"
    assert graph.dim == 3 and graph.vertex_ids.tolist() == [0, 10, 20, 30] and not graph.chained
    v = graph.vertices
    assert list(v) == ["id", "t", "x", "y", "z", "qx", "qy", "qz", "qw", "line"]
    np.testing.assert_array_equal(v["t"], [0.0, 1.0, 2.0, 3.0])
    np.testing.assert_array_equal(np.c_[v["x"], v["y"], v["z"]], positions)
    np.testing.assert_array_equal(np.c_[v["qx"], v["qy"], v["qz"], v["qw"]], quats)
    np.testing.assert_array_equal(v["line"], [2, 3, 4, 5])
    e = graph.edges
    assert list(e)[:13] == [
        "line",
        "from_id",
        "to_id",
        "i",
        "j",
        "loop_closure",
        "dx",
        "dy",
        "dz",
        "qx",
        "qy",
        "qz",
        "qw",
    ]
    assert (
        e["i"].tolist() == [0, 3]
        and e["j"].tolist() == [1, 0]
        and e["loop_closure"].tolist() == [True, True]  # ids 10 apart
    )
    np.testing.assert_array_equal(
        np.c_[tuple(e[c] for c in ["dx", "dy", "dz", "qx", "qy", "qz", "qw"])][0],
        [1, 2, 3, 0, 0, 0.6, 0.8],
    )
    upper_names = [f"info_{a}{b}" for a in range(6) for b in range(a, 6)]
    assert list(e)[13:] == upper_names
    np.testing.assert_array_equal([e[c][0] for c in upper_names], np.arange(1, 22))
    assert np.isnan([e[c][1] for c in upper_names]).all(), "no information given: NaN"
    np.testing.assert_array_equal(graph.trajectory.positions, positions)


def write_lines(path: Path, lines: list[str]) -> Path:
    """Writes ``lines`` to ``path``, one a line; returns ``path``."""
    path.write_text("\n".join(lines) + "\n")
    return path


def small_graph(tmp_path: Path) -> tuple[Path, np.ndarray, list[tuple[int, int]]]:
    """A figure of eight traced twice with a drift (90 vertices, headings along the path),
    odometry edges and loop closures between many pairs; the file, positions and closures."""
    n = 90
    a = np.arange(n) * 2 * np.pi / 45
    points = np.c_[6 * np.sin(a) + 0.01 * np.arange(n), 3 * np.sin(2 * a) + 0.004 * np.arange(n)]
    heading = np.arctan2(*np.gradient(points, axis=0)[:, ::-1].T)
    lines = [
        f"VERTEX_SE2 {k} {num(x)} {num(y)} {num(h)}"
        for k, ((x, y), h) in enumerate(zip(points, heading, strict=True))
    ]
    lines += [f"EDGE_SE2 {k} {k + 1} 0 0 0 1 0 0 1 0 1" for k in range(n - 1)]
    closures = []
    for i in range(n):
        for j in range(i + 2, n):
            if (i * 7 + j * 3) % 17 == 0:
                pair = (i, j) if (i + j) % 2 == 0 else (j, i)
                closures.append(pair)
                lines.append(f"EDGE_SE2 {pair[0]} {pair[1]} 0 0 0 1 0 0 1 0 1")
    path = write_lines(tmp_path / "small.g2o", lines)
    return path, points, closures


def brute_labels(points: np.ndarray, gamma: float, separation: il.Separation | None) -> np.ndarray:
    """Labels of the upper triangle (i <= j) of {δ <= γ, separated}, 4-connected, by scipy."""
    n = len(points)
    d = cdist(points, points)
    i, j = np.indices((n, n))
    inside = (d <= gamma) & (i <= j)
    if separation is not None:
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
        t = np.arange(n, dtype=float)
        inside &= (j > i) & (s[j] - s[i] >= separation.path) & (t[j] - t[i] >= separation.time_s)
    labels, _ = ndimage.label(inside)
    return labels


@pytest.mark.parametrize(
    "separation",
    ["auto", None, il.Separation(path=2.0, time_s=9.0)],
    ids=["default", "none", "path-and-time"],
)
def test_edge_verdicts_are_the_brute_forces(tmp_path: Path, separation) -> None:
    path, points, closures = small_graph(tmp_path)
    gamma = 1.5
    graph = il.read_pose_graph(path)
    loops = il.find_loops(graph.trajectory, gamma=gamma, separation=separation)
    table = graph.edge_verdicts(loops)
    assert [
        (int(a), int(b)) for a, b in zip(table["from_id"], table["to_id"], strict=True)
    ] == closures
    sep = None if separation is None else loops.separation
    labels = brute_labels(points, gamma, sep)
    d = cdist(points, points)
    engine_to_label: dict[int, int] = {}
    for i, j, distance, verdict, component in zip(
        table["i"], table["j"], table["distance"], table["verdict"], table["component"], strict=True
    ):
        a, b = min(i, j), max(i, j)
        assert distance == pytest.approx(d[i, j], rel=1e-12, abs=1e-12)
        label = labels[a, b]
        if verdict == "outside":
            assert d[i, j] > gamma and component == -1
        elif verdict == "not-separated":
            assert d[i, j] <= gamma and label == 0 and sep is not None and component == -1
        else:
            assert label > 0 and component >= 0
            assert engine_to_label.setdefault(int(component), int(label)) == label
            holds_diagonal = bool((np.diag(labels) == label).any())
            assert (verdict == "trivial") == holds_diagonal
            assert bool(loops.components["trivial"][component]) == holds_diagonal
    assert len(set(engine_to_label.values())) == len(engine_to_label)
    expected = {"default": {"component", "not-separated", "outside"}}
    if separation is None:
        assert {"component", "trivial", "outside"} <= set(table["verdict"])
    elif separation == "auto":
        assert expected["default"] <= set(table["verdict"])
    # Loops.pair_verdicts says the same for the same pairs.
    pairs = loops.pair_verdicts(table["i"], table["j"], graph.trajectory)
    for column in ("i", "j", "distance", "verdict", "component"):
        np.testing.assert_array_equal(pairs[column], table[column])


def test_python_and_the_command_line_give_the_same_verdicts(
    tmp_path: Path, loops_cli: Path
) -> None:
    path, _, _ = small_graph(tmp_path)
    out = tmp_path / "edges.csv"
    command = [str(loops_cli), "components", str(path), "--gamma", "1.5", "--edges-csv", str(out)]
    subprocess.run(command, check=True, capture_output=True)
    with out.open() as file:
        rows = list(csv.DictReader(file))
    graph = il.read_pose_graph(path)
    table = graph.edge_verdicts(il.find_loops(graph.trajectory, gamma=1.5))
    assert [row["verdict"] for row in rows] == table["verdict"].tolist()
    assert [int(row["component"] or -1) for row in rows] == table["component"].tolist()
    assert [int(row["line"]) for row in rows] == table["line"].tolist()
    assert [float(row["distance"]) for row in rows] == table["distance"].tolist()


def test_verdicts_refuse_another_trajectory_or_metric(tmp_path: Path) -> None:
    path, _, _ = small_graph(tmp_path)
    graph = il.read_pose_graph(path)
    loops = il.find_loops(graph.trajectory, gamma=1.5)
    other = il.Trajectory(np.arange(5.0), np.zeros(5))
    with pytest.raises(il.InvalidParameterError, match="different trajectories"):
        loops.pair_verdicts([0], [1], other)
    with pytest.raises(il.InvalidParameterError, match="the metric the loops were found with"):
        loops.pair_verdicts([0], [1], graph.trajectory, metric="se2(rotation_weight_m_per_rad=1)")
    with pytest.raises(IndexError, match="90"):
        loops.pair_verdicts([0], [90], graph.trajectory)
    with pytest.raises(ValueError, match="i has 2 values but j has 1"):
        loops.pair_verdicts([0, 1], [1], graph.trajectory)
    empty = loops.pair_verdicts([], [], graph.trajectory)
    assert empty.num_rows == 0 and list(empty) == ["i", "j", "distance", "verdict", "component"]


# --- edge-only files ------------------------------------------------------------------------------


def random_se3(rng: np.random.Generator, n: int) -> tuple[np.ndarray, Rotation]:
    """A wandering 3-D path (the first pose at the origin, unrotated) and random orientations."""
    rotations = Rotation.random(n, random_state=rng)
    rotations = Rotation.concatenate([Rotation.identity(), rotations[1:]])
    steps = rng.uniform([0.1, -0.3, -0.3], [2.0, 0.3, 0.3], size=(n, 3))
    positions = np.zeros((n, 3))
    for k in range(1, n):
        positions[k] = positions[k - 1] + rotations[k - 1].apply(steps[k])
    return positions, rotations


def chained_se3(
    seed: int, n: int, edge: Callable[[int, int, np.ndarray, Rotation], str], flipped: int = -1
) -> tuple[np.ndarray, Rotation, list[str]]:
    """A :func:`random_se3` path of ``n`` poses and the lines ``edge(a, b, d, r)`` of its steps
    (pose b in the frame of pose a: translation d, rotation r), from each pose to the next
    (step ``flipped`` from the next pose back)."""
    positions, rotations = random_se3(np.random.default_rng(seed), n)
    lines = []
    for k in range(n - 1):
        a, b = (k + 1, k) if k == flipped else (k, k + 1)
        d = rotations[a].inv().apply(positions[b] - positions[a])
        lines.append(edge(a, b, d, rotations[a].inv() * rotations[b]))
    return positions, rotations, lines


def test_chained_se3_quat_edges_give_back_the_vertices(tmp_path: Path) -> None:
    n = 120
    # r.as_quat(): x, y, z, w.
    positions, rotations, lines = chained_se3(
        7,
        n,
        lambda a, b, d, r: f"EDGE_SE3:QUAT {a} {b} " + " ".join(num(v) for v in [*d, *r.as_quat()]),
        flipped=40,
    )
    lines.append(f"EDGE_SE3:QUAT 100 3 0 0 0 0 0 0 1{' 1' * 21}")
    path = write_lines(tmp_path / "se3.g2o", lines)
    with pytest.raises(il.LoopsIOError, match=r"120 edge\(s\).*chain_edges=True"):
        il.read_pose_graph(path)
    with pytest.warns(il.DeadReckoningWarning, match="120 poses .vertices 0 to 119. chained"):
        graph = il.read_pose_graph(
            path, chain_edges=True, metric="se3(rotation_weight_m_per_rad=1)"
        )
    assert graph.chained and graph.dim == 3 and graph.edges.num_rows == n
    points = graph.trajectory.positions  # x y z qx qy qz qw
    np.testing.assert_allclose(points[:, :3], positions, atol=1e-9)
    dots = np.abs(np.sum(points[:, 3:] * rotations.as_quat(), axis=1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-9)
    np.testing.assert_allclose(np.isnan(graph.edges["info_55"]), [True] * (n - 1) + [False])


def test_chained_toro_edge3_uses_roll_pitch_yaw(tmp_path: Path) -> None:
    """TORO's EDGE3 x y z roll pitch yaw, R = Rz(yaw) Ry(pitch) Rx(roll): scipy's intrinsic ZYX."""
    # r.as_euler("ZYX"): yaw, pitch, roll; TORO writes roll, pitch, yaw.
    positions, rotations, lines = chained_se3(
        11,
        60,
        lambda a, b, d, r: (
            f"EDGE3 {a} {b} " + " ".join(num(v) for v in [*d, *r.as_euler("ZYX")[::-1]])
        ),
    )
    path = write_lines(tmp_path / "edges.graph", lines)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", il.DeadReckoningWarning)
        traj = il.read_trajectory(path, chain_edges=True, metric="se3_rotation")
    np.testing.assert_allclose(traj.positions[:, :3], positions, atol=1e-9)
    dots = np.abs(np.sum(traj.positions[:, 3:] * rotations.as_quat(), axis=1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-9)


def test_chained_edge2_list_round_trip_and_gap(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    n = 150
    theta = np.cumsum(np.r_[0.0, rng.uniform(-0.8, 0.8, n - 1)])
    step = rng.uniform(0.1, 2.0, n)
    xy = np.zeros((n, 2))
    for k in range(1, n):
        xy[k] = xy[k - 1] + step[k] * np.array([np.cos(theta[k - 1]), np.sin(theta[k - 1])])
    lines = []
    for k in range(n - 1):
        rot = Rotation.from_euler("z", theta[k])
        dx, dy, _ = rot.inv().apply([*(xy[k + 1] - xy[k]), 0.0])
        lines.append(
            f"EDGE2 {k} {k + 1} {num(dx)} {num(dy)} {num(theta[k + 1] - theta[k])} 1 0 1 1 0 0"
        )
    path = write_lines(tmp_path / "odometry.graph", lines)
    with pytest.raises(il.LoopsIOError, match="chain_edges=True"):
        il.read_trajectory(path)
    with pytest.warns(il.DeadReckoningWarning, match="dead reckoning"):
        traj = il.read_trajectory(path, chain_edges=True, metric="se2(rotation_weight_m_per_rad=1)")
    np.testing.assert_allclose(traj.positions[:, :2], xy, atol=1e-9)
    np.testing.assert_allclose(
        np.angle(np.exp(1j * (traj.positions[:, 2] - theta))), 0.0, atol=1e-9
    )
    np.testing.assert_array_equal(traj.timestamps, np.arange(n))
    gap = tmp_path / "gap.graph"
    gap.write_text("\n".join(lines[:70] + lines[71:]) + "\n")
    with pytest.raises(il.LoopsIOError, match="no edge joins vertex 70 and vertex 71"):
        il.read_pose_graph(gap, chain_edges=True)


@pytest.mark.parametrize("name", ["input_INTEL_g2o.g2o", "FR079_P_toro.graph"])
def test_real_odometry_edges_chain_to_the_vertex_guesses(tmp_path: Path, name: str) -> None:
    """The classic data sets' vertices are their odometry composed (printed to 6 decimals)."""
    needs_graphs()
    text = (GRAPHS / name).read_text().splitlines()
    edges_only = tmp_path / name
    edges_only.write_text("\n".join(line for line in text if line.startswith("EDGE")) + "\n")
    given = il.read_pose_graph(GRAPHS / name)
    with pytest.warns(il.DeadReckoningWarning):
        chained = il.read_pose_graph(edges_only, chain_edges=True)
    np.testing.assert_array_equal(chained.vertex_ids, given.vertex_ids)
    np.testing.assert_allclose(chained.trajectory.positions, given.trajectory.positions, atol=2e-4)
    for column in ("from_id", "to_id", "dx", "dy", "dtheta", "info_22"):
        np.testing.assert_array_equal(chained.edges[column], given.edges[column])


def test_the_example_prints_the_verdicts(tmp_path: Path) -> None:
    path, _, _ = small_graph(tmp_path)
    example = Path(__file__).parents[2] / "examples" / "pose_graph_edges.py"
    out = tmp_path / "verdicts.csv"
    command = [sys.executable, str(example), str(path), "--gamma", "1.5", "--csv", str(out)]
    printed = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    graph = il.read_pose_graph(path)
    verdicts = graph.edge_verdicts(il.find_loops(graph.trajectory, gamma=1.5))
    outside = int((verdicts["verdict"] == "outside").sum())
    assert f"  outside        {outside:>5}" in printed, printed
    pytest.importorskip("pandas")
    with out.open() as file:
        assert [row["verdict"] for row in csv.DictReader(file)] == verdicts["verdict"].tolist()


def test_gtsam_graphs_say_what_they_skip_and_evo_kitti_reads(tmp_path):
    """GTSAM's LANDMARK2/BR lines and TORO's EQUIV are skipped with one warning naming them;
    evo's ``.kitti`` files are KITTI."""
    path = tmp_path / "example.graph"
    path.write_text(
        "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 1 0 1 1 0 0\n"
        "LANDMARK2 1 7 2.5 0.3 1 0 1\nBR 1 7 0.2 2.5 0.01 0.1\nEQUIV 0 1\n"
    )
    for read in (il.read_trajectory, il.read_pose_graph):
        with pytest.warns(il.DroppedInputWarning) as caught:
            read(path)
        messages = [str(w.message) for w in caught]
        assert len(messages) == 1, messages
        assert "1 LANDMARK2 line" in messages[0] and "1 BR line" in messages[0], messages
        assert "1 EQUIV line (first on line 6)" in messages[0], messages
    kitti = tmp_path / "traj.kitti"
    kitti.write_text("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n")
    traj = il.read_trajectory(kitti, rate_hz=10.0)
    np.testing.assert_array_equal(traj.positions[1], [1.0, 0.0, 0.0])
