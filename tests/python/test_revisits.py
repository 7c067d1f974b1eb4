"""Revisits (a minimum separation along the trajectory) against a dense reference.

The reference X is built from numpy and scipy alone: ``D = cdist(P, P)``, and the cells (i, j)
of the upper triangle j > i with ``D <= gamma``, ``s_j - s_i >= L`` and ``t_j - t_i >= T``,
where s is the path length ``il.path_length`` returns (the only engine output the reference
uses: it is the definition of the separation, and its own test is a cumulative sum below). Its
components are ``scipy.ndimage.label`` with 4-connectivity, holes come from
``skimage.measure.euler_number``, and tau/alpha/rho from a dense sum over the full-plane X
(both halves) with the time-cell widths (half cells at the ends, (t_{j+1} - t_{j-1}) / 2
inside).

Inputs: random walks (hypothesis), adversarial ones (out and back, stationary stretches, a
zig-zag, lattice points exactly gamma apart with separations met exactly), and windows of real
trajectories (TUC Corridor, KITTI 00) when ../shared/data is present.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import ndimage
from scipy.spatial.distance import cdist
from skimage.measure import euler_number

import inexact_loops as il

#: /work/shared/data beside the checkout (absent in a user's clone).
DATA_DIR = Path(__file__).parents[2] / ".." / "shared" / "data"
FOUR = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]])


def widths(t: np.ndarray) -> np.ndarray:
    steps = np.diff(t)
    return np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2


def holes_of(mask: np.ndarray) -> int:
    """Holes of a connected 4-connected set: 1 - Euler number (8-connected background)."""
    return 1 - int(euler_number(np.pad(mask, 1), connectivity=1))


def dense_x(t, p, gamma, separation):
    """(upper-half mask of X, distance matrix) from scratch."""
    n = len(t)
    d = cdist(p, p)
    s = il.path_length(il.Trajectory(t, p))
    i, j = np.indices((n, n))
    mask = (j > i) & (d <= gamma)
    mask &= (s[j] - s[i] >= separation.path) & (t[j] - t[i] >= separation.time_s)
    return mask, d


def runs_matrix(loops, n: int) -> np.ndarray:
    """Dense (n, n) component ids from the runs, -1 outside X."""
    runs = loops.runs()
    out = np.full((n, n), -1, dtype=np.int64)
    for r, a, b, c in zip(runs["row"], runs["start"], runs["end"], runs["component"], strict=True):
        assert out[r, a : b + 1].max() == -1, "runs overlap"
        out[r, a : b + 1] = c
    return out


def check_revisits(t, p, gamma, separation, *, threads=None):
    """Asserts that find_loops with ``separation`` equals the dense reference."""
    t = np.asarray(t, dtype=float)
    p = np.asarray(p, dtype=float).reshape(len(t), -1)
    n = len(t)
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=separation, threads=threads)
    assert loops.separation == separation
    mask, d = dense_x(t, p, gamma, separation)
    ours = runs_matrix(loops, n)
    np.testing.assert_array_equal(ours >= 0, mask, err_msg="the runs are not X's upper half")
    assert loops.pair_count == 2 * int(mask.sum()), "X in the full plane: both halves"

    labels, count = ndimage.label(mask, structure=FOUR)
    table = loops.components
    k = len(table["id"])
    assert k == count, f"{k} components, scipy finds {count}"
    assert not np.any(table["trivial"]), "with a separation no component is trivial"
    # A bijection between our ids and scipy's labels, cell by cell.
    cells = np.nonzero(mask)
    pairs = np.unique(np.c_[ours[cells], labels[cells]], axis=0)
    assert len(pairs) == k and len(np.unique(pairs[:, 0])) == k == len(np.unique(pairs[:, 1]))
    label_of = dict(pairs.tolist())
    boxes = ndimage.find_objects(labels)

    w = widths(t)
    full = (mask | mask.T).astype(float)
    span = t[-1] - t[0]
    for c in range(k):
        box = boxes[label_of[c] - 1]
        component = labels[box] == label_of[c]
        what = f"component {c}"
        assert table["pair_count"][c] == component.sum(), what
        extents = (box[0].start, box[0].stop - 1, box[1].start, box[1].stop - 1)
        got = tuple(int(table[key][c]) for key in ("i_min", "i_max", "j_min", "j_max"))
        assert got == extents, what
        assert table["holes"][c] == holes_of(component), f"{what}: holes"
        closest = d[box][component].min()
        np.testing.assert_allclose(table["closest_distance"][c], closest, rtol=1e-9, atol=1e-12)
        ci, cj = int(table["closest_i"][c]), int(table["closest_j"][c])
        assert ours[ci, cj] == c, f"{what}: its closest pair lies in it"
        np.testing.assert_allclose(d[ci, cj], closest, rtol=1e-9, atol=1e-12)
        area = float(w[box[0]] @ component @ w[box[1]])
        np.testing.assert_allclose(table["area_s2"][c], area, rtol=1e-9, atol=1e-12 * span**2)
        half = np.zeros((n, n))
        half[box] = component
        tau_c = (half + half.T) @ w
        np.testing.assert_allclose(
            loops.loop_duration(components=[c]), tau_c, rtol=1e-9, atol=1e-12 * span
        )

    # tau(t_i) = sum_j w_j over X's cells of row i, both halves; alpha and rho over the span.
    tau = full @ w
    np.testing.assert_allclose(loops.loop_duration(), tau, rtol=1e-9, atol=1e-12 * span)
    upper_tau = mask.astype(float) @ w
    np.testing.assert_allclose(
        loops.loop_duration(side="begin"), upper_tau, rtol=1e-9, atol=1e-12 * span
    )
    np.testing.assert_allclose(
        loops.loop_duration(side="end"), mask.T.astype(float) @ w, rtol=1e-9, atol=1e-12 * span
    )
    area = float(w @ full @ w)
    np.testing.assert_allclose(loops.loop_area(t[0], t[-1]), area, rtol=1e-9, atol=1e-9 * span)
    np.testing.assert_allclose(loops.loop_density(t[0], t[-1]), area / span, rtol=1e-9, atol=1e-9)
    # Point queries: in X, or None (also for pairs of S_gamma the separation leaves out).
    rng = np.random.default_rng(n)
    for i, j in rng.integers(0, n, size=(60, 2)).tolist():
        lo, hi = min(i, j), max(i, j)
        expected = int(ours[lo, hi]) if mask[lo, hi] else None
        assert loops.component_of(i, j) == expected, (i, j)
    return loops, mask


# --- inputs ----------------------------------------------------------------------------------


def random_walk(rng: np.random.Generator, n: int, gamma: float):
    """A 2-D walk by stretches: steps far below gamma, near it and beyond it, stops, and
    revisits (an earlier stretch again, forwards or backwards, a little off); uneven times."""
    points = [np.zeros(2)]
    while len(points) < n:
        kind = rng.choice(["walk", "stop", "revisit"], p=[0.55, 0.15, 0.3])
        length = int(rng.integers(1, max(2, n // 5)))
        if kind == "walk":
            scale = gamma * rng.choice([0.05, 0.3, 1.0, 1.6])
            points.extend(points[-1] + np.cumsum(rng.normal(size=(length, 2)) * scale, axis=0))
        elif kind == "stop":
            points.extend([points[-1]] * length)
        else:
            k = int(rng.integers(0, len(points)))
            stretch = np.array(points[k : k + length])
            if rng.random() < 0.5:
                stretch = stretch[::-1]
            points.extend(stretch + rng.normal(size=2) * gamma * rng.uniform(0.0, 0.7))
    t = np.r_[0.0, np.cumsum(rng.uniform(0.05, 2.0, n - 1))]
    return t, np.array(points[:n])


@st.composite
def walks(draw):
    n = draw(st.integers(3, 300))
    gamma = draw(st.floats(0.2, 5.0))
    seed = draw(st.integers(0, 2**32 - 1))
    t, p = random_walk(np.random.default_rng(seed), n, gamma)
    path = draw(st.sampled_from([0.0, 0.5, 1.0, 2.0, 4.0, 8.0])) * gamma
    time_s = draw(st.sampled_from([0.0, 0.0, 1.0, 10.0, 50.0]))
    if path == 0.0 and time_s == 0.0:
        path = gamma
    return t, p, gamma, il.Separation(path=path, time_s=time_s)


@settings(
    max_examples=200,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(walks())
def test_random_walks(case):
    t, p, gamma, separation = case
    check_revisits(t, p, gamma, separation)


def adversarial(name: str):
    """(timestamps, positions, gamma, separations) of a nasty input."""
    if name == "out_and_back":  # along a line of integers and back: every revisit on the way
        x = np.r_[np.arange(0, 30), np.arange(30, -1, -1)].astype(float)
        return np.arange(len(x), dtype=float), x, 2.0, [2.0, 4.0, 6.0, 7.5, 8.0, 40.0]
    if name == "out_and_back_twice":  # a corridor walked four times, with stops at both ends
        leg = np.r_[np.arange(0, 20), np.full(15, 20), np.arange(20, 0, -1), np.zeros(15)]
        x = np.tile(leg, 2).astype(float)
        return np.arange(len(x)) * 0.5, np.c_[x, np.zeros_like(x)], 3.0, [3.0, 6.0, 12.0, 24.0]
    if name == "stationary":  # long stops: no path is travelled, time goes on
        x = np.r_[np.zeros(40), np.arange(1, 25), np.full(40, 24.0), np.arange(23, -1, -1)]
        return np.arange(len(x), dtype=float), np.c_[x, x * 0], 1.0, [1.0, 4.0, 16.0]
    if name == "zig_zag":  # back and forth within gamma: the path grows, the position does not
        x = np.tile([0.0, 0.75, 0.25, 1.0], 40)
        y = np.repeat(np.arange(16) * 0.1, 10)
        return np.arange(len(x)) * 0.1, np.c_[x, y], 1.0, [0.5, 1.0, 2.0, 4.0, 16.0]
    if name == "exactly_gamma":  # lattice steps of 3-4-5 triangles: distances and paths exact
        steps = np.array([[3, 4], [4, -3], [-3, -4], [-4, 3]] * 12, dtype=float)
        p = np.vstack([np.zeros(2), np.cumsum(steps, axis=0)])
        return np.arange(len(p), dtype=float), p, 5.0, [5.0, 10.0, 15.0, 20.0]
    if name == "square_exact":  # a square of side 5 walked thrice in unit steps
        side = np.arange(5, dtype=float)
        one = np.r_[
            np.c_[side, 0 * side],
            np.c_[5 + 0 * side, side],
            np.c_[5 - side, 5 + 0 * side],
            np.c_[0 * side, 5 - side],
        ]
        p = np.vstack([one] * 3)
        return np.arange(len(p), dtype=float), p, 1.0, [1.0, 4.0, 19.0, 20.0, 21.0]
    raise ValueError(name)


@pytest.mark.parametrize(
    "name",
    [
        "out_and_back",
        "out_and_back_twice",
        "stationary",
        "zig_zag",
        "exactly_gamma",
        "square_exact",
    ],
)
def test_adversarial(name):
    t, p, gamma, paths = adversarial(name)
    for path in paths:
        check_revisits(t, p, gamma, il.Separation(path=path))
        check_revisits(t, p, gamma, il.Separation(path=path, time_s=float(t[len(t) // 5] - t[0])))
    check_revisits(t, p, gamma, il.Separation(time_s=float(t[3] - t[0])), threads=1)


def test_out_and_back_is_one_revisit():
    """The issue's case: out and back along a corridor. No separation: one trivial component;
    separated: the way back is one revisit component of the way out."""
    t, x, gamma, _ = adversarial("out_and_back")
    plain = il.find_loops(il.Trajectory(t, x), gamma=gamma, separation=None)
    assert plain.components["trivial"].tolist() == [True]
    loops, _ = check_revisits(t, x, gamma, il.Separation.for_gamma(gamma))
    assert len(loops.components["id"]) == 1


def test_separation_adds_no_distance_evaluations():
    """The separation clips the scan: with a counting Python metric, a separated search asks
    for no more distances than the plain one (and for fewer when the band is long)."""
    rng = np.random.default_rng(3)
    t, p = random_walk(rng, 250, 1.0)
    calls = {"n": 0}

    def counting(a, b):
        calls["n"] += 1
        return float(np.linalg.norm(a - b))

    traj = il.Trajectory(t, p)
    counts = {}
    for key, separation in (
        ("none", None),
        ("4", il.Separation(path=4.0)),
        ("16", il.Separation(path=16.0)),
    ):
        calls["n"] = 0
        loops = il.find_loops(traj, gamma=1.0, metric=counting, separation=separation)
        counts[key] = calls["n"]
        reference = il.find_loops(traj, gamma=1.0, separation=separation)
        np.testing.assert_array_equal(loops.runs()["start"], reference.runs()["start"])
    assert counts["16"] <= counts["4"] <= counts["none"], counts
    assert counts["16"] < counts["none"], counts


# --- windows of real trajectories ------------------------------------------------------------


def require(path: Path) -> Path:
    if not path.is_file():
        pytest.skip(f"{path.resolve()} is missing (real data is not in a user's clone)")
    return path


def corridor():
    path = require(DATA_DIR / "tuc" / "SLAM" / "Corridor_GT.txt")
    rows = [line.split() for line in path.read_text().splitlines() if line.startswith("point2")]
    values = np.array([[float(r[1]), float(r[2]), float(r[3])] for r in rows])
    return values[:, 0], values[:, 1:]


def kitti00():
    poses = np.loadtxt(require(DATA_DIR / "kitti_odometry" / "00.txt"))
    return poses[:, 0], poses[:, [4, 12]]  # time, then row-major [R|t]: t_x, t_z


@pytest.mark.parametrize(
    "window",
    [
        ("corridor", slice(3000, 3600), 1.0),  # 2 min of the corridor, on the way back
        ("corridor", slice(0, 2400, 4), 1.0),  # the first revisit, every 4th pose (0.3 m)
        ("corridor", slice(8100, None, 5), 1.0),  # the last revisit, every 5th pose
        ("kitti00", slice(3800, 4400), 6.0),  # 1 min of driving, no revisit beyond 2 gamma
        ("kitti00", slice(0, 2480, 4), 6.0),  # two loops, every 4th pose
        ("kitti00", slice(2300, None, 4), 6.0),
    ],
    ids=lambda w: f"{w[0]}[{w[1].start}:{w[1].stop}:{w[1].step}]",
)
@pytest.mark.parametrize("multiple", [1.0, 2.0, 4.0, 16.0])
def test_real_windows(window, multiple):
    name, part, gamma = window
    t, p = corridor() if name == "corridor" else kitti00()
    t, p = t[part], p[part]
    check_revisits(t, p, gamma, il.Separation(path=multiple * gamma))
    if multiple == 4.0:
        check_revisits(t, p, gamma, il.Separation(path=multiple * gamma, time_s=30.0))


def test_path_length_is_the_cumulative_step_length():
    rng = np.random.default_rng(5)
    t, p = random_walk(rng, 200, 1.0)
    s = il.path_length(il.Trajectory(t, p))
    expected = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    np.testing.assert_allclose(s, expected, rtol=1e-12, atol=1e-12)
