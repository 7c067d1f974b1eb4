"""A process forked after a parallel computation computes too: the engine's thread pool belongs
to the process that made it, and a forked child (``multiprocessing`` with the ``fork`` start
method, ``os.fork``) makes its own instead of waiting for the parent's threads, which it does not
have. Each child runs in a subprocess with a time bound, so a hang fails the test instead of
hanging the suite."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent(
    """
    import multiprocessing, os, sys
    import inexact_loops as il

    traj = il.urban_drive(duration_s=900.0, seed=3)
    expected = il.find_loops(traj, gamma=40.0).components["pair_count"].tolist()

    def pairs(seed):
        return il.find_loops(traj, gamma=40.0).components["pair_count"].tolist()

    if sys.argv[1] == "pool":
        with multiprocessing.get_context("fork").Pool(2) as pool:
            got = pool.map(pairs, range(3))
        assert all(g == expected for g in got), got
    else:
        pid = os.fork()
        if pid == 0:
            os._exit(0 if pairs(0) == expected else 3)
        _, status = os.waitpid(pid, 0)
        assert os.waitstatus_to_exitcode(status) == 0, status
    print("ok")
    """
)


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="no fork on this platform")
@pytest.mark.parametrize("how", ["pool", "os.fork"])
def test_a_child_forked_after_a_parallel_find_loops_computes(how: str) -> None:
    try:
        run = subprocess.run(
            [sys.executable, "-c", SCRIPT, how], capture_output=True, text=True, timeout=180
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"the forked child ({how}) did not finish within 180 s: it waits for ever")
    assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr
