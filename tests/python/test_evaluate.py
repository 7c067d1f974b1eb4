"""``inexact_loops.evaluate``: the map each sampler makes.

The pipeline returns the reference when the odometry is exact; true loop closures lower the
error of a drifted odometry; a wrong match is down-weighted by the robust back end; ATE and RPE
equal evo's APE and RPE; the drift model and the verifier follow their documented laws (checked
statistically against the formulas, not against earlier output); and ``loops-eval`` writes its
table and plot. The back-end tests skip, saying why, when GTSAM is not installed.
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import inexact_loops as il
from inexact_loops import evaluate as ev
from inexact_loops.evaluate import _poses

#: The back-end tests: skipped, saying why, without GTSAM (conftest.py).
needs_gtsam = pytest.mark.gtsam


def circuit(laps: float = 2.0, n: int = 400, radius: float = 50.0) -> ev.Poses:
    """``laps`` times round a circle of ``radius`` metres, a pose a second, heading along it."""
    angle = np.linspace(0.0, laps * 2 * np.pi, n)
    return ev.Poses.from_positions(
        np.arange(n, dtype=float), radius * np.c_[np.cos(angle), np.sin(angle)]
    )


def random_se3(n: int, seed: int) -> ev.Poses:
    """A wandering SE(3) path: steps of about 1 m forwards, turns about every axis."""
    rng = np.random.default_rng(seed)
    m = np.empty((n, 4, 4))
    m[0] = np.eye(4)
    for k in range(1, n):
        step = np.eye(4)
        step[:3, :3] = _poses.rot3(rng.normal(0.0, 0.1, 3))
        step[:3, 3] = [1.0 + rng.normal(0, 0.1), rng.normal(0, 0.1), rng.normal(0, 0.1)]
        m[k] = m[k - 1] @ step
    return ev.Poses(np.arange(n, dtype=float) * 0.1, m)


def lift(poses: ev.Poses) -> ev.Poses:
    """SE(2) poses as SE(3) at z = 0."""
    return ev.Poses(poses.timestamps, _poses._lift3(poses.matrices))


EXACT = ev.DriftModel(
    translation_sigma_m_per_sqrt_m=0.0,
    rotation_sigma_rad_per_sqrt_m=0.0,
    heading_bias_rad_per_m=0.0,
)


# ---------------------------------------------------------------------------------------------
# Poses
# ---------------------------------------------------------------------------------------------


def test_poses_constructors_agree_and_refuse_bad_input():
    t = np.arange(4.0)
    xyt = np.array([[0, 0, 0], [1, 0, 0.5], [2, 1, 1.0], [2, 2, 3.0]])
    poses = ev.Poses.se2(t, xyt)
    assert np.allclose(poses.xytheta, xyt)
    # SE(3) from the same headings as yaw quaternions, projected back.
    q = np.c_[np.zeros((4, 2)), np.sin(xyt[:, 2] / 2), np.cos(xyt[:, 2] / 2)]
    se3 = ev.Poses.se3(t, np.c_[xyt[:, :2], np.zeros(4)], q)
    assert np.allclose(se3.matrices, lift(poses).matrices)
    assert np.allclose(se3.quaternions_xyzw, q)
    # Relative poses: T_i^-1 T_j, checked on one pair by hand.
    rel = poses.relative([0, 1], [1, 2])
    assert np.allclose(rel[0], poses.matrices[1])
    assert np.allclose(poses.matrices[1] @ rel[1], poses.matrices[2])
    with pytest.raises(il.InvalidParameterError, match="pose 2 at 1.0 s follows 2.0 s"):
        ev.Poses.se2([0.0, 2.0, 1.0], xyt[:3])
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        ev.Poses.se2(t, xyt[:, :2])
    with pytest.raises(il.InvalidParameterError, match="quaternion 1"):
        ev.Poses.se3(t, np.zeros((4, 3)), np.r_[q[:1], np.zeros((1, 4)), q[2:]])
    with pytest.raises(il.InvalidParameterError, match="pose 3 is not finite"):
        ev.Poses.se2(t, np.r_[xyt[:3], [[np.nan, 0, 0]]])


def test_rotations_equal_scipys():
    from scipy.spatial.transform import Rotation

    rotations = Rotation.random(500, random_state=3)
    q = rotations.as_quat()  # x, y, z, w
    poses = ev.Poses.se3(np.arange(500.0), np.zeros((500, 3)), q)
    assert np.allclose(poses.rotations, rotations.as_matrix())
    ours = poses.quaternions_xyzw
    assert np.allclose(ours, q * np.sign(q[:, 3:]))
    v = rotations.as_rotvec()
    assert np.allclose(_poses.rot3(v), rotations.as_matrix())
    assert np.allclose(_poses.rot3(np.zeros((1, 3))), np.eye(3))


def test_headings_follow_the_motion_and_hold_at_stops():
    p = np.array([[0, 0], [1, 0], [1, 0], [1, 0], [1, 1], [1, 2]], dtype=float)
    poses = ev.Poses.from_positions(np.arange(6.0), p)
    theta = poses.xytheta[:, 2]
    assert theta[0] == pytest.approx(0.0)
    assert theta[-1] == pytest.approx(np.pi / 2)
    # Standing at (1, 0): 1 -> 3 see motion on one side; the middle one keeps the last heading.
    assert theta[2] == pytest.approx(theta[1])


def test_keyframes_and_odometry_take_compose_the_steps():
    ref = circuit(1.0, 200)
    keep = ref.keyframes(5.0)
    gaps = np.linalg.norm(np.diff(ref.positions[keep], axis=0), axis=1)
    assert keep[0] == 0 and keep[-1] == len(ref) - 1
    assert (gaps[:-1] >= 5.0).all()
    odo = ev.DriftModel().simulate(ref, seed=3)
    sub = odo.take(keep)
    assert np.allclose(sub.estimate.matrices, odo.estimate.matrices[keep])
    # Variances add along the path.
    assert sub.translation_sigma_m[0] == pytest.approx(
        math.sqrt((odo.translation_sigma_m[: keep[1]] ** 2).sum())
    )


def test_read_kitti_in_its_ground_plane(data_dir):
    path = data_dir / "kitti_odometry" / "05.txt"
    poses = ev.Poses.read(path, axes=(0, 2))
    raw = np.loadtxt(path)
    assert len(poses) == len(raw)
    assert np.allclose(poses.positions, raw[:, [4, 12]])
    se3 = ev.Poses.read(path, dim=3)
    assert np.allclose(se3.matrices[:, :3, :], raw[:, 1:].reshape(-1, 3, 4), atol=1e-6)


# ---------------------------------------------------------------------------------------------
# The drift model and the verifier follow their documented laws
# ---------------------------------------------------------------------------------------------


def test_drift_model_statistics():
    n = 20001
    line = ev.Poses.se2(
        np.arange(n, dtype=float), np.c_[4.0 * np.arange(n), np.zeros(n), np.zeros(n)]
    )
    model = ev.DriftModel(
        translation_sigma_m_per_sqrt_m=0.05,
        rotation_sigma_rad_per_sqrt_m=0.01,
        heading_bias_rad_per_m=1e-3,
        scale_bias=0.02,
    )
    odo = model.simulate(line, seed=11)
    steps = odo.steps
    # Step length 4 m: noise sd = sigma * sqrt(4); scale bias 2 %; heading bias 4 mrad a step.
    dx = steps[:, 0, 2] - 4.0 * 1.02
    heading = np.arctan2(steps[:, 1, 0], steps[:, 0, 0])
    for sample, mean, sd in ((dx, 0.0, 0.1), (steps[:, 1, 2], 0.0, 0.1), (heading, 4e-3, 0.02)):
        assert abs(sample.mean() - mean) < 4 * sd / math.sqrt(n)
        assert sample.std() == pytest.approx(sd, rel=0.03)
    assert np.allclose(odo.translation_sigma_m, 0.1)
    assert np.allclose(odo.rotation_sigma_rad, 0.02)
    # Seeded: the same seed, the same odometry; another seed, another one.
    assert np.array_equal(model.simulate(line, seed=11).steps, steps)
    assert not np.array_equal(model.simulate(line, seed=12).steps, steps)
    # No motion, no drift; the floors are what the back end is told.
    still = ev.Poses.se2(np.arange(5.0), np.zeros((5, 3)))
    quiet = model.simulate(still, seed=0)
    assert np.allclose(quiet.steps, np.eye(3))
    assert np.allclose(quiet.translation_sigma_m, model.min_translation_sigma_m)
    with pytest.raises(il.InvalidParameterError, match="rotation_sigma_rad_per_sqrt_m"):
        ev.DriftModel(rotation_sigma_rad_per_sqrt_m=-1.0)


def test_drift_model_in_se3_turns_about_the_up_axis():
    ref = random_se3(300, 1)
    odo = ev.DriftModel(
        translation_sigma_m_per_sqrt_m=0.0,
        rotation_sigma_rad_per_sqrt_m=0.0,
        heading_bias_rad_per_m=0.01,
        up_axis=(0.0, 1.0, 0.0),
    ).simulate(ref, seed=0)
    truth = ref.relative(np.arange(299), np.arange(1, 300))
    error = np.linalg.inv(truth[:, :3, :3]) @ odo.steps[:, :3, :3]
    length = np.linalg.norm(truth[:, :3, 3], axis=1)
    # A rotation about y by 0.01 rad per metre of the step.
    assert np.allclose(error[:, 0, 2], np.sin(0.01 * length), atol=1e-9)
    assert np.allclose(error[:, 1, 1], 1.0)


def test_verifier_follows_its_laws():
    verifier = ev.Verifier(
        outlier_rate=0.1,
        success_max=0.9,
        half_success_distance_m=10.0,
        translation_sigma_m=0.1,
        translation_sigma_per_m=0.01,
    )
    n = 40001
    # Pose 0 at the origin; poses 1.. at 5 m and 20 m: p(5) = 0.9 * 2^-0.25, p(20) = 0.9 / 16.
    xs = np.where(np.arange(n) % 2 == 1, 5.0, 20.0)
    xs[0] = 0.0
    poses = ev.Poses.se2(np.arange(n, dtype=float), np.c_[xs, np.zeros(n), np.zeros(n)])
    j = np.arange(1, n)
    i = np.zeros(n - 1, dtype=np.int64)
    m = verifier.verify(poses, i, j, seed=5)
    assert m.tried == n - 1
    wrong = m.wrong.sum()
    trials = n - 1
    assert abs(wrong - 0.1 * trials) < 4 * math.sqrt(0.1 * 0.9 * trials)
    for d, p in ((5.0, 0.9 * 2**-0.25), (20.0, 0.9 / 16)):
        near = xs[j] == d
        right = (~m.wrong & (xs[m.j] == d)).sum()
        expected = near.sum() * 0.9 * p
        assert abs(right - expected) < 4 * math.sqrt(expected), (d, right, expected)
        # The noise: sd 0.1 + 0.01 d per translation axis around the truth.
        sel = ~m.wrong & (xs[m.j] == d)
        err = m.relative[sel, 0, 2] - d
        assert err.std() == pytest.approx(0.1 + 0.01 * d, rel=0.1)
        assert abs(err.mean()) < 4 * (0.1 + 0.01 * d) / math.sqrt(sel.sum())
    # Wrong matches: translations in the 20 m disc, uniform: half of them inside 20/sqrt(2).
    r = np.linalg.norm(m.relative[m.wrong, :2, 2], axis=1)
    assert r.max() <= 20.0
    assert abs((r < 20 / math.sqrt(2)).mean() - 0.5) < 4 * math.sqrt(0.25 / wrong)
    # The reported sigmas are the law at the measured distance.
    assert np.allclose(
        m.translation_sigma_m, 0.1 + 0.01 * np.linalg.norm(m.relative[:, :2, 2], axis=1)
    )


@pytest.mark.parametrize("dim", [2, 3])
def test_verifier_outcome_is_a_property_of_the_pair(dim):
    ref = circuit() if dim == 2 else random_se3(400, 0)
    verifier = ev.Verifier(outlier_rate=0.2)
    rng = np.random.default_rng(0)
    i = rng.integers(0, 200, 300)
    j = i + rng.integers(1, 200, 300)
    whole = verifier.verify(ref, i, j, seed=9)
    part = verifier.verify(ref, i[::3], j[::3], seed=9)
    key = {
        (a, b): (w, rel.tobytes())
        for a, b, w, rel in zip(whole.i, whole.j, whole.wrong, whole.relative, strict=True)
    }
    for a, b, w, rel in zip(part.i, part.j, part.wrong, part.relative, strict=True):
        assert key[(a, b)] == (w, rel.tobytes())
    other = verifier.verify(ref, i, j, seed=10)
    assert not np.array_equal(other.i, whole.i) or not np.allclose(other.relative, whole.relative)
    # Wrong rotations are uniform: a heading uniform in [-pi, pi), or uniform on SO(3), where
    # the trace of R has mean 0 and variance 1.
    pi, pj = np.triu_indices(len(ref), 1)
    everything = ev.Verifier(outlier_rate=1.0).verify(ref, pi[:20000], pj[:20000], seed=1)
    rotations = everything.relative[:, :dim, :dim]
    if dim == 2:
        heading = np.arctan2(rotations[:, 1, 0], rotations[:, 0, 0])
        assert abs(heading.mean()) < 4 * np.pi / math.sqrt(3 * 20000)
        assert heading.std() == pytest.approx(2 * np.pi / math.sqrt(12), rel=0.03)
    else:
        trace = np.trace(rotations, axis1=1, axis2=2)
        assert abs(trace.mean()) < 4 / math.sqrt(20000)
        assert trace.var() == pytest.approx(1.0, rel=0.05)
    with pytest.raises(IndexError, match=r"j\[0\] = 400 is not a pose"):
        verifier.verify(ref, [0], [400], seed=0)
    with pytest.raises(il.InvalidParameterError, match="outlier_rate"):
        ev.Verifier(outlier_rate=1.5)


def test_candidates_on_the_reference_and_on_the_estimate():
    ref = circuit(3.0, 600)
    rule = ev.CandidateRule("closest-first", 50, gamma=5.0)
    i, j = ev.choose_candidates(ref, rule, seed=0)
    assert len(i) == 50 and (i < j).all()
    d = np.linalg.norm(ref.positions[i] - ref.positions[j], axis=1)
    assert (d <= 5.0).all()
    # With the separation, every pair is at least 4 gamma of path apart.
    path = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(ref.positions, axis=0), axis=1))]
    assert (path[j] - path[i] >= 20.0 - 1e-9).all()
    # On a drifted estimate the loops are the estimate's at 2 gamma.
    odo = ev.DriftModel(heading_bias_rad_per_m=2e-4).simulate(ref, seed=0)
    on_estimate = ev.CandidateRule("rho", 50, gamma=5.0, on="estimate")
    i2, j2 = ev.choose_candidates(odo.estimate, on_estimate, seed=0)
    est = odo.estimate.positions
    assert (np.linalg.norm(est[i2] - est[j2], axis=1) <= 10.0).all()
    # From detections, and a baseline.
    det = ev.CandidateRule("alpha", 30, gamma=5.0, source="detections", detection_rate=0.2)
    assert len(ev.choose_candidates(ref, det, seed=1)[0]) == 30
    lio = ev.CandidateRule("lio-sam", 1000, gamma=5.0)
    i3, j3 = ev.choose_candidates(ref, lio, seed=0)
    assert 0 < len(i3) < 1000
    with pytest.raises(il.InvalidParameterError, match="unknown sampler 'sigma'"):
        ev.CandidateRule("sigma", 10, gamma=5.0)
    with pytest.raises(il.InvalidParameterError, match="budget = 0"):
        ev.CandidateRule("rho", 0, gamma=5.0)


# ---------------------------------------------------------------------------------------------
# ATE and RPE against evo
# ---------------------------------------------------------------------------------------------


def needs_evo() -> None:
    pytest.importorskip("evo", reason="evo is not installed: the ATE/RPE comparison needs it")


def evo_ape(ref: ev.Poses, est: ev.Poses, align: bool) -> float:
    from evo.core import metrics

    r, e = ref.to_evo(), est.to_evo()
    if align:
        e.align(r)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((r, e))
    return float(ape.get_statistic(metrics.StatisticsType.rmse))


def evo_rpe(ref: ev.Poses, est: ev.Poses, delta: float, unit: str, all_pairs: bool) -> float:
    from evo.core import metrics

    rpe = metrics.RPE(
        metrics.PoseRelation.translation_part,
        delta=delta,
        delta_unit=metrics.Unit.frames if unit == "frames" else metrics.Unit.meters,
        all_pairs=all_pairs,
        pairs_from_reference=True,
    )
    rpe.process_data((ref.to_evo(), est.to_evo()))
    return float(rpe.get_statistic(metrics.StatisticsType.rmse))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ate_and_rpe_equal_evos(seed):
    needs_evo()
    ref3 = random_se3(300, seed)
    est3 = ev.DriftModel(heading_bias_rad_per_m=3e-3).simulate(ref3, seed=seed).estimate
    ref2 = circuit(1.5, 250)
    est2 = ev.DriftModel(heading_bias_rad_per_m=1e-3).simulate(ref2, seed=seed).estimate
    for ref, est in ((ref3, est3), (ref2, est2)):
        for align in (True, False):
            ours = ev.ate(ref, est, align=align)
            assert ours > 0.1
            assert ours == pytest.approx(evo_ape(ref, est, align), rel=1e-9, abs=1e-12)
        for delta, unit, all_pairs in (
            (1, "frames", False),
            (7, "frames", False),
            (7, "frames", True),
            (20.0, "m", False),
            (20.0, "m", True),
        ):
            ours = ev.rpe(ref, est, delta=delta, delta_unit=unit, all_pairs=all_pairs)
            theirs = evo_rpe(ref, est, delta, unit, all_pairs)
            assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-12), (delta, unit, all_pairs)


def test_umeyama_equals_evos():
    needs_evo()
    from evo.core.geometry import umeyama_alignment

    rng = np.random.default_rng(4)
    for dim in (2, 3):
        x = rng.normal(size=(50, dim))
        y = x @ np.linalg.qr(rng.normal(size=(dim, dim)))[0].T + rng.normal(size=dim)
        y += rng.normal(scale=0.01, size=y.shape)
        r, t = ev.umeyama(x, y)
        r_evo, t_evo, _ = umeyama_alignment(x.T, y.T)
        assert np.allclose(r, r_evo) and np.allclose(t, t_evo)
        assert np.isclose(np.linalg.det(r), 1.0)


# ---------------------------------------------------------------------------------------------
# The pose graph
# ---------------------------------------------------------------------------------------------


@needs_gtsam
@pytest.mark.parametrize("dim", [2, 3])
def test_exact_odometry_returns_the_reference(dim):
    ref = circuit() if dim == 2 else random_se3(200, 5)
    odo = EXACT.simulate(ref, seed=0)
    assert ev.ate(ref, odo.estimate, align=False) < 1e-9
    rule = ev.CandidateRule("closest-first", 50, gamma=10.0)
    for kernel in ("cauchy", "gauss"):
        est, matches, pairs = ev.evaluate_one(
            ref,
            odo,
            rule,
            seed=0,
            verifier=ev.Verifier(
                translation_sigma_m=1e-4,
                translation_sigma_per_m=0.0,
                rotation_sigma_rad=1e-5,
                rotation_sigma_rad_per_m=0.0,
            ),
            backend=ev.BackEnd(kernel=kernel),
        )
        if dim == 2:
            assert len(matches) > 10
        assert ev.ate(ref, est, align=False) < 1e-3
        assert ev.rpe(ref, est) < 1e-3


@needs_gtsam
@pytest.mark.parametrize("dim", [2, 3])
def test_true_loop_closures_lower_the_error(dim):
    if dim == 2:
        ref = circuit(3.0, 600)
        odo = ev.DriftModel(heading_bias_rad_per_m=5e-4).simulate(ref, seed=1)
        rule = ev.CandidateRule("closest-first", 100, gamma=5.0)
        i, j = ev.choose_candidates(ref, rule, seed=0)
    else:
        ref = lift(circuit(3.0, 600))
        odo = ev.DriftModel(heading_bias_rad_per_m=5e-4).simulate(ref, seed=1)
        i, j = ev.choose_candidates(ref, ev.CandidateRule("closest-first", 100, gamma=5.0), seed=0)
    alone = ev.ate(ref, ev.optimize(odo))
    assert alone == pytest.approx(ev.ate(ref, odo.estimate), rel=1e-6)  # the odometry alone
    closed = ev.ate(ref, ev.optimize(odo, ev.Matches.exact(ref, i, j)))
    assert alone > 5.0
    assert closed < 0.2 * alone, (closed, alone)
    # More closures, lower still: the first few alone leave more error than all of them.
    few = ev.ate(ref, ev.optimize(odo, ev.Matches.exact(ref, i[:3], j[:3])))
    assert closed < few < alone


@needs_gtsam
@pytest.mark.parametrize("kernel", ["cauchy", "huber", "gnc"])
def test_a_wrong_match_is_down_weighted(kernel):
    ref = circuit(3.0, 600)
    odo = ev.DriftModel(heading_bias_rad_per_m=2e-4).simulate(ref, seed=2)
    i, j = ev.choose_candidates(ref, ev.CandidateRule("closest-first", 60, gamma=5.0), seed=0)
    right = ev.Matches.exact(ref, i, j, sigma_m=0.05, sigma_rad=0.005)
    # Three wrong matches: pairs on opposite sides of the circle claimed to be 1 m apart.
    wi, wj = np.array([10, 200, 330]), np.array([110, 300, 430])
    claim = np.tile(np.eye(3), (3, 1, 1))
    claim[:, 0, 2] = 1.0
    wrong = ev.Matches(
        np.r_[right.i, wi],
        np.r_[right.j, wj],
        np.r_[right.relative, claim],
        np.r_[right.translation_sigma_m, [0.05] * 3],
        np.r_[right.rotation_sigma_rad, [0.005] * 3],
        np.r_[right.wrong, [True] * 3],
        len(right.i) + 3,
    )
    clean = ev.ate(ref, ev.optimize(odo, right, ev.BackEnd(kernel="gauss")))
    gauss = ev.ate(ref, ev.optimize(odo, wrong, ev.BackEnd(kernel="gauss")))
    robust = ev.ate(
        ref,
        ev.optimize(
            odo, wrong, ev.BackEnd(kernel=kernel, kernel_width=1.345 if kernel == "huber" else 1.0)
        ),
    )
    assert gauss > 10.0, gauss  # the wrong matches bend the plain Gaussian's map
    assert robust < 0.1 * gauss, (robust, gauss)
    assert robust < clean + 0.5, (robust, clean)


@needs_gtsam
def test_evaluate_grid_and_its_files(tmp_path):
    ref = circuit(3.0, 600)
    results = ev.evaluate(
        ref,
        gamma=5.0,
        samplers=["closest-first", "alpha", "lio-sam"],
        budgets=[10, 100],
        seeds=[0, 1],
        separations=(True, False),
        sources=("exact", "detections"),
        detection_samplers=("alpha",),
        outlier_rates=(0.0, 0.2),
        dataset="circle",
    )
    rows = results.rows
    # Per seed: the odometry row; per outlier rate: closest-first and alpha on exact with and
    # without separation, alpha on detections with and without, lio-sam once (separation on).
    per_seed = 1 + 2 * 2 * (2 + 2 + 2 + 1)
    assert len(rows) == 2 * per_seed
    odometry = {r["seed"]: r["ate_m"] for r in rows if r["sampler"] == "odometry"}
    assert all(r["odometry_ate_m"] == odometry[r["seed"]] for r in rows)
    assert all(r["candidates"] <= r["budget"] for r in rows if r["sampler"] != "odometry")
    assert all(r["wrong"] == 0 for r in rows if r["outlier_rate"] == 0.0)
    assert any(r["wrong"] > 0 for r in rows if r["outlier_rate"] > 0.0)
    table = results.table()
    assert set(table) == set(ev.COLUMNS) and len(table["ate_m"]) == len(rows)
    summary = results.summary()
    cf = [
        s
        for s in summary
        if s["sampler"] == "closest-first"
        and s["budget"] == 100
        and s["separation"]
        and s["outlier_rate"] == 0.0
    ]
    assert len(cf) == 1 and cf[0]["seeds"] == 2
    assert cf[0]["ate_min_m"] <= cf[0]["ate_median_m"] <= cf[0]["ate_max_m"]
    assert cf[0]["ate_median_m"] < cf[0]["odometry_ate_m"]
    results.to_csv(tmp_path / "rows.csv")
    again = ev.Results.from_csv(tmp_path / "rows.csv")
    assert again.rows == [{k: r[k] for k in ev.COLUMNS} for r in rows]
    results.to_json(tmp_path / "rows.json")
    document = json.loads((tmp_path / "rows.json").read_text())
    assert document["settings"]["gamma"] == 5.0 and len(document["rows"]) == len(rows)
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    ax = ev.plot_error_vs_matches(results, select={"separation": True, "outlier_rate": 0.0})
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "odometry alone" in labels and any("closest-first" in t for t in labels)
    import matplotlib.pyplot as plt

    plt.close("all")


@needs_gtsam
def test_loops_eval_command(tmp_path):
    ref = circuit(3.0, 600)
    poses = tmp_path / "circle.tum"
    ref.to_tum(poses)
    out = tmp_path / "eval"
    cmd = [
        sys.executable,
        "-m",
        "inexact_loops.evaluate",
        str(poses),
        "--gamma",
        "5",
        "--budgets",
        "10,50",
        "--seeds",
        "2",
        "--samplers",
        "closest-first,rho",
        "--out",
        str(out),
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    rows = ev.Results.from_csv(out / "results.csv").rows
    assert {r["sampler"] for r in rows} == {"odometry", "closest-first", "rho"}
    assert len(rows) == 2 * (1 + 2 * 2)
    assert (out / "results.json").exists() and (out / "error_vs_matches.png").stat().st_size > 1000
    assert "closest-first" in done.stdout
    # An existing folder is kept; a missing file is one line naming it, exit code 2.
    again = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert again.returncode == 2 and "exists and is not empty" in again.stderr
    missing = subprocess.run(
        cmd[:3] + ["nowhere.tum"] + cmd[4:-1] + [str(tmp_path / "x")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert missing.returncode == 2 and "nowhere.tum" in missing.stderr
    assert len(missing.stderr.strip().splitlines()) == 1
    # Rounds in time order: recorded in the settings; a baseline cannot take them (one line).
    timed = [*cmd[:-1], str(tmp_path / "t"), "--on", "estimate", "--rounds", "2"]
    timed += ["--rounds-order", "time", "--budgets", "20", "--seeds", "1"]
    done = subprocess.run(timed, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    settings = json.loads((tmp_path / "t" / "results.json").read_text())["settings"]
    assert settings["rounds_order"] == "time"
    rows = ev.Results.from_csv(tmp_path / "t" / "results.csv").rows
    assert {(r["on"], r["rounds"]) for r in rows if r["sampler"] != "odometry"} == {("estimate", 2)}
    timed[timed.index("closest-first,rho")] = "lio-sam"
    timed[timed.index(str(tmp_path / "t"))] = str(tmp_path / "b")
    bad = subprocess.run(timed, capture_output=True, text=True, check=False)
    assert bad.returncode == 2 and 'rounds_order="time"' in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1


def test_verifier_models_follow_their_laws():
    """The three named models: the steep one falls to half at 8 m, the blind one does not
    depend on the distance up to its range and fails beyond; 10 % wrong matches on each."""
    d = np.array([0.0, 8.0, 20.0, 39.0, 41.0])
    aware, steep, blind = (ev.VERIFIER_MODELS[k] for k in ("distance-aware", "steep", "blind"))
    assert aware == ev.Verifier()
    np.testing.assert_allclose(aware.success_probability(d)[[0, 2]], [0.95, 0.475])
    np.testing.assert_allclose(steep.success_probability(d)[[0, 1]], [0.95, 0.475])
    np.testing.assert_allclose(blind.success_probability(d), [0.8, 0.8, 0.8, 0.8, 0.0])
    np.testing.assert_allclose(blind.sigmas(d)[0], 0.1)
    # Counted: a blind model's matches do not thin out with the distance.
    n = 4000
    poses = ev.Poses.from_positions(
        np.arange(n + 1.0), np.c_[np.r_[0.0, np.full(n, 30.0)], np.zeros(n + 1)]
    )
    matches = blind.verify(poses, np.zeros(n, np.int64), np.arange(1, n + 1), seed=3)
    assert abs(len(matches) / n - 0.8) < 0.03
    wrong = dataclasses.replace(steep, outlier_rate=0.1).verify(
        poses, np.zeros(n, np.int64), np.arange(1, n + 1), seed=3
    )
    assert abs(wrong.wrong.sum() / n - 0.1) < 0.02
    with pytest.raises(il.InvalidParameterError):
        ev.Verifier(max_range_m=0.0)
    with pytest.raises(il.InvalidParameterError, match="unknown verifier model"):
        ev.evaluate(circuit(), gamma=10.0, verifier="perfect")


def test_rounds_choose_on_the_estimate_they_are_given():
    """A round's candidates move when the estimate moves; a pair is tried once; the budget is
    spent in the rounds; the inflation of gamma shrinks as the estimate settles."""
    reference = circuit(laps=3.0, n=600)
    drifted = ev.DriftModel(heading_bias_rad_per_m=2e-3).simulate(reference, seed=0).estimate
    rule = ev.CandidateRule("closest-then-spread", 60, 8.0, on="estimate", rounds=3)
    on_reference, on_drifted = ev.Rounds(rule, seed=1), ev.Rounds(rule, seed=1)
    a = set(zip(*(x.tolist() for x in on_reference.choose(reference)), strict=True))
    b = set(zip(*(x.tolist() for x in on_drifted.choose(drifted)), strict=True))
    assert len(a) == len(b) == 20
    assert len(a & b) < 10, f"{len(a & b)} of 20 pairs the same on a drifted estimate"
    # The next rounds: no pair again, the budget spent, gamma back towards 1x once settled.
    on_reference.update(drifted, reference)
    assert on_reference.gamma_inflation == rule.gamma_inflation  # moved by far more than gamma
    chosen = set(a)
    while not on_reference.done:
        i, j = on_reference.choose(reference)
        new = set(zip(i.tolist(), j.tolist(), strict=True))
        assert not new & chosen
        chosen |= new
        on_reference.update(reference, reference)
        assert on_reference.gamma_inflation == 1.0
    assert len(chosen) == on_reference.tried == 60
    with pytest.raises(il.InvalidParameterError):
        ev.CandidateRule("rho", 10, 8.0, rounds=2)


def test_rounds_in_time_order_choose_each_stretch_of_the_path_in_turn():
    """Rounds in time order: round r's pairs all have their later pose in the r-th of R
    stretches of equal path length (measured here by summing the steps), each pair a revisit
    of the estimate it was chosen on (within the inflated gamma, 4 gamma of path apart), the
    round's whole share spent on them, the budget spent in all, and the same pairs for the
    same seed."""
    reference = circuit(laps=3.0, n=600)
    drifted = ev.DriftModel(heading_bias_rad_per_m=2e-3).simulate(reference, seed=0).estimate
    rule = ev.CandidateRule(
        "nearest-then-uniform", 60, 8.0, on="estimate", rounds=3, rounds_order="time"
    )
    steps = np.linalg.norm(np.diff(drifted.positions, axis=0), axis=1)
    path = np.r_[0.0, np.cumsum(steps)]
    edges = path[-1] * np.array([0.0, 1 / 3, 2 / 3, np.inf])

    def drive(seed: int) -> list[list[tuple[int, int]]]:
        rounds, estimate, chosen = ev.Rounds(rule, seed=seed), drifted, []
        while not rounds.done:
            inflation = rounds.gamma_inflation
            i, j = rounds.choose(estimate)
            r = rounds.round - 1
            assert len(i) == 20, f"round {r}: {len(i)} pairs of a share of 20"
            assert (i < j).all()
            assert ((path[j] >= edges[r]) & (path[j] < edges[r + 1])).all(), f"round {r}"
            d = np.linalg.norm(estimate.positions[i] - estimate.positions[j], axis=1)
            assert (d <= 8.0 * inflation + 1e-9).all() and (path[j] - path[i] >= 32.0).all()
            chosen.append(list(zip(i.tolist(), j.tolist(), strict=True)))
            rounds.update(estimate, reference)
            estimate = reference  # the next rounds choose on the corrected estimate
        assert rounds.tried == sum(map(len, chosen)) == 60
        return chosen

    first = drive(seed=1)
    assert drive(seed=1) == first
    assert drive(seed=2) != first
    # Later rounds reach back: some pairs tie the stretch to the earlier laps.
    assert any(path[i] < edges[1] for i, _ in first[2])
    for bad in (
        dict(rounds_order="lap"),
        dict(sampler="lio-sam", rounds_order="time"),
        dict(source="detections", rounds_order="time"),
    ):
        with pytest.raises(il.InvalidParameterError, match="rounds_order"):
            dataclasses.replace(rule, **bad)
    # The evaluation hands the order to its rules: a baseline in time-ordered rounds refuses.
    with pytest.raises(il.InvalidParameterError, match="rounds_order"):
        ev.evaluate(
            reference,
            gamma=8.0,
            samplers=["lio-sam"],
            budgets=[10],
            seeds=[0],
            on=["estimate"],
            rounds=3,
            rounds_order="time",
            include_odometry=False,
        )


@needs_gtsam
def test_rounds_in_the_evaluation_match_more_of_their_candidates():
    """Candidates in rounds on a drifted estimate: later rounds choose on the corrected
    estimate, so more of the same budget are revisits the verifier accepts, and the map is no
    worse than with all of them chosen at once."""
    reference = circuit(laps=3.0, n=600)
    odometry = ev.DriftModel(heading_bias_rad_per_m=5e-4).simulate(reference, seed=0)
    ate, matched = {}, {}
    for rounds in (1, 3):
        rule = ev.CandidateRule("closest-then-spread", 60, 8.0, on="estimate", rounds=rounds)
        estimate, matches, pairs = ev.evaluate_one(reference, odometry, rule, seed=0)
        assert matches is not None and len(pairs[0]) <= 60
        ate[rounds], matched[rounds] = ev.ate(reference, estimate), len(matches)
    assert matched[3] > matched[1] + 5, matched
    assert ate[3] <= ate[1], ate
