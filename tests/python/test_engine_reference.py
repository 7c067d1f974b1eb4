"""The engine against a dense reference (scipy cdist / ndimage.label, skimage euler_number).

Trajectories are built to be nasty: repeated points, stationary stretches, steps larger than
gamma, revisits (forwards and backwards, with and without an offset), integer lattice points with
integer gamma so that distances hit gamma exactly, and uneven timestamps.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import inexact_loops as il

# Lattice offsets whose length is exactly an integer: (3, 4) -> 5, (2, 3, 6) -> 7, ...
EXACT_OFFSETS = {
    1: [(1,), (-1,)],
    2: [(3, 4), (-6, 8), (1, 0), (0, 2)],
    3: [(2, 3, 6), (1, -4, 8), (2, 2, 1), (3, 4, 0)],
}


def build_trajectory(rng: np.random.Generator, n: int, dim: int, kind: str, gamma: float):
    """(timestamps, positions) of n poses in R^dim made of random nasty segments.

    kind "lattice": integer coordinates (gamma is an integer), "dyadic": multiples of 1/4
    (gamma too), "real": arbitrary floats. In the first two every distance that equals gamma
    is computed exactly, so the boundary of S_gamma is full of exact ties.
    """
    unit = {"lattice": 1.0, "dyadic": 0.25, "real": 0.0}[kind]

    def snap(x):
        return np.round(x / unit) * unit if unit else x

    points = [snap(rng.uniform(-3 * gamma, 3 * gamma, dim))]
    while len(points) < n:
        segment = rng.choice(
            ["walk", "line", "stationary", "jump", "revisit", "retrace", "offset_revisit"],
            p=[0.2, 0.15, 0.15, 0.1, 0.15, 0.1, 0.15],
        )
        length = int(rng.integers(1, max(2, n // 4)))
        last = points[-1]
        if segment == "walk":
            scale = gamma * rng.choice([0.1, 0.5, 1.0, 1.5])
            steps = rng.normal(size=(length, dim)) * scale / np.sqrt(dim)
            if unit:
                steps = np.round(steps / unit) * unit
            points.extend(last + np.cumsum(steps, axis=0))
        elif segment == "line":
            # Collinear, evenly spaced: the triangle inequality is tight (up to rounding).
            direction = np.zeros(dim) if unit else rng.normal(size=dim)
            direction[rng.integers(dim)] += 1.0
            direction /= np.linalg.norm(direction)
            step = gamma * rng.choice([0.25, 1 / 3, 0.5, 1.0])
            step = max(unit, snap(step)) if unit else step
            points.extend(last + np.arange(1, length + 1)[:, None] * step * direction)
        elif segment == "stationary":
            points.extend([last.copy() for _ in range(length)])
        elif segment == "jump":
            direction = rng.normal(size=dim)
            direction /= np.linalg.norm(direction) or 1.0
            points.append(snap(last + direction * gamma * rng.uniform(1.01, 6.0)))
        elif segment in ("revisit", "retrace", "offset_revisit"):
            k = int(rng.integers(0, len(points)))
            stretch = np.array(points[k : k + length])
            if segment == "retrace":
                stretch = np.array(points[max(0, len(points) - length) :])[::-1]
            elif rng.random() < 0.5:
                stretch = stretch[::-1]
            if segment == "offset_revisit":
                if unit:
                    options = EXACT_OFFSETS[dim]
                    offset = np.array(options[rng.integers(len(options))], dtype=float)
                    # Scale to length gamma exactly when possible: a tie on every cell.
                    offset = offset / np.linalg.norm(offset) * gamma
                    if not np.array_equal(offset, snap(offset)):
                        offset = snap(offset)  # off the lattice: the nearest lattice vector
                else:
                    offset = rng.normal(size=dim)
                    offset *= gamma * rng.uniform(0.5, 1.5) / (np.linalg.norm(offset) or 1.0)
                stretch = stretch + offset
            points.extend(stretch)
    positions = np.array(points[:n], dtype=float).reshape(n, dim)
    if kind == "real" and rng.random() < 0.3:
        positions += 4.0e6  # far from the origin, as ECEF coordinates: rounding in differences

    # Uneven timestamps: a few regimes of step, some tiny, some huge, on a large clock offset.
    regime = rng.choice([1e-3, 0.1, 1.0, 30.0], size=n - 1)
    dt = regime * rng.uniform(0.2, 1.0, size=n - 1)
    start = rng.choice([0.0, -17.25, 1.3e9])
    timestamps = start + np.concatenate(([0.0], np.cumsum(dt)))
    assert np.all(np.diff(timestamps) > 0)
    return timestamps, positions


@st.composite
def nasty_cases(draw):
    n = draw(st.integers(2, 400) | st.integers(250, 400))
    dim = draw(st.integers(1, 3))
    kind = draw(st.sampled_from(["lattice", "dyadic", "real"]))
    if kind == "lattice":
        gamma = float(draw(st.integers(1, 7)))
    elif kind == "dyadic":
        gamma = draw(st.integers(1, 16)) * 0.25
    else:
        gamma = draw(st.floats(0.01, 20.0, allow_nan=False, allow_infinity=False))
    seed = draw(st.integers(0, 2**32 - 1))
    t, p = build_trajectory(np.random.default_rng(seed), n, dim, kind, gamma)
    return t, p, gamma


def assert_same_loops(a, b) -> None:
    """Bitwise identical results (runs, component table, tau)."""
    for key, value in a.runs().items():
        np.testing.assert_array_equal(value, b.runs()[key], err_msg=key)
    table_a, table_b = a.components, b.components
    assert table_a.keys() == table_b.keys()
    for key in table_a:
        np.testing.assert_array_equal(table_a[key], table_b[key], err_msg=key)
    np.testing.assert_array_equal(a.loop_duration(), b.loop_duration())
    assert a.warnings == b.warnings
    assert a.pair_count == b.pair_count


@settings(
    max_examples=500,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(nasty_cases())
def test_engine_equals_dense_reference(check_dense, case):
    t, p, gamma = case
    traj = il.Trajectory(t, p)
    # Widths from differences of neighbouring timestamps, exact on an epoch clock too.
    steps = np.diff(t)
    np.testing.assert_allclose(
        traj.cell_widths, np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2, rtol=1e-12
    )
    one = il.find_loops(traj, gamma=gamma, threads=1, separation=None)
    two = il.find_loops(traj, gamma=gamma, threads=2, separation=None)
    assert_same_loops(one, two)
    check_dense(one, t, p, gamma)


@pytest.mark.parametrize(
    "name",
    [
        "all_identical",
        "all_steps_beyond_gamma",
        "two_poses_far",
        "two_poses_tie",
        "shuttle_1d",
        "detour_around_gap",
    ],
)
def test_degenerate_cases(check_dense, name):
    n = 60
    t = np.cumsum(np.r_[0.0, np.linspace(0.01, 3.0, n - 1)])
    gamma = 1.0
    if name == "all_identical":
        p = np.zeros((n, 2))
    elif name == "all_steps_beyond_gamma":
        p = np.c_[np.arange(n) * 2.0, np.zeros(n)]
    elif name == "two_poses_far":
        t, p = np.array([0.0, 1.0]), np.array([[0.0], [5.0]])
    elif name == "two_poses_tie":
        t, p = np.array([0.0, 1.0]), np.array([[0.0, 0.0], [3.0, 4.0]])
        gamma = 5.0
    elif name == "shuttle_1d":  # back and forth on a line of integers: ties everywhere
        p = np.abs((np.arange(n) % 20) - 10).astype(float)
        gamma = 2.0
    else:
        # Step 1 -> 2 is longer than gamma, yet (1, 1) and (2, 2) are joined around the missing
        # cell (1, 2) through (0, 2), (0, 3), (1, 3): one trivial component whose full-plane
        # set has one hole, the cells (1, 2) and (2, 1) (diagonal neighbours).
        t, p = np.array([0.0, 1.0, 1.5, 4.0]), np.array([0.0, 0.9, -0.5, 0.2])
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    ref = check_dense(loops, t, p, gamma)
    if name == "all_identical":
        # One trivial component: the whole square.
        assert loops.components["trivial"].tolist() == [True]
        assert loops.pair_count == n * n
    elif name in ("all_steps_beyond_gamma", "two_poses_far"):
        # Only the diagonal cells, each its own trivial component.
        assert loops.components["trivial"].all()
        assert len(loops.components["id"]) == len(t) == ref.count
        assert len(loops.warnings) == 1
    elif name == "two_poses_tie":
        assert loops.pair_count == 4
        assert loops.components["trivial"].tolist() == [True]
    elif name == "detour_around_gap":
        assert loops.components["trivial"].tolist() == [True]
        assert loops.components["holes"].tolist() == [1]
        assert loops.component_of(1, 2) is None
        assert len(loops.warnings) == 1 and "first at index 1" in loops.warnings[0]


@pytest.mark.parametrize("span_s", [1.0, 0.015625])
def test_normalized_measures_do_not_lose_precision_on_a_unix_clock(span_s):
    """BUG: with normalized=True, a and b are fractions of the span, but the library turns them
    into absolute times (t0 + a * span) before integrating, so on a Unix clock (t0 = 1.3e9 s,
    ulp 2.4e-7 s) the result is off by ~ulp(t0) / span: 1.6e-7 relative for a 1 s span, 1.5e-5
    for 1/64 s. Two poses within gamma: tau = span everywhere, normalized tau = 1, so
    alpha(0, 0.3) = 0.3 and rho(0, 0.3) = 1 exactly (both timestamps are exact floats)."""
    t = 1.3e9 + np.array([0.0, span_s])
    loops = il.find_loops(il.Trajectory(t, np.array([[0.0], [0.5]])), gamma=1.0, separation=None)
    assert loops.span_s == span_s
    np.testing.assert_allclose(loops.loop_duration(normalized=True), [1.0, 1.0], rtol=1e-12)
    assert loops.loop_area(0.0, 1.0, normalized=True) == pytest.approx(1.0, rel=1e-12)
    assert loops.loop_area(0.0, 0.3, normalized=True) == pytest.approx(0.3, rel=1e-12)
    assert loops.loop_density(0.0, 0.3, normalized=True) == pytest.approx(1.0, rel=1e-12)
