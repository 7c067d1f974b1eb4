"""Fleets against independent references: every block between two sessions is the 4-connected
labelling (``scipy.ndimage.label``, default structure) of its dense cross mask
``cdist(A, B) <= gamma`` (same partition of cells, pair counts, areas sum w_i w_j, closest
distances and pairs, extents, holes from scikit-image's Euler number), and every block within
a session is :func:`find_loops` of that session alone; on random fleets, adversarial ones (two
identical sessions, a time-reversed session, parked sessions, a session far from all others)
and MulRan KAIST 01 and 02 (both localized in the map of sequence 02: one frame).

Then the measures (the overlap matrix and the split loop duration against the areas and
against scipy's KD-tree pair counts), sampling across the fleet (between sessions only, P1,
seeds), the synthetic fleet, the plots, the warnings and the errors.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist
from skimage.measure import euler_number

import inexact_loops as il

PRUNINGS = ("hierarchy", "kd-tree")
quiet = pytest.mark.filterwarnings("ignore::inexact_loops.errors.LoopsWarning")


def cell_widths(timestamps: np.ndarray) -> np.ndarray:
    """w_i = (t_{i+1} - t_{i-1}) / 2, half cells at both ends (seconds)."""
    steps = np.diff(np.asarray(timestamps, dtype=float))
    return np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2


def holes_of(mask: np.ndarray) -> int:
    """Holes of a connected 4-connected set: 1 - Euler number (8-connected background)."""
    return 1 - int(euler_number(np.pad(mask, 1), connectivity=1))


def rows_of(table: il.Table, keep: np.ndarray) -> dict[str, list]:
    return {name: column[keep].tolist() for name, column in table.items()}


# --- the references -------------------------------------------------------------------------------


def check_between(loops: il.FleetLoops, a: int, b: int, *, holes: bool = True) -> int:
    """Asserts that block (a, b), a < b, is the labelling of its dense cross mask; returns its
    number of components."""
    fleet = loops.fleet
    sa, sb = fleet.session(a), fleet.session(b)
    pa, pb = sa.positions, sb.positions
    D = cdist(pa, pb)
    M = D <= loops.gamma
    labels, count = ndimage.label(M)  # default structure: 4-connectivity
    n, m = M.shape
    start_a, start_b = fleet.starts[a], fleet.starts[b]
    rows_i, cols_j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    ids = loops.loops.components_of_pairs(start_a + rows_i.ravel(), start_b + cols_j.ravel())
    ids = ids.reshape(n, m)
    what = f"block ({a}, {b}) at gamma {loops.gamma}"
    np.testing.assert_array_equal(ids >= 0, M, err_msg=f"{what}: cells of S_gamma")
    table = loops.components
    in_block = (table["session_a"] == a) & (table["session_b"] == b)
    block_ids = table["id"][in_block]
    pairs = np.unique(np.c_[labels[M], ids[M]], axis=0)
    assert len(pairs) == count == len(block_ids), f"{what}: partitions differ from scipy's"
    assert set(pairs[:, 1].tolist()) == set(block_ids.tolist()), what
    w = np.outer(cell_widths(sa.timestamps), cell_widths(sb.timestamps))
    for label, c in pairs:
        cells = labels == label
        ((rows, cols),) = ndimage.find_objects(cells.astype(int))
        row = {name: column[c] for name, column in table.items()}
        assert row["id"] == c and not row["trivial"], what
        assert (row["name_a"], row["name_b"]) == (fleet.names[a], fleet.names[b])
        assert row["pair_count"] == cells.sum(), f"{what}: component {c} pairs"
        area = float(w[cells].sum())
        np.testing.assert_allclose(row["area_s2"], area, rtol=1e-12, err_msg=f"{what}: area")
        extents = (rows.start, rows.stop - 1, cols.start, cols.stop - 1)
        assert tuple(row[k] for k in ("i_min", "i_max", "j_min", "j_max")) == extents, what
        times = (
            sa.timestamps[[rows.start, rows.stop - 1]],
            sb.timestamps[[cols.start, cols.stop - 1]],
        )
        assert (row["t_min_s"], row["t_max_s"]) == tuple(times[0]), f"{what}: session a's clock"
        assert (row["t_prime_min_s"], row["t_prime_max_s"]) == tuple(times[1]), what
        closest = D[cells].min()
        np.testing.assert_allclose(row["closest_distance"], closest, rtol=1e-12, atol=1e-12)
        ci, cj = row["closest_i"], row["closest_j"]
        assert labels[ci, cj] == label, f"{what}: the closest pair lies in its component"
        np.testing.assert_allclose(D[ci, cj], closest, rtol=1e-12, atol=1e-12)
        if holes:
            assert row["holes"] == holes_of(cells[rows, cols]), f"{what}: holes"
    return count


def check_within(loops: il.FleetLoops, a: int, separation: object) -> None:
    """Asserts that block (a, a) is find_loops of session a alone, component for component."""
    fleet = loops.fleet
    alone = il.find_loops(fleet.session(a), gamma=loops.gamma, separation=separation).components
    table = loops.components
    own = (table["session_a"] == a) & (table["session_b"] == a)
    assert own.sum() == len(alone["id"]), f"session {a}: components"
    for key in (
        "trivial",
        "area_s2",
        "pair_count",
        "holes",
        "i_min",
        "i_max",
        "j_min",
        "j_max",
        "t_min_s",
        "t_max_s",
        "t_prime_min_s",
        "t_prime_max_s",
        "closest_i",
        "closest_j",
        "closest_distance",
    ):
        np.testing.assert_array_equal(table[key][own], alone[key], err_msg=f"session {a}: {key}")


def check_fleet(sessions: dict[str, il.Trajectory], gamma: float, separation: object) -> None:
    fleet = il.Fleet(sessions)
    results = []
    for pruning in PRUNINGS:
        loops = il.find_fleet_loops(fleet, gamma=gamma, separation=separation, pruning=pruning)
        assert loops.pruning == pruning
        for a in range(len(fleet)):
            check_within(loops, a, separation)
            for b in range(a + 1, len(fleet)):
                check_between(loops, a, b)
        check_measures(loops)
        results.append(loops)
    first, second = (r.components for r in results)
    for key in first:
        np.testing.assert_array_equal(first[key], second[key], err_msg=f"prunings differ: {key}")


def check_measures(loops: il.FleetLoops) -> None:
    """Sums: components to session pairs, session pairs to the overlap matrix, the split
    loop duration to the areas (each against the others, from the tables alone)."""
    fleet = loops.fleet
    table, pairs = loops.components, loops.session_pairs()
    n = len(fleet)
    alpha = np.zeros((n, n))
    cells = np.zeros((n, n), dtype=np.int64)
    for a, b, trivial, area, count in zip(
        table["session_a"],
        table["session_b"],
        table["trivial"],
        table["area_s2"],
        table["pair_count"],
        strict=True,
    ):
        mirrored = 2 if (a == b and not trivial) else 1
        alpha[a, b] += mirrored * area
        cells[a, b] += mirrored * count
    for a, b, k, count, area, density in zip(
        pairs["session_a"],
        pairs["session_b"],
        pairs["components"],
        pairs["pair_count"],
        pairs["area_s2"],
        pairs["density"],
        strict=True,
    ):
        in_block = (table["session_a"] == a) & (table["session_b"] == b)
        assert k == in_block.sum() and count == cells[a, b]
        np.testing.assert_allclose(area, alpha[a, b], rtol=1e-12)
        spans = fleet.session(a).span_s * fleet.session(b).span_s
        np.testing.assert_allclose(density, area / spans, rtol=1e-12)
    assert len(pairs["session_a"]) == int((alpha > 0).sum() + (cells[alpha == 0] > 0).sum())
    dense = loops.overlap_matrix()
    np.testing.assert_allclose(dense, np.triu(alpha) + np.triu(alpha, 1).T, rtol=1e-12)
    sparse = loops.overlap_matrix(sparse=True)
    np.testing.assert_array_equal(sparse.toarray(), dense)
    tau = loops.loop_duration()
    w = np.concatenate([cell_widths(fleet.session(a).timestamps) for a in range(n)])
    for a in range(n):
        mine = tau["session"] == a
        assert np.array_equal(tau["pose"][mine], np.arange(len(fleet.session(a))))
        assert np.array_equal(tau["t_s"][mine], fleet.session(a).timestamps)
        np.testing.assert_allclose(tau["own_s"][mine] @ w[mine], alpha[a, a], rtol=1e-9, atol=1e-9)
        one = loops.loop_duration(fleet.names[a])
        for key in tau:
            np.testing.assert_array_equal(one[key], tau[key][mine])
    between = float(np.triu(alpha, 1).sum())
    np.testing.assert_allclose(tau["other_s"] @ w, 2 * between, rtol=1e-9, atol=1e-9)


# --- random and adversarial fleets ---------------------------------------------------------------


def random_session(rng: np.random.Generator, dim: int, t0: float) -> il.Trajectory:
    """A walk of 20-90 poses in a few-metre box, uneven time steps, with parked stretches and
    the odd jump (a data gap) so that some diagonals break."""
    n = int(rng.integers(20, 90))
    steps = rng.normal(scale=rng.uniform(0.1, 0.8), size=(n, dim))
    steps[rng.random(n) < 0.15] = 0.0  # parked
    steps[rng.random(n) < 0.03] *= 8.0  # a jump
    points = rng.uniform(-2, 2, size=dim) + np.cumsum(steps, axis=0)
    times = t0 + np.cumsum(rng.uniform(0.05, 2.0, size=n))
    return il.Trajectory(times, points)


@quiet
@pytest.mark.parametrize("seed", range(24))
def test_random_fleets_equal_scipy_labelling_per_session_pair(seed):
    rng = np.random.default_rng(seed)
    dim = 1 + seed % 3
    sessions = {
        f"s{k}": random_session(rng, dim, float(rng.uniform(-1e3, 1e3)))
        for k in range(int(rng.integers(2, 6)))
    }
    gamma = float(rng.uniform(0.3, 1.5))
    separation = [None, "auto", 2 * gamma][seed % 3]
    check_fleet(sessions, gamma, separation)


def tour(n: int, t0: float, offset=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """A figure-eight-ish tour, 1.5 times round: times and points."""
    s = np.arange(n) / n * 2 * np.pi * 1.5
    points = np.c_[offset[0] + 10 * np.cos(s), offset[1] + 6 * np.sin(2 * s)]
    return t0 + 0.5 * np.arange(n), points


@quiet
@pytest.mark.parametrize("gamma", [0.5, 1.5, 4.0])
@pytest.mark.parametrize("separation", [None, "auto"])
def test_adversarial_fleets_equal_scipy_labelling(gamma, separation):
    t, points = tour(120, 0.0)
    sessions = {
        "tour": il.Trajectory(t, points),
        "twin": il.Trajectory(t, points),  # the same session twice
        "reversed": il.Trajectory(1e9 + np.arange(120.0), points[::-1]),  # backwards in time
        "parked": il.Trajectory(np.arange(80) * 0.1, np.tile([10.0, 0.0], (80, 1))),
        "parked-far": il.Trajectory(np.arange(50.0), np.tile([1e4, 1e4], (50, 1))),
        "far": il.Trajectory(*tour(90, 7.0, (5e3, -5e3))),
    }
    check_fleet(sessions, gamma, separation)


@quiet
def test_identical_and_reversed_sessions_overlap_as_the_session_with_itself():
    """Two identical sessions: their block is the session's whole square (the cells of the
    mirror of its S_gamma); the time-reversed session's block is that square flipped."""
    t, points = tour(150, 0.0)
    fleet = il.Fleet(
        [
            ("a", il.Trajectory(t, points)),
            ("b", il.Trajectory(t, points)),
            ("r", il.Trajectory(t, points[::-1])),
        ]
    )
    loops = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
    alone = il.find_loops(fleet.session("a"), gamma=1.0, separation=None)
    pairs = loops.session_pairs()
    by_pair = {
        (a, b): k
        for k, (a, b) in enumerate(zip(pairs["session_a"], pairs["session_b"], strict=True))
    }
    for block in ((0, 1), (0, 2), (1, 2)):
        k = by_pair[block]
        assert pairs["pair_count"][k] == alone.pair_count, block
    np.testing.assert_allclose(pairs["area_s2"][by_pair[(0, 1)]], pairs["area_s2"][by_pair[(0, 0)]])
    assert pairs["pair_count"][by_pair[(0, 0)]] == alone.pair_count


# --- MulRan KAIST 01 and 02 ----------------------------------------------------------------------

MULRAN = {
    "kaist01": Path("mulran_kaist") / "kaist01_localization_poses01_seq02asmap.txt",
    "kaist02": Path("mulran_kaist") / "kaist02_localization_poses02_seq02asmap.txt",
}
MULRAN_GAMMA = 10.0


@pytest.fixture(scope="module")
def mulran(data_dir) -> il.Fleet:
    paths = [data_dir / path for path in MULRAN.values()]
    for path in paths:
        if not path.is_file():
            pytest.skip(f"MulRan KAIST not found at {path.resolve()}")
    fleet = il.Fleet(paths, format="kitti", rate_hz=10.0)  # no timestamps: 10 Hz lidar
    assert fleet.names == [path.stem for path in paths], "each path a session named by its stem"
    return il.Fleet(dict(zip(MULRAN, (fleet.session(0), fleet.session(1)), strict=True)))


@pytest.fixture(scope="module")
def mulran_loops(mulran) -> il.FleetLoops:
    return il.find_fleet_loops(mulran, gamma=MULRAN_GAMMA)


@quiet
def test_mulran_subsampled_equals_scipy_labelling(mulran):
    """Every 20th pose of both drives (a 2 s step): every block against the references."""
    sessions = {}
    for name in mulran.names:
        session = mulran.session(name)
        sessions[name] = il.Trajectory(session.timestamps[::20], session.positions[::20])
    for gamma in (10.0, 25.0):
        fleet = il.Fleet(sessions)
        loops = il.find_fleet_loops(fleet, gamma=gamma, separation=None)
        for a in range(2):
            check_within(loops, a, None)
        assert check_between(loops, 0, 1) > 0, "the two drives share the campus"
        check_measures(loops)


def test_mulran_full_size_blocks_and_measures(mulran, mulran_loops):
    """The full drives (8226 and 8941 poses): intra blocks equal find_loops; the block between
    them has the cells, area and partition of scipy's KD-tree pairs (joined 4-adjacently by
    scipy's connected components); the sums of the areas equal the integrals of tau."""
    loops = mulran_loops
    assert loops.pruning == "kd-tree" and loops.separation == il.Separation.for_gamma(10.0)
    for a in range(2):
        check_within(loops, a, "auto")
    check_measures(loops)
    a, b = mulran.session(0), mulran.session(1)
    pa, pb = a.positions, b.positions
    wa, wb = cell_widths(a.timestamps), cell_widths(b.timestamps)
    ta, tb = cKDTree(pa), cKDTree(pb)
    pairs = loops.session_pairs()
    k = int(np.flatnonzero((pairs["session_a"] == 0) & (pairs["session_b"] == 1))[0])
    count = ta.count_neighbors(tb, MULRAN_GAMMA)
    area = ta.count_neighbors(tb, MULRAN_GAMMA, weights=(wa, wb))
    assert pairs["pair_count"][k] == count
    np.testing.assert_allclose(pairs["area_s2"][k], area, rtol=1e-9)

    # The partition of the block, from scipy alone: cells within gamma, 4-adjacent cells joined.
    cells = ta.sparse_distance_matrix(tb, MULRAN_GAMMA, output_type="ndarray")
    i, j = cells["i"].astype(np.int64), cells["j"].astype(np.int64)
    m = len(b)
    key = i * m + j
    order = np.argsort(key)
    key, i, j = key[order], i[order], j[order]
    edges = []
    for di, dj in ((0, 1), (1, 0)):
        neighbour = (i + di) * m + (j + dj)
        at = np.minimum(np.searchsorted(key, neighbour), len(key) - 1)
        found = (key[at] == neighbour) & (j + dj < m)
        edges.append(np.c_[np.flatnonzero(found), at[found]])
    edges = np.concatenate(edges)
    from scipy.sparse import coo_array

    graph = coo_array((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(key),) * 2)
    count, labels = connected_components(graph, directed=False)
    ours = loops.loops.components_of_pairs(i, mulran.starts[1] + j)
    assert (ours >= 0).all()
    joined = np.unique(np.c_[labels, ours], axis=0)
    assert len(joined) == count == len(np.unique(ours)) == int(pairs["components"][k])
    assert count > 1, "several places where the two drives overlap"


def test_mulran_sampling_between_the_drives(mulran, mulran_loops):
    samples = il.sample_fleet(mulran_loops, "rho", budget=500, seed=3, between_only=True)
    rows = samples.table
    assert len(samples) == 500
    assert set(rows["name_a"].tolist()) == {"kaist01"} and set(rows["name_b"].tolist()) == {
        "kaist02"
    }
    assert set(rows["component"].tolist()) == set(mulran_loops.between_sessions().tolist())
    gap = mulran.session(0).positions[rows["i"]] - mulran.session(1).positions[rows["j"]]
    assert (np.linalg.norm(gap, axis=1) <= MULRAN_GAMMA).all()


# --- sampling ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def city() -> il.Fleet:
    return il.urban_fleet(vehicles=4, days=2, duration_s=300.0, seed=11)


@pytest.fixture(scope="module")
def city_loops(city) -> il.FleetLoops:
    return il.find_fleet_loops(city, gamma=20.0)


@pytest.mark.parametrize("sampler", ["one", "rho", "rho-dispersed", "alpha"])
def test_samples_between_sessions_name_both_and_cover_every_overlap(city, city_loops, sampler):
    between = city_loops.between_sessions()
    assert len(between) > 10
    samples = il.sample_fleet(city_loops, sampler, budget=600, seed=5, between_only=True)
    rows = samples.table
    assert len(samples) == 600 == len(rows["i"]) and samples.sampler == sampler
    assert (rows["session_a"] < rows["session_b"]).all(), "only between sessions"
    names = np.array(city.names)
    assert (rows["name_a"] == names[rows["session_a"]]).all()
    assert (rows["name_b"] == names[rows["session_b"]]).all()
    table = city_loops.components
    assert set(rows["component"].tolist()) <= set(between.tolist())
    assert (table["session_a"][rows["component"]] == rows["session_a"]).all()
    for k in range(len(samples)):
        a, b = city.session(int(rows["session_a"][k])), city.session(int(rows["session_b"][k]))
        i, j = int(rows["i"][k]), int(rows["j"][k])
        assert (a.timestamps[i], b.timestamps[j]) == (rows["t_s"][k], rows["t_prime_s"][k])
        gap = float(np.linalg.norm(a.positions[i] - b.positions[j]))
        np.testing.assert_allclose(rows["distance"][k], gap, rtol=1e-12)
        assert gap <= 20.0
    if sampler != "alpha":
        assert set(rows["component"].tolist()) == set(between.tolist()), "P1 between sessions"
        assert samples.groups == len(between)
    # The joint samples index the joint trajectory.
    joint = samples.samples
    np.testing.assert_array_equal(joint.i, city.starts[rows["session_a"]] + rows["i"])
    np.testing.assert_array_equal(joint.j, city.starts[rows["session_b"]] + rows["j"])
    quality = il.sample_quality(joint, city_loops.loops)
    assert quality.components == len(table["id"])
    # Seeded: the same seed, the same samples; another seed, others.
    again = il.sample_fleet(city_loops, sampler, budget=600, seed=5, between_only=True).table
    other = il.sample_fleet(city_loops, sampler, budget=600, seed=6, between_only=True).table
    for key in rows:
        np.testing.assert_array_equal(again[key], rows[key])
    assert not all(np.array_equal(other[key], rows[key]) for key in ("i", "j"))


def test_samples_over_the_whole_fleet_and_baselines(city, city_loops):
    everything = il.sample_fleet(city_loops, "one", budget=2000, seed=1)
    rows = everything.table
    assert set(rows["component"].tolist()) == set(city_loops.components["id"].tolist()), "P1"
    assert (rows["session_a"] == rows["session_b"]).any() and (
        rows["session_a"] != rows["session_b"]
    ).any()
    assert everything.fleet is city_loops.fleet
    with pytest.raises(il.InvalidParameterError, match="lio-sam"):
        il.sample_fleet(city_loops, "lio-sam", budget=10, seed=0, between_only=True)
    baseline = il.sample_fleet(city_loops, "time-gap", budget=50, seed=0, time_gap_s=30.0)
    assert len(baseline) == 50 and (baseline.table["t_prime_s"] >= 0).all()
    frame = everything.to_pandas()
    assert list(frame.columns) == list(rows) and len(frame) == len(everything)
    assert "FleetSamples(2000 samples" in repr(everything)
    assert everything.available > 0 and everything.warnings == []


# --- the fleet object ---------------------------------------------------------------------------


def test_fleet_from_trajectories_pairs_and_paths(tmp_path):
    a = il.Trajectory([0.0, 1.0, 2.0], [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    b = il.Trajectory([5.0, 6.0], [[2.0, 0.5], [0.0, 0.5]])
    by_dict = il.Fleet({"a": a, "b": b})
    by_pairs = il.Fleet([("a", a), ("b", b)])
    for fleet in (by_dict, by_pairs):
        assert fleet.names == ["a", "b"] and len(fleet) == 2 and fleet.poses == 5
        assert fleet.starts.tolist() == [0, 3]
        assert [fleet.locate(k) for k in range(5)] == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1)]
        assert [fleet.index("b", 1), fleet.index(0, 2)] == [4, 2]
        np.testing.assert_array_equal(fleet.session("b").positions, b.positions)
        np.testing.assert_array_equal(fleet.session(1).timestamps, b.timestamps)
    joint = by_dict.joint
    np.testing.assert_array_equal(joint.positions, np.r_[a.positions, b.positions])
    offsets = by_dict.clock_offsets
    np.testing.assert_array_equal(
        joint.timestamps, np.r_[a.timestamps + offsets[0], b.timestamps + offsets[1]]
    )
    assert joint.timestamps[3] - joint.timestamps[2] == 3600.0, "an hour between sessions"
    assert "Fleet(2 sessions" in repr(by_dict)

    # Paths: one session each, named by the file stem, read as read_trajectory reads them.
    for name, traj in (("monday", a), ("tuesday", b)):
        lines = [
            f"{t} {x} {y} 0 0 0 0 1"
            for t, (x, y) in zip(traj.timestamps, traj.positions, strict=True)
        ]
        (tmp_path / f"{name}.tum").write_text("\n".join(lines) + "\n")
    paths = [tmp_path / "monday.tum", str(tmp_path / "tuesday.tum")]
    fleet = il.Fleet(paths, axes=(0, 1))
    assert fleet.names == ["monday", "tuesday"]
    np.testing.assert_array_equal(fleet.session("tuesday").positions, b.positions)
    assert fleet.session(0).plane_axes == (0, 1)
    mixed = il.Fleet([("first", a), tmp_path / "tuesday.tum"], axes=(0, 1))
    assert mixed.names == ["first", "tuesday"]
    poses = il.Fleet({"m": tmp_path / "monday.tum"}, metric="se3(rotation_weight_m_per_rad=1)")
    assert poses.session("m").manifold == "se3"
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "monday.tum").write_text((tmp_path / "monday.tum").read_text())
    with pytest.raises(il.InvalidParameterError, match="both named 'monday'|both named \"monday\""):
        il.Fleet([tmp_path / "monday.tum", tmp_path / "other" / "monday.tum"])


def test_fleet_errors(tmp_path):
    a = il.Trajectory([0.0, 1.0], [[0.0, 0.0], [1.0, 0.0]])
    flat = il.Trajectory([0.0, 1.0], [0.0, 1.0])
    with pytest.raises(il.InvalidParameterError, match="session"):
        il.Fleet({})
    with pytest.raises(il.InvalidParameterError, match='"a"'):
        il.Fleet([("a", a), ("a", a)])
    with pytest.raises(il.InvalidParameterError, match='session "b" has 1 coordinates'):
        il.Fleet({"a": a, "b": flat})
    with pytest.raises(TypeError, match="got str"):
        il.Fleet("drive.tum")
    with pytest.raises(TypeError, match=r"sessions\[0\].*Trajectory without a name"):
        il.Fleet([a])
    with pytest.raises(TypeError, match="session names must be str"):
        il.Fleet({1: a})
    with pytest.raises(FileNotFoundError, match="missing.tum"):
        il.Fleet([tmp_path / "missing.tum"])
    fleet = il.Fleet({"a": a, "b": a})
    with pytest.raises(KeyError, match="'c'|\"c\""):
        fleet.session("c")
    with pytest.raises(IndexError, match="session 2"):
        fleet.session(2)
    with pytest.raises(IndexError, match="-1"):
        fleet.locate(-1)
    with pytest.raises(IndexError, match="4"):
        fleet.locate(4)
    with pytest.raises(IndexError):
        fleet.index("a", 2)
    with pytest.raises(TypeError, match="float"):
        fleet.session(1.0)


@quiet
def test_find_fleet_loops_options_and_errors():
    t, points = tour(100, 0.0)
    fleet = il.Fleet({"a": il.Trajectory(t, points), "b": il.Trajectory(t + 10, points + 0.3)})
    auto = il.find_fleet_loops(fleet, gamma=1.0)
    assert auto.separation == il.Separation.for_gamma(1.0) and auto.pruning == "kd-tree"
    assert auto.gamma == 1.0 and auto.metric_name == "euclidean" and auto.names == ["a", "b"]
    assert "FleetLoops(gamma=1" in repr(auto) and auto.warnings == []
    chunks = il.find_fleet_loops(fleet, gamma=1.0, chunk_radius=0.3)
    for key in auto.components:
        np.testing.assert_array_equal(chunks.components[key], auto.components[key])
    called = il.find_fleet_loops(
        fleet, gamma=1.0, metric=lambda p, q: float(np.linalg.norm(p - q)), pruning="hierarchy"
    )
    for key in ("area_s2", "pair_count", "closest_i", "closest_j"):
        np.testing.assert_array_equal(called.components[key], auto.components[key])
    assert isinstance(auto.loops, il.Loops) and auto.loops is auto.loops
    assert len(auto.loops) == fleet.poses
    with pytest.raises(il.InvalidParameterError, match="kd-tree"):
        il.find_fleet_loops(fleet, gamma=1.0, pruning="kd")
    with pytest.raises(il.InvalidParameterError, match="gamma|γ"):
        il.find_fleet_loops(fleet, gamma=-1.0)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    xyz = np.c_[points, np.zeros(len(t))]
    poses = il.Fleet({"a": il.Trajectory.se3(t, xyz, q), "b": il.Trajectory.se3(t + 5, xyz, q)})
    with pytest.raises(il.InvalidParameterError, match="kd-tree pruning"):
        il.find_fleet_loops(poses, gamma=1.0, pruning="kd-tree")
    assert il.find_fleet_loops(poses, gamma=1.0).pruning == "hierarchy"
    with pytest.raises(il.InvalidParameterError, match='session "b" has 3 coordinates'):
        il.Fleet({"a": il.Trajectory.se3(t, xyz, q), "b": il.Trajectory(t, xyz)})


def test_sessions_measured_by_different_metrics_need_a_metric(tmp_path):
    t, points = tour(60, 0.0)
    lines = [f"{s} {x} {y} 0 0 0 0 1" for s, (x, y) in zip(t, points, strict=True)]
    (tmp_path / "a.tum").write_text("\n".join(lines) + "\n")
    weighted = il.read_trajectory(tmp_path / "a.tum", metric="se3(rotation_weight_m_per_rad=1)")
    plain = il.read_trajectory(tmp_path / "a.tum", metric="se3(rotation_weight_m_per_rad=0)")
    fleet = il.Fleet({"w": weighted, "p": plain})
    with pytest.raises(il.InvalidParameterError, match="pass metric="):
        il.find_fleet_loops(fleet, gamma=1.0)
    loops = il.find_fleet_loops(fleet, gamma=1.0, metric="se3(rotation_weight_m_per_rad=0)")
    assert loops.metric_name.startswith("se3")


# --- warnings -----------------------------------------------------------------------------------


def test_warnings_come_in_their_categories(tmp_path):
    gap = il.Trajectory([0.0, 1.0, 2.0], [[0.0, 0.0], [5.0, 0.0], [5.1, 0.0]])
    far = il.Trajectory([0.0, 1.0], [[100.0, 0.0], [100.5, 0.0]])
    fleet = il.Fleet({"gap": gap, "far": far})
    with pytest.warns(il.DiagonalBrokenWarning):
        loops = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
    assert loops.warnings
    with pytest.warns(il.NoLoopsWarning):
        il.find_fleet_loops(fleet, gamma=1.0)
    with pytest.warns(il.EmptySampleWarning):
        nothing = il.sample_fleet(loops, "one", budget=5, seed=0, between_only=True)
    assert len(nothing) == 0 and nothing.table["i"].dtype == np.int64
    with pytest.warns(il.SampleBudgetWarning):
        il.sample_fleet(loops, "alpha", budget=10_000, seed=0)
    (tmp_path / "d.tum").write_text(
        "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n1 2 0 0 0 0 0 1\n2 3 0 0 0 0 0 1\n"
    )
    with pytest.warns(il.DroppedInputWarning, match="d.tum"):
        il.Fleet([tmp_path / "d.tum"], drop_duplicate_stamps=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error", il.LoopsWarning)
        with pytest.raises(il.DiagonalBrokenWarning):
            il.find_fleet_loops(fleet, gamma=1.0, separation=None)


# --- the synthetic fleet ------------------------------------------------------------------------


def test_urban_fleet_is_seeded_and_names_vehicles_and_days():
    fleet = il.urban_fleet(vehicles=3, days=2, duration_s=60.0, seed=4)
    assert fleet.names == [f"car{v}-day{d}" for d in range(2) for v in range(3)]
    again = il.urban_fleet(vehicles=3, days=2, duration_s=60.0, seed=4)
    other = il.urban_fleet(vehicles=3, days=2, duration_s=60.0, seed=5)
    for a in range(len(fleet)):
        session = fleet.session(a)
        assert len(session) == 600 and session.dim == 3
        np.testing.assert_array_equal(session.positions, again.session(a).positions)
        day = a // 3
        assert day * 86_400 <= session.timestamps[0] < day * 86_400 + 3600
    assert not np.array_equal(fleet.session(0).positions, other.session(0).positions)
    districts = il.urban_fleet(vehicles=2, duration_s=60.0, city_size_m=2000.0, district_m=1000.0)
    assert len(districts) == 2
    with pytest.raises(il.InvalidParameterError, match="vehicles"):
        il.urban_fleet(vehicles=0)
    with pytest.raises(il.InvalidParameterError, match="district_m"):
        il.urban_fleet(district_dwell_s=10.0)


# --- plots --------------------------------------------------------------------------------------


def test_plots_of_a_fleet(city, city_loops):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from inexact_loops import plot

    ax = plot.overlap_matrix(city_loops, diagonal=False)
    image = ax.images[0].get_array()
    dense = city_loops.overlap_matrix()
    off = ~np.eye(len(city), dtype=bool) & (dense > 0)
    np.testing.assert_array_equal(image.mask, ~off)
    np.testing.assert_array_equal(image.data[off], dense[off])
    assert [label.get_text() for label in ax.get_yticklabels()] == city.names

    ax = plot.fleet_trajectories(city, city_loops)
    assert len(ax.lines) == len(city)
    for a, line in enumerate(ax.lines):
        np.testing.assert_array_equal(line.get_xydata(), city.session(a).positions[:, :2])
        assert line.get_label() == city.names[a]
    table = city_loops.components
    between = table["session_a"] != table["session_b"]
    marks = ax.collections[-1].get_offsets()
    assert len(marks) == between.sum()
    first = city.session(int(table["session_a"][between][0])).positions[
        table["closest_i"][between][0], :2
    ]
    second = city.session(int(table["session_b"][between][0])).positions[
        table["closest_j"][between][0], :2
    ]
    np.testing.assert_allclose(marks[0], (first + second) / 2)
    assert len(plot.fleet_trajectories(city).collections) == 0
    with pytest.raises(TypeError, match="FleetLoops"):
        plot.overlap_matrix(city)
    with pytest.raises(TypeError, match="Fleet"):
        plot.fleet_trajectories(city_loops)
    with pytest.raises(ValueError, match="another fleet"):
        plot.fleet_trajectories(il.urban_fleet(vehicles=2, duration_s=60.0), city_loops)
    plt.close("all")
