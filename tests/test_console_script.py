"""The wheel's `loops` command: `pip install .` installs it beside the package, and it prints and
exits exactly as the binary cargo builds from crates/loops-cli (it is that code, in the Python
process: `inexact_loops._cli`).

The console script must be present in the installed distribution: a missing one fails here,
it is never skipped.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import subprocess
from pathlib import Path

import pytest

#: The summary line ends with the time find_loops took: the one thing two runs do not share.
_SECONDS = re.compile(r"; \d+\.\d{3} s$", re.MULTILINE)


@pytest.fixture(scope="module")
def script() -> Path:
    """The `loops` console script of the installed inexact-loops, from its RECORD."""
    dist = importlib.metadata.distribution("inexact-loops")
    declared = [
        ep for ep in dist.entry_points if ep.group == "console_scripts" and ep.name == "loops"
    ]
    assert [ep.value for ep in declared] == ["inexact_loops._cli:main"], (
        "the installed inexact-loops declares no `loops` console script: reinstall it "
        "(`pip install .`)"
    )
    files = [
        f
        for f in dist.files or []
        if f.name in ("loops", "loops.exe") and f.parent.name in ("bin", "Scripts")
    ]
    assert files, f"`loops` is not among the installed files of inexact-loops ({dist.files})"
    path = Path(dist.locate_file(files[0])).resolve()
    assert path.is_file() and os.access(path, os.X_OK), path
    return path


def run(command: Path, *args: object, **kwargs) -> subprocess.CompletedProcess[str]:
    return subprocess.run([command, *map(str, args)], capture_output=True, text=True, **kwargs)


def assert_same(
    script: Path, binary: Path, *args: object, mask=None
) -> subprocess.CompletedProcess:
    """Both give the same exit code, stdout and stderr (after `mask`); the script's run."""
    ours, theirs = run(script, *args), run(binary, *args)
    masked = mask or (lambda text: text)
    assert ours.returncode == theirs.returncode, (args, ours.stderr, theirs.stderr)
    assert masked(ours.stdout) == masked(theirs.stdout), args
    assert ours.stderr == theirs.stderr, args
    return ours


def test_the_script_is_installed_and_runs_from_its_folder(script: Path) -> None:
    done = run(script, "--version")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"loops {importlib.metadata.version('inexact-loops')}\n"


@pytest.mark.parametrize(
    "args",
    [
        ["--version"],
        ["--help"],
        ["-h"],
        ["demo", "--help"],
        ["components", "--help"],
        ["run", "--version"],
        [],  # the help, on stderr, with exit code 2
        ["--bogus"],
        ["demo", "--gamma"],
        ["demo", "--seed", "x"],
    ],
)
def test_help_version_and_usage_errors_equal_the_binary(
    script: Path, loops_cli: Path, args: list[str]
) -> None:
    done = assert_same(script, loops_cli, *args)
    asks_for_help = any(a in ("--help", "-h", "--version") for a in args)
    assert done.returncode == (0 if asks_for_help else 2)
    assert (done.stdout and not done.stderr) if asks_for_help else (done.stderr and not done.stdout)


def test_demo_equals_the_binary(script: Path, loops_cli: Path) -> None:
    """The README's `loops demo`, and its JSON report, to the byte (the timing masked)."""
    done = assert_same(script, loops_cli, "demo", mask=lambda text: _SECONDS.sub("; (time)", text))
    assert done.returncode == 0
    assert done.stdout.startswith("urban drive (seed 0, 7560 s at 10 Hz)\n")
    assert "\n  75600 poses over 7559.9 s; gamma 40 (euclidean): " in done.stdout
    assert _SECONDS.search(done.stdout)
    done = assert_same(script, loops_cli, "demo", "--duration-s", "900", "--json", "-")
    assert json.loads(done.stdout)["poses"] == 9000


def test_errors_exit_as_the_binary(tmp_path: Path, script: Path, loops_cli: Path) -> None:
    missing = assert_same(script, loops_cli, "components", tmp_path / "missing.tum", "--gamma", "5")
    assert missing.returncode == 2
    assert missing.stderr.startswith("loops: error: ") and "missing.tum" in missing.stderr
    bad = tmp_path / "bad.tum"
    bad.write_text("0 0 0\n1 1 1\n")
    # A log that cannot be read: exit code 1 (the others would go on), into a fresh folder each.
    ours = run(script, "run", bad, "--gamma", "5", "--out", tmp_path / "a", "--quiet")
    theirs = run(loops_cli, "run", bad, "--gamma", "5", "--out", tmp_path / "b", "--quiet")
    assert ours.returncode == theirs.returncode == 1, ours.stderr
    assert ours.stderr == theirs.stderr
    assert ours.stderr.startswith("loops: [1/1] bad: error: ") and "line 1" in ours.stderr


@pytest.mark.parametrize("which", ["script", "binary"])
def test_a_closed_stdout_ends_the_command_quietly(
    which: str, script: Path, loops_cli: Path
) -> None:
    """`loops demo --json - | head -c 100`: the reader goes away, the command exits 0 with
    nothing on stderr, as the binary does."""
    command = script if which == "script" else loops_cli
    whole = run(command, "demo", "--json", "-").stdout
    assert len(whole) > 3 * 65536, "the output must outgrow the pipe's buffer"
    process = subprocess.Popen(
        [command, "demo", "--json", "-"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert process.stdout is not None and process.stderr is not None
    assert process.stdout.read(100) == whole.encode()[:100]
    process.stdout.close()
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=300) == 0, stderr
    assert stderr == ""


def test_ctrl_c_removes_unfinished_output_and_exits_130(
    tmp_path: Path, script: Path, interrupt_batch
) -> None:
    logs = tmp_path / "logs"
    done = run(script, "synth", logs, "--count", "8", "--duration-s", "1800")
    assert done.returncode == 0, done.stderr
    out = tmp_path / "results"
    args = [script, "run", *sorted(logs.glob("*.mcap")), "--gamma", "40", "--out", out]
    rest = interrupt_batch([*args, "--threads", "1"], 8)
    assert "loops: interrupted" in rest
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
