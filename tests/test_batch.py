"""`loops run` over a batch of MCAP logs made by `loops synth`, checked against the Python API
on the same files; a corrupt log among them; interrupting a run."""

from __future__ import annotations

import csv
import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

GAMMA_M = 40.0
BUDGET = 300
SEED = 5
LOGS = 19  # and one corrupt log: a batch of 20
FILES = {"components.csv", "samples.csv", "loop_duration.csv", "summary.json", "report.html"}


def read_csv(path: Path) -> dict[str, list[str]]:
    """The columns of a CSV file, as text."""
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {name: [row[k] for row in body] for k, name in enumerate(header)}


def floats(column: list[str]) -> np.ndarray:
    return np.array([float(v) if v else np.nan for v in column])


def synth(loops_cli: Path, logs: Path, count: int, duration_s: int) -> list[Path]:
    """``count`` synthetic logs of ``duration_s`` seconds (`loops synth`) in ``logs``, sorted."""
    subprocess.run(
        [loops_cli, "synth", logs, "--count", str(count), "--duration-s", str(duration_s)],
        check=True,
        capture_output=True,
    )
    return sorted(logs.glob("*.mcap"))


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path):
    """19 synthetic logs (10 min each, seeds 0..18) and a truncated one: a batch of 20."""
    root = tmp_path_factory.mktemp("batch")
    logs = root / "logs"
    good = synth(loops_cli, logs, LOGS, 600)
    assert len(good) == LOGS
    corrupt = logs / "corrupt.mcap"
    data = good[0].read_bytes()
    corrupt.write_bytes(data[: len(data) // 2])
    inputs = {p: p.stat().st_mtime_ns for p in [*good, corrupt]}
    out = root / "results"
    args = [loops_cli, "run", *good[:9], corrupt, *good[9:], "--gamma", str(GAMMA_M)]
    args += ["--budget", str(BUDGET), "--seed", str(SEED), "--out", out]
    done = subprocess.run(args, capture_output=True, text=True)
    return {"logs": good, "corrupt": corrupt, "out": out, "run": done, "inputs": inputs}


def test_batch_reports_the_corrupt_log_and_finishes_the_others(batch) -> None:
    run, out = batch["run"], batch["out"]
    assert run.returncode == 1, run.stderr
    # Not a terminal: one plain line per log on stderr, the corrupt one with its error.
    lines = [line for line in run.stderr.splitlines() if line.startswith("loops: [")]
    assert len(lines) == LOGS + 1, run.stderr
    bad = [line for line in lines if "error:" in line]
    assert len(bad) == 1 and "corrupt" in bad[0], bad
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["logs"], summary["succeeded"], summary["failed"]) == (LOGS + 1, LOGS, 1)
    failed = [r for r in summary["results"] if not r["ok"]]
    assert failed[0]["name"] == "corrupt" and "corrupt.mcap" in failed[0]["error"]
    folders = sorted(p.name for p in out.iterdir() if p.is_dir())
    assert folders == sorted(p.stem for p in batch["logs"])
    for folder in folders:
        assert {p.name for p in (out / folder).iterdir()} == FILES
    assert not [p for p in out.rglob(".*")], "no hidden staging or temporary files are left"
    index = (out / "index.html").read_text()
    assert index.count("<tr") == LOGS + 2  # header, 19 logs, 1 failure
    assert "failed" in index and "report.html" in index
    # Inputs untouched.
    assert {p: p.stat().st_mtime_ns for p in batch["inputs"]} == batch["inputs"]
    # The table on stdout has a row per log.
    rows = [
        line for line in run.stdout.splitlines() if line.startswith(("urban-drive-", "corrupt "))
    ]
    assert len(rows) == LOGS + 1 and "19 done, 1 failed" in run.stdout, run.stdout
    assert [line for line in rows if "failed:" in line][0].startswith("corrupt ")


@pytest.mark.parametrize("k", range(LOGS))
def test_batch_numbers_equal_the_python_api(batch, k: int) -> None:
    log = batch["logs"][k]
    folder = batch["out"] / log.stem
    traj = il.read_trajectory(log)
    loops = il.find_loops(traj, gamma=GAMMA_M)
    samples = il.sample(loops, il.DEFAULT_SAMPLER, budget=BUDGET, seed=SEED, trajectory=traj)
    quality = il.sample_quality(samples, loops, epsilon_s=30.0)

    # components.csv: every column of Loops.components, and samples per component.
    table = read_csv(folder / "components.csv")
    ours = loops.components
    assert len(table["id"]) == len(ours["id"]) >= 1
    # Both default to the revisits 4 gamma apart along the path.
    assert loops.separation == il.Separation.for_gamma(GAMMA_M)
    for name in ("id", "pair_count", "run_count", "holes", "i_min", "i_max", "j_min", "j_max"):
        np.testing.assert_array_equal(
            np.array(table[name], dtype=np.int64), ours[name], err_msg=name
        )
    for name in (
        "area_s2",
        "t_min_s",
        "t_max_s",
        "t_prime_min_s",
        "t_prime_max_s",
        "closest_distance",
    ):
        np.testing.assert_array_equal(floats(table[name]), ours[name], err_msg=name)
    assert [v == "true" for v in table["trivial"]] == list(ours["trivial"])
    np.testing.assert_array_equal(np.array(table["samples"], dtype=np.int64), quality.per_component)

    # samples.csv: the same pairs as il.sample with the same sampler, budget and seed.
    rows = read_csv(folder / "samples.csv")
    np.testing.assert_array_equal(np.array(rows["i"], dtype=np.int64), samples.i)
    np.testing.assert_array_equal(np.array(rows["j"], dtype=np.int64), samples.j)
    np.testing.assert_array_equal(floats(rows["distance"]), samples.distance)
    assert set(rows["sampler"]) == {il.DEFAULT_SAMPLER}

    # loop_duration.csv: tau of every pose.
    durations = read_csv(folder / "loop_duration.csv")
    np.testing.assert_array_equal(floats(durations["t_s"]), traj.timestamps)
    np.testing.assert_array_equal(floats(durations["loop_duration_s"]), loops.loop_duration())

    # summary.json.
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["poses"] == len(traj)
    assert summary["pair_count"] == loops.pair_count
    assert summary["separation"] == {"path": 4 * GAMMA_M, "time_s": 0.0}
    assert summary["components"] == len(ours["id"])
    assert summary["quality"]["covered"] == quality.covered
    assert summary["samples"] == len(samples) == BUDGET
    t = traj.timestamps
    assert summary["loop_density_s"] == pytest.approx(loops.loop_density(t[0], t[-1]), rel=1e-12)


def test_skip_trivial_run_equals_the_python_api(tmp_path: Path, batch, loops_cli: Path) -> None:
    log = batch["logs"][2]
    out = tmp_path / "skip"
    args = ["--gamma", "40", "--budget", "300", "--seed", "5", "--out", out, "--quiet"]
    done = subprocess.run(
        [loops_cli, "run", log, *args, "--skip-trivial"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    folder = out / log.stem
    traj = il.read_trajectory(log)
    found = il.find_loops(traj, gamma=40.0)
    samples = il.sample(
        found, il.DEFAULT_SAMPLER, budget=300, seed=5, trajectory=traj, skip_trivial=True
    )
    rows = read_csv(folder / "samples.csv")
    np.testing.assert_array_equal(np.array(rows["i"], dtype=np.int64), samples.i)
    np.testing.assert_array_equal(np.array(rows["j"], dtype=np.int64), samples.j)
    trivial = found.components["trivial"]
    assert not trivial[np.array(rows["component"], dtype=np.int64)].any()
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["skip_trivial"] is True and summary["samples"] == 300
    assert json.loads((out / "summary.json").read_text())["skip_trivial"] is True
    assert "(trivial components skipped)" in (folder / "report.html").read_text()
    refused = subprocess.run(
        [loops_cli, "run", log, *args, "--skip-trivial", "--sampler", "lio-sam"],
        capture_output=True,
        text=True,
    )
    assert refused.returncode == 2 and "--skip-trivial does not apply" in refused.stderr


def test_python_writes_the_files_of_loops_run(tmp_path: Path, batch, loops_cli: Path) -> None:
    """components.csv and loop_duration.csv from Python are, byte for byte, those of `loops run`;
    the JSON report those of `loops components --json`."""
    log = batch["logs"][0]
    folder = batch["out"] / log.stem
    traj = il.read_trajectory(log)
    loops = il.find_loops(traj, gamma=GAMMA_M)
    samples = il.sample(loops, il.DEFAULT_SAMPLER, budget=BUDGET, seed=SEED, trajectory=traj)
    per_component = il.sample_quality(samples, loops).per_component
    loops.components_to_csv(tmp_path / "components.csv", samples_per_component=per_component)
    loops.loop_duration_to_csv(tmp_path / "loop_duration.csv", traj)
    for name in ("components.csv", "loop_duration.csv"):
        assert (tmp_path / name).read_bytes() == (folder / name).read_bytes(), name
    loops.to_json(tmp_path / "loops.json", source=str(log))
    cli = subprocess.run(
        [loops_cli, "components", log, "--gamma", str(GAMMA_M), "--json", "-"],
        capture_output=True,
        check=True,
    )
    assert (tmp_path / "loops.json").read_bytes() == cli.stdout
    # Kept unless overwrite; replaced with it; nothing else left in the folder.
    with pytest.raises(FileExistsError):
        loops.components_to_csv(tmp_path / "components.csv")
    loops.components_to_csv(tmp_path / "components.csv", overwrite=True)
    assert "samples" not in (tmp_path / "components.csv").read_text().splitlines()[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "components.csv",
        "loop_duration.csv",
        "loops.json",
    ]
    other = il.Trajectory(traj.timestamps[:-1], traj.positions[:-1])
    with pytest.raises(il.InvalidParameterError, match="different trajectories"):
        loops.loop_duration_to_csv(tmp_path / "other.csv", other)


def test_concurrent_runs_into_one_folder(tmp_path: Path, loops_cli: Path) -> None:
    """A second `loops run` into a folder a run holds stops at once, naming
    the folder and the holder's pid; the first finishes undisturbed."""
    logs = synth(loops_cli, tmp_path / "logs", 2, 1800)
    out = tmp_path / "results"
    out.mkdir()
    args = [loops_cli, "run", *logs, "--out", out, "--threads", "1"]
    first = subprocess.Popen(
        [*args, "--gamma", "20"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 60
    while not (out / "loops-run.json").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    second = subprocess.run([*args, "--gamma", "40", "--force"], capture_output=True, text=True)
    running = first.poll() is None
    first.communicate(timeout=600)
    if not running:
        pytest.skip("the first run finished before the second started")
    assert second.returncode == 2, second.stderr
    assert str(out) in second.stderr and f"pid {first.pid}" in second.stderr, second.stderr
    assert first.returncode == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["gamma"], summary["succeeded"], summary["failed"]) == (20.0, 2, 0)
    assert not [p for p in out.rglob(".*")]


def test_existing_results_are_kept_without_force(batch, loops_cli: Path) -> None:
    out = batch["out"]
    before = (out / "summary.json").read_bytes()
    again = subprocess.run(
        [loops_cli, "run", batch["logs"][0], "--gamma", "40", "--out", out],
        capture_output=True,
        text=True,
    )
    assert again.returncode == 2
    assert "--force" in again.stderr and len(again.stderr.strip().splitlines()) == 1
    assert (out / "summary.json").read_bytes() == before


def test_force_replaces_only_results(tmp_path: Path, batch, loops_cli: Path) -> None:
    out = tmp_path / "results"
    log = batch["logs"][1]
    first = subprocess.run(
        [loops_cli, "run", log, "--gamma", "40", "--out", out], capture_output=True
    )
    assert first.returncode == 0, first.stderr
    redo = [loops_cli, "run", log, "--gamma", "30", "--out", out, "--force", "--quiet"]
    second = subprocess.run(redo, capture_output=True, text=True)
    assert second.returncode == 0 and second.stdout == "" and second.stderr == ""
    assert json.loads((out / log.stem / "summary.json").read_text())["gamma"] == 30.0
    # A folder of the user's with a log's name is never replaced.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / log.stem).mkdir()
    (mine / log.stem / "notes.txt").write_text("keep me")
    clash = subprocess.run(
        [loops_cli, "run", log, "--gamma", "40", "--out", mine, "--force"],
        capture_output=True,
        text=True,
    )
    assert clash.returncode == 1
    assert "not an output of `loops run`" in clash.stderr
    assert (mine / log.stem / "notes.txt").read_text() == "keep me"


def test_json_summary_on_stdout(tmp_path: Path, batch, loops_cli: Path) -> None:
    out = tmp_path / "results"
    done = subprocess.run(
        [loops_cli, "run", *batch["logs"][:2], "--gamma", "40", "--out", out, "--json", "-"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary == json.loads((out / "summary.json").read_text())
    assert [r["name"] for r in summary["results"]] == [p.stem for p in batch["logs"][:2]]


def test_interrupt_leaves_no_partial_output(
    tmp_path: Path, loops_cli: Path, interrupt_batch
) -> None:
    """SIGINT in the middle of a batch: finished logs stay whole, unfinished ones vanish."""
    logs = synth(loops_cli, tmp_path / "logs", 8, 1800)
    out = tmp_path / "results"
    args = [loops_cli, "run", *logs, "--gamma", "40", "--out", out]
    rest = interrupt_batch([*args, "--threads", "1"], 8)
    assert "interrupted" in rest
    entries = list(out.iterdir()) if out.exists() else []
    assert not [p for p in entries if p.name.startswith(".")], entries
    assert not (out / "index.html").exists() or (out / "summary.json").exists()
    finished = [p for p in entries if p.is_dir()]
    assert 1 <= len(finished) < 8
    for folder in finished:
        assert {p.name for p in folder.iterdir()} == FILES
        json.loads((folder / "summary.json").read_text())
        assert (folder / "report.html").read_text().rstrip().endswith("</html>")
