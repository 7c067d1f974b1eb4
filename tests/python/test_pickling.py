"""Every class of the package pickles and unpickles to an equal object, in every pickle protocol
and across processes (multiprocessing with the spawn start method); a corrupt or forged state
raises ``pickle.UnpicklingError`` naming what is wrong, never a crash."""

from __future__ import annotations

import copy
import functools
import multiprocessing
import pickle
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il


@pytest.fixture(scope="module")
def results() -> dict[str, object]:
    traj = il.urban_drive(duration_s=900.0, seed=3)
    loops = il.find_loops(traj, gamma=40.0)
    paper = il.find_loops(traj, gamma=40.0, separation=None)
    detections = il.draw_detections(paper, rate=0.01, seed=1)
    scored = il.Detections([0.0, 5.0, 30.0], [9.0, 1.0, 60.0], scores=[0.5, 0.25, 0.75])
    clusters = il.cluster_detections(detections, epsilon_s=20.0)
    samples = il.sample(loops, "rho", budget=200, seed=0, trajectory=traj)
    s = np.sqrt(0.5)
    se3 = il.Trajectory.se3(
        [0.0, 1.0, 2.0],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, s, s], [0.0, 0.0, 1.0, 0.0]],
    )
    return {
        "trajectory": traj,
        "se3 trajectory": se3,
        "loops": loops,
        "paper loops": paper,
        "separation": il.Separation(path=24.0, time_s=30.0),
        "detections": detections,
        "scored detections": scored,
        "clusters": clusters,
        "samples": samples,
        "cluster samples": il.sample(clusters, "rho-dispersed", budget=50, seed=2),
        "quality": il.sample_quality(samples, loops),
        "plane grid": il.PlaneGrid(traj, 100),
    }


@pytest.mark.parametrize("protocol", range(2, pickle.HIGHEST_PROTOCOL + 1))
def test_every_class_round_trips_to_an_equal_object(results, protocol):
    for name, value in results.items():
        back = pickle.loads(pickle.dumps(value, protocol=protocol))
        assert type(back) is type(value), name
        assert back == value, name
        assert name == "separation" or hash(back) == hash(value), name
        assert copy.deepcopy(value) == value, name


def test_equality_compares_the_whole_value(results):
    loops, paper = results["loops"], results["paper loops"]
    assert loops != paper
    assert loops != 3 and loops != results["trajectory"]
    assert results["detections"] != results["scored detections"]
    # Equal values found twice are equal, and hash alike (usable as dict keys, as before).
    again = il.find_loops(results["trajectory"], gamma=40.0)
    assert again == loops and hash(again) == hash(loops)
    assert len({loops, again, paper}) == 2


def test_unpickled_results_work_as_the_originals(results):
    traj, loops = results["trajectory"], results["loops"]
    back = pickle.loads(pickle.dumps(loops))
    np.testing.assert_array_equal(back.loop_duration(), loops.loop_duration())
    for key, column in loops.components.items():
        np.testing.assert_array_equal(back.components[key], column, err_msg=key)
    again = il.sample(back, "rho", budget=200, seed=0, trajectory=pickle.loads(pickle.dumps(traj)))
    assert again == results["samples"]
    read = pickle.loads(pickle.dumps(results["se3 trajectory"]))
    assert read.metric_name == results["se3 trajectory"].metric_name


def test_a_trajectory_read_for_a_metric_keeps_it(tmp_path: Path):
    path = tmp_path / "poses.tum"
    q = np.c_[np.zeros((50, 3)), np.ones(50)]
    np.savetxt(path, np.c_[np.arange(50.0), np.c_[np.arange(50.0), np.zeros((50, 2))], q])
    traj = il.read_trajectory(path, metric="se3(rotation_weight_m_per_rad=10)")
    back = pickle.loads(pickle.dumps(traj))
    assert back == traj and back.metric_name == traj.metric_name


def test_results_cross_process_boundaries_with_spawn(results):
    traj = results["trajectory"]
    other = il.urban_drive(duration_s=600.0, seed=9)
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        found = pool.map(functools.partial(il.find_loops, gamma=40.0), [traj, other])
        echoed = pool.map(copy.copy, list(results.values()))
    assert found == [results["loops"], il.find_loops(other, gamma=40.0)]
    assert echoed == list(results.values())


def state_of(value: object) -> tuple[object, bytes]:
    restore, (state,) = value.__reduce__()
    assert isinstance(state, bytes)
    return restore, state


def test_corrupt_and_forged_states_are_clear_errors(results):
    loops = results["loops"]
    restore, state = state_of(loops)
    assert restore(state) == loops
    # The header: a MessagePack array of 4, "inexact_loops", the format (1), the class name.
    assert state[:15] == b"\x94\xadinexact_loops" and state[15] == 1
    cases = {
        state[: len(state) // 2]: "cannot unpickle Loops: ",
        b"not a pickle": "cannot unpickle Loops: not a pickled inexact_loops state",
        state[:15]
        + b"\x02"
        + state[16:]: "it was pickled in state format 2 (by another version of "
        "inexact_loops); this version reads format 1",
        state_of(results["samples"])[1]: "cannot unpickle Loops: the state is of a Samples",
    }
    for forged, message in cases.items():
        with pytest.raises(pickle.UnpicklingError) as error:
            restore(forged)
        assert message in str(error.value)
        assert "\n" not in str(error.value)


@pytest.mark.parametrize("name", ["loops", "samples", "clusters", "trajectory", "plane grid"])
def test_flipped_bytes_give_an_equal_object_a_valid_one_or_an_unpickling_error(results, name):
    value = results[name]
    restore, state = state_of(value)
    rng = np.random.default_rng(15)
    outcomes = {"error": 0, "object": 0}
    positions, values = rng.integers(16, len(state), 300), rng.integers(0, 256, 300)
    for position, byte in zip(positions, values, strict=True):
        forged = state[:position] + bytes([byte]) + state[position + 1 :]
        try:
            back = restore(forged)
        except pickle.UnpicklingError as error:
            assert str(error).startswith(f"cannot unpickle {type(value).__name__}: "), error
            outcomes["error"] += 1
        else:
            # A change the checks cannot see (a time, a distance) reads back as a valid object.
            assert type(back) is type(value)
            repr(back)
            outcomes["object"] += 1
    assert outcomes["error"] > 0, outcomes


def test_a_forged_state_that_does_not_fit_together_names_the_part(results):
    # A sample's pose pair past the end of its trajectory: the MessagePack of the state holds the
    # pose count right after the row list; a pair index is forged to point past it.
    samples = results["samples"]
    restore, state = state_of(samples)
    poses = len(results["trajectory"])
    last_pair = int(samples.j[-1])
    needle = b"\xcd" + last_pair.to_bytes(2, "big")  # a uint16, as MessagePack writes it
    assert poses > 255 and needle in state
    position = state.rindex(needle)
    forged = state[:position] + b"\xcd" + (poses + 5).to_bytes(2, "big") + state[position + 3 :]
    with pytest.raises(
        pickle.UnpicklingError, match=r"invalid saved Samples: sample \d+ has the pair"
    ):
        restore(forged)
