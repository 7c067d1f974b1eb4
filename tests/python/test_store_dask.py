"""The fleet store updated on a Dask ``LocalCluster`` of 2 worker processes
(:func:`inexact_loops.dask.update_store`: a plan task, scan tasks spread over the workers, an
apply task) against the store updated in this process and one made at once from the final
sessions: every table of every state, bit for bit (pyarrow reads them), after a seeded random
sequence of adds, replacements and removals; the scans run on both workers (the scheduler's
task stream); a corrupt log refused on the worker changes no file; a worker killed during the
scans or the apply leaves the old state or the new one.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

pytest.importorskip("distributed", reason="dask.distributed: pip install '.[dask]'")
pq = pytest.importorskip("pyarrow.parquet")

from inexact_loops.dask import local_client, update_store  # noqa: E402

quiet = pytest.mark.filterwarnings("ignore::inexact_loops.errors.LoopsWarning")

SETTINGS = {"gamma": 40.0, "block": 300, "sampler": "one", "budget": 40, "seed": 3}
#: The tables of a state that hold the answer (the others hold how it is kept).
ANSWER = ("components", "session_pairs", "loop_duration", "samples")
TABLES = ("sessions", "tiles", "merges", *ANSWER)
#: The tables kept by part (a folder of Parquet files), with the columns that order their rows.
PARTS = {
    "tiles": ("session_a", "session_b", "rows_start", "columns_start"),
    "merges": ("session_a", "session_b"),
}
#: The store's ownership marker (it names the last process that held the store).
MARKER = "loops-store.json"


@pytest.fixture(scope="module")
def client():
    with local_client() as client:
        yield client


def write_tum(path: Path, t: np.ndarray, xy: np.ndarray) -> Path:
    """A TUM file (t x y z qx qy qz qw) of planar poses, written to read back bit for bit."""
    n = len(t)
    np.savetxt(path, np.c_[t, xy, np.zeros(n), np.zeros((n, 3)), np.ones(n)], fmt="%.17g")
    return path


def pool(folder: Path) -> dict[str, list[Path]]:
    """Two versions of each session of three cars on two days, as TUM files, by name."""
    fleet = il.urban_fleet(vehicles=3, days=2, duration_s=200.0, seed=5)
    rng = np.random.default_rng(2)
    folder.mkdir(parents=True, exist_ok=True)
    files: dict[str, list[Path]] = {}
    for name in fleet.names:
        t = fleet.session(name)
        xy = t.positions[:, :2]
        files[name] = [
            write_tum(folder / f"{name}.v0.tum", t.timestamps, xy),
            write_tum(folder / f"{name}.v1.tum", t.timestamps, xy + rng.normal(0, 2.0, xy.shape)),
        ]
    return files


def state(folder: Path) -> Path:
    return folder / json.loads((folder / "store.json").read_text())["state"]


def table_bits(folder: Path, name: str, drop: tuple[str, ...] = ()) -> dict[str, bytes]:
    """A table's columns as bytes: floats bit for bit. The tiles and the merges are the rows of
    every part of the state's folders ``tiles`` and ``merges``, by sessions (and place: how
    they fall into parts depends on the updates that wrote them)."""
    if name in PARTS:
        table = pq.read_table(state(folder) / name).sort_by([(c, "ascending") for c in PARTS[name]])
        table = table.to_pydict()
    else:
        table = pq.read_table(state(folder) / f"{name}.parquet").to_pydict()
    out = {}
    for column, values in table.items():
        if column in drop:
            continue
        if values and isinstance(values[0], float):
            out[column] = np.asarray(values, dtype=np.float64).tobytes()
        else:
            out[column] = repr(values).encode()
    return out


def times_and_bytes(folder: Path) -> dict[str, tuple[int, bytes | None]]:
    """The folder and everything under it: each modification time, and each file's bytes."""
    paths = [folder, *folder.rglob("*")]
    return {str(p): (p.stat().st_mtime_ns, p.read_bytes() if p.is_file() else None) for p in paths}


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def assert_same_tables(got: Path, want: Path, tables=TABLES, drop: tuple[str, ...] = ()) -> None:
    for name in tables:
        assert table_bits(got, name, drop) == table_bits(want, name, drop), name


@quiet
def test_random_updates_on_the_cluster_equal_in_process_and_from_scratch(tmp_path, client):
    files = pool(tmp_path / "logs")
    names = sorted(files)
    rng = np.random.default_rng(7)
    on_cluster, here = tmp_path / "cluster", tmp_path / "here"
    local = il.FleetStore.open(here)
    held: dict[str, int] = {}
    kinds = []
    for step in range(7):
        absent = [n for n in names if n not in held]
        kind = "add" if not held else str(rng.choice(["add", "replace", "remove"]))
        if kind == "add" and not absent:
            kind = "replace"
        add: dict[str, str] = {}
        remove: list[str] = []
        if kind == "add":
            for name in rng.choice(absent, size=min(2, len(absent)), replace=False):
                held[str(name)] = int(rng.integers(2))
                add[str(name)] = str(files[str(name)][held[str(name)]])
        elif kind == "replace":
            name = sorted(held)[int(rng.integers(len(held)))]
            held[name] = 1 - held[name]
            add[name] = str(files[name][held[name]])
        else:
            name = sorted(held)[int(rng.integers(len(held)))]
            del held[name]
            remove.append(name)
        kinds.append(kind)
        settings = SETTINGS if step == 0 else {}
        summary = update_store(
            on_cluster, add=add or None, remove=remove or None, client=client, **settings
        )
        want = local.update(add=add or None, remove=remove or None, **settings)
        assert summary["last_update"] == dict(want)
        assert summary["names"] == sorted(held) == local.names
        assert summary["components"] == len(local.components["id"])
        # Every table, bit for bit, and the settings.
        assert_same_tables(on_cluster, here)
        assert (state(on_cluster) / "settings.json").read_text() == (
            state(here) / "settings.json"
        ).read_text()
        if step == 3:
            broken = tmp_path / "logs" / "broken.tum"
            broken.write_text("0.0 1.0 2.0\nnot a pose\n")
            before = files_of(on_cluster)
            with pytest.raises((il.errors.LoopsError, OSError, ValueError), match="broken.tum"):
                update_store(on_cluster, add=[str(broken)], client=client)
            assert files_of(on_cluster) == before
    assert {"add", "replace", "remove"} <= set(kinds), kinds
    # From scratch: one update of the final sessions; the answer's tables, bit for bit.
    scratch = tmp_path / "scratch"
    final = {name: str(files[name][v]) for name, v in held.items()}
    update_store(scratch, add=final, client=client, **SETTINGS)
    assert_same_tables(on_cluster, scratch, ("sessions", "tiles", "merges"))
    assert_same_tables(on_cluster, scratch, ANSWER, drop=("added",))


@quiet
def test_scans_run_on_both_workers_and_equal_the_update_here(tmp_path, client):
    """The scan tasks of one update land on both workers (the scheduler's record of where
    each task ran), and the store they make is the in-process update's, bit for bit."""
    from distributed import get_task_stream

    files = pool(tmp_path / "logs")
    names = sorted(files)
    first = {n: str(files[n][0]) for n in names[:2]}
    second = {n: str(files[n][0]) for n in names[2:]}
    here, there = tmp_path / "here", tmp_path / "there"
    update_store(here, add=first, **SETTINGS)
    update_store(there, add=first, client=client, **SETTINGS)
    want = update_store(here, add=second)
    with get_task_stream(client) as stream:
        got = update_store(there, add=second, client=client, groups=8)
    assert got["last_update"] == want["last_update"]
    assert got["last_update"]["tiles_scanned"] >= 8
    scans = [t for t in stream.data if str(t["key"]).startswith("store_scan_task")]
    assert len(scans) == 8
    assert len({t["worker"] for t in scans}) == 2, [t["worker"] for t in scans]
    assert_same_tables(there, here)
    # Run again (yesterday's update, and one of nothing): nothing changed, nothing written.
    written = times_and_bytes(there)
    for add in (second, None):
        again = update_store(there, add=add, client=client)
        assert not again["last_update"]["changed"], again
        assert again["state_path"] == got["state_path"]
        assert again["added_components"] == got["added_components"]
        assert times_and_bytes(there) == written


def test_trajectories_are_refused_with_a_client(client):
    line = il.Trajectory(np.arange(5.0), np.c_[np.arange(5.0), np.zeros(5)])
    with pytest.raises(TypeError, match="workers read every session from a path"):
        update_store("unused", add={"a": line}, client=client)


@quiet
def test_a_worker_killed_mid_update_leaves_the_old_or_the_new_state(tmp_path):
    """Each trial SIGKILLs a worker while it runs a scan task (even trials) or the apply task
    (odd trials), a seeded moment after the task starts, on a cluster that does not run a task
    again: the store is the old state or the new one, never a mix, and the next update ends in
    the new state."""
    import dask

    files = pool(tmp_path / "logs")
    names = sorted(files)
    first = {n: str(files[n][0]) for n in names[:3]}
    second = {n: str(files[n][0]) for n in names[3:]}
    # The new state as an update in this process writes it.
    here = tmp_path / "here"
    update_store(here, add=first, **SETTINGS)
    update_store(here, add=second)
    rng = np.random.default_rng(4)
    outcomes, hit = [], []
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 0}),
        local_client() as client,
    ):
        for trial in range(6):
            client.wait_for_workers(1, timeout=120)
            target = "store_scan_task" if trial % 2 == 0 else "store_update_task"
            folder = tmp_path / f"killed{trial}"
            update_store(folder, add=first, client=client, **SETTINGS)
            old_files = files_of(folder)
            pids = client.run(os.getpid)
            result: dict[str, object] = {}

            def run(folder=folder, result=result):
                try:
                    result["summary"] = update_store(folder, add=second, client=client)
                except Exception as error:  # noqa: BLE001 - the kill, as the client sees it
                    result["error"] = error

            thread = threading.Thread(target=run)
            thread.start()
            # Wait until a worker runs a task of the target kind, then kill it a moment later.
            deadline = time.monotonic() + 60
            busy: list[str] = []
            while not busy and time.monotonic() < deadline and thread.is_alive():
                busy = [
                    w
                    for w, keys in client.processing().items()
                    if any(str(k).startswith(target) for k in keys)
                ]
                time.sleep(0.002)
            if busy:
                time.sleep(float(rng.uniform(0.0, 0.05)))
                # A worker the nanny restarted after `pids` was taken is asked for its pid now.
                pid = pids.get(busy[0]) or client.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, signal.SIGKILL)
                hit.append(target)
            thread.join(120)
            assert not thread.is_alive()
            now = files_of(folder)
            if state(folder).name == "state-000001":
                # What a killed update leaves besides (its scratch folder) the next one removes.
                changed = [k for k, v in old_files.items() if k != MARKER and now.get(k) != v]
                assert not changed, f"trial {trial}: the old state, changed: {changed}"
                outcomes.append("old")
                # The next update ends in the new state.
                client.wait_for_workers(1, timeout=120)
                update_store(folder, add=second, client=client)
            else:
                outcomes.append("new")
            assert_same_tables(folder, here)
            assert "error" in result or "old" not in outcomes[-1:], (
                "a finished update left the old state"
            )
    assert "old" in outcomes, outcomes
    assert {"store_scan_task", "store_update_task"} <= set(hit), hit


@quiet
def test_an_apply_run_again_after_its_result_was_lost_writes_nothing(tmp_path):
    """When a worker dies holding the apply task's result, after the task wrote the new state,
    the scheduler runs the plan, the scans and the apply again (the client still wants the
    result): the store already holds the update, so the second apply writes nothing and
    reports the update it repeats. Run here by the tasks' own functions, in the order the
    scheduler runs them; an apply not told what the plan changes (``changes=None``, as before)
    wrote a further state of an empty update there, which marked no component as added."""
    from inexact_loops.dask._store import (
        plan_summary,
        store_plan_task,
        store_scan_task,
        store_update_task,
    )

    files = pool(tmp_path / "logs")
    names = sorted(files)
    first = {n: str(files[n][0]) for n in names[:3]}
    second = {n: str(files[n][0]) for n in names[3:]}
    second[names[0]] = str(files[names[0]][1])  # one session replaced too
    folder = tmp_path / "store"
    update_store(folder, add=first, **SETTINGS)

    def tasks(count: int | None = None):
        plan = store_plan_task(str(folder), second, None, {})
        tiles, changes = plan_summary(plan)
        count = tiles if count is None else count  # the client's count, fixed at the first run
        scans = [store_scan_task(plan, g, count, second, {}) for g in range(count)]
        return count, changes, scans

    count, changes, scans = tasks()
    assert changes["added"] == names[3:] and changes["replaced"] == [names[0]]
    done = store_update_task(str(folder), second, None, {}, scans, changes)
    assert done["added_components"] > 0
    after = files_of(folder)
    _, _, scans_again = tasks(count)
    again = store_update_task(str(folder), second, None, {}, scans_again, changes)
    assert files_of(folder) == after
    assert again == done
    here = tmp_path / "here"
    update_store(here, add=first, **SETTINGS)
    update_store(here, add=second)
    assert_same_tables(folder, here)


@quiet
def test_loops_dask_says_in_one_line_that_a_day_given_again_changes_nothing(tmp_path, capsys):
    """``loops-dask --store`` run again with a day already stored: one line says nothing
    changed, and nothing is written (every file and time as it was)."""
    from inexact_loops.dask._cli import main

    files = pool(tmp_path / "logs")
    day = [str(files[n][0]) for n in sorted(files) if n.endswith("day0")]
    folder = tmp_path / "store"
    assert main([*day, "--store", str(folder), "--gamma", "40", "--block", "300"]) == 0
    capsys.readouterr()
    written = times_and_bytes(folder)
    assert main([*day, "--store", str(folder)]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1, out
    assert "nothing changed, nothing written: 3 stored as given" in out, out
    assert times_and_bytes(folder) == written
