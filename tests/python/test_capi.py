"""The C ABI from C++: ``examples/cpp/online_replay.cpp``, built with the system's C++ compiler
against ``libinexact_loops.a`` (``crates/loops-capi``), prints exactly the candidates that the
Python API gives on the same TUM file and options; bad lines and bad poses are one-line errors.

``make test-cpp`` builds the example and points ``ONLINE_REPLAY`` at it; without it, this file
builds the library (``cargo build -p loops-capi``) and the example itself. Skipped, saying so,
only when no C++ compiler is found.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

REPO = Path(__file__).resolve().parents[2]
HEADER_DIR = REPO / "crates" / "loops-capi" / "include"
EXAMPLE = REPO / "examples" / "cpp" / "online_replay.cpp"


def find_compiler(*names: str) -> str | None:
    return next((path for name in names if name and (path := shutil.which(name))), None)


def static_library() -> Path:
    """``libinexact_loops.a``, built by cargo (a no-op when it is up to date)."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    target = target if target.is_absolute() else REPO / target
    cargo = shutil.which("cargo")
    assert cargo, "cargo is needed to build the C ABI (crates/loops-capi)"
    subprocess.run([cargo, "build", "--quiet", "-p", "loops-capi"], cwd=REPO, check=True)
    path = target / "debug" / "libinexact_loops.a"
    assert path.exists(), path
    return path


@pytest.fixture(scope="module")
def online_replay(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example's binary: ``$ONLINE_REPLAY`` (``make test-cpp`` builds it), or built here."""
    built = os.environ.get("ONLINE_REPLAY")
    if built:
        path = Path(built)
        return path if path.is_absolute() else REPO / path
    cxx = find_compiler(os.environ.get("CXX", ""), "c++", "g++", "clang++")
    if cxx is None:
        pytest.skip(
            "no C++ compiler (c++, g++ or clang++) on PATH: the C ABI's C++ example is not built"
        )
    binary = tmp_path_factory.mktemp("cpp") / "online_replay"
    command = [
        cxx,
        "-std=c++17",
        "-O2",
        "-Wall",
        "-Wextra",
        "-Werror",
        f"-I{HEADER_DIR}",
        str(EXAMPLE),
    ]
    subprocess.run(
        [*command, str(static_library()), "-lpthread", "-ldl", "-lm", "-o", str(binary)], check=True
    )
    return binary


@pytest.fixture(scope="module")
def drive_tum(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 10 min urban drive as a TUM file, headings as unit quaternions about z, every number
    written so that it reads back exactly."""
    traj = il.urban_drive(duration_s=600.0, seed=5)
    positions = traj.positions
    heading = np.arctan2(np.gradient(positions[:, 1]), np.gradient(positions[:, 0]))
    rows = np.c_[
        traj.timestamps,
        positions,
        np.zeros((len(traj), 2)),
        np.sin(heading / 2),
        np.cos(heading / 2),
    ]
    path = tmp_path_factory.mktemp("tum") / "drive.tum"
    lines = ["# timestamp tx ty tz qx qy qz qw"] + [
        " ".join(repr(float(v)) for v in row) for row in rows
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def run(binary: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(binary), *args], capture_output=True, text=True, timeout=600)


def printed(binary: Path, *args: str) -> list[tuple[int, int, int, float]]:
    result = run(binary, *args)
    assert result.returncode == 0, result.stderr
    out = []
    for line in result.stdout.splitlines():
        keyframe, j, component, distance = line.split()
        out.append((int(keyframe), int(j), int(component), float(distance)))
    return out


def python_candidates(
    path: Path, gamma: float, metric: str, **options
) -> list[tuple[int, int, int, float]]:
    """The same replay through the Python API: the file read as the example reads it."""
    rows = np.loadtxt(path, ndmin=2)
    t, values = rows[:, 0], rows[:, 1:].copy()
    if metric.startswith("se3"):
        q = values[:, 3:7]
        norm = np.sqrt(
            q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3]
        )
        values[:, 3:7] = q / norm[:, None]
    else:
        values = values[:, :3]
    online = il.OnlineLoops(gamma=gamma, dim=values.shape[1], metric=metric)
    sampler = il.OnlineSampler(**options)
    out = []
    for k in range(len(t)):
        update = online.push(t[k], values[k])
        out += [(c.keyframe, c.j, c.component, c.distance) for c in sampler.offer(online, update)]
    return out


CASES = [
    (
        ["--gamma", "40", "--rate", "0.05", "--cap-per-minute", "2", "--separation-path", "160"],
        40.0,
        "euclidean",
        # The example uses the first version of the C sampler: first candidates at the edge.
        {
            "rate": 0.05,
            "cap_per_minute": 2.0,
            "separation": il.Separation(path=160.0),
            "first_offer": "edge",
        },
    ),
    (
        [
            "--gamma",
            "30",
            "--metric",
            "se3(rotation_weight_m_per_rad=5)",
            "--rate",
            "0.02",
            "--no-first",
        ]
        + ["--cap-per-metre", "0.05", "--separation-time", "60", "--seed", "11"],
        30.0,
        "se3(rotation_weight_m_per_rad=5)",
        {
            "rate": 0.02,
            "first_on_appearance": False,
            "cap_per_metre": 0.05,
            "separation": il.Separation(time_s=60.0),
            "seed": 11,
        },
    ),
]


@pytest.mark.parametrize(("args", "gamma", "metric", "options"), CASES)
def test_the_cpp_example_prints_the_candidates_of_the_python_api(
    online_replay, drive_tum, args, gamma, metric, options
):
    from_cpp = printed(online_replay, str(drive_tum), *args)
    from_python = python_candidates(drive_tum, gamma, metric, **options)
    assert len(from_cpp) > 10
    assert from_cpp == from_python


def test_bad_lines_options_and_poses_are_one_line_errors(online_replay, tmp_path):
    path = tmp_path / "bad.tum"
    path.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 nan 0 0 0 0 0 1\n")
    result = run(online_replay, str(path), "--gamma", "1")
    assert result.returncode == 2
    assert (
        result.stderr.count("\n") == 1 and f"{path}:3:" in result.stderr and "NaN" in result.stderr
    ), result.stderr
    path.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n0.5 2 0 0 0 0 0 1\n")
    result = run(online_replay, str(path), "--gamma", "1")
    assert result.returncode == 2 and f"{path}:3:" in result.stderr and "0.5" in result.stderr, (
        result.stderr
    )
    path.write_text("0 0 0 0\n")
    result = run(online_replay, str(path), "--gamma", "1")
    assert result.returncode == 2 and "expected 8 numbers" in result.stderr, result.stderr
    result = run(online_replay, str(path), "--gamma", "-1")
    assert (
        result.returncode == 2 and "loops_online_new" in result.stderr and "-1" in result.stderr
    ), result.stderr
    result = run(online_replay, str(path), "--gamma", "1", "--rate", "-2")
    assert result.returncode == 2 and "rate" in result.stderr, result.stderr


def test_the_header_is_valid_c(tmp_path):
    cc = find_compiler(os.environ.get("CC", ""), "cc", "gcc", "clang")
    if cc is None:
        pytest.skip("no C compiler (cc, gcc or clang) on PATH")
    source = tmp_path / "use.c"
    source.write_text(
        '#include "inexact_loops.h"\n'
        "int main(void) {\n"
        "    LoopsSamplerOptions options;\n"
        "    LoopsOnline *online = 0;\n"
        "    if (loops_sampler_options_default(&options) != LOOPS_STATUS_OK) return 1;\n"
        '    if (loops_online_new("euclidean", 2, 1.0, &online) != LOOPS_STATUS_OK) return 1;\n'
        "    loops_online_free(online);\n"
        "    return options.first_on_appearance ? 0 : 1;\n"
        "}\n"
    )
    subprocess.run(
        [
            cc,
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            f"-I{HEADER_DIR}",
            "-c",
            str(source),
            "-o",
            str(tmp_path / "use.o"),
        ],
        check=True,
    )
