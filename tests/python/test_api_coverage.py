"""Every public name of ``inexact_loops`` is exercised, with its error cases.

Each test says which public names it covers (``@covers``); :func:`test_every_public_name_is_covered`
fails when a name of ``inexact_loops.__all__``, a public method or property of a public class, or
a metric class has no test, here or in the file named in :data:`ELSEWHERE`. Errors are checked
for their class and for naming the offending value, index or argument. Values are checked
against independent formulas (numpy, scipy, scikit-learn) where there is one.
"""

from __future__ import annotations

import csv
import importlib.metadata
import json
import re
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation
from sklearn.cluster import DBSCAN

import inexact_loops as il
from inexact_loops import metrics, tiles, viewers

TESTS = Path(__file__).parent

#: Public name -> the tests of this file that exercise it.
COVERED: dict[str, list[str]] = {}

#: Public names tested in other files: name -> (file, test function).
ELSEWHERE = {
    **{
        f"viewers.{name}": ("python/test_viewers.py", "test_python_to_mcap_equals_the_csv_files")
        for name in ("LAYOUT_FILE", "Scene", "scene", "to_mcap")
    },
    "viewers.to_rerun": ("python/test_viewers.py", "test_rerun_recording_holds_the_same_entities"),
    **{
        f"viewers.LiveServer.{name}": (
            "python/test_viewers_live.py",
            "test_python_serve_sends_each_keyframe_and_closing_frees_the_port",
        )
        for name in ("address", "wait_for_client", "send", "send_plane")
    },
    **{
        name: (
            "python/test_store.py",
            "test_duckdb_pandas_and_pyarrow_read_what_find_fleet_loops_finds",
        )
        for name in (
            "FleetStore",
            "FleetStore.open",
            "FleetStore.state_path",
            "FleetStore.components",
            "FleetStore.added",
            "FleetStore.session_pairs",
            "FleetStore.overlap_matrix",
            "FleetStore.loop_duration",
            "FleetStore.samples",
        )
    },
    **{
        name: ("python/test_store.py", "test_an_update_by_its_steps_writes_the_update_here")
        for name in (
            "StoreUpdatePlan",
            "StoreUpdatePlan.scan",
            "StoreUpdatePlan.tile_sessions",
            "StoreUpdatePlan.last_update",
        )
    },
    "FleetStore.near": (
        "python/test_store_queries.py",
        "test_near_a_polygon_matches_matplotlib_and_edge_distances",
    ),
    "FleetStore.revisits": (
        "python/test_store_queries.py",
        "test_revisits_match_the_components_table",
    ),
    **{
        name: ("python/test_store.py", "test_random_adds_replacements_and_removals_equal_one_run")
        # (`update` is also a name of dict's, which the check leaves out.)
        for name in ("FleetStore.names",)
    },
    **{
        name: ("python/test_store.py", "test_settings_are_fixed_when_the_store_is_made")
        for name in (
            "FleetStore.DEFAULT_BLOCK",
            "FleetStore.path",
            "FleetStore.gamma",
            "FleetStore.metric_name",
            "FleetStore.separation",
            "FleetStore.block",
            "FleetStore.sampler",
            "FleetStore.last_update",
        )
    },
    **{
        name: ("python/test_online.py", test)
        for test, names in {
            "test_after_every_push_the_live_components_equal_find_loops": (
                "OnlineLoops",
                "OnlineLoops.push",
                "OnlineLoops.components",
                "OnlineLoops.to_loops",
                "OnlineLoops.loop_duration",
            ),
            "test_push_many_equals_push_one_at_a_time": (
                "OnlineLoops.push_many",
                "OnlineSampler",
                "OnlineSampler.offer",
                "Update",
                "Update.first_pose",
                "Update.pose",
                "Candidate",
            ),
            "test_an_update_reports_the_new_rows_runs_created_and_merged_components": (
                "Update.runs",
                "Update.created",
                "Update.extended",
                "Update.merged",
                "Update.loop_duration_s",
                "OnlineLoops.resolve",
            ),
            "test_rebuild_then_push_equals_the_batch_of_the_corrected_trajectory": (
                "OnlineLoops.rebuild",
                "OnlineLoops.rebuild_count",
            ),
            "test_the_getters_say_what_was_given": (
                "OnlineLoops.gamma",
                "OnlineLoops.dim",
                "OnlineLoops.metric_name",
                "OnlineLoops.timestamps",
                "OnlineLoops.trajectory",
                "OnlineSampler.rate",
                "OnlineSampler.cap_per_minute",
                "OnlineSampler.cap_per_metre",
                "OnlineSampler.first_on_appearance",
                "OnlineSampler.first_offer",
                "OnlineSampler.separation",
                "OnlineSampler.seed",
            ),
            "test_p1_online_every_component_gets_its_closest_pair_when_it_appears": (
                "Candidate.keyframe",
                "Candidate.j",
                "Candidate.pair",
                "Candidate.component",
                "Candidate.distance",
                "Candidate.first",
            ),
            "test_a_candidate_offered_after_its_pair_says_both": (
                "Candidate.k",
                "Candidate.improves",
            ),
        }.items()
        for name in names
    },
    "tiles.SessionBlocks.coarsened": (
        "python/test_dask.py",
        "test_coarsened_blocks_are_cut_as_asked_and_pickle",
    ),
    "tiles.scan_tiles": ("python/test_dask.py", "test_a_group_of_tiles_scans_as_each_tile_alone"),
    **{
        name: ("python/test_dask.py", "test_tiles_pickle_as_their_bytes_and_corrupt_bytes_fail")
        for name in (
            "tiles.SessionBlocks",
            "tiles.SessionBlocks.block",
            "tiles.SessionBlocks.metric_name",
            "tiles.SessionBlocks.poses",
            "tiles.SessionBlocks.span_s",
            "tiles.SessionBlocks.to_bytes",
            "tiles.Tile",
            "tiles.Tile.columns",
            "tiles.Tile.rows",
            "tiles.Tile.sessions",
            "tiles.TileMerge",
            "tiles.TileMerge.component_count",
            "tiles.TileMerge.from_bytes",
            "tiles.TileMerge.open_edge_count",
            "tiles.TileMerge.tile_count",
            "tiles.TileMerge.to_bytes",
            "tiles.TileSummary",
            "tiles.TileSummary.component_count",
            "tiles.TileSummary.edge_count",
            "tiles.TileSummary.from_bytes",
            "tiles.TileSummary.tile",
            "tiles.TileSummary.to_bytes",
            "tiles.merge_tiles",
            "tiles.plan_tiles",
            "tiles.scan_tile",
            "tiles.session_blocks",
        )
    },
    **{
        name: ("python/test_dask.py", "test_in_process_equals_the_fleet")
        for name in (
            "tiles.TileMerge.finish",
            "TiledFleetLoops",
            "TiledFleetLoops.between_sessions",
            "TiledFleetLoops.components",
            "TiledFleetLoops.names",
            "TiledFleetLoops.overlap_matrix",
            "TiledFleetLoops.session_pairs",
        )
    },
    **{
        name: ("python/test_dask.py", "test_samples_on_the_cluster_equal_sample_fleet")
        for name in (
            "TiledFleetLoops.draw",
            "TiledFleetLoops.tiles",
            "tiles.KeyedDraw",
            "tiles.KeyedDraw.absorb",
            "tiles.KeyedDraw.available",
            "tiles.KeyedDraw.done",
            "tiles.KeyedDraw.groups",
            "tiles.KeyedDraw.requests",
            "tiles.KeyedDraw.table",
            "tiles.KeyedDraw.warnings",
            "tiles.TileDrawRequest",
            "tiles.TileDrawRequest.tile",
            "tiles.DrawCandidates",
            "tiles.DrawCandidates.to_bytes",
            "tiles.draw_tile",
        )
    },
    **{
        name: ("python/test_dask.py", "test_loop_duration_from_tiles_equals_the_fleet")
        for name in (
            "tiles.TileDuration",
            "tiles.TileDuration.tile",
            "tiles.TileDuration.to_bytes",
            "tiles.session_loop_duration",
        )
    },
    **{
        name: ("python/test_dask.py", "test_draws_from_kept_runs_or_rescans_are_the_same")
        for name in (
            "tiles.TileRuns",
            "tiles.TileRuns.metric_name",
            "tiles.TileRuns.nbytes",
            "tiles.TileRuns.tile",
        )
    },
    "Trajectory.from_evo": (
        "python/test_interop.py",
        "test_from_evo_se3_reorders_w_first_quaternions",
    ),
    **{
        name: (
            "python/test_trajectory_manifold.py",
            "test_find_loops_without_metric_uses_the_manifolds_metric",
        )
        for name in ("Trajectory.manifold", "Trajectory.metric_name")
    },
    "Detections.to_pandas": ("python/test_interop.py", "test_detections_to_pandas"),
    "OutOfMemoryError": (
        "python/test_nothing_aborted.py",
        "test_an_answer_too_big_for_memory_raises_memory_error_and_the_interpreter_survives",
    ),
    "read_detections": (
        "python/test_reading.py",
        "test_read_detections_drops_outside_the_span_on_request",
    ),
    "Samples.to_pandas": ("python/test_interop.py", "test_samples_to_pandas_equals_the_csv"),
    "Table.to_pandas": ("python/test_interop.py", "test_tables_to_pandas"),
    "Trajectory.plane_axes": (
        "test_ground_plane.py",
        "test_maps_draw_and_label_the_plane_a_trajectory_was_read_on",
    ),
    **{
        name: ("python/test_plane.py", "test_grid_of_every_pose_and_of_evenly_spaced_pixels")
        for name in (
            "PlaneGrid",
            "PlaneGrid.columns",
            "PlaneGrid.rows",
            "PlaneGrid.column_edges_s",
            "PlaneGrid.row_edges_s",
            "PlaneGrid.width",
            "PlaneGrid.height",
            "PlaneGrid.poses",
        )
    },
    "distance_image": (
        "python/test_plane.py",
        "test_so3_and_se3_distance_images_equal_scipy_rotations",
    ),
    "Loops.label_image": ("python/test_plane.py", "test_label_image_is_the_dense_labelling_folded"),
    **{
        name: ("python/test_plane.py", "test_components_of_pairs_and_counts")
        for name in ("Loops.components_of_pairs", "Loops.pair_counts_per_component")
    },
    "Trajectory.nearest_poses": ("python/test_plane.py", "test_nearest_poses_are_the_argmin"),
    **{
        name: ("python/test_plane.py", "test_outlines_are_the_pixel_sides_between_labels")
        for name in ("outline_segments", "component_outlines")
    },
    "chain_polylines": ("python/test_plane.py", "test_chain_polylines_use_every_edge_once"),
    "isocontour": ("python/test_plane.py", "test_isocontour_crosses_between_pixel_centres"),
    "sampler_symbol": ("python/test_plane.py", "test_sampler_symbols_come_from_the_core"),
    **{
        name: ("python/test_pose_graphs.py", "test_tables_of_a_3d_graph")
        for name in (
            "read_pose_graph",
            "PoseGraph",
            "PoseGraph.trajectory",
            "PoseGraph.vertex_ids",
            "PoseGraph.dim",
            "PoseGraph.vertices",
            "PoseGraph.edges",
        )
    },
    **{
        name: ("python/test_pose_graphs.py", "test_chained_se3_quat_edges_give_back_the_vertices")
        for name in ("PoseGraph.chained", "DeadReckoningWarning")
    },
    "PoseGraph.edge_verdicts": (
        "python/test_pose_graphs.py",
        "test_edge_verdicts_are_the_brute_forces",
    ),
    "Loops.pair_verdicts": (
        "python/test_pose_graphs.py",
        "test_verdicts_refuse_another_trajectory_or_metric",
    ),
    **{
        name: ("python/test_fleet.py", "test_fleet_from_trajectories_pairs_and_paths")
        for name in (
            "Fleet",
            "Fleet.names",
            "Fleet.poses",
            "Fleet.starts",
            "Fleet.clock_offsets",
            "Fleet.joint",
            "Fleet.session",
            "Fleet.locate",
            "Fleet.index",
        )
    },
    **{
        name: ("python/test_fleet.py", "test_find_fleet_loops_options_and_errors")
        for name in (
            "find_fleet_loops",
            "FleetLoops",
            "FleetLoops.names",
            "FleetLoops.gamma",
            "FleetLoops.separation",
            "FleetLoops.metric_name",
            "FleetLoops.pruning",
            "FleetLoops.warnings",
            "FleetLoops.loops",
            "FleetLoops.components",
        )
    },
    **{
        name: ("python/test_fleet.py", "test_random_fleets_equal_scipy_labelling_per_session_pair")
        for name in (
            "FleetLoops.fleet",
            "FleetLoops.session_pairs",
            "FleetLoops.overlap_matrix",
            "FleetLoops.loop_duration",
        )
    },
    **{
        name: (
            "python/test_fleet.py",
            "test_samples_between_sessions_name_both_and_cover_every_overlap",
        )
        for name in (
            "sample_fleet",
            "FleetLoops.between_sessions",
            "FleetSamples",
            "FleetSamples.samples",
            "FleetSamples.sampler",
            "FleetSamples.groups",
            "FleetSamples.table",
        )
    },
    **{
        name: ("python/test_fleet.py", "test_samples_over_the_whole_fleet_and_baselines")
        for name in (
            "FleetSamples.fleet",
            "FleetSamples.available",
            "FleetSamples.warnings",
            "FleetSamples.to_pandas",
        )
    },
    "urban_fleet": (
        "python/test_fleet.py",
        "test_urban_fleet_is_seeded_and_names_vehicles_and_days",
    ),
}


def covers(*names: str) -> Callable[[Callable[..., None]], Callable[..., None]]:
    def register(test: Callable[..., None]) -> Callable[..., None]:
        for name in names:
            COVERED.setdefault(name, []).append(test.__name__)
        return test

    return register


def public_names() -> set[str]:
    """``__all__``, the public attributes of its classes (not those of ``dict`` or ``object``),
    the same of :mod:`inexact_loops.tiles`, and the metric classes."""
    names = set()
    inherited = set(dir(dict)) | set(dir(object))
    for name in il.__all__:
        names.add(name)
        obj = getattr(il, name)
        if isinstance(obj, type) and not issubclass(obj, BaseException):
            names.update(
                f"{name}.{attr}"
                for attr in dir(obj)
                if not attr.startswith("_") and attr not in inherited
            )
    # The tiles' plumbing, a submodule of its own: its names and their classes' attributes.
    for name in tiles.__all__:
        names.add(f"tiles.{name}")
        obj = getattr(tiles, name)
        if isinstance(obj, type):
            names.update(
                f"tiles.{name}.{attr}"
                for attr in dir(obj)
                if not attr.startswith("_") and attr not in inherited
            )
    names.update(f"metrics.{name}" for name in metrics.__all__)
    names.add("metrics.Metric.spec")
    names.update(f"viewers.{name}" for name in viewers.__all__)
    names.update(
        f"viewers.LiveServer.{attr}" for attr in dir(viewers.LiveServer) if not attr.startswith("_")
    )
    return names


def raises(error: type[BaseException], *named: str):
    """``pytest.raises(error)`` whose message must contain each of ``named`` literally."""
    return pytest.raises(error, match="".join(f"(?=.*{re.escape(text)})" for text in named))


N = 40


def ring(n: int = N) -> tuple[np.ndarray, np.ndarray]:
    """A 95% circle of radius 10 m, 10 Hz: one trivial and one non-trivial component at 4 m."""
    angle = np.linspace(0.0, 0.95 * 2 * np.pi, n)
    return np.arange(n) * 0.1, 10.0 * np.c_[np.cos(angle), np.sin(angle)]


@pytest.fixture(scope="module")
def traj() -> il.Trajectory:
    return il.Trajectory(*ring())


@pytest.fixture(scope="module")
def loops(traj) -> il.Loops:
    return il.find_loops(traj, gamma=4.0, separation=None)


@pytest.fixture(scope="module")
def clusters() -> il.DetectionClusters:
    det = il.Detections([0.0, 1.0, 3.0], [3.5, 3.6, 3.9], scores=[0.1, 0.2, 0.3])
    return il.cluster_detections(det, epsilon_s=1.0)


# --- the package ----------------------------------------------------------------------------------


@covers("__version__")
def test_version_is_the_distribution_version():
    assert il.__version__ == importlib.metadata.version("inexact-loops")
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", il.__version__)


@covers(
    "LoopsError",
    "InvalidTrajectoryError",
    "InvalidParameterError",
    "LoopsIOError",
    "InternalError",
)
def test_each_error_class_is_what_its_cases_raise(tmp_path):
    with raises(il.InvalidTrajectoryError, "pose 1"):
        il.Trajectory([0.0, 1.0], [0.0, np.nan])
    with raises(il.InvalidParameterError, "gamma", "-1"):
        il.find_loops(il.Trajectory(*ring()), gamma=-1.0, separation=None)
    bad = tmp_path / "bad.tum"
    bad.write_text("0 0 0 0 0 0 0 1\n1 x 0 0 0 0 0 1\n")
    with raises(il.LoopsIOError, "bad.tum line 2", '"x"'):
        il.read_trajectory(bad)
    for cls in (il.InvalidTrajectoryError, il.InvalidParameterError, il.LoopsIOError):
        assert issubclass(cls, il.LoopsError)
    # InternalError is a caught Rust panic: no input should raise it. Its place in the hierarchy:
    assert issubclass(il.InternalError, il.LoopsError) and issubclass(
        il.InternalError, RuntimeError
    )


# --- Table ----------------------------------------------------------------------------------------


@covers(
    "Separation",
    "Separation.for_gamma",
    "Separation.is_none",
    "Separation.path",
    "Separation.time_s",
    "Loops.separation",
    "path_length",
)
def test_separation_and_path_length(traj) -> None:
    # The default of find_loops: 4 gamma along the path, no time separation.
    assert il.Separation.for_gamma(1.0) == il.Separation(path=4.0)
    auto = il.Separation.for_gamma(4.0)
    assert (auto.path, auto.time_s, auto.is_none) == (16.0, 0.0, False)
    assert il.find_loops(traj, gamma=4.0).separation == auto
    assert il.find_loops(traj, gamma=4.0, separation="auto").separation == auto
    for paper in (None, "none", 0.0, il.Separation()):
        found = il.find_loops(traj, gamma=4.0, separation=paper)
        assert found.separation.is_none and found.separation == il.Separation(), paper
    given = il.Separation(path=2.5, time_s=30.0)
    assert il.find_loops(traj, gamma=4.0, separation=given).separation == given
    assert il.find_loops(traj, gamma=4.0, separation=7).separation == il.Separation(path=7.0)
    assert (
        repr(given) == "Separation(path=2.5, time_s=30.0)"
        and str(given) == "path >= 2.5, time >= 30 s"
    )
    with pytest.raises(il.InvalidParameterError, match="time separation"):
        il.Separation(time_s=-1.0)
    with pytest.raises(il.InvalidParameterError, match="path separation"):
        il.find_loops(traj, gamma=4.0, separation=float("nan"))
    with pytest.raises(il.InvalidParameterError, match="separation must be"):
        il.find_loops(traj, gamma=4.0, separation="everything")
    with pytest.raises(TypeError, match="separation must be"):
        il.find_loops(traj, gamma=4.0, separation=True)
    with pytest.raises(TypeError, match="separation must be"):
        il.find_loops(traj, gamma=4.0, separation=[1.0])
    with pytest.raises(il.InvalidParameterError, match="gamma"):
        il.Separation.for_gamma(0.0)
    # The path length is the running sum of the steps, as numpy sums them.
    s = il.path_length(traj)
    assert s.dtype == np.float64 and s.shape == (len(traj),) and s[0] == 0.0
    steps = np.linalg.norm(np.diff(ring()[1], axis=0), axis=1)
    np.testing.assert_array_equal(s[1:], np.cumsum(steps))


@covers("Table", "Table.num_rows")
def test_table_is_a_dict_of_columns(loops):
    table = loops.components
    assert isinstance(table, il.Table) and isinstance(table, dict)
    assert table.num_rows == len(table["id"]) == 2
    assert il.Table().num_rows == 0
    built = il.Table(a=np.arange(3), b=np.zeros(3))
    assert built.num_rows == 3 and list(built) == ["a", "b"]


# --- Trajectory -----------------------------------------------------------------------------------


@covers(
    "Trajectory",
    "Trajectory.dim",
    "Trajectory.timestamps",
    "Trajectory.positions",
    "Trajectory.cell_widths",
    "Trajectory.span_s",
)
def test_trajectory_and_its_arrays():
    t, p = ring()
    traj = il.Trajectory(t, p)
    assert len(traj) == N and traj.dim == 2
    np.testing.assert_array_equal(traj.timestamps, t)
    np.testing.assert_array_equal(traj.positions, p)
    steps = np.diff(t)
    np.testing.assert_allclose(
        traj.cell_widths, np.r_[steps[0], steps[:-1] + steps[1:], steps[-1]] / 2
    )
    assert traj.span_s == pytest.approx(t[-1] - t[0]) == pytest.approx(traj.cell_widths.sum())
    with raises(il.InvalidTrajectoryError, "pose 7", "coordinate 1", "inf"):
        il.Trajectory(t, np.where(np.arange(N)[:, None] == 7, [0.0, np.inf], p))
    with raises(ValueError, "positions", "[40, 2, 1]"):
        il.Trajectory(t, p[:, :, None])
    with raises(TypeError, "timestamps", "object"):
        il.Trajectory(None, p)


QUATERNIONS = Rotation.from_rotvec(np.linspace(0, 2, N)[:, None] * [0.3, -0.5, 0.8])


@covers("Trajectory.se3")
def test_se3():
    t, p = ring()
    positions = np.c_[p, np.zeros(N)]
    q = QUATERNIONS.as_quat()
    traj = il.Trajectory.se3(t, positions, 3 * q, quaternion_tolerance=2.5)
    assert traj.dim == 7
    np.testing.assert_allclose(traj.positions, np.c_[positions, q], atol=1e-15)
    q_zero = q.copy()
    q_zero[9] = 0.0
    with raises(il.InvalidTrajectoryError, "quaternion of pose 9", "norm 0"):
        il.Trajectory.se3(t, positions, q_zero)
    with raises(il.InvalidTrajectoryError, "quaternion of pose 0", "norm 3"):
        il.Trajectory.se3(t, positions, 3 * q)
    with raises(ValueError, "positions", "(n, 3)", "2 columns"):
        il.Trajectory.se3(t, p, q)
    with raises(ValueError, "quaternions_xyzw", "(n, 4)", "3 columns"):
        il.Trajectory.se3(t, positions, q[:, :3])


@covers("Trajectory.so3")
def test_so3():
    t, _ = ring()
    q = QUATERNIONS.as_quat()
    np.testing.assert_allclose(il.Trajectory.so3(t, q).positions, q, atol=1e-15)
    with raises(il.InvalidTrajectoryError, "quaternion of pose 0", "norm 2"):
        il.Trajectory.so3(t, 2 * q)
    with raises(ValueError, "timestamps has 40 rows", "quaternions_xyzw has 5"):
        il.Trajectory.so3(t, q[:5])


@covers("Trajectory.se3", "Trajectory.so3")
def test_bad_quaternion_tolerance_is_named():
    t, _ = ring()
    q = QUATERNIONS.as_quat()
    for tolerance in (np.nan, -1.0):
        with raises(il.InvalidParameterError, "quaternion_tolerance"):
            il.Trajectory.so3(t, 5 * q, quaternion_tolerance=tolerance)


@covers("Trajectory.so3_from_rotation_vectors")
def test_so3_from_rotation_vectors_equals_scipy():
    t, _ = ring()
    traj = il.Trajectory.so3_from_rotation_vectors(t, QUATERNIONS.as_rotvec())
    agree = np.abs(np.sum(traj.positions * QUATERNIONS.as_quat(), axis=1))
    np.testing.assert_allclose(agree, 1.0, atol=1e-12)
    bad = QUATERNIONS.as_rotvec()
    bad[12, 2] = np.nan
    with raises(il.InvalidTrajectoryError, "pose 12", "coordinate 2", "NaN"):
        il.Trajectory.so3_from_rotation_vectors(t, bad)
    with raises(ValueError, "rotation_vectors", "(n, 3)"):
        il.Trajectory.so3_from_rotation_vectors(t, QUATERNIONS.as_quat())


@covers("Trajectory.se2")
def test_se2_wraps_the_heading():
    t = np.arange(3.0)
    traj = il.Trajectory.se2(t, [[0, 0, np.pi], [0, 0, -np.pi], [1, 2, 4.0]])
    np.testing.assert_allclose(traj.positions[:, 2], [np.pi, np.pi, 4.0 - 2 * np.pi])
    with raises(ValueError, "poses_xy_theta", "(n, 3)", "2 columns"):
        il.Trajectory.se2(t, np.zeros((3, 2)))
    with raises(il.InvalidTrajectoryError, "pose 1", "NaN"):
        il.Trajectory.se2(t, [[0, 0, 0], [0, 0, np.nan], [0, 0, 0]])


@covers("Trajectory.torus")
def test_torus_wraps_the_angles():
    angles = np.array([[np.pi, -np.pi], [1.5 * np.pi, 0.0], [7.0, -7.0]])
    traj = il.Trajectory.torus(np.arange(3.0), angles)
    expected = np.where(
        np.isclose(np.angle(np.exp(1j * angles)), -np.pi), np.pi, np.angle(np.exp(1j * angles))
    )
    np.testing.assert_allclose(traj.positions, expected, atol=1e-12)
    with raises(il.InvalidTrajectoryError, "pose 2", "inf"):
        il.Trajectory.torus(np.arange(3.0), [[0.0], [0.0], [np.inf]])
    with raises(ValueError, "angles_rad", "[3, 1, 1]"):
        il.Trajectory.torus(np.arange(3.0), np.zeros((3, 1, 1)))


@covers("Trajectory.sphere", "Trajectory.sphere_from_lat_lon")
def test_sphere_points():
    t = np.arange(3.0)
    vectors = np.array([[2.0, 0, 0], [0, 0, -3], [1, 1, 0]])
    np.testing.assert_allclose(
        il.Trajectory.sphere(t, vectors).positions,
        vectors / np.linalg.norm(vectors, axis=1, keepdims=True),
    )
    with raises(il.InvalidTrajectoryError, "vector of pose 1", "norm 0"):
        il.Trajectory.sphere(t, [[1.0, 0, 0], [0, 0, 0], [0, 1, 0]])
    with raises(ValueError, "vectors", "(n, 3)"):
        il.Trajectory.sphere(t, np.ones((3, 2)))
    lat, lon = np.radians([10.0, -45.0, 89.0]), np.radians([20.0, 170.0, -30.0])
    traj = il.Trajectory.sphere_from_lat_lon(t, np.degrees(np.c_[lat, lon]))
    unit = np.c_[np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)]
    np.testing.assert_allclose(traj.positions, unit, atol=1e-15)
    with raises(il.InvalidTrajectoryError, "latitude of pose 2", "91"):
        il.Trajectory.sphere_from_lat_lon(t, [[0.0, 0], [0, 0], [91, 0]])


def wgs84_ecef(lat_lon_height: np.ndarray) -> np.ndarray:
    """Earth-centred, Earth-fixed WGS 84 coordinates (metres), the textbook formula."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    lat, lon = np.radians(lat_lon_height[:, 0]), np.radians(lat_lon_height[:, 1])
    h = lat_lon_height[:, 2]
    n = a / np.sqrt(1 - e2 * np.sin(lat) ** 2)
    return np.c_[
        (n + h) * np.cos(lat) * np.cos(lon),
        (n + h) * np.cos(lat) * np.sin(lon),
        (n * (1 - e2) + h) * np.sin(lat),
    ]


@covers("Trajectory.gnss", "Trajectory.gnss_ecef")
def test_gnss():
    t = np.arange(3.0)
    fixes = np.array([[48.1, 11.5, 520.0], [48.1005, 11.5003, 525.0], [48.2, 11.6, 500.0]])
    ecef = il.Trajectory.gnss_ecef(t, fixes)
    expected = wgs84_ecef(fixes)
    # East, north and up of the first fix: pymap3d's ENU, and a rotation of the ECEF offsets.
    pymap3d = pytest.importorskip("pymap3d")
    enu = np.array(pymap3d.geodetic2enu(*fixes.T, *fixes[0], deg=True)).T
    np.testing.assert_allclose(ecef.positions, enu, atol=1e-6)
    offsets = expected - expected[0]
    np.testing.assert_allclose(
        np.linalg.norm(ecef.positions, axis=1), np.linalg.norm(offsets, axis=1), atol=1e-6
    )
    gnss = il.Trajectory.gnss(t, fixes)
    assert gnss.dim == 4
    np.testing.assert_array_equal(gnss.positions[:, 3], fixes[:, 2])
    for build in (il.Trajectory.gnss, il.Trajectory.gnss_ecef):
        with raises(il.InvalidTrajectoryError, "latitude of pose 1", "-95"):
            build(t, [[0.0, 0, 0], [-95, 0, 0], [0, 0, 0]])
        with raises(ValueError, "lat_lon_height", "(n, 3)"):
            build(t, fixes[:, :2])


@covers("Trajectory.descriptors")
def test_descriptors():
    t = np.arange(3.0)
    rows = [[3.0, 4.0], [0.0, 2.0], [1.0, 0.0]]
    np.testing.assert_allclose(
        il.Trajectory.descriptors(t, rows).positions, [[0.6, 0.8], [0, 1], [1, 0]]
    )
    np.testing.assert_array_equal(
        il.Trajectory.descriptors(t, rows, normalize=False).positions, rows
    )
    with raises(ValueError, "descriptors row 2 has 1 values", "row 0 has 2"):
        il.Trajectory.descriptors(t, [[1, 2], [3, 4], [5]])
    with raises(il.InvalidTrajectoryError, "vector of pose 1", "norm 0"):
        il.Trajectory.descriptors(t, [[1.0, 0], [0, 0], [0, 1]])


# --- find_loops and Loops -------------------------------------------------------------------------


@covers(
    "find_loops",
    "Loops",
    "Loops.gamma",
    "Loops.metric_name",
    "Loops.span_s",
    "Loops.pair_count",
    "Loops.pose_pair_count",
)
def test_find_loops_counts_the_dense_pairs(traj, loops):
    distances = cdist(traj.positions, traj.positions)
    assert loops.pair_count == np.count_nonzero(distances <= 4.0)
    assert loops.pose_pair_count == np.count_nonzero(np.triu(distances <= 4.0, k=1))
    assert loops.gamma == 4.0 and loops.metric_name == "euclidean" and loops.span_s == traj.span_s
    assert len(loops) == N
    by_callable = il.find_loops(
        traj, gamma=4.0, metric=lambda a, b: float(np.linalg.norm(a - b)), separation=None
    )
    assert by_callable.pair_count == loops.pair_count


@covers("find_loops")
def test_find_loops_errors(traj):
    with raises(il.InvalidParameterError, "gamma", "0"):
        il.find_loops(traj, gamma=0.0, separation=None)
    with raises(il.InvalidParameterError, "gamma", "NaN"):
        il.find_loops(traj, gamma=np.nan, separation=None)
    with raises(il.InvalidParameterError, '"taxicab"', "euclidean"):
        il.find_loops(traj, gamma=1.0, metric="taxicab", separation=None)
    with raises(il.InvalidParameterError, "se3(", "dimension 7", "dimension 2"):
        il.find_loops(
            traj, gamma=1.0, metric=metrics.SE3(rotation_weight_m_per_rad=1.0), separation=None
        )
    with raises(il.InvalidParameterError, "threads = 0"):
        il.find_loops(traj, gamma=1.0, threads=0, separation=None)
    with pytest.raises(OverflowError) as negative:
        il.find_loops(traj, gamma=1.0, threads=-1, separation=None)
    assert "while processing 'threads'" in negative.value.__notes__
    with raises(TypeError, "metric must be a name", "got int"):
        il.find_loops(traj, gamma=1.0, metric=3, separation=None)
    with raises(TypeError, "Trajectory"):
        il.find_loops(traj.positions, gamma=1.0, separation=None)
    with raises(TypeError, "the metric callable must return a float, got str"):
        il.find_loops(traj, gamma=1.0, metric=lambda a, b: "far", separation=None)
    with raises(ValueError, "the metric callable returned NaN"):
        il.find_loops(traj, gamma=1.0, metric=lambda a, b: float("nan"), separation=None)
    with raises(ValueError, "the metric callable returned -1"):
        il.find_loops(traj, gamma=1.0, metric=lambda a, b: -1.0, separation=None)
    with pytest.raises(ZeroDivisionError):  # the callable's own exception, unchanged
        il.find_loops(traj, gamma=1.0, metric=lambda a, b: 1 / 0, separation=None)


@covers("Loops.warnings")
def test_warnings_name_the_broken_diagonal():
    with pytest.warns(il.DiagonalBrokenWarning):
        loops = il.find_loops(
            il.Trajectory([0.0, 1, 2, 3], [0.0, 0, 100, 100]), gamma=1.0, separation=None
        )
    assert len(loops.warnings) == 1
    assert (
        "first at index 1" in loops.warnings[0] and "farther apart than gamma" in loops.warnings[0]
    )
    assert il.find_loops(il.Trajectory(*ring()), gamma=4.0, separation=None).warnings == []


def issued(call: Callable[[], object]) -> tuple[object, list[warnings.WarningMessage]]:
    """What ``call`` returns and every warning it issues (none filtered out)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, caught


@covers(
    "LoopsWarning",
    "DiagonalBrokenWarning",
    "EmptyResultWarning",
    "EmptySampleWarning",
    "NoLoopsWarning",
    "SampleBudgetWarning",
    "DroppedInputWarning",
)
def test_engine_warnings_are_python_warnings_to_filter(tmp_path, traj, loops, clusters):
    """Each warning of the engine is issued once, in its category, at the caller's line, with
    the sentence the result keeps; an "error" filter makes it an exception, "ignore" silences
    it, and a result with nothing to say issues nothing."""
    for cls in (
        il.DiagonalBrokenWarning,
        il.NoLoopsWarning,
        il.EmptySampleWarning,
        il.SampleBudgetWarning,
        il.DroppedInputWarning,
    ):
        assert issubclass(cls, il.LoopsWarning)
    assert issubclass(il.EmptySampleWarning, il.EmptyResultWarning)
    assert issubclass(il.NoLoopsWarning, il.EmptyResultWarning)
    assert issubclass(il.LoopsWarning, UserWarning) and not issubclass(
        il.LoopsWarning, il.LoopsError
    )

    gap = il.Trajectory([0.0, 1, 2, 3], [0.0, 0, 100, 100])
    line = sys._getframe().f_lineno + 1
    broken, caught = issued(lambda: il.find_loops(gap, gamma=1.0, separation=None))
    assert [w.category for w in caught] == [il.DiagonalBrokenWarning]
    assert [str(w.message) for w in caught] == broken.warnings
    assert (caught[0].filename, caught[0].lineno) == (__file__, line)

    # No revisit: a straight line keeps no pair within gamma 4 gamma apart along the path, and
    # a sample of those loops is empty.
    straight = il.Trajectory(np.arange(50.0), np.arange(50.0))
    none, caught = issued(lambda: il.find_loops(straight, gamma=3.0))
    assert len(none.components["id"]) == 0
    assert [w.category for w in caught] == [il.NoLoopsWarning]
    assert [str(w.message) for w in caught] == none.warnings
    assert "no revisit at gamma 3" in none.warnings[0]
    samples, caught = issued(lambda: il.sample(none, "rho", budget=10, seed=0, trajectory=straight))
    assert len(samples) == 0 and [w.category for w in caught] == [il.EmptySampleWarning]

    # No budget spent as asked: fewer candidates than the budget, or fewer samples than groups.
    pairs = (loops.pair_count - N) // 2
    for source, sampler, budget, text in [
        (loops, "alpha", pairs + 1, f"more than the {pairs} candidates"),
        (loops, "one", 1, "P1 cannot hold"),
        (clusters, "alpha", 4, "more than the 3 candidates"),
    ]:
        on = traj if source is loops else None
        samples, caught = issued(
            lambda s=source, k=sampler, b=budget, t=on: il.sample(
                s, k, budget=b, seed=0, trajectory=t
            )
        )
        assert [w.category for w in caught] == [il.SampleBudgetWarning], text
        assert [str(w.message) for w in caught] == samples.warnings and text in samples.warnings[0]

    # Empty: every component is trivial and skip_trivial leaves them out. With a budget the
    # sampler says so itself; with a rate the bindings do, naming skip_trivial.
    only_trivial = il.find_loops(straight, gamma=3.0, separation=None)
    assert only_trivial.components["trivial"].tolist() == [True]
    for size, text in [
        ({"budget": 10}, "budget 10 is more than the 0 candidates"),
        (
            {"rate": 1.0},
            "no samples: the rho sampler kept none of its 0 candidate(s) (skip_trivial",
        ),
    ]:
        samples, caught = issued(
            lambda z=size: il.sample(
                only_trivial, "rho", seed=0, trajectory=straight, skip_trivial=True, **z
            )
        )
        assert len(samples) == 0
        assert [w.category for w in caught] == [il.EmptySampleWarning], size
        assert str(caught[0].message).startswith(text)

    # A lenient reading option says what it dropped.
    path = tmp_path / "twice.tum"
    path.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n1 2 0 0 0 0 0 1\n2 3 0 0 0 0 0 1\n")
    read, caught = issued(lambda: il.read_trajectory(path, drop_duplicate_stamps=True))
    assert len(read) == 3 and [w.category for w in caught] == [il.DroppedInputWarning]
    assert str(caught[0].message).endswith(
        "dropped 1 pose(s) whose timestamp repeats the one before (line 3)"
    )

    # Nothing to say: nothing issued, even under "error".
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert il.find_loops(traj, gamma=4.0).warnings == []
        assert il.sample(loops, "one", budget=2, seed=0, trajectory=traj).warnings == []

    # Filters by category: an exception under "error", nothing under "ignore".
    with warnings.catch_warnings():
        warnings.simplefilter("error", il.LoopsWarning)
        with raises(il.DiagonalBrokenWarning, "first at index 1", "farther apart than gamma"):
            il.find_loops(gap, gamma=1.0, separation=None)
        with raises(il.NoLoopsWarning, "no revisit"):
            il.find_loops(straight, gamma=3.0)
        with raises(il.SampleBudgetWarning, "P1 cannot hold"):
            il.sample(loops, "one", budget=1, seed=0, trajectory=traj)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warnings.simplefilter("ignore", il.DiagonalBrokenWarning)
        assert len(il.find_loops(gap, gamma=1.0, separation=None).warnings) == 1
    assert caught == []


@covers("Loops.components", "Loops.runs")
def test_components_and_runs_agree(loops):
    table, runs = loops.components, loops.runs()
    assert table["trivial"].tolist() == [True, False]
    pairs_upper = ((runs["end"] - runs["start"] + 1) * 1).sum()
    assert pairs_upper == (loops.pair_count + len(loops)) // 2
    for c in table["id"]:
        rows = runs["row"][runs["component"] == c]
        assert rows.min() == table["i_min"][c] and rows.max() == table["i_max"][c]
    d = table["closest_distance"][1]
    assert d == pytest.approx(
        np.linalg.norm(np.subtract(*ring()[1][[table["closest_i"][1], table["closest_j"][1]]]))
    )


@covers("Loops.component_of", "Loops.is_simple")
def test_pair_lookups_and_their_index_errors(loops):
    assert loops.component_of(0, N - 1) == 1 and loops.component_of(N - 1, 0) == 1
    assert loops.component_of(0, N // 2) is None
    assert (
        loops.is_simple(3, 4) and not loops.is_simple(0, N - 1) and not loops.is_simple(0, N // 2)
    )
    for lookup in (loops.component_of, loops.is_simple):
        with raises(IndexError, f"pose index {N}", f"{N} poses"):
            lookup(0, N)
        with raises(IndexError, "i = -1", "negative"):
            lookup(-1, 0)
        with raises(IndexError, "j = -3", "negative"):
            lookup(0, -3)
        with pytest.raises(TypeError):
            lookup(0.5, 1)


@covers("Loops.loop_duration", "Loops.loop_area", "Loops.loop_density")
def test_measures_and_their_errors(traj, loops):
    distances = cdist(traj.positions, traj.positions)
    tau = (distances <= 4.0) @ traj.cell_widths
    np.testing.assert_allclose(loops.loop_duration(), tau)
    np.testing.assert_allclose(loops.loop_duration(normalized=True), tau / traj.span_s)
    a, b = traj.timestamps[0], traj.timestamps[-1]
    assert loops.loop_area(a, b) == pytest.approx(tau @ traj.cell_widths)
    assert loops.loop_density(a, b) == pytest.approx(loops.loop_area(a, b) / (b - a))
    assert loops.loop_density(0.0, 1.0, normalized=True) == pytest.approx(
        loops.loop_area(a, b) / traj.span_s**2
    )
    total = sum(loops.loop_duration(components=[c]) for c in (0, 1))
    np.testing.assert_allclose(total, tau)
    with raises(il.InvalidParameterError, '"sideways"', "both", "begin", "end"):
        loops.loop_duration(side="sideways")
    with raises(il.InvalidParameterError, "id 5", "2"):
        loops.loop_area(a, b, components=[5])
    with raises(il.InvalidParameterError, "[2, 1]", "a < b"):
        loops.loop_density(2.0, 1.0)
    with raises(il.InvalidParameterError, "NaN", "a < b"):
        loops.loop_area(np.nan, 1.0)


# --- urban_drive ----------------------------------------------------------------------------------


@covers("urban_drive")
def test_urban_drive_and_its_parameter_errors():
    traj = il.urban_drive(duration_s=30.0, rate_hz=5.0, seed=2)
    assert len(traj) == 150 and traj.dim == 3
    np.testing.assert_allclose(np.diff(traj.timestamps), 0.2)
    np.testing.assert_array_equal(
        il.urban_drive(duration_s=30.0, rate_hz=5.0, seed=2).positions, traj.positions
    )
    se3 = il.urban_drive(duration_s=30.0, rate_hz=5.0, seed=2, se3=True)
    assert se3.dim == 7
    np.testing.assert_allclose(np.linalg.norm(se3.positions[:, 3:], axis=1), 1.0)
    bad = {
        "duration_s": 0.0, "rate_hz": -1.0, "block_m": np.nan, "city_size_m": 10.0,
        "stop_probability": 1.5, "lane_offset_m": -2.0, "lateral_noise_m": np.inf,
    }  # fmt: skip
    for name, value in bad.items():
        with raises(il.InvalidParameterError, f"{name} = "):
            il.urban_drive(**{"duration_s": 30.0, name: value})
    with raises(il.InvalidParameterError, "max_speed_mps = 3", "min_speed_mps"):
        il.urban_drive(duration_s=30.0, min_speed_mps=5.0, max_speed_mps=3.0)
    with raises(il.InvalidParameterError, "max_stop_s = 1", "min_stop_s"):
        il.urban_drive(duration_s=30.0, min_stop_s=10.0, max_stop_s=1.0)
    with raises(il.InvalidParameterError, "at least 2 poses"):
        il.urban_drive(duration_s=0.1, rate_hz=1.0)
    # Districts: the first dwell stays in the first district; bad sides and dwells are errors.
    city = il.urban_drive(
        duration_s=1200.0, city_size_m=5000.0, district_m=500.0, district_dwell_s=600.0
    )
    first, second = city.positions[:6000, :2], city.positions[6000:, :2]
    assert first.min() > -5.0 and first.max() < 505.0
    assert second[:, 0].max() > 505.0, "moves on to the next district"
    for name, value, field in [
        ("district_m", 0.0, "side_m"),
        ("district_dwell_s", -1.0, "dwell_s"),
    ]:
        with raises(il.InvalidParameterError, f"districts.{field} = "):
            il.urban_drive(duration_s=30.0, **{"district_m": 100.0, name: value})
    with raises(il.InvalidParameterError, "districts.side_m = 2000", "city_size_m"):
        il.urban_drive(duration_s=30.0, district_m=2000.0)
    with raises(il.InvalidParameterError, "district_dwell_s = 5", "district_m"):
        il.urban_drive(duration_s=30.0, district_dwell_s=5.0)
    with pytest.raises(OverflowError) as negative:
        il.urban_drive(duration_s=30.0, seed=-1)
    assert "while processing 'seed'" in negative.value.__notes__


@covers("urban_drive")
def test_urban_drive_too_many_poses_is_an_error_not_an_abort():
    code = (
        "import inexact_loops as il\n"
        "try:\n"
        "    il.urban_drive(duration_s=1e12)\n"
        "except il.InvalidParameterError as error:\n"
        "    print(error)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-300:]
    assert "poses" in result.stdout


# --- files ----------------------------------------------------------------------------------------


def write_mcap(path: Path) -> None:
    """A JSON-encoded MCAP file: /pose (foxglove.PoseInFrame, 5 poses along x) and /chatter."""
    from mcap.writer import Writer

    with open(path, "wb") as stream:
        writer = Writer(stream)
        writer.start()
        schema = writer.register_schema(
            name="foxglove.PoseInFrame", encoding="jsonschema", data=b'{"type": "object"}'
        )
        pose = writer.register_channel(topic="/pose", message_encoding="json", schema_id=schema)
        chatter = writer.register_channel(topic="/chatter", message_encoding="json", schema_id=0)
        for k in range(5):
            stamp_ns = (k + 1) * 10**8
            message = {
                "timestamp": {"sec": 0, "nsec": stamp_ns},
                "frame_id": "map",
                "pose": {
                    "position": {"x": float(k), "y": 0.0, "z": 0.0},
                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                },
            }
            data = json.dumps(message).encode()
            writer.add_message(pose, log_time=stamp_ns, publish_time=stamp_ns, data=data)
        writer.add_message(chatter, log_time=1, publish_time=1, data=b"{}")
        writer.finish()


@covers("list_topics")
def test_list_topics_and_its_errors(tmp_path):
    path = tmp_path / "drive.mcap"
    write_mcap(path)
    topics = {row["topic"]: row for row in il.list_topics(path)}
    assert topics["/pose"] == {
        "topic": "/pose", "schema": "foxglove.PoseInFrame", "encoding": "json", "messages": 5,
        "start_ns": 10**8, "end_ns": 5 * 10**8, "pose_type": "foxglove.PoseInFrame",
    }  # fmt: skip
    assert topics["/chatter"]["pose_type"] is None
    with raises(FileNotFoundError, "missing.mcap"):
        il.list_topics(tmp_path / "missing.mcap")
    text = tmp_path / "drive.txt"
    text.write_text("0 0 0 0 0 0 0 1\n")
    with raises(il.LoopsIOError, "drive.txt offset 0", "not an MCAP file"):
        il.list_topics(text)


TUM = "".join(f"{k * 0.1:.1f} {k} 0 0 0 0 0 1\n" for k in range(6))


@covers("read_trajectory")
def test_read_trajectory_and_its_errors(tmp_path):
    path = tmp_path / "drive.tum"
    path.write_text(TUM)
    np.testing.assert_array_equal(il.read_trajectory(path).positions[:, 0], np.arange(6.0))
    assert il.read_trajectory(str(path), metric="so3").dim == 4
    mcap = tmp_path / "drive.mcap"
    write_mcap(mcap)
    np.testing.assert_allclose(il.read_trajectory(mcap).timestamps, np.arange(1, 6) * 0.1)
    assert len(il.read_trajectory([mcap], topic="/pose", time="log")) == 5
    with raises(FileNotFoundError, "nope.tum"):
        il.read_trajectory(tmp_path / "nope.tum")
    with raises(TypeError, "path must be a str or an os.PathLike", "got int"):
        il.read_trajectory(5)
    with raises(TypeError, "path[1] must be a str or an os.PathLike", "got float"):
        il.read_trajectory([mcap, 1.5])
    with raises(il.InvalidParameterError, "empty list"):
        il.read_trajectory([])
    with raises(il.InvalidParameterError, '"bag"', "tum"):
        il.read_trajectory(path, format="bag")
    with raises(il.InvalidParameterError, "drive.tum", 'metric "torus" does not fit here', "se3"):
        il.read_trajectory(path, metric="torus")
    with raises(ValueError, "read_trajectory takes a metric name or object, not a callable"):
        il.read_trajectory(path, metric=lambda a, b: 0.0)
    with raises(il.InvalidParameterError, '"wall"', "header"):
        il.read_trajectory(mcap, time="wall")
    with raises(il.LoopsIOError, 'no topic "/nope"', "/pose"):
        il.read_trajectory(mcap, topic="/nope")
    with raises(il.LoopsIOError, "/chatter", "does not read poses"):
        il.read_trajectory(mcap, topic="/chatter")
    kitti = tmp_path / "poses.txt"
    kitti.write_text("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n")
    assert il.read_trajectory(kitti, format="kitti", rate_hz=10.0).span_s == pytest.approx(0.1)
    with raises(il.InvalidParameterError, "poses.txt", "rate_hz = 0"):
        il.read_trajectory(kitti, format="kitti", rate_hz=0.0)


# --- detections and clusters ----------------------------------------------------------------------


@covers(
    "Detections",
    "Detections.t",
    "Detections.t_prime",
    "Detections.score",
    "Detections.i",
    "Detections.j",
    "Detections.poses",
)
def test_detections_and_their_errors():
    det = il.Detections([5.0, 1.0], [2.0, 3.0], scores=[0.5, 0.25])
    assert det.t.tolist() == [2.0, 1.0] and det.t_prime.tolist() == [5.0, 3.0]
    assert det.score.tolist() == [0.5, 0.25]
    assert det.i is None and det.j is None and det.poses is None and len(det) == 2
    assert il.Detections([1.0], [2.0]).score is None
    with raises(il.InvalidParameterError, "no detections"):
        il.Detections([], [])
    with raises(il.InvalidParameterError, "t_prime", "1 values", "2 are needed"):
        il.Detections([1.0, 2.0], [3.0])
    with raises(il.InvalidParameterError, "detection 1", "NaN"):
        il.Detections([1.0, np.nan], [3.0, 4.0])
    with raises(il.InvalidParameterError, "score of detection 0", "inf"):
        il.Detections([1.0], [3.0], scores=[np.inf])
    with raises(ValueError, "t must be 1-dimensional", "[2, 2]"):
        il.Detections(np.zeros((2, 2)), [3.0, 4.0])
    with raises(TypeError, "t_prime", "<U1"):
        il.Detections([1.0], ["a"])


@covers("Detections.from_indices", "Detections.locate")
def test_detections_on_a_trajectory_and_their_errors(traj, loops):
    det = il.Detections.from_indices(loops, [5, 30], [1, 2], scores=[1.0, 2.0])
    assert det.i.tolist() == [1, 2] and det.j.tolist() == [5, 30] and det.poses == N
    np.testing.assert_array_equal(det.t_prime, traj.timestamps[[5, 30]])
    located = il.Detections([0.04, 1.01], [0.26, 2.0]).locate(traj)
    assert located.i.tolist() == [0, 10] and located.j.tolist() == [3, 20]
    with raises(IndexError, "detection 1", "pose 50", "40 poses"):
        il.Detections.from_indices(traj, [0, 50], [1, 2])
    with raises(IndexError, "j[0] = -1", "negative"):
        il.Detections.from_indices(traj, [0], [-1])
    with raises(TypeError, "i must hold pose indices", "float64"):
        il.Detections.from_indices(traj, [0.5], [1])
    with raises(TypeError, "trajectory_or_loops", "got ndarray"):
        il.Detections.from_indices(traj.positions, [0], [1])
    with raises(il.InvalidParameterError, "detection 0 at 100 s", "outside"):
        il.Detections([0.0], [100.0]).locate(traj)
    with raises(TypeError, "trajectory_or_loops", "got int"):
        il.Detections([0.0], [1.0]).locate(5)


@covers("draw_detections")
def test_draw_detections_and_its_errors(loops):
    det = il.draw_detections(loops, budget=20, seed=3)
    assert len(det) == 20 and len(set(zip(det.i.tolist(), det.j.tolist(), strict=True))) == 20
    assert all(
        loops.component_of(i, j) is not None and i < j for i, j in zip(det.i, det.j, strict=True)
    )
    assert len(il.draw_detections(loops, rate=1.0, seed=0)) == (loops.pair_count - N) // 2
    with raises(il.InvalidParameterError, "rate or budget"):
        il.draw_detections(loops, seed=0)
    with raises(il.InvalidParameterError, "not both", "rate=0.5", "budget=3"):
        il.draw_detections(loops, rate=0.5, budget=3, seed=0)
    with raises(il.InvalidParameterError, "rate = 1.5", "(0, 1]"):
        il.draw_detections(loops, rate=1.5, seed=0)
    with raises(il.InvalidParameterError, "budget = 100000", "pairs"):
        il.draw_detections(loops, budget=100_000, seed=0)
    with pytest.raises(OverflowError) as negative:
        il.draw_detections(loops, budget=-1, seed=0)
    assert "while processing 'budget'" in negative.value.__notes__


@covers(
    "cluster_detections",
    "DetectionClusters",
    "DetectionClusters.epsilon_s",
    "DetectionClusters.cell_side_s",
    "DetectionClusters.detections",
    "DetectionClusters.labels",
    "DetectionClusters.clusters",
)
def test_clusters_equal_dbscan_and_their_errors(loops):
    det = il.draw_detections(loops, rate=0.3, seed=5)
    clusters = il.cluster_detections(det, epsilon_s=0.35)
    points = np.c_[det.t, det.t_prime]
    theirs = DBSCAN(eps=0.35, min_samples=1).fit_predict(points)
    ours = clusters.labels
    assert (
        len(set(zip(ours.tolist(), theirs.tolist(), strict=True)))
        == len(set(ours.tolist()))
        == len(set(theirs.tolist()))
    )
    assert clusters.epsilon_s == 0.35 and 0 < clusters.cell_side_s < 0.35 / np.sqrt(2)
    np.testing.assert_array_equal(clusters.detections.t, det.t)
    table = clusters.clusters
    assert table.num_rows == len(clusters) and table["size"].sum() == len(det)
    with raises(il.InvalidParameterError, "epsilon_s = 0"):
        il.cluster_detections(det, epsilon_s=0.0)
    with raises(il.InvalidParameterError, "epsilon_s = NaN"):
        il.cluster_detections(det, epsilon_s=np.nan)
    with raises(il.InvalidParameterError, "threads = 0"):
        il.cluster_detections(det, threads=0)
    with raises(TypeError, "Detections"):
        il.cluster_detections([1.0, 2.0])


# --- sampling -------------------------------------------------------------------------------------


@covers("sample")
def test_sample_errors(traj, loops, clusters):
    with raises(il.InvalidParameterError, '"best"', "one", "rho", "alpha", "lio-sam"):
        il.sample(clusters, "best", budget=1, seed=0)
    with raises(il.InvalidParameterError, '"lio-sam"', "one, rho, rho-dispersed, alpha"):
        il.sample(clusters, "lio-sam", budget=1, seed=0)
    assert il.sample(clusters, "one", seed=0) == il.sample(
        clusters, "one", budget=il.DEFAULT_BUDGET, seed=0
    )
    with raises(il.InvalidParameterError, "budget = 0"):
        il.sample(clusters, "one", budget=0, seed=0)
    with raises(il.InvalidParameterError, "rate = 2", "(0, 1]"):
        il.sample(clusters, "alpha", rate=2.0, seed=0)
    with raises(TypeError, "needs trajectory="):
        il.sample(loops, "one", budget=1, seed=0)
    with raises(TypeError, "metric= needs trajectory="):
        il.sample(clusters, "one", budget=1, seed=0, metric="euclidean")
    with raises(TypeError, "source must be DetectionClusters", "got Detections"):
        il.sample(clusters.detections, "one", budget=1, seed=0)
    other = il.Trajectory([0.0, 1.0], [0.0, 1.0])
    with raises(il.InvalidParameterError, "different trajectories", "2 and 40 poses"):
        il.sample(loops, "one", budget=1, seed=0, trajectory=other)
    with raises(il.InvalidParameterError, "detection 0 at 3", "outside"):
        il.sample(clusters, "one", budget=1, seed=0, trajectory=other)
    with raises(il.InvalidParameterError, "threads = 0"):
        il.sample(loops, "one", budget=1, seed=0, trajectory=traj, threads=0)
    baselines = {
        "lio-sam": {"lio_sam_period_s": -1.0, "lio_sam_min_age_s": np.nan},
        "hdl-graph-slam": {
            "hdl_keyframe_step": -1.0,
            "hdl_min_travel": np.nan,
            "hdl_edge_spacing": -1.0,
        },
        "cartographer": {"cartographer_min_gap_s": -5.0},
        "time-gap": {"time_gap_s": np.nan},
    }
    for sampler, parameters in baselines.items():
        for name, value in parameters.items():
            with raises(il.InvalidParameterError, f"{name} = "):
                il.sample(loops, sampler, budget=1, seed=0, trajectory=traj, **{name: value})
    with raises(il.InvalidParameterError, "skip_trivial does not apply to detection clusters"):
        il.sample(clusters, "rho", budget=1, seed=0, skip_trivial=True)
    with raises(il.InvalidParameterError, "skip_trivial does not apply to the lio-sam baseline"):
        il.sample(loops, "lio-sam", budget=1, seed=0, trajectory=traj, skip_trivial=True)


@covers("DEFAULT_SAMPLER")
def test_the_default_sampler_is_the_cores_everywhere():
    """``sample``, ``sample_fleet`` and the online sampler take the core's default when no
    sampler is named: nearest-then-uniform, whose picks include each component's closest pair."""
    assert il.DEFAULT_SAMPLER == "nearest-then-uniform"
    drive = il.urban_drive(duration_s=1200.0, seed=4)
    found = il.find_loops(drive, gamma=40.0)
    plain = il.sample(found, budget=200, seed=3, trajectory=drive)
    named = il.sample(found, il.DEFAULT_SAMPLER, budget=200, seed=3, trajectory=drive)
    assert plain.sampler == il.DEFAULT_SAMPLER
    assert np.array_equal(plain.i, named.i) and np.array_equal(plain.j, named.j)
    pairs = set(zip(plain.i.tolist(), plain.j.tolist(), strict=True))
    table = found.components
    nontrivial = ~table["trivial"]
    closest = zip(
        table["closest_i"][nontrivial].tolist(),
        table["closest_j"][nontrivial].tolist(),
        strict=True,
    )
    for i, j in closest:
        assert (min(i, j), max(i, j)) in pairs
    fleet = il.urban_fleet(vehicles=2, duration_s=300.0, seed=1)
    fleet_loops = il.find_fleet_loops(fleet, gamma=20.0)
    assert il.sample_fleet(fleet_loops, budget=20, seed=0).sampler == il.DEFAULT_SAMPLER
    assert "closest_in_row=True" in repr(il.OnlineSampler())


def test_sample_skip_trivial_draws_from_the_non_trivial_components_only():
    drive = il.urban_drive(duration_s=1200.0, seed=4)
    found = il.find_loops(drive, gamma=40.0, separation=None)
    table = found.components
    trivial = set(table["id"][table["trivial"]].tolist())
    nontrivial = set(table["id"][~table["trivial"]].tolist())
    assert trivial and len(nontrivial) > 5
    samplers = ["one", "rho", "rho-dispersed", "alpha", "closest-first", "closest-then-spread"]
    for sampler in [*samplers, "nearest-then-uniform"]:
        plain = il.sample(found, sampler, budget=300, seed=3, trajectory=drive)
        only = il.sample(found, sampler, budget=300, seed=3, trajectory=drive, skip_trivial=True)
        assert set(plain.component.tolist()) & trivial, sampler
        assert len(only) == 300 and not set(only.component.tolist()) & trivial, sampler
        if sampler != "alpha":
            assert set(only.component.tolist()) == nontrivial, sampler
        # Every pair is in S_γ, in the component it names (checked by the loops, independently).
        for i, j, c in zip(only.i.tolist(), only.j.tolist(), only.component.tolist(), strict=True):
            assert i < j and found.component_of(i, j) == c


@covers(
    "Samples",
    "Samples.sampler",
    "Samples.groups",
    "Samples.available",
    "Samples.poses",
    "Samples.warnings",
    "Samples.t",
    "Samples.t_prime",
    "Samples.i",
    "Samples.j",
    "Samples.component",
    "Samples.cluster",
    "Samples.detection",
    "Samples.distance",
    "Samples.score",
)
def test_samples_columns(traj, loops, clusters):
    samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
    assert samples.sampler == "one" and samples.groups == 2 and len(samples) == 2
    assert samples.available == (loops.pair_count - N) // 2 and samples.poses == N
    assert samples.warnings == []
    assert sorted(samples.component.tolist()) == [0, 1]
    for k in range(2):
        i, j = samples.i[k], samples.j[k]
        assert samples.t[k] == traj.timestamps[i] and samples.t_prime[k] == traj.timestamps[j]
        assert samples.distance[k] == pytest.approx(
            np.linalg.norm(traj.positions[i] - traj.positions[j])
        )
    assert (
        (samples.cluster == -1).all() and (samples.detection == -1).all() and samples.score is None
    )
    of_clusters = il.sample(clusters, "alpha", rate=1.0, seed=0)
    assert of_clusters.detection.tolist() == [0, 1, 2] and of_clusters.score.tolist() == [
        0.1,
        0.2,
        0.3,
    ]
    assert (
        of_clusters.i is None and np.isnan(of_clusters.distance).all() and of_clusters.poses is None
    )
    with pytest.warns(il.SampleBudgetWarning):
        over = il.sample(loops, "one", budget=1, seed=0, trajectory=traj)
    assert len(over.warnings) == 1 and "budget" in over.warnings[0]


@covers("Samples.locate", "Samples.measure")
def test_samples_locate_measure_and_their_errors(traj, loops, clusters):
    samples = il.sample(clusters, "alpha", rate=1.0, seed=0)
    located = samples.locate(loops)
    assert located.poses == N and (located.component >= -1).all()
    assert located.i.tolist() == [0, 10, 30]
    measured = samples.measure(traj)
    np.testing.assert_allclose(
        measured.distance,
        np.linalg.norm(traj.positions[measured.i] - traj.positions[measured.j], axis=1),
    )
    by_callable = samples.measure(traj, metric=lambda a, b: float(np.abs(a - b).sum()))
    np.testing.assert_allclose(
        by_callable.distance,
        np.abs(traj.positions[measured.i] - traj.positions[measured.j]).sum(axis=1),
    )
    short = il.Trajectory([0.0, 1.0], [0.0, 1.0])
    with raises(il.InvalidParameterError, "detection 0 at 3.5 s", "outside", "[0, 1]"):
        samples.measure(short)
    with raises(il.InvalidParameterError, "detection 0 at 3.5 s", "outside"):
        samples.locate(il.find_loops(short, gamma=1.0, separation=None))
    with raises(il.InvalidParameterError, "so3", "dimension 4", "dimension 2"):
        samples.measure(traj, metric="so3")
    with raises(TypeError, "Loops"):
        samples.locate(traj)
    with pytest.raises(ZeroDivisionError):
        samples.measure(traj, metric=lambda a, b: 1 / 0)


@covers("Samples.to_csv", "Samples.to_json", "Samples.relative_poses")
def test_samples_files_and_their_errors(tmp_path, clusters):
    samples = il.sample(clusters, "alpha", rate=1.0, seed=0)
    csv, js = tmp_path / "s.csv", tmp_path / "s.json"
    samples.to_csv(csv)
    samples.to_json(js)
    lines = csv.read_text().splitlines()
    assert lines[0] == ",".join(
        ["t_s,t_prime_s,i,j,component,cluster,detection,distance,score,sampler"]
        + ["dx,dy,dz,dqx,dqy,dqz,dqw,dtheta_rad"]
        + ["i_x,i_y,i_z,j_x,j_y,j_z"]
    )
    assert len(lines) == 4
    assert np.isnan(samples.relative_poses).all(), "detections not placed: no guess"
    document = json.loads(js.read_text())
    assert document["count"] == 3 and [s["score"] for s in document["samples"]] == [0.1, 0.2, 0.3]
    for write, path in ((samples.to_csv, csv), (samples.to_json, js)):
        with raises(FileExistsError, path.name, "refusing to overwrite"):
            write(path)
        write(path, overwrite=True)
        with raises(FileNotFoundError, "missing"):
            write(tmp_path / "missing" / path.name)


@covers("Loops.components_to_csv", "Loops.loop_duration_to_csv", "Loops.to_json")
def test_loops_files_and_their_errors(tmp_path, traj, loops):
    samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
    components, durations, report = (tmp_path / n for n in ("c.csv", "d.csv", "r.json"))
    per_component = il.sample_quality(samples, loops, epsilon_s=1.0).per_component
    loops.components_to_csv(components, samples_per_component=per_component)
    loops.loop_duration_to_csv(durations, traj)
    loops.to_json(report)
    table = list(csv.DictReader(components.open()))
    assert [int(row["id"]) for row in table] == loops.components["id"].tolist()
    assert [int(row["samples"]) for row in table] == per_component.tolist()
    rows = list(csv.DictReader(durations.open()))
    tau = [float(r["loop_duration_s"]) for r in rows]
    np.testing.assert_array_equal(tau, loops.loop_duration())
    np.testing.assert_array_equal([float(r["x"]) for r in rows], traj.positions[:, 0])
    assert {r["z"] for r in rows} == {"0"}  # a 2-D trajectory
    document = json.loads(report.read_text())
    assert document["source"] is None and document["poses"] == len(traj)
    assert [c["id"] for c in document["components"]] == loops.components["id"].tolist()
    writes = (
        (lambda path, **kw: loops.components_to_csv(path, **kw), components),
        (lambda path, **kw: loops.loop_duration_to_csv(path, traj, **kw), durations),
        (lambda path, **kw: loops.to_json(path, **kw), report),
    )
    for write, path in writes:
        with raises(FileExistsError, path.name, "refusing to overwrite"):
            write(path)
        write(path, overwrite=True)
        with raises(FileNotFoundError, "missing"):
            write(tmp_path / "missing" / path.name)
    shorter = il.Trajectory(traj.timestamps[:-1], traj.positions[:-1])
    with raises(il.InvalidParameterError, "different trajectories"):
        loops.loop_duration_to_csv(tmp_path / "other.csv", shorter)
    with raises(ValueError, "one count each"):
        loops.components_to_csv(tmp_path / "other.csv", samples_per_component=per_component[:-1])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.csv", "d.csv", "r.json"]


@covers(
    "sample_quality",
    "SampleQuality",
    "SampleQuality.samples",
    "SampleQuality.outside",
    "SampleQuality.components",
    "SampleQuality.covered",
    "SampleQuality.nontrivial_components",
    "SampleQuality.nontrivial_covered",
    "SampleQuality.coverage",
    "SampleQuality.missed",
    "SampleQuality.epsilon_s",
    "SampleQuality.redundant",
    "SampleQuality.redundancy",
    "SampleQuality.median_spacing_s",
    "SampleQuality.p3_slope",
    "SampleQuality.p3_components",
    "SampleQuality.per_component",
    "SampleQuality.sample_components",
    "SampleQuality.nearest_spacing_s",
)
def test_sample_quality_and_its_errors(traj, loops):
    i, j = np.array([3, 4, 0, 1]), np.array([4, 5, N - 1, N // 2])  # two in the diagonal, one far
    samples = il.sample(
        il.cluster_detections(il.Detections.from_indices(traj, i, j), epsilon_s=1.0),
        "alpha", rate=1.0, seed=0, trajectory=traj,
    )  # fmt: skip
    q = il.sample_quality(samples, loops, epsilon_s=0.5)
    components = [loops.component_of(a, b) for a, b in zip(samples.i, samples.j, strict=True)]
    assert q.samples == 4 and q.outside == components.count(None) == 1
    assert q.components == 2 and q.covered == 2 and q.coverage == 1.0
    assert q.nontrivial_components == 1 and q.nontrivial_covered == 1
    assert q.missed.num_rows == 0
    assert q.sample_components.tolist() == [-1 if c is None else c for c in components]
    assert q.per_component.tolist() == [2, 1]
    spacing = np.hypot(0.1, 0.1)  # the two diagonal samples, (0.3, 0.4) and (0.4, 0.5)
    assert q.epsilon_s == 0.5 and q.redundant == 2 and q.redundancy == 0.5
    assert q.median_spacing_s == pytest.approx(spacing)
    np.testing.assert_allclose(q.nearest_spacing_s[[2, 3]], spacing)  # in (t, t') order
    assert np.isnan(q.nearest_spacing_s[:2]).all()  # alone in its component; outside S_gamma
    assert q.p3_components == 2 and q.p3_slope is not None
    assert il.sample_quality(samples, loops).epsilon_s == 30.0
    with raises(il.InvalidParameterError, "epsilon_s = 0"):
        il.sample_quality(samples, loops, epsilon_s=0.0)
    with raises(il.InvalidParameterError, "epsilon_s = -inf"):
        il.sample_quality(samples, loops, epsilon_s=-np.inf)
    other = il.find_loops(il.urban_drive(duration_s=60.0), gamma=10.0, separation=None)
    with raises(il.InvalidParameterError, "different trajectories"):
        il.sample_quality(samples, other)
    with raises(TypeError, "Samples"):
        il.sample_quality(loops, loops)


# --- metrics --------------------------------------------------------------------------------------


@covers(*(f"metrics.{name}" for name in metrics.__all__), "metrics", "metrics.Metric.spec")
def test_metric_objects_and_their_errors():
    specs = {
        metrics.Euclidean(): "euclidean",
        metrics.SO3(rotation="chordal"): "so3(rotation=chordal)",
        metrics.SE3(rotation_weight_m_per_rad=2.5): "se3(rotation_weight_m_per_rad=2.5)",
        metrics.SE3Rotation(): "se3_rotation",
        metrics.SE2(rotation_weight_m_per_rad=1.0): "se2(rotation_weight_m_per_rad=1.0)",
        metrics.Torus(): "torus",
        metrics.Sphere(radius=2.0): "sphere(radius=2.0)",
        metrics.Haversine(): "haversine",
        metrics.Angular(): "angular",
    }
    assert {type(m).__name__ for m in specs} | {"Metric"} == set(metrics.__all__)
    for metric, spec in specs.items():
        assert metric.spec == str(metric) == spec
        assert isinstance(metric, metrics.Metric)
    t = np.arange(N) * 0.1
    points = {
        "so3": il.Trajectory.so3(t, QUATERNIONS.as_quat()),
        "se3": il.Trajectory.se3(t, np.zeros((N, 3)), QUATERNIONS.as_quat()),
        "se2": il.Trajectory.se2(t, np.c_[np.zeros((N, 2)), np.linspace(0, 3, N)]),
        "torus": il.Trajectory.torus(t, np.linspace(0, 3, N)),
        "sphere": il.Trajectory.sphere_from_lat_lon(t, np.c_[np.linspace(0, 30, N), np.zeros(N)]),
        "haversine": il.Trajectory.gnss(t, np.c_[np.linspace(0, 0.01, N), np.zeros((N, 2))]),
        "angular": il.Trajectory.descriptors(t, np.c_[np.ones(N), np.linspace(0, 1, N)]),
        "euclidean": il.Trajectory(*ring()),
    }
    for metric in specs:
        traj = points[metric.spec.split("(")[0].removesuffix("_rotation")]
        assert il.find_loops(
            traj, gamma=0.5, metric=metric, separation=None
        ).metric_name.startswith(metric.spec.split("(")[0])
    with pytest.raises(TypeError, match="rotation_weight_m_per_rad"):
        metrics.SE3()  # type: ignore[call-arg]
    with raises(il.InvalidParameterError, '"nope"', "geodesic", "chordal"):
        il.find_loops(
            points["so3"], gamma=0.5, metric=metrics.SO3(rotation="nope"), separation=None
        )  # type: ignore[arg-type]
    with raises(il.InvalidParameterError, "sphere(radius=-1.0)", "radius"):
        il.find_loops(
            points["sphere"], gamma=0.5, metric=metrics.Sphere(radius=-1.0), separation=None
        )


# --- the list -------------------------------------------------------------------------------------


def test_every_public_name_is_covered():
    public = public_names()
    missing = sorted(public - set(COVERED) - set(ELSEWHERE))
    assert not missing, f"public names without a test: {missing}"
    stale = sorted((set(COVERED) | set(ELSEWHERE)) - public)
    assert not stale, f"tests for names that are not public: {stale}"
    for name, (file, test) in ELSEWHERE.items():
        assert f"def {test}(" in (TESTS.parent / file).read_text(), (name, file, test)


@covers("DEFAULT_BUDGET", "SAMPLER_NAMES", "BASELINE_NAMES")
def test_sampler_names_and_default_budget_come_from_the_core(loops_cli):
    from inexact_loops.dask import _cli as dask_cli

    traj = il.urban_drive(duration_s=300.0, seed=3)
    loops = il.find_loops(traj, gamma=40.0)
    assert set(il.SAMPLER_NAMES).isdisjoint(il.BASELINE_NAMES)
    for name in il.SAMPLER_NAMES + il.BASELINE_NAMES:
        il.sample(loops, name, budget=5, seed=0, trajectory=traj)
    with pytest.raises(il.errors.LoopsError) as refused:
        il.sample(loops, "no-such-sampler", budget=5, seed=0)
    listed = re.findall(r"[a-z][a-z-]+", str(refused.value).split("expected", 1)[-1])
    assert set(il.SAMPLER_NAMES + il.BASELINE_NAMES) <= set(listed), str(refused.value)
    assert il.DEFAULT_SAMPLER in il.SAMPLER_NAMES

    # loops-dask's help lists the samplers that draw from tiles, with the core's default budget.
    helps = {a.dest: a.help for a in dask_cli._parser()._actions}
    assert all(name in helps["sampler"] for name in il.SAMPLER_NAMES)
    assert not any(name in helps["sampler"] for name in il.BASELINE_NAMES)
    assert f"default: {il.DEFAULT_BUDGET} " in helps["budget"]

    # The command line draws DEFAULT_BUDGET samples when given neither a rate nor a budget.
    cli = subprocess.run(
        [loops_cli, "sample", "--help"], capture_output=True, text=True, check=True
    )
    assert f"[default: {il.DEFAULT_BUDGET}" in " ".join(cli.stdout.split()), cli.stdout


def test_the_tile_plumbing_is_reached_through_its_submodule():
    """The tiles' plan, scan, merge and draw are :mod:`inexact_loops.tiles`'s, not the
    package's: the package keeps what a user calls."""
    assert tiles.__all__ and set(tiles.__all__).isdisjoint(il.__all__)
    for name in tiles.__all__:
        assert not hasattr(il, name), name
        assert getattr(tiles, name) is getattr(il._core, name), name
    assert il.tiles is tiles


@covers("viewers.serve", "viewers.LiveServer", "viewers.LiveServer.port")
@covers("viewers.LiveServer.close", "viewers.LiveServer.closed")
def test_live_server_errors_name_the_address_and_closing_frees_the_port():
    """The loopback test of the messages is in test_viewers_live.py; here, its errors."""
    import socket

    with raises(ValueError, "not-an-address", "HOST:PORT"):
        viewers.serve("not-an-address")
    server = viewers.serve("127.0.0.1:0", name="drive")
    assert not server.closed and server.address == f"127.0.0.1:{server.port}"
    assert "serving" in repr(server)
    with raises(OSError, f"127.0.0.1:{server.port}"):
        viewers.serve(server.address)  # the port is taken
    socket.create_connection(("127.0.0.1", server.port), timeout=5).close()
    online = il.OnlineLoops(gamma=1.0, dim=1)
    first = online.push(0.0, 0.0)
    server.send(online, first)  # one pose draws nothing
    with raises(ValueError, "timeout_s = -1"):
        server.wait_for_client(timeout_s=-1.0)
    assert server.wait_for_client(timeout_s=0.0) is False  # no client
    server.close()
    server.close()  # twice: nothing
    assert server.closed and "closed" in repr(server)
    with raises(ValueError, "closed"):
        server.send(online, online.push(1.0, 0.5))
    assert refuses_connections(server.port)
    with viewers.serve() as held:
        port = held.port
    assert held.closed
    assert refuses_connections(port)


def refuses_connections(port: int, within_s: float = 5.0) -> bool:
    """Whether a connection to ``port`` on loopback is refused, now or within ``within_s``: the
    server's listener closes on its own runtime, which a loaded machine may run a moment late."""
    import socket

    deadline = time.monotonic() + within_s
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=5).close()
        except OSError:
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
