"""The online engine and sampler from Python (``il.OnlineLoops``, ``il.OnlineSampler``): after
every push the live components equal the batch ``il.find_loops`` of the poses so far (and a
scipy brute force of the lattice), batches equal single pushes, a rebuild continues correctly,
the sampler keeps its promises (P1 online, the cap, the rate, the separation), bad input is a
clear error, and the classes pickle."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.distance import cdist

import inexact_loops as il

# Random walks break the diagonal where a step is longer than γ: expected, and tested elsewhere.
pytestmark = pytest.mark.filterwarnings("ignore::inexact_loops.DiagonalBrokenWarning")

#: Columns that must agree between the online table and the batch's (ids differ: online ids are
#: in creation order, batch ids in the batch's order).
STATS = (
    "trivial",
    "pair_count",
    "run_count",
    "holes",
    "i_min",
    "i_max",
    "j_min",
    "j_max",
    "closest_i",
    "closest_j",
    "closest_distance",
    "t_min_s",
    "t_max_s",
    "t_prime_min_s",
    "t_prime_max_s",
)


def walk(seed: int, n: int, dim: int = 2, step: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A random walk that wanders back on itself (a drift towards the start), and increasing
    times with uneven steps."""
    rng = np.random.default_rng(seed)
    points = np.zeros((n, dim))
    for k in range(1, n):
        points[k] = points[k - 1] + step * rng.normal(size=dim) - 0.05 * points[k - 1]
    times = np.cumsum(rng.uniform(0.1, 1.0, n))
    return times, points


def rows(table: dict) -> list[tuple]:
    """The rows of a component table as tuples of STATS, sorted, each with its area last, rounded
    to 12 significant digits: the online engine sums a component's area in the order its cells
    arrive, the batch in row order, so the last bits may differ (``to_loops`` is bit for bit)."""
    areas = [float(f"{a:.12g}") for a in np.asarray(table["area_s2"]).tolist()]
    return sorted(zip(*(np.asarray(table[name]).tolist() for name in STATS), areas, strict=True))


def batch(times: np.ndarray, points: np.ndarray, gamma: float) -> il.Loops:
    return il.find_loops(il.Trajectory(times, points), gamma=gamma, separation=None)


@pytest.mark.parametrize(
    ("seed", "dim", "gamma"), [(0, 1, 0.8), (1, 2, 1.5), (2, 2, 2.5), (3, 3, 2.0)]
)
def test_after_every_push_the_live_components_equal_find_loops(seed, dim, gamma):
    times, points = walk(seed, 70, dim)
    online = il.OnlineLoops(gamma=gamma, dim=dim)
    for k in range(len(times)):
        online.push(times[k], points[k])
        assert len(online) == k + 1
        if k == 0:
            continue
        expected = batch(times[: k + 1], points[: k + 1], gamma)
        table = online.components
        assert rows(table) == rows(expected.components), f"after pose {k}"
        assert np.all(np.diff(table["id"]) > 0)
        assert online.to_loops() == expected
        # τ so far: sums over Fenwick trees online, row sums in the batch (the last bits differ).
        tau = [online.loop_duration(p) for p in range(k + 1)]
        np.testing.assert_allclose(tau, expected.loop_duration(), rtol=1e-12, atol=0.0)


def lattice_components(
    points: np.ndarray, gamma: float
) -> list[tuple[bool, int, int, int, int, int]]:
    """(trivial, pair count, i range, j range) of every component, by scipy: the full n × n
    lattice of pairs within γ labelled with 4-connectivity; a trivial component holds the
    diagonal and is counted whole, a non-trivial one by its half i < j."""
    inside = cdist(points, points) <= gamma
    labels, count = ndimage.label(inside)
    out = []
    for label in range(1, count + 1):
        i, j = np.nonzero(labels == label)
        if np.any(i == j):
            out.append((True, len(i), int(i.min()), int(i.max()), int(j.min()), int(j.max())))
        elif np.all(i < j):
            out.append((False, len(i), int(i.min()), int(i.max()), int(j.min()), int(j.max())))
    return sorted(out)


@pytest.mark.parametrize(("seed", "gamma"), [(4, 1.2), (5, 2.0), (6, 3.0)])
def test_live_components_equal_a_scipy_brute_force(seed, gamma):
    times, points = walk(seed, 90)
    online = il.OnlineLoops(gamma=gamma, dim=2)
    for k in range(len(times)):
        online.push(times[k], points[k])
        if k % 15 == 14 or k == len(times) - 1:
            table = online.components
            got = sorted(
                zip(
                    table["trivial"].tolist(),
                    table["pair_count"].tolist(),
                    table["i_min"].tolist(),
                    table["i_max"].tolist(),
                    table["j_min"].tolist(),
                    table["j_max"].tolist(),
                    strict=True,
                )
            )
            assert got == lattice_components(points[: k + 1], gamma), f"after pose {k}"


def candidates_of(
    times, points, gamma, cuts, **options
) -> tuple[list[il.Candidate], il.OnlineLoops]:
    """The candidates of a sampler with `options`, the poses pushed in batches ending before
    each cut (a cut of 1 everywhere is one pose at a time)."""
    online = il.OnlineLoops(gamma=gamma, dim=points.shape[1])
    sampler = il.OnlineSampler(**options)
    found: list[il.Candidate] = []
    bounds = [0, *cuts, len(times)]
    for a, b in zip(bounds, bounds[1:], strict=False):
        if a == b:
            continue
        update = (
            online.push_many(times[a:b], points[a:b])
            if b - a > 1
            else online.push(times[a], points[a])
        )
        assert (update.first_pose, update.pose) == (a, b - 1)
        found += sampler.offer(online, update)
    return found, online


@pytest.mark.parametrize("seed", [7, 8, 9])
def test_push_many_equals_push_one_at_a_time(seed):
    times, points = walk(seed, 120)
    rng = np.random.default_rng(seed)
    cuts = sorted(set(rng.integers(1, len(times), 12).tolist()))
    options = {
        "rate": 0.4,
        "cap_per_minute": 3.0,
        "separation": il.Separation(path=4.0),
        "seed": seed,
    }
    single, one = candidates_of(times, points, 2.0, range(1, len(times)), **options)
    batched, many = candidates_of(times, points, 2.0, cuts, **options)
    assert single == batched and len(single) > 5
    assert rows(one.components) == rows(many.components)
    assert one.components["id"].tolist() == many.components["id"].tolist()
    # One batch of everything, too.
    everything = il.OnlineLoops(gamma=2.0, dim=2)
    update = everything.push_many(times, points)
    assert (update.first_pose, update.pose) == (0, len(times) - 1)
    assert rows(everything.components) == rows(one.components)
    assert everything.to_loops() == one.to_loops()


def test_an_update_reports_the_new_rows_runs_created_and_merged_components():
    times, points = walk(10, 100)
    online = il.OnlineLoops(gamma=2.0, dim=2)
    seen: set[int] = set()
    for k in range(len(times)):
        update = online.push(times[k], points[k])
        runs = update.runs
        assert set(runs["row"].tolist()) <= {k}
        # The runs are row k's cells: every pose j within γ of pose k, as intervals.
        within = np.nonzero(np.linalg.norm(points[: k + 1] - points[k], axis=1) <= 2.0)[0]
        cells = [
            j
            for s, e in zip(runs["start"].tolist(), runs["end"].tolist(), strict=True)
            for j in range(s, e + 1)
        ]
        assert cells == within.tolist()
        for s, e, c in zip(
            runs["start"].tolist(), runs["end"].tolist(), runs["closest"].tolist(), strict=True
        ):
            distances = np.linalg.norm(points[s : e + 1] - points[k], axis=1)
            assert c == s + int(np.argmin(distances))
        live = set(online.components["id"].tolist())
        created, extended = set(update.created.tolist()), set(update.extended.tolist())
        assert created <= live and not created & seen
        assert (
            extended <= live
            and not extended & created
            and extended <= set(runs["component"].tolist())
        )
        assert update.extended.tolist() == sorted(extended)
        for retired, survivor in zip(
            update.merged["retired"].tolist(), update.merged["survivor"].tolist(), strict=True
        ):
            assert survivor < retired and retired not in live and online.resolve(retired) in live
        seen |= set(update.created.tolist())
        assert update.loop_duration_s == pytest.approx(online.loop_duration(k), rel=1e-12)
    assert seen >= set(online.components["id"].tolist())


def test_rebuild_then_push_equals_the_batch_of_the_corrected_trajectory():
    times, points = walk(11, 140)
    half = 80
    online = il.OnlineLoops(gamma=2.0, dim=2)
    online.push_many(times[:half], points[:half])
    corrected = points.copy()
    corrected[:half] += np.linspace(0.0, 1.0, half)[:, None] * np.array(
        [0.7, -0.4]
    )  # the back end's fix
    online.rebuild(il.Trajectory(times[:half], corrected[:half]))
    assert online.rebuild_count == 1 and len(online) == half
    assert online.to_loops() == batch(times[:half], corrected[:half], 2.0)
    for k in range(half, len(times)):
        online.push(times[k], corrected[k])
    assert online.to_loops() == batch(times, corrected, 2.0)
    assert rows(online.components) == rows(batch(times, corrected, 2.0).components)
    # Ids restart from 0 at a rebuild.
    online.rebuild(il.Trajectory(times, corrected))
    assert online.components["id"][0] == 0 and online.to_loops() == batch(times, corrected, 2.0)
    online.clear()
    assert len(online) == 0 and online.trajectory is None and online.rebuild_count == 3


def test_the_components_agree_under_the_se3_metric():
    rng = np.random.default_rng(12)
    times, positions = walk(12, 60, 3)
    angles = rng.uniform(-np.pi, np.pi, 60)
    quats = np.c_[np.zeros(60), np.zeros(60), np.sin(angles / 2), np.cos(angles / 2)]
    metric = "se3(rotation_weight_m_per_rad=0.5)"
    online = il.OnlineLoops(gamma=2.5, dim=7, metric=metric)
    for k in range(60):
        online.push(times[k], np.r_[positions[k], quats[k]])
    expected = il.find_loops(
        il.Trajectory.se3(times, positions, quats), gamma=2.5, metric=metric, separation=None
    )
    assert online.metric_name == expected.metric_name

    def rounded(table: dict) -> dict:
        # Trajectory.se3 stores its quaternions normalised again: distances agree to the last bits.
        return {
            **table,
            "closest_distance": np.array([float(f"{d:.12g}") for d in table["closest_distance"]]),
        }

    assert rows(rounded(online.components)) == rows(rounded(expected.components))
    runs, expected_runs = online.to_loops().runs(), expected.runs()
    assert all(np.array_equal(runs[name], expected_runs[name]) for name in expected_runs)
    assert online.to_loops() == il.find_loops(online.trajectory, gamma=2.5, separation=None)


def off_diagonal_cells(loops: il.Loops, n: int) -> dict[int, list[tuple[int, int]]]:
    """The pairs (j, k), j < k, of each component."""
    cells: dict[int, list[tuple[int, int]]] = {}
    for k in range(n):
        for j in range(k):
            c = loops.component_of(j, k)
            if c is not None:
                cells.setdefault(c, []).append((j, k))
    return cells


@pytest.mark.parametrize("seed", [13, 14])
def test_p1_online_every_component_gets_its_closest_pair_when_it_appears(seed):
    times, points = walk(seed, 110)
    gamma = 2.0
    found, online = candidates_of(
        times, points, gamma, range(1, len(times)), rate=0.0, first_offer="edge"
    )
    assert found and all(c.first for c in found)
    loops = online.to_loops()
    cells = off_diagonal_cells(loops, len(times))
    by_component: dict[int, list[il.Candidate]] = {}
    for c in found:
        assert c.j < c.keyframe and c.pair == (c.j, c.keyframe)
        assert c.distance == pytest.approx(
            np.linalg.norm(points[c.j] - points[c.keyframe]), rel=1e-12
        )
        assert c.distance <= gamma
        by_component.setdefault(loops.component_of(c.j, c.keyframe), []).append(c)
    # The candidates' online ids, followed through merges, name the batch's components one to one.
    live_to_batch = {
        (online.resolve(c.component), loops.component_of(c.j, c.keyframe)) for c in found
    }
    assert (
        len({a for a, _ in live_to_batch})
        == len({b for _, b in live_to_batch})
        == len(live_to_batch)
    )
    # Every component with a pair got a candidate; the earliest at the first row where it had
    # one, the closest pair of that row.
    assert set(by_component) == set(cells)
    for component, pairs in cells.items():
        first_row = min(k for _, k in pairs)
        earliest = min(by_component[component], key=lambda c: c.keyframe)
        assert earliest.keyframe == first_row
        row = [
            (np.linalg.norm(points[j] - points[first_row]), j) for j, k in pairs if k == first_row
        ]
        assert earliest.j == min(row)[1]


def test_rate_one_draws_one_pair_per_component_per_pose():
    times, points = walk(15, 100)
    online = il.OnlineLoops(gamma=2.0, dim=2)
    sampler = il.OnlineSampler(rate=1.0, first_on_appearance=False)
    drawn = 0
    for k in range(len(times)):
        update = online.push(times[k], points[k])
        candidates = sampler.offer(online, update)
        runs = update.runs
        with_pairs = {
            c
            for s, e, c in zip(
                runs["start"].tolist(),
                runs["end"].tolist(),
                runs["component"].tolist(),
                strict=True,
            )
            if s < k  # a run with a pose before k
        }
        assert sorted(c.component for c in candidates) == sorted(with_pairs)
        assert not any(c.first for c in candidates)
        drawn += len(candidates)
    assert drawn > 50


@pytest.mark.parametrize(("cap", "unit"), [(2.0, "minute"), (0.5, "minute"), (0.2, "metre")])
def test_the_cap_bounds_every_components_candidates_over_every_stretch(cap, unit):
    times, points = walk(16, 200)
    times = times * 20.0  # slower: minutes of driving
    option = {"minute": "cap_per_minute", "metre": "cap_per_metre"}[unit]
    found, _ = candidates_of(times, points, 2.5, range(1, len(times)), rate=3.0, **{option: cap})
    uncapped, _ = candidates_of(times, points, 2.5, range(1, len(times)), rate=3.0)
    assert 0 < len(found) < len(uncapped)
    steps = np.r_[0.0, np.linalg.norm(np.diff(points, axis=0), axis=1)]
    travel = {"minute": times / 60.0, "metre": np.cumsum(steps)}[unit]
    groups: dict[int, list[il.Candidate]] = {}
    for c in found:
        groups.setdefault(c.component, []).append(c)
    for group in groups.values():
        at = [travel[c.keyframe] for c in group]
        firsts = sum(c.first for c in group)
        for a in range(len(group)):
            for b in range(a, len(group)):
                stretch = at[b] - at[a]
                assert b - a + 1 <= max(1.0, cap) + cap * stretch + firsts + 1e-9


def test_the_separation_and_the_seed():
    times, points = walk(17, 150)
    path = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
    separation = il.Separation(path=6.0, time_s=5.0)
    found, _ = candidates_of(
        times, points, 2.5, range(1, len(times)), rate=0.5, separation=separation, seed=3
    )
    assert found
    for c in found:
        assert path[c.keyframe] - path[c.j] >= 6.0 - 1e-9 and times[c.keyframe] - times[c.j] >= 5.0
    again, _ = candidates_of(
        times, points, 2.5, range(1, len(times)), rate=0.5, separation=separation, seed=3
    )
    other, _ = candidates_of(
        times, points, 2.5, range(1, len(times)), rate=0.5, separation=separation, seed=4
    )
    assert again == found and other != found


def test_bad_input_is_a_clear_error_and_changes_nothing():
    online = il.OnlineLoops(gamma=1.0, dim=2)
    online.push_many([0.0, 1.0, 2.0], [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    with pytest.raises(il.InvalidTrajectoryError, match=r"pose 3 is not finite \(NaN\)"):
        online.push(3.0, [float("nan"), 0.0])
    with pytest.raises(il.InvalidTrajectoryError, match=r"3.*1\.5"):
        online.push(1.5, [1.0, 1.0])
    with pytest.raises(il.InvalidTrajectoryError):
        online.push(float("inf"), [1.0, 1.0])
    with pytest.raises(ValueError, match=r"2 coordinate\(s\).*\(3,\)"):
        online.push(3.0, [1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="2 coordinate"):
        online.push_many([3.0, 4.0], np.zeros((2, 3)))
    with pytest.raises(TypeError, match="real numbers"):
        online.push(3.0, ["a", "b"])
    # A batch with a bad pose in the middle adds none of its poses; the message names the pose
    # by its index in the whole trajectory.
    with pytest.raises(il.InvalidTrajectoryError, match="4"):
        online.push_many([3.0, 4.0, 5.0], [[1.0, 0.0], [1.0, np.inf], [1.0, 0.0]])
    assert len(online) == 3
    with pytest.raises(IndexError):
        online.loop_duration(7)
    with pytest.raises(IndexError):
        online.loop_duration(-1)
    with pytest.raises(il.InvalidTrajectoryError):
        il.OnlineLoops(gamma=1.0, dim=2).to_loops()
    with pytest.raises(il.InvalidParameterError, match="gamma"):
        il.OnlineLoops(gamma=-1.0, dim=2)
    with pytest.raises(il.InvalidParameterError, match="manhattan"):
        il.OnlineLoops(gamma=1.0, dim=2, metric="manhattan")
    with pytest.raises(ValueError, match="not a callable"):
        il.OnlineLoops(gamma=1.0, dim=2, metric=lambda a, b: 0.0)
    with pytest.raises(il.InvalidParameterError):
        il.OnlineLoops(gamma=1.0, dim=3, metric="se3(rotation_weight_m_per_rad=1)")
    for bad in (
        {"rate": -1.0},
        {"rate": float("nan")},
        {"cap_per_minute": 0.0},
        {"separation": -2.0},
    ):
        with pytest.raises(il.InvalidParameterError):
            il.OnlineSampler(**bad)
    with pytest.raises(il.InvalidParameterError, match="not both"):
        il.OnlineSampler(cap_per_minute=1.0, cap_per_metre=1.0)
    with pytest.raises(il.InvalidParameterError, match="for_gamma"):
        il.OnlineSampler(separation="auto")
    with pytest.raises(il.InvalidParameterError):
        il.OnlineLoops(gamma=1.0, dim=2).rebuild(il.Trajectory([0.0, 1.0], np.zeros((2, 3))))


def test_an_update_is_offered_once_in_order_to_its_own_engine():
    online, other = il.OnlineLoops(gamma=1.0, dim=1), il.OnlineLoops(gamma=1.0, dim=1)
    sampler = il.OnlineSampler()
    first = online.push(0.0, [0.0])
    second = online.push(1.0, [0.5])
    with pytest.raises(il.InvalidParameterError, match="not the last push"):
        sampler.offer(online, first)
    with pytest.raises(il.InvalidParameterError, match="not the last push"):
        sampler.offer(other, second)
    sampler.offer(online, second)
    with pytest.raises(il.InvalidParameterError, match="already offered"):
        sampler.offer(online, second)
    online.rebuild(il.Trajectory([0.0, 1.0], [0.0, 0.5]))
    with pytest.raises(il.InvalidParameterError, match="not the last push"):
        sampler.offer(online, second)
    with pytest.raises(il.InvalidParameterError, match="not the last push"):
        sampler.offer(online, pickle.loads(pickle.dumps(online.push(2.0, [0.9]))))


def test_a_dimension_beyond_the_limit_is_refused_naming_it():
    for dim in (2**62, 2**16 + 1):
        with pytest.raises(il.InvalidParameterError, match=f"dim = {dim} is invalid"):
            il.OnlineLoops(gamma=1.0, dim=dim)
    widest = il.OnlineLoops(gamma=1.0, dim=2**16)
    widest.push(0.0, np.zeros(2**16))
    assert len(widest) == 1


def test_a_sampler_offered_another_engines_updates_starts_afresh():
    """Each engine's components are new to the sampler, whichever engine it followed before
    and whatever became of that engine."""
    times, points = walk(4, 80)

    def candidates(sampler: il.OnlineSampler) -> list[tuple[int, int, bool]]:
        online = il.OnlineLoops(gamma=2.0, dim=2)
        update = online.push_many(times, points)
        return [(c.keyframe, c.j, c.first) for c in sampler.offer(online, update)]

    expected = candidates(il.OnlineSampler(seed=3))
    assert any(first for _, _, first in expected)
    sampler = il.OnlineSampler(seed=3)
    for _ in range(3):
        assert candidates(sampler) == expected


def test_the_getters_say_what_was_given():
    online = il.OnlineLoops(gamma=1.5, dim=2, metric=il.metrics.Euclidean())
    assert (online.gamma, online.dim, online.metric_name, online.rebuild_count) == (
        1.5,
        2,
        "euclidean",
        0,
    )
    assert online.trajectory is None and online.timestamps.tolist() == []
    online.push_many([0.0, 2.0], [[0.0, 0.0], [1.0, 1.0]])
    assert online.timestamps.tolist() == [0.0, 2.0]
    assert online.trajectory == il.Trajectory([0.0, 2.0], [[0.0, 0.0], [1.0, 1.0]])
    assert "2 poses" in repr(online)
    sampler = il.OnlineSampler(
        rate=0.25, cap_per_metre=0.1, first_on_appearance=False, separation=3.0, seed=9
    )
    assert (sampler.rate, sampler.cap_per_minute, sampler.cap_per_metre) == (0.25, None, 0.1)
    assert (sampler.first_on_appearance, sampler.seed) == (False, 9)
    assert sampler.first_offer == "edge-then-closest"
    for where in ("edge", "closest-approach", "edge-then-closest"):
        assert il.OnlineSampler(first_offer=where).first_offer == where
        assert f"first_offer={where!r}".replace("'", '"') in repr(
            il.OnlineSampler(first_offer=where)
        )
    with pytest.raises(
        il.InvalidParameterError, match="unknown first offer .closest.: expected one of edge, "
    ):
        il.OnlineSampler(first_offer="closest")
    assert sampler.separation == il.Separation(path=3.0)
    assert "cap_per_metre=0.1" in repr(sampler)
    default = il.OnlineSampler()
    assert (default.rate, default.first_on_appearance, default.seed) == (1.0, True, 0)
    assert default.separation.is_none and default.cap_per_minute is None


def test_the_classes_pickle():
    times, points = walk(18, 120)
    corrected = points * 1.01

    def drive() -> tuple[il.OnlineLoops, il.Update]:
        online = il.OnlineLoops(gamma=2.0, dim=2)
        online.push_many(times[:50], points[:50])
        online.rebuild(il.Trajectory(times[:50], corrected[:50]))
        return online, online.push_many(times[50:90], corrected[50:90])

    candidate = il.Candidate(keyframe=9, j=2, component=4, distance=0.5, first=False)
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        online, update = drive()
        back = pickle.loads(pickle.dumps(online, protocol=protocol))
        assert len(back) == len(online) and back.rebuild_count == 1
        assert rows(back.components) == rows(online.components)
        assert back.components["id"].tolist() == online.components["id"].tolist()
        # The copy goes on as the original does.
        assert back.push_many(times[90:], corrected[90:]) == online.push_many(
            times[90:], corrected[90:]
        )
        assert back.to_loops() == online.to_loops()
        assert copy.deepcopy(online).components["id"].tolist() == online.components["id"].tolist()
        u = pickle.loads(pickle.dumps(update, protocol=protocol))
        assert u == update and hash(u) == hash(update) and u != online.push(1e6, [0.0, 0.0])
        c = pickle.loads(pickle.dumps(candidate, protocol=protocol))
        assert c == candidate and hash(c) == hash(candidate) and c.pair == (2, 9)
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle OnlineLoops"):
        il.OnlineLoops._from_state(b"not a pickle")


def test_a_pickled_sampler_draws_as_the_original():
    """Pickled midway with its engine, a sampler gives the rest of the drive the candidates the
    original gives; pickled alone, it goes on with the engine it followed."""
    times, points = walk(19, 160)
    kwargs = {"rate": 0.4, "cap_per_minute": 3.0, "seed": 5}

    def pairs(candidates: list[il.Candidate]) -> list[tuple[int, int, int, bool]]:
        return [(c.keyframe, c.j, c.component, c.first) for c in candidates]

    online, sampler = il.OnlineLoops(gamma=2.0, dim=2), il.OnlineSampler(**kwargs)
    online.push_many(times[:30], points[:30])
    online.rebuild(il.Trajectory(times[:30], points[:30] * 1.01))
    online.rebuild(il.Trajectory(times[:30], points[:30]))
    sampler.offer(online, online.push_many(times[30:80], points[30:80]))
    went_on = []
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        back_online, back_sampler = pickle.loads(pickle.dumps((online, sampler), protocol=protocol))
        assert back_online.rebuild_count == online.rebuild_count == 2
        rest = back_online.push_many(times[80:], points[80:])
        went_on.append(pairs(back_sampler.offer(back_online, rest)))
        # P1 served the components seen before the pickle: a new sampler serves them again.
        fresh = pairs(il.OnlineSampler(**kwargs).offer(back_online, rest))
        assert sum(c[3] for c in fresh) > sum(c[3] for c in went_on[-1])
    alone = pickle.loads(pickle.dumps(sampler))
    assert repr(alone) == repr(sampler)
    rest = online.push_many(times[80:], points[80:])
    expected = pairs(sampler.offer(online, rest))
    assert went_on == [expected] * len(went_on)
    assert pairs(alone.offer(online, rest)) == expected
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle OnlineSampler"):
        il.OnlineSampler._from_state(b"not a pickle")


# `pickle.dumps(il.OnlineSampler(rate=0.0, first_at_closest_approach=flag, seed=3))` by the
# version before `first_offer`, for flag False and True; and of a Candidate of that version.
_SAVED_BEFORE_FIRST_OFFER = {
    "edge": (
        "800495a1000000000000008c086275696c74696e73948c07676574617474729493948c13696e6578"
        "6163745f6c6f6f70732e5f636f7265948c0d4f6e6c696e6553616d706c65729493948c0b5f66726f"
        "6d5f73746174659486945294434894ad696e65786163745f6c6f6f707301ad4f6e6c696e6553616d"
        "706c65729497cb0000000000000000a44e6f6e65c3c2c392cb0000000000000000cb000000000000"
        "000003c0909094859452942e"
    ),
    "closest-approach": (
        "800495a1000000000000008c086275696c74696e73948c07676574617474729493948c13696e6578"
        "6163745f6c6f6f70732e5f636f7265948c0d4f6e6c696e6553616d706c65729493948c0b5f66726f"
        "6d5f73746174659486945294434894ad696e65786163745f6c6f6f707301ad4f6e6c696e6553616d"
        "706c65729497cb0000000000000000a44e6f6e65c3c3c392cb0000000000000000cb000000000000"
        "000003c0909094859452942e"
    ),
}
_CANDIDATE_BEFORE_FIRST_OFFER = (
    "80049570000000000000008c13696e65786163745f6c6f6f70732e5f636f7265948c0943616e6469"
    "64617465949394297d94288c086b65796672616d65944b0c8c016a944b038c09636f6d706f6e656e"
    "74944b018c0864697374616e636594473fe00000000000008c05666972737494888c016b944b0975"
    "92942e"
)


def test_a_sampler_pickled_before_first_offer_reads_back_as_it_was():
    """A sampler saved with the earlier flag keeps offering where it did: the flag's False is
    the edge and True the closest approach, not the new default; a saved candidate reads back
    without an improvement."""
    for offer, state in _SAVED_BEFORE_FIRST_OFFER.items():
        back = pickle.loads(bytes.fromhex(state))
        assert back.first_offer == offer
        assert repr(back) == repr(il.OnlineSampler(rate=0.0, first_offer=offer, seed=3))
    candidate = pickle.loads(bytes.fromhex(_CANDIDATE_BEFORE_FIRST_OFFER))
    assert candidate == il.Candidate(keyframe=12, j=3, k=9, component=1, distance=0.5, first=True)
    assert candidate.improves is None


def test_a_candidate_offered_after_its_pair_says_both():
    c = il.Candidate(keyframe=12, j=3, k=9, component=1, distance=0.5, first=True)
    assert (c.keyframe, c.j, c.k, c.pair) == (12, 3, 9, (3, 9))
    assert repr(c) == "Candidate(keyframe=12, j=3, component=1, distance=0.5, first=True, k=9)"
    back = pickle.loads(pickle.dumps(c))
    assert back == c and hash(back) == hash(c)
    plain = il.Candidate(keyframe=12, j=3, component=1, distance=0.5, first=True)
    assert plain.k == 12 and plain != c
    assert plain.improves is None and c.improves is None
    better = il.Candidate(
        keyframe=20, j=4, k=15, component=1, distance=0.1, first=False, improves=(3, 9)
    )
    assert better.improves == (3, 9)
    assert repr(better) == (
        "Candidate(keyframe=20, j=4, component=1, distance=0.1, first=False, k=15, improves=(3, 9))"
    )
    assert pickle.loads(pickle.dumps(better)) == better
    assert better != il.Candidate(keyframe=20, j=4, k=15, component=1, distance=0.1, first=False)


def test_first_candidates_at_the_closest_approach_on_kitti00(data_dir):
    """KITTI 00 at γ = 6 m, revisits only (24 m of path apart): at its appearance a component's
    first candidate lies near the edge of γ; at the closest approach it is the closest separated
    pair of the component so far, by brute force over the lattice of the poses before its
    keyframe (scipy's labelling), and its keyframe is after its pair."""
    path = data_dir / "kitti_odometry" / "00.txt"
    if not path.is_file():
        pytest.skip(f"{path} is missing")
    xz = np.loadtxt(path)[:, [4, 12]]
    t = 0.1 * np.arange(len(xz))
    gamma = 6.0
    separation = il.Separation.for_gamma(gamma)

    def firsts(where: str) -> list[il.Candidate]:
        online = il.OnlineLoops(gamma=gamma, dim=2)
        sampler = il.OnlineSampler(rate=0.0, separation=separation, first_offer=where)
        out = []
        for k in range(len(t)):
            out += sampler.offer(online, online.push(t[k], xz[k]))
        return out

    at_edge, at_closest = firsts("edge"), firsts("closest-approach")
    assert all(c.first for c in at_edge + at_closest)
    # Every revisit but one still under way when the log ends.
    assert len(at_closest) >= max(4, len(at_edge) - 1), (len(at_edge), len(at_closest))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xz, axis=0), axis=1))])
    for c in at_closest:
        j, k, kf = c.j, c.k, c.keyframe
        assert j < k < kf
        d = cdist(xz[:kf], xz[:kf])
        labels, _ = ndimage.label(d <= gamma)
        separated = s[None, :kf] - s[:kf, None] >= separation.path
        mine = (labels == labels[j, k]) & separated
        assert c.distance == pytest.approx(d[mine].min(), abs=1e-9), c
        assert c.distance == pytest.approx(d[j, k], abs=1e-12)
    edge = np.median([c.distance for c in at_edge])
    closest = np.median([c.distance for c in at_closest])
    print(
        f"KITTI 00, gamma 6 m: median first distance {edge:.2f} m at appearance, "
        f"{closest:.2f} m at the closest approach ({len(at_closest)} components)"
    )
    assert closest < 0.5 * edge
    # The default: the edge candidates at once, then each pass's closest pair as an improvement
    # naming its first (none where the first was the closest): the two streams above, merged.
    default = firsts("edge-then-closest")
    improvements = [c for c in default if c.improves is not None]
    assert [c for c in default if c.improves is None] == at_edge
    by_pair = {c.pair: c for c in at_edge}
    late = {(c.keyframe, c.pair): c for c in at_closest}
    lags = []
    for c in improvements:
        first = by_pair[c.improves]
        assert not c.first and c.distance < first.distance, (c, first)
        assert late[(c.keyframe, c.pair)].distance == c.distance, c
        lags.append(c.keyframe - first.keyframe)
    # Every pass that ended improved unless its edge pair was its closest.
    assert len(improvements) == sum(1 for c in at_closest if c.pair not in by_pair), (
        "an improvement for every pass whose closest pair was not its edge pair"
    )
    better = [c.distance for c in improvements]
    print(
        f"edge then closest: {len(improvements)} improvements, median {np.median(better):.2f} m "
        f"(p90 {np.percentile(better, 90):.2f} m), {np.median(lags):.0f} keyframes after the "
        f"first (p90 {np.percentile(lags, 90):.0f}); lags {sorted(lags)}"
    )
