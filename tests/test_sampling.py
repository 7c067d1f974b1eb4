"""Detections, ε-graph clustering and the samplers through the Python API.

- The cluster partition equals scikit-learn's ``DBSCAN(eps, min_samples=1)`` (a KD-tree, which
  tests ``dx² + dy² <= eps²`` as we do) on random and adversarial point sets.
- Budgets are exact, P1 holds for σ_1 and σ_ρ when the budget allows it, seeds reproduce on any
  thread count; bad input gives clear errors; sample files are written atomically.
- The TUC Corridor's real place-recognition detections, clustered and sampled, with P1 measured
  against the exact components of its ground truth (run with ``-s`` for the report).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.cluster import DBSCAN

import inexact_loops as il

CLUSTER_SAMPLERS = ("one", "rho", "rho-dispersed", "alpha")
BASELINES = ("lio-sam", "hdl-graph-slam", "cartographer", "time-gap")
TUC = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "tuc" / "SLAM"


# --- helpers ---------------------------------------------------------------------------------


def sklearn_labels(points: np.ndarray, eps: float) -> np.ndarray:
    """DBSCAN(eps, min_samples=1) with a KD-tree: every point is a core point, so its clusters
    are the connected components of the graph of pairs within eps."""
    return DBSCAN(eps=eps, min_samples=1, algorithm="kd_tree").fit_predict(points)


def assert_same_partition(ours: np.ndarray, theirs: np.ndarray) -> None:
    """The two labellings put the same points together: their label pairs form a bijection."""
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    assert ours.shape == theirs.shape
    pairs = np.unique(np.c_[ours, theirs], axis=0)
    assert len(pairs) == len(np.unique(ours)) == len(np.unique(theirs)), (
        f"{len(np.unique(ours))} clusters here, {len(np.unique(theirs))} in scikit-learn, "
        f"{len(pairs)} label pairs"
    )


def check_against_sklearn(t: np.ndarray, t_prime: np.ndarray, eps: float) -> il.DetectionClusters:
    det = il.Detections(t, t_prime)
    clusters = il.cluster_detections(det, epsilon_s=eps)
    labels = clusters.labels
    # The stored pairs (t <= t') are the points that are clustered.
    assert_same_partition(labels, sklearn_labels(np.c_[det.t, det.t_prime], eps))
    # Ids follow each cluster's smallest (t, t'); the table agrees with the labels.
    table = clusters.clusters
    k = len(clusters)
    np.testing.assert_array_equal(table["id"], np.arange(k))
    np.testing.assert_array_equal(table["size"], np.bincount(labels, minlength=k))
    assert table["size"].sum() == len(det)
    order = np.lexsort((det.t_prime, det.t))
    first_seen = labels[order][np.sort(np.unique(labels[order], return_index=True)[1])]
    np.testing.assert_array_equal(first_seen, np.arange(k))
    for key, column, reduce in (
        ("t_min_s", det.t, np.minimum),
        ("t_max_s", det.t, np.maximum),
        ("t_prime_min_s", det.t_prime, np.minimum),
        ("t_prime_max_s", det.t_prime, np.maximum),
    ):
        expected = np.full(k, np.inf if reduce is np.minimum else -np.inf)
        reduce.at(expected, labels, column)
        np.testing.assert_array_equal(table[key], expected, err_msg=key)
    return clusters


def samplable_components(loops: il.Loops) -> set[int]:
    """Components holding a pair (i, j) with i < j, from the runs (a run reaching past its row)."""
    runs = loops.runs()
    return set(np.unique(runs["component"][runs["end"] > runs["row"]]).tolist())


def columns(samples: il.Samples) -> dict[str, np.ndarray | None]:
    return {
        key: getattr(samples, key)
        for key in ("t", "t_prime", "i", "j", "component", "cluster", "detection", "distance")
    }


def assert_same_samples(a: il.Samples, b: il.Samples) -> None:
    for key, value in columns(a).items():
        other = columns(b)[key]
        if value is None:
            assert other is None, key
        else:
            np.testing.assert_array_equal(value, other, err_msg=key)


# --- clustering against scikit-learn ---------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 400),
    eps=st.floats(0.05, 50.0),
    spread=st.floats(1.0, 5000.0),
    blobs=st.integers(0, 5),
)
def test_partition_equals_dbscan_on_random_sets(seed, n, eps, spread, blobs):
    rng = np.random.default_rng(seed)
    t = rng.uniform(0.0, spread, n)
    t_prime = t + rng.uniform(0.0, spread, n)
    if blobs:
        # Dense blobs a few ε wide: many points per cell, clusters that touch across cells.
        centres = rng.uniform(0.0, spread, (blobs, 2))
        pick = rng.integers(0, blobs, n)
        t = centres[pick, 0] + rng.normal(0.0, 2.0 * eps, n)
        t_prime = t + np.abs(centres[pick, 1] - centres[pick, 0]) + rng.normal(0.0, 2.0 * eps, n)
    check_against_sklearn(t, t_prime, eps)


@pytest.mark.parametrize("eps", [30.0, 0.1, 1.0 / 3.0, 7.3e-3])
def test_grid_exactly_epsilon_apart(eps):
    # Neighbours exactly ε apart (as far as floating point allows) along both axes, diagonals
    # at ε√2; computed as multiples, so some gaps round to just above ε and some to just below:
    # both sides must test them alike.
    a, b = np.meshgrid(np.arange(40), np.arange(40), indexing="ij")
    t = a.ravel() * eps
    t_prime = 1000.0 * eps + b.ravel() * eps
    clusters = check_against_sklearn(t, t_prime, eps)
    if eps == 30.0:  # exact in binary: one cluster
        assert len(clusters) == 1


@pytest.mark.parametrize("eps", [30.0, 0.1])
def test_grid_at_the_cell_side(eps):
    # Points on the lattice of side ε/√2, our cell side up to rounding: diagonal neighbours are
    # ε apart up to rounding, and points sit on cell boundaries.
    side = eps / math.sqrt(2.0)
    a, b = np.meshgrid(np.arange(30), np.arange(30), indexing="ij")
    keep = (a + b) % 2 == 0  # only diagonal neighbours
    check_against_sklearn(a[keep] * side, 500.0 * eps + b[keep] * side, eps)
    slightly = eps * (1 + 1e-15)
    check_against_sklearn(a.ravel() * side, 500.0 * eps + b.ravel() * side, slightly)


def test_duplicates():
    rng = np.random.default_rng(4)
    base_t = rng.uniform(0.0, 2000.0, 50)
    base_tp = base_t + rng.uniform(0.0, 2000.0, 50)
    copies = rng.integers(1, 40, 50)
    t, t_prime = np.repeat(base_t, copies), np.repeat(base_tp, copies)
    # Everything duplicated once more, and one point repeated 5000 times.
    t = np.r_[t, t, np.full(5000, 123.0)]
    t_prime = np.r_[t_prime, t_prime, np.full(5000, 456.0)]
    clusters = check_against_sklearn(t, t_prime, 30.0)
    assert clusters.clusters["size"].max() >= 5000


def test_one_huge_cluster():
    # A chain of 30,000 points along the diagonal band, consecutive points 0.9 ε apart, with
    # jitter: one cluster across thousands of cells; plus scattered points that touch it or not.
    rng = np.random.default_rng(5)
    eps = 10.0
    steps = rng.uniform(0.5, 0.9, 30_000) * eps / math.sqrt(2.0)
    t = np.cumsum(steps)
    t_prime = t + 500.0 + rng.uniform(-0.05, 0.05, len(t)) * eps
    extra_t = rng.uniform(0.0, t[-1], 3000)
    extra_tp = extra_t + rng.uniform(0.0, 2000.0, 3000)
    clusters = check_against_sklearn(np.r_[t, extra_t], np.r_[t_prime, extra_tp], eps)
    assert clusters.clusters["size"].max() >= 30_000


def test_threads_and_order_do_not_change_clusters():
    rng = np.random.default_rng(6)
    t = rng.uniform(0.0, 5000.0, 20_000)
    t_prime = t + rng.uniform(0.0, 3000.0, 20_000)
    det = il.Detections(t, t_prime)
    one = il.cluster_detections(det, epsilon_s=12.0, threads=1)
    two = il.cluster_detections(det, epsilon_s=12.0, threads=2)
    np.testing.assert_array_equal(one.labels, two.labels)
    for key, value in one.clusters.items():
        np.testing.assert_array_equal(value, two.clusters[key], err_msg=key)
    # Ids follow the smallest point of each cluster, not the input order.
    perm = rng.permutation(len(t))
    shuffled = il.cluster_detections(il.Detections(t[perm], t_prime[perm]), epsilon_s=12.0)
    np.testing.assert_array_equal(shuffled.labels, one.labels[perm])
    assert one.epsilon_s == 12.0 and 0 < one.cell_side_s < 12.0 / math.sqrt(2.0)
    assert len(one.detections) == len(det)


# --- the samplers ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def drive():
    """A 30 min urban drive at γ = 40 m, 1% of S_γ as detections, ε = 30 s."""
    traj = il.urban_drive(duration_s=1800.0, seed=3)
    loops = il.find_loops(traj, gamma=40.0, separation=None)
    det = il.draw_detections(loops, rate=0.01, seed=1)
    clusters = il.cluster_detections(det, epsilon_s=30.0)
    return traj, loops, det, clusters


def test_drawn_detections_lie_in_s_gamma(drive):
    traj, loops, det, _ = drive
    assert det.poses == len(traj)
    i, j = det.i, det.j
    assert np.all(i < j)
    np.testing.assert_array_equal(det.t, traj.timestamps[i])
    np.testing.assert_array_equal(det.t_prime, traj.timestamps[j])
    d = np.linalg.norm(traj.positions[i] - traj.positions[j], axis=1)
    assert np.all(d <= 40.0)
    # About 1% of the pairs i < j of S_γ.
    pairs = (loops.pair_count - len(traj)) // 2
    assert abs(len(det) - 0.01 * pairs) < 5 * math.sqrt(0.01 * pairs)
    # Distinct pairs in row-major order.
    keys = i.astype(np.int64) * len(traj) + j
    assert np.all(np.diff(keys) > 0)
    exactly = il.draw_detections(loops, budget=777, seed=2)
    assert len(exactly) == 777


@pytest.mark.parametrize("sampler", CLUSTER_SAMPLERS)
def test_budget_is_exact_on_clusters(drive, sampler):
    _, _, det, clusters = drive
    groups = len(clusters)
    for budget in (groups, groups + 1, 1000, 5000):
        samples = il.sample(clusters, sampler, budget=budget, seed=0)
        assert len(samples) == budget
        assert samples.warnings == []
        assert samples.sampler == sampler
        # Samples are detections of their cluster.
        k = samples.detection
        assert np.all(k >= 0)
        np.testing.assert_array_equal(samples.t, det.t[k])
        np.testing.assert_array_equal(samples.t_prime, det.t_prime[k])
        np.testing.assert_array_equal(samples.cluster, clusters.labels[k])
        assert len(np.unique(k)) == budget, "without replacement"
        if sampler != "alpha":
            assert set(samples.cluster.tolist()) == set(range(groups)), "P1 on the clusters"
    # A budget below the number of clusters: exactly B, and a warning that P1 cannot hold.
    if sampler != "alpha":
        few = il.sample(clusters, sampler, budget=groups - 1, seed=0)
        assert len(few) == groups - 1
        assert len(few.warnings) == 1 and "P1 cannot hold" in few.warnings[0]


@pytest.mark.parametrize("sampler", CLUSTER_SAMPLERS + BASELINES)
def test_budget_and_p1_on_exact_components(drive, sampler):
    traj, loops, _, _ = drive
    samplable = samplable_components(loops)
    budget = 2000
    samples = il.sample(loops, sampler, budget=budget, seed=0, trajectory=traj)
    i, j = samples.i, samples.j
    assert np.all(i < j)
    np.testing.assert_array_equal(samples.t, traj.timestamps[i])
    np.testing.assert_allclose(
        samples.distance, np.linalg.norm(traj.positions[i] - traj.positions[j], axis=1)
    )
    component = [loops.component_of(int(a), int(b)) for a, b in zip(i, j, strict=True)]
    np.testing.assert_array_equal(samples.component, [-1 if c is None else c for c in component])
    quality = il.sample_quality(samples, loops, epsilon_s=30.0)
    assert quality.samples == len(samples)
    assert quality.components == len(samplable)
    if sampler in BASELINES[:2]:
        # Rules that propose few pairs: all of them, with a warning when fewer than the budget.
        assert len(samples) <= budget
        assert (len(samples) < budget) == bool(samples.warnings)
        return
    assert len(samples) == budget
    assert np.all(samples.distance <= 40.0)
    if sampler != "alpha" and sampler not in BASELINES:
        assert set(component) == samplable, "P1: every component has a sample"
        assert quality.covered == quality.components and len(quality.missed["id"]) == 0


def test_p1_with_the_smallest_budget_that_allows_it(drive):
    traj, loops, _, clusters = drive
    components = len(samplable_components(loops))
    for sampler in ("one", "rho", "rho-dispersed"):
        samples = il.sample(loops, sampler, budget=components, seed=5, trajectory=traj)
        assert sorted(samples.component.tolist()) == sorted(samplable_components(loops))
        samples = il.sample(clusters, sampler, budget=len(clusters), seed=5)
        assert sorted(samples.cluster.tolist()) == list(range(len(clusters)))


def test_rate_mode(drive):
    traj, loops, det, clusters = drive
    every = il.sample(clusters, "alpha", rate=1.0, seed=0)
    assert len(every) == len(det)
    one = il.sample(clusters, "one", rate=1.0, seed=0)
    assert sorted(one.cluster.tolist()) == list(range(len(clusters)))
    rho = il.sample(loops, "rho", rate=0.05, seed=0, trajectory=traj)
    assert set(rho.component.tolist()) == samplable_components(loops)


@pytest.mark.parametrize("sampler", CLUSTER_SAMPLERS + BASELINES)
def test_seeds_reproduce_on_any_thread_count(drive, sampler):
    traj, loops, _, clusters = drive
    sources = [(loops, {"trajectory": traj})]
    if sampler in CLUSTER_SAMPLERS:
        sources.append((clusters, {}))
    for source, extra in sources:
        a = il.sample(source, sampler, budget=500, seed=11, threads=1, **extra)
        b = il.sample(source, sampler, budget=500, seed=11, threads=2, **extra)
        c = il.sample(source, sampler, budget=500, seed=11, **extra)
        assert_same_samples(a, b)
        assert_same_samples(a, c)
        if sampler not in ("lio-sam", "hdl-graph-slam", "rho-dispersed"):
            other = il.sample(source, sampler, budget=500, seed=12, **extra)
            assert not np.array_equal(a.t, other.t) or not np.array_equal(a.t_prime, other.t_prime)


def test_measure_and_locate_samples_of_clusters(drive):
    traj, loops, _, clusters = drive
    samples = il.sample(clusters, "rho", budget=300, seed=0)
    assert np.all(samples.component == -1) and np.isnan(samples.distance).all()
    measured = il.sample(clusters, "rho", budget=300, seed=0, trajectory=traj)
    np.testing.assert_array_equal(measured.t, samples.t)
    i, j = measured.i, measured.j
    np.testing.assert_allclose(
        measured.distance, np.linalg.norm(traj.positions[i] - traj.positions[j], axis=1)
    )
    located = samples.locate(loops)
    expected = [loops.component_of(int(a), int(b)) for a, b in zip(i, j, strict=True)]
    np.testing.assert_array_equal(located.component, expected)
    quality = il.sample_quality(samples, loops, epsilon_s=30.0)
    np.testing.assert_array_equal(quality.sample_components, expected)
    assert quality.outside == 0  # drawn detections all lie in S_γ


def test_quality_against_numpy(drive):
    traj, loops, _, _ = drive
    samples = il.sample(loops, "alpha", budget=3000, seed=2, trajectory=traj)
    quality = il.sample_quality(samples, loops, epsilon_s=20.0)
    comp = samples.component
    table = loops.components
    counts = np.bincount(comp, minlength=len(table["id"]))
    np.testing.assert_array_equal(quality.per_component, counts)
    samplable = sorted(samplable_components(loops))
    missed = [c for c in samplable if counts[c] == 0]
    assert sorted(quality.missed["id"].tolist()) == missed
    np.testing.assert_array_equal(quality.missed["area_s2"], table["area_s2"][quality.missed["id"]])
    assert quality.covered == len(samplable) - len(missed)
    assert quality.coverage == pytest.approx(quality.covered / quality.components)
    # P2: nearest other sample of the same component in the (t, t') plane, brute force.
    points = np.c_[samples.t, samples.t_prime]
    d = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=-1)
    d[comp[:, None] != comp[None, :]] = np.inf
    np.fill_diagonal(d, np.inf)
    nearest = d.min(axis=1)
    expected = np.where(np.isfinite(nearest), nearest, np.nan)
    np.testing.assert_allclose(quality.nearest_spacing_s, expected, rtol=1e-12)
    assert quality.redundant == int((nearest <= 20.0).sum())
    assert quality.median_spacing_s == pytest.approx(np.median(nearest[np.isfinite(nearest)]))
    # P3: slope of ln samples on ln area over the covered samplable components.
    covered = [c for c in samplable if counts[c] > 0]
    slope = np.polyfit(np.log(table["area_s2"][covered]), np.log(counts[covered]), 1)[0]
    assert quality.p3_slope == pytest.approx(slope, rel=1e-9, abs=1e-12)


def test_sampling_uses_the_loops_metric():
    from scipy.spatial.transform import Rotation

    traj = il.urban_drive(duration_s=300.0, se3=True)
    loops = il.find_loops(
        traj, gamma=40.0, metric=il.metrics.SE3(rotation_weight_m_per_rad=10.0), separation=None
    )
    samples = il.sample(loops, "alpha", budget=300, seed=0, trajectory=traj)
    p, i, j = traj.positions, samples.i, samples.j
    angle = (Rotation.from_quat(p[i, 3:]).inv() * Rotation.from_quat(p[j, 3:])).magnitude()
    se3 = np.linalg.norm(p[i, :3] - p[j, :3], axis=1) + 10.0 * angle
    np.testing.assert_allclose(samples.distance, se3, atol=1e-9)
    rotation = il.sample(loops, "alpha", budget=300, seed=0, trajectory=traj, metric="se3_rotation")
    np.testing.assert_allclose(rotation.distance, angle, atol=1e-9)
    # The Euclidean metric would take the quaternions for coordinates: it does not fit poses.
    with pytest.raises(
        il.InvalidParameterError, match="metric euclidean does not fit an se3 trajectory"
    ):
        il.sample(loops, "alpha", budget=300, seed=0, trajectory=traj, metric="euclidean")
    # A callable is recorded as custom(NAME), which names no metric: it must be given again.
    line = il.Trajectory(np.arange(50) * 0.1, np.c_[np.cos(np.arange(50)), np.zeros(50)])

    def l1(a, b):
        return float(np.abs(a - b).sum())

    callable_loops = il.find_loops(line, gamma=0.5, metric=l1, separation=None)
    with pytest.raises(
        il.InvalidParameterError, match=r'metric "custom\(l1\)", which is not a metric'
    ):
        il.sample(callable_loops, "one", budget=5, seed=0, trajectory=line)
    again = il.sample(callable_loops, "one", budget=5, seed=0, trajectory=line, metric=l1)
    pos = line.positions
    np.testing.assert_allclose(again.distance, np.abs(pos[again.i] - pos[again.j]).sum(axis=1))


# --- files -----------------------------------------------------------------------------------


def test_sample_files(drive, tmp_path):
    traj, loops, _, clusters = drive
    samples = il.sample(clusters, "rho-dispersed", budget=100, seed=0, trajectory=traj)
    path = tmp_path / "candidates.csv"
    samples.to_csv(path)
    with open(path, newline="") as lines:
        rows = list(csv.DictReader(lines))
    assert list(rows[0]) == [
        "t_s",
        "t_prime_s",
        "i",
        "j",
        "component",
        "cluster",
        "detection",
        "distance",
        "score",
        "sampler",
        *["dx", "dy", "dz", "dqx", "dqy", "dqz", "dqw", "dtheta_rad"],
        *["i_x", "i_y", "i_z", "j_x", "j_y", "j_z"],
    ]
    assert len(rows) == len(samples)
    np.testing.assert_array_equal([float(r["t_s"]) for r in rows], samples.t)
    np.testing.assert_array_equal([int(r["i"]) for r in rows], samples.i)
    np.testing.assert_array_equal([float(r["distance"]) for r in rows], samples.distance)
    np.testing.assert_array_equal([int(r["cluster"]) for r in rows], samples.cluster)
    assert {r["component"] for r in rows} == {""}
    assert {r["sampler"] for r in rows} == {"rho-dispersed"}

    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        samples.to_csv(path)
    path.write_text("keep")
    with pytest.raises(FileExistsError):
        samples.to_json(path)
    assert path.read_text() == "keep"
    samples.to_json(path, overwrite=True)
    document = json.loads(path.read_text())
    assert document["sampler"] == "rho-dispersed" and document["count"] == len(samples)
    assert document["poses"] == len(traj) and document["warnings"] == []
    np.testing.assert_array_equal([s["t_prime_s"] for s in document["samples"]], samples.t_prime)
    assert all(s["component"] is None and s["score"] is None for s in document["samples"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["candidates.csv"], "no temporary files"
    with pytest.raises(FileNotFoundError, match="cannot write"):
        samples.to_csv(tmp_path / "missing" / "candidates.csv")


# --- bad input -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def small():
    """A 95% circle of radius 10 m at 10 Hz, γ = 4 m: one trivial and one non-trivial component."""
    angle = np.linspace(0.0, 0.95 * 2 * np.pi, 200)
    traj = il.Trajectory(np.arange(200) * 0.1, 10.0 * np.c_[np.cos(angle), np.sin(angle)])
    loops = il.find_loops(traj, gamma=4.0, separation=None)
    det = il.Detections([0.0, 0.5, 19.0], [19.5, 19.9, 19.8], scores=[0.5, 0.9, 0.1])
    return traj, loops, det, il.cluster_detections(det, epsilon_s=1.0)


@pytest.mark.parametrize("eps", [0.0, -1.0, math.nan, math.inf])
def test_bad_epsilon(small, eps):
    traj, loops, det, clusters = small
    with pytest.raises(il.InvalidParameterError, match="epsilon_s"):
        il.cluster_detections(det, epsilon_s=eps)
    samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
    with pytest.raises(il.InvalidParameterError, match="epsilon_s"):
        il.sample_quality(samples, loops, epsilon_s=eps)


def test_detections_outside_the_time_span(small):
    traj, loops, _, _ = small
    det = il.Detections([1.0, -0.5], [2.0, 3.0])
    with pytest.raises(il.InvalidParameterError, match=r"detection 1 at -0.5 s lies outside"):
        det.locate(traj)
    with pytest.raises(il.InvalidParameterError, match=r"outside the trajectory's time span"):
        det.locate(loops)
    late = il.cluster_detections(il.Detections([1.0], [25.0]), epsilon_s=1.0)
    samples = il.sample(late, "alpha", rate=1.0, seed=0)
    with pytest.raises(il.InvalidParameterError, match=r"25 s lies outside .*\[0, 19.9"):
        il.sample(late, "alpha", rate=1.0, seed=0, trajectory=traj)
    with pytest.raises(il.InvalidParameterError, match="outside"):
        il.sample_quality(samples, loops, epsilon_s=1.0)
    with pytest.raises(il.InvalidParameterError, match="outside"):
        samples.locate(loops)


def test_bad_budget_rate_and_sampler(small):
    traj, loops, _, clusters = small
    for source, extra in ((clusters, {}), (loops, {"trajectory": traj})):
        with pytest.raises(il.InvalidParameterError, match="budget = 0 is invalid"):
            il.sample(source, "rho", budget=0, seed=0, **extra)
        with pytest.raises(il.InvalidParameterError, match="not both"):
            il.sample(source, "rho", rate=0.1, budget=10, seed=0, **extra)
        # Neither a rate nor a budget: the command line's default budget.
        neither = il.sample(source, "rho", seed=0, **extra)
        assert neither == il.sample(source, "rho", budget=il.DEFAULT_BUDGET, seed=0, **extra)
        assert neither != il.sample(source, "rho", budget=3, seed=0, **extra)
        with pytest.raises(il.InvalidParameterError, match="rate = 1.5 is invalid"):
            il.sample(source, "alpha", rate=1.5, seed=0, **extra)
        with pytest.raises(il.InvalidParameterError, match="rate = -1 is invalid"):
            il.sample(source, "one", rate=-1.0, seed=0, **extra)
        with pytest.raises(il.InvalidParameterError) as error:
            il.sample(source, "sigma_rho", budget=10, seed=0, **extra)
        assert str(error.value) == (
            'unknown sampler "sigma_rho": expected one of one, rho, rho-dispersed, alpha, '
            "closest-first, closest-then-spread, nearest-then-uniform, lio-sam, hdl-graph-slam, "
            "cartographer, time-gap"
        )
        with pytest.raises(il.InvalidParameterError, match="threads"):
            il.sample(source, "one", budget=1, seed=0, threads=0, **extra)
    with pytest.raises(il.InvalidParameterError, match="budget = 0 is invalid"):
        il.draw_detections(loops, budget=0, seed=0)
    with pytest.raises(il.InvalidParameterError, match="not both"):
        il.draw_detections(loops, rate=0.5, budget=3, seed=0)
    with pytest.raises(il.InvalidParameterError, match="give rate or budget"):
        il.draw_detections(loops, seed=0)
    with pytest.raises(il.InvalidParameterError, match="rate = 0 is invalid"):
        il.draw_detections(loops, rate=0.0, seed=0)
    with pytest.raises(il.InvalidParameterError, match="at most the off-diagonal pairs"):
        il.draw_detections(loops, budget=10**9, seed=0)
    # Baselines need the trajectory: not on clusters.
    with pytest.raises(il.InvalidParameterError, match="expected one of one, rho, rho-disp"):
        il.sample(clusters, "lio-sam", budget=3, seed=0)
    with pytest.raises(il.InvalidParameterError, match="lio_sam_period_s"):
        il.sample(loops, "lio-sam", budget=3, seed=0, trajectory=traj, lio_sam_period_s=0.0)
    with pytest.raises(TypeError, match="needs trajectory="):
        il.sample(loops, "one", budget=3, seed=0)
    with pytest.raises(TypeError, match="metric= needs trajectory="):
        il.sample(clusters, "one", budget=3, seed=0, metric="euclidean")
    with pytest.raises(TypeError, match="source must be DetectionClusters"):
        il.sample(traj, "one", budget=3, seed=0)
    other = il.Trajectory(np.arange(10) * 1.0, np.zeros((10, 2)))
    with pytest.raises(il.InvalidParameterError, match="different trajectories"):
        il.sample(loops, "one", budget=3, seed=0, trajectory=other)


def test_bad_detections(small):
    traj, loops, _, _ = small
    with pytest.raises(il.InvalidParameterError, match="no detections"):
        il.Detections([], [])
    with pytest.raises(il.InvalidParameterError, match="no detections"):
        il.Detections.from_indices(traj, [], [])
    with pytest.raises(il.InvalidParameterError, match="no detections"):
        il.Detections(np.array([]), np.array([]), scores=np.array([]))
    with pytest.raises(il.InvalidParameterError, match="t_prime_s has 1 values, but 2"):
        il.Detections([1.0, 2.0], [3.0])
    with pytest.raises(il.InvalidParameterError, match="score has 1 values, but 2"):
        il.Detections([1.0, 2.0], [3.0, 4.0], scores=[1.0])
    with pytest.raises(il.InvalidParameterError, match=r"t_s of detection 1 is not finite \(NaN\)"):
        il.Detections([1.0, np.nan], [3.0, 4.0])
    with pytest.raises(il.InvalidParameterError, match="score of detection 0 is not finite"):
        il.Detections([1.0], [3.0], scores=[np.inf])
    with pytest.raises(ValueError, match="1-dimensional"):
        il.Detections(np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(TypeError, match="real numbers"):
        il.Detections(["a"], ["b"])
    with pytest.raises(IndexError, match="detection 1 refers to pose 200"):
        il.Detections.from_indices(traj, [0, 200], [5, 6])
    with pytest.raises(IndexError, match=r"i\[0\] = -1 is not a pose index"):
        il.Detections.from_indices(loops, [-1], [5])
    with pytest.raises(TypeError, match="integer dtype"):
        il.Detections.from_indices(traj, [0.5], [5.0])
    with pytest.raises(il.InvalidParameterError, match="j has 2 values, but 1"):
        il.Detections.from_indices(traj, [0], [5, 6])
    with pytest.raises(TypeError, match="must be a Trajectory or Loops"):
        il.Detections.from_indices(np.arange(5), [0], [1])


def test_detections_from_indices_and_scores(small):
    traj, loops, det, clusters = small
    by_index = il.Detections.from_indices(loops, np.array([195, 3], dtype=np.uint32), [5, 190])
    assert by_index.i.tolist() == [5, 3] and by_index.j.tolist() == [195, 190]
    np.testing.assert_array_equal(by_index.t, traj.timestamps[[5, 3]])
    assert by_index.score is None and by_index.poses == len(traj)
    located = det.locate(traj)
    assert located.i.tolist() == [0, 5, 190] and located.j.tolist() == [195, 199, 198]
    np.testing.assert_array_equal(located.score, [0.5, 0.9, 0.1])
    assert det.i is None and det.poses is None
    assert "3 pairs" in repr(det) and "2 clusters" in repr(clusters)
    # The dispersed σ_ρ prefers a row's best-scored detection: here one per cluster.
    samples = il.sample(clusters, "rho-dispersed", budget=2, seed=0)
    np.testing.assert_array_equal(samples.score, [0.9, 0.1])


# --- real detections: the TUC Corridor -------------------------------------------------------
#
# An indoor robot drives a 160 m corridor back and forth (6 passes, 38 min). At γ = 1 m (the
# data README counts 22% of the detections within 1 m) every revisit band of S_γ touches the
# diagonal at a turn-around, so S_γ is one trivial component and P1 against exact components says
# nothing. The test therefore also counts revisits as pass pairs (pass a seen again in pass b,
# from the ground truth with numpy) and measures P1 against the exact components at γ = 0.5 m,
# where three non-trivial components separate.

CORRIDOR_GAMMA_M = 1.0
CORRIDOR_FINE_GAMMA_M = 0.5
CORRIDOR_EPSILON_S = 10.0  # a few seconds: detections come at ~3 s intervals along a revisit
CORRIDOR_BUDGET = 2000  # above the number of clusters, so σ_1 and σ_ρ reach every cluster


def read_corridor() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ground truth (t, x, y) and the `loop t1 t2 score` detections, parsed with numpy."""
    gt_path, input_path = TUC / "Corridor_GT.txt", TUC / "Corridor_Input.txt"
    if not (gt_path.is_file() and input_path.is_file()):
        pytest.skip(f"the TUC SLAM data is not at {TUC.resolve()} (not in a user's clone)")
    with open(gt_path) as lines:
        gt = np.array([line.split()[1:4] for line in lines if line.startswith("point2 ")], float)
    with open(input_path) as lines:
        loops = np.array([line.split()[1:4] for line in lines if line.startswith("loop ")], float)
    return gt[:, 0], gt[:, 1:3], loops


def corridor_passes(x: np.ndarray, window: int = 25, moving_m: float = 1.0) -> np.ndarray:
    """Pass number of every pose: a new pass starts where the direction of travel along the
    corridor (x over ±`window` poses, ignoring less than `moving_m`) turns around."""
    ahead = np.r_[x[2 * window :] - x[: -2 * window], np.zeros(2 * window)]
    step = np.roll(ahead, window)
    direction = np.sign(np.where(np.abs(step) > moving_m, step, 0.0))
    moving = np.flatnonzero(direction)
    # Standing still keeps the direction of the last (or, at the start, the next) motion.
    last = np.clip(np.searchsorted(moving, np.arange(len(x)), "right") - 1, 0, None)
    direction = direction[moving[last]]
    return np.r_[0, np.cumsum(direction[1:] != direction[:-1])]


@pytest.fixture(scope="module")
def corridor():
    t, xy, detections = read_corridor()
    traj = il.Trajectory(t, xy)
    inside = (detections[:, :2] >= t[0]).all(axis=1) & (detections[:, :2] <= t[-1]).all(axis=1)
    det = il.Detections(detections[inside, 0], detections[inside, 1], scores=detections[inside, 2])
    return traj, det.locate(traj), int((~inside).sum()), len(detections)


def test_tuc_corridor_real_detections(corridor):
    traj, det, dropped, total = corridor
    loops = il.find_loops(traj, gamma=CORRIDOR_GAMMA_M, separation=None)
    fine = il.find_loops(traj, gamma=CORRIDOR_FINE_GAMMA_M, separation=None)
    clusters = il.cluster_detections(det, epsilon_s=CORRIDOR_EPSILON_S)
    assert CORRIDOR_BUDGET >= len(clusters)
    positions = traj.positions
    passes = corridor_passes(positions[:, 0])

    def revisits(i: np.ndarray, j: np.ndarray) -> set[tuple[int, int]]:
        """Pass pairs (a < b) of the pairs within γ (numpy distances)."""
        within = np.linalg.norm(positions[i] - positions[j], axis=1) <= CORRIDOR_GAMMA_M
        a, b = passes[i][within], passes[j][within]
        return set(zip(a[a != b].tolist(), b[a != b].tolist(), strict=True))

    def fine_components(i: np.ndarray, j: np.ndarray) -> np.ndarray:
        return np.array([-1 if c is None else c for c in map(fine.component_of, i, j)])

    # What the detections reach, and the clusters made only of true detections of one revisit.
    i, j = det.i, det.j
    d = np.linalg.norm(positions[i] - positions[j], axis=1)
    component = np.array([-1 if c is None else c for c in map(loops.component_of, i, j)])
    np.testing.assert_array_equal(component >= 0, d <= CORRIDOR_GAMMA_M)
    reached = revisits(i, j)
    fine_trivial = fine.components["trivial"]
    fine_nontrivial = samplable_components(fine) - set(np.flatnonzero(fine_trivial).tolist())
    fine_reached = set(fine_components(i, j).tolist()) & fine_nontrivial
    revisit_of = [
        (int(a), int(b)) if ok and a != b else None
        for a, b, ok in zip(passes[i], passes[j], d <= CORRIDOR_GAMMA_M, strict=True)
    ]
    members: dict[int, set] = {}
    for label, revisit in zip(clusters.labels.tolist(), revisit_of, strict=True):
        members.setdefault(label, set()).add(revisit)
    pure = {next(iter(m)) for m in members.values() if len(m) == 1 and None not in m}

    lines = [
        f"\nTUC Corridor: {len(traj)} poses, {traj.span_s:.0f} s, {passes.max() + 1} passes "
        f"along the corridor; gamma {CORRIDOR_GAMMA_M} m: {len(loops.components['id'])} exact "
        f"component(s) ({int((~loops.components['trivial']).sum())} non-trivial); "
        f"gamma {CORRIDOR_FINE_GAMMA_M} m: {len(fine_nontrivial)} non-trivial",
        f"  detections: {total} in the file, {dropped} outside the ground truth's time span "
        f"(dropped), {len(det)} kept, {(d <= CORRIDOR_GAMMA_M).sum()} "
        f"({100 * (d <= CORRIDOR_GAMMA_M).mean():.0f}%) within {CORRIDOR_GAMMA_M} m",
        f"  they reach {len(reached)} revisits (pass pairs) and {len(fine_reached)} of the "
        f"{len(fine_nontrivial)} non-trivial components at {CORRIDOR_FINE_GAMMA_M} m; "
        f"{len(clusters)} clusters at epsilon {CORRIDOR_EPSILON_S} s, {len(pure)} revisits own a "
        "cluster of true detections",
        f"  budget {CORRIDOR_BUDGET}, seed 0:",
        "  | route | sampler | within 1 m | revisits covered (of reached) | non-trivial "
        f"components at {CORRIDOR_FINE_GAMMA_M} m covered | revisits missed |",
        "  |---|---|---:|---:|---:|---|",
    ]
    for route, source, extra in (
        ("detections", clusters, {}),
        ("exact components", loops, {"trajectory": traj}),
    ):
        samplers = CLUSTER_SAMPLERS if route == "detections" else CLUSTER_SAMPLERS + BASELINES
        for sampler in samplers:
            samples = il.sample(source, sampler, budget=CORRIDOR_BUDGET, seed=0, **extra)
            si, sj = samples.i, samples.j
            within = np.linalg.norm(positions[si] - positions[sj], axis=1) <= CORRIDOR_GAMMA_M
            covered = revisits(si, sj)
            fine_quality = il.sample_quality(samples, fine, epsilon_s=CORRIDOR_EPSILON_S)
            fine_hit = set(fine_quality.sample_components.tolist()) & fine_nontrivial
            missed = sorted(reached - covered)
            lines.append(
                f"  | {route} | {sampler} | {within.sum()} | {len(covered & reached)}/"
                f"{len(reached)} | {len(fine_hit)}/{len(fine_nontrivial)} | "
                f"{', '.join(f'{a}-{b}' for a, b in missed) or '-'} |"
            )
            quality = il.sample_quality(samples, loops, epsilon_s=CORRIDOR_EPSILON_S)
            if route == "detections":
                assert covered <= reached and fine_hit <= fine_reached, (
                    "samples of detections only cover what the detections reach"
                )
                if sampler != "alpha":
                    assert set(samples.cluster.tolist()) == set(range(len(clusters)))
                    assert pure <= covered, f"{sampler} missed a revisit with a cluster of its own"
            elif sampler in ("one", "rho", "rho-dispersed"):
                assert quality.covered == quality.components, "P1 on the exact components"
                assert within.all()
    print("\n".join(lines))
