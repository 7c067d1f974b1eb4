"""The parts of the attack sweep (issue 15) that are not about file contents: calls with wrong
types and values through the whole Python API, `loops run` killed at seeded moments, runs at
the same time, and the C ABI attacked from C under AddressSanitizer. Each part counts its
cases and fails on a panic, an abort, or a lost or half-written result. (Corrupted and crafted
files: `crates/loops-io/tests/attack_sweep.rs`.)

Seeded: `LOOPS_SWEEP_SEED` changes the seed, `LOOPS_SWEEP_ROUNDS` the number of kills (and a
hundredth of the C ABI's cases).
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

SEED = int(os.environ.get("LOOPS_SWEEP_SEED", "15"))
ROUNDS = int(os.environ.get("LOOPS_SWEEP_ROUNDS", "8"))
ROOT = Path(__file__).resolve().parents[1]
FILES = {"components.csv", "samples.csv", "loop_duration.csv", "summary.json", "report.html"}

#: Runs in a child: a panic that escapes, or an abort, ends the child, not this test.
WRONG_CALLS = r"""
import inspect, json, random, sys, warnings
import numpy as np
import inexact_loops as il

warnings.simplefilter("ignore")
rng = random.Random(int(sys.argv[1]))
traj = il.urban_drive(duration_s=300.0)
loops = il.find_loops(traj, gamma=40.0)
samples = il.sample(loops, "rho", budget=20, seed=0, trajectory=traj)
fleet = il.urban_fleet(vehicles=2, duration_s=200.0)
fleet_loops = il.find_fleet_loops(fleet, gamma=40.0)
instances = [traj, loops, samples, il.sample_quality(samples, loops), fleet, fleet_loops,
             il.PlaneGrid(traj, 16), il.Separation(time_s=10.0)]

WRONG = [None, "x", "", b"\xff", [], [[1.0]], {}, object(), -1, 0, 2**70, -2**70, float("nan"),
         float("inf"), -0.0, 1e308, True, np.zeros((0, 3)), np.array(["a", "b"]),
         np.full((3, 3), np.nan), np.zeros((2, 2, 2)), traj, loops, samples, lambda *a: "x"]

def candidates():
    for name in il.__all__:
        value = getattr(il, name)
        if callable(value) and not (isinstance(value, type) and issubclass(value, BaseException)):
            yield name, value
    for obj in instances:
        for name in dir(obj):
            if name.startswith("_"):
                continue
            try:
                value = getattr(obj, name)
            except Exception:
                continue
            if callable(value):
                yield f"{type(obj).__name__}.{name}", value

# Plausible values by parameter name, mixed with the wrong ones, so that calls get past the
# first argument's conversion and reach the checks of values and of their combinations.
PLAUSIBLE = {
    "gamma": [40.0, 1e-300, 1e300, -1.0, 0.0, float("nan")],
    "budget": [10, 0, -1, 2**62],
    "seed": [0, 2**64 - 1, -1],
    "traj": [traj], "trajectory": [traj], "loops": [loops], "samples": [samples], "fleet": [fleet],
    "metric": ["euclidean", "se3", "so3(rotation=chordal,rotation=geodesic)", "nope", None],
    "sampler": ["rho", "one", "alpha", "closest-first", "nope"],
    "separation": [il.Separation(time_s=10.0), None],
    "epsilon_s": [1.0, -1.0, float("inf")],
    "axes": [(0, 1), (0, 0), (5, 9), ()],
    "path": ["x", "/dev/null", "/nonexistent/x"],
    "dim": [2, 0, 2**16 + 1, 2**62],
}
# Calls that would legitimately run long get only modest numbers.
SLOW = {"urban_drive", "urban_fleet"}
counts = {"calls": 0, "ok": 0, "raised": 0, "panics": 0, "multi_line": 0, "foreign": 0}
bad = []
names = list(candidates())

def arguments(name, function):
    try:
        parameters = list(inspect.signature(function).parameters.values())
    except (TypeError, ValueError):
        parameters = []
    args, kwargs = [], {}
    for p in parameters:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.name == "self":
            continue
        if p.default is not p.empty and rng.random() < 0.5:
            continue
        pool = PLAUSIBLE.get(p.name, [1, 0.5, 10])
        value = rng.choice(pool) if rng.random() < 0.7 else rng.choice(WRONG)
        if name in SLOW and isinstance(value, (int, float)) and not abs(value) <= 1e4:
            value = 10.0
        if p.kind == p.KEYWORD_ONLY:
            kwargs[p.name] = value
        else:
            args.append(value)
    if not parameters:
        args = [rng.choice(WRONG) for _ in range(rng.randint(0, 3))]
    return args, kwargs

for round in range(int(sys.argv[2])):
    for name, function in names:
        args, kwargs = arguments(name, function)
        counts["calls"] += 1
        try:
            function(*args, **kwargs)
            counts["ok"] += 1
        except (TypeError, ValueError, il.LoopsError, OverflowError, IndexError, KeyError,
                MemoryError, OSError, AttributeError, NotImplementedError) as error:
            counts["raised"] += 1
            text = str(error)
            if "\n" in text.strip():
                counts["multi_line"] += 1
                bad.append(f"{name}{tuple(map(type, args))}: multi-line: {text[:200]!r}")
        except BaseException as error:  # pyo3's PanicException derives from BaseException
            if type(error).__name__ == "PanicException":
                counts["panics"] += 1
            else:
                counts["foreign"] += 1
            bad.append(f"{name}: {type(error).__name__}: {str(error)[:200]}")
print(json.dumps({"counts": counts, "bad": bad[:20], "names": len(names)}))
"""


def test_wrong_types_and_values_through_the_whole_api_raise_one_line_errors(tmp_path: Path) -> None:
    # In a folder of its own: a writer given a wrong but valid path ("x") writes there.
    child = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(WRONG_CALLS), str(SEED), "20"],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=tmp_path,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    # A negative return code is a signal: an abort or a crash of the interpreter.
    assert child.returncode == 0, f"exit {child.returncode}: {child.stderr[-3000:]}"
    report = json.loads(child.stdout.strip().splitlines()[-1])
    counts = report["counts"]
    print(f"{report['names']} callables; {counts}")
    assert report["names"] > 60, report["names"]
    assert counts["calls"] == counts["ok"] + counts["raised"] + counts["panics"] + counts["foreign"]
    assert counts["raised"] > counts["calls"] // 2, counts  # the wrong values did reach the checks
    assert counts["panics"] == 0 and counts["foreign"] == 0 and counts["multi_line"] == 0, report[
        "bad"
    ]


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path) -> list[Path]:
    root = tmp_path_factory.mktemp("sweep-logs")
    subprocess.run(
        [loops_cli, "synth", root, "--count", "4", "--duration-s", "900"],
        check=True,
        capture_output=True,
    )
    found = sorted(root.glob("*.mcap"))
    assert len(found) == 4
    return found


def run_args(loops_cli: Path, logs: list[Path], out: Path, *extra: str) -> list[str]:
    return [
        str(loops_cli),
        "run",
        *map(str, logs),
        "--gamma",
        "40",
        "--budget",
        "200",
        "--seed",
        "3",
        "--out",
        str(out),
        "--quiet",
        *extra,
    ]


def complete_results(out: Path, logs: list[Path]) -> dict[str, bytes]:
    """Every visible per-log folder in `out` is whole: its five files, its summary.json parses.
    Returns the per-log CSV files' contents."""
    contents = {}
    for folder in sorted(p for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")):
        assert {p.name for p in folder.iterdir()} == FILES, (
            f"{folder}: {sorted(os.listdir(folder))}"
        )
        json.loads((folder / "summary.json").read_text())
        for name in ("components.csv", "samples.csv", "loop_duration.csv"):
            contents[f"{folder.name}/{name}"] = (folder / name).read_bytes()
    return contents


def test_loops_run_killed_at_seeded_moments_loses_nothing(
    tmp_path: Path, loops_cli: Path, logs
) -> None:
    rng = random.Random(SEED)
    reference = tmp_path / "reference"
    start = time.monotonic()
    subprocess.run(run_args(loops_cli, logs, reference), check=True, capture_output=True)
    full_s = time.monotonic() - start
    expected = complete_results(reference, logs)
    assert len(expected) == 3 * len(logs)

    kills = {"before_any_log": 0, "partial": 0, "after_all": 0}
    for round in range(ROUNDS):
        out = tmp_path / f"out-{round}"
        out.mkdir()
        # The user's own files, which --force must keep.
        (out / "notes.txt").write_text("mine")
        (out / ".hidden-notes").write_text("mine too")
        child = subprocess.Popen(run_args(loops_cli, logs, out, "--force"), stderr=subprocess.PIPE)
        time.sleep(rng.uniform(0.0, full_s))
        child.send_signal(signal.SIGKILL)
        child.wait()
        assert (out / "notes.txt").read_text() == "mine" and (
            out / ".hidden-notes"
        ).read_text() == "mine too"
        partial = complete_results(out, logs)
        # What is there equals the uninterrupted run's, file for file.
        for name, data in partial.items():
            assert data == expected[name], name
        done = len(partial) // 3
        kills[
            "before_any_log" if done == 0 else "after_all" if done == len(logs) else "partial"
        ] += 1
        # The next run into the folder finishes, removes the leftovers and keeps the user's files.
        again = subprocess.run(
            run_args(loops_cli, logs, out, "--force"), capture_output=True, text=True
        )
        assert again.returncode == 0, again.stderr
        assert complete_results(out, logs) == expected
        assert (out / "notes.txt").read_text() == "mine" and (
            out / ".hidden-notes"
        ).read_text() == "mine too"
        leftovers = [
            p.name for p in out.iterdir() if p.name.startswith(".") and p.name != ".hidden-notes"
        ]
        assert leftovers == [], leftovers
    print(f"{ROUNDS} kills over a {full_s:.1f} s run: {kills}")


def test_runs_at_the_same_time(tmp_path: Path, loops_cli: Path, logs) -> None:
    # Into different folders: all finish, with the same results.
    outs = [tmp_path / f"apart-{k}" for k in range(3)]
    children = [
        subprocess.Popen(run_args(loops_cli, logs, out), stderr=subprocess.PIPE, text=True)
        for out in outs
    ]
    for child in children:
        _, err = child.communicate(timeout=600)
        assert child.returncode == 0, err
    results = [complete_results(out, logs) for out in outs]
    assert results[0] == results[1] == results[2]

    # Into one folder: the runs that find it held stop with one line naming it; what the folder
    # holds at the end is one whole run's results, never a mix.
    shared = tmp_path / "shared"
    children = [
        subprocess.Popen(
            run_args(loops_cli, logs, shared, "--force"), stderr=subprocess.PIPE, text=True
        )
        for _ in range(3)
    ]
    codes = []
    for child in children:
        _, err = child.communicate(timeout=600)
        codes.append(child.returncode)
        if child.returncode != 0:
            lines = err.strip().splitlines()
            assert len(lines) == 1 and str(shared) in lines[0], err
    assert 0 in codes, codes
    assert complete_results(shared, logs) == results[0]


def test_the_c_abi_attacked_from_c_under_address_sanitizer(tmp_path: Path) -> None:
    """`crates/loops-capi/tests/c/attacks.c`, built with AddressSanitizer and
    UndefinedBehaviorSanitizer against the debug `libinexact_loops.a`: a seeded sweep of cap
    kinds outside the enum, huge dimensions and counts, engines freed and made again, updates
    offered twice and NULL pointers; every call returns the status it deserves, with nothing
    read or written out of bounds and nothing leaked."""
    cc = next(
        (
            shutil.which(n)
            for n in (os.environ.get("CC", ""), "cc", "gcc", "clang")
            if n and shutil.which(n)
        ),
        None,
    )
    cargo = shutil.which("cargo")
    if cc is None or cargo is None:
        pytest.skip("the C ABI sweep needs cargo and a C compiler (cc, gcc or clang)")
    subprocess.run([cargo, "build", "--quiet", "-p", "loops-capi"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    library = (target if target.is_absolute() else ROOT / target) / "debug" / "libinexact_loops.a"
    binary = tmp_path / "attacks"
    sanitizers = ["-fsanitize=address,undefined", "-fno-sanitize-recover=undefined"]
    build = [cc, "-std=c11", "-g", "-O1", "-fno-omit-frame-pointer", "-Wall", "-Wextra", "-Werror"]
    capi = ROOT / "crates" / "loops-capi"
    source = [f"-I{capi / 'include'}", str(capi / "tests" / "c" / "attacks.c"), str(library)]
    built = subprocess.run(
        [*build, *sanitizers, *source, "-lpthread", "-ldl", "-lm", "-o", str(binary)],
        capture_output=True,
        text=True,
    )
    if built.returncode != 0 and "sanitize" in built.stderr:
        pytest.skip(f"{cc} cannot build with AddressSanitizer here: {built.stderr[-300:]}")
    assert built.returncode == 0, built.stderr
    child = subprocess.run(
        [str(binary), str(SEED), str(100 * ROUNDS)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0"},
    )
    # A negative return code is a crash; a sanitizer's report exits 1 with its report on stderr.
    assert child.returncode == 0, (
        f"exit {child.returncode}: {child.stdout[-2000:]}{child.stderr[-3000:]}"
    )
    kinds = {}
    for line in child.stdout.splitlines():
        name, cases, refused, accepted = line.split()
        kinds[name] = (int(cases), int(refused), int(accepted))
    print(kinds)
    assert set(kinds) == {
        "cap_kind",
        "dim",
        "count",
        "remade_engine",
        "offered_twice",
        "null_pointers",
    }
    # Every kind ran, and the bad values were among the cases.
    assert all(cases > 0 for cases, _, _ in kinds.values()), kinds
    assert all(kinds[k][1] > 0 for k in ("cap_kind", "dim", "count", "offered_twice")), kinds
