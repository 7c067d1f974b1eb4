"""``inexact_loops.evaluate``, the fleet case: several sessions, one map.

With exact odometry and exact matches the multi-session pose graph returns the references,
whatever the sessions' unknown starts; without a match between sessions they stay apart (each
where its own odometry frame puts it); true matches between sessions lower the joint error and
the inter-session error; the errors follow their definitions (checked on displacements whose
errors are known exactly); the initial placement follows the majority of the matches; and
``loops-eval --fleet`` writes its tables and plot. The back-end tests skip, saying why, when
GTSAM is not installed.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import inexact_loops as il
from inexact_loops import evaluate as ev
from inexact_loops.evaluate import _fleet, _poses

#: The back-end tests: skipped, saying why, without GTSAM (conftest.py).
needs_gtsam = pytest.mark.gtsam

EXACT = ev.DriftModel(
    translation_sigma_m_per_sqrt_m=0.0,
    rotation_sigma_rad_per_sqrt_m=0.0,
    heading_bias_rad_per_m=0.0,
)


def circuit(
    centre: tuple[float, float],
    phase: float,
    *,
    laps: float = 1.5,
    n: int = 300,
    radius: float = 40.0,
) -> ev.Poses:
    """``laps`` times round a circle, starting at angle ``phase``, a pose a second."""
    angle = phase + np.linspace(0.0, laps * 2 * np.pi, n)
    xy = np.asarray(centre) + radius * np.c_[np.cos(angle), np.sin(angle)]
    return ev.Poses.from_positions(np.arange(n, dtype=float), xy)


def three_sessions(dim: int = 2) -> dict[str, ev.Poses]:
    """Three sessions round overlapping circles, far from the origin and from each other's
    starts: what each session's own odometry frame (its start at the origin) gets wrong."""
    sessions = {
        "north": circuit((300.0, 200.0), 0.0),
        "east": circuit((330.0, 190.0), 2.0),
        "south": circuit((310.0, 160.0), 4.0),
    }
    if dim == 3:
        sessions = {
            n: ev.Poses(p.timestamps, _poses._lift3(p.matrices)) for n, p in sessions.items()
        }
    return sessions


def joint_pairs(references: dict[str, ev.Poses], rule: ev.FleetRule, seed: int = 0):
    return ev.choose_fleet_candidates(references, rule, seed=seed)


def starts_of(references: dict[str, ev.Poses]) -> np.ndarray:
    return np.r_[0, np.cumsum([len(p) for p in references.values()])]


def split(i: np.ndarray, j: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which pairs are within a session, which between two."""
    between = np.searchsorted(starts, i, side="right") != np.searchsorted(starts, j, side="right")
    return ~between, between


def joint_poses(references: dict[str, ev.Poses]) -> ev.Poses:
    m = np.concatenate([p.matrices for p in references.values()])
    return ev.Poses(np.arange(len(m), dtype=float), m)


def subset(matches: ev.Matches, keep: np.ndarray) -> ev.Matches:
    return ev.Matches(
        matches.i[keep],
        matches.j[keep],
        matches.relative[keep],
        matches.translation_sigma_m[keep],
        matches.rotation_sigma_rad[keep],
        matches.wrong[keep],
        int(keep.sum()),
    )


def drifted_sessions(
    *, seed: int, heading_bias_rad_per_m: float, budget: int, dim: int = 2
) -> tuple[dict[str, ev.Poses], dict[str, ev.Odometry], tuple[np.ndarray, np.ndarray]]:
    """:func:`three_sessions`, their odometry simulated with ``seed`` and a heading bias, and
    ``budget`` candidate pairs of closest-first (gamma 5 m) in fleet indices."""
    refs = three_sessions(dim)
    odos = ev.simulate_fleet_odometry(
        refs, seed=seed, drift=ev.DriftModel(heading_bias_rad_per_m=heading_bias_rad_per_m)
    )
    return refs, odos, joint_pairs(refs, ev.FleetRule("closest-first", budget, 5.0))


# ---------------------------------------------------------------------------------------------
# Keys, errors and placement
# ---------------------------------------------------------------------------------------------


@needs_gtsam
def test_session_keys_are_gtsams_symbols_as_loops_fleet_writes_them():
    import gtsam

    assert ev.session_key(0, 5) == gtsam.symbol("a", 5) == 6989586621679009797
    assert ev.session_key(25, 7) == gtsam.symbol("z", 7)
    assert ev.session_key(26, 3) == gtsam.symbol("A", 3)
    assert ev.session_key(51, 0) == gtsam.symbol("Z", 0)
    with pytest.raises(il.InvalidParameterError, match="52 at most"):
        ev.session_key(52, 0)


def test_fleet_errors_follow_their_definitions():
    refs = three_sessions()
    exact = list(refs.values())
    errors = ev.fleet_errors(refs, exact, overlap_m=5.0)
    assert errors.ate_m == pytest.approx(0.0, abs=1e-9)
    assert errors.inter_m == pytest.approx(0.0, abs=1e-9) and errors.inter_pairs > 20
    # "east" shifted by 3 m along x: its own shape is right (session ATE 0), the relative pose
    # of every pair of it with another session is 3 m off, and the joint ATE is not 0.
    shifted = exact[1].matrices.copy()
    shifted[:, 0, 2] += 3.0
    moved = [exact[0], ev.Poses(exact[1].timestamps, shifted), exact[2]]
    errors = ev.fleet_errors(refs, moved, overlap_m=5.0)
    assert errors.session_ate_m["east"] == pytest.approx(0.0, abs=1e-9)
    assert errors.session_rms_m == pytest.approx(0.0, abs=1e-9)
    assert 0.5 < errors.ate_m < 3.0
    # Pairs involving east: error exactly 3 m; pairs of north with south: 0.
    i, j = _fleet._inter_pairs(list(refs.items()), 5.0)
    starts = starts_of(refs)
    east = (np.searchsorted(starts, i, side="right") == 2) | (
        np.searchsorted(starts, j, side="right") == 2
    )
    expected = math.sqrt(9.0 * east.mean())
    assert errors.inter_m == pytest.approx(expected, rel=1e-9)
    # The joint ATE is the single-trajectory ATE of the sessions one after another.
    assert errors.ate_m == pytest.approx(
        ev.ate(joint_poses(refs), joint_poses(dict(zip(refs, moved, strict=True)))), rel=1e-12
    )
    # Pairs: every pose of a with its nearest pose of b, when within the radius (brute force).
    from scipy.spatial.distance import cdist

    count = 0
    names = list(refs)
    for a in range(3):
        for b in range(a + 1, 3):
            d = cdist(refs[names[a]].positions, refs[names[b]].positions)
            count += int((d.min(axis=1) <= 5.0).sum())
    assert count == errors.inter_pairs


def test_place_sessions_follows_the_majority_of_matches():
    refs = three_sessions()
    odos = ev.simulate_fleet_odometry(refs, seed=0, drift=EXACT)
    estimates = [o.estimate for o in odos.values()]
    joint = joint_poses(refs)
    i, j = joint_pairs(refs, ev.FleetRule("closest-first", 60, 5.0, between_only=True))
    right = ev.Matches.exact(joint, i, j)
    # Four wrong matches, each claiming another place (identity relative pose).
    k = np.arange(4)
    wrong = ev.Matches(
        np.r_[right.i, i[k]],
        np.r_[right.j, j[k] + 40],
        np.r_[right.relative, np.tile(np.eye(3), (4, 1, 1))],
        np.r_[right.translation_sigma_m, [0.05] * 4],
        np.r_[right.rotation_sigma_rad, [0.005] * 4],
        np.r_[right.wrong, [True] * 4],
        len(i) + 4,
    )
    offsets, placed = ev.place_sessions(estimates, wrong)
    assert placed == [True, True, True]
    for offset, estimate, ref in zip(offsets, estimates, refs.values(), strict=True):
        np.testing.assert_allclose(offset @ estimate.matrices, ref.matrices, atol=1e-6)
    # Without matches between sessions, every session keeps its own frame.
    within, _ = split(i, j, starts_of(refs))
    offsets, placed = ev.place_sessions(estimates, subset(right, within))
    assert placed == [True, False, False]
    assert all(np.array_equal(o, np.eye(3)) for o in offsets)


def test_simulated_sessions_start_in_their_own_frames_but_the_anchor():
    refs = three_sessions()
    odos = ev.simulate_fleet_odometry(refs, seed=3, anchor="east")
    np.testing.assert_array_equal(odos["east"].start, refs["east"].matrices[0])
    for name in ("north", "south"):
        np.testing.assert_array_equal(odos[name].start, np.eye(3))
    # Each session its own seed: the same model gives the sessions different noise.
    steps = [np.diff(o.estimate.positions, axis=0)[:20] for o in odos.values()]
    assert not np.allclose(steps[0], steps[1])
    with pytest.raises(il.InvalidParameterError, match="anchor 'west' is not a session"):
        ev.simulate_fleet_odometry(refs, seed=0, anchor="west")


# ---------------------------------------------------------------------------------------------
# The multi-session pose graph
# ---------------------------------------------------------------------------------------------


@needs_gtsam
@pytest.mark.parametrize("dim", [2, 3])
def test_exact_odometry_and_matches_return_the_references(dim):
    refs = three_sessions(dim)
    odos = ev.simulate_fleet_odometry(refs, seed=0, drift=EXACT)
    # The sessions but the anchor start at the origin of their own frames: far off.
    assert ev.fleet_errors(refs, [o.estimate for o in odos.values()], overlap_m=5.0).ate_m > 50
    rule = ev.FleetRule("closest-first", 80, 5.0)
    verifier = ev.Verifier(
        success_max=1.0,
        translation_sigma_m=1e-4,
        translation_sigma_per_m=0.0,
        rotation_sigma_rad=1e-5,
        rotation_sigma_rad_per_m=0.0,
    )
    for kernel in ("cauchy", "gnc"):
        estimates, matches, (i, j), placed = ev.evaluate_fleet_one(
            refs, odos, rule, seed=0, verifier=verifier, backend=ev.BackEnd(kernel=kernel)
        )
        assert matches is not None and placed == 3
        assert split(matches.i, matches.j, starts_of(refs))[1].sum() > 5
        errors = ev.fleet_errors(refs, estimates, overlap_m=5.0)
        assert errors.ate_m < 1e-3 and errors.inter_m < 1e-3, errors
        # Each session within millimetres: the matches' rotation noise (1e-5 rad), 300 m from
        # the origin, moves a session by about one, as the pairs chosen happen to weigh it.
        for ref, est in zip(refs.values(), estimates, strict=True):
            assert ev.ate(ref, est, align=False) < 2e-3


@needs_gtsam
def test_without_a_match_between_sessions_the_sessions_stay_apart():
    refs, odos, (i, j) = drifted_sessions(seed=1, heading_bias_rad_per_m=5e-4, budget=150)
    matches = ev.Matches.exact(joint_poses(refs), i, j)
    within, between = split(i, j, starts_of(refs))
    assert within.sum() > 10 and between.sum() > 10
    alone = ev.fleet_errors(refs, ev.optimize_fleet(list(odos.values())), overlap_m=5.0)
    inside = ev.fleet_errors(
        refs, ev.optimize_fleet(list(odos.values()), subset(matches, within)), overlap_m=5.0
    )
    # Closures within the sessions fix each session's shape, not where it lies: the sessions
    # but the anchor stay in their own frames, hundreds of metres off.
    assert inside.session_rms_m < 0.3 * alone.session_rms_m
    assert inside.inter_m > 100 and alone.inter_m > 100
    assert inside.ate_m > 50
    estimates = ev.optimize_fleet(list(odos.values()), subset(matches, within))
    for name, estimate in zip(list(refs)[1:], estimates[1:], strict=True):
        # Its first pose stays near where its own odometry frame starts, the origin (the weak
        # prior holds it there; closures within the session reshape it by a metre or so), far
        # from its true start.
        assert np.linalg.norm(estimate.positions[0]) < 5.0, name
        assert np.linalg.norm(refs[name].positions[0]) > 300.0, name


@needs_gtsam
@pytest.mark.parametrize("dim", [2, 3])
def test_true_matches_between_sessions_lower_the_joint_error(dim):
    refs, odos, (i, j) = drifted_sessions(seed=2, heading_bias_rad_per_m=5e-4, budget=150, dim=dim)
    matches = ev.Matches.exact(joint_poses(refs), i, j)
    within, between = split(i, j, starts_of(refs))
    sessions = list(odos.values())
    inside = ev.fleet_errors(
        refs, ev.optimize_fleet(sessions, subset(matches, within)), overlap_m=5.0
    )
    few = ev.fleet_errors(
        refs,
        ev.optimize_fleet(
            sessions, subset(matches, within | (between & (np.cumsum(between) <= 3)))
        ),
        overlap_m=5.0,
    )
    every = ev.fleet_errors(refs, ev.optimize_fleet(sessions, matches), overlap_m=5.0)
    assert every.ate_m < 0.01 * inside.ate_m, (every, inside)
    assert every.inter_m < 0.01 * inside.inter_m
    assert every.inter_m < few.inter_m < inside.inter_m
    assert every.ate_m < 0.5


@needs_gtsam
def test_a_wrong_match_between_sessions_is_down_weighted():
    refs, odos, (i, j) = drifted_sessions(seed=4, heading_bias_rad_per_m=2e-4, budget=120)
    right = ev.Matches.exact(joint_poses(refs), i, j, sigma_m=0.05, sigma_rad=0.005)
    _, between = split(i, j, starts_of(refs))
    k = np.flatnonzero(between)[:3]
    claim = np.tile(np.eye(3), (3, 1, 1))
    claim[:, 0, 2] = 15.0  # 15 m off
    wrong = ev.Matches(
        np.r_[right.i, i[k]],
        np.r_[right.j, j[k]],
        np.r_[right.relative, claim],
        np.r_[right.translation_sigma_m, [0.05] * 3],
        np.r_[right.rotation_sigma_rad, [0.005] * 3],
        np.r_[right.wrong, [True] * 3],
        len(i) + 3,
    )
    sessions = list(odos.values())
    clean = ev.fleet_errors(refs, ev.optimize_fleet(sessions, right), overlap_m=5.0)
    gauss = ev.fleet_errors(
        refs, ev.optimize_fleet(sessions, wrong, ev.BackEnd(kernel="gauss")), overlap_m=5.0
    )
    robust = ev.fleet_errors(refs, ev.optimize_fleet(sessions, wrong), overlap_m=5.0)
    assert gauss.inter_m > 0.5
    assert robust.inter_m < 0.2 * gauss.inter_m, (robust, gauss)
    assert robust.inter_m < clean.inter_m + 0.1


@needs_gtsam
def test_evaluate_fleet_grid_and_its_files(tmp_path):
    fleet = il.urban_fleet(vehicles=3, duration_s=240.0, seed=5)
    results = ev.evaluate_fleet(
        fleet,
        gamma=20.0,
        samplers=["closest-first", "one", "lio-sam"],
        budgets=[10, 60],
        seeds=[0, 1],
        outlier_rates=(0.0, 0.2),
        keyframe_m=10.0,
        dataset="fleet",
    )
    rows = results.rows
    # Per seed: the odometry row; per outlier rate: 2 samplers x 2 between_only + lio-sam (all
    # components only), at 2 budgets.
    assert len(rows) == 2 * (1 + 2 * (2 * 2 + 1) * 2)
    assert len(results.sessions) == 3 * len(rows)
    assert all(r["candidates"] <= r["budget"] for r in rows if r["sampler"] != "odometry")
    assert all(r["between_candidates"] == r["candidates"] for r in rows if r["between_only"])
    assert all(r["wrong"] == 0 for r in rows if r["outlier_rate"] == 0.0)
    odometry = {r["seed"]: r["ate_m"] for r in rows if r["sampler"] == "odometry"}
    assert all(r["odometry_ate_m"] == odometry[r["seed"]] for r in rows)
    summary = results.summary()
    cf = [
        s
        for s in summary
        if s["sampler"] == "closest-first"
        and s["between_only"]
        and s["budget"] == 60
        and s["outlier_rate"] == 0.0
    ]
    assert len(cf) == 1 and cf[0]["seeds"] == 2
    assert cf[0]["ate_median_m"] < 0.1 * cf[0]["odometry_ate_m"]
    assert cf[0]["inter_q25_m"] <= cf[0]["inter_median_m"] <= cf[0]["inter_q75_m"]
    results.to_csv(tmp_path / "rows.csv", tmp_path / "sessions.csv")
    again = ev.FleetResults.from_csv(tmp_path / "rows.csv")
    assert again.rows == [{k: r[k] for k in ev.FLEET_COLUMNS} for r in rows]
    assert len((tmp_path / "sessions.csv").read_text().splitlines()) == 1 + len(results.sessions)
    results.to_json(tmp_path / "rows.json")
    document = json.loads((tmp_path / "rows.json").read_text())
    assert document["settings"]["sessions"] == {
        n: len(p) for n, p in ev.fleet_references(fleet, keyframe_m=10.0).items()
    }
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    for metric in ("ate", "inter", "session_ate"):
        ax = ev.plot_fleet_error_vs_matches(results, metric=metric, select={"outlier_rate": 0.0})
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "odometry alone" in labels and any("between sessions only" in t for t in labels)
    import matplotlib.pyplot as plt

    plt.close("all")


def test_fleet_rules_and_inputs_are_checked():
    with pytest.raises(il.InvalidParameterError, match="not with between_only"):
        ev.FleetRule("lio-sam", 10, 5.0, between_only=True)
    with pytest.raises(il.InvalidParameterError, match="unknown sampler"):
        ev.FleetRule("nearest", 10, 5.0)
    refs = three_sessions()
    mixed = refs | {"up": three_sessions(3)["north"]}
    with pytest.raises(il.InvalidParameterError, match="mix SE\\(2\\) and SE\\(3\\)"):
        ev.simulate_fleet_odometry(mixed, seed=0)
    odos = ev.simulate_fleet_odometry(refs, seed=0)
    with pytest.raises(il.InvalidParameterError, match="no odometry for session"):
        ev.evaluate_fleet_one(refs, {"north": odos["north"]}, None, seed=0)


@needs_gtsam
def test_loops_eval_fleet_command(tmp_path):
    files = []
    for name, poses in three_sessions().items():
        path = tmp_path / f"{name}.tum"
        poses.to_tum(path)
        files.append(str(path))
    out = tmp_path / "eval"
    cmd = [
        sys.executable,
        "-m",
        "inexact_loops.evaluate",
        "--fleet",
        *files,
        "--gamma",
        "5",
        "--budgets",
        "10,40",
        "--seeds",
        "2",
        "--samplers",
        "closest-first,rho",
        "--anchor",
        "east",
        "--out",
        str(out),
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    rows = ev.FleetResults.from_csv(out / "results.csv").rows
    assert {r["sampler"] for r in rows} == {"odometry", "closest-first", "rho"}
    assert len(rows) == 2 * (1 + 2 * 2 * 2)
    assert {r["between_only"] for r in rows} == {False, True}
    document = json.loads((out / "results.json").read_text())
    assert document["settings"]["anchor"] == "east"
    assert (out / "sessions.csv").exists() and (out / "error_vs_matches.png").stat().st_size > 1000
    assert "closest-first" in done.stdout and "inter" in done.stdout
    # Options a fleet does not take: one line, exit code 2.
    for extra, message in (
        (["--source", "detections"], "not with --source detections"),
        (["--odometry", files[0]], "--fleet takes no --odometry"),
        (["--rounds-order", "time"], "not with --rounds-order time"),
    ):
        bad = subprocess.run(
            [*cmd[:-1], str(tmp_path / "x"), *extra], capture_output=True, text=True, check=False
        )
        assert bad.returncode == 2 and message in bad.stderr
        assert len(bad.stderr.strip().splitlines()) == 1
    # On the estimates, in rounds, every start known.
    rounds = subprocess.run(
        [*cmd[:-1], str(tmp_path / "r"), "--on", "both", "--rounds", "2", "--known-starts"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert rounds.returncode == 0, rounds.stderr
    rows = ev.FleetResults.from_csv(tmp_path / "r" / "results.csv").rows
    conditions = {(r["starts"], r["on"], r["rounds"]) for r in rows if r["sampler"] != "odometry"}
    assert conditions == {("known", "reference", 1), ("known", "estimate", 2)}
    same = subprocess.run(
        [*cmd[:4], files[0], files[0], *cmd[4 + len(files) : -1], str(tmp_path / "y")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert same.returncode == 2 and "two sessions are named 'north'" in same.stderr


@needs_gtsam
def test_mulran_kaist_drives_as_a_fleet(data_dir):
    folder = data_dir / "mulran_kaist"
    paths = {
        "kaist01": folder / "kaist01_localization_poses01_seq02asmap.txt",
        "kaist02": folder / "kaist02_localization_poses02_seq02asmap.txt",
    }
    refs = {n: ev.Poses.read(p, rate_hz=10.0) for n, p in paths.items()}
    refs = {n: p.take(p.keyframes(10.0)) for n, p in refs.items()}
    odos = ev.simulate_fleet_odometry(refs, seed=0)
    rule = ev.FleetRule("closest-first", 100, 15.0, between_only=True)
    estimates, matches, (i, j), placed = ev.evaluate_fleet_one(refs, odos, rule, seed=0)
    assert placed == 2 and matches is not None and len(matches) > 50
    alone = ev.fleet_errors(refs, [o.estimate for o in odos.values()], overlap_m=15.0)
    merged = ev.fleet_errors(refs, estimates, overlap_m=15.0)
    # The two drives cover the same campus: hundreds of keyframe pairs between them.
    assert merged.inter_pairs > 300
    assert merged.ate_m < 0.1 * alone.ate_m and merged.inter_m < 0.1 * alone.inter_m


# ---------------------------------------------------------------------------------------------
# Candidates in rounds on the sessions' estimates
# ---------------------------------------------------------------------------------------------


def pair_set(chosen: tuple[np.ndarray, ...]) -> set[tuple[int, int, int, int]]:
    return set(zip(*(x.tolist() for x in chosen), strict=True))


def drifted_estimates(seed: int = 0) -> tuple[dict[str, ev.Poses], list[ev.Poses]]:
    """:func:`three_sessions` and their odometry's estimates, drifted by a heading bias, all
    starting at their references' first poses (one frame)."""
    refs = three_sessions()
    odos = ev.simulate_fleet_odometry(
        refs,
        seed=seed,
        drift=ev.DriftModel(heading_bias_rad_per_m=2e-3),
        known_starts=True,
    )
    return refs, [odos[n].estimate for n in refs]


def test_fleet_rounds_choose_on_the_estimates_they_are_given():
    """A round's pairs move when the estimates move: on drifted estimates most of them are not
    the pairs the references give; pairs join two sessions only where they share a frame."""
    refs, drifted = drifted_estimates()
    on_refs = [refs[n] for n in refs]
    assert np.median(np.linalg.norm(drifted[2].positions - on_refs[2].positions, axis=1)) > 10
    rule = ev.FleetRule("closest-first", 90, 5.0, on="estimate", rounds=3)
    a = pair_set(ev.FleetRounds(rule, seed=1).choose(on_refs))
    b = pair_set(ev.FleetRounds(rule, seed=1).choose(drifted))
    assert len(a) == len(b) == 30
    assert len(a & b) < 15, f"{len(a & b)} of 30 pairs the same on drifted estimates"
    assert any(p[0] != p[2] for p in a), "no pair between sessions in one frame"
    # Each session in a frame of its own: pairs within sessions only; two sharing one: between
    # those two only.
    alone = ev.FleetRounds(rule, seed=1).choose(on_refs, frames=[0, 1, 2])
    assert len(alone[0]) and (alone[0] == alone[2]).all()
    two = pair_set(ev.FleetRounds(rule, seed=1).choose(on_refs, frames=[5, 5, 7]))
    assert {(p[0], p[2]) for p in two if p[0] != p[2]} == {(0, 1)}
    # Pairs are (session_a, i, session_b, j): session_a <= session_b, i < j within a session,
    # indices within their sessions.
    for sa, i, sb, j in a | b:
        assert sa <= sb and (sa < sb or i < j)
        assert 0 <= i < len(on_refs[sa]) and 0 <= j < len(on_refs[sb])


def test_fleet_rounds_are_seeded_never_exceed_the_budget_nor_repeat_a_pair():
    """The same seed and estimates give the same rounds; across rounds on moving estimates no
    pair comes twice and the pairs never exceed the budget, which the rounds spend; gamma's
    inflation shrinks as the estimates settle."""
    refs, drifted = drifted_estimates()
    on_refs = [refs[n] for n in refs]
    rule = ev.FleetRule("closest-first", 100, 5.0, on="estimate", rounds=4)
    # Arrays of matrices are sessions too.
    assert pair_set(ev.FleetRounds(rule, seed=0).choose([p.matrices for p in on_refs])) == (
        pair_set(ev.FleetRounds(rule, seed=0).choose(on_refs))
    )

    def drive(seed: int) -> tuple[list[set], ev.FleetRounds]:
        rounds, estimates, chosen = ev.FleetRounds(rule, seed=seed), drifted, []
        while not rounds.done:
            chosen.append(pair_set(rounds.choose(estimates)))
            rounds.update(estimates, on_refs)
            estimates = on_refs
        return chosen, rounds

    first, rounds = drive(3)
    again, _ = drive(3)
    assert first == again
    assert first != drive(4)[0]
    assert [len(c) for c in first] == [25, 25, 25, 25]
    union = set().union(*first)
    assert len(union) == sum(len(c) for c in first) == rounds.tried == 100
    assert rounds.round == 4 and rounds.gamma_inflation == 1.0
    assert all(len(x) == 0 for x in rounds.choose(on_refs))  # done: nothing more
    # A budget above the pairs there are: every round offers only pairs not tried before.
    small = ev.FleetRule("closest-first", 100000, 5.0, on="estimate", rounds=3)
    rounds, seen, total = ev.FleetRounds(small, seed=0), set(), 0
    while not rounds.done:
        new = pair_set(rounds.choose(on_refs))
        assert not new & seen
        seen |= new
        total += len(new)
    assert total == len(seen) == rounds.tried <= 100000


def test_fleet_rounds_check_their_sessions():
    """Bad input is one line naming the session: an empty session, sessions of another number
    or size than the first round's, frames of another length."""
    refs, drifted = drifted_estimates()
    rule = ev.FleetRule("closest-first", 30, 5.0, on="estimate", rounds=3)
    empty = np.zeros((0, 3, 3))
    cases = [
        (lambda r: r.choose([drifted[0], empty, drifted[2]]), "session 1 has no pose"),
        (lambda r: r.choose([drifted[0], drifted[1], np.zeros((5, 4))]), "session 2: "),
        (lambda r: r.choose([]), "no session"),
        (lambda r: r.choose(drifted, frames=[0, 0]), "session 2"),
    ]
    for call, text in cases:
        with pytest.raises(il.InvalidParameterError, match=text) as caught:
            call(ev.FleetRounds(rule, seed=0))
        assert len(str(caught.value).splitlines()) == 1
    rounds = ev.FleetRounds(rule, seed=0)
    rounds.choose(drifted)
    for call, text in [
        (lambda: rounds.choose(drifted[:2]), "session 2 is missing"),
        (lambda: rounds.choose([*drifted, drifted[0]]), "session 3 is new"),
        (lambda: rounds.choose([drifted[0], drifted[1].take(range(10)), drifted[2]]), "session 1"),
        (lambda: rounds.update(drifted, drifted[:2]), "session 2 is missing"),
    ]:
        with pytest.raises(il.InvalidParameterError, match=text) as caught:
            call()
        assert len(str(caught.value).splitlines()) == 1
    with pytest.raises(il.InvalidParameterError, match='on="estimate"'):
        ev.FleetRounds(ev.FleetRule("closest-first", 30, 5.0), seed=0)
    with pytest.raises(il.InvalidParameterError, match="rounds = 2"):
        ev.FleetRule("closest-first", 30, 5.0, rounds=2)


def test_old_fleet_rows_read_as_candidates_on_the_references(tmp_path):
    """Rows written before the starts, on and rounds columns read as what they were: unknown
    starts, candidates on the references, one round."""
    old = [c for c in ev.FLEET_COLUMNS if c not in ("starts", "on", "rounds")]
    row = {c: 0 for c in old} | {"dataset": "d", "sampler": "one", "between_only": "False"}
    path = tmp_path / "old.csv"
    path.write_text(",".join(old) + "\n" + ",".join(str(row[c]) for c in old) + "\n")
    (read,) = ev.FleetResults.from_csv(path).rows
    assert (read["starts"], read["on"], read["rounds"]) == ("unknown", "reference", 1)


@needs_gtsam
def test_fleet_rounds_in_the_evaluation_match_more_of_their_candidates(tmp_path):
    """On drifted estimates with known starts, later rounds choose on the corrected estimates:
    more of the same budget are revisits the verifier accepts, and the map is no worse than
    with all of them chosen at once. With unknown starts nothing ties the sessions: no pair
    between them. The grid's rows say where and in how many rounds, and survive CSV."""
    refs = three_sessions()
    odos = ev.simulate_fleet_odometry(
        refs, seed=0, drift=ev.DriftModel(heading_bias_rad_per_m=1e-3), known_starts=True
    )
    ate, matched = {}, {}
    for rounds in (1, 3):
        rule = ev.FleetRule("closest-first", 60, 5.0, on="estimate", rounds=rounds)
        estimates, matches, pairs, _ = ev.evaluate_fleet_one(
            refs, odos, rule, seed=0, known_starts=True
        )
        assert matches is not None and len(pairs[0]) <= 60
        ate[rounds] = ev.fleet_errors(refs, estimates, overlap_m=5.0).ate_m
        matched[rounds] = len(matches)
    assert matched[3] > matched[1], matched
    assert ate[3] <= ate[1] * 1.05, ate
    unknown = ev.simulate_fleet_odometry(refs, seed=0)
    rule = ev.FleetRule("closest-first", 60, 5.0, on="estimate", rounds=3)
    _, _, (i, j), placed = ev.evaluate_fleet_one(refs, unknown, rule, seed=0)
    within, between = split(i, j, starts_of(refs))
    assert within.all() and placed == 1
    results = ev.evaluate_fleet(
        refs,
        gamma=5.0,
        samplers=["closest-first"],
        budgets=[30],
        seeds=[0],
        between_only=(False,),
        on=("reference", "estimate"),
        rounds=2,
        known_starts=True,
    )
    conditions = [(r["starts"], r["on"], r["rounds"]) for r in results.rows]
    assert conditions == [("known", "", 0), ("known", "reference", 1), ("known", "estimate", 2)]
    results.to_csv(tmp_path / "rows.csv")
    again = ev.FleetResults.from_csv(tmp_path / "rows.csv").rows
    assert again == [{k: r[k] for k in ev.FLEET_COLUMNS} for r in results.rows]


@needs_gtsam
@pytest.mark.parametrize("on", ["reference", "estimate"])
def test_known_starts_hold_every_session_where_its_start_is(on):
    """With known starts every session's first pose is known in the map's frame, as with a fix
    at the start: the back end holds each there, and matches between sessions, wrong ones too,
    do not move a session's start. Here every match is wrong (the verifier's outlier rate 1):
    the map is the odometry alone's, each session's first pose its reference's (to 1 cm), and
    its joint ATE no larger. Before, the wrong matches placed the sessions (a weak prior at the
    guess they made) and moved them by metres."""
    refs = three_sessions()
    odos = ev.simulate_fleet_odometry(refs, seed=3, known_starts=True)
    alone, _, _, _ = ev.evaluate_fleet_one(refs, odos, None, seed=3, known_starts=True)
    rule = ev.FleetRule("closest-first", 12, 5.0, between_only=True, on=on)
    estimates, matches, (i, j), _ = ev.evaluate_fleet_one(
        refs, odos, rule, seed=3, verifier=ev.Verifier(outlier_rate=1.0), known_starts=True
    )
    _, between = split(i, j, starts_of(refs))
    assert matches is not None and matches.wrong.all() and between.sum() >= 4
    for reference, estimate in zip(refs.values(), estimates, strict=True):
        assert np.linalg.norm(estimate.positions[0] - reference.positions[0]) < 0.01
    wrong = ev.fleet_errors(refs, estimates, overlap_m=5.0).ate_m
    assert wrong <= ev.fleet_errors(refs, alone, overlap_m=5.0).ate_m * 1.01 + 0.01
