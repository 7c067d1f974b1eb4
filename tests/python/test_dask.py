"""Fleets from tiles, in this process and on a Dask ``LocalCluster`` of 2 worker processes, against
the single-machine fleet API (:func:`inexact_loops.find_fleet_loops`): components, session pairs
and the overlap matrix identical (areas to a relative 1e-10) for 1, 2 and 7 tiles per session
pair, on random and adversarial fleets written to TUM files and on MulRan KAIST 01/02; a worker
SIGKILLed during a run changes nothing. Also: the tile objects pickle as their bytes, corrupt
bytes fail clearly, and without ``client=`` Dask is not imported.
"""

from __future__ import annotations

import math
import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il
from inexact_loops.dask import find_fleet_loops_dask

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
        if column == "area_s2":
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
    distributed = pytest.importorskip(
        "distributed", reason="dask.distributed is not installed: pip install 'inexact-loops[dask]'"
    )
    import logging

    with (
        distributed.LocalCluster(
            n_workers=2,
            processes=True,
            threads_per_worker=1,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
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
    )("scan-tile-", 10)
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


def test_tiles_pickle_as_their_bytes_and_corrupt_bytes_fail(tmp_path):
    x = np.arange(30) * 0.5
    a = il.Trajectory(np.arange(30.0), np.c_[x, 0 * x])
    b = il.Trajectory(np.arange(30.0), np.c_[x[::-1], 0 * x + 0.5])
    blocks = [il.session_blocks(s, block=10) for s in (a, b)]
    assert (len(blocks[0]), blocks[0].poses, blocks[0].block, blocks[0].span_s) == (3, 30, 10, 29.0)
    copy = pickle.loads(pickle.dumps(blocks[0]))
    assert copy.to_bytes() == blocks[0].to_bytes() and copy.metric_name == "euclidean"
    tiles = il.plan_tiles(blocks, gamma=1.0)
    assert pickle.loads(pickle.dumps(tiles)) == tiles
    assert len({*tiles, *tiles}) == len(tiles)
    tile = next(t for t in tiles if t.sessions == (0, 1))
    assert tile.rows[1] - tile.rows[0] == 10 and tile.columns[0] >= 30
    summary = il.scan_tile(tile, a, b, starts=(0, 30), gamma=1.0)
    assert summary.tile == tile and summary.component_count > 0 and summary.edge_count > 0
    again = pickle.loads(pickle.dumps(summary))
    assert isinstance(again, il.TileSummary) and again.to_bytes() == summary.to_bytes()
    assert il.TileSummary.from_bytes(summary.to_bytes()).to_bytes() == summary.to_bytes()
    merged = il.merge_tiles([summary])
    assert (merged.tile_count, merged.component_count) == (1, summary.component_count)
    assert merged.open_edge_count == summary.edge_count, "one tile: every edge run still open"
    assert il.TileMerge.from_bytes(merged.to_bytes()).to_bytes() == merged.to_bytes()
    assert pickle.loads(pickle.dumps(merged)).to_bytes() == merged.to_bytes()
    with pytest.raises(il.InvalidParameterError, match="these are the bytes of a tile merge"):
        il.TileSummary(merged.to_bytes())
    with pytest.raises(il.InvalidParameterError, match="invalid saved tile merge: .*bytes"):
        il.TileMerge(merged.to_bytes()[:-3])
    with pytest.raises(il.InvalidParameterError, match="each tile summarised once"):
        il.merge_tiles([summary, summary])
    with pytest.raises(
        TypeError, match=r"parts\[1\] must be a TileSummary or a TileMerge, got int"
    ):
        il.merge_tiles([summary, 3])
    with pytest.raises(TypeError, match="needs session_b"):
        il.scan_tile(tile, a, starts=(0, 30), gamma=1.0)
    with pytest.raises(il.InvalidParameterError, match="tile"):
        il.scan_tile(tile, a, b, starts=(0, 25), gamma=1.0)
    with pytest.raises(ValueError, match="not a callable"):
        il.session_blocks(a, block=10, metric=lambda p, q: 0.0)
    with pytest.raises(il.InvalidParameterError, match="measured with"):
        il.plan_tiles([blocks[0], il.session_blocks(b, block=10, metric="torus")], gamma=1.0)
    with pytest.raises(il.InvalidParameterError, match="2 names for 1 sessions"):
        il.merge_tiles([summary]).finish(blocks[:1], names=["a", "b"])


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
