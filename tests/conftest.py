"""Fixtures shared by the tests that drive the `loops` command line."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def loops_cli() -> Path:
    """The debug `loops` binary, built if needed (cargo knows whether it is up to date)."""
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.skip("cargo is not installed: the CLI cannot be built")
    subprocess.run([cargo, "build", "--quiet", "-p", "loops-cli"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "debug" / "loops"


def _interrupt_batch(args: list, logs: int) -> str:
    """Runs the batch ``args`` (a `loops run` of ``logs`` logs), sends it SIGINT once the first
    log has finished (while the next is in progress) and returns the rest of its stderr.
    Skips the test when the batch finished before the interrupt arrived; asserts exit code
    130 otherwise."""
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stderr is not None
    deadline = time.monotonic() + 300
    line = ""
    while f"[1/{logs}]" not in line and time.monotonic() < deadline:
        line = process.stderr.readline()
        assert line or process.poll() is None, "the run ended before it could be interrupted"
    process.send_signal(signal.SIGINT)
    _, rest = process.communicate(timeout=120)
    if process.returncode == 0:
        pytest.skip("the batch finished before the interrupt arrived")
    assert process.returncode == 130, rest
    return rest


@pytest.fixture(scope="session")
def interrupt_batch():
    """``interrupt_batch(args, logs)``: the rest of the stderr of a batch interrupted after its
    first log (:func:`_interrupt_batch`)."""
    return _interrupt_batch
