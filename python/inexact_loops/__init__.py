"""Find, measure and sample inexact loops in robot trajectories.

An *inexact loop* is a pair of times (t, t') at which a trajectory comes back within a distance
gamma of itself. :func:`find_loops` finds all of them exactly and groups them into *loop
components* (connected components in the time x time plane); :class:`Loops` measures loop
duration, loop area and loop density over them.

By default only *revisits* count: pairs at least 4 gamma apart along the path
(:class:`Separation`), the pairs a SLAM back end wants to match. ``separation=None`` gives the
paper's S_gamma, whose trivial components hold the pairs that odometry already ties together.

Example:
    >>> import inexact_loops as il
    >>> traj = il.urban_drive(duration_s=600.0, seed=7)
    >>> loops = il.find_loops(traj, gamma=40.0)
    >>> loops.separation
    Separation(path=160.0, time_s=0.0)
    >>> bool(loops.components["trivial"].any())
    False
    >>> paper = il.find_loops(traj, gamma=40.0, separation=None)
    >>> bool(paper.components["trivial"][0]), paper.pair_count > loops.pair_count
    (True, True)
    >>> tau = loops.loop_duration()
    >>> tau.shape == (len(traj),)
    True

Several sessions (vehicles, days, robots) in one frame form a :class:`Fleet`;
:func:`find_fleet_loops` finds the loops within each session and between every two, and
:meth:`FleetLoops.overlap_matrix` says how much each two sessions overlap. For fleets beyond one
machine, :func:`inexact_loops.dask.find_fleet_loops_dask` gives the same answer from tiles
scanned on a Dask cluster; :mod:`inexact_loops.tiles` holds the tiles' plumbing (plan, scan,
merge, draw) for a scheduler of one's own.

While the robot drives, :class:`OnlineLoops` keeps the loop components up to date pose by pose
and :class:`OnlineSampler` picks loop-closure candidates at each keyframe.
"""

from . import metrics
from . import tiles as tiles  # a submodule of its own, not in __all__ (like dask)
from ._core import (
    BASELINE_NAMES,
    DEFAULT_BUDGET,
    DEFAULT_SAMPLER,
    SAMPLER_NAMES,
    Candidate,
    DetectionClusters,
    Detections,
    Fleet,
    FleetLoops,
    FleetSamples,
    FleetStore,
    Loops,
    OnlineLoops,
    OnlineSampler,
    PlaneGrid,
    PoseGraph,
    SampleQuality,
    Samples,
    Separation,
    StoreUpdatePlan,
    TiledFleetLoops,
    Trajectory,
    Update,
    __version__,
    chain_polylines,
    cluster_detections,
    component_outlines,
    distance_image,
    draw_detections,
    find_fleet_loops,
    find_loops,
    isocontour,
    list_topics,
    outline_segments,
    path_length,
    read_detections,
    read_pose_graph,
    read_trajectory,
    sample,
    sample_fleet,
    sample_quality,
    sampler_symbol,
    urban_drive,
    urban_fleet,
)
from .errors import (
    DeadReckoningWarning,
    DiagonalBrokenWarning,
    DroppedInputWarning,
    EmptyResultWarning,
    EmptySampleWarning,
    InternalError,
    InvalidParameterError,
    InvalidTrajectoryError,
    LoopsError,
    LoopsIOError,
    LoopsWarning,
    NoLoopsWarning,
    OutOfMemoryError,
    SampleBudgetWarning,
)
from .table import Table

__all__ = [
    "Candidate",
    "DeadReckoningWarning",
    "DetectionClusters",
    "Detections",
    "DiagonalBrokenWarning",
    "DroppedInputWarning",
    "EmptyResultWarning",
    "EmptySampleWarning",
    "Fleet",
    "FleetLoops",
    "FleetStore",
    "StoreUpdatePlan",
    "FleetSamples",
    "InternalError",
    "InvalidParameterError",
    "InvalidTrajectoryError",
    "Loops",
    "LoopsError",
    "LoopsIOError",
    "LoopsWarning",
    "NoLoopsWarning",
    "OnlineLoops",
    "OnlineSampler",
    "OutOfMemoryError",
    "PlaneGrid",
    "PoseGraph",
    "SampleBudgetWarning",
    "SampleQuality",
    "Samples",
    "Separation",
    "Table",
    "TiledFleetLoops",
    "Trajectory",
    "Update",
    "BASELINE_NAMES",
    "DEFAULT_BUDGET",
    "DEFAULT_SAMPLER",
    "SAMPLER_NAMES",
    "__version__",
    "chain_polylines",
    "cluster_detections",
    "component_outlines",
    "distance_image",
    "draw_detections",
    "find_fleet_loops",
    "find_loops",
    "isocontour",
    "list_topics",
    "metrics",
    "outline_segments",
    "path_length",
    "read_detections",
    "read_pose_graph",
    "read_trajectory",
    "sample",
    "sample_fleet",
    "sample_quality",
    "sampler_symbol",
    "urban_drive",
    "urban_fleet",
]


def __getattr__(name: str) -> object:
    """``inexact_loops.plot``, ``inexact_loops.evaluate`` and ``inexact_loops.viewers`` on first
    use: matplotlib is imported only when plots are drawn (the optional extra
    ``inexact-loops[plot]``), GTSAM only when a pose graph is optimised (``inexact-loops[maps]``),
    rerun-sdk only when a recording is written (``inexact-loops[rerun]``)."""
    if name in ("plot", "evaluate", "viewers"):
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), "plot", "evaluate", "viewers"])
