"""Every class of the package pickles and unpickles to an equal object, in every pickle protocol
and across processes (multiprocessing and concurrent.futures with the spawn start method); a
corrupt or forged state raises ``pickle.UnpicklingError`` naming what is wrong, never a crash.
Fleet results and pose graphs travel with their fleet or trajectory, which pickle writes once
for all the objects pickled together."""

from __future__ import annotations

import copy
import functools
import multiprocessing
import pickle
import struct
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


def assert_round_trips(
    values: dict, protocol: int, *, unhashed: tuple[str, ...] = (), same_repr: bool = False
) -> None:
    """Each of ``values`` pickled with ``protocol`` reads back as an equal object of its type
    with its hash (but those named in ``unhashed``) and, with ``same_repr``, its repr; a deep
    copy is equal too."""
    for name, value in values.items():
        back = pickle.loads(pickle.dumps(value, protocol=protocol))
        assert type(back) is type(value), name
        assert back == value, name
        assert name in unhashed or hash(back) == hash(value), name
        assert copy.deepcopy(value) == value, name
        if same_repr:
            assert repr(back) == repr(value), name


@pytest.mark.parametrize("protocol", range(2, pickle.HIGHEST_PROTOCOL + 1))
def test_every_class_round_trips_to_an_equal_object(results, protocol):
    assert_round_trips(results, protocol, unhashed=("separation",))


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


def msgpack(value: object) -> bytes:
    """MessagePack of strings, small non-negative ints, floats and lists (enough to write a
    state as the package does, for a state no build of today writes)."""
    if isinstance(value, str):
        data = value.encode()
        assert len(data) < 32
        return bytes([0xA0 | len(data)]) + data
    if isinstance(value, bool) or not isinstance(value, (int, float, list)):
        raise TypeError(value)
    if isinstance(value, int):
        assert 0 <= value < 128
        return bytes([value])
    if isinstance(value, float):
        return b"\xcb" + struct.pack(">d", value)
    if len(value) < 16:
        head = bytes([0x90 | len(value)])
    else:
        head = b"\xdd" + len(value).to_bytes(4, "big")
    return head + b"".join(msgpack(item) for item in value)


def test_loops_keep_their_closest_pairs_positions_only(results):
    traj, loops = results["trajectory"], results["loops"]
    table = loops.components
    for side in "ij":
        at = table[f"closest_{side}"]
        for k, axis in enumerate("xyz"):
            np.testing.assert_array_equal(table[f"closest_{side}_{axis}"], traj.positions[at, k])
    # The second argument of the pickle: six numbers a component, not three a pose.
    _, (_, closest) = loops.__reduce__()
    assert len(closest) < 60 * len(table["id"]) + 100 < 24 * len(traj)


def test_loops_pickled_with_every_pose_position_read_as_before(results):
    # Earlier versions passed every pose's position as the second argument.
    traj, loops = results["trajectory"], results["loops"]
    restore, (state, _) = loops.__reduce__()
    every = msgpack(["inexact_loops", 2, "LoopsPositions", traj.positions.tolist()])
    back = restore(state, every)
    assert back == loops
    for key, column in loops.components.items():
        np.testing.assert_array_equal(back.components[key], column, err_msg=key)
    short = msgpack(["inexact_loops", 2, "LoopsPositions", traj.positions[:-1].tolist()])
    with pytest.raises(pickle.UnpicklingError, match="its positions are not one per pose"):
        restore(state, short)
    few = msgpack(["inexact_loops", 2, "LoopsClosestPositions", [[0.0] * 6]])
    with pytest.raises(pickle.UnpicklingError, match="not one per component"):
        restore(state, few)


def state_of(value: object) -> tuple[object, bytes]:
    # A Loops found on a trajectory passes its poses' positions as a second argument.
    restore, (state, *_) = value.__reduce__()
    assert isinstance(state, bytes)
    return restore, state


def test_corrupt_and_forged_states_are_clear_errors(results):
    loops = results["loops"]
    restore, state = state_of(loops)
    assert restore(state) == loops
    # The header: a MessagePack array of 4, "inexact_loops", the format (2), the class name.
    assert state[:15] == b"\x94\xadinexact_loops" and state[15] == 2
    cases = {
        state[: len(state) // 2]: "cannot unpickle Loops: ",
        b"not a pickle": "cannot unpickle Loops: not a pickled inexact_loops state",
        state[:15]
        + b"\x03"
        + state[16:]: "it was pickled in state format 3 (by another version of "
        "inexact_loops); this version reads formats 1 to 2",
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
    assert_flipped_bytes_are_caught(value, restore, state, seed=15)


def assert_flipped_bytes_are_caught(
    value: object,
    restore,
    state: bytes,
    *,
    seed: int,
    one_line: bool = False,
    tables: tuple[str, ...] = (),
) -> None:
    """``restore`` of ``state`` (the pickled state of ``value``) with one of 300 random bytes
    past its header flipped either raises an UnpicklingError naming the class (of one line with
    ``one_line``) or reads back as a valid object of its type, whose repr and ``tables`` work;
    at least one flip is caught."""
    rng = np.random.default_rng(seed)
    outcomes = {"error": 0, "object": 0}
    positions, values = rng.integers(16, len(state), 300), rng.integers(0, 256, 300)
    for position, byte in zip(positions, values, strict=True):
        forged = state[:position] + bytes([byte]) + state[position + 1 :]
        try:
            back = restore(forged)
        except pickle.UnpicklingError as error:
            assert str(error).startswith(f"cannot unpickle {type(value).__name__}: "), error
            if one_line:
                assert "\n" not in str(error)
            outcomes["error"] += 1
        else:
            # A change the checks cannot see (a time, a distance) reads back as a valid object.
            assert type(back) is type(value)
            repr(back)
            for table in tables:
                if hasattr(back, table):
                    getattr(back, table)
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


# ---------------------------------------------------------------------------------------------
# Fleets, tiled fleet loops and pose graphs
# ---------------------------------------------------------------------------------------------


def write_tum(path: Path, t: np.ndarray, xyz: np.ndarray) -> Path:
    q = np.c_[np.zeros((len(t), 3)), np.ones(len(t))]
    np.savetxt(path, np.c_[t, xyz, q])
    return path


@pytest.fixture(scope="module")
def fleet_results(tmp_path_factory) -> dict[str, object]:
    from inexact_loops.dask import find_fleet_loops_dask

    fleet = il.urban_fleet(vehicles=3, duration_s=300.0, seed=2)
    loops = il.find_fleet_loops(fleet, gamma=30.0)
    folder = tmp_path_factory.mktemp("fleet")
    # Two sessions read from files, for a metric and on a plane: what a Fleet keeps beside poses.
    x = np.linspace(0.0, 40.0, 81)
    paths = {
        "monday": write_tum(folder / "monday.tum", np.arange(81.0), np.c_[x, 0 * x, 0 * x]),
        "tuesda": write_tum(
            folder / "tuesda.tum", 500 + np.arange(81.0), np.c_[x[::-1], 1 + 0 * x, 0 * x]
        ),
    }
    read = il.Fleet(paths, metric="se3(rotation_weight_m_per_rad=10)")
    planar = il.Fleet(paths, axes=(0, 1))
    sessions = {name: fleet.session(name) for name in fleet.names}
    graph_path = folder / "square.g2o"
    graph_path.write_text(
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 1.5708\nVERTEX_SE2 2 1 1 3.1416\n"
        "EDGE_SE2 0 1 1 0 1.5708 10 0 0 10 0 100\nEDGE_SE2 1 2 1 0 1.5708 10 0 0 10 0 100\n"
        "EDGE_SE2 2 0 1 1 -3.1416 5 0 0 5 0 50\n"
    )
    graph3_path = folder / "two.g2o"
    graph3_path.write_text(
        "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
        "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1\n"
    )
    chain_path = folder / "edges.graph"
    chain_path.write_text(
        "EDGE2 0 1 1 0 1.5707963267948966\nEDGE2 1 2 1 0 0\nEDGE2 2 0 -1 1 -1.5\n"
    )
    with pytest.warns(il.DeadReckoningWarning):
        chained = il.read_pose_graph(chain_path, chain_edges=True)
    return {
        "fleet": fleet,
        "read fleet": read,
        "planar fleet": planar,
        "fleet loops": loops,
        "paper fleet loops": il.find_fleet_loops(fleet, gamma=30.0, separation=None),
        "read fleet loops": il.find_fleet_loops(read, gamma=2.0),
        "fleet samples": il.sample_fleet(loops, "closest-first", budget=80, seed=1),
        "between samples": il.sample_fleet(loops, "one", budget=40, seed=2, between_only=True),
        "baseline fleet samples": il.sample_fleet(loops, "lio-sam", budget=40, seed=3),
        # FleetRun holds the run's connection; its tables pickle as TiledFleetLoops.
        "tiled fleet loops": find_fleet_loops_dask(sessions, 30.0, block=500).loops,
        "pose graph": il.read_pose_graph(graph_path, metric="se2(rotation_weight_m_per_rad=2)"),
        "3-D pose graph": il.read_pose_graph(graph3_path),
        "chained pose graph": chained,
    }


@pytest.mark.parametrize("protocol", range(2, pickle.HIGHEST_PROTOCOL + 1))
def test_fleet_classes_and_pose_graphs_round_trip_to_equal_objects(fleet_results, protocol):
    assert_round_trips(fleet_results, protocol, same_repr=True)


def test_fleet_equality_compares_the_whole_value(fleet_results):
    r = fleet_results
    assert r["fleet"] != r["read fleet"] and r["read fleet"] != r["planar fleet"]
    assert r["fleet loops"] != r["paper fleet loops"]
    assert r["fleet samples"] != r["between samples"]
    assert r["fleet"] != r["fleet"].joint and r["fleet loops"] != r["fleet loops"].loops
    assert r["pose graph"] != r["3-D pose graph"]
    again = il.urban_fleet(vehicles=3, duration_s=300.0, seed=2)
    assert again == r["fleet"] and hash(again) == hash(r["fleet"])
    assert il.find_fleet_loops(again, gamma=30.0) == r["fleet loops"]


def test_objects_pickled_together_share_their_fleet_again(fleet_results):
    r = fleet_results
    fleet, loops, samples = pickle.loads(
        pickle.dumps([r["fleet"], r["fleet loops"], r["fleet samples"]])
    )
    assert loops.fleet is fleet and samples.fleet is fleet
    graph = pickle.loads(pickle.dumps(r["pose graph"]))
    assert graph.trajectory == r["pose graph"].trajectory
    assert graph.trajectory.metric_name == r["pose graph"].trajectory.metric_name


def test_unpickled_fleet_results_work_as_the_originals(fleet_results):
    r = fleet_results
    fleet = pickle.loads(pickle.dumps(r["read fleet"]))
    assert fleet.names == ["monday", "tuesda"]
    assert fleet.session("tuesda").metric_name == r["read fleet"].session("tuesda").metric_name
    assert il.find_fleet_loops(fleet, gamma=2.0) == r["read fleet loops"]
    loops = pickle.loads(pickle.dumps(r["fleet loops"]))
    for key, column in r["fleet loops"].components.items():
        np.testing.assert_array_equal(loops.components[key], column, err_msg=key)
    np.testing.assert_array_equal(loops.overlap_matrix(), r["fleet loops"].overlap_matrix())
    assert loops.pruning == r["fleet loops"].pruning and loops.loops == r["fleet loops"].loops
    again = il.sample_fleet(loops, "closest-first", budget=80, seed=1)
    assert again == r["fleet samples"]
    samples = pickle.loads(pickle.dumps(r["between samples"]))
    for key, column in r["between samples"].table.items():
        np.testing.assert_array_equal(samples.table[key], column, err_msg=key)
    tiled = pickle.loads(pickle.dumps(r["tiled fleet loops"]))
    for key, column in r["tiled fleet loops"].components.items():
        np.testing.assert_array_equal(tiled.components[key], column, err_msg=key)
    np.testing.assert_array_equal(tiled.overlap_matrix(), r["tiled fleet loops"].overlap_matrix())
    graph = pickle.loads(pickle.dumps(r["pose graph"]))
    for key, column in r["pose graph"].edges.items():
        np.testing.assert_array_equal(graph.edges[key], column, err_msg=key)
    found = il.find_loops(graph.trajectory, gamma=5.0, separation=None)
    assert graph.edge_verdicts(found) == graph.edge_verdicts(found)
    assert graph.chained is False and pickle.loads(pickle.dumps(r["chained pose graph"])).chained


def test_fleet_results_cross_process_boundaries():
    from concurrent.futures import ProcessPoolExecutor

    fleets = [il.urban_fleet(vehicles=2, duration_s=200.0, seed=s) for s in (4, 5)]
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(2, mp_context=context) as pool:
        found = list(pool.map(functools.partial(il.find_fleet_loops, gamma=30.0), fleets))
        samples = list(
            pool.map(functools.partial(il.sample_fleet, sampler="rho", budget=30, seed=0), found)
        )
    assert found == [il.find_fleet_loops(f, gamma=30.0) for f in fleets]
    assert samples == [il.sample_fleet(f, "rho", budget=30, seed=0) for f in found]
    assert [s.fleet for s in samples] == fleets


def test_fleet_results_echo_through_a_spawned_pool(fleet_results):
    values = list(fleet_results.values())
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        echoed = pool.map(copy.copy, values)
    assert echoed == values


def test_corrupt_and_forged_fleet_states_are_clear_errors(fleet_results):
    r = fleet_results
    restore, fleet_state = state_of(r["read fleet"])
    assert restore(fleet_state) == r["read fleet"]
    forged_names = fleet_state.replace(b"\xa6tuesda", b"\xa6monday", 1)
    forged_metric = fleet_state.replace(b"se3(rotation", b"so3(rotation", 1)
    assert forged_names != fleet_state and forged_metric != fleet_state
    cases = {
        fleet_state[: len(fleet_state) // 2]: "cannot unpickle Fleet: ",
        forged_names: "cannot unpickle Fleet: ",
        forged_metric: "cannot unpickle Fleet: session ",
        fleet_state[:15] + b"\x03" + fleet_state[16:]: "it was pickled in state format 3",
        state_of(r["fleet"].joint)[1]: "cannot unpickle Fleet: the state is of a Trajectory",
    }
    for forged, message in cases.items():
        with pytest.raises(pickle.UnpicklingError) as error:
            restore(forged)
        assert message in str(error.value)
        assert "\n" not in str(error.value)

    # States that come with the wrong object, or with another fleet's.
    restore, (state, fleet) = r["fleet loops"].__reduce__()
    assert restore(state, fleet) == r["fleet loops"]
    with pytest.raises(pickle.UnpicklingError, match="its fleet is a Trajectory, not a Fleet"):
        restore(state, r["fleet"].joint)
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle FleetLoops: invalid saved"):
        restore(state, r["read fleet"])
    restore, (state, fleet) = r["fleet samples"].__reduce__()
    assert restore(state, fleet) == r["fleet samples"]
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle FleetSamples: the samples"):
        restore(state, r["read fleet"])
    with pytest.raises(pickle.UnpicklingError, match="the state is of a FleetLoops"):
        restore(r["fleet loops"].__reduce__()[1][0], fleet)
    restore, (state, trajectory) = r["pose graph"].__reduce__()
    assert restore(state, trajectory) == r["pose graph"]
    with pytest.raises(pickle.UnpicklingError, match="its trajectory has 2 poses"):
        restore(state, r["3-D pose graph"].trajectory)
    with pytest.raises(pickle.UnpicklingError, match="its trajectory is a Fleet, not a Trajectory"):
        restore(state, r["fleet"])
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle PoseGraph: "):
        restore(state[:-3], trajectory)


@pytest.mark.parametrize(
    "name", ["read fleet", "fleet loops", "fleet samples", "tiled fleet loops", "pose graph"]
)
def test_flipped_bytes_of_fleet_states_give_an_equal_object_a_valid_one_or_an_error(
    fleet_results, name
):
    value = fleet_results[name]
    restore, args = value.__reduce__()
    state, companions = args[0], args[1:]
    assert_flipped_bytes_are_caught(
        value,
        lambda forged: restore(forged, *companions),
        state,
        seed=20,
        one_line=True,
        tables=("components", "table", "edges", "vertices"),
    )


# ---------------------------------------------------------------------------------------------
# Forged states the checks used to let through, and every failure an UnpicklingError
# ---------------------------------------------------------------------------------------------


def float_at(value: float) -> bytes:
    """A float64 as MessagePack writes it."""
    import struct

    return b"\xcb" + struct.pack(">d", value)


def test_a_time_cell_wider_than_its_timestamps_is_refused():
    # Cells of 0.5, 1.5, 3 and 2 s: one of 1e308 s would make every area infinite.
    traj = il.Trajectory([0.0, 1.0, 3.0, 7.0], np.array([[0.0, 0], [0.5, 0], [0.1, 0], [0.2, 0]]))
    loops = il.find_loops(traj, gamma=1.0, separation=None)
    for value in (loops, traj):
        restore, state = state_of(value)
        assert state.count(float_at(1.5)) == 1
        for width in (1e308, 1.6, -0.5):
            forged = state.replace(float_at(1.5), float_at(width))
            with pytest.raises(
                pickle.UnpicklingError, match=r"the time cell of pose 1 is .* s, outside 0 to 1.5 s"
            ):
                restore(forged)
    assert pickle.loads(pickle.dumps(loops)).loop_area(0.0, 7.0) == loops.loop_area(0.0, 7.0)


def test_a_metric_name_that_is_no_metric_is_refused():
    traj = il.Trajectory([0.0, 1.0, 2.0], np.array([[0.0, 0], [0.5, 0], [0.1, 0]]))
    loops = il.find_loops(traj, gamma=1.0, separation=None)
    restore, state = state_of(loops)
    for forged_name in (b"\xa1x", b"\xa9euclidea_", b"\xa3se3"):
        forged = state.replace(b"\xa9euclidean", forged_name, 1)
        with pytest.raises(pickle.UnpicklingError, match="cannot unpickle Loops: .*its metric"):
            restore(forged)

    # A callable's loops name it custom(NAME), and pickle.
    def manhattan(a, b):
        return float(np.abs(a - b).sum())

    custom = il.find_loops(traj, gamma=1.0, metric=manhattan, separation=None)
    assert custom.metric_name == "custom(manhattan)"
    assert pickle.loads(pickle.dumps(custom)) == custom
    with pytest.raises(il.InvalidParameterError, match=r"custom\(manhattan\).*pass metric="):
        il.sample(custom, "one", budget=1, seed=0, trajectory=traj)


def test_every_failure_of_unpickling_is_an_unpickling_error():
    # A separation out of range, and the tile objects' bytes (their constructors raise
    # InvalidParameterError when called directly).
    restore, state = state_of(il.Separation(path=2.0))
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle Separation: .*path"):
        restore(state.replace(float_at(2.0), float_at(-2.0)))
    fleet = il.urban_fleet(vehicles=2, duration_s=120.0, seed=2)
    blocks = il.tiles.session_blocks(fleet.session(fleet.names[0]), block=50)
    restore, (data, metric) = blocks.__reduce__()
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle SessionBlocks: "):
        restore(data[:-5], metric)
    with pytest.raises(
        pickle.UnpicklingError, match="cannot unpickle SessionBlocks: unknown metric"
    ):
        restore(data, "x")
    with pytest.raises(il.InvalidParameterError):
        il.tiles.SessionBlocks(data[:-5], metric)
    session = fleet.session(fleet.names[0])
    tile = il.tiles.plan_tiles([blocks], gamma=30.0)[0]
    summary = il.tiles.scan_tile(tile, session, starts=(0, 0), gamma=30.0)
    assert pickle.loads(pickle.dumps(summary)).to_bytes() == summary.to_bytes()
    restore, (data,) = summary.__reduce__()
    with pytest.raises(pickle.UnpicklingError, match="cannot unpickle TileSummary: "):
        restore(data[: len(data) // 2])
