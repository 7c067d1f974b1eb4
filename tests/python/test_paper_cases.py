"""The paper's Fig. 2 kind of trajectories in R^2, with the structure of S_gamma derived from
their geometry (chord lengths on circles), each also checked against the dense reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

import inexact_loops as il


def circle_points(radius: float, angles: np.ndarray) -> np.ndarray:
    return radius * np.c_[np.cos(angles), np.sin(angles)]


def half_width(gamma: float, radius: float, step_rad: float) -> int:
    """Largest k with chord(k * step) <= gamma on a circle: 2 R sin(k step / 2) <= gamma.

    Asserts that gamma is not (nearly) a tie, so the floor is safe from rounding."""
    if gamma >= 2 * radius:
        return 10**9
    k = 2 * math.asin(gamma / (2 * radius)) / step_rad
    assert abs(k - round(k)) > 1e-6, "choose gamma away from a sample tie"
    return math.floor(k)


def component_cells(loops, c: int) -> set[tuple[int, int]]:
    runs = loops.runs()
    cells = set()
    for i, a, b, k in zip(runs["row"], runs["start"], runs["end"], runs["component"], strict=True):
        if k == c:
            cells.update((int(i), j) for j in range(int(a), int(b) + 1))
    return cells


def test_95_percent_circle(check_dense):
    """One non-trivial component besides the trivial band: the pairs that close the gap, a
    triangle at (t, t') = (0, 1)."""
    radius, gamma, n, dt = 10.0, 5.0, 400, 0.1
    sweep = 0.95 * 2 * np.pi
    angles = np.linspace(0.0, sweep, n)
    step = sweep / (n - 1)
    t, p = np.arange(n) * dt, circle_points(radius, angles)
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)

    band = half_width(gamma, radius, step)  # |i - j| <= band along the circle
    # Across the gap the angular distance is theta_i + (2 pi - theta_j) = g + (i + n-1-j) step.
    gap = 2 * np.pi - sweep
    corner = math.floor((2 * math.asin(gamma / (2 * radius)) - gap) / step)
    assert 0 < corner < band < n // 4

    table = loops.components
    assert table["trivial"].tolist() == [True, False]
    assert loops.warnings == []
    # The trivial component is exactly the band around the diagonal.
    assert table["pair_count"][0] == n + 2 * sum(n - k for k in range(1, band + 1))
    # The non-trivial one is the triangle i + (n-1-j) <= corner, located at (0, 1).
    expected = {(i, j) for i in range(corner + 1) for j in range(n - 1 - corner + i, n)}
    assert component_cells(loops, 1) == expected
    assert table["pair_count"][1] == (corner + 1) * (corner + 2) // 2
    assert (table["i_min"][1], table["i_max"][1]) == (0, corner)
    assert (table["j_min"][1], table["j_max"][1]) == (n - 1 - corner, n - 1)
    span = t[-1]
    assert table["t_max_s"][1] / span < 0.05 and table["t_prime_min_s"][1] / span > 0.95
    assert (table["closest_i"][1], table["closest_j"][1]) == (0, n - 1)
    assert table["closest_distance"][1] == pytest.approx(2 * radius * math.sin(gap / 2))
    assert table["holes"].tolist() == [0, 0]
    # Continuous area of the corner triangle: legs (theta_gamma - g) / omega seconds.
    leg_s = (2 * math.asin(gamma / (2 * radius)) - gap) / (step / dt)
    assert table["area_s2"][1] == pytest.approx(leg_s**2 / 2, rel=0.25)
    # Mid-trajectory the loop duration is the band: (2 band + 1) samples.
    tau = loops.loop_duration()
    np.testing.assert_allclose(tau[band + corner + 1 : n - band - corner - 1], (2 * band + 1) * dt)
    assert loops.is_simple(0, band) and not loops.is_simple(0, n - 1)
    assert loops.component_of(n - 1, 0) == loops.component_of(0, n - 1) == 1


@pytest.mark.parametrize("gamma", [1.0, 1.5, 1.9, 2.3, 3.0])
def test_double_loop_merges_as_gamma_grows(check_dense, gamma):
    """A circle of radius 1.05 driven twice. Below the diameter (2.1) S_gamma is three bands:
    the diagonal, the pairs one lap apart (a non-trivial band) and the corner where the end
    meets the start two laps later. Above it every pair is within gamma: one trivial component."""
    radius, per_lap = 1.05, 180
    n = 2 * per_lap + 1
    step = 2 * np.pi / per_lap
    t = np.arange(n) * 1.0
    p = circle_points(radius, np.arange(n) * step)
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)
    table = loops.components

    if gamma < 2 * radius:
        k = half_width(gamma, radius, step)
        assert k < per_lap // 2  # the three bands do not touch
        assert table["trivial"].tolist() == [True, False, False]
        lap = loops.component_of(0, per_lap)
        end = loops.component_of(0, n - 1)
        assert {lap, end} == {1, 2}
        # One band: every pair one lap apart, shifted by up to k samples.
        shifted = {
            loops.component_of(i, i + per_lap + s) for i in range(per_lap - k) for s in (-k, 0, k)
        }
        assert shifted == {lap}
        assert loops.component_of(0, per_lap + k + 1) is None
        assert loops.component_of(0, per_lap - k - 1) is None
        assert (table["i_min"][lap], table["i_max"][lap]) == (0, per_lap + k)
        assert (table["j_min"][lap], table["j_max"][lap]) == (per_lap - k, n - 1)
        # Corner: j - i >= 2 laps - k.
        assert table["pair_count"][end] == (k + 1) * (k + 2) // 2
        assert table["holes"].tolist() == [0, 0, 0]
    else:
        # All within gamma: the whole square, one trivial component.
        assert table["trivial"].tolist() == [True]
        assert loops.pair_count == n * n == table["pair_count"][0]
        assert table["area_s2"][0] == pytest.approx(t[-1] ** 2)
        assert loops.is_simple(0, per_lap) and loops.is_simple(0, n - 1)


def test_double_loop_components_only_merge():
    """Non-trivial components never appear as gamma grows on the double loop; they merge."""
    radius, per_lap = 1.05, 180
    n = 2 * per_lap + 1
    p = circle_points(radius, np.arange(n) * 2 * np.pi / per_lap)
    traj = il.Trajectory(np.arange(n) * 1.0, p)
    counts = []
    for gamma in np.linspace(1.0, 3.0, 21):
        table = il.find_loops(traj, gamma=float(gamma), separation=None).components
        counts.append(int((~table["trivial"]).sum()))
    assert counts[0] == 2 and counts[-1] == 0
    assert all(a >= b for a, b in zip(counts[:-1], counts[1:], strict=True)), counts


def spiral(r0: float, pitch: float, turns: float, ds: float) -> np.ndarray:
    """Archimedean spiral r = r0 + pitch theta / 2 pi, resampled every ds metres of arc."""
    theta = np.linspace(0.0, 2 * np.pi * turns, 200_000)
    r = r0 + pitch * theta / (2 * np.pi)
    xy = np.c_[r * np.cos(theta), r * np.sin(theta)]
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))]
    s = np.arange(0.0, arc[-1], ds)
    return np.c_[np.interp(s, arc, xy[:, 0]), np.interp(s, arc, xy[:, 1])]


@pytest.mark.parametrize("gamma", [1.0, 3.0])
def test_outward_spiral_loops_are_all_simple(check_dense, gamma):
    """Turns 5 m apart (pitch 5 m, curvature radius >= 10 m): below ~4.9 m every pair within
    gamma is a short stretch of the same turn, so S_gamma is one band around the diagonal."""
    p = spiral(r0=10.0, pitch=5.0, turns=3.0, ds=0.4)
    n = len(p)
    t = np.arange(n) * 0.1
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)
    table = loops.components
    assert table["trivial"].tolist() == [True]
    assert table["holes"].tolist() == [0]
    assert loops.warnings == []
    runs = loops.runs()
    assert np.all(runs["start"] == runs["row"]), "every run starts on the diagonal: one band"
    # Chord of the arc: pairs within gamma are at most ~gamma / ds samples apart (a bit more,
    # as the chord is shorter than the arc).
    assert np.all(runs["end"] - runs["row"] <= math.ceil(1.01 * gamma / 0.4))
    assert loops.is_simple(0, 1) and loops.is_simple(n - 2, n - 1)


def test_outward_spiral_above_the_pitch_has_one_lap_component(check_dense):
    """Above the pitch (5 m) the pairs one turn apart form one non-trivial band."""
    p = spiral(r0=10.0, pitch=5.0, turns=3.0, ds=0.4)
    n = len(p)
    t = np.arange(n) * 0.1
    gamma = 6.0
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)
    table = loops.components
    assert table["trivial"].tolist() == [True, False]
    angle = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
    # The sample one turn later at the same angle is 5 m out: always in component 1.
    for i in range(0, n, 25):
        later = np.searchsorted(angle, angle[i] + 2 * np.pi)
        if later < n:
            assert loops.component_of(i, int(later)) == 1, i
    assert table["holes"].tolist() == [0, 0]


def test_shuttle_trivial_component_has_holes(check_dense):
    """Out along a corridor, back on the other lane (0.5 m over), out again. The U-turns join
    the pairs (leg 1, leg 2) and (leg 2, leg 3) to the diagonal, and (leg 1, leg 3) joins
    their far ends: a closed ring around the pairs (B at t_1, A at t_2). So the trivial
    component has one hole in each half plane, two in all."""
    ds, length, lane = 0.25, 20.0, 0.5
    x = np.arange(0.0, length + ds / 2, ds)
    leg1 = np.c_[x, np.zeros_like(x)]
    leg2 = np.c_[x[::-1], np.full_like(x, lane)]
    p = np.r_[leg1, leg2, leg1]
    n = len(p)
    t = np.cumsum(np.r_[0.0, np.where(np.arange(n - 1) % 7 == 0, 0.3, 0.1)])  # uneven clock
    gamma = 1.0
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)
    table = loops.components
    assert table["trivial"].tolist() == [True]
    assert table["holes"].tolist() == [2]
    m = len(x)
    # The ring: (B, B'), (A', A''), (B, B'') are all in it; its middle (B at leg 1, A at leg 3)
    # is the hole's inside.
    assert loops.component_of(m - 1, m) == 0
    assert loops.component_of(2 * m - 1, 2 * m) == 0
    assert loops.component_of(0, 2 * m) == 0
    assert loops.component_of(m - 1, 3 * m - 1) == 0
    assert loops.component_of(m - 1, 2 * m) is None


def test_lollipop_stick_is_a_non_trivial_component(check_dense):
    """Out along a stick, once around a circle of radius 10 >> gamma, back along the stick.
    The stick pairs (out, back) form an anti-diagonal band from (0, T) to (t_1, t_2) (the
    circle's start and end, both at its foot). Neither end touches the diagonal, so it is a
    non-trivial component and the trivial band has no hole."""
    ds, stick, radius, gamma = 0.5, 20.0, 10.0, 1.0
    out = np.c_[np.arange(0.0, stick, ds), np.zeros(int(stick / ds))]
    theta = np.arange(0.0, 2 * np.pi, ds / radius)
    around = np.c_[stick + radius * np.sin(theta), radius - radius * np.cos(theta)]
    p = np.r_[out, around, out[::-1]]
    n = len(p)
    t = np.arange(n) * 0.5
    loops = il.find_loops(il.Trajectory(t, p), gamma=gamma, separation=None)
    check_dense(loops, t, p, gamma)
    table = loops.components
    assert table["trivial"].tolist() == [True, False]
    assert table["holes"].tolist() == [0, 0]
    m, c = len(out), len(around)
    assert {loops.component_of(k, n - 1 - k) for k in range(m)} == {1}
    assert loops.component_of(m, m + c) == 1  # the circle's foot, passed twice
    assert loops.component_of(m + c // 2, m + c) is None  # far side of the circle
