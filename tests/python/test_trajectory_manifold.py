"""A trajectory knows its manifold: every constructor records what its points are, and
``find_loops``, ``sample``, ``Samples.measure`` and ``distance_image`` without ``metric=``
measure them with that manifold's metric — checked against a brute-force distance matrix written
here from the definitions (scipy's ``Rotation`` for rotations, a textbook haversine, numpy) —
while a metric that does not fit them raises, naming both. No path measures a quaternion as a
vector.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation

import inexact_loops as il

# γ is chosen low on purpose (the 5% quantile of all distances), where steps exceed it and the
# diagonal breaks, and some constructors' default separation leaves no revisit: the engine says
# so, as it should; here the sets themselves are checked.
pytestmark = pytest.mark.filterwarnings(
    "ignore::inexact_loops.DiagonalBrokenWarning", "ignore::inexact_loops.NoLoopsWarning"
)

N = 140
EARTH_RADIUS_M = 6_371_008.8


def _path(seed: int) -> tuple[np.ndarray, np.random.Generator]:
    """Twice round a loop (so the trajectory comes back to itself), with noise."""
    rng = np.random.default_rng(seed)
    u = 2 * 2 * np.pi * np.arange(N) / N + 0.05 * rng.uniform(-1, 1, N)
    return u, rng


def _rotations(u: np.ndarray, rng: np.random.Generator) -> Rotation:
    return Rotation.from_rotvec(
        np.c_[
            0.6 * np.cos(u) + 0.1 * rng.uniform(-1, 1, len(u)), 0.6 * np.sin(u), 1.3 * np.sin(2 * u)
        ]
    )


def _quaternions(rotations: Rotation, rng: np.random.Generator) -> np.ndarray:
    """x, y, z, w, each with a random sign (q and −q are one rotation)."""
    signs = rng.choice([-1.0, 1.0], size=(len(rotations), 1))
    return rotations.as_quat() * signs


def _geodesic(rotations: Rotation) -> np.ndarray:
    """The angle of R_a⁻¹ R_b for every pair, by scipy."""
    return np.stack([(rotations[i].inv() * rotations).magnitude() for i in range(len(rotations))])


def _wrapped(d: np.ndarray) -> np.ndarray:
    """Least angular difference, |d| mod 2π folded into [0, π]."""
    return np.abs(np.angle(np.exp(1j * d)))


def _angle(vectors: np.ndarray) -> np.ndarray:
    """The angle between every two vectors, from their cosine (clipped)."""
    unit = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
    return np.arccos(np.clip(unit @ unit.T, -1.0, 1.0))


def _haversine_m(lat_lon_deg: np.ndarray) -> np.ndarray:
    """Textbook haversine, metres, for every pair."""
    lat, lon = np.radians(lat_lon_deg[:, 0]), np.radians(lat_lon_deg[:, 1])
    d_lat = lat[:, None] - lat[None, :]
    d_lon = lon[:, None] - lon[None, :]
    a = (
        np.sin(d_lat / 2) ** 2
        + np.cos(lat[:, None]) * np.cos(lat[None, :]) * np.sin(d_lon / 2) ** 2
    )
    return 2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0.0, 1.0)))


@dataclass
class Case:
    """A trajectory as a constructor built it, the distance matrix of its manifold's metric by
    brute force, and what it must report."""

    name: str
    traj: il.Trajectory
    distances: np.ndarray
    manifold: str
    metric: str


def _cases(seed: int) -> list[Case]:
    u, rng = _path(seed)
    t = np.arange(N, dtype=float)
    noise = rng.uniform(-1, 1, N)
    xyz = np.c_[10 * np.cos(u), 10 * np.sin(u), noise]
    rotations = _rotations(u, rng)
    quaternions = _quaternions(rotations, rng)
    headings = 5 * u + 3 * rng.uniform(-1, 1, N)  # far beyond ±π
    angles = np.c_[u, 3 * u + 0.1 * rng.uniform(-1, 1, N), -7 + 0.2 * rng.uniform(-1, 1, N)]
    vectors = np.c_[5 * np.cos(u), 5 * np.sin(u), 2 + rng.uniform(-1, 1, N)]
    lat_lon = np.c_[30 + 10 * np.sin(u), 175 + 10 * np.cos(u) + 0.3 * rng.uniform(-1, 1, N)]
    fixes = np.c_[48.1 + 1e-3 * np.sin(u), 179.999 + 1e-3 * np.cos(u), 5 * rng.uniform(-1, 1, N)]
    descriptors = np.stack([np.sin(u + k) * (2 + k) for k in range(8)], axis=1) + 0.1 * rng.uniform(
        -1, 1, (N, 8)
    )
    ecef = il.Trajectory.gnss_ecef(t, fixes)
    se3_rotations = _rotations(u + 2 * rng.uniform(-1, 1, N), rng)
    se3 = "se3(rotation_weight_m_per_rad=0, rotation=geodesic)"
    return [
        Case("Trajectory", il.Trajectory(t, xyz), cdist(xyz, xyz), "euclidean", "euclidean"),
        # SE(3) and SE(2): the translation, whatever the rotations.
        Case(
            "se3",
            il.Trajectory.se3(t, xyz, _quaternions(se3_rotations, rng)),
            cdist(xyz, xyz),
            "se3",
            se3,
        ),
        Case(
            "so3",
            il.Trajectory.so3(t, quaternions),
            _geodesic(rotations),
            "so3",
            "so3(rotation=geodesic)",
        ),
        Case(
            "so3_from_rotation_vectors",
            il.Trajectory.so3_from_rotation_vectors(t, rotations.as_rotvec()),
            _geodesic(rotations),
            "so3",
            "so3(rotation=geodesic)",
        ),
        Case(
            "se2",
            il.Trajectory.se2(t, np.c_[xyz[:, :2], headings]),
            cdist(xyz[:, :2], xyz[:, :2]),
            "se2",
            "se2(rotation_weight_m_per_rad=0)",
        ),
        Case(
            "torus",
            il.Trajectory.torus(t, angles),
            np.sqrt((_wrapped(angles[:, None, :] - angles[None, :, :]) ** 2).sum(axis=2)),
            "torus",
            "torus",
        ),
        Case(
            "sphere",
            il.Trajectory.sphere(t, vectors),
            _angle(vectors),
            "sphere",
            "sphere(radius=1)",
        ),
        Case(
            "sphere_from_lat_lon",
            il.Trajectory.sphere_from_lat_lon(t, lat_lon),
            _haversine_m(lat_lon) / EARTH_RADIUS_M,
            "sphere",
            "sphere(radius=1)",
        ),
        Case(
            "gnss",
            il.Trajectory.gnss(t, fixes),
            np.hypot(_haversine_m(fixes[:, :2]), fixes[:, 2, None] - fixes[None, :, 2]),
            "gnss",
            "haversine(radius_m=6371008.8)",
        ),
        Case("gnss_ecef", ecef, cdist(ecef.positions, ecef.positions), "euclidean", "euclidean"),
        Case(
            "descriptors",
            il.Trajectory.descriptors(t, descriptors),
            _angle(descriptors),
            "descriptors",
            "angular",
        ),
        Case(
            "descriptors(normalize=False)",
            il.Trajectory.descriptors(t, descriptors, normalize=False),
            cdist(descriptors, descriptors),
            "euclidean",
            "euclidean",
        ),
    ]


CASES = _cases(1) + _cases(2)
# Every manifold is built by some constructor above.
assert {c.manifold for c in CASES} == {
    "euclidean",
    "se3",
    "so3",
    "se2",
    "torus",
    "sphere",
    "gnss",
    "descriptors",
}


def _gamma_between(distances: np.ndarray, quantile: float) -> float:
    """A γ half way between two consecutive distances near ``quantile``, far from every one of
    them (so S_γ does not depend on how either side rounds)."""
    d = np.sort(distances[np.triu_indices(len(distances))])
    gaps = np.diff(d)
    start = int(quantile * len(d))
    k = start + int(np.argmax(gaps[start:] > 1e-6 * d[-1]))
    return float(0.5 * (d[k] + d[k + 1]))


def _mask(loops: il.Loops, n: int) -> np.ndarray:
    """S_γ's upper half as a dense boolean matrix, from the runs."""
    runs = loops.runs()
    mask = np.zeros((n, n), dtype=bool)
    for row, start, end in zip(runs["row"], runs["start"], runs["end"], strict=True):
        mask[row, start : end + 1] = True
    return mask


@pytest.mark.parametrize("case", CASES, ids=[f"{c.name}-{k}" for k, c in enumerate(CASES)])
def test_find_loops_without_metric_uses_the_manifolds_metric(case: Case) -> None:
    assert case.traj.manifold == case.manifold
    assert case.traj.metric_name == case.metric
    assert f", {case.manifold}, dim {case.traj.dim}," in repr(case.traj)
    upper = np.triu(np.ones((N, N), dtype=bool))
    # Path length under the manifold's metric: the sum of the brute-force steps.
    path = il.path_length(case.traj)
    steps = case.distances[np.arange(N - 1), np.arange(1, N)]
    np.testing.assert_allclose(path, np.r_[0.0, np.cumsum(steps)], rtol=1e-9, atol=1e-7)
    for quantile in (0.05, 0.3):
        gamma = _gamma_between(case.distances, quantile)
        loops = il.find_loops(case.traj, gamma=gamma, separation=None)
        assert loops.metric_name == case.metric
        expected = (case.distances <= gamma) & upper
        got = _mask(loops, N)
        wrong = np.argwhere(got != expected)
        assert len(wrong) == 0, (
            f"{case.name}: pairs {wrong[:5].tolist()} differ from the brute force"
        )
        # The second lap comes back: the check sees revisits, not only the diagonal.
        assert np.triu(expected, N // 3).any()
        # The same as naming the metric.
        named = il.find_loops(case.traj, gamma=gamma, metric=case.metric, separation=None)
        assert named.runs()["end"].tolist() == loops.runs()["end"].tolist()
        # The default separation (4 γ of path) is measured by the same metric.
        revisits = il.find_loops(case.traj, gamma=gamma)
        assert revisits.metric_name == case.metric
        separated = expected & np.triu(path[None, :] - path[:, None] >= 4 * gamma, 1)
        assert (_mask(revisits, N) == separated).all(), case.name


@pytest.mark.parametrize("case", CASES[:12], ids=[c.name for c in CASES[:12]])
def test_sampling_measuring_and_images_use_the_manifolds_metric(case: Case) -> None:
    gamma = _gamma_between(case.distances, 0.1)
    loops = il.find_loops(case.traj, gamma=gamma, separation=None)
    samples = il.sample(loops, "alpha", budget=50, seed=3, trajectory=case.traj)
    i, j = samples.i, samples.j
    assert i is not None and j is not None
    assert samples.distance == pytest.approx(case.distances[i, j], rel=1e-6, abs=1e-7)
    # Detections clustered, then placed and measured on the trajectory: its metric again.
    detections = il.Detections(case.traj.timestamps[i], case.traj.timestamps[j])
    clusters = il.cluster_detections(detections, epsilon_s=5.0)
    placed = il.sample(clusters, "alpha", budget=20, seed=0, trajectory=case.traj)
    assert placed.i is not None and placed.j is not None
    assert placed.distance == pytest.approx(case.distances[placed.i, placed.j], rel=1e-6, abs=1e-7)
    measured = il.sample(clusters, "alpha", budget=20, seed=0).measure(case.traj)
    assert measured.distance == pytest.approx(placed.distance, rel=1e-12, abs=0)
    grid = il.PlaneGrid(case.traj, 40)
    image = il.distance_image(case.traj, grid)
    reference = case.distances[np.ix_(grid.columns, grid.rows)].T
    np.testing.assert_allclose(image, reference, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize(
    "case", [c for c in CASES[:12] if c.manifold not in ("euclidean", "descriptors")]
)
def test_a_metric_that_does_not_fit_raises_naming_both(case: Case) -> None:
    gamma = 1.0
    pattern = (
        rf"metric euclidean does not fit an? {case.manifold} trajectory "
        + rf"\({case.traj.dim} columns: .*\).*default, "
        + re.escape(case.metric)
    )
    with pytest.raises(il.InvalidParameterError, match=pattern):
        il.find_loops(case.traj, gamma=gamma, metric="euclidean")
    with pytest.raises(il.InvalidParameterError, match="does not fit"):
        il.find_loops(case.traj, gamma=gamma, metric=il.metrics.Euclidean())
    with pytest.raises(il.InvalidParameterError, match="does not fit"):
        il.distance_image(case.traj, il.PlaneGrid(case.traj, 10), metric="euclidean")
    loops = il.find_loops(case.traj, gamma=gamma)
    with pytest.raises(il.InvalidParameterError, match="does not fit"):
        il.sample(loops, "rho", budget=10, seed=0, trajectory=case.traj, metric="euclidean")
    clusters = il.cluster_detections(il.Detections([0.0], [50.0]), epsilon_s=1.0)
    with pytest.raises(il.InvalidParameterError, match="does not fit"):
        il.sample(clusters, "one", budget=1, seed=0).measure(case.traj, metric="euclidean")
    # A Python callable is the user's own: it gets the points as stored, unchecked.
    assert (
        il.find_loops(case.traj, gamma=gamma, metric=lambda a, b: float(abs(a[0] - b[0])))
        is not None
    )


def test_the_issue_as_reported() -> None:
    """``Trajectory.se3(...)``, ``from_evo(..., metric="se3(...)")`` and ``Trajectory.gnss(...)``
    measured with no ``metric=``: no L2 over the stored columns."""
    u, rng = _path(5)
    t = np.arange(N, dtype=float)
    xyz = np.c_[3 * np.cos(u), 3 * np.sin(u), np.zeros(N)]
    # Heading reversed on the second lap: L2 over quaternion columns would split the laps.
    yaw = np.where(np.arange(N) < N // 2, u, u + np.pi)
    quaternions = Rotation.from_euler("z", yaw[:, None]).as_quat()
    poses = il.Trajectory.se3(t, xyz, quaternions)
    loops = il.find_loops(poses, gamma=0.3, separation=None)
    reference = cdist(xyz, xyz) <= 0.3
    assert _mask(loops, N).tolist() == np.triu(reference).tolist()
    stored = poses.positions
    assert stored.shape == (N, 7)
    assert not (np.triu(cdist(stored, stored) <= 0.3) == _mask(loops, N)).all(), (
        "L2 over 7 columns differs"
    )

    evo = SimpleNamespace(
        timestamps=t, positions_xyz=xyz, orientations_quat_wxyz=np.roll(quaternions, 1, axis=1)
    )
    weighted = il.Trajectory.from_evo(evo, metric="se3(rotation_weight_m_per_rad=1)")
    assert weighted.metric_name == "se3(rotation_weight_m_per_rad=1, rotation=geodesic)"
    assert il.find_loops(weighted, gamma=0.3).metric_name == weighted.metric_name
    assert il.Trajectory.from_evo(evo).manifold == "euclidean"
    assert il.Trajectory.from_evo(evo, metric="so3").metric_name == "so3(rotation=geodesic)"
    planar = il.Trajectory.from_evo(evo, metric=il.metrics.SE2(rotation_weight_m_per_rad=0.5))
    assert (planar.manifold, planar.metric_name) == ("se2", "se2(rotation_weight_m_per_rad=0.5)")

    fixes = np.c_[48.0 + 1e-4 * np.cos(u), 11.0 + 1e-4 * np.sin(u), np.zeros(N)]
    gnss = il.Trajectory.gnss(t, fixes)
    assert gnss.positions.shape == (N, 4)
    assert il.find_loops(gnss, gamma=3.0).metric_name == "haversine(radius_m=6371008.8)"

    drive = il.urban_drive(duration_s=60.0, se3=True)
    assert (drive.manifold, il.find_loops(drive, gamma=40.0).metric_name) == (
        "se3",
        poses.metric_name,
    )


def test_read_trajectory_keeps_the_metric_it_was_read_for(tmp_path: Path) -> None:
    u, rng = _path(9)
    rows = [
        f"{k}.0 {10 * np.cos(a):.6f} {10 * np.sin(a):.6f} 0.0"
        + f" 0 0 {np.sin(a / 2):.6f} {np.cos(a / 2):.6f}"
        for k, a in enumerate(u)
    ]
    path = tmp_path / "loop.tum"
    path.write_text("\n".join(rows) + "\n")
    positions = il.read_trajectory(path)
    assert (positions.manifold, positions.metric_name, positions.dim) == (
        "euclidean",
        "euclidean",
        3,
    )
    poses = il.read_trajectory(path, metric="se3(rotation_weight_m_per_rad=2)")
    assert (poses.manifold, poses.metric_name) == (
        "se3",
        "se3(rotation_weight_m_per_rad=2, rotation=geodesic)",
    )
    assert il.find_loops(poses, gamma=1.0).metric_name == poses.metric_name
    # Given again, a metric replaces the one it was read for, and must fit the poses.
    assert (
        il.find_loops(poses, gamma=1.0, metric="se3_rotation").metric_name
        == "se3_rotation(rotation=geodesic)"
    )
    with pytest.raises(il.InvalidParameterError, match="does not fit an se3 trajectory"):
        il.find_loops(poses, gamma=1.0, metric="euclidean")
    rotations = il.read_trajectory(path, metric="so3(rotation=chordal)")
    assert il.find_loops(rotations, gamma=0.1).metric_name == "so3(rotation=chordal)"
