"""Interop: trajectories from evo, tables to pandas, and the numpy arrays of the results.

``Trajectory.from_evo`` is checked against real ``evo.core.trajectory.PoseTrajectory3D`` objects
(evo is in the ``test`` extra) with orientations compared through scipy's ``Rotation``, and
against evo's own TUM reader; ``to_pandas`` against ``pandas.read_csv`` of the samples' CSV.
"""

from __future__ import annotations

import re
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from evo.core.trajectory import PosePath3D, PoseTrajectory3D
from evo.tools import file_interface
from scipy.spatial.transform import Rotation

import inexact_loops as il

N = 120


def evo_trajectory(n: int = N, seed: int = 3) -> tuple[PoseTrajectory3D, Rotation]:
    """A random walk with smoothly turning orientations, built by evo from 4x4 SE(3) matrices
    (so evo computes its own w-first quaternions), and the rotations as scipy holds them."""
    rng = np.random.default_rng(seed)
    positions = np.cumsum(rng.normal(scale=0.5, size=(n, 3)), axis=0)
    rotations = Rotation.from_rotvec(np.cumsum(rng.normal(scale=0.15, size=(n, 3)), axis=0))
    traj = PoseTrajectory3D(
        poses_se3=list(se3_matrices(rotations, positions)),
        timestamps=1_700_000_000.0 + np.arange(n) * 0.1,
    )
    return traj, rotations


def se3_matrices(rotations: Rotation, positions: np.ndarray) -> np.ndarray:
    matrices = np.tile(np.eye(4), (len(positions), 1, 1))
    matrices[:, :3, :3] = rotations.as_matrix()
    matrices[:, :3, 3] = positions
    return matrices


def stand_in(**overrides: object) -> SimpleNamespace:
    """A duck-typed PoseTrajectory3D: 5 poses along x, identity orientations."""
    fields: dict[str, object] = {
        "timestamps": np.arange(5) * 0.5,
        "positions_xyz": np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)],
        "orientations_quat_wxyz": np.tile([1.0, 0.0, 0.0, 0.0], (5, 1)),
    }
    fields.update(overrides)
    return SimpleNamespace(**fields)


# --- Trajectory.from_evo ----------------------------------------------------------------------


def test_from_evo_positions_by_default():
    evo, _ = evo_trajectory()
    traj = il.Trajectory.from_evo(evo)
    assert traj.dim == 3 and len(traj) == N
    np.testing.assert_array_equal(traj.timestamps, evo.timestamps)
    np.testing.assert_array_equal(traj.positions, evo.positions_xyz)
    for metric in ("euclidean", il.metrics.Euclidean()):
        np.testing.assert_array_equal(
            il.Trajectory.from_evo(evo, metric=metric).positions, evo.positions_xyz
        )


def test_from_evo_plane_axes():
    evo, _ = evo_trajectory()
    traj = il.Trajectory.from_evo(evo, axes=(0, 2))
    np.testing.assert_array_equal(traj.positions, evo.positions_xyz[:, [0, 2]])


def test_from_evo_se3_reorders_w_first_quaternions():
    evo, rotations = evo_trajectory()
    traj = il.Trajectory.from_evo(evo, metric=il.metrics.SE3(rotation_weight_m_per_rad=2.0))
    assert traj.dim == 7
    np.testing.assert_array_equal(traj.positions[:, :3], evo.positions_xyz)
    quaternions = traj.positions[:, 3:]
    # The same rotations as scipy's (x, y, z, w), up to the sign of the quaternion.
    agree = np.abs(np.sum(quaternions * rotations.as_quat(), axis=1))
    np.testing.assert_allclose(agree, 1.0, atol=1e-12)
    np.testing.assert_allclose(
        (Rotation.from_quat(quaternions) * rotations.inv()).magnitude(), 0.0, atol=1e-7
    )
    reference = il.Trajectory.se3(evo.timestamps, evo.positions_xyz, rotations.as_quat())
    metric = "se3(rotation_weight_m_per_rad=2)"
    ours = il.find_loops(traj, gamma=3.0, metric=metric, separation=None)
    theirs = il.find_loops(reference, gamma=3.0, metric=metric, separation=None)
    assert ours.pair_count == theirs.pair_count > N
    for key, column in ours.components.items():
        if column.dtype == np.float64:  # evo's quaternions are its own, from the matrices
            np.testing.assert_allclose(column, theirs.components[key], rtol=1e-12, err_msg=key)
        else:
            np.testing.assert_array_equal(column, theirs.components[key], err_msg=key)


@pytest.mark.parametrize(("metric", "gamma"), [("se3_rotation", 0.6), ("so3", 0.6)])
def test_from_evo_rotation_distances_match_scipy(metric, gamma):
    """Pairs within gamma of each other in rotation angle, against scipy's geodesic angle: a
    w-first quaternion read as x-first would give other angles."""
    evo, rotations = evo_trajectory()
    loops = il.find_loops(
        il.Trajectory.from_evo(evo, metric=metric), gamma=gamma, metric=metric, separation=None
    )
    angles = np.array([(rotations[k].inv() * rotations).magnitude() for k in range(N)])
    within = angles <= gamma
    assert 0 < within.sum() < N * N
    assert loops.pair_count == within.sum()
    for i, j in [(0, 1), (0, N - 1), (10, 60), (40, 41)]:
        assert (loops.component_of(i, j) is not None) == within[i, j], (i, j)


def test_from_evo_se2_takes_the_yaw():
    rng = np.random.default_rng(8)
    yaw = rng.uniform(-np.pi, np.pi, N)
    tilt = rng.uniform(
        -0.2, 0.2, (N, 2)
    )  # pitch and roll: yaw is the first intrinsic Z-Y-X angle (ROS)
    rotations = Rotation.from_euler("ZYX", np.c_[yaw, tilt])
    positions = np.c_[rng.normal(size=(N, 2)), np.zeros(N)]
    evo = PoseTrajectory3D(
        poses_se3=list(se3_matrices(rotations, positions)), timestamps=np.arange(N) * 0.1
    )
    traj = il.Trajectory.from_evo(evo, metric=il.metrics.SE2(rotation_weight_m_per_rad=1.0))
    np.testing.assert_array_equal(traj.positions[:, :2], evo.positions_xyz[:, :2])
    np.testing.assert_allclose(traj.positions[:, 2], rotations.as_euler("ZYX")[:, 0], atol=1e-12)


def test_from_evo_equals_read_trajectory_of_the_same_tum_file(tmp_path):
    evo, _ = evo_trajectory()
    path = tmp_path / "walk.tum"
    file_interface.write_tum_trajectory_file(str(path), evo)
    from_evo_reader = file_interface.read_tum_trajectory_file(str(path))
    for metric in (None, "se3(rotation_weight_m_per_rad=1)", "so3"):
        ours = il.read_trajectory(path, metric=metric)
        theirs = il.Trajectory.from_evo(from_evo_reader, metric=metric)
        np.testing.assert_array_equal(theirs.timestamps, ours.timestamps)
        np.testing.assert_allclose(theirs.positions, ours.positions, rtol=0, atol=1e-12)


def test_from_evo_duck_typed_and_evo_not_imported():
    code = (
        "import sys, numpy as np, types, inexact_loops as il\n"
        "t = types.SimpleNamespace(timestamps=np.arange(3.0), positions_xyz=np.eye(3),\n"
        "    orientations_quat_wxyz=np.tile([1.0, 0, 0, 0], (3, 1)))\n"
        "assert il.Trajectory.from_evo(t).dim == 3\n"
        "assert not any(name == 'evo' or name.startswith('evo.') for name in sys.modules)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_from_evo_lists_are_read():
    traj = il.Trajectory.from_evo(
        stand_in(
            timestamps=[0, 1, 2],
            positions_xyz=[[0, 0, 0]] * 3,
            orientations_quat_wxyz=[[1, 0, 0, 0]] * 3,
        )
    )
    assert traj.dim == 3 and len(traj) == 3


@pytest.mark.parametrize(
    ("obj", "named"),
    [
        (
            PosePath3D(np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 1))),
            r"got PosePath3D without timestamps$",
        ),
        (
            object(),
            r"got object without timestamps or positions_xyz or orientations_quat_wxyz$",
        ),
        (np.zeros((5, 3)), r"got ndarray without timestamps"),
        (
            SimpleNamespace(timestamps=[0.0, 1.0], positions_xyz=np.zeros((2, 3))),
            r"got SimpleNamespace without orientations_quat_wxyz$",
        ),
    ],
)
def test_from_evo_rejects_other_objects_naming_what_is_missing(obj, named):
    with pytest.raises(
        TypeError, match=r"Trajectory\.from_evo takes an evo PoseTrajectory3D"
    ) as error:
        il.Trajectory.from_evo(obj)
    assert re.search(named, str(error.value)), str(error.value)


@pytest.mark.parametrize(
    ("overrides", "error", "pattern"),
    [
        ({"positions_xyz": np.zeros((5, 2))}, ValueError, r"positions_xyz.*\(n, 3\).*2 columns"),
        (
            {"orientations_quat_wxyz": np.zeros((5, 3))},
            ValueError,
            r"orientations_quat_wxyz.*\(n, 4\)",
        ),
        (
            {"positions_xyz": np.zeros((4, 3))},
            ValueError,
            r"timestamps has 5 rows.*positions_xyz has 4",
        ),
        ({"timestamps": np.zeros((5, 1))}, ValueError, r"timestamps.*1-dimensional"),
        ({"positions_xyz": np.full((5, 3), "x")}, TypeError, r"positions_xyz.*dtype <U1"),
    ],
)
def test_from_evo_wrong_shapes_and_dtypes_name_the_attribute(overrides, error, pattern):
    with pytest.raises(error, match=pattern):
        il.Trajectory.from_evo(stand_in(**overrides))


def test_from_evo_bad_values_name_the_pose():
    positions = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]
    positions[3, 1] = np.nan
    with pytest.raises(il.InvalidTrajectoryError, match=r"coordinate 1 of pose 3 .*NaN"):
        il.Trajectory.from_evo(stand_in(positions_xyz=positions))
    with pytest.raises(il.InvalidTrajectoryError, match=r"index 2 .*index 1"):
        il.Trajectory.from_evo(stand_in(timestamps=np.array([0.0, 1.0, 0.5, 2.0, 3.0])))
    quaternions = np.tile([1.0, 0.0, 0.0, 0.0], (5, 1))
    quaternions[4] = [2.0, 0.0, 0.0, 0.0]
    bad = stand_in(orientations_quat_wxyz=quaternions)
    assert len(il.Trajectory.from_evo(bad)) == 5  # positions only: orientations unused
    with pytest.raises(il.InvalidTrajectoryError, match=r"quaternion of pose 4 has norm 2"):
        il.Trajectory.from_evo(bad, metric="se3(rotation_weight_m_per_rad=1)")
    with pytest.raises(il.InvalidTrajectoryError, match=r"at least 2 poses, got 1"):
        il.Trajectory.from_evo(
            stand_in(
                timestamps=[0.0],
                positions_xyz=[[0.0, 0, 0]],
                orientations_quat_wxyz=[[1.0, 0, 0, 0]],
            )
        )


def test_from_evo_bad_metric_or_axes_are_named():
    evo = stand_in()
    with pytest.raises(il.InvalidParameterError, match=r'metric "torus" does not fit here: .*se3'):
        il.Trajectory.from_evo(evo, metric="torus")
    with pytest.raises(il.InvalidParameterError, match=r'unknown metric "manhattan"'):
        il.Trajectory.from_evo(evo, metric="manhattan")
    with pytest.raises(il.InvalidParameterError, match=r'"se3\(.*\)" does not fit here: axes'):
        il.Trajectory.from_evo(evo, metric="se3(rotation_weight_m_per_rad=1)", axes=(0, 1))
    with pytest.raises(il.InvalidParameterError, match=r"plane axis = 3"):
        il.Trajectory.from_evo(evo, axes=(0, 3))
    with pytest.raises(ValueError, match=r"from_evo takes a metric name or object, not a callable"):
        il.Trajectory.from_evo(evo, metric=lambda a, b: 0.0)
    with pytest.raises(TypeError, match=r"metric must be a name.*got int"):
        il.Trajectory.from_evo(evo, metric=3)


# --- to_pandas ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def results():
    traj = il.urban_drive(duration_s=600.0, seed=7)
    loops = il.find_loops(traj, gamma=40.0, separation=None)
    detections = il.draw_detections(loops, budget=300, seed=1)
    clusters = il.cluster_detections(detections, epsilon_s=30.0)
    samples = il.sample(loops, "rho", budget=50, seed=2, trajectory=traj)
    quality = il.sample_quality(samples, loops)
    return SimpleNamespace(
        traj=traj,
        loops=loops,
        detections=detections,
        clusters=clusters,
        samples=samples,
        quality=quality,
    )


TABLES = {
    "Loops.components": (lambda r: r.loops.components, {
        "id": "int64", "trivial": "bool", "area_s2": "float64", "pair_count": "int64",
        "pose_pair_count": "int64", "run_count": "int64", "holes": "int64",
        "i_min": "int64", "i_max": "int64", "j_min": "int64", "j_max": "int64",
        "t_min_s": "float64", "t_max_s": "float64",
        "t_prime_min_s": "float64", "t_prime_max_s": "float64", "closest_i": "int64",
        "closest_j": "int64", "closest_distance": "float64",
        "closest_i_x": "float64", "closest_i_y": "float64", "closest_i_z": "float64",
        "closest_j_x": "float64", "closest_j_y": "float64", "closest_j_z": "float64",
    }),
    "Loops.runs": (lambda r: r.loops.runs(), {
        "row": "int64", "start": "int64", "end": "int64", "component": "int64",
    }),
    "DetectionClusters.clusters": (lambda r: r.clusters.clusters, {
        "id": "int64", "size": "int64", "t_min_s": "float64", "t_max_s": "float64",
        "t_prime_min_s": "float64", "t_prime_max_s": "float64", "cells": "int64",
        "area_proxy_s2": "float64", "anchor": "int64",
    }),
    "SampleQuality.missed": (lambda r: r.quality.missed, {
        "id": "int64", "trivial": "bool", "area_s2": "float64", "pair_count": "int64",
    }),
}  # fmt: skip


@pytest.mark.parametrize("name", TABLES)
def test_tables_are_dicts_of_plain_numpy_columns_with_the_documented_dtypes(results, name):
    get, dtypes = TABLES[name]
    table = get(results)
    assert isinstance(table, il.Table) and isinstance(table, dict)
    assert list(table) == list(dtypes)
    for column, dtype in dtypes.items():
        array = table[column]
        assert type(array) is np.ndarray, column
        assert array.dtype == np.dtype(dtype) and array.ndim == 1, column
        assert array.flags.writeable and array.flags.c_contiguous, column
        assert len(array) == table.num_rows
    assert get(results)[next(iter(dtypes))] is not table[next(iter(dtypes))]  # a new copy


@pytest.mark.parametrize("name", TABLES)
def test_tables_to_pandas(results, name):
    get, dtypes = TABLES[name]
    table = get(results)
    frame = table.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == list(dtypes)
    assert {k: str(v) for k, v in frame.dtypes.items()} == dtypes
    assert len(frame) == table.num_rows
    for column in dtypes:
        np.testing.assert_array_equal(frame[column].to_numpy(), table[column])


def test_empty_table_to_pandas_keeps_columns_and_dtypes(results):
    assert results.quality.covered == results.quality.components
    missed = results.quality.missed
    assert missed.num_rows == 0
    frame = missed.to_pandas()
    assert frame.shape == (0, 4)
    assert str(frame["trivial"].dtype) == "bool" and str(frame["id"].dtype) == "int64"
    assert il.Table().num_rows == 0 and il.Table().to_pandas().shape == (0, 0)


def test_per_component_joins_the_components_table(results):
    table = results.loops.components
    table["samples"] = results.quality.per_component
    frame = table.to_pandas()
    assert frame["samples"].sum() == len(results.samples)
    assert (frame.groupby("trivial")["samples"].sum() >= 0).all()


def test_detections_to_pandas(results):
    frame = results.detections.to_pandas()
    assert list(frame.columns) == ["t", "t_prime", "i", "j"]
    assert [str(d) for d in frame.dtypes] == ["float64", "float64", "int64", "int64"]
    np.testing.assert_array_equal(frame["j"], results.detections.j)
    bare = il.Detections([3.0, 1.0], [2.0, 5.0], scores=[0.5, 0.25]).to_pandas()
    assert bare.to_dict("list") == {"t": [2.0, 1.0], "t_prime": [3.0, 5.0], "score": [0.5, 0.25]}


def test_samples_to_pandas_equals_the_csv(results, tmp_path):
    samples = results.samples
    frame = samples.to_pandas()
    assert list(frame.columns) == [
        "t", "t_prime", "i", "j", "component", "cluster", "detection", "distance",
        "dx", "dy", "dz", "dqx", "dqy", "dqz", "dqw", "dtheta_rad",
        "i_x", "i_y", "i_z", "j_x", "j_y", "j_z",
    ]  # fmt: skip
    assert len(frame) == len(samples)
    path = tmp_path / "samples.csv"
    samples.to_csv(path)
    csv = pd.read_csv(path)
    np.testing.assert_allclose(frame["t"], csv["t_s"])
    np.testing.assert_allclose(frame["t_prime"], csv["t_prime_s"])
    for column in ("i", "j", "component"):
        np.testing.assert_array_equal(frame[column], csv[column], err_msg=column)
    np.testing.assert_allclose(frame["distance"], csv["distance"], rtol=1e-12)
    for column in ("i_x", "i_y", "i_z", "j_x", "j_y", "j_z"):
        np.testing.assert_allclose(frame[column], csv[column], rtol=1e-12, err_msg=column)
    assert (frame["cluster"] == -1).all() and csv["cluster"].isna().all()


def test_samples_of_scored_clusters_to_pandas():
    det = il.Detections([0.0, 0.0, 500.0], [100.0, 101.0, 900.0], scores=[0.2, 0.8, 0.5])
    samples = il.sample(il.cluster_detections(det, epsilon_s=30.0), "alpha", rate=1.0, seed=0)
    frame = samples.to_pandas()
    assert "i" not in frame and frame["score"].tolist() == [0.2, 0.8, 0.5]
    assert frame["distance"].isna().all()


def test_to_pandas_without_pandas_is_a_clear_import_error(results, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # `import pandas` now raises ImportError
    calls = {
        "Table": results.loops.components.to_pandas,
        "Detections": results.detections.to_pandas,
        "Samples": results.samples.to_pandas,
    }
    for name, call in calls.items():
        with pytest.raises(ImportError, match=r"to_pandas\(\) needs pandas.*pip install pandas"):
            call()
            pytest.fail(f"{name}.to_pandas() without pandas")
    # The numpy columns need no pandas.
    assert results.loops.components["id"].dtype == np.int64


def test_importing_the_package_does_not_import_pandas_or_evo():
    code = (
        "import sys, inexact_loops as il\n"
        "loops = il.find_loops(il.urban_drive(duration_s=60.0), gamma=20.0, separation=None)\n"
        "loops.components, loops.runs()\n"
        "assert 'pandas' not in sys.modules, 'pandas imported'\n"
        "assert 'evo' not in sys.modules, 'evo imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


# --- numpy outputs --------------------------------------------------------------------------------

ARRAYS = {
    "Trajectory.timestamps": (lambda r: r.traj.timestamps, "float64", 1),
    "Trajectory.positions": (lambda r: r.traj.positions, "float64", 2),
    "Trajectory.cell_widths": (lambda r: r.traj.cell_widths, "float64", 1),
    "Loops.loop_duration": (lambda r: r.loops.loop_duration(), "float64", 1),
    "Detections.t": (lambda r: r.detections.t, "float64", 1),
    "Detections.t_prime": (lambda r: r.detections.t_prime, "float64", 1),
    "Detections.i": (lambda r: r.detections.i, "int64", 1),
    "Detections.j": (lambda r: r.detections.j, "int64", 1),
    "DetectionClusters.labels": (lambda r: r.clusters.labels, "int64", 1),
    "Samples.t": (lambda r: r.samples.t, "float64", 1),
    "Samples.t_prime": (lambda r: r.samples.t_prime, "float64", 1),
    "Samples.i": (lambda r: r.samples.i, "int64", 1),
    "Samples.j": (lambda r: r.samples.j, "int64", 1),
    "Samples.component": (lambda r: r.samples.component, "int64", 1),
    "Samples.cluster": (lambda r: r.samples.cluster, "int64", 1),
    "Samples.detection": (lambda r: r.samples.detection, "int64", 1),
    "Samples.distance": (lambda r: r.samples.distance, "float64", 1),
    "SampleQuality.per_component": (lambda r: r.quality.per_component, "int64", 1),
    "SampleQuality.sample_components": (lambda r: r.quality.sample_components, "int64", 1),
    "SampleQuality.nearest_spacing_s": (lambda r: r.quality.nearest_spacing_s, "float64", 1),
}


@pytest.mark.parametrize("name", ARRAYS)
def test_array_outputs_are_plain_owned_numpy_arrays(results, name):
    get, dtype, ndim = ARRAYS[name]
    array = get(results)
    assert type(array) is np.ndarray
    assert array.dtype == np.dtype(dtype) and array.ndim == ndim
    assert array.flags.writeable and array.flags.c_contiguous
    again = get(results)
    assert not np.shares_memory(array, again)  # a copy each time: writing to it changes nothing
    array[...] = 0
    np.testing.assert_array_equal(get(results), again)
