"""Metrics on manifolds against independent code (scipy's Rotation, a textbook haversine,
numpy), and the paper's Fig. 5 on real KITTI drives."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import inexact_loops as il

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
RNG = np.random.default_rng(20261122)


def engine_distance(points: np.ndarray, build, metric) -> float:
    """δ(points[0], points[1]) as the engine sees it: the largest γ at which the pair is
    outside S_γ, found by bisection (the engine only answers δ ≤ γ)."""
    traj = build(np.array([0.0, 1.0]), points)
    lo, hi = 0.0, 1.0
    while il.find_loops(traj, gamma=hi, metric=metric, separation=None).component_of(0, 1) is None:
        hi *= 2.0
    if (
        il.find_loops(traj, gamma=1e-300, metric=metric, separation=None).component_of(0, 1)
        is not None
    ):
        return 0.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if (
            il.find_loops(traj, gamma=mid, metric=metric, separation=None).component_of(0, 1)
            is None
        ):
            lo = mid
        else:
            hi = mid
    return hi


def random_rotations(n: int) -> Rotation:
    rotations = Rotation.random(n, random_state=7)
    # Adversarial: near π, exactly π, identity, and q / −q pairs.
    special = Rotation.from_rotvec(
        [[np.pi, 0, 0], [0, np.pi - 1e-9, 0], [0, 0, 0], [1e-9, 0, 0], [0, 0, np.pi / 2]]
    )
    return Rotation.concatenate([rotations, special])


@pytest.mark.parametrize("rotation", ["geodesic", "chordal"])
def test_so3_matches_scipy(rotation: str) -> None:
    rs = random_rotations(12)
    for k in range(len(rs) - 1):
        a, b = rs[k], rs[k + 1]
        if rotation == "geodesic":
            expected = (a.inv() * b).magnitude()
        else:
            expected = np.linalg.norm(a.as_matrix() - b.as_matrix())
        q = np.stack([a.as_quat(), b.as_quat()])
        if k % 2:
            q[1] = -q[1]  # q and −q are the same rotation
        got = engine_distance(q, il.Trajectory.so3, il.metrics.SO3(rotation=rotation))
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-9), (k, rotation)


def test_so3_from_rotation_vectors_matches_scipy() -> None:
    rv = RNG.normal(size=(50, 3))
    traj = il.Trajectory.so3_from_rotation_vectors(np.arange(50.0), rv)
    q = traj.positions
    expected = Rotation.from_rotvec(rv).as_quat()
    np.testing.assert_allclose(np.abs(np.sum(q * expected, axis=1)), 1.0, atol=1e-12)


def test_se3_weighted_sum() -> None:
    rs = random_rotations(6)
    p = RNG.normal(size=(2, 3)) * 5
    for w in [0.0, 0.5, 10.0]:
        q = np.stack([rs[0].as_quat(), rs[1].as_quat()])
        expected = np.linalg.norm(p[0] - p[1]) + w * (rs[0].inv() * rs[1]).magnitude()
        got = engine_distance(
            p,
            lambda t, pos, q=q: il.Trajectory.se3(t, pos, q),
            il.metrics.SE3(rotation_weight_m_per_rad=w),
        )
        assert got == pytest.approx(expected, rel=1e-9)


def haversine_m(lat1: float, lon1: float, lat2: float, lon2: float, r: float = 6371008.8) -> float:
    """The textbook formula."""
    p1, p2 = np.radians(lat1), np.radians(lat2)
    dp, dl = p2 - p1, np.radians(lon2 - lon1)
    a = np.sin(dp / 2) ** 2 + np.cos(p1) * np.cos(p2) * np.sin(dl / 2) ** 2
    return float(2 * r * np.arcsin(np.sqrt(a)))


@pytest.mark.parametrize(
    ("a", "b"),
    [
        ((48.8566, 2.3522), (51.5074, -0.1278)),  # Paris – London
        ((0.0, 179.9999), (0.0, -179.9999)),  # across the date line
        ((89.9999, 0.0), (89.9999, 180.0)),  # across the pole
        ((-33.9, 151.2), (40.7, -74.0)),  # Sydney – New York
    ],
)
def test_haversine_matches_textbook(a: tuple[float, float], b: tuple[float, float]) -> None:
    fixes = np.array([[a[0], a[1], 0.0], [b[0], b[1], 0.0]])
    got = engine_distance(fixes, il.Trajectory.gnss, il.metrics.Haversine())
    assert got == pytest.approx(haversine_m(*a, *b), rel=1e-9)


def test_paris_london() -> None:
    assert haversine_m(48.8566, 2.3522, 51.5074, -0.1278) == pytest.approx(343.5e3, abs=1e3)


def test_descriptors_angular_and_euclidean_match_numpy() -> None:
    d = RNG.normal(size=(2, 16))
    cos = d[0] @ d[1] / np.linalg.norm(d[0]) / np.linalg.norm(d[1])
    angular = engine_distance(d, lambda t, x: il.Trajectory.descriptors(t, x), il.metrics.Angular())
    assert angular == pytest.approx(np.arccos(cos), rel=1e-9)
    euclidean = engine_distance(
        d, lambda t, x: il.Trajectory.descriptors(t, x, normalize=False), il.metrics.Euclidean()
    )
    assert euclidean == pytest.approx(np.linalg.norm(d[0] - d[1]), rel=1e-9)


def test_torus_and_se2_least_angles() -> None:
    angles = np.array([[np.pi - 0.1, -np.pi + 0.05], [-np.pi + 0.1, np.pi - 0.05]])
    got = engine_distance(angles, il.Trajectory.torus, il.metrics.Torus())
    assert got == pytest.approx(np.hypot(0.2, 0.1), rel=1e-9)
    poses = np.array([[0.0, 0.0, np.pi - 0.1], [3.0, 4.0, -np.pi + 0.1]])
    got = engine_distance(poses, il.Trajectory.se2, il.metrics.SE2(rotation_weight_m_per_rad=2.0))
    assert got == pytest.approx(5.0 + 2.0 * 0.2, rel=1e-9)


def test_engine_equals_brute_force_on_so3() -> None:
    rv = np.cumsum(RNG.normal(scale=0.15, size=(250, 3)), axis=0)
    traj = il.Trajectory.so3_from_rotation_vectors(np.arange(250.0), rv)
    rs = Rotation.from_rotvec(rv)
    dense = np.array([[(rs[i].inv() * rs[j]).magnitude() for j in range(250)] for i in range(250)])
    for gamma in [0.3, 1.0, 2.5]:
        loops = il.find_loops(traj, gamma=gamma, metric="so3", separation=None)
        runs = loops.runs()
        mask = np.zeros_like(dense, dtype=bool)
        for r, a, b in zip(runs["row"], runs["start"], runs["end"], strict=True):
            mask[r, a : b + 1] = True
        np.testing.assert_array_equal(mask, np.triu(dense <= gamma))


def test_bad_manifold_input() -> None:
    t = np.array([0.0, 1.0])
    with pytest.raises(il.InvalidTrajectoryError, match="pose 1"):
        il.Trajectory.so3(t, [[0, 0, 0, 1.0], [0, 0, 0, 1.01]])
    # Within 1e-3 of unit length (4 printed decimals), as read_trajectory accepts: normalised.
    ok = il.Trajectory.so3(t, [[0, 0, 0, 1.0], [0, 0, 0, 1.00001]])
    assert np.linalg.norm(ok.positions[1]) == pytest.approx(1.0, abs=1e-15)
    with pytest.raises(il.InvalidTrajectoryError, match="pose 0"):
        il.Trajectory.se3(t, np.zeros((2, 3)), [[0, 0, 0, 0.0], [0, 0, 0, 1.0]])
    with pytest.raises(il.InvalidTrajectoryError, match="pose 1"):
        il.Trajectory.gnss(t, [[10.0, 0, 0], [90.5, 0, 0]])
    with pytest.raises(ValueError, match="row 1"):
        il.Trajectory.descriptors(np.arange(3.0), [[1.0, 2.0], [1.0, 2.0, 3.0], [1.0, 2.0]])
    with pytest.raises(il.InvalidTrajectoryError, match="pose 1"):
        il.Trajectory.descriptors(t, [[1.0, 2.0], [0.0, 0.0]])
    traj = il.Trajectory.se3(t, np.zeros((2, 3)), [[0, 0, 0, 1.0], [0, 0, 0, 1.0]])
    with pytest.raises(il.InvalidParameterError, match="rotation_weight_m_per_rad"):
        il.find_loops(
            traj, gamma=1.0, metric=il.metrics.SE3(rotation_weight_m_per_rad=-1.0), separation=None
        )
    with pytest.raises(
        il.InvalidParameterError, match="metric so3.* does not fit an se3 trajectory"
    ):
        il.find_loops(traj, gamma=1.0, metric="so3", separation=None)
    with pytest.raises(il.InvalidParameterError, match="dimension"):
        il.find_loops(il.Trajectory(t, traj.positions), gamma=1.0, metric="so3", separation=None)
    with pytest.raises(TypeError, match="metric"):
        il.find_loops(traj, gamma=1.0, metric=3, separation=None)


def test_python_callable_metric_is_a_slow_path_that_agrees() -> None:
    traj = il.urban_drive(duration_s=60.0, seed=2)
    fast = il.find_loops(traj, gamma=15.0, separation=None)
    slow = il.find_loops(
        traj, gamma=15.0, metric=lambda a, b: float(np.linalg.norm(a - b)), separation=None
    )
    np.testing.assert_array_equal(fast.runs()["end"], slow.runs()["end"])
    with pytest.raises(ZeroDivisionError):
        il.find_loops(traj, gamma=15.0, metric=lambda a, b: 1 / 0, separation=None)


def kitti_se3(seq: str) -> il.Trajectory:
    path = DATA / "kitti_odometry" / f"{seq}.txt"
    if not path.exists():
        pytest.skip(f"{path} is absent: real-data tests need ../shared/data beside the checkout")
    a = np.loadtxt(path)
    m = a[:, 1:].reshape(-1, 3, 4)
    q = Rotation.from_matrix(m[:, :, :3]).as_quat()
    return il.Trajectory.se3(a[:, 0], m[:, :, 3], q, quaternion_tolerance=1e-3)


def heading_difference(traj: il.Trajectory, i: int, j: int) -> float:
    q = traj.positions[:, 3:]
    return (Rotation.from_quat(q[i]).inv() * Rotation.from_quat(q[j])).magnitude()


def test_fig5_opposite_direction_revisits_separate_under_se3() -> None:
    """KITTI 08 drives its revisits in the opposite direction: under L2 on translations they
    are loop components; under SE(3) with 10 m/rad a half turn costs 31 m > γ = 10 m, so every
    pair of them leaves S_γ."""
    traj = kitti_se3("08")
    gamma, weight = 10.0, 10.0
    l2 = il.find_loops(
        traj, gamma=gamma, metric=il.metrics.SE3(rotation_weight_m_per_rad=0.0), separation=None
    )
    se3 = il.find_loops(
        traj, gamma=gamma, metric=il.metrics.SE3(rotation_weight_m_per_rad=weight), separation=None
    )
    table = l2.components
    revisits = np.flatnonzero(~table["trivial"])
    print(
        f"KITTI 08, gamma {gamma} m: L2 {len(table['id'])} components, "
        f"SE(3) {len(se3.components['id'])}"
    )
    assert len(revisits) >= 1
    for c in revisits:
        i, j = table["closest_i"][c], table["closest_j"][c]
        turn = heading_difference(traj, i, j)
        print(
            f"  component {c}: closest pair ({i}, {j}), "
            f"heading difference {np.degrees(turn):.0f} deg"
        )
        assert turn > gamma / weight  # so w * angle > γ for that pair
        assert se3.component_of(i, j) is None
    assert not np.any(~se3.components["trivial"])


def test_fig5_holes_under_l2_not_under_se3() -> None:
    """KITTI 05 at γ = 80 m: some components are multiply connected under L2 on translations,
    none under SE(3) (10 m/rad) — the paper's Fig. 5 observation."""
    traj = kitti_se3("05")
    l2 = il.find_loops(
        traj, gamma=80.0, metric=il.metrics.SE3(rotation_weight_m_per_rad=0.0), separation=None
    )
    se3 = il.find_loops(
        traj, gamma=80.0, metric=il.metrics.SE3(rotation_weight_m_per_rad=10.0), separation=None
    )
    print(
        "KITTI 05 holes: L2",
        l2.components["holes"].tolist(),
        "SE(3)",
        se3.components["holes"].tolist(),
    )
    assert l2.components["holes"].sum() > 0
    assert se3.components["holes"].sum() == 0
