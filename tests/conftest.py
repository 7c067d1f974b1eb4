"""Fixtures shared by the tests that drive the `loops` command line."""

from __future__ import annotations

import os
import shutil
import subprocess
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
