"""Nothing aborted: a budget too large for one answer is refused
before anything is drawn, an answer (or an input, or a synthetic fleet) too big for memory
raises ``OutOfMemoryError`` (a ``MemoryError``) instead of killing the interpreter, the
command line exits 2 with one line for both, and Ctrl-C stops a long computation at once.

The memory tests run in a child process whose address space is capped (``RLIMIT_AS``) a few
hundred MB above what it holds after start-up, on inputs whose answers need gigabytes, so the
machine is never short of memory.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

HUGE = 2**64 - 1


def parked(n: int) -> il.Trajectory:
    """A robot that never moves, 10 Hz: every pair is within any gamma, n(n-1)/2 candidates."""
    return il.Trajectory(np.arange(n) * 0.1, np.zeros((n, 2)))


# --- item 13: a budget that large is refused, naming what it needs ----------------------------


def test_a_budget_beyond_max_samples_is_refused_with_what_it_needs():
    traj = parked(3_600)  # 6,478,200 candidate pairs, more than the 5 million one call returns
    loops = il.find_loops(traj, gamma=1.0, separation=None)
    start = time.monotonic()
    for sampler in ("alpha", "rho", "one", "rho-dispersed", "time-gap"):
        with pytest.raises(il.InvalidParameterError) as error:
            il.sample(loops, sampler, budget=HUGE, seed=0, trajectory=traj)
        message = str(error.value)
        assert "\n" not in message
        assert message.startswith(f"budget {HUGE} asks for "), message
        assert "GiB of memory); one call returns at most 5000000" in message, message
        assert message.endswith("give a budget of at most 5000000, or a smaller rate"), message
    with pytest.raises(il.InvalidParameterError, match=r"^rate 1 asks for 6478200 samples"):
        il.sample(loops, "alpha", rate=1.0, seed=0, trajectory=traj)
    with pytest.raises(il.InvalidParameterError, match=r"asks for 6478200 detections"):
        il.draw_detections(loops, rate=1.0, seed=0)
    # Refused before anything was drawn: far quicker than drawing 6.5 million samples.
    assert time.monotonic() - start < 30
    # Within the bound, a budget is spent exactly.
    assert len(il.sample(loops, "rho", budget=100_000, seed=0, trajectory=traj)) == 100_000


def test_the_command_line_refuses_it_in_one_line_and_writes_nothing(tmp_path: Path):
    poses = tmp_path / "parked.tum"
    np.savetxt(poses, np.c_[np.arange(3_600) * 0.1, np.zeros((3_600, 6)), np.ones(3_600)])
    csv = tmp_path / "pairs.csv"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "inexact_loops._cli",
            "sample",
            poses,
            "--gamma",
            "1",
            "--no-separation",
            "--budget",
            str(HUGE),
            "--csv",
            csv,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert f"budget {HUGE} asks for 6478200 samples" in done.stderr
    assert "one call returns at most 5000000" in done.stderr
    assert not csv.exists()


# --- item 15: answers too big for memory -----------------------------------------------------

#: Caps the child's address space 600 MB above what it holds once the package is imported.
LIMIT = """
import resource

def cap_memory(extra_mb=600):
    with open("/proc/self/status") as status:
        size_kb = next(int(line.split()[1]) for line in status if line.startswith("VmSize:"))
    limit = size_kb * 1024 + extra_mb * 2**20
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
"""

#: A zig-zag along a line, 2,000 passes of 100 poses: at gamma 0.4 every row meets every later
#: pass once, 2 x 10^8 runs of S_gamma (about 3 GB with their closest columns and labels).
ZIGZAG = """
import numpy as np
passes, m = 2_000, 100
x = np.tile(np.r_[np.arange(m), np.arange(m)[::-1]], passes // 2).astype(float)
t = np.arange(x.size) * 0.1
"""


#: The error of S_gamma's runs, or of their closest columns, whichever outgrows the room first.
RUNS_OUT_OF_MEMORY = r"bytes\) for the (runs|closest columns) of S_gamma could not be allocated"


def run_child(code: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_an_answer_too_big_for_memory_raises_memory_error_and_the_interpreter_survives():
    done = run_child(
        LIMIT
        + ZIGZAG
        + """
import inexact_loops as il
traj = il.Trajectory(t, x)
cap_memory()
try:
    il.find_loops(traj, gamma=0.4, separation=None)
except il.OutOfMemoryError as error:
    assert isinstance(error, MemoryError) and isinstance(error, il.LoopsError)
    print("raised:", error)
# Images too: 10^5 x 10^5 pixels.
grid = il.PlaneGrid(traj, 100_000)
line = il.find_loops(il.Trajectory(t, t), gamma=0.4, separation=None)  # no revisit: cheap
for image in (lambda: il.distance_image(traj, grid), lambda: line.label_image(grid)):
    try:
        image()
    except il.OutOfMemoryError as error:
        print("image:", error)
# The interpreter goes on: a small answer still computes.
small = il.find_loops(il.Trajectory(t[:1000], x[:1000]), gamma=0.4, separation=None)
print("after:", len(small.components))
"""
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert lines[0].startswith("raised: out of memory: "), lines
    assert re.search(RUNS_OUT_OF_MEMORY, lines[0]), lines
    image = "image: out of memory: 74.5 GiB (80000000000 bytes) for the distance image could"
    assert lines[1].startswith(image), lines
    assert lines[2].startswith("image: out of memory: "), lines
    assert lines[3].startswith("after: "), lines


def test_a_fleet_too_big_for_memory_raises_memory_error():
    """Ten million vehicles driving 30 s each: 3 x 10^9 poses, about 120 GB of joint trajectory.
    Refused at once, naming its size; the generator once aborted some hundred thousand
    sessions in."""
    done = run_child(
        LIMIT
        + """
import inexact_loops as il
cap_memory()
try:
    il.urban_fleet(vehicles=10**7, duration_s=30.0)
except il.OutOfMemoryError as error:
    print("raised:", error)
print("after:", len(il.urban_fleet(vehicles=2, duration_s=30.0)))
"""
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert lines[0].startswith("raised: out of memory: 111.8 GiB (120000000000 bytes)"), lines
    assert "for the joint trajectory of a fleet could not be allocated" in lines[0], lines
    assert lines[1] == "after: 2", lines


def test_a_trajectory_and_find_loops_too_big_for_memory_raise_memory_error():
    """2.5 x 10^7 poses on a line, 600 MB above what the interpreter holds: the trajectory's
    copy does not fit; made before the cap, it fits, and find_loops does not. find_loops once
    aborted growing its ball hierarchy."""
    done = run_child(
        LIMIT
        + """
import numpy as np
import inexact_loops as il
n = 25_000_000
t, x = np.arange(n) * 0.1, np.arange(n, dtype=float)
made = il.Trajectory(t, x)
cap_memory(extra_mb=200)
try:
    il.Trajectory(t, x)
except il.OutOfMemoryError as error:
    print("trajectory:", error)
try:
    il.find_loops(made, gamma=0.5)
except il.OutOfMemoryError as error:
    print("find_loops:", error)
print("after:", len(il.find_loops(il.Trajectory(t[:1000], x[:1000]), gamma=0.5).components))
"""
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert lines[0].startswith("trajectory: out of memory: "), lines
    assert lines[1].startswith("find_loops: out of memory: "), lines
    assert lines[2].startswith("after: "), lines


def test_the_command_line_exits_2_with_one_line_when_memory_runs_out(tmp_path: Path):
    poses = tmp_path / "zigzag.tum"
    done = run_child(
        ZIGZAG
        + f"""
zeros = np.zeros(x.size)
np.savetxt({str(poses)!r}, np.c_[t, x, zeros, zeros, zeros, zeros, zeros, zeros + 1.0])
"""
    )
    assert done.returncode == 0, done.stderr
    done = run_child(
        LIMIT
        + f"""
import sys
from inexact_loops._cli import main
cap_memory()
sys.argv = ["loops", "components", {str(poses)!r}, "--gamma", "0.4", "--no-separation"]
sys.exit(main())
"""
    )
    assert done.returncode == 2, (done.returncode, done.stderr[-2000:])
    assert done.stderr.count("\n") == 1, done.stderr
    assert "out of memory: " in done.stderr
    assert re.search(RUNS_OUT_OF_MEMORY, done.stderr)


# --- item 18: Ctrl-C during a long computation -----------------------------------------------


def signalled(code: str) -> tuple[str, float, float]:
    """Runs `code` in a child, which prints "started" first; sends it SIGINT one second later.
    Returns its output once it exits (with code 0), when it said "started" and when the signal
    was sent (this process's monotonic clock)."""
    # Ctrl-C as in a terminal: where the tests themselves run with SIGINT ignored (a shell's
    # background job), the child would inherit that and never see the signal.
    code = "import signal\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n" + code
    child = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert child.stdout is not None
    assert child.stdout.readline() == "started\n"
    started = time.monotonic()
    time.sleep(1.0)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    try:
        out, err = child.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        child.kill()
        raise
    assert child.returncode == 0, err[-2000:]
    return out, sent, started


def interrupt_child(setup: str, call: str) -> tuple[float, str]:
    """Runs `call` in a child after `setup`; sends SIGINT one second into it. Returns the
    seconds from the signal to the KeyboardInterrupt in the child (its own clock: neither the
    interpreter's exit nor the call after it count), and its output."""
    code = (
        setup
        + f"""
import sys, time
print("started", flush=True)
start = time.monotonic()
try:
    {call}
    print("finished", time.monotonic() - start, flush=True)
except KeyboardInterrupt:
    print("interrupted", time.monotonic() - start, flush=True)
    # The interpreter goes on, and the next call is not interrupted.
    small = il.find_loops(il.urban_drive(duration_s=300.0), gamma=40.0)
    print("after", len(small.components), flush=True)
"""
    )
    out, sent, started = signalled(textwrap.dedent(code))
    first = out.split()
    if first[:1] == ["interrupted"]:
        # The call started right after "started" and the signal came `sent - started` later.
        return float(first[1]) - (sent - started), out
    return time.monotonic() - sent, out


#: 30,000 random points in 256 dimensions: no pair within gamma, and nothing for the triangle
#: inequality to skip, so the scan measures every pair (4.5 x 10^8 distances of 256 coordinates:
#: minutes), holding only the points (61 MB).
SCATTER = """
import numpy as np
import inexact_loops as il
rng = np.random.default_rng(0)
traj = il.Trajectory(np.arange(30_000) * 0.1, rng.normal(size=(30_000, 256)))
"""


def test_ctrl_c_stops_a_long_find_loops_at_once():
    seconds, out = interrupt_child(SCATTER, "il.find_loops(traj, gamma=1.0, separation=None)")
    lines = out.splitlines()
    assert lines[0].startswith("interrupted "), out
    assert lines[1].startswith("after "), out
    # The full scan takes minutes; the interrupt arrives within a fraction of a second (a
    # generous bound for a loaded machine: 10 s).
    assert seconds < 10, seconds


def test_ctrl_c_stops_a_python_metric_callable():
    seconds, out = interrupt_child(
        """
import numpy as np
import inexact_loops as il
traj = il.urban_drive(duration_s=7200.0)
""",
        "il.find_loops(traj, gamma=40.0, metric=lambda a, b: float(np.linalg.norm(a - b)))",
    )
    assert out.startswith("interrupted "), out
    assert seconds < 10, seconds


def test_ctrl_c_stops_a_long_distance_image():
    # 6,000 points in 2,048 dimensions: 3.6 x 10^7 pixels of 2,048 coordinates (tens of
    # seconds), an image of 288 MB.
    setup = """
import numpy as np
import inexact_loops as il
rng = np.random.default_rng(0)
traj = il.Trajectory(np.arange(6_000) * 0.1, rng.normal(size=(6_000, 2_048)))
"""
    seconds, out = interrupt_child(setup, "il.distance_image(traj, il.PlaneGrid(traj, 6_000))")
    assert out.startswith("interrupted "), out
    assert seconds < 10, seconds


# --- Ctrl-C in the samplers, the quality measures and the online engine ----------------------
# Each input takes tens of seconds or more in full; the interrupt must arrive within a bound
# (a hang check for a loaded machine, not a timing benchmark).

#: A robot parked for 40,000 poses: one trivial component whose rows each span the whole stop.
#: The closest-first sampler measures every row's diagonal run for its return column: 8 x 10^8
#: distances.
PARKED = """
import numpy as np
import inexact_loops as il
import warnings
warnings.simplefilter("ignore")
def parked(n):
    return il.Trajectory(np.arange(n) * 0.1, np.zeros((n, 2)))
"""


def test_ctrl_c_stops_the_closest_first_sampler():
    setup = (
        PARKED
        + """
traj = parked(40_000)
loops = il.find_loops(traj, gamma=1.0, separation=None)
"""
    )
    call = 'il.sample(loops, "closest-first", budget=10, seed=0, trajectory=traj)'
    seconds, out = interrupt_child(setup, call)
    assert out.startswith("interrupted "), out
    assert seconds < 10, seconds


def test_ctrl_c_stops_sample_quality():
    # 10^6 samples of one component, 3,000 to a row: the nearest other sample of each is
    # searched among its row's.
    setup = (
        PARKED
        + """
traj = parked(3_000)
loops = il.find_loops(traj, gamma=1.0, separation=None)
samples = il.sample(loops, "alpha", budget=1_000_000, seed=0, trajectory=traj)
"""
    )
    seconds, out = interrupt_child(setup, "il.sample_quality(samples, loops)")
    assert out.startswith("interrupted "), out
    assert seconds < 10, seconds


def test_ctrl_c_stops_sample_fleet():
    setup = (
        PARKED
        + """
fleet = il.Fleet({"monday": parked(30_000), "tuesday": parked(30_000)})
loops = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
"""
    )
    call = 'il.sample_fleet(loops, "closest-first", budget=10, seed=0)'
    seconds, out = interrupt_child(setup, call)
    assert out.startswith("interrupted "), out
    assert seconds < 10, seconds


def test_ctrl_c_stops_push_many_and_keeps_the_poses_before():
    # 30,000 points in 256 dimensions: every new pose is measured against every earlier one
    # (minutes in full).
    code = textwrap.dedent(
        """
        import sys, time
        import numpy as np
        import inexact_loops as il
        rng = np.random.default_rng(0)
        points = rng.normal(size=(30_000, 256))
        times = np.arange(len(points)) * 0.1
        online = il.OnlineLoops(gamma=1.0, dim=256)
        print("started", flush=True)
        start = time.monotonic()
        try:
            online.push_many(times, points)
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic() - start, flush=True)
        n = len(online)
        again = il.OnlineLoops(gamma=1.0, dim=256)
        again.push_many(times[:n], points[:n])
        tables = online.components, again.components
        same = all(np.array_equal(tables[0][k], tables[1][k]) for k in tables[1])
        duration = online.loop_duration(n - 1) == again.loop_duration(n - 1)
        print("kept", n, same, duration, flush=True)
        # It goes on from there, as if the poses had come in two batches.
        online.push_many(times[n : n + 10], points[n : n + 10])
        print("went on", len(online), flush=True)
        """
    )
    out, sent, started = signalled(code)
    lines = out.splitlines()
    assert lines[0].startswith("interrupted "), out
    assert float(lines[0].split()[1]) - (sent - started) < 10, out
    _, kept, same, duration = lines[1].split()
    assert 0 < int(kept) < 30_000 and same == "True" and duration == "True", out
    assert lines[2] == f"went on {int(kept) + 10}", out


def test_ctrl_c_stops_a_call_waiting_for_another_threads_and_gives_up_its_turn():
    # A thread pushes 5,000 points in 256 dimensions (seconds, and a thread other than the main
    # one is not interrupted); the main thread's call waits for the engine meanwhile, and Ctrl-C
    # raises KeyboardInterrupt in it. The calls after it are served once the push is done: the
    # interrupted call's turn is given up, not kept for ever.
    code = textwrap.dedent(
        """
        import threading, time
        import numpy as np
        import inexact_loops as il
        rng = np.random.default_rng(0)
        points = rng.normal(size=(5_000, 256))
        online = il.OnlineLoops(gamma=1.0, dim=256)
        pushing = threading.Thread(target=online.push_many, args=(np.arange(5_000) * 0.1, points))
        pushing.start()
        time.sleep(0.2)
        print("started", flush=True)
        start = time.monotonic()
        try:
            online.components
            print("finished", len(online), flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic() - start, flush=True)
        pushed = []
        later = threading.Thread(target=lambda: pushed.append(len(online)), daemon=True)
        later.start()
        later.join(120)
        pushing.join(120)
        print("after", pushed, len(online), flush=True)
        """
    )
    out, sent, started = signalled(code)
    lines = out.splitlines()
    if lines[0].startswith("finished "):
        pytest.skip(f"the push ended before the signal: {out}")
    assert lines[0].startswith("interrupted "), out
    assert float(lines[0].split()[1]) - (sent - started) < 10, out
    assert lines[1] == "after [5000] 5000", out
