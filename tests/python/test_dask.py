"""Fleets from tiles, in this process and on a Dask ``LocalCluster`` of 2 worker processes, against
the single-machine fleet API (:func:`inexact_loops.find_fleet_loops`): components, session pairs
and the overlap matrix identical (areas to a relative 1e-10) for 1, 2 and 7 tiles per session
pair, on random and adversarial fleets written to TUM files and on MulRan KAIST 01/02; a worker
SIGKILLed during a run changes nothing; samples drawn from the runs the scans kept equal those
drawn from rescans (every draw a cache hit, every one a miss). Also: the tile objects pickle as
their bytes, corrupt bytes fail clearly, and without ``client=`` Dask is not imported.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pickle
import random
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il
import inexact_loops.dask as il_dask
from inexact_loops.dask import find_fleet_loops_dask, local_client

TILES_PER_PAIR = (1, 2, 7)


def write_tum(path: Path, t: np.ndarray, xy: np.ndarray) -> Path:
    """A TUM file (t x y z qx qy qz qw) of planar poses."""
    n = len(t)
    rows = np.c_[t, xy, np.zeros(n), np.zeros((n, 3)), np.ones(n)]
    np.savetxt(path, rows, fmt="%.9f")
    return path


def random_fleet(folder: Path, seed: int) -> list[Path]:
    """3-4 random walks in a 30 m square, each its own clock: they cross each other often."""
    rng = np.random.default_rng(seed)
    paths = []
    for k in range(rng.integers(3, 5)):
        n = int(rng.integers(40, 120))
        steps = rng.normal(0.0, 1.0, (n, 2))
        xy = np.cumsum(steps, axis=0) + rng.uniform(-10, 10, 2)
        t = 100.0 * k + np.cumsum(rng.uniform(0.05, 0.3, n))
        paths.append(write_tum(folder / f"walk{k}.tum", t, xy))
    return paths


def adversarial_fleet(folder: Path) -> list[Path]:
    """Two identical sessions, one the other's time reversal, a parked one on the route, a
    parked one far away and a loop far from all others."""
    n = 90
    s = np.arange(n) / n * 2 * math.pi * 1.5
    loop = np.c_[10 * np.cos(s), 6 * np.sin(2 * s)]
    t = 0.5 * np.arange(n)
    return [
        write_tum(folder / "loop.tum", t, loop),
        write_tum(folder / "again.tum", t + 1e4, loop),
        write_tum(folder / "reversed.tum", t + 2e4, loop[::-1]),
        write_tum(folder / "parked.tum", 0.1 * np.arange(60), np.tile([10.0, 0.0], (60, 1))),
        write_tum(folder / "parked_far.tum", np.arange(40.0), np.tile([1e4, 1e4], (40, 1))),
        write_tum(folder / "far.tum", t, loop + [5e3, -5e3]),
    ]


def assert_same(tiled: il.TiledFleetLoops, fleet: il.FleetLoops) -> None:
    """Every column of the tables equal; areas and densities to a relative 1e-10."""
    assert tiled.names == fleet.names
    ours, theirs = tiled.components, fleet.components
    assert list(ours) == list(theirs)
    for column in theirs:
        if column.startswith("closest_") and column[-2:] in ("_x", "_y", "_z"):
            assert np.isnan(ours[column]).all(), column  # a tile merge keeps no poses
        elif column == "area_s2":
            np.testing.assert_allclose(ours[column], theirs[column], rtol=1e-10, atol=1e-12)
        else:
            np.testing.assert_array_equal(ours[column], theirs[column], err_msg=column)
    ours, theirs = tiled.session_pairs(), fleet.session_pairs()
    assert list(ours) == list(theirs)
    for column in theirs:
        if column in ("area_s2", "density"):
            np.testing.assert_allclose(ours[column], theirs[column], rtol=1e-10, atol=1e-12)
        else:
            np.testing.assert_array_equal(ours[column], theirs[column], err_msg=column)
    np.testing.assert_allclose(tiled.overlap_matrix(), fleet.overlap_matrix(), rtol=1e-10)
    np.testing.assert_array_equal(tiled.between_sessions(), fleet.between_sessions())


def blocks_for(paths: list[Path], per_pair: int, **read) -> int:
    """The block giving ``per_pair`` row (and column) blocks to the longest session."""
    longest = max(len(il.read_trajectory(p, **read)) for p in paths)
    return max(1, -(-longest // per_pair))


@pytest.fixture(scope="module")
def client():
    pytest.importorskip(
        "distributed",
        reason="dask.distributed is not installed: pip install '.[dask]' in a checkout",
    )
    with local_client() as client:
        yield client


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_fleets_on_the_cluster_equal_the_fleet(tmp_path, client, seed):
    paths = random_fleet(tmp_path, seed)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    assert len(fleet.between_sessions()) > 0, "the walks must meet for the test to mean much"
    for per_pair in TILES_PER_PAIR:
        block = blocks_for(paths, per_pair)
        tiled = find_fleet_loops_dask(paths, 1.5, client=client, block=block, fan_in=3)
        assert_same(tiled, fleet)


@pytest.mark.filterwarnings("ignore::inexact_loops.DiagonalBrokenWarning")
@pytest.mark.parametrize("separation", ["auto", None])
def test_adversarial_fleets_on_the_cluster_equal_the_fleet(tmp_path, client, separation):
    paths = adversarial_fleet(tmp_path)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5, separation=separation)
    for per_pair in TILES_PER_PAIR:
        block = blocks_for(paths, per_pair)
        tiled = find_fleet_loops_dask(
            paths, 1.5, client=client, block=block, separation=separation, fan_in=2
        )
        assert_same(tiled, fleet)


@pytest.mark.parametrize("per_pair", TILES_PER_PAIR)
def test_in_process_equals_the_fleet(tmp_path, per_pair):
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 7)
    sessions = dict(zip([p.stem for p in paths], paths, strict=True))
    separation = il.Separation(path=3.0, time_s=2.0)
    fleet = il.find_fleet_loops(il.Fleet(sessions), gamma=1.5, separation=separation)
    block = blocks_for(paths, per_pair)
    tiled = find_fleet_loops_dask(sessions, 1.5, block=block, separation=separation)
    assert_same(tiled, fleet)
    # Trajectories in memory, without a client, as well.
    trajectories = {name: il.read_trajectory(p) for name, p in sessions.items()}
    assert_same(find_fleet_loops_dask(trajectories, 1.5, block=block, separation=separation), fleet)


@pytest.mark.filterwarnings("ignore::inexact_loops.DiagonalBrokenWarning")
@pytest.mark.parametrize("where", ["in-process", "cluster"])
def test_the_chosen_block_gives_the_fleet(tmp_path, request, monkeypatch, where):
    """``block=None`` cuts each session into blocks of the smallest unit first, then joins
    them (``SessionBlocks.coarsened``) to the longest session: the tiles are fewer and the
    answer is the fleet's, samples included."""
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 3)
    client = request.getfixturevalue("client") if where == "cluster" else None
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    longest = max(len(il.read_trajectory(p)) for p in paths)
    unit = 7
    monkeypatch.setattr(il_dask, "DEFAULT_BLOCK", unit)
    monkeypatch.setattr(il_dask, "MAX_AUTO_BLOCK", 10_000)
    chosen = find_fleet_loops_dask(paths, 1.5, client=client)
    assert chosen.stats["block"] == unit * -(-longest // unit) > unit
    assert_same(chosen, fleet)
    fine = find_fleet_loops_dask(paths, 1.5, client=client, block=unit)
    assert chosen.stats["tiles"] < fine.stats["tiles"]
    expected = il.sample_fleet(fleet, "rho", budget=40, seed=5).table
    got = chosen.sample("rho", budget=40, seed=5)
    for column in ("i", "j", "component"):
        np.testing.assert_array_equal(got[column], expected[column], err_msg=column)
    # The largest block caps the choice.
    monkeypatch.setattr(il_dask, "MAX_AUTO_BLOCK", 2 * unit + 1)
    capped = find_fleet_loops_dask(paths, 1.5, client=client)
    assert capped.stats["block"] == 2 * unit
    assert_same(capped, fleet)


def test_coarsened_blocks_are_cut_as_asked_and_pickle():
    rng = np.random.default_rng(4)
    xy = np.cumsum(rng.normal(0.0, 1.0, (101, 2)), axis=0)
    drive = il.Trajectory(np.arange(101.0), xy)
    fine = il.tiles.session_blocks(drive, block=6)
    for factor in (1, 2, 5, 17, 40):
        coarse = fine.coarsened(factor)
        assert (coarse.block, len(coarse), coarse.poses) == (
            6 * factor,
            -(-101 // (6 * factor)),
            101,
        )
        again = pickle.loads(pickle.dumps(coarse))
        assert again.to_bytes() == coarse.to_bytes()
    with pytest.raises(il.InvalidParameterError, match="factor"):
        fine.coarsened(0)


MULRAN = {
    "kaist01": Path("mulran_kaist") / "kaist01_localization_poses01_seq02asmap.txt",
    "kaist02": Path("mulran_kaist") / "kaist02_localization_poses02_seq02asmap.txt",
}


def test_mulran_on_the_cluster_equals_the_fleet(data_dir, client):
    paths = [data_dir / path for path in MULRAN.values()]
    for path in paths:
        if not path.is_file():
            pytest.skip(f"MulRan KAIST not found at {path.resolve()}")
    read = {"format": "kitti", "rate_hz": 10.0}  # no timestamps: 10 Hz lidar
    fleet = il.find_fleet_loops(il.Fleet(paths, **read), gamma=10.0)
    assert len(fleet.between_sessions()) > 0
    for per_pair in (2, 7):
        block = blocks_for(paths, per_pair, **read)
        tiled = find_fleet_loops_dask(paths, 10.0, client=client, block=block, **read)
        assert_same(tiled, fleet)


class KillWorkerAfter:
    """A scheduler plugin that SIGKILLs the worker process holding the ``after``-th finished
    task whose key starts with ``prefix`` (once), and counts the finishes of such tasks: a
    task that finished twice was rerun."""

    name = "kill-worker-after"

    def __init__(self, prefix: str, after: int) -> None:
        self.prefix, self.after = prefix, after
        self.finished, self.killed = 0, None
        self.finishes: dict[str, int] = {}

    async def start(self, scheduler) -> None:
        self.scheduler = scheduler

    def transition(self, key, start, finish, *args, **kwargs) -> None:
        if finish != "memory" or not str(key).startswith(self.prefix):
            return
        self.finishes[str(key)] = self.finishes.get(str(key), 0) + 1
        if self.killed is not None:
            return
        self.finished += 1
        if self.finished >= self.after:
            # The result just made is on this worker alone: no task has fetched it yet.
            worker = next(iter(self.scheduler.tasks[key].who_has))
            self.killed = worker.pid
            os.kill(worker.pid, signal.SIGKILL)


def test_a_worker_killed_mid_run_changes_nothing(tmp_path, client):
    distributed = pytest.importorskip("distributed")
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 3)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    block = blocks_for(paths, 7)
    before = set(client.run(os.getpid).values())
    plugin = type(
        "KillWorkerAfterPlugin",
        (KillWorkerAfter, distributed.diagnostics.plugin.SchedulerPlugin),
        {},
    )("scan-tiles-", 10)
    client.register_plugin(plugin)
    try:
        tiled = find_fleet_loops_dask(paths, 1.5, client=client, block=block, fan_in=2)
        killed, finishes = client.run_on_scheduler(
            lambda dask_scheduler: (
                dask_scheduler.plugins["kill-worker-after"].killed,
                dask_scheduler.plugins["kill-worker-after"].finishes,
            )
        )
    finally:
        client.unregister_scheduler_plugin("kill-worker-after")
    assert killed in before, "a worker of the cluster was killed during the run"
    assert len(finishes) > 10, "tiles were left to scan after the kill"
    assert max(finishes.values()) >= 2, "the killed worker's tiles were scanned again"
    assert_same(tiled, fleet)
    client.wait_for_workers(2, timeout=60)
    assert killed not in set(client.run(os.getpid).values()), "the nanny started a new worker"


class Hung(BaseException):
    """A run past its deadline (a BaseException, so that no ``except Exception`` of the code
    under test swallows it)."""


@contextlib.contextmanager
def deadline(seconds: int, what: str) -> Iterator[None]:
    """Fails the block when it runs past ``seconds`` (SIGALRM in the main thread): a run that
    hangs fails the test instead of hanging it."""

    def expired(signum, frame) -> None:
        raise Hung(f"{what}: still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def test_tasks_stranded_when_the_only_worker_dies_run_on_its_restart(tmp_path, monkeypatch):
    """A cluster of one worker, SIGKILLed after its first scan task: the run's tasks, which
    prefer that worker, find no running worker and wait in Dask's no-worker state, which Dask
    never reconsiders for the worker the nanny starts at a new address. The run sends them
    there, and gives the fleet's answer."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(il_dask, "NO_WORKER_TIMEOUT_S", 90.0)
    paths = adversarial_fleet(tmp_path)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    block = blocks_for(paths, 7)
    with local_client(workers=1) as own:
        own.wait_for_workers(1, timeout=60)
        plugin = type(
            "KillWorkerAfterPlugin",
            (KillWorkerAfter, distributed.diagnostics.plugin.SchedulerPlugin),
            {},
        )("scan-tiles-", 1)
        own.register_plugin(plugin)
        with deadline(240, "a run whose only worker was killed"):
            tiled = find_fleet_loops_dask(paths, 1.5, client=own, block=block, fan_in=2)
        killed = own.run_on_scheduler(
            lambda dask_scheduler: dask_scheduler.plugins["kill-worker-after"].killed
        )
    assert killed is not None, "the worker was killed during the run"
    assert_same(tiled, fleet)


def worker_pids(client, gone: list[int], want: int = 2) -> list[int]:
    """The process ids of the cluster's ``want`` workers, none of them in ``gone`` (workers
    killed). A nanny does not always start a new worker for one killed at an unlucky moment
    (Dask's own fragility, not the driver's): after 30 s without them, the cluster's workers
    are replaced (scaled to none and back)."""
    started, replaced = time.monotonic(), False
    with deadline(240, f"{want} workers other than {gone}"):
        while True:
            pids = sorted(client.run(os.getpid, on_error="ignore").values())
            if len(pids) >= want and not set(pids) & set(gone):
                return pids
            if not replaced and time.monotonic() - started > 30:
                client.cluster.scale(0)
                while client.scheduler_info()["workers"]:
                    time.sleep(0.1)
                client.cluster.scale(want)
                replaced = True
            time.sleep(0.2)


#: Seeded trials of a worker killed at a random moment of a run.
KILL_TRIALS = 6


def test_workers_killed_at_seeded_moments_never_hang_a_run(tmp_path, monkeypatch):
    """On a cluster of two worker processes of its own, each trial SIGKILLs one worker, or
    every worker (seeded), at a seeded moment of a run (or just after it): the run gives the
    fleet's answer, or fails with ClusterError, within its deadline; then the next run on the
    same cluster gives the fleet's answer. (When every worker is gone at once, the run's tasks
    have none to go to: they wait in Dask's no-worker state until the nannies' new workers
    join, at new addresses.)"""
    pytest.importorskip("distributed")
    monkeypatch.setattr(il_dask, "NO_WORKER_TIMEOUT_S", 20.0)
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 8)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    block = blocks_for(paths, 7)
    outcomes = []
    victims: list[int] = []

    def kill(pids: list[int]) -> None:
        for pid in pids:
            os.kill(pid, signal.SIGKILL)

    with local_client(workers=2) as own:
        for trial in range(KILL_TRIALS):
            rng = random.Random(trial)
            pids = worker_pids(own, gone=victims)
            victims = pids if rng.random() < 0.5 else [rng.choice(pids)]
            delay_s = rng.uniform(0.2, 1.2)
            killer = threading.Timer(delay_s, kill, (victims,))
            killer.start()
            what = f"trial {trial} (workers {victims} killed after {delay_s:.2f} s)"
            try:
                with deadline(240, what):
                    tiled = find_fleet_loops_dask(paths, 1.5, client=own, block=block, fan_in=2)
                assert_same(tiled, fleet)
                outcomes.append("same")
            except il_dask.ClusterError as error:
                assert "\n" not in str(error)
                outcomes.append("ClusterError")
            finally:
                killer.join()
        print(outcomes)
        worker_pids(own, gone=victims)
        with deadline(240, "the run after the trials"):
            tiled = find_fleet_loops_dask(paths, 1.5, client=own, block=block, fan_in=2)
    assert_same(tiled, fleet)


def test_a_run_whose_tasks_find_no_worker_fails_and_the_cluster_runs_the_next(
    tmp_path, monkeypatch
):
    """With no running worker (all gone), a run's tasks wait in Dask's no-worker state: the
    run raises ClusterError after NO_WORKER_TIMEOUT_S and cancels them; once workers are back
    the next run on the same cluster gives the fleet's answer."""
    pytest.importorskip("distributed")
    monkeypatch.setattr(il_dask, "NO_WORKER_TIMEOUT_S", 2.0)
    paths = random_fleet(tmp_path, 9)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    block = blocks_for(paths, 2)
    with local_client(workers=1) as own:
        own.wait_for_workers(1, timeout=60)
        own.cluster.scale(0)
        with deadline(120, "the cluster's worker leaving"):
            while own.scheduler_info()["workers"]:
                time.sleep(0.1)
        with deadline(120, "a run without workers"):
            with pytest.raises(il_dask.ClusterError, match="found no worker to run on"):
                find_fleet_loops_dask(paths, 1.5, client=own, block=block)
        # Its tasks were cancelled: none is left waiting for a worker.
        with deadline(60, "the failed run's tasks left in the cluster"):
            while own.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)):
                time.sleep(0.1)
        own.cluster.scale(1)
        own.wait_for_workers(1, timeout=60)
        with deadline(120, "the run after it"):
            tiled = find_fleet_loops_dask(paths, 1.5, client=own, block=block)
    assert_same(tiled, fleet)


def test_a_group_of_tiles_scans_as_each_tile_alone():
    # Three sessions crossing one another, in blocks of 20: tiles share their sides.
    s = np.arange(60.0)
    sessions = [
        il.Trajectory(s, np.c_[s * 0.5, 5 * np.sin(s / 7)]),
        il.Trajectory(s, np.c_[30 - s * 0.5, 5 * np.cos(s / 5)]),
        il.Trajectory(s, np.c_[s * 0.5, 0.3 * s - 9]),
    ]
    blocks = [il.tiles.session_blocks(t, block=20) for t in sessions]
    tiles = il.tiles.plan_tiles(blocks, gamma=2.0)
    starts = [0, 60, 120]
    jobs = [
        (
            t,
            sessions[t.sessions[0]],
            None if t.sessions[0] == t.sessions[1] else sessions[t.sessions[1]],
            (starts[t.sessions[0]], starts[t.sessions[1]]),
        )
        for t in tiles
    ]
    sides = [(t.sessions[0], t.rows) for t in tiles if t.sessions[0] != t.sessions[1]]
    assert len(set(sides)) < len(sides), "some side is read by two tiles"
    together = il.tiles.scan_tiles(jobs[::-1], gamma=2.0, separation=None, duration=True)
    for (tile, a, b, at), (summary, share) in zip(jobs[::-1], together, strict=True):
        alone, alone_share = il.tiles.scan_tile(
            tile, a, b, starts=at, gamma=2.0, separation=None, duration=True
        )
        assert summary.to_bytes() == alone.to_bytes() and share.to_bytes() == alone_share.to_bytes()
    # Not a vacuous check: tiles between sessions hold cells.
    between = [
        s
        for (t, *_), (s, _) in zip(jobs[::-1], together, strict=True)
        if t.sessions[0] != t.sessions[1]
    ]
    assert sum(s.component_count > 0 for s in between) >= 2
    assert il.tiles.scan_tiles([], gamma=2.0) == []
    torus = il.Trajectory.torus(s, np.c_[s * 0.05, s * 0.05])
    with pytest.raises(il.InvalidParameterError, match="name one metric"):
        il.tiles.scan_tiles([jobs[0], (jobs[0][0], torus, None, (0, 0))], gamma=2.0)
    with pytest.raises(il.InvalidParameterError, match="tile"):
        il.tiles.scan_tiles([jobs[0], (jobs[-1][0], sessions[0], None, (0, 0))], gamma=2.0)


def test_tiles_pickle_as_their_bytes_and_corrupt_bytes_fail(tmp_path):
    x = np.arange(30) * 0.5
    a = il.Trajectory(np.arange(30.0), np.c_[x, 0 * x])
    b = il.Trajectory(np.arange(30.0), np.c_[x[::-1], 0 * x + 0.5])
    blocks = [il.tiles.session_blocks(s, block=10) for s in (a, b)]
    assert (len(blocks[0]), blocks[0].poses, blocks[0].block, blocks[0].span_s) == (3, 30, 10, 29.0)
    copy = pickle.loads(pickle.dumps(blocks[0]))
    assert copy.to_bytes() == blocks[0].to_bytes() and copy.metric_name == "euclidean"
    tiles = il.tiles.plan_tiles(blocks, gamma=1.0)
    assert pickle.loads(pickle.dumps(tiles)) == tiles
    assert len({*tiles, *tiles}) == len(tiles)
    tile = next(t for t in tiles if t.sessions == (0, 1))
    assert tile.rows[1] - tile.rows[0] == 10 and tile.columns[0] >= 30
    summary = il.tiles.scan_tile(tile, a, b, starts=(0, 30), gamma=1.0)
    assert summary.tile == tile and summary.component_count > 0 and summary.edge_count > 0
    again = pickle.loads(pickle.dumps(summary))
    assert isinstance(again, il.tiles.TileSummary) and again.to_bytes() == summary.to_bytes()
    assert il.tiles.TileSummary.from_bytes(summary.to_bytes()).to_bytes() == summary.to_bytes()
    merged = il.tiles.merge_tiles([summary])
    assert (merged.tile_count, merged.component_count) == (1, summary.component_count)
    assert merged.open_edge_count == summary.edge_count, "one tile: every edge run still open"
    assert il.tiles.TileMerge.from_bytes(merged.to_bytes()).to_bytes() == merged.to_bytes()
    assert pickle.loads(pickle.dumps(merged)).to_bytes() == merged.to_bytes()
    with pytest.raises(il.InvalidParameterError, match="these are the bytes of a tile merge"):
        il.tiles.TileSummary(merged.to_bytes())
    with pytest.raises(il.InvalidParameterError, match="invalid saved tile merge: .*bytes"):
        il.tiles.TileMerge(merged.to_bytes()[:-3])
    with pytest.raises(il.InvalidParameterError, match="each tile summarised once"):
        il.tiles.merge_tiles([summary, summary])
    with pytest.raises(
        TypeError, match=r"parts\[1\] must be a TileSummary or a TileMerge, got int"
    ):
        il.tiles.merge_tiles([summary, 3])
    with pytest.raises(TypeError, match="needs session_b"):
        il.tiles.scan_tile(tile, a, starts=(0, 30), gamma=1.0)
    with pytest.raises(il.InvalidParameterError, match="tile"):
        il.tiles.scan_tile(tile, a, b, starts=(0, 25), gamma=1.0)
    with pytest.raises(ValueError, match="not a callable"):
        il.tiles.session_blocks(a, block=10, metric=lambda p, q: 0.0)
    with pytest.raises(il.InvalidParameterError, match="measured with"):
        il.tiles.plan_tiles(
            [blocks[0], il.tiles.session_blocks(b, block=10, metric="torus")], gamma=1.0
        )
    with pytest.raises(il.InvalidParameterError, match="2 names for 1 sessions"):
        il.tiles.merge_tiles([summary]).finish(blocks[:1], names=["a", "b"])


def test_inputs_and_errors(tmp_path, client):
    paths = random_fleet(tmp_path, 4)
    traj = il.read_trajectory(paths[0])
    with pytest.raises(TypeError, match="workers read every session from a path"):
        find_fleet_loops_dask({"a": traj, "b": paths[1]}, 1.0, client=client)
    with pytest.raises(il.InvalidParameterError, match="both named 'walk0'"):
        find_fleet_loops_dask([paths[0], paths[0]], 1.0)
    with pytest.raises(il.InvalidParameterError, match="fan_in = 1"):
        find_fleet_loops_dask(paths, 1.0, fan_in=1)
    with pytest.raises(il.InvalidParameterError, match="block"):
        find_fleet_loops_dask(paths, 1.0, block=0)
    with pytest.raises(FileNotFoundError, match="missing.tum"):
        find_fleet_loops_dask([tmp_path / "missing.tum"], 1.0, client=client)
    with pytest.raises(TypeError, match="got a Trajectory without a name"):
        find_fleet_loops_dask([traj], 1.0)
    # Names as il.Fleet gives them.
    tiled = find_fleet_loops_dask(paths, 1.0, block=50)
    assert tiled.names == il.Fleet(paths).names


def test_without_a_client_dask_is_not_imported(tmp_path):
    paths = random_fleet(tmp_path, 5)
    code = (
        "import sys\n"
        "from inexact_loops.dask import find_fleet_loops_dask\n"
        f"loops = find_fleet_loops_dask({[str(p) for p in paths]!r}, 1.0, block=30)\n"
        "assert len(loops.components['id']) > 0\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout


# ---------------------------------------------------------------------------------------------
# Samples and tau from tiles, Parquet, faults, the output folder and loops-dask
# ---------------------------------------------------------------------------------------------

SAMPLERS = [
    ("one", {"budget": 25}),
    ("rho", {"budget": 60}),
    ("rho-dispersed", {"budget": 40}),
    ("alpha", {"budget": 30}),
    ("closest-first", {"budget": 50}),
    ("closest-then-spread", {"budget": 50}),
    ("rho", {"rate": 0.2}),
    ("alpha", {"rate": 0.02}),
]


def assert_same_samples(ours: dict, theirs: dict) -> None:
    assert list(ours) == list(theirs)
    for column in theirs:
        np.testing.assert_array_equal(ours[column], theirs[column], err_msg=column)


@pytest.mark.filterwarnings("ignore::inexact_loops.DiagonalBrokenWarning")
@pytest.mark.filterwarnings("ignore::inexact_loops.SampleBudgetWarning")
@pytest.mark.parametrize("separation", ["auto", None])
def test_samples_on_the_cluster_equal_sample_fleet(tmp_path, client, separation):
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 11)
    fleet = il.Fleet(paths)
    loops = il.find_fleet_loops(fleet, gamma=1.5, separation=separation)
    expected = {}
    for k, (sampler, size) in enumerate(SAMPLERS):
        for between_only in (False, True):
            key = (k, between_only)
            expected[key] = il.sample_fleet(
                loops, sampler, seed=k, between_only=between_only, **size
            ).table
    for per_pair in TILES_PER_PAIR:
        block = blocks_for(paths, per_pair)
        tiled = find_fleet_loops_dask(
            paths, 1.5, client=client, block=block, separation=separation, fan_in=3
        )
        for k, (sampler, size) in enumerate(SAMPLERS):
            for between_only in (False, True):
                got = tiled.sample(sampler, seed=k, between_only=between_only, **size)
                assert_same_samples(got, expected[(k, between_only)])
    # In this process, with 1 and 2 threads: the same.
    for threads in (1, 2):
        tiled = find_fleet_loops_dask(
            paths, 1.5, block=blocks_for(paths, 2), separation=separation, threads=threads
        )
        got = tiled.sample("closest-first", budget=50, seed=4)
        assert_same_samples(got, expected[(4, False)])
    # The same draw by hand, through pickles, as a cluster runs it.
    sessions = [il.read_trajectory(p) for p in paths]
    starts = np.cumsum([0] + [len(t) for t in sessions])
    by_hand = tiled.loops.draw("rho", budget=600, seed=1)
    theirs = il.sample_fleet(loops, "rho", budget=600, seed=1)
    assert (by_hand.groups, by_hand.available, by_hand.warnings) == (
        theirs.samples.groups,
        theirs.samples.available,
        [],
    )
    tiles = tiled.loops.tiles
    while not by_hand.done:
        offers = []
        for t, request in by_hand.requests():
            request = pickle.loads(pickle.dumps(request))
            assert request.tile == tiles[t]
            a, b = request.tile.sessions
            offer = il.tiles.draw_tile(
                request,
                sessions[a],
                sessions[b],
                starts=(int(starts[a]), int(starts[b])),
                gamma=1.5,
                separation=separation,
            )
            offers.append(il.tiles.DrawCandidates(offer.to_bytes()))
        by_hand.absorb(offers)
    assert by_hand.requests() == []
    assert_same_samples(by_hand.table(), theirs.table)
    with pytest.raises(il.InvalidParameterError, match="baseline"):
        tiled.loops.draw("lio-sam", budget=10, seed=0)
    # A pickled result keeps its tables, not the merge.
    unpickled = pickle.loads(pickle.dumps(tiled.loops))
    assert unpickled == tiled.loops
    with pytest.raises(il.InvalidParameterError, match="read from a pickle"):
        unpickled.draw("rho", budget=10, seed=0)
    many = tiled.loops.draw("one", budget=10_000_000, seed=0)
    assert any("candidates" in w for w in many.warnings), many.warnings
    # Neither a rate nor a budget: the core's default budget, as sample_fleet takes it.
    default = tiled.loops.draw(seed=2)
    assert (default.groups, default.available) == (
        tiled.loops.draw(il.DEFAULT_SAMPLER, budget=il.DEFAULT_BUDGET, seed=2).groups,
        il.sample_fleet(loops, seed=2).samples.available,
    )
    with pytest.raises(il.InvalidParameterError, match="rate"):
        tiled.loops.draw(rate=0.5, budget=10, seed=0)


def runs_counts(client) -> dict[str, int]:
    """The draws from kept runs ("hits") and from rescans ("misses") of every worker so far."""
    counts = client.run(lambda: dict(il_dask._cache._runs_counts)).values()
    return {k: sum(c[k] for c in counts) for k in ("hits", "misses")}


@pytest.mark.filterwarnings("ignore::inexact_loops.DiagonalBrokenWarning")
@pytest.mark.filterwarnings("ignore::inexact_loops.SampleBudgetWarning")
def test_draws_from_kept_runs_or_rescans_are_the_same(tmp_path, client, monkeypatch):
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 13)
    loops = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    draws = [("rho", {"budget": 300}), ("closest-first", {"budget": 50}), ("alpha", {"rate": 0.05})]
    expected = [il.sample_fleet(loops, s, seed=3, **size).table for s, size in draws]
    block = blocks_for(paths, 7)

    def sample(run) -> None:
        for (sampler, size), want in zip(draws, expected, strict=True):
            assert_same_samples(run.sample(sampler, seed=3, **size), want)

    # On the cluster: the draws go where their tiles were scanned and read the kept runs.
    run = find_fleet_loops_dask(paths, 1.5, client=client, block=block)
    before = runs_counts(client)
    sample(run)
    hits = runs_counts(client)
    assert hits["hits"] > before["hits"], "no draw found its tile's runs"
    # Every kept run dropped between the scan and the draw: the draws rescan, the same samples.
    client.run(il_dask._cache._forget_runs)
    sample(run)
    misses = runs_counts(client)
    assert misses["hits"] == hits["hits"], "runs were found after they were dropped"
    assert misses["misses"] > hits["misses"], "no draw rescanned its tile"
    # In this process: every draw a hit; with nothing kept (RUNS_KEPT = 0), every one a miss.
    for kept, field in ((il_dask.RUNS_KEPT, "hits"), (0, "misses")):
        monkeypatch.setattr(il_dask, "RUNS_KEPT", kept)
        il_dask._cache._forget_runs()
        counted = dict(il_dask._cache._runs_counts)
        sample(find_fleet_loops_dask(paths, 1.5, block=block))
        other = "misses" if field == "hits" else "hits"
        assert il_dask._cache._runs_counts[other] == counted[other], f"RUNS_KEPT = {kept}"
        assert il_dask._cache._runs_counts[field] > counted[field], f"RUNS_KEPT = {kept}"
    il_dask._cache._forget_runs()
    # By hand: a tile's kept runs offer what its rescan offers, and only for that tile.
    sessions = [il.read_trajectory(p) for p in paths]
    starts = np.cumsum([0] + [len(t) for t in sessions])
    tiled = find_fleet_loops_dask(paths, 1.5, block=block)
    tiles = tiled.loops.tiles
    draw = tiled.loops.draw("rho", budget=300, seed=3)
    offered = 0
    for t, request in draw.requests():
        a, b = tiles[t].sessions
        kwargs = {"starts": (int(starts[a]), int(starts[b])), "gamma": 1.5}
        summary, share, runs = il.tiles.scan_tile(
            tiles[t], sessions[a], sessions[b], **kwargs, duration=True, runs=True
        )
        assert (
            summary.to_bytes()
            == il.tiles.scan_tile(tiles[t], sessions[a], sessions[b], **kwargs).to_bytes()
        )
        assert share.tile == runs.tile == tiles[t]
        assert runs.metric_name == "euclidean" and "runs" in repr(runs)
        assert runs.nbytes >= 16 * len(runs)
        kept = il.tiles.draw_tile(request, sessions[a], sessions[b], runs=runs, **kwargs)
        rescanned = il.tiles.draw_tile(request, sessions[a], sessions[b], **kwargs)
        assert kept.to_bytes() == rescanned.to_bytes()
        offered += len(kept)
        other = next(u for u in tiles if u != tiles[t] and u.sessions == tiles[t].sessions)
        _, wrong = il.tiles.scan_tile(other, sessions[a], sessions[b], **kwargs, runs=True)
        with pytest.raises(il.InvalidParameterError, match="runs are of tile"):
            il.tiles.draw_tile(request, sessions[a], sessions[b], runs=wrong, **kwargs)
        with pytest.raises(il.InvalidParameterError, match="metric"):
            il.tiles.draw_tile(
                request, sessions[a], sessions[b], runs=runs, metric="chebyshev", **kwargs
            )
    assert offered > 0
    with pytest.raises(TypeError):
        pickle.dumps(runs)


def test_loop_duration_from_tiles_equals_the_fleet(tmp_path, client):
    paths = adversarial_fleet(tmp_path) + random_fleet(tmp_path, 12)
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5, separation=None)
    for per_pair, c in ((1, None), (7, client)):
        tiled = find_fleet_loops_dask(
            paths,
            1.5,
            client=c,
            block=blocks_for(paths, per_pair),
            separation=None,
            loop_duration=True,
        )
        for name in tiled.names:
            ours, theirs = tiled.loop_duration(name), fleet.loop_duration(name)
            np.testing.assert_array_equal(ours["pose"], theirs["pose"])
            np.testing.assert_array_equal(ours["t_s"], theirs["t_s"])
            for column in ("own_s", "other_s"):
                np.testing.assert_allclose(ours[column], theirs[column], rtol=1e-10, atol=1e-9)
    with pytest.raises(il.InvalidParameterError, match="loop_duration=True"):
        find_fleet_loops_dask(paths, 1.5, block=50).loop_duration(tiled.names[0])
    # The shares by hand, through their bytes.
    sessions = [il.read_trajectory(p) for p in paths]
    blocks = [il.tiles.session_blocks(t, block=40) for t in sessions]
    starts = np.cumsum([0] + [len(t) for t in sessions])
    shares = []
    for tile in il.tiles.plan_tiles(blocks, gamma=1.5):
        a, b = tile.sessions
        _, share = il.tiles.scan_tile(
            tile,
            sessions[a],
            sessions[b],
            starts=(int(starts[a]), int(starts[b])),
            gamma=1.5,
            separation=None,
            duration=True,
        )
        assert share.tile == tile
        shares.append(pickle.loads(pickle.dumps(il.tiles.TileDuration(share.to_bytes()))))
    own, other = il.tiles.session_loop_duration(
        2, start=int(starts[2]), poses=len(sessions[2]), parts=shares
    )
    theirs = fleet.loop_duration(fleet.names[2])
    np.testing.assert_allclose(own, theirs["own_s"], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(other, theirs["other_s"], rtol=1e-10, atol=1e-9)


def write_parquet(path: Path, t: np.ndarray, xy: np.ndarray) -> Path:
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    pq.write_table(pa.table({"t": t, "x": xy[:, 0], "y": xy[:, 1], "z": np.zeros(len(t))}), path)
    return path


def test_parquet_pose_stores_read_where_the_tiles_are(tmp_path, client):
    tum = random_fleet(tmp_path, 13)
    stores = []
    for p in tum:
        traj = il.read_trajectory(p)
        stores.append(
            write_parquet(tmp_path / f"{p.stem}.parquet", traj.timestamps, traj.positions[:, :2])
        )
    fleet = il.find_fleet_loops(il.Fleet(tum), gamma=1.5)
    tiled = find_fleet_loops_dask(stores, 1.5, client=client, block=blocks_for(tum, 2))
    assert_same(tiled, fleet)
    # Bad stores fail with one line naming the file and what is wrong.
    from inexact_loops.dask import read_pose_parquet

    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    bad = tmp_path / "bad.parquet"
    pq.write_table(pa.table({"t": [0.0, 1.0], "x": [0.0, 1.0]}), bad)
    with pytest.raises(il.LoopsIOError, match=r"bad.parquet: .* missing y"):
        read_pose_parquet(bad)
    garbage = tmp_path / "garbage.parquet"
    garbage.write_bytes(b"not parquet at all")
    with pytest.raises(il.LoopsIOError, match="garbage.parquet: not a Parquet pose store"):
        read_pose_parquet(garbage)


def test_a_bad_log_fails_only_its_session(tmp_path, client):
    paths = random_fleet(tmp_path, 14)
    corrupt = tmp_path / "corrupt.tum"
    corrupt.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\nthis is not a pose\n")
    missing = tmp_path / "missing.tum"
    sessions = [paths[0], corrupt, *paths[1:], missing]
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    tiled = find_fleet_loops_dask(sessions, 1.5, client=client, block=blocks_for(paths, 2))
    assert_same(tiled, fleet)
    assert [f[0] for f in tiled.failures] == ["corrupt", "missing"]
    for name, source, error in tiled.failures:
        assert "\n" not in error and source.endswith(f"{name}.tum"), error
    assert "line 3" in tiled.failures[0][2], tiled.failures[0][2]
    assert tiled.failures[1][2].startswith("FileNotFoundError"), tiled.failures[1][2]
    got = tiled.sample("rho", budget=40, seed=1)
    assert_same_samples(got, il.sample_fleet(fleet, "rho", budget=40, seed=1).table)
    with pytest.raises(il.LoopsIOError, match="corrupt.tum"):
        find_fleet_loops_dask(sessions, 1.5, client=client, on_error="raise")


def read_parquet(path: Path) -> dict:
    pq = pytest.importorskip("pyarrow.parquet")
    table = pq.read_table(path)
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}


def test_the_output_folder_holds_parquet_tables_written_safely(tmp_path, client):
    from inexact_loops.dask import run_fleet_dask

    paths = random_fleet(tmp_path, 15)
    corrupt = tmp_path / "corrupt.tum"
    corrupt.write_text("garbage\n")
    out = tmp_path / "out"
    summary = run_fleet_dask(
        [*paths, corrupt],
        1.5,
        out=out,
        client=client,
        block=blocks_for(paths, 2),
        sampler="rho",
        budget=30,
        seed=2,
    )
    fleet = il.find_fleet_loops(il.Fleet(paths), gamma=1.5)
    names = sorted(os.listdir(out))
    assert names == [
        "components.parquet",
        "failures.parquet",
        "loop_duration",
        "loops-dask.json",
        "samples.parquet",
        "session_pairs.parquet",
        "summary.json",
    ], names
    components = read_parquet(out / "components.parquet")
    for column in ("id", "session_a", "session_b", "pair_count", "holes", "i_min", "j_max"):
        np.testing.assert_array_equal(components[column], fleet.components[column], err_msg=column)
    samples = read_parquet(out / "samples.parquet")
    expected = il.sample_fleet(fleet, "rho", budget=30, seed=2).table
    for column in ("i", "j", "component", "distance"):
        np.testing.assert_array_equal(samples[column], expected[column], err_msg=column)
    failures = read_parquet(out / "failures.parquet")
    assert (
        list(failures["session"]) == ["corrupt"] and summary["failures"][0]["session"] == "corrupt"
    )
    for name in fleet.names:
        tau = read_parquet(out / "loop_duration" / f"{name}.parquet")
        theirs = fleet.loop_duration(name)
        np.testing.assert_allclose(tau["own_s"], theirs["own_s"], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(tau["other_s"], theirs["other_s"], rtol=1e-10, atol=1e-9)
    assert not [n for n in os.listdir(out) if n.startswith(".")], "temporary files left"
    # Not again without force; with force, only what it wrote is replaced.
    with pytest.raises(il.InvalidParameterError, match="not empty; pass force=True"):
        run_fleet_dask(paths, 1.5, out=out, block=50)
    # An entry shaped like a killed run's leftover is the user's unless the marker lists it.
    (out / ".components.parquet.abc123.tmp").write_text("the user's")
    (out / ".thesis.partial-2024").mkdir()
    run_fleet_dask(paths, 1.5, out=out, block=50, force=True, sampler=None)
    assert not (out / "samples.parquet").exists(), "an earlier run's samples were left"
    assert (out / ".components.parquet.abc123.tmp").read_text() == "the user's"
    assert (out / ".thesis.partial-2024").is_dir()
    # What a killed run left in its scratch folder, which the marker lists, goes.
    (out / ".loops-dask.partial").mkdir()
    (out / ".loops-dask.partial" / "0").write_text("half a table")
    run_fleet_dask(paths, 1.5, out=out, block=50, force=True, sampler=None)
    assert not (out / ".loops-dask.partial").exists()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "components.parquet").write_text("a file of the user's")
    with pytest.raises(
        il.InvalidParameterError, match="holds components.parquet, which `loops-dask` did not write"
    ):
        run_fleet_dask(paths, 1.5, out=mine, block=50, force=True)
    assert (mine / "components.parquet").read_text() == "a file of the user's"


def test_no_output_lands_on_an_input(tmp_path):
    """``out`` and ``--json`` on a session's file (or a link to it, or ``out`` holding it) are
    refused, ``force`` or not, and the file is left as it was."""
    paths = random_fleet(tmp_path, 4)
    before = paths[0].read_bytes()
    link = tmp_path / "link.json"
    link.symlink_to(paths[0])
    for out, says in (
        (paths[0], "would overwrite the input"),
        (link, "would overwrite the input"),
        (tmp_path, "lies inside out"),
    ):
        with pytest.raises(il.InvalidParameterError, match=says):
            il_dask.run_fleet_dask(paths, 1.5, out=out, block=50, force=True)
    for target in (paths[0], link):
        argv = [*map(str, paths), "--gamma", "1.5", "--out", str(tmp_path / "o"), "--force"]
        run = subprocess.run(
            [sys.executable, "-m", "inexact_loops.dask", *argv, "--json", str(target)],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 2, run.stderr
        assert "would overwrite the input" in run.stderr and run.stderr.count("\n") == 1
        assert not (tmp_path / "o").exists()
    assert paths[0].read_bytes() == before


def test_loops_dask_is_the_one_switch(tmp_path, client):
    paths = random_fleet(tmp_path, 16)
    corrupt = tmp_path / "corrupt.tum"
    corrupt.write_text("garbage\n")
    here = [
        sys.executable,
        "-m",
        "inexact_loops.dask",
        *map(str, paths),
        "--gamma",
        "1.5",
        "--block",
        "40",
    ]
    run = subprocess.run([*here, "--out", str(tmp_path / "here")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "on this machine" in run.stdout
    address = client.scheduler.address
    there = [
        *here,
        str(corrupt),
        "--scheduler",
        address,
        "--out",
        str(tmp_path / "there"),
        "--json",
        "-",
    ]
    run = subprocess.run(there, capture_output=True, text=True)
    assert run.returncode == 1, run.stderr  # a session was left out
    assert "session corrupt" in run.stderr and "left out" in run.stderr
    summary = json.loads(run.stdout)
    assert summary["stats"]["workers"] == 2
    a = read_parquet(tmp_path / "here" / "samples.parquet")
    b = read_parquet(tmp_path / "there" / "samples.parquet")
    for column in a:
        np.testing.assert_array_equal(a[column], b[column], err_msg=column)
    run = subprocess.run([*here, "--out", str(tmp_path / "here")], capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.startswith("loops-dask: error: out "), run.stderr
    assert run.stderr.count("\n") == 1, run.stderr


def test_session_a_means_one_thing_on_every_surface(tmp_path):
    """``session_a`` and ``session_b`` are the sessions' indices in fleet order, and ``name_a`` and
    ``name_b`` their names, in ``loops fleet``'s CSV files, in the Python tables and in
    ``run_fleet_dask``'s Parquet tables alike (the CSV once named them ``session_a``)."""
    import csv
    import subprocess
    import sys

    from inexact_loops.dask import run_fleet_dask

    paths = random_fleet(tmp_path, 21)
    names = [p.stem for p in paths]
    fleet = il.Fleet(paths)
    loops = il.find_fleet_loops(fleet, gamma=1.5)
    python = {
        "components": loops.components,
        "session_pairs": loops.session_pairs(),
        "samples": il.sample_fleet(loops, "rho", budget=20, seed=3).table,
    }
    cli_out, dask_out = tmp_path / "cli", tmp_path / "dask"
    run = subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", "fleet", *map(str, paths)]
        + ["--gamma", "1.5", "--sampler", "rho", "--budget", "20", "--seed", "3"]
        + ["--out", str(cli_out), "--quiet"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    run_fleet_dask(paths, 1.5, out=dask_out, sampler="rho", budget=20, seed=3)
    for table, ours in python.items():
        with (cli_out / f"{table}.csv").open(newline="") as f:
            rows = list(csv.DictReader(f))
        parquet = read_parquet(dask_out / f"{table}.parquet")
        assert len(rows) == len(ours["session_a"]) == len(parquet["session_a"]) > 0, table
        for side in ("a", "b"):
            index = np.asarray(ours[f"session_{side}"], dtype=np.int64)
            assert [int(r[f"session_{side}"]) for r in rows] == index.tolist(), table
            np.testing.assert_array_equal(parquet[f"session_{side}"], index)
            want = [names[k] for k in index]
            assert [r[f"name_{side}"] for r in rows] == want, table
            assert list(ours[f"name_{side}"]) == want == list(parquet[f"name_{side}"]), table
