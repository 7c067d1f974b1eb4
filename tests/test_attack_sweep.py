"""The parts of the attack sweep that are not about file contents: calls with wrong types and
values through the whole Python API, `loops run` killed at seeded moments, runs at the same
time, output folders holding a user's leftover-shaped entries and outputs aimed at the logs,
Ctrl-C or a kill while `loops` or Python reads a file-compressed rosbag2 bag (no decompressed
copy may stay in the temporary folder), forged pickles, bad arguments to every console script,
threads sharing one engine, and the C ABI attacked from C under AddressSanitizer. Each part
counts its cases and fails on a panic, an abort, a hang, a lost, overwritten or half-written
result, a file left behind, or an error of more than one line or of the wrong class.
(Corrupted and crafted files: `crates/loops-io/tests/attack_sweep.rs`.)

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
    for module, prefix in ((il, ""), (il.tiles, "tiles.")):
        for name in module.__all__:
            value = getattr(module, name)
            error = isinstance(value, type) and issubclass(value, BaseException)
            if callable(value) and not error:
                yield prefix + name, value
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
    # "null" links to /dev/null (made by the test): a writer must write into it, not replace it.
    "path": ["x", "null", "/nonexistent/x"],
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
    (tmp_path / "null").symlink_to("/dev/null")
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
    # A writer given the link wrote into the device; none put a file in the link's place.
    assert (tmp_path / "null").is_symlink() and (tmp_path / "null").is_char_device()


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


def _square_laps(path: Path, t0: int, dx: float) -> Path:
    """Two laps of a 40 m square at 1 m/s as TUM: a small log with revisits."""
    lines = []
    for k in range(320):
        s, side = (k % 160) * 0.25, (k % 160) // 40
        x, y = [(s, 0.0), (10.0, s - 10.0), (30.0 - s, 10.0), (0.0, 40.0 - s)][side]
        lines.append(f"{t0 + k}.0 {x + dx} {y} 0 0 0 0 1")
    path.write_text("\n".join(lines) + "\n")
    return path


def _leftover_shaped(rng: random.Random) -> str:
    stem = rng.choice(["thesis", "a", "drive-0", "summary.json", "index.html", "notes"])
    kind = rng.randrange(3)
    if kind == 0:
        return f".{stem}.partial-{rng.randrange(10**6)}"
    if kind == 1:
        return f".{stem}.old-{rng.randrange(10**6)}"
    return f".{stem}.{''.join(rng.choices('abcXYZ019', k=6))}.tmp"


def test_output_folders_never_lose_a_users_file(tmp_path: Path, loops_cli: Path) -> None:
    """Seeded: folders holding a user's entries shaped like a killed run's leftovers (and files
    named like the tools' own), logs named like the tools' files, and outputs aimed at the logs
    being read (by path, through a link, by another spelling), through `loops run`, `loops
    fleet`, `loops components` and `loops sample`, with and without --force. Every user file and
    every log must be left as it was."""
    rng = random.Random(SEED)
    logs = tmp_path / "logs"
    logs.mkdir()
    inputs = [_square_laps(logs / "a.tum", 0, 0.0), _square_laps(logs / "b.tum", 1000, 0.5)]
    inputs.append(_square_laps(logs / "loops-run.json.tum", 2000, 0.2))
    (tmp_path / "link.json").symlink_to(inputs[0])
    counts = {"cases": 0, "refused": 0, "ran": 0, "deleted": 0, "overwritten": 0, "panics": 0}
    for case in range(int(os.environ.get("LOOPS_SWEEP_FOLDERS", "36"))):
        out = tmp_path / f"out-{case}"
        out.mkdir()
        mine: dict[Path, bytes] = {}
        for k in range(rng.randint(0, 4)):
            entry = out / _leftover_shaped(rng)
            if entry.name.endswith(".tmp"):
                entry.write_bytes(f"user file {k}".encode())
                mine[entry] = entry.read_bytes()
            else:
                entry.mkdir(exist_ok=True)
                (entry / "work.txt").write_text(f"user work {k}")
                mine[entry / "work.txt"] = (entry / "work.txt").read_bytes()
        if rng.random() < 0.3:
            top = out / rng.choice(["index.html", "summary.json", "components.csv"])
            top.write_text("a file of the user's")
            mine[top] = top.read_bytes()
        before = {p: p.read_bytes() for p in inputs}
        onto_inputs = [str(inputs[0]), str(tmp_path / "link.json"), f"{logs}/./a.tum"]
        target = rng.choice(onto_inputs) if rng.random() < 0.4 else str(tmp_path / "x.out")
        command = rng.choice(["run", "fleet", "components", "sample"])
        args = [str(loops_cli), command]
        if command in ("run", "fleet"):
            args += [str(p) for p in rng.sample(inputs, rng.randint(2, 3))]
            args += ["--out", str(out), "--budget", "10"]
            if rng.random() < 0.5:
                args += ["--json", target]
        else:
            args += [str(inputs[0])]
            flag = "--json" if command == "components" else rng.choice(["--csv", "--g2o", "--json"])
            args += [flag, target] + (["--budget", "5"] if command == "sample" else [])
        args += ["--gamma", "2", "--quiet"] + (["--force"] if rng.random() < 0.6 else [])
        run = subprocess.run(args, capture_output=True, text=True, timeout=300)
        counts["cases"] += 1
        counts["panics"] += "panicked" in run.stderr or run.returncode not in (0, 1, 2)
        counts["refused" if run.returncode == 2 else "ran"] += 1
        for path, data in {**mine, **before}.items():
            if not path.exists():
                counts["deleted"] += 1
                print(f"case {case}: {path} deleted by {args}")
            elif path.read_bytes() != data:
                counts["overwritten"] += 1
                print(f"case {case}: {path} overwritten by {args}")
        with_json = Path(target).name == "x.out" and Path(target).exists()
        if with_json:
            Path(target).unlink()
    print(f"output-folder sweep, seed {SEED}: {counts}")
    assert counts["deleted"] == counts["overwritten"] == counts["panics"] == 0, counts
    assert counts["refused"] > 0 and counts["ran"] > 0, counts


#: Reads the bag ``sys.argv[1]`` in a child, after a line on stdout: the parent interrupts it.
READ_BAG = r"""
import sys
import inexact_loops as il

print("reading", flush=True)
il.read_trajectory(sys.argv[1])
print("read", flush=True)
"""


@pytest.fixture(scope="module")
def compressed_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A rosbag2 sqlite3 bag of 60,000 PoseStamped compressed per file (zstd), written by the
    independent `rosbags` writer."""
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types
    folder = tmp_path_factory.mktemp("compressed-bag") / "drive"
    writer = Writer2(folder, version=9, storage_plugin=StoragePlugin.SQLITE3)
    writer.set_compression(CompressionMode.FILE, CompressionFormat.ZSTD)
    with writer:
        conn = writer.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=store)
        for i in range(60_000):
            ns = 1_700_000_000_000_000_000 + i * 100_000_000
            stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            message = t["geometry_msgs/msg/PoseStamped"](
                header=t["std_msgs/msg/Header"](stamp=stamp, frame_id="map"),
                pose=t["geometry_msgs/msg/Pose"](
                    position=t["geometry_msgs/msg/Point"](x=0.01 * i, y=1.0, z=0.0),
                    orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                ),
            )
            writer.write(conn, ns, store.serialize_cdr(message, "geometry_msgs/msg/PoseStamped"))
    assert list(folder.glob("*.db3.zstd")), sorted(os.listdir(folder))
    return folder


def holds_a_file_in(pid: int, folder: Path) -> bool:
    """Whether process ``pid`` has a file of ``folder`` open (Linux: its /proc fd links)."""
    try:
        fds = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return False
    for fd in fds:
        try:
            if os.readlink(f"/proc/{pid}/fd/{fd}").startswith(str(folder)):
                return True
        except OSError:
            continue
    return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="watches /proc for the open copy")
def test_interrupted_bag_reads_leave_no_decompressed_copy(
    tmp_path: Path, loops_cli: Path, compressed_bag: Path
) -> None:
    """`loops info` and a Python read of a `.db3.zstd` bag, sent SIGINT (Ctrl-C, or
    KeyboardInterrupt in Python) or SIGKILL at a seeded moment after the copy is opened: the
    private TMPDIR is empty afterwards, every time."""
    rng = random.Random(SEED)
    readers = {
        "cli": [str(loops_cli), "info", str(compressed_bag)],
        "python": [sys.executable, "-c", READ_BAG, str(compressed_bag)],
    }
    outcomes: dict[str, int] = {}
    for round in range(2 * ROUNDS):
        reader = "cli" if round % 2 == 0 else "python"
        sig = signal.SIGINT if rng.random() < 0.75 else signal.SIGKILL
        tmp = tmp_path / f"tmp-{round}"
        tmp.mkdir()
        child = subprocess.Popen(
            readers[reader],
            env={**os.environ, "TMPDIR": str(tmp)},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        start = time.monotonic()
        while not holds_a_file_in(child.pid, tmp) and child.poll() is None:
            assert time.monotonic() - start < 120, f"{reader}: never opened a temporary file"
            time.sleep(0.002)
        time.sleep(rng.uniform(0.0, 0.3))
        child.send_signal(sig)
        child.communicate(timeout=300)
        left = sorted(os.listdir(tmp))
        assert left == [], f"round {round}: {reader} sent {sig.name} left {left} in TMPDIR"
        key = f"{reader} {sig.name} exit {child.returncode}"
        outcomes[key] = outcomes.get(key, 0) + 1
    print(f"{2 * ROUNDS} interrupted bag reads, nothing left: {outcomes}")


# --- Forged pickles: every state that does not hold together is an UnpicklingError ------------

#: Runs in a child. Each picklable object's state is forged at seeded places (bytes flipped,
#: cut short, a float made huge, NaN or negative, a name replaced, a length or type byte
#: changed); restoring it either raises ``pickle.UnpicklingError`` of one line or gives an object
#: whose repr works and whose measures are finite.
FORGED_PICKLES = r"""
import json, math, pickle, random, struct, sys, warnings
import numpy as np
import inexact_loops as il

warnings.simplefilter("ignore")
rng = random.Random(int(sys.argv[1]))
cases_per_object = int(sys.argv[2])

def objects():
    traj = il.urban_drive(duration_s=300.0, seed=3)
    loops = il.find_loops(traj, gamma=40.0)
    paper = il.find_loops(traj, gamma=40.0, separation=None)
    det = il.draw_detections(paper, rate=0.01, seed=1)
    clusters = il.cluster_detections(det, epsilon_s=20.0)
    samples = il.sample(loops, "rho", budget=50, seed=0, trajectory=traj)
    fleet = il.urban_fleet(vehicles=2, duration_s=200.0, seed=2)
    fleet_loops = il.find_fleet_loops(fleet, gamma=30.0)
    online = il.OnlineLoops(gamma=1.0, dim=2)
    online.push_many(np.arange(50.0), np.c_[np.cos(np.arange(50) / 5), np.sin(np.arange(50) / 5)])
    update = online.push(50.0, [1.0, 0.0])
    sessions = [fleet.session(n) for n in fleet.names]
    blocks = [il.tiles.session_blocks(s, block=100) for s in sessions]
    starts = np.cumsum([0] + [len(s) for s in sessions])
    tiles = il.tiles.plan_tiles(blocks, gamma=30.0)
    tile = tiles[0]
    a, b = tile.sessions
    kwargs = dict(starts=(int(starts[a]), int(starts[b])), gamma=30.0)
    summary, duration = il.tiles.scan_tile(tile, sessions[a], sessions[b], **kwargs, duration=True)
    summaries = [il.tiles.scan_tile(t, sessions[t.sessions[0]], sessions[t.sessions[1]],
                              starts=(int(starts[t.sessions[0]]), int(starts[t.sessions[1]])),
                              gamma=30.0)
                 for t in tiles]
    merge = il.tiles.merge_tiles(summaries)
    from inexact_loops.dask import find_fleet_loops_dask
    named = dict(zip(fleet.names, sessions))
    tiled = find_fleet_loops_dask(named, 30.0, block=100).loops
    with open("square.g2o", "w") as f:
        f.write("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 1.5708\nVERTEX_SE2 2 1 1 3.1416\n"
                "EDGE_SE2 0 1 1 0 1.5708 10 0 0 10 0 100\nEDGE_SE2 2 0 1 1 -3.1416 5 0 0 5 0 50\n")
    graph = il.read_pose_graph("square.g2o")
    return {
        "Trajectory": traj, "Loops": loops, "paper Loops": paper,
        "Separation": il.Separation(path=24.0, time_s=30.0),
        "Detections": det, "DetectionClusters": clusters, "Samples": samples,
        "SampleQuality": il.sample_quality(samples, loops), "PlaneGrid": il.PlaneGrid(traj, 50),
        "Fleet": fleet, "FleetLoops": fleet_loops,
        "FleetSamples": il.sample_fleet(fleet_loops, "closest-first", budget=30, seed=1),
        "TiledFleetLoops": tiled, "PoseGraph": graph, "OnlineLoops": online, "Update": update,
        "SessionBlocks": blocks[0], "Tile": tile, "TileSummary": summary, "TileDuration": duration,
        "TileMerge": merge,
    }

def floats(data):
    return [k for k in range(len(data) - 8) if data[k] == 0xCB]

def strings(data):
    return [k for k in range(len(data))
            if 0xA1 <= data[k] <= 0xBF and k + 1 + (data[k] - 0xA0) <= len(data)
            and all(32 <= c < 127 for c in data[k + 1 : k + 1 + data[k] - 0xA0])]

WEIRD = [1e308, -1e308, float("nan"), float("inf"), -1.0, 0.0, 1e-300, 5e15]

def mutate(data):
    kind = rng.choice(["flip", "truncate", "float", "string", "int"])
    data = bytearray(data)
    if kind == "flip":
        for _ in range(rng.randint(1, 3)):
            data[rng.randrange(len(data))] = rng.randrange(256)
    elif kind == "truncate":
        data = data[: rng.randrange(len(data))]
    elif kind == "float" and floats(data):
        k = rng.choice(floats(data))
        data[k + 1 : k + 9] = struct.pack(">d", rng.choice(WEIRD))
    elif kind == "string" and strings(data):
        k = rng.choice(strings(data))
        n = data[k] - 0xA0
        data[k : k + 1 + n] = bytes([0xA1]) + b"x"
    else:
        k = rng.randrange(len(data))
        data[k] = rng.choice([0x00, 0x7F, 0xCC, 0xCD, 0xCE, 0xCF, 0xFF, 0xE0])
    return kind, bytes(data)

UNPLACED_OK = {f"closest_{p}_{a}" for p in "ij" for a in "xyz"}

def sane(obj):
    # Whatever reads back must hold together: its repr works and its measures are finite.
    repr(obj)
    tables = [getattr(obj, name) for name in ("components", "table") if hasattr(obj, name)]
    for table in tables:
        if callable(table) or not hasattr(table, "items"):
            continue
        for column, values in table.items():
            values = np.asarray(values)
            if values.dtype.kind != "f":
                continue
            # A closest pair's position is NaN where the table holds no poses (a tiled fleet).
            known = ~np.isnan(values) if column in UNPLACED_OK else slice(None)
            if not np.isfinite(values[known]).all():
                raise ValueError(f"column {column} is not finite")
    if isinstance(obj, il.Loops):
        if not np.isfinite(obj.loop_duration()).all():
            raise ValueError("loop duration is not finite")
        area = obj.loop_area(-1e15, 1e15)
        if area is not None and not math.isfinite(area):
            raise ValueError(f"loop area {area}")

counts = {"cases": 0, "objects": 0, "unpickling_errors": 0, "other_errors": 0, "panics": 0,
          "insane": 0}
bad = []
for name, value in objects().items():
    reduced = value.__reduce__()
    restore, args = reduced[0], tuple(reduced[1])
    slot = next((k for k, a in enumerate(args) if isinstance(a, bytes)), None)
    if slot is None:
        continue
    for _ in range(cases_per_object):
        kind, forged = mutate(args[slot])
        forged_args = args[:slot] + (forged,) + args[slot + 1 :]
        counts["cases"] += 1
        try:
            back = restore(*forged_args)
        except pickle.UnpicklingError as error:
            counts["unpickling_errors"] += 1
            if "\n" in str(error):
                bad.append(f"{name}/{kind}: multi-line {str(error)[:100]!r}")
        except Exception as error:
            counts["other_errors"] += 1
            bad.append(f"{name}/{kind}: {type(error).__name__}: {str(error)[:120]}")
        except BaseException as error:
            counts["panics"] += 1
            bad.append(f"{name}/{kind}: {type(error).__name__}: {str(error)[:120]}")
        else:
            counts["objects"] += 1
            try:
                sane(back)
            except Exception as error:
                counts["insane"] += 1
                bad.append(f"{name}/{kind}: accepted but {type(error).__name__}: {error}"[:200])
print(json.dumps({"counts": counts, "bad": bad[:20]}))
"""


def test_forged_pickles_are_unpickling_errors_or_objects_that_hold_together(tmp_path: Path) -> None:
    child = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(FORGED_PICKLES), str(SEED), "25"],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=tmp_path,
    )
    assert child.returncode == 0, f"exit {child.returncode}: {child.stderr[-3000:]}"
    report = json.loads(child.stdout.strip().splitlines()[-1])
    counts = report["counts"]
    print(f"forged pickles: {counts}")
    assert counts["cases"] >= 400 and counts["unpickling_errors"] > counts["cases"] // 4, counts
    assert counts["other_errors"] == counts["panics"] == counts["insane"] == 0, report["bad"]


# --- Bad arguments to the console scripts: one line, exit code 2 -----------------------------

SCRIPTS = {
    "inexact_loops._cli": [
        ["components", "LOG", "--gamma", "BAD"],
        ["sample", "LOG", "--gamma", "5", "--budget", "BAD"],
        ["run", "LOG", "--gamma", "5", "--out", "o", "--threads", "BAD"],
        ["fleet", "LOG", "--gamma", "BAD", "--out", "o"],
        ["replay", "LOG", "--gamma", "5", "--rate", "BAD"],
        ["info", "LOG", "--BAD"],
    ],
    "inexact_loops.evaluate": [
        ["LOG", "--gamma", "BAD", "--out", "e"],
        ["LOG", "--gamma", "5", "--fleet", "--out", "e", "--seeds", "BAD"],
        ["LOG", "--gamma", "5", "--fleet", "--budgets", "10", "--seeds", "1", "--out", "e"],
    ],
    "inexact_loops.dask": [
        ["LOG", "--gamma", "BAD", "--out", "d"],
        ["LOG", "--gamma", "5", "--out", "d", "--block", "BAD"],
        ["LOG", "--gamma", "5", "--out", "d", "--axes", "BAD"],
    ],
}
BAD_VALUES = ["abc", "", "-1", "nan", "1e999", "--x", "0x10", "1,2,3", "\u00e9", "inf"]


def test_bad_arguments_to_the_console_scripts_are_one_line(tmp_path: Path) -> None:
    rng = random.Random(SEED)
    poses = tmp_path / "drive.tum"
    poses.write_text("".join(f"{0.5 * k} {k % 17} {k % 5} 0 0 0 0 1\n" for k in range(120)))
    counts = {"cases": 0, "one_line": 0}
    bad = []
    for module, forms in SCRIPTS.items():
        for form in forms:
            value = rng.choice(BAD_VALUES)
            args = [str(poses) if a == "LOG" else value if a == "BAD" else a for a in form]
            done = subprocess.run(
                [sys.executable, "-m", module, *args],
                capture_output=True,
                text=True,
                timeout=300,
                cwd=tmp_path,
                env={**os.environ, "MPLBACKEND": "Agg"},
            )
            counts["cases"] += 1
            if (
                done.returncode == 2
                and done.stderr.count("\n") == 1
                and "Traceback" not in done.stderr
            ):
                counts["one_line"] += 1
            elif done.returncode != 0:
                bad.append(f"{module} {args}: exit {done.returncode}: {done.stderr[-300:]!r}")
    print(f"console scripts: {counts}")
    assert not bad, bad


# --- Threads sharing one object: calls run one at a time -------------------------------------

#: Runs in a child: seeded calls of four threads on one OnlineLoops and one OnlineSampler.
THREADS = r"""
import json, random, sys, threading
import numpy as np
import inexact_loops as il

rng = random.Random(int(sys.argv[1]))
online = il.OnlineLoops(gamma=1.0, dim=8)
sampler = il.OnlineSampler(rate=0.5, seed=1)
points = np.random.default_rng(int(sys.argv[1])).normal(size=(20_000, 8))
clock = {"next": 0}
ticket = threading.Lock()
counts = {"calls": 0, "expected_refusals": 0, "unexpected": 0}
bad = []

def call(plan):
    for name in plan:
        counts["calls"] += 1
        try:
            if name == "push_many":
                with ticket:
                    k = clock["next"]
                    clock["next"] += 400
                online.push_many(np.arange(k, k + 400) * 0.1, points[k % 19_600 : k % 19_600 + 400])
            elif name == "offer":
                update = online.push_many([], np.zeros((0, 8)))
                sampler.offer(online, update)
            elif name == "read":
                len(online), online.components, repr(online)
            elif name == "pickle":
                __import__("pickle").dumps(online)
            elif name == "to_loops" and len(online) >= 2:
                online.to_loops()
        except (il.InvalidTrajectoryError, il.InvalidParameterError):
            counts["expected_refusals"] += 1
        except Exception as error:
            counts["unexpected"] += 1
            bad.append(f"{name}: {type(error).__name__}: {error}")

names = ["push_many", "offer", "read", "pickle", "to_loops"]
plans = [[rng.choice(names) for _ in range(25)] for _ in range(4)]
threads = [threading.Thread(target=call, args=(p,)) for p in plans]
for t in threads:
    t.start()
for t in threads:
    t.join(600)
hung = sum(t.is_alive() for t in threads)
print(json.dumps({"counts": counts, "hung": hung, "bad": bad[:20]}))
"""


def test_threads_sharing_one_engine_never_collide() -> None:
    child = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(THREADS), str(SEED)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert child.returncode == 0, f"exit {child.returncode}: {child.stderr[-3000:]}"
    report = json.loads(child.stdout.strip().splitlines()[-1])
    print(f"threads: {report['counts']}")
    assert report["hung"] == 0 and report["counts"]["unexpected"] == 0, report["bad"]


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
