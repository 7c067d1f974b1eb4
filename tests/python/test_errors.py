"""Bad input gives a clear error of the right class, naming the index, line or value; odd but
valid memory layouts and dtypes are read correctly."""

from __future__ import annotations

import re

import numpy as np
import pytest

import inexact_loops as il

N = 40


def ring(n: int = N) -> tuple[np.ndarray, np.ndarray]:
    """A 95% circle of radius 10 m, 10 Hz: one trivial and one non-trivial component at 4 m."""
    angle = np.linspace(0.0, 0.95 * 2 * np.pi, n)
    return np.arange(n) * 0.1, 10.0 * np.c_[np.cos(angle), np.sin(angle)]


@pytest.fixture(scope="module")
def loops():
    t, p = ring()
    return il.find_loops(il.Trajectory(t, p), gamma=4.0, separation=None)


def assert_same_loops(a, b) -> None:
    for key, value in a.runs().items():
        np.testing.assert_array_equal(value, b.runs()[key], err_msg=key)
    for key, value in a.components.items():
        np.testing.assert_array_equal(value, b.components[key], err_msg=key)
    np.testing.assert_array_equal(a.loop_duration(), b.loop_duration())


# --- the exception classes -------------------------------------------------------------------


def test_exception_hierarchy():
    assert issubclass(il.InvalidTrajectoryError, ValueError)
    assert issubclass(il.InvalidParameterError, ValueError)
    assert issubclass(il.LoopsIOError, OSError)
    assert issubclass(il.InternalError, RuntimeError)
    for cls in (
        il.InvalidTrajectoryError,
        il.InvalidParameterError,
        il.LoopsIOError,
        il.InternalError,
    ):
        assert issubclass(cls, il.LoopsError)
    assert issubclass(il.LoopsError, Exception)
    assert not issubclass(il.LoopsIOError, ValueError)


# --- trajectories ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("index", "axis", "value", "shown"),
    [
        (3, 1, np.nan, "NaN"),
        (0, 0, np.inf, "inf"),
        (N - 1, 1, -np.inf, "-inf"),
        (17, 0, np.nan, "NaN"),
    ],
)
def test_non_finite_position_names_the_pose(index, axis, value, shown):
    t, p = ring()
    p[index, axis] = value
    with pytest.raises(il.InvalidTrajectoryError) as error:
        il.Trajectory(t, p)
    message = str(error.value)
    assert re.search(rf"\bpose {index}\b", message), message
    assert re.search(rf"\bcoordinate {axis}\b", message), message
    assert shown in message


@pytest.mark.parametrize(("index", "value"), [(2, np.nan), (N - 1, np.inf), (0, -np.inf)])
def test_non_finite_timestamp_names_the_index(index, value):
    t, p = ring()
    t[index] = value
    with pytest.raises(il.InvalidTrajectoryError, match=rf"\bindex {index}\b"):
        il.Trajectory(t, p)


def test_magnitudes_the_arithmetic_cannot_hold_are_refused():
    # Squared distances of 1e155 overflow to inf; timestamps near f64's limit make the span
    # infinite. Both are refused, naming the pose and the value.
    t, p = ring()
    p[5, 1] = 1e155
    with pytest.raises(il.InvalidTrajectoryError, match=r"coordinate 1 of pose 5 is 1e155"):
        il.Trajectory(t, p)
    t, p = ring()
    t[-1] = 1.7e308
    with pytest.raises(il.InvalidTrajectoryError, match=rf"index {N - 1} is 1.7e308 s"):
        il.Trajectory(t, p)


@pytest.mark.parametrize("kind", ["decreasing", "duplicate"])
def test_timestamps_must_strictly_increase(kind):
    t, p = ring()
    t[7] = t[6] if kind == "duplicate" else t[6] - 0.05
    with pytest.raises(il.InvalidTrajectoryError) as error:
        il.Trajectory(t, p)
    message = str(error.value)
    assert re.search(r"\bindex 7\b", message) and re.search(r"\bindex 6\b", message), message
    assert f"{t[7]:g}" in message


@pytest.mark.parametrize(
    ("t", "p", "count"),
    [
        (np.array([]), np.zeros((0, 2)), 0),
        (np.array([]), np.array([]), 0),
        (np.array([0.0]), np.zeros((1, 3)), 1),
        (np.array([5.0]), np.array([1.0]), 1),
    ],
)
def test_too_few_poses(t, p, count):
    with pytest.raises(il.InvalidTrajectoryError, match=rf"at least 2 poses, got {count}\b"):
        il.Trajectory(t, p)


def test_zero_dimensional_points():
    with pytest.raises(il.InvalidTrajectoryError, match="dimension 0"):
        il.Trajectory(np.arange(3.0), np.zeros((3, 0)))


@pytest.mark.parametrize(
    ("t", "p", "pattern"),
    [
        (np.zeros((N, 2)), None, r"timestamps.*\(n,\).*\[40, 2\]"),
        (np.float64(1.0), None, r"timestamps.*1-dimensional"),
        (None, np.zeros((N, 2, 2)), r"positions.*\[40, 2, 2\]"),
        (None, np.zeros((N - 1, 2)), r"40.*39"),
        (np.arange(N + 1.0), None, r"41.*40"),
    ],
)
def test_wrong_shapes_are_value_errors(t, p, pattern):
    t0, p0 = ring()
    with pytest.raises(ValueError, match=pattern):
        il.Trajectory(t0 if t is None else t, p0 if p is None else p)


@pytest.mark.parametrize(
    ("t", "p", "pattern"),
    [
        (None, np.full((N, 2), "a"), r"positions.*<U1"),
        (None, np.ones((N, 2), dtype=complex), r"positions.*complex128"),
        (None, np.full((N, 2), None, dtype=object), r"positions.*object"),
        (None, np.ones((N, 2)).astype(object), r"positions.*object"),
        (None, np.ones((N, 2), dtype=bool), r"positions.*bool"),
        (np.array([str(k) for k in range(N)]), None, r"timestamps.*<U"),
        (np.arange(N, dtype=complex), None, r"timestamps.*complex"),
    ],
)
def test_wrong_dtypes_are_type_errors(t, p, pattern):
    t0, p0 = ring()
    with pytest.raises(TypeError, match=pattern):
        il.Trajectory(t0 if t is None else t, p0 if p is None else p)


@pytest.mark.parametrize(
    "layout", ["fortran", "strided_rows", "strided_columns", "transposed", "negative_stride"]
)
def test_memory_layouts_give_identical_results(layout):
    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(0.05, 0.2, 300))
    walk = np.cumsum(rng.normal(size=(300, 3)), axis=0)
    if layout == "fortran":
        p = np.asfortranarray(walk)
    elif layout == "strided_rows":
        big = np.zeros((600, 3))
        big[::2] = walk
        p = big[::2]
    elif layout == "strided_columns":
        big = np.zeros((300, 7))
        big[:, ::3] = walk
        p = big[:, ::3]
    elif layout == "transposed":
        p = np.ascontiguousarray(walk.T).T
    else:
        p = np.ascontiguousarray(walk[::-1])[::-1]  # a view with a negative row stride
    assert not p.flags.c_contiguous
    np.testing.assert_array_equal(p, walk)
    strided_t = np.repeat(t, 2)[::2]
    assert not strided_t.flags.c_contiguous
    traj = il.Trajectory(strided_t, p)
    np.testing.assert_array_equal(traj.positions, walk)
    np.testing.assert_array_equal(traj.timestamps, t)
    reference = il.find_loops(
        il.Trajectory(t, np.ascontiguousarray(walk)), gamma=3.0, separation=None
    )
    assert_same_loops(il.find_loops(traj, gamma=3.0, separation=None), reference)


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.uint16, np.float32, np.float16])
def test_integer_and_low_precision_inputs(dtype):
    rng = np.random.default_rng(5)
    p = np.cumsum(rng.integers(-2, 3, size=(200, 2)), axis=0) + 50
    t = np.arange(200) * 3
    typed = p.astype(dtype)
    traj = il.Trajectory(t.astype(dtype) if dtype != np.float16 else t, typed)
    np.testing.assert_array_equal(traj.positions, typed.astype(np.float64))
    reference = il.find_loops(
        il.Trajectory(t.astype(float), typed.astype(np.float64)), gamma=2.0, separation=None
    )
    assert_same_loops(il.find_loops(traj, gamma=2.0, separation=None), reference)


def test_lists_and_1d_positions():
    traj = il.Trajectory([0, 1, 2.5], [0.0, 3.0, 0.5])
    assert traj.dim == 1 and len(traj) == 3
    np.testing.assert_array_equal(traj.positions, [[0.0], [3.0], [0.5]])


# --- parameters --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("gamma", "shown"),
    [(0.0, "0"), (-1.5, "-1.5"), (np.nan, "NaN"), (np.inf, "inf"), (-np.inf, "-inf")],
)
def test_bad_gamma(gamma, shown):
    traj = il.Trajectory(*ring())
    with pytest.raises(il.InvalidParameterError, match=r"gamma") as error:
        il.find_loops(traj, gamma=gamma, separation=None)
    assert str(error.value).endswith(shown)


def test_unknown_metric_is_named():
    traj = il.Trajectory(*ring())
    with pytest.raises(il.InvalidParameterError, match=r'"manhattan".*euclidean'):
        il.find_loops(traj, gamma=1.0, metric="manhattan", separation=None)
    loops = il.find_loops(traj, gamma=1.0, metric="euclidean", separation=None)
    assert loops.metric_name == "euclidean"


def test_zero_threads():
    traj = il.Trajectory(*ring())
    with pytest.raises(il.InvalidParameterError, match=r"threads = 0"):
        il.find_loops(traj, gamma=1.0, threads=0, separation=None)


@pytest.mark.parametrize("side", ["middle", "Both", "", "start"])
def test_bad_side_is_named(loops, side):
    pattern = re.escape(f'"{side}"') + ".*both.*begin.*end"
    with pytest.raises(il.InvalidParameterError, match=pattern):
        loops.loop_duration(side=side)
    with pytest.raises(il.InvalidParameterError, match=pattern):
        loops.loop_area(0.0, 1.0, side=side)
    with pytest.raises(il.InvalidParameterError, match=pattern):
        loops.loop_density(0.0, 1.0, side=side, normalized=True)


@pytest.mark.parametrize(
    ("a", "b"),
    [(1.0, 0.5), (1.0, 1.0), (np.nan, 1.0), (0.0, np.nan), (-np.inf, 1.0), (0.0, np.inf)],
)
def test_bad_interval(loops, a, b):
    for normalized in (False, True):
        with pytest.raises(il.InvalidParameterError, match=r"interval.*a < b"):
            loops.loop_area(a, b, normalized=normalized)
        with pytest.raises(il.InvalidParameterError, match=r"interval.*a < b"):
            loops.loop_density(a, b, normalized=normalized)


def test_unknown_component_is_named(loops):
    count = len(loops.components["id"])
    assert count == 2
    with pytest.raises(il.InvalidParameterError, match=rf"\bid {count}\b.*\b{count}\b"):
        loops.loop_duration(components=[0, count])
    with pytest.raises(il.InvalidParameterError, match=r"\bid 99\b"):
        loops.loop_area(0.0, 1.0, components=[99])
    with pytest.raises(il.InvalidParameterError, match=r"\bid 7\b"):
        loops.loop_density(0.0, 1.0, components=[7], normalized=True)
    with pytest.raises(OverflowError):
        loops.loop_duration(components=[-1])


def test_pair_index_out_of_range_is_an_error(loops):
    """BUG: ``component_of``/``is_simple`` silently answer None/False for a pose index past the
    end (the docstring reserves None for delta > gamma), so a mismatch between labels and the
    trajectory (e.g. off-by-one frame indices) goes unnoticed."""
    assert loops.component_of(0, N - 1) is not None  # in range: the loop closing the ring
    with pytest.raises((IndexError, ValueError), match=rf"\b{N + 5}\b"):
        loops.component_of(0, N + 5)
    with pytest.raises((IndexError, ValueError), match=rf"\b{N}\b"):
        loops.is_simple(N, N)


# --- files -------------------------------------------------------------------------------------

TUM_OK = "# timestamp tx ty tz qx qy qz qw\n" + "".join(
    f"{k * 0.1:.1f} {k} 0 {k % 3} 0 0 0 1\n" for k in range(6)
)


def test_missing_file(tmp_path):
    path = tmp_path / "nope.txt"
    with pytest.raises(FileNotFoundError) as error:
        il.read_trajectory(path)
    assert isinstance(error.value, OSError)
    assert "nope.txt" in str(error.value)


def test_directory_is_an_os_error(tmp_path):
    folder = tmp_path / "folder.txt"
    folder.mkdir()
    with pytest.raises(OSError, match="folder.txt"):
        il.read_trajectory(folder)


@pytest.mark.parametrize(
    ("line", "pattern"),
    [
        ("0.7 abc 0 0 0 0 0 1", r'column 2 \("abc"\)'),
        ("0.7 1 2 3", r"8 columns.*found 4"),
        ("0.7 1 nan 3 0 0 0 1", r"column 3.*not finite"),
        ("x.7 1 2 3 0 0 0 1", r'column 1 \("x.7"\)'),
    ],
)
def test_malformed_tum_line_is_named(tmp_path, line, pattern):
    path = tmp_path / "drive.txt"
    path.write_text(TUM_OK + "\n# a comment\n" + line + "\n")  # the bad line is line 10
    with pytest.raises(il.LoopsIOError) as error:
        il.read_trajectory(path)
    message = str(error.value)
    assert isinstance(error.value, OSError) and isinstance(error.value, il.LoopsError)
    assert "drive.txt line 10" in message, message
    assert re.search(pattern, message), message


def test_tum_duplicate_timestamp_names_the_lines(tmp_path):
    path = tmp_path / "dup.tum"
    lines = TUM_OK.splitlines()
    lines.insert(4, "0.2 9 9 9 0 0 0 1")  # line 5 repeats the timestamp of line 4
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(il.InvalidTrajectoryError) as error:
        il.read_trajectory(path)
    message = str(error.value)
    assert "dup.tum line 5" in message and "(line 4)" in message, message
    assert isinstance(error.value, ValueError)


def test_tum_without_poses(tmp_path):
    path = tmp_path / "empty.txt"
    path.write_text("# nothing here\n\n")
    with pytest.raises(il.LoopsIOError, match=r"empty\.txt.*no poses"):
        il.read_trajectory(path)


def test_good_tum_file_reads(tmp_path):
    path = tmp_path / "drive.txt"
    path.write_text(TUM_OK)
    traj = il.read_trajectory(path)
    np.testing.assert_array_equal(traj.timestamps, np.loadtxt(path)[:, 0])
    np.testing.assert_array_equal(traj.positions, np.loadtxt(path)[:, 1:4])
    plane = il.read_trajectory(path, axes=(0, 2))
    np.testing.assert_array_equal(plane.positions, np.loadtxt(path)[:, [1, 3]])


@pytest.mark.parametrize(
    ("axes", "pattern"),
    [((0, 3), r"plane axis = 3"), ((7, 1), r"plane axis = 7"), ((2, 2), r"two different axes")],
)
def test_bad_axes(tmp_path, axes, pattern):
    path = tmp_path / "drive.txt"
    path.write_text(TUM_OK)
    with pytest.raises(il.InvalidParameterError, match=pattern):
        il.read_trajectory(path, axes=axes)


def test_bad_axes_for_a_2d_csv(tmp_path):
    path = tmp_path / "drive.csv"
    path.write_text("t,x,y\n0,0,0\n1,1,0\n2,1,1\n")
    with pytest.raises(il.InvalidParameterError, match=r"plane axis = 2.*2-D"):
        il.read_trajectory(path, axes=(0, 2))


def test_unknown_format(tmp_path):
    path = tmp_path / "drive.txt"
    path.write_text(TUM_OK)
    with pytest.raises(il.InvalidParameterError, match=r'"rosbag".*tum.*csv'):
        il.read_trajectory(path, format="rosbag")
    other = tmp_path / "drive.log"
    other.write_text(TUM_OK)
    with pytest.raises(il.LoopsIOError, match=r'"\.log"'):
        il.read_trajectory(other)
    assert len(il.read_trajectory(other, format="tum")) == 6


# --- refused at once, named by the core --------------------------------------------


def test_thread_counts_past_the_cap_are_refused_at_once():
    """Item 14: a million threads is refused by the core's cap, before any thread starts."""
    import time

    t, p = ring()
    traj = il.Trajectory(t, p)
    start = time.monotonic()
    with pytest.raises(il.InvalidParameterError, match="threads = 1000000 is invalid: between 1"):
        il.find_loops(traj, gamma=4.0, threads=1_000_000, separation=None)
    loops = il.find_loops(traj, gamma=4.0, separation=None)
    with pytest.raises(il.InvalidParameterError, match="between 1 and 1024"):
        il.sample(loops, "one", budget=1, seed=0, trajectory=traj, threads=1025)
    assert time.monotonic() - start < 10


def test_a_repeated_metric_key_is_named():
    """Item 20: the metric parser names a repeated key rather than a missing one."""
    t, p = ring()
    traj = il.Trajectory(t, p)
    with pytest.raises(il.InvalidParameterError, match="repeated parameter 'rotation'"):
        il.find_loops(
            traj, gamma=1.0, metric="so3(rotation=chordal,rotation=geodesic)", separation=None
        )


# --- the console scripts: a usage error is one line, exit code 2 ------------------------------


def console(module: str, *args: str, cwd=None) -> tuple[int, str]:
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-m", module, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
        env={**__import__("os").environ, "MPLBACKEND": "Agg"},
    )
    return done.returncode, done.stderr


@pytest.mark.parametrize(
    ("args", "shown"),
    [
        (["components", "x.tum", "--gamma", "abc"], "invalid value 'abc' for '--gamma <GAMMA>'"),
        (["components", "x.tum"], "required arguments were not provided: --gamma <GAMMA>"),
        (["sample", "x.tum", "--gamma", "5", "--sampler"], "a value is required for '--sampler"),
        (
            ["run", "x.tum", "--gamma", "5", "--out", "o", "--bogus"],
            "unexpected argument '--bogus'",
        ),
        (["frobnicate"], "unrecognized subcommand 'frobnicate'"),
    ],
)
def test_usage_errors_of_loops_are_one_line(tmp_path, args, shown):
    code, err = console("inexact_loops._cli", *args, cwd=tmp_path)
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("loops: error: "), err
    assert shown in err, err
    command = "loops" if args[0] == "frobnicate" else f"loops {args[0]}"
    assert err.rstrip().endswith(f"(try '{command} --help')"), err


def test_usage_errors_of_the_python_scripts_are_one_line(tmp_path):
    t = np.arange(200) * 0.5
    poses = np.c_[
        t, 30 * np.cos(t / 20), 30 * np.sin(t / 20), 0 * t, 0 * t, 0 * t, 0 * t, 1 + 0 * t
    ]
    np.savetxt(tmp_path / "ref.tum", poses)
    cases = [
        (
            "inexact_loops.evaluate",
            ["ref.tum", "--gamma", "abc", "--out", "e1"],
            "argument --gamma",
        ),
        (
            "inexact_loops.evaluate",
            [
                "ref.tum",
                "--gamma",
                "5",
                "--fleet",
                "--budgets",
                "10",
                "--seeds",
                "1",
                "--out",
                "eo",
            ],
            "--fleet needs the pose files of at least two sessions, got 1",
        ),
        (
            "inexact_loops.evaluate",
            ["ref.tum", "--gamma", "5", "--out", "e2", "--budgets", "x"],
            "",
        ),
        ("inexact_loops.dask", ["ref.tum", "--gamma", "abc", "--out", "d1"], "argument --gamma"),
        ("inexact_loops.dask", ["ref.tum", "--gamma", "5", "--out", "d2", "--axes", "0"], "--axes"),
    ]
    for module, args, shown in cases:
        code, err = console(module, *args, cwd=tmp_path)
        assert code == 2, (args, err[-2000:])
        assert err.count("\n") == 1 and "Traceback" not in err, (args, err[-2000:])
        assert shown in err, (args, err)
