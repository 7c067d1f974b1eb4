"""Shared fixtures: the dense reference that every engine result is checked against.

The reference is built only from numpy, scipy and scikit-image, never from inexact_loops:
``D = cdist(P, P)``, ``M = D <= gamma``, components from ``scipy.ndimage.label(M)``
(4-connectivity), holes from ``skimage.measure.euler_number(..., connectivity=1)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.distance import cdist
from skimage.measure import euler_number

#: /work/shared/data beside the checkout (absent in a user's clone).
DATA_DIR = Path(__file__).parents[2] / ".." / "shared" / "data"


def cell_widths(timestamps: np.ndarray) -> np.ndarray:
    """w_i = (t_{i+1} - t_{i-1}) / 2, half cells at both ends (seconds), from differences of
    neighbouring timestamps (exact on an epoch clock, where midpoints round)."""
    steps = np.diff(np.asarray(timestamps, dtype=float))
    return np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2


def cell_edges(timestamps: np.ndarray) -> np.ndarray:
    """Cell boundaries on the clock of the first pose (t - t0 is exact)."""
    t = np.asarray(timestamps, dtype=float)
    t = t - t[0]
    return np.concatenate(([t[0]], (t[:-1] + t[1:]) / 2, [t[-1]]))


def _intervals_to_matrix(n: int, row, start, end, value) -> np.ndarray:
    """Dense (n, n) int matrix holding ``value[k]`` on row[k], columns start[k]..=end[k]."""
    diff = np.zeros((n, n + 1), dtype=np.int32)
    np.add.at(diff, (row, start), value)
    np.add.at(diff, (row, end + 1), -value)
    return np.cumsum(diff, axis=1)[:, :n]


class DenseReference:
    """S_gamma, its 4-connected components and their measures, from a dense distance matrix."""

    def __init__(self, timestamps, positions, gamma: float):
        self.t = np.asarray(timestamps, dtype=float)
        self.n = n = len(self.t)
        self.P = np.asarray(positions, dtype=float).reshape(n, -1)
        self.gamma = gamma
        self.w = cell_widths(self.t)
        self.D = cdist(self.P, self.P)
        self.M = self.D <= gamma
        self.labels, self.count = ndimage.label(self.M)  # default structure: 4-connectivity
        self.boxes = ndimage.find_objects(self.labels)
        self.mirror = {}  # scipy label -> label of its mirror image
        upper = np.nonzero(np.triu(self.M))
        pairs = np.unique(np.c_[self.labels[upper], self.labels.T[upper]], axis=0)
        for a, b in pairs:
            self.mirror[int(a)] = int(b)
            self.mirror[int(b)] = int(a)
        self.diagonal_labels = set(np.unique(self.labels[np.arange(n), np.arange(n)]).tolist())

    def tau(self, side: str = "both") -> np.ndarray:
        """tau_i = sum_j w_j M[i, j]; the diagonal cell counts half to begin, half to end."""
        m = self.M.astype(float)
        if side == "both":
            return m @ self.w
        if side == "begin":
            return np.triu(m, 1) @ self.w + self.w / 2
        if side == "end":
            return np.tril(m, -1) @ self.w + self.w / 2
        raise ValueError(side)

    def box(self, label: int):
        return self.boxes[label - 1]

    def component_mask(self, label: int):
        """(box, mask in box) of one scipy label."""
        box = self.box(label)
        return box, self.labels[box] == label

    def component_tau(self, label: int) -> np.ndarray:
        """tau over the full-plane component (the label and its mirror)."""
        tau = np.zeros(self.n)
        box, mask = self.component_mask(label)
        rows, cols = box
        tau[rows] += mask @ self.w[cols]
        if self.mirror[label] != label:
            tau[cols] += mask.T @ self.w[rows]
        return tau


def area_between(timestamps: np.ndarray, tau: np.ndarray, a: float, b: float) -> float:
    """alpha(a, b) = sum_i |cell_i & [a, b]| tau_i (seconds in, s^2 out)."""
    edges = cell_edges(timestamps)
    t0 = float(np.asarray(timestamps, dtype=float)[0])
    a, b = a - t0, b - t0
    overlap = np.clip(np.minimum(edges[1:], b) - np.maximum(edges[:-1], a), 0.0, None)
    return float(overlap @ tau)


def holes_of(mask: np.ndarray) -> int:
    """Holes of a connected 4-connected set: 1 - Euler number (8-connected background)."""
    return 1 - int(euler_number(np.pad(mask, 1), connectivity=1))


def _close(actual, expected, scale: float, what: str) -> None:
    np.testing.assert_allclose(actual, expected, rtol=1e-9, atol=1e-12 * scale, err_msg=what)


def check_against_dense(loops, timestamps, positions, gamma: float) -> DenseReference:
    """Asserts that ``loops`` (``find_loops(..., gamma, separation=None)``) equals the reference."""
    ref = DenseReference(timestamps, positions, gamma)
    n, w, M, D = ref.n, ref.w, ref.M, ref.D
    span = ref.t[-1] - ref.t[0]
    assert len(loops) == n
    assert loops.gamma == gamma
    assert loops.pair_count == int(M.sum()), "pairs of S_gamma in the full plane"

    # --- runs: maximal, disjoint, row by row, covering exactly the upper triangle of M.
    runs = loops.runs()
    row, start, end, comp = (np.asarray(runs[k]) for k in ("row", "start", "end", "component"))
    assert len(row) == len(start) == len(end) == len(comp)
    assert np.all(start >= row) and np.all(end >= start) and np.all(end < n)
    assert np.all(np.diff(row) >= 0), "runs come row by row"
    same_row = row[1:] == row[:-1]
    assert np.all(start[1:][same_row] > end[:-1][same_row] + 1), "runs are sorted and maximal"
    cover = _intervals_to_matrix(n, row, start, end, np.ones_like(row))
    np.testing.assert_array_equal(cover, np.triu(M).astype(np.int32), err_msg="runs != triu(M)")
    ours = _intervals_to_matrix(n, row, start, end, comp + 1) - 1  # -1 outside S

    # --- components: a bijection with scipy's labels, mirrors folded together.
    table = loops.components
    k = len(table["id"])
    np.testing.assert_array_equal(table["id"], np.arange(k))
    upper = np.nonzero(np.triu(M))
    our_ids, their_labels = ours[upper], ref.labels[upper]
    assert np.all(our_ids >= 0)
    assert set(np.unique(our_ids).tolist()) == set(range(k)), "every component has cells"
    pairs = np.unique(np.c_[our_ids, their_labels], axis=0)
    assert len(pairs) == k == len(np.unique(their_labels)), "partitions differ from scipy's"
    folded = set(their_labels.tolist()) | {ref.mirror[int(x)] for x in their_labels}
    assert folded == set(range(1, ref.count + 1)), "every scipy label is ours or a mirror"
    _, first_cell = np.unique(our_ids, return_index=True)
    assert np.all(np.diff(first_cell) > 0), "ids follow the first cell, row by row"
    label_of = dict(pairs.tolist())

    total_area = 0.0
    tau_sum = np.zeros(n)
    for c in range(k):
        label = label_of[c]
        box, mask = ref.component_mask(label)
        rows, cols = box
        trivial = label in ref.diagonal_labels
        assert trivial == (ref.mirror[label] == label)
        what = f"component {c} (scipy label {label})"
        assert bool(table["trivial"][c]) == trivial, what
        upper_in_box = (
            np.arange(rows.start, rows.stop)[:, None] <= np.arange(cols.start, cols.stop)[None, :]
        )
        if not trivial:
            assert np.all(upper_in_box[mask]), f"{what}: the reported half lies above the diagonal"
        assert table["pair_count"][c] == mask.sum(), f"{what}: pairs"
        area = float(w[rows] @ mask @ w[cols])
        _close(table["area_s2"][c], area, span * span, f"{what}: area")
        total_area += area if trivial else 2 * area
        extents = (rows.start, rows.stop - 1, cols.start, cols.stop - 1)
        got = tuple(int(table[key][c]) for key in ("i_min", "i_max", "j_min", "j_max"))
        assert got == extents, f"{what}: index extents"
        t_ext = (ref.t[extents[0]], ref.t[extents[1]], ref.t[extents[2]], ref.t[extents[3]])
        keys = ("t_min_s", "t_max_s", "t_prime_min_s", "t_prime_max_s")
        assert tuple(float(table[key][c]) for key in keys) == t_ext, f"{what}: time extents"
        sub_d = D[box]
        closest = sub_d[mask].min()
        _close(table["closest_distance"][c], closest, 1.0, f"{what}: closest distance")
        ci, cj = int(table["closest_i"][c]), int(table["closest_j"][c])
        assert ci <= cj and ref.labels[ci, cj] == label, f"{what}: closest pair in it"
        _close(D[ci, cj], closest, 1.0, f"{what}: distance at the closest pair")
        # The documented rule: the argmin of the metric's rank (squared distance here, which
        # orders as the distance does up to rounding), earliest in row order on ties.
        diff = ref.P[:, None, :] - ref.P[None, :, :]
        sq = (diff * diff).sum(axis=-1)[box]
        assert sq[ci - rows.start, cj - cols.start] == sq[mask].min(), (
            f"{what}: smallest squared distance"
        )
        tie = mask & (sq == sq[ci - rows.start, cj - cols.start]) & upper_in_box
        ti, tj = np.unravel_index(np.argmax(tie), tie.shape)
        assert (ci, cj) == (rows.start + ti, cols.start + tj), f"{what}: earliest closest pair"
        assert table["holes"][c] == holes_of(mask), f"{what}: holes"
        tau_c = ref.component_tau(label)
        _close(loops.loop_duration(components=[c]), tau_c, span, f"{what}: tau")
        tau_sum += tau_c

    # --- measures.
    tau = ref.tau()
    _close(tau_sum, tau, span, "tau: components sum to the whole")
    got_tau = loops.loop_duration()
    _close(got_tau, tau, span, "tau_i = sum_j w_j M[i, j]")
    _close(loops.loop_duration(components=list(range(k))), tau, span, "all components = all")
    begin, end_ = loops.loop_duration(side="begin"), loops.loop_duration(side="end")
    _close(begin, ref.tau("begin"), span, "tau begin")
    _close(end_, ref.tau("end"), span, "tau end")
    _close(begin + end_, got_tau, span, "begin + end = both")
    _close(loops.loop_duration(normalized=True), got_tau / span, 1.0, "normalized tau")
    dense_area = float(w @ M.astype(float) @ w)
    _close(total_area, dense_area, span * span, "sum of component areas")
    t0, t1 = ref.t[0], ref.t[-1]
    area = loops.loop_area(t0, t1)
    _close(area, dense_area, span * span, "loop_area over the span")
    _close(float(w @ got_tau), dense_area, span * span, "integral of tau")
    _close(loops.loop_density(t0, t1), dense_area / span, span, "loop density over the span")
    _close(loops.loop_area(0.0, 1.0, normalized=True), area / span**2, 1.0, "normalized alpha")
    _close(loops.loop_density(0.0, 1.0, normalized=True), area / span**2, 1.0, "normalized rho")
    for side in ("begin", "end"):
        _close(loops.loop_area(t0, t1, side=side), float(w @ ref.tau(side)), span**2, side)
    # A sub-interval. In seconds, a and b are absolute times and the cell edges (t_i + t_i+1)/2
    # are rounded on the clock (e.g. Unix time): allow a few ulps of t0 per unit of tau. The
    # normalized reference is exact: fractions of the span, measured from t0.
    fa, fb = 0.25, 0.6
    a, b = t0 + fa * span, t0 + fb * span
    clock = 8 * np.spacing(abs(t0) + span) * (float(tau.max()) + span)
    sub_area = area_between(ref.t, tau, a, b)
    np.testing.assert_allclose(loops.loop_area(a, b), sub_area, rtol=1e-9, atol=clock)
    np.testing.assert_allclose(
        loops.loop_density(a, b), sub_area / (b - a), rtol=1e-9, atol=clock / (b - a)
    )
    exact_area = area_between(ref.t - t0, tau, fa * span, fb * span) / span**2
    normalized_area = loops.loop_area(fa, fb, normalized=True)
    np.testing.assert_allclose(normalized_area, exact_area, rtol=1e-9, atol=clock / span**2)
    np.testing.assert_allclose(
        loops.loop_density(fa, fb, normalized=True),
        exact_area / (fb - fa),
        rtol=1e-9,
        atol=clock / span**2 / (fb - fa),
    )
    parts = sum(loops.loop_area(t0, t1, components=[c]) for c in range(k))
    _close(parts, area, span * span, "alpha over components sums to the total")

    # --- point queries, on a deterministic sample of cells (in S and not).
    rng = np.random.default_rng(n)
    cells = list(
        zip(rng.integers(0, n, 100).tolist(), rng.integers(0, n, 100).tolist(), strict=True)
    )
    cells += [(int(i), int(j)) for i, j in zip(upper[0][::97], upper[1][::97], strict=True)]
    for i, j in cells:
        lo, hi = min(i, j), max(i, j)
        expected = int(ours[lo, hi]) if M[i, j] else None
        assert loops.component_of(i, j) == expected, (i, j)
        simple = expected is not None and bool(table["trivial"][expected])
        assert loops.is_simple(i, j) == simple, (i, j)

    # --- a broken diagonal is reported.
    steps = D[np.arange(n - 1), np.arange(1, n)]
    gaps = np.nonzero(steps > gamma)[0]
    if len(gaps):
        assert len(loops.warnings) == 1
        assert f"first at index {gaps[0]}" in loops.warnings[0]
    else:
        assert loops.warnings == []
    return ref


@pytest.fixture(scope="session")
def check_dense():
    """``check_dense(loops, timestamps, positions, gamma)`` -> DenseReference, asserting."""
    return check_against_dense


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The shared real-data folder; skips the test when it is absent."""
    if not DATA_DIR.is_dir():
        pytest.skip(f"real trajectories not found at {DATA_DIR.resolve()} (not in a user's clone)")
    return DATA_DIR


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "gtsam: the test needs GTSAM (the pose-graph back end of inexact_loops.evaluate); "
        "skipped, saying why, where it is not installed",
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skips the tests marked ``gtsam`` where GTSAM is not installed."""
    try:
        import gtsam  # noqa: F401
    except ImportError:  # pragma: no cover - CI installs the [test] extra, which has gtsam
        skip = pytest.mark.skip(
            reason="GTSAM is not installed: pip install '.[maps]' in a checkout to test the "
            "pose-graph back end"
        )
        for item in items:
            if item.get_closest_marker("gtsam") is not None:
                item.add_marker(skip)
