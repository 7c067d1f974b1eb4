"""The fleet store (:class:`inexact_loops.FleetStore`) against one run over its sessions.

Its Parquet tables, read by DuckDB, pandas and pyarrow (independent Parquet readers), hold the
values of :func:`find_fleet_loops` and :func:`sample_fleet` over the stored sessions in name
order; a seeded random sequence of adds, replacements and removals (and a corrupt log, which
changes no file) ends with the answer of one run over the final sessions.
"""

from __future__ import annotations

import json
import multiprocessing
import pickle
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

duckdb = pytest.importorskip("duckdb")
pq = pytest.importorskip("pyarrow.parquet")
pd = pytest.importorskip("pandas")

quiet = pytest.mark.filterwarnings("ignore::inexact_loops.errors.LoopsWarning")

GAMMA = 40.0
BLOCK = 700
SAMPLING = {"sampler": "one", "budget": 60, "seed": 3}

#: Component columns compared exactly (areas to rounding: a tiling sums them in another order).
EXACT = (
    "session_a",
    "session_b",
    "trivial",
    "pair_count",
    "holes",
    "i_min",
    "i_max",
    "j_min",
    "j_max",
)


def sessions() -> dict[str, il.Trajectory]:
    """Three cars on two days in one city, by name."""
    fleet = il.urban_fleet(vehicles=3, days=2, duration_s=300.0, seed=5)
    return {name: fleet.session(name) for name in fleet.names}


def scratch(stored: dict[str, il.Trajectory]) -> tuple[il.FleetLoops, il.FleetSamples]:
    """One run over `stored` in name order, as the store orders its sessions."""
    fleet = il.Fleet({name: stored[name] for name in sorted(stored)})
    loops = il.find_fleet_loops(fleet, gamma=GAMMA)
    return loops, il.sample_fleet(
        loops, SAMPLING["sampler"], budget=SAMPLING["budget"], seed=SAMPLING["seed"]
    )


def state_dir(folder: Path) -> Path:
    """The current state, as a reader finds it: the folder `store.json` names."""
    return folder / json.loads((folder / "store.json").read_text())["state"]


def assert_same_answer(store: il.FleetStore, stored: dict[str, il.Trajectory]) -> None:
    loops, samples = scratch(stored)
    assert store.names == sorted(stored)
    got, want = store.components, loops.components
    assert len(got["id"]) == len(want["id"])
    for column in EXACT:
        np.testing.assert_array_equal(got[column], want[column], err_msg=column)
    np.testing.assert_allclose(got["area_s2"], want["area_s2"], rtol=1e-9)
    np.testing.assert_allclose(store.overlap_matrix(), loops.overlap_matrix(), rtol=1e-9, atol=1e-9)
    tau, want_tau = store.loop_duration(), loops.loop_duration()
    np.testing.assert_array_equal(tau["t_s"], want_tau["t_s"])
    for column in ("own_s", "other_s"):
        np.testing.assert_allclose(
            tau[column], want_tau[column], rtol=1e-9, atol=1e-9, err_msg=column
        )
    drawn, want_drawn = store.samples, samples.table
    for column in ("session_a", "i", "session_b", "j", "component"):
        np.testing.assert_array_equal(drawn[column], want_drawn[column], err_msg=column)


@quiet
def test_duckdb_pandas_and_pyarrow_read_what_find_fleet_loops_finds(tmp_path: Path) -> None:
    """A store built day by day; its tables, read by DuckDB, pandas and pyarrow, hold what one
    run over the same sessions finds."""
    all_sessions = sessions()
    folder = tmp_path / "city"
    store = il.FleetStore.open(folder)
    for day in ("day0", "day1"):
        today = {name: t for name, t in all_sessions.items() if name.endswith(day)}
        store.update(add=today, gamma=GAMMA, block=BLOCK, **SAMPLING)
    assert store.last_update["added"] == ["car0-day1", "car1-day1", "car2-day1"]
    assert store.last_update["tiles_kept"] > 0
    loops, samples = scratch(all_sessions)
    state = state_dir(folder)
    assert state == store.state_path

    # DuckDB: counts, a join with the sessions table and a GROUP BY against the overlap matrix.
    sql = duckdb.connect().execute
    components = (state / "components.parquet").as_posix()
    sessions_table = (state / "sessions.parquet").as_posix()
    (count,) = sql(f"SELECT count(*) FROM '{components}'").fetchone()
    assert count == len(loops.components["id"]) > len(all_sessions)
    # Every state folder matches the glob; only the current one is left after an update.
    (globbed,) = sql(
        f"SELECT count(*) FROM '{folder.as_posix()}/state-*/components.parquet'"
    ).fetchone()
    assert globbed == count
    rows = sql(
        "SELECT c.id, sa.name AS name_a, sb.name AS name_b, c.pair_count, c.area_s2, "
        "c.i_min, c.j_max "
        f"FROM '{components}' c JOIN '{sessions_table}' sa ON c.a = sa.session "
        f"JOIN '{sessions_table}' sb ON c.b = sb.session ORDER BY c.id"
    ).fetchnumpy()
    want = loops.components
    np.testing.assert_array_equal(rows["id"], want["id"])
    for column in ("name_a", "name_b", "pair_count", "i_min", "j_max"):
        np.testing.assert_array_equal(np.asarray(rows[column]), want[column], err_msg=column)
    np.testing.assert_allclose(rows["area_s2"], want["area_s2"], rtol=1e-9)
    pairs = sql(
        f"SELECT a, b, count(*) AS components, sum(pair_count) AS cells, sum(area_s2) AS area_s2 "
        f"FROM '{components}' GROUP BY a, b ORDER BY a, b"
    ).fetchnumpy()
    want_pairs = loops.session_pairs()
    np.testing.assert_array_equal(pairs["a"], want_pairs["session_a"])
    np.testing.assert_array_equal(pairs["b"], want_pairs["session_b"])
    np.testing.assert_array_equal(pairs["components"], want_pairs["components"])
    # Within a session a component is the half t < t' (as FleetLoops.components; the
    # separation keeps the diagonal out), the session pair the whole square: twice as much.
    halves = np.where(pairs["a"] == pairs["b"], 2, 1)
    np.testing.assert_array_equal(pairs["cells"] * halves, want_pairs["pair_count"])
    np.testing.assert_allclose(pairs["area_s2"] * halves, want_pairs["area_s2"], rtol=1e-9)
    (added,) = sql(f"SELECT count(*) FROM '{components}' WHERE added").fetchone()
    assert added == len(store.added) > 0
    drawn = sql(
        f"SELECT a, i, b, j, component FROM '{(state / 'samples.parquet').as_posix()}'"
    ).fetchnumpy()
    want_drawn = samples.table
    assert len(drawn["a"]) == len(want_drawn["i"]) == SAMPLING["budget"]
    for column, want_column in (("a", "session_a"), ("i", "i"), ("b", "session_b"), ("j", "j")):
        np.testing.assert_array_equal(drawn[column], want_drawn[want_column], err_msg=column)
    np.testing.assert_array_equal(drawn["component"], want_drawn["component"])

    # pandas and pyarrow: the session pairs and the loop duration.
    frame = pd.read_parquet(state / "session_pairs.parquet")
    np.testing.assert_array_equal(frame["session_a"].to_numpy(), want_pairs["name_a"])
    np.testing.assert_allclose(frame["area_s2"].to_numpy(), want_pairs["area_s2"], rtol=1e-9)
    np.testing.assert_allclose(frame["density"].to_numpy(), want_pairs["density"], rtol=1e-9)
    tau = pq.read_table(state / "loop_duration.parquet").to_pydict()
    want_tau = loops.loop_duration()
    np.testing.assert_array_equal(tau["pose"], want_tau["pose"])
    np.testing.assert_allclose(tau["own_s"], want_tau["own_s"], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(tau["other_s"], want_tau["other_s"], rtol=1e-9, atol=1e-9)

    # The tiles, by part (the first day's, then the second day's new tiles), and their blobs
    # (LZ4-compressed columns) read back alike in DuckDB and pyarrow, each with its tag.
    parts = sorted(p.name for p in (state / "tiles").iterdir())
    assert parts == ["000001.parquet", "000002.parquet"], parts
    tiles = (state / "tiles").as_posix()
    (count,) = sql(f"SELECT count(*) FROM '{tiles}/*.parquet'").fetchone()
    assert count == store.last_update["tiles_kept"] + store.last_update["tiles_scanned"]
    for column, tag in (("summary", b"ILts"), ("runs", b"ILtr")):
        rows = sql(
            f"SELECT {column} FROM read_parquet('{tiles}/*.parquet', filename = true, "
            "file_row_number = true) ORDER BY filename, file_row_number"
        ).fetchall()
        blobs = [bytes(b) for (b,) in rows]
        assert blobs == pq.read_table(tiles)[column].to_pylist()
        assert blobs and all(b[:4] == tag for b in blobs if b), column
    # The merges too: one a session pair with tiles, the second day's pairs in a part of their
    # own.
    merges = (state / "merges").as_posix()
    assert sorted(p.name for p in (state / "merges").iterdir()) == parts
    (pairs,) = sql(
        f"SELECT count(*) FROM (SELECT DISTINCT session_a, session_b FROM '{tiles}/*.parquet')"
    ).fetchone()
    rows = sql(f"SELECT session_a, session_b, merge FROM '{merges}/*.parquet'").fetchall()
    assert len(rows) == len({(a, b) for a, b, _ in rows}) == pairs
    assert all(bytes(m)[:4] == b"ILml" for _, _, m in rows)

    # The Python tables are those of find_fleet_loops, and a store read back is the same.
    assert_same_answer(store, all_sessions)
    assert_same_answer(il.FleetStore.open(folder), all_sessions)


@quiet
def test_random_adds_replacements_and_removals_equal_one_run(tmp_path: Path) -> None:
    """A seeded random sequence of updates, each checked against one run over the sessions
    then stored; a corrupt log on the way is refused and changes no file."""
    rng = np.random.default_rng(11)
    pool = sessions()
    names = sorted(pool)
    folder = tmp_path / "store"
    store = il.FleetStore.open(folder)
    stored: dict[str, il.Trajectory] = {}
    first = names[int(rng.integers(len(names)))]
    store.update(add=[(first, pool[first])], gamma=GAMMA, block=BLOCK, **SAMPLING)
    stored[first] = pool[first]
    kinds = []
    for step in range(6):
        kind = rng.choice(["add", "replace", "remove"])
        absent = [n for n in names if n not in stored]
        if kind == "add" and absent or not stored:
            new = list(
                rng.choice(absent, size=min(len(absent), int(rng.integers(1, 3))), replace=False)
            )
            update = store.update(add={n: pool[n] for n in new})
            stored.update({n: pool[n] for n in new})
            assert update["added"] == sorted(new)
        elif kind == "replace" or len(stored) == 1:
            name = sorted(stored)[int(rng.integers(len(stored)))]
            old = stored[name]
            moved = old.positions + rng.normal(0.0, 2.0, size=old.positions.shape)
            stored[name] = il.Trajectory(old.timestamps, moved)
            update = store.update(add=[(name, stored[name])])
            assert update["replaced"] == [name]
        else:
            name = sorted(stored)[int(rng.integers(len(stored)))]
            del stored[name]
            update = store.update(remove=[name])
            assert update["removed"] == [name]
        kinds.append(str(kind))
        assert_same_answer(store, stored)
        if step == 2:
            corrupt = tmp_path / "broken.tum"
            corrupt.write_text("0.0 1.0 2.0\nnot a pose\n")
            before = {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}
            with pytest.raises((il.errors.LoopsError, OSError, ValueError), match="broken.tum"):
                store.update(add=[corrupt])
            assert {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()} == before
    assert {"add", "replace", "remove"} <= set(kinds), kinds


def test_settings_are_fixed_when_the_store_is_made(tmp_path: Path) -> None:
    t = np.arange(30.0)
    line = il.Trajectory(t, np.c_[t, 0 * t])
    store = il.FleetStore.open(tmp_path / "s")
    assert len(store) == 0 and store.gamma is None and len(store.components["id"]) == 0
    with pytest.raises(il.errors.InvalidParameterError, match="needs its settings"):
        store.update(add=[("a", line)])
    store.update(add=[("a", line)], gamma=2.0, separation=None, block=8)
    assert (store.gamma, store.block, store.sampler, store.metric_name) == (
        2.0,
        8,
        None,
        "euclidean",
    )
    assert store.path == tmp_path / "s" and store.separation == il.Separation()
    with pytest.raises(il.errors.InvalidParameterError, match="gamma is 2 in the store, not 3"):
        store.update(add=[("b", line)], gamma=3.0, separation=None, block=8)
    with pytest.raises(il.errors.InvalidParameterError, match="given whole"):
        store.update(add=[("b", line)], block=8)
    with pytest.raises(il.errors.InvalidParameterError, match="is not in the store"):
        store.update(remove=["nobody"])
    assert store.names == ["a"]
    # The same settings given again are accepted.
    store.update(add=[("b", line)], gamma=2.0, separation=None, block=8)
    assert store.names == ["a", "b"] and store.last_update["added"] == ["b"]
    assert store.session_pairs()["components"].tolist() == [1, 1, 1]
    assert store.loop_duration("b")["session"].tolist() == [1] * len(t)
    (tmp_path / "theirs").mkdir()
    (tmp_path / "theirs" / "notes.txt").write_text("mine")
    with pytest.raises(FileNotFoundError, match="no fleet store here"):
        il.FleetStore.open(tmp_path / "theirs")


def open_and_describe(store: il.FleetStore) -> tuple[str, list[str], list[int]]:
    """In a worker process: what it sees of a store it was sent."""
    return str(store.path), store.names, store.components["pair_count"].tolist()


def test_a_store_pickles_as_its_folder(tmp_path: Path) -> None:
    t = np.arange(30.0)
    line = il.Trajectory(t, np.c_[t, 0 * t])
    store = il.FleetStore.open(tmp_path / "s")
    store.update(add=[("a", line), ("b", line)], gamma=2.0, separation=None, block=8)
    state = state_dir(tmp_path / "s")
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        data = pickle.dumps(store, protocol)
        assert len(data) < 1000  # the folder, not the tables
        back = pickle.loads(data)
        assert back.path == store.path and back.state_path == store.state_path == state
        assert back.names == store.names and back.gamma == store.gamma
        for key, column in store.components.items():
            np.testing.assert_array_equal(back.components[key], column, err_msg=key)
    # A process of its own opens the same folder.
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        (seen,) = pool.map(open_and_describe, [store])
    assert seen == open_and_describe(store)
    # Unpickled later, it is the store the folder holds then.
    data = pickle.dumps(store)
    store.update(remove=["b"])
    assert pickle.loads(data).names == ["a"]


def test_the_dask_runner_cuts_sessions_by_the_core_block() -> None:
    """One constant: the Dask runner's default block is the core's object, not a copy."""
    dask_runner = pytest.importorskip("inexact_loops.dask")
    assert dask_runner.DEFAULT_BLOCK is il.FleetStore.DEFAULT_BLOCK


def times_and_bytes(folder: Path) -> dict[str, tuple[int, bytes | None]]:
    """The folder and everything under it: each modification time, and each file's bytes."""
    paths = [folder, *folder.rglob("*")]
    return {str(p): (p.stat().st_mtime_ns, p.read_bytes() if p.is_file() else None) for p in paths}


@quiet
def test_an_update_that_changes_nothing_writes_nothing(tmp_path: Path) -> None:
    """Nothing given, or the stored sessions given again (as a rerun of yesterday's update
    gives them), in process or by the Dask runner without a cluster: nothing is written (no new
    state, no file or time of the folder touched), the summary says so, and the store's last
    update is still the one that changed it."""
    from inexact_loops.dask import update_store

    pool = sessions()
    folder = tmp_path / "store"
    store = il.FleetStore.open(folder)
    first = dict(list(pool.items())[:3])
    store.update(add=first, gamma=GAMMA, block=BLOCK, **SAMPLING)
    done = store.update(add=dict(list(pool.items())[3:]))
    before, state, added = times_and_bytes(folder), store.state_path, store.added.tolist()
    samples = store.samples.to_pandas()
    assert done["changed"] and done == store.last_update
    for add in (None, first, pool):
        update = store.update(add=add)
        assert not update["changed"] and update["tiles_scanned"] == 0
        assert update["unchanged"] == sorted(add or [])
        assert store.last_update == done and store.state_path == state
        assert store.added.tolist() == added
        assert store.samples.to_pandas().equals(samples)
        assert times_and_bytes(folder) == before, "an update that changes nothing wrote"
        again = il.FleetStore.open(folder)
        assert again.last_update == done and again.state_path == state
    summary = update_store(folder, add=first)
    assert not summary["last_update"]["changed"]
    assert summary["added_components"] == len(added)
    assert times_and_bytes(folder) == before, "an update that changes nothing wrote"


def table_bytes(folder: Path) -> dict[str, bytes]:
    """Every table of the current state, as its file's bytes."""
    return {p.name: p.read_bytes() for p in sorted(state_dir(folder).glob("*.parquet"))}


@quiet
def test_an_update_by_its_steps_writes_the_update_here(tmp_path: Path) -> None:
    """Plan (pickled, as a cluster ships it), each tile scanned on its own in reverse order,
    then the update with the scans: every table is the one-step update's, byte for byte; a
    missing scan, or scans of a plan of another state, are refused and change no file."""
    given = sessions()
    names = sorted(given)
    first = {n: given[n] for n in names[:3]}
    second = {n: given[n] for n in names[3:]}
    here, steps = tmp_path / "here", tmp_path / "steps"
    for folder in (here, steps):
        il.FleetStore.open(folder).update(add=first, gamma=GAMMA, block=BLOCK, **SAMPLING)
    il.FleetStore.open(here).update(add=second)

    plan = pickle.loads(pickle.dumps(il.StoreUpdatePlan(steps, add=second)))
    assert len(plan) > 1 and plan.last_update["added"] == names[3:]
    assert all(a in second or b in second for a, b in plan.tile_sessions)
    # Each scan reads only the new sessions its tile holds.
    scanned = [b for k in reversed(range(len(plan))) for b in plan.scan([k], add=second)]
    before = table_bytes(steps)
    store = il.FleetStore.open(steps)
    with pytest.raises(il.errors.LoopsError, match="was not scanned"):
        store.update(add=second, scanned=scanned[1:])
    other = il.StoreUpdatePlan(steps, add={names[3]: given[names[3]]})
    with pytest.raises(il.errors.LoopsError, match="was scanned for plan"):
        store.update(add=second, scanned=scanned[1:] + other.scan([0], add=second))
    assert table_bytes(steps) == before
    update = store.update(add=second, scanned=scanned)
    assert update["tiles_scanned"] == len(plan)
    assert table_bytes(steps) == table_bytes(here)
