"""Type stubs of the compiled module ``inexact_loops._core``.

The docstrings are the bindings', copied by ``python tests/stubs.py`` (``make stubs``): edit
them in ``crates/loops-py``, not here.
"""

from collections.abc import Callable
from os import PathLike
from pathlib import Path
from typing import Any, ClassVar, Literal, Protocol, final

import numpy as np
import numpy.typing as npt
import pandas  # type: ignore[import-untyped, import-not-found, unused-ignore]

from .table import Table

__all__ = [
    "list_topics",
    "Separation",
    "path_length",
    "DetectionClusters",
    "Detections",
    "Loops",
    "PlaneGrid",
    "PoseGraph",
    "SampleQuality",
    "Samples",
    "Trajectory",
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
    "find_loops",
    "isocontour",
    "outline_segments",
    "read_detections",
    "read_pose_graph",
    "read_trajectory",
    "run_cli",
    "sample",
    "sample_quality",
    "sampler_symbol",
    "urban_drive",
    "Fleet",
    "FleetLoops",
    "FleetStore",
    "StoreUpdatePlan",
    "FleetSamples",
    "find_fleet_loops",
    "sample_fleet",
    "urban_fleet",
    "SessionBlocks",
    "Tile",
    "TileMerge",
    "TileRuns",
    "TileSummary",
    "TiledFleetLoops",
    "merge_tiles",
    "plan_tiles",
    "scan_tile",
    "scan_tiles",
    "session_blocks",
    "OnlineLoops",
    "Update",
    "OnlineSampler",
    "Candidate",
    "KeyedDraw",
    "TileDrawRequest",
    "DrawCandidates",
    "TileDuration",
    "draw_tile",
    "session_loop_duration",
    "log_name",
    "OutDir",
    "refuse_output_on_input",
    "write_file",
    "Scene",
    "scene",
    "LiveServer",
]

__version__: str
DEFAULT_SAMPLER: str
#: The budget the command line and Dask draw with when neither a rate nor a budget is given.
DEFAULT_BUDGET: int
#: The names of the samplers that draw from loop components (the paper's and the project's).
SAMPLER_NAMES: tuple[str, ...]
#: The names of the baseline rules (LIO-SAM's, hdl_graph_slam's, Cartographer's, a time gap),
#: which draw from whole trajectories.
BASELINE_NAMES: tuple[str, ...]

_Side = Literal["both", "begin", "end"]
_SamplerName = Literal[
    "one",
    "rho",
    "rho-dispersed",
    "alpha",
    "closest-first",
    "closest-then-spread",
    "nearest-then-uniform",
    "lio-sam",
    "hdl-graph-slam",
    "cartographer",
    "time-gap",
]
_Manifold = Literal["euclidean", "se3", "so3", "se2", "torus", "sphere", "gnss", "descriptors"]

class _MetricLike(Protocol):
    @property
    def spec(self) -> str: ...

class _EvoTrajectory(Protocol):
    """What :meth:`Trajectory.from_evo` reads: evo's ``PoseTrajectory3D`` attributes."""

    @property
    def timestamps(self) -> npt.ArrayLike: ...
    @property
    def positions_xyz(self) -> npt.ArrayLike: ...
    @property
    def orientations_quat_wxyz(self) -> npt.ArrayLike: ...

_MetricArg = (
    str | _MetricLike | Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], float] | None
)

@final
class Trajectory:
    """A sampled trajectory: strictly increasing timestamps (seconds) and one point per timestamp.

    A trajectory knows its manifold (:attr:`manifold`): built here, its points are Rⁿ positions,
    measured by the Euclidean metric; built by :meth:`se3`, :meth:`so3`, :meth:`se2`,
    :meth:`torus`, :meth:`sphere`, :meth:`gnss` or :meth:`descriptors`, they are measured by that
    manifold's metric (:attr:`metric_name`) wherever no ``metric=`` is given, and a metric that does
    not fit them raises, naming both.

    Args:
        timestamps: shape ``(n,)``, seconds, strictly increasing, finite.
        positions: shape ``(n, d)`` (or ``(n,)`` for d = 1), finite; any real dtype and any memory
            order (C, Fortran, strided) is read correctly.

    Raises:
        InvalidTrajectoryError: NaN or infinite values, unsorted or duplicate timestamps, fewer
            than 2 poses; the message names the first bad index.
        ValueError: wrong shapes. TypeError: non-numeric dtypes.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> traj = il.Trajectory(np.array([0.0, 1.0, 3.0]), np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
        >>> len(traj), traj.dim
        (3, 2)
        >>> traj.cell_widths
        array([0.5, 1.5, 1. ])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], Trajectory], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Trajectory: ...
    def __new__(cls, timestamps: npt.ArrayLike, positions: npt.ArrayLike) -> Trajectory: ...
    def __len__(self) -> int: ...
    @property
    def dim(self) -> int:
        """Coordinates per point."""
    @property
    def plane_axes(self) -> tuple[int, int] | None:
        """The plane a trajectory was read on: the position axes of its source (0 = x, 1 = y,
        2 = z) that its first two coordinates are, as given to :func:`read_trajectory` or
        :meth:`from_evo` with ``axes=`` (Euclidean: the plane's two coordinates; ``se2``: those
        and the heading in the plane); ``None`` for every other trajectory, whose coordinates are
        its own. The maps of :mod:`inexact_loops.plot` draw and label this plane.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> il.Trajectory(np.arange(3.0), np.zeros((3, 2))).plane_axes is None
            True
        """
    @property
    def manifold(self) -> _Manifold:
        """The manifold of the points, as its constructor built them: ``"euclidean"`` (this class's
        constructor, :meth:`gnss_ecef`, unnormalised :meth:`descriptors`), ``"se3"``, ``"so3"``,
        ``"se2"``, ``"torus"``, ``"sphere"``, ``"gnss"`` or ``"descriptors"``.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> q = np.tile([0, 0, 0, 1.0], (2, 1))
            >>> il.Trajectory.se3(np.array([0.0, 1.0]), np.zeros((2, 3)), q).manifold
            'se3'
        """
    @property
    def metric_name(self) -> str:
        """The name of the metric :func:`find_loops`, :func:`sample`, :func:`distance_image` and
        :meth:`Samples.measure` use when no ``metric=`` is given (as :attr:`Loops.metric_name`
        names the one the loops were found with): the one the trajectory was read
        or converted for (:func:`read_trajectory` and :meth:`from_evo` with ``metric=``), or else
        its manifold's — ``euclidean``; ``se3(rotation_weight_m_per_rad=0, rotation=geodesic)``
        and ``se2(rotation_weight_m_per_rad=0)`` (the translation, metres: a radian's weight has
        no universal value, so rotation counts only when asked for); ``so3(rotation=geodesic)``;
        ``torus``; ``sphere(radius=1)``; ``haversine(radius_m=6371008.8)`` for :meth:`gnss`;
        ``angular`` for normalised :meth:`descriptors`.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> il.Trajectory.so3_from_rotation_vectors(np.arange(2.0), np.zeros((2, 3))).metric_name
            'so3(rotation=geodesic)'
        """
    @property
    def timestamps(self) -> npt.NDArray[np.float64]:
        """Timestamps, seconds, shape ``(n,)`` (a copy)."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Points, shape ``(n, d)`` (a copy)."""
    @property
    def cell_widths(self) -> npt.NDArray[np.float64]:
        """Time-cell widths w_i, seconds, shape ``(n,)``: sample i stands for the cell between the
        midpoints to its neighbours (half cells at the ends); they sum to ``span_s``.
        """
    @property
    def span_s(self) -> float:
        """Last minus first timestamp, seconds."""
    def nearest_poses(self, times_s: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """The pose nearest each time: the pose whose time cell holds it, ties to the earlier pose.

        Args:
            times_s: times, seconds on the clock of the timestamps, shape ``(m,)``.

        Returns:
            int64 pose indices, shape ``(m,)``.

        Raises:
            InvalidParameterError: a time outside the trajectory's time span (or NaN), naming it.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.array([0.0, 1.0, 3.0]), np.zeros(3))
            >>> traj.nearest_poses([0.4, 0.5, 2.1, 3.0]).tolist()
            [0, 0, 2, 2]
        """
    @staticmethod
    def se3(
        timestamps: npt.ArrayLike,
        positions: npt.ArrayLike,
        quaternions_xyzw: npt.ArrayLike,
        *,
        quaternion_tolerance: float | None = None,
    ) -> Trajectory:
        """SE(3) poses, for the ``se3`` / ``se3_rotation`` metrics: positions ``(n, 3)`` and
        orientations as quaternions ``(n, 4)`` in **x, y, z, w** order (the ROS and
        ``scipy.spatial.transform.Rotation.as_quat()`` order). Quaternions within
        ``quaternion_tolerance`` (default 1e-3, as :func:`read_trajectory`) of unit length are normalised; others (zero
        included) raise, naming the pose: 4-decimal quaternions (TUM files) are accepted.

        Without ``metric=``, the poses are measured by
        ``se3(rotation_weight_m_per_rad=0, rotation=geodesic)``: the distance between the
        positions, metres; pass e.g. ``metric="se3(rotation_weight_m_per_rad=10)"`` to count
        rotation too. The Euclidean metric does not fit them (it would measure quaternion
        components as coordinates) and raises.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> q = np.array([[0, 0, 0, 1.0], [0, 0, 1.0, 0]])
            >>> traj = il.Trajectory.se3(np.array([0.0, 1.0]), np.zeros((2, 3)), q)
            >>> traj.positions.shape
            (2, 7)
        """
    @staticmethod
    def so3(
        timestamps: npt.ArrayLike,
        quaternions_xyzw: npt.ArrayLike,
        *,
        quaternion_tolerance: float | None = None,
    ) -> Trajectory:
        """Rotations, for the ``so3`` metric (their default, geodesic angle in radians): quaternions
        ``(n, 4)`` in x, y, z, w order, normalised as in :meth:`se3`.
        """
    @staticmethod
    def so3_from_rotation_vectors(
        timestamps: npt.ArrayLike, rotation_vectors: npt.ArrayLike
    ) -> Trajectory:
        """Rotations, for the ``so3`` metric (their default), from rotation vectors ``(n, 3)``
        (axis × angle, radians; ``Rotation.as_rotvec()``).
        """
    @staticmethod
    def se2(timestamps: npt.ArrayLike, poses_xy_theta: npt.ArrayLike) -> Trajectory:
        """Planar poses, for the ``se2`` metric: ``(n, 3)`` rows of x, y (metres) and heading θ
        (radians, wrapped to (−π, π]). Without ``metric=`` they are measured by
        ``se2(rotation_weight_m_per_rad=0)``, the distance between the positions.
        """
    @staticmethod
    def torus(timestamps: npt.ArrayLike, angles_rad: npt.ArrayLike) -> Trajectory:
        """Points on a torus S¹ × … × S¹, for the ``torus`` metric (their default): angles
        ``(n, k)`` in radians (wrapped to (−π, π]).
        """
    @staticmethod
    def sphere(timestamps: npt.ArrayLike, vectors: npt.ArrayLike) -> Trajectory:
        """Points on the sphere S², for the ``sphere`` metric (their default is ``sphere(radius=1)``,
        radians; ``angular`` fits too): non-zero vectors ``(n, 3)``, normalised.
        """
    @staticmethod
    def sphere_from_lat_lon(timestamps: npt.ArrayLike, lat_lon_deg: npt.ArrayLike) -> Trajectory:
        """Points on the sphere S², for the ``sphere`` metric (as :meth:`sphere`), from ``(n, 2)``
        latitude and longitude in degrees.
        """
    @staticmethod
    def gnss(timestamps: npt.ArrayLike, lat_lon_height: npt.ArrayLike) -> Trajectory:
        """GNSS fixes, for the ``haversine`` metric (their default, metres): ``(n, 3)`` latitude
        (degrees, within ±90), longitude (degrees) and height (metres). The points are stored as
        ``(n, 4)`` unit direction and height, which no other metric fits.
        """
    @staticmethod
    def gnss_ecef(timestamps: npt.ArrayLike, lat_lon_height: npt.ArrayLike) -> Trajectory:
        """GNSS fixes as WGS 84 Earth-centred positions relative to the first fix, turned into the
        first fix's east-north-up frame (metres east, north and up: plots and reports draw a
        map), for the ``euclidean`` metric; input as in :meth:`gnss`. A rotation of ECEF, so
        distances are the straight-line ones. A Euclidean trajectory (:attr:`manifold`).

        Example:
            >>> import inexact_loops as il
            >>> traj = il.Trajectory.gnss_ecef([0.0, 1.0], [[48.0, 11.0, 500.0], [48.001, 11.0, 500.0]])
            >>> east, north, up = traj.positions[1]  # 111 m north, a little down: the Earth curves
            >>> round(float(north), 1), bool(abs(east) < 1e-6), bool(-0.01 < up < 0)
            (111.2, True, True)
        """
    @staticmethod
    def descriptors(
        timestamps: npt.ArrayLike, descriptors: npt.ArrayLike, *, normalize: bool = True
    ) -> Trajectory:
        """Descriptor vectors (place recognition) ``(n, d)``: normalised to unit length when
        ``normalize`` (manifold ``"descriptors"``, measured by ``angular`` unless ``metric=``
        says ``euclidean``), kept as given otherwise (a Euclidean trajectory). A list of rows of
        unequal length raises ``ValueError`` naming the row.
        """
    @staticmethod
    def from_evo(
        trajectory: _EvoTrajectory,
        *,
        metric: str | _MetricLike | None = None,
        axes: tuple[int, int] | None = None,
    ) -> Trajectory:
        """A trajectory from an `evo <https://github.com/MichaelGrupp/evo>`_ ``PoseTrajectory3D``
        (or any object with its attributes ``timestamps`` ``(n,)`` seconds, ``positions_xyz``
        ``(n, 3)`` and ``orientations_quat_wxyz`` ``(n, 4)``, quaternions **w first**, as evo
        stores them). evo itself is not imported.

        What is built follows ``metric`` exactly as in :func:`read_trajectory`: positions
        (x, y, z) for Euclidean (the default), or the plane ``axes`` of them; positions and
        orientations for ``se3`` / ``se3_rotation`` (as :meth:`se3`); orientations for ``so3``;
        x, y and yaw for ``se2`` (or the plane ``axes`` and the heading in it). Quaternions within
        1e-3 of unit length are normalised.
        The trajectory keeps ``metric`` (:attr:`metric_name`): :func:`find_loops` without
        ``metric=`` measures it so.

        Args:
            trajectory: an ``evo.core.trajectory.PoseTrajectory3D``.
            metric: the metric the trajectory is for, a name or :mod:`inexact_loops.metrics`
                object (as in :func:`find_loops`); ``None`` is Euclidean.
            axes: a plane of two position axes, e.g. ``(0, 2)``: Euclidean keeps only them, ``se2``
                takes them and the heading in that plane, as in :func:`read_trajectory`
                (:attr:`plane_axes`).

        Raises:
            TypeError: ``trajectory`` lacks one of the attributes (the message names them all,
                e.g. ``timestamps`` for an evo ``PosePath3D``), or holds non-numeric values.
            ValueError: arrays of the wrong shape (named by attribute).
            InvalidTrajectoryError: NaN, unsorted timestamps, a quaternion far from unit length,
                naming the pose.
            InvalidParameterError: an unknown metric, or one whose points are not poses.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> from types import SimpleNamespace  # stands in for evo's PoseTrajectory3D here
            >>> evo_traj = SimpleNamespace(
            ...     timestamps=np.array([0.0, 0.1, 0.2]),
            ...     positions_xyz=np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]),
            ...     orientations_quat_wxyz=np.tile([1.0, 0, 0, 0], (3, 1)),
            ... )
            >>> il.Trajectory.from_evo(evo_traj).positions[-1]
            array([2., 0., 0.])
            >>> poses = il.Trajectory.from_evo(evo_traj, metric="se3(rotation_weight_m_per_rad=1)")
            >>> poses.dim, poses.manifold, poses.metric_name
            (7, 'se3', 'se3(rotation_weight_m_per_rad=1, rotation=geodesic)')
        """

@final
class Separation:
    """The minimum separation along the trajectory between the two poses of a loop: a path length
    (the metric's unit, e.g. metres) and a time (seconds); both must hold. With either above 0,
    :func:`find_loops` finds *revisits*: the pairs within γ that odometry does not already tie
    together, and no component is trivial. ``Separation()`` (both 0) is the paper's S_γ.

    Args:
        path: minimum path length between the poses, in the metric's unit (≥ 0).
        time_s: minimum time between the poses, seconds (≥ 0).

    Raises:
        InvalidParameterError: a bound negative or not finite.

    Example:
        >>> import inexact_loops as il
        >>> il.Separation(path=24.0, time_s=30.0)
        Separation(path=24.0, time_s=30.0)
        >>> il.Separation.for_gamma(6.0)
        Separation(path=24.0, time_s=0.0)
    """

    def __reduce__(self) -> tuple[Callable[[bytes], Separation], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Separation: ...
    def __new__(cls, *, path: float = 0.0, time_s: float = 0.0) -> Separation: ...
    @staticmethod
    def for_gamma(gamma: float) -> Separation:
        """The default of :func:`find_loops` (``separation="auto"``) at threshold ``gamma``: a path
        of 4 γ, no time separation; measured on real trajectories (the guide
        "Choose γ and the separation").
        """
    @property
    def path(self) -> float:
        """Minimum path length between the poses, in the metric's unit."""
    @property
    def time_s(self) -> float:
        """Minimum time between the poses, seconds."""
    @property
    def is_none(self) -> bool:
        """Whether both are 0: the paper's S_γ, trivial components included."""
    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]

def path_length(
    trajectory: Trajectory,
    *,
    metric: str | _MetricLike | None = None,
) -> npt.NDArray[np.float64]:
    """The cumulative path length of every pose under ``metric``: s_0 = 0, s_k = s_{k−1} + δ(x_{k−1},
    x_k), in the metric's unit, summed in order (as ``numpy.cumsum`` of the steps). A path
    :class:`Separation` bounds ``s[j] - s[i]``.

    Args:
        trajectory: a :class:`Trajectory`.
        metric: as in :func:`find_loops` (a name or an :mod:`inexact_loops.metrics` object;
            ``None``: the trajectory's own, :attr:`Trajectory.metric_name`).

    Returns:
        numpy.ndarray: float64, one value per pose.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> traj = il.Trajectory(np.arange(3.0), np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 4.0]]))
        >>> il.path_length(traj).tolist()
        [0.0, 5.0, 5.0]
    """

@final
class Loops:
    """The inexact loops of a trajectory at one γ: the sublevel set S_γ as runs, its loop
    components, and the loop duration, area and density over them. Returned by
    :func:`find_loops`.
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(
        self,
    ) -> tuple[Callable[[bytes, bytes | None], Loops], tuple[bytes, bytes | None]]: ...
    @classmethod
    def _from_state(cls, state: bytes, positions: bytes | None = None) -> Loops: ...
    def __len__(self) -> int: ...
    @property
    def gamma(self) -> float:
        """The threshold γ."""
    @property
    def separation(self) -> Separation:
        """The separation the pairs keep (:class:`Separation`; both 0 for the paper's S_γ)."""
    @property
    def metric_name(self) -> str:
        """The name of the metric the loops were found with: its spec (``"euclidean"``,
        ``"se3(rotation_weight_m_per_rad=10, rotation=geodesic)"``), or ``custom(NAME)`` for a
        callable, NAME its ``__name__``.
        """
    @property
    def span_s(self) -> float:
        """Last minus first timestamp, seconds."""
    @property
    def pair_count(self) -> int:
        """Number of lattice cells (i, j) of S_γ in the full plane, both halves and the diagonal."""
    @property
    def pose_pair_count(self) -> int:
        """Number of pose pairs {i, j}, i < j, of S_γ (unordered pairs of distinct poses): the
        count the command line's summaries and reports print, the sum of the components'
        ``pose_pair_count``, and what :func:`sample` draws from.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> loops = il.find_loops(il.Trajectory(np.arange(3.0), np.zeros(3)), gamma=1.0, separation=None)
            >>> loops.pair_count, loops.pose_pair_count
            (9, 3)
        """
    @property
    def warnings(self) -> list[str]:
        """Warnings about the result (e.g. consecutive poses farther apart than γ), as sentences;
        :func:`find_loops` also issues each with :func:`warnings.warn`, in a category of
        :class:`LoopsWarning`.
        """
    @property
    def components(self) -> Table:
        """The loop components as a :class:`~inexact_loops.Table` (a dict of numpy columns, one row
        a component, by id; ``.to_pandas()`` for a DataFrame): ``id`` (int64), ``trivial``
        (bool), ``area_s2`` (float64, s²: the half t ≤ t′ for a non-trivial component, the whole
        set for a trivial one), ``pair_count`` (int64, cells, same rule), ``pose_pair_count`` (int64, pairs
        of distinct poses i < j: they sum to :attr:`pose_pair_count`), ``run_count``, ``holes`` (int64),
        ``i_min``, ``i_max``, ``j_min``, ``j_max`` (int64, index extents), ``t_min_s``, ``t_max_s``,
        ``t_prime_min_s``, ``t_prime_max_s`` (float64, seconds), ``closest_i``, ``closest_j``
        (int64) and ``closest_distance`` (float64, the metric's unit): the columns of
        ``components.csv``, in its order.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
            >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
            >>> table = il.find_loops(traj, gamma=4.0, separation=None).components
            >>> table["id"].dtype, table["trivial"].tolist(), table["i_max"].tolist()
            (dtype('int64'), [True, False], [199, 7])
        """
    def runs(self) -> Table:
        """The runs of S_γ's upper half (j ≥ i), row by row, as a :class:`~inexact_loops.Table` of
        int64 columns: ``row`` i, columns ``start``..=``end`` (inclusive) and ``component`` id.
        For plotting.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> runs = il.find_loops(traj, gamma=0.5, separation=None).runs()
            >>> {name: column.tolist() for name, column in runs.items()}
            {'row': [0, 0, 1, 2, 3], 'start': [0, 3, 1, 2, 3], 'end': [0, 3, 2, 2, 3], 'component': [0, 1, 2, 2, 3]}
        """
    def component_of(self, i: int, j: int) -> int | None:
        """The component id of the pair (i, j) (either order), or ``None`` when δ > γ or, with a
        separation, when the pair is not that far apart along the trajectory.

        Raises:
            IndexError: ``i`` or ``j`` is not a pose index (negative, or past the last pose).

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
            >>> loops.component_of(3, 0), loops.component_of(0, 1)
            (1, None)
        """
    def is_simple(self, i: int, j: int) -> bool:
        """Whether (i, j) is a simple loop: a pair in a trivial component.

        Raises:
            IndexError: ``i`` or ``j`` is not a pose index (negative, or past the last pose).

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
            >>> loops.is_simple(1, 2), loops.is_simple(0, 3)
            (True, False)
        """
    def label_image(self, grid: PlaneGrid) -> npt.NDArray[np.int64]:
        """The loop component of every pixel of ``grid``: the component holding the pair (column
        pose, row pose), either order (so the image is mirrored across the diagonal), −1
        outside S_γ. The same pixels as :func:`distance_image`: −1 exactly where δ > γ. With a
        grid of every pose it is the lattice of the components itself; when the grid downsamples,
        a component smaller than a pixel may hold no pixel's pair (mark it at its closest pair).

        Args:
            grid: a :class:`PlaneGrid` made for these loops (or their trajectory).

        Returns:
            int64 array, shape ``(grid.height, grid.width)``, row 0 the earliest t′.

        Raises:
            InvalidParameterError: a grid made for another number of poses.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 5.0, 5.0, 0.0]))  # out and back
            >>> loops = il.find_loops(traj, gamma=1.0, separation=None)
            >>> loops.label_image(il.PlaneGrid(loops, 10)).tolist()
            [[0, -1, -1, 1], [-1, 2, 2, -1], [-1, 2, 2, -1], [1, -1, -1, 3]]
        """
    def components_of_pairs(self, i: npt.ArrayLike, j: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """The component id of each pair ``(i[k], j[k])`` (either order), −1 outside S_γ: what
        :meth:`component_of` gives, for many pairs at once (a binary search over the runs each).

        Args:
            i, j: integer pose indices, shape ``(m,)``.

        Returns:
            int64 array, shape ``(m,)``.

        Raises:
            IndexError: a pose index past the last pose (or negative).
            ValueError: ``i`` and ``j`` of different lengths.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
            >>> loops.components_of_pairs([3, 0, 0], [0, 3, 1]).tolist()
            [1, 1, -1]
        """
    def pair_counts_per_component(
        self, i: npt.ArrayLike, j: npt.ArrayLike
    ) -> npt.NDArray[np.int64]:
        """How many of the pairs ``(i[k], j[k])`` each component holds, by component id (pairs
        outside S_γ are not counted).

        Args:
            i, j: as :meth:`components_of_pairs`.

        Returns:
            int64 array, shape ``(number of components,)``.

        Raises:
            As :meth:`components_of_pairs`.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
            >>> loops.pair_counts_per_component([3, 0, 0, 1], [0, 3, 1, 2]).tolist()
            [0, 2, 1, 0]
        """
    def pair_verdicts(
        self,
        i: npt.ArrayLike,
        j: npt.ArrayLike,
        trajectory: Trajectory,
        *,
        metric: str
        | _MetricLike
        | Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], float]
        | None = None,
    ) -> Table:
        """Where each pair ``(i[k], j[k])`` (either order) falls, with δ: in a loop component, in a
        trivial one, within γ but not a revisit, or outside S_γ — for the loop-closure edges of a
        pose graph (:meth:`PoseGraph.edge_verdicts`), the detections of a place recognizer, any
        pairs.

        The verdicts (column ``verdict``):

        - ``"component"``: in a non-trivial loop component (``component`` its id): a revisit;
        - ``"trivial"``: in a trivial component, a simple loop (only with ``separation=None``);
        - ``"not-separated"``: δ ≤ γ, but the two poses are closer along the trajectory than the
          loops' :class:`Separation` (path length or time, checked as the engine checks it): not
          a revisit, in no component (only with a separation);
        - ``"outside"``: δ > γ, outside S_γ.

        Args:
            i, j: integer pose indices, shape ``(m,)``.
            trajectory: the :class:`Trajectory` the loops were found on.
            metric: the metric they were found with; ``None`` takes it from the loops (pass the
                same callable for loops found with one).

        Returns:
            :class:`~inexact_loops.Table`: ``i``, ``j`` (int64, as given), ``distance``
            (float64, δ in the metric's unit), ``verdict`` (str) and ``component`` (int64, −1 in
            none).

        Raises:
            IndexError: a pose index past the last pose (or negative).
            ValueError: ``i`` and ``j`` of different lengths.
            InvalidParameterError: another trajectory, or another metric, than the loops'.

        Example:
            Out along a line and back: the way back revisits the way out, 3 m of path later.

            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(7.0), np.array([0.0, 1, 2, 3, 2, 1, 0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=il.Separation(path=3.0))
            >>> table = loops.pair_verdicts([0, 2, 0], [6, 4, 3], traj)
            >>> table["verdict"].tolist(), table["component"].tolist(), table["distance"].tolist()
            (['component', 'not-separated', 'outside'], [0, -1, -1], [0.0, 0.0, 3.0])
        """
    def loop_duration(
        self,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> npt.NDArray[np.float64]:
        """Loop duration τ(t_i) for every sample: how long the trajectory stays within γ of
        ξ(t_i) (paper, Eq. 6).

        Args:
            components: component ids to restrict to; ``None`` is all of S_γ.
            side: ``"both"`` (every t′), ``"begin"`` (t′ > t) or ``"end"`` (t′ < t).
            normalized: fractions of the span instead of seconds.

        Returns:
            numpy array, shape ``(n,)``.
        """
    def loop_area(
        self,
        a: float,
        b: float,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> float:
        """Loop area α(a, b) = ∫_a^b τ(t) dt (paper, Eq. 7), s² (or normalized units, where a and
        b are fractions of the span).

        Args: as :meth:`loop_duration`, plus the interval ``a < b`` (seconds, same clock as the
        timestamps).
        """
    def loop_density(
        self,
        a: float,
        b: float,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> float:
        """Loop density ρ(a, b) = α(a, b) / (b − a) (paper, Eq. 8): the mean loop duration over
        [a, b], seconds (or normalized).
        """
    def components_to_csv(
        self,
        path: str | PathLike[str],
        *,
        samples_per_component: npt.ArrayLike | None = None,
        overwrite: bool = False,
    ) -> None:
        """Writes ``components.csv``, the file ``loops run`` writes: one row per component, by id,
        with the columns of :attr:`components` (``id, trivial, area_s2, pair_count, pose_pair_count,
        run_count, holes, i_min, i_max, j_min, j_max, t_min_s, t_max_s, t_prime_min_s, t_prime_max_s,
        closest_i, closest_j, closest_distance``) and, with ``samples_per_component``, a last
        column ``samples``. Numbers are printed in the shortest form that reads back as the same
        float. Atomic (a temporary file renamed into place).

        Args:
            path: the file.
            samples_per_component: samples per component, by id: one count per component, as
                ``sample_quality(samples, loops).per_component``.
            overwrite: replace an existing file.

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.
            ValueError: ``samples_per_component`` does not hold one count per component.

        Example:
            >>> import os, tempfile, numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> path = os.path.join(tempfile.mkdtemp(), "components.csv")
            >>> il.find_loops(traj, gamma=0.5, separation=None).components_to_csv(path)
            >>> open(path).read().splitlines()[2]
            '1,false,0.25,1,1,1,0,0,0,3,3,0,0,3,3,0,3,0,0,0,0,0,0,0'
        """
    def loop_duration_to_csv(
        self,
        path: str | PathLike[str],
        trajectory: Trajectory,
        *,
        overwrite: bool = False,
    ) -> None:
        """Writes ``loop_duration.csv``, the file ``loops run`` writes: one row per pose, ``index,
        t_s, x, y, z, loop_duration_s`` (τ of :meth:`loop_duration`, seconds). ``x, y, z`` are
        the trajectory's first three coordinates (0 for those it lacks): its positions for a
        trajectory of positions or of SE(3) poses, the chart's first coordinates otherwise.
        Atomic, as :meth:`components_to_csv`.

        Args:
            path: the file.
            trajectory: the :class:`Trajectory` these loops were found on.
            overwrite: replace an existing file.

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.
            InvalidParameterError: ``trajectory`` is not the one of these loops (other timestamps).

        Example:
            >>> import os, tempfile, numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> path = os.path.join(tempfile.mkdtemp(), "loop_duration.csv")
            >>> il.find_loops(traj, gamma=0.5, separation=None).loop_duration_to_csv(path, traj)
            >>> open(path).read().splitlines()[:2]
            ['index,t_s,x,y,z,loop_duration_s', '0,0,0,0,0,1']
        """
    def to_json(
        self,
        path: str | PathLike[str],
        *,
        source: str | None = None,
        overwrite: bool = False,
    ) -> None:
        """Writes the loops as the JSON report of ``loops components --json``: ``source``,
        ``poses``, ``span_s``, ``gamma``, ``metric``, ``pair_count``, ``loop_density_s``,
        ``warnings`` and ``components`` (a list of objects with ``id``, ``trivial``,
        ``area_s2``, ``pair_count``, ``run_count``, ``holes``, ``t_range_s``,
        ``t_prime_range_s``, ``i_range``, ``j_range``, ``closest_pair``, ``closest_distance``;
        ranges as ``[first, last]``). Atomic, as :meth:`components_to_csv`.

        Args:
            path: the file.
            source: where the trajectory came from (a file name), or ``None`` (``null``).
            overwrite: replace an existing file.

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.

        Example:
            >>> import json, os, tempfile, numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> path = os.path.join(tempfile.mkdtemp(), "loops.json")
            >>> il.find_loops(traj, gamma=0.5, separation=None).to_json(path, source="line.csv")
            >>> report = json.load(open(path))
            >>> report["source"], report["poses"], report["components"][1]["i_range"]
            ('line.csv', 4, [0, 0])
        """

def find_loops(
    trajectory: Trajectory,
    *,
    gamma: float,
    metric: str
    | _MetricLike
    | Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], float]
    | None = None,
    separation: Separation | float | Literal["auto", "none"] | None = "auto",
    threads: int | None = None,
) -> Loops:
    """Finds every inexact loop of ``trajectory`` at threshold ``gamma`` exactly (every pair
    (t, t′) with δ ≤ γ, nothing subsampled) and partitions them into loop components.

    By default only *revisits* count: pairs at least ``Separation.for_gamma(gamma)`` (4 γ) apart
    along the path, the pairs a SLAM back end wants to match; pairs that odometry already ties
    together are left out, and no component is trivial. ``separation=None`` gives the paper's
    S_γ, with its trivial components and simple loops.

    Args:
        trajectory: a :class:`Trajectory` (for a manifold, built by the matching constructor,
            e.g. :meth:`Trajectory.se3`).
        gamma: the distance threshold γ > 0, in the metric's unit (metres for positions).
        metric: ``None`` (the trajectory's own, :attr:`Trajectory.metric_name`: Euclidean for
            positions, the manifold's metric for :meth:`Trajectory.se3` and friends, the one
            given to :func:`read_trajectory`), a name such as ``"se3(rotation_weight_m_per_rad=10)"``, an
            :mod:`inexact_loops.metrics` object such as ``il.metrics.SE3(rotation_weight_m_per_rad=10)``,
            or — a slow path, one Python call per distance on one thread — any callable
            ``f(a, b) -> float`` on two points (numpy arrays) satisfying the triangle inequality.
        separation: ``"auto"`` (the default, ``Separation.for_gamma(gamma)``), ``None`` (the
            paper's S_γ), a path length in the metric's unit, or a :class:`Separation` (path
            length and/or time).
        threads: worker threads; ``None`` uses one per core. Results do not depend on it.

    Returns:
        :class:`Loops`.

    Raises:
        InvalidParameterError: gamma not positive and finite, unknown metric, a metric that does
            not fit the trajectory's manifold (e.g. ``"euclidean"`` on :meth:`Trajectory.se3`
            poses; the message names both), a negative separation, threads = 0.
        OutOfMemoryError: the answer does not fit in memory (a ``MemoryError``; the message
            names the size it needs). Ctrl-C raises ``KeyboardInterrupt`` within a row.

    Warns:
        DiagonalBrokenWarning: consecutive poses farther apart than gamma (a data gap, or gamma
            below the step): more than one trivial component.
        NoLoopsWarning: a separation was asked for and no pair within gamma keeps it: no
            revisit, no component. Both also in :attr:`Loops.warnings`.

    Example:
        A 95% circle of radius 10 m: its ends come within 3.1 m of each other, 60 m apart along
        the path.

        >>> import numpy as np, inexact_loops as il
        >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
        >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
        >>> loops = il.find_loops(traj, gamma=4.0)
        >>> loops.separation, loops.components["trivial"].tolist()
        (Separation(path=16.0, time_s=0.0), [False])
        >>> il.find_loops(traj, gamma=4.0, separation=None).components["trivial"].tolist()
        [True, False]
    """

def urban_drive(
    *,
    duration_s: float | None = None,
    rate_hz: float | None = None,
    city_size_m: float | None = None,
    block_m: float | None = None,
    min_speed_mps: float | None = None,
    max_speed_mps: float | None = None,
    stop_probability: float | None = None,
    min_stop_s: float | None = None,
    max_stop_s: float | None = None,
    lane_offset_m: float | None = None,
    lateral_noise_m: float | None = None,
    seed: int | None = None,
    district_m: float | None = None,
    district_dwell_s: float | None = None,
    se3: bool = False,
) -> Trajectory:
    """A seeded synthetic drive on a Manhattan grid (x, y, z in metres, 10 Hz by default).

    Every argument left as ``None`` takes the library default: a 1 km² city of 100 m blocks,
    2.1 h at 10 Hz (75,600 poses), 5–12 m/s, stops of 5 s – 4 min at some intersections.
    With ``se3=True`` the poses carry the heading of travel as an orientation (for the ``se3``
    metrics); otherwise they are positions (x, y, z).

    With ``district_m`` the drive works the city one square district of that side at a time,
    ``district_dwell_s`` seconds each (default 10,000 s), in snake order: the revisits of a place
    stay bounded however long the drive, as for a delivery or mapping vehicle. Without it the
    drive roams the whole city.

    Example:
        >>> import inexact_loops as il
        >>> traj = il.urban_drive(duration_s=60.0, seed=3)
        >>> len(traj), traj.dim
        (600, 3)
        >>> big = il.urban_drive(duration_s=600.0, city_size_m=10_000.0, district_m=1000.0)
        >>> bool(big.positions[:, :2].max() < 1005.0)
        True
    """

def read_trajectory(
    path: str | PathLike[str] | list[str | PathLike[str]],
    *,
    format: str | None = None,
    axes: tuple[int, int] | None = None,
    metric: str | _MetricLike | None = None,
    topic: str | None = None,
    time: Literal["header", "log", "publish"] | str | None = None,
    frames: tuple[str, str] | None = None,
    rate_hz: float | None = None,
    times: str | PathLike[str] | None = None,
    drop_duplicate_stamps: bool = False,
    quaternion_tolerance: float | None = None,
    chain_edges: bool = False,
) -> Trajectory:
    """Reads a trajectory file: TUM, CSV, KITTI, EuRoC, TUC, g2o/TORO pose graphs, MCAP logs
    (ROS 2 and Foxglove pose, odometry and transform messages), rosbag2 bags (sqlite3 or MCAP,
    compressed or not, split or not) or ROS 1 bags — by ``format``, or told from the extension
    and first line (a folder is a rosbag2 bag).

    Reading is strict: a repeated timestamp is an error naming its line. With
    ``drop_duplicate_stamps=True`` the later poses of a repeated stamp are dropped (the first
    is kept), and a :class:`DroppedInputWarning` per file says how many and on which lines.

    Args:
        path: the file (or a rosbag2 bag's folder or ``metadata.yaml``), or a list of files read
            as one trajectory: MCAP files merged by time (a recording split in parts), other
            files joined in time order (their times must not overlap: an error names both files
            and the stamps).
        format: ``"tum"``, ``"csv"``, ``"kitti"``, ``"euroc"``, ``"tuc"``, ``"g2o"``,
            ``"mcap"``, ``"rosbag2"``, ``"ros1"``, or ``None`` to tell.
        axes: a plane of two position axes (0 = x, 1 = y, 2 = z), e.g. ``(0, 2)`` for KITTI's
            ground plane: Euclidean keeps only these coordinates; ``se2`` takes them and the
            heading in the plane, the rotation about its normal (on x-z, the ground of KITTI's
            camera frame, about −y: up); ``se3`` and ``so3`` take none. The trajectory remembers
            it (:attr:`Trajectory.plane_axes`) for the plots.
        metric: the metric the trajectory is for (as in :func:`find_loops`): positions for
            Euclidean (the default); positions and orientations for ``se3``; orientations for
            ``so3``; x, y and yaw about z for ``se2`` (or the plane ``axes`` and the heading in
            it). Quaternions within ``quaternion_tolerance`` of unit length are normalised.
            The trajectory keeps it (:attr:`Trajectory.metric_name`): :func:`find_loops` without
            ``metric=`` measures it so.
        topic: the topic (MCAP, bags); ``None`` picks the one topic with poses (several: an error
            listing them, see :func:`list_topics`).
        time: MCAP and bag times from ``"header"`` stamps (the default), ``"log"`` or ``"publish"`` time.
        frames: ``(parent, child)`` frame pair of a transform topic (TF); ``None`` takes the
            topic's only pair. Frames that no one transform links are composed along the TF
            tree, ``/tf_static`` included (``("map", "velodyne")`` through ``odom`` and
            ``base_link``), at the stamps of the moving link nearest the child, the others
            interpolated there.
        rate_hz: for files without times (KITTI poses, pose graphs): pose i at i / rate_hz s.
        times: for files without times (KITTI poses, pose graphs): a file of one time a line,
            seconds, one per pose in order (KITTI's ``sequences/XX/times.txt``).
        drop_duplicate_stamps: drop the poses whose timestamp repeats the one before, with a
            warning saying how many (default: they are an error).
        quaternion_tolerance: how far from unit length a quaternion may be and still be
            normalised (default 1e-3: files often print 4 decimals).
        chain_edges: for a pose graph without vertices (a list of edges), chain its odometry
            edges into a trajectory, with a :class:`DeadReckoningWarning` (see
            :func:`read_pose_graph`); without it such a file is an error naming this option.

    Raises:
        OSError: the file cannot be opened. LoopsIOError: a malformed line or message (the
        message names file, line or byte offset, topic); files whose times overlap.
        InvalidTrajectoryError: e.g. unsorted or repeated timestamps, a quaternion farther than
        ``quaternion_tolerance`` from unit length (names the line or message).
        InvalidParameterError: an unknown format or time source, a metric whose points are not
        poses (named), bad axes, an empty list, both ``rate_hz`` and ``times``.
        TypeError: ``path`` is not a str, an ``os.PathLike`` or a list of them.

    Example:
        >>> import pathlib, tempfile, warnings, inexact_loops as il
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "desk.tum"
        >>> _ = path.write_text("0 0 0 0 0 0 0 1\\n1 1 0 0 0 0 0 1\\n1 2 0 0 0 0 0 1\\n2 3 0 0 0 0 0 1\\n")
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     traj = il.read_trajectory(path, drop_duplicate_stamps=True)
        >>> len(traj), str(caught[0].message).endswith("dropped 1 pose(s) whose timestamp repeats the one before (line 3)")
        (3, True)
    """

def list_topics(path: str | PathLike[str]) -> list[dict[str, object]]:
    """The topics of an MCAP file, a rosbag2 bag (its folder, ``metadata.yaml`` or a storage
    file) or a ROS 1 bag: one dict per topic with ``topic``, ``schema``,
    ``encoding``, ``messages``, ``start_ns`` and ``end_ns`` (log time, ``None`` when empty) and
    ``pose_type`` (the pose message type the library reads from it, or ``None``).

    Raises:
        OSError: the file cannot be opened. LoopsIOError: not a valid MCAP file or bag (names
        the offset, or the sqlite row).
    """

def log_name(path: str | PathLike[str]) -> str:
    """The name a pose log gives its session (or its folder of results): the file's stem, or a
    rosbag2 bag's folder name however the bag is given (its folder, ``metadata.yaml`` or a storage
    file; a storage file of a split bag adds its own stem). ``loops run``, ``loops fleet``,
    :class:`Fleet` and ``inexact_loops.dask`` all name sessions by this one rule.

    Example:
        >>> from inexact_loops import _core
        >>> _core.log_name("logs/monday.tum"), _core.log_name("logs/monday.db3.zstd")
        ('monday', 'monday')
    """

@final
class Detections:
    """A set of detections D: unordered pairs of times (t, t′), seconds, at which the trajectory is
    believed to come back to itself (place recognition), with optional scores and, once placed
    on a trajectory, the pose indices (i, j) of each pair.

    A pair given as (t′, t) with t′ > t is stored as (t, t′): loop components are reported on
    the half t ≤ t′. Rows keep the order they were given in; duplicates are allowed.

    Args:
        t, t_prime: shape ``(n,)``, seconds, finite, n ≥ 1; either order within a pair.
        scores: shape ``(n,)``, finite (higher is more confident), or ``None``.

    Raises:
        InvalidParameterError: no detections, columns of different lengths, a NaN or infinite
            value (the message names the detection).
        ValueError: wrong shapes. TypeError: non-numeric dtypes.

    Example:
        >>> import inexact_loops as il
        >>> det = il.Detections([30.0, 100.0], [10.0, 400.0], scores=[0.9, 0.4])
        >>> det.t.tolist(), det.t_prime.tolist(), len(det)
        ([10.0, 100.0], [30.0, 400.0], 2)
        >>> det.i is None  # not placed on a trajectory
        True
        >>> traj = il.Trajectory([0.0, 1.0, 2.0], [0.0, 5.0, 0.0])
        >>> by_index = il.Detections.from_indices(traj, [2], [0])
        >>> by_index.t.tolist(), by_index.t_prime.tolist(), by_index.i.tolist()
        ([0.0], [2.0], [0])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], Detections], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Detections: ...
    def __new__(
        cls, t: npt.ArrayLike, t_prime: npt.ArrayLike, scores: npt.ArrayLike | None = None
    ) -> Detections: ...
    @staticmethod
    def from_indices(
        trajectory_or_loops: Trajectory | Loops,
        i: npt.ArrayLike,
        j: npt.ArrayLike,
        scores: npt.ArrayLike | None = None,
    ) -> Detections:
        """Detections from pose indices (i, j) of a trajectory, either order within a pair; the
        times are the poses' timestamps.

        Args:
            trajectory_or_loops: the :class:`Trajectory`, or the :class:`Loops` found on it.
            i, j: shape ``(n,)``, integer pose indices.
            scores: shape ``(n,)`` or ``None``.

        Raises:
            IndexError: an index past the last pose (or negative), naming the detection.
            InvalidParameterError: no detections, columns of different lengths.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> det = il.Detections.from_indices(traj, [3, 1], [0, 2])
            >>> det.i.tolist(), det.j.tolist(), det.t_prime.tolist()
            ([0, 1], [3, 2], [3.0, 2.0])
        """
    def locate(self, trajectory_or_loops: Trajectory | Loops) -> Detections:
        """The same detections placed on a trajectory: each time goes to the nearest pose (the
        pose whose time cell holds it; ties to the earlier), filling :attr:`i` and :attr:`j`.
        The times are kept as given.

        Raises:
            InvalidParameterError: a time outside the trajectory's time span, naming the
                detection.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> det = il.Detections([0.1, 2.2], [2.9, 1.4]).locate(traj)
            >>> det.i.tolist(), det.j.tolist()
            ([0, 1], [3, 2])
        """
    def __len__(self) -> int: ...
    @property
    def t(self) -> npt.NDArray[np.float64]:
        """The earlier time t of each pair, seconds, shape ``(n,)``."""
    @property
    def t_prime(self) -> npt.NDArray[np.float64]:
        """The later time t′ ≥ t of each pair, seconds, shape ``(n,)``."""
    @property
    def i(self) -> npt.NDArray[np.int64] | None:
        """Pose index i (of t) of each pair, int64, or ``None`` when not placed on a trajectory."""
    @property
    def j(self) -> npt.NDArray[np.int64] | None:
        """Pose index j ≥ i (of t′) of each pair, int64, or ``None`` when not placed."""
    @property
    def score(self) -> npt.NDArray[np.float64] | None:
        """The score of each pair, or ``None`` without scores."""
    @property
    def poses(self) -> int | None:
        """Number of poses of the trajectory the detections are placed on, or ``None``."""
    def to_pandas(self) -> pandas.DataFrame:
        """The detections as a ``pandas.DataFrame``, one row a detection in the order given:
        columns ``t``, ``t_prime`` (float64, seconds), then ``i``, ``j`` (int64) once placed on
        a trajectory and ``score`` (float64) when there are scores.

        Raises:
            ImportError: pandas is not installed (it is not a dependency of the library).

        Example:
            >>> import inexact_loops as il
            >>> traj = il.Trajectory([0.0, 1.0, 2.0], [0.0, 5.0, 0.0])
            >>> frame = il.Detections([2.0], [0.1], scores=[0.5]).locate(traj).to_pandas()
            >>> list(frame.columns), frame.loc[0, "j"]
            (['t', 't_prime', 'i', 'j', 'score'], np.int64(2))
        """

@final
class DetectionClusters:
    """The connected components of the ε graph of a detection set: approximations of the loop
    components. Returned by :func:`cluster_detections`.

    Example:
        >>> import inexact_loops as il
        >>> det = il.Detections([0.0, 20.0, 500.0], [100.0, 100.0, 900.0])
        >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
        >>> len(clusters), clusters.labels.tolist(), clusters.clusters["t_max_s"].tolist()
        (2, [0, 0, 1], [20.0, 500.0])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], DetectionClusters], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> DetectionClusters: ...
    def __len__(self) -> int: ...
    @property
    def epsilon_s(self) -> float:
        """The threshold ε, seconds."""
    @property
    def cell_side_s(self) -> float:
        """Side of the grid cells, seconds (a little less than ε/√2)."""
    @property
    def detections(self) -> Detections:
        """The detections that were clustered."""
    @property
    def labels(self) -> npt.NDArray[np.int64]:
        """The cluster id of each detection, int64, in the order of the detections."""
    @property
    def clusters(self) -> Table:
        """The clusters as a :class:`~inexact_loops.Table` (a dict of numpy columns, one row a
        cluster, by id; ``.to_pandas()`` for a DataFrame): ``id``, ``size`` (detections; int64),
        ``t_min_s``, ``t_max_s``, ``t_prime_min_s``, ``t_prime_max_s`` (extents, seconds;
        float64), ``cells`` (grid cells holding its detections; int64), ``area_proxy_s2``
        (cells × side², s²; float64), ``anchor`` (index of its smallest detection in (t, t′)
        order; int64).
        """

@final
class Samples:
    """The samples a sampler chose — candidate pairs for the scan matcher — in order of (t, t′),
    as numpy columns. Returned by :func:`sample`.

    Example:
        >>> import inexact_loops as il
        >>> det = il.Detections([0.0, 0.0, 500.0], [100.0, 101.0, 900.0], scores=[0.2, 0.8, 0.5])
        >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
        >>> samples = il.sample(clusters, "rho-dispersed", budget=2, seed=0)
        >>> samples.t_prime.tolist(), samples.cluster.tolist(), samples.score.tolist()
        ([101.0, 900.0], [0, 1], [0.8, 0.5])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], Samples], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Samples: ...
    def __len__(self) -> int: ...
    @property
    def sampler(self) -> str:
        """The sampler's name (``"one"``, ``"rho"``, ...)."""
    @property
    def groups(self) -> int:
        """Number of groups sampled from (clusters, or components with a pair; 0 for σ_α and the
        baselines, which do not group).
        """
    @property
    def available(self) -> int:
        """Number of candidates the sampler chose from (detections, pairs, or a rule's pairs)."""
    @property
    def poses(self) -> int | None:
        """Number of poses of the trajectory the pairs index, or ``None``."""
    @property
    def warnings(self) -> list[str]:
        """Warnings (a budget below the number of groups, or above the candidates), as sentences;
        :func:`sample` also issues each with :func:`warnings.warn`, in a category of
        :class:`LoopsWarning`.
        """
    @property
    def t(self) -> npt.NDArray[np.float64]:
        """The earlier time of each sample, seconds."""
    @property
    def t_prime(self) -> npt.NDArray[np.float64]:
        """The later time of each sample, seconds."""
    @property
    def i(self) -> npt.NDArray[np.int64] | None:
        """Pose index i of each sample, int64, or ``None`` when not placed on a trajectory."""
    @property
    def j(self) -> npt.NDArray[np.int64] | None:
        """Pose index j ≥ i of each sample, int64, or ``None`` when not placed on a trajectory."""
    @property
    def component(self) -> npt.NDArray[np.int64]:
        """The exact loop component of each sample, int64; −1 when unknown (samples of clusters
        before :meth:`locate`) or outside S_γ.
        """
    @property
    def cluster(self) -> npt.NDArray[np.int64]:
        """The detection cluster each sample was drawn from, int64; −1 for samples of ``Loops``."""
    @property
    def detection(self) -> npt.NDArray[np.int64]:
        """The index of the detection each sample is, int64; −1 for samples of ``Loops``."""
    @property
    def distance(self) -> npt.NDArray[np.float64]:
        """δ(x_i, x_j) of each sample in the metric's unit; NaN where not measured."""
    @property
    def score(self) -> npt.NDArray[np.float64] | None:
        """The detection's score of each sample, or ``None`` when the detections had none."""
    @property
    def relative_poses(self) -> npt.NDArray[np.float64]:
        """The relative pose the trajectory predicts from pose ``i`` to pose ``j`` of each sample:
        the scan matcher's initial guess, shape ``(n, 8)``, columns ``dx, dy, dz, dqx, dqy, dqz,
        dqw, dtheta_rad``: ``T_i⁻¹ T_j`` for SE(3) and SE(2) trajectories (translation in the
        frame of pose ``i``; ``dtheta_rad`` for SE(2) only), the coordinate difference for
        positions alone (up to 3 columns; no rotation). NaN where there is none (no pose pair;
        other manifolds). No uncertainty: trajectories hold no covariance.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.5]))
            >>> loops = il.find_loops(traj, gamma=0.6, separation=None)
            >>> il.sample(loops, "alpha", rate=1.0, seed=0, trajectory=traj).relative_poses[:, 0].tolist()
            [0.5, 0.0, -0.5, -0.5]
        """
    def locate(self, loops: Loops) -> Samples:
        """The same samples placed on the poses of ``loops``' trajectory (where not yet), with the
        exact loop component of each (:attr:`component`).

        Raises:
            InvalidParameterError: the samples index another trajectory, or a time lies outside
                its span.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.0]))
            >>> loops = il.find_loops(traj, gamma=0.5, separation=None)
            >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
            >>> il.sample(clusters, "alpha", rate=1.0, seed=0).locate(loops).component.tolist()
            [1]
        """
    def measure(self, trajectory: Trajectory, *, metric: _MetricArg = None) -> Samples:
        """The same samples placed on ``trajectory`` (where not yet), with the distance
        δ(x_i, x_j) of each (:attr:`distance`) under ``metric`` (as in :func:`find_loops`;
        ``None`` is the trajectory's own, :attr:`Trajectory.metric_name`).

        Raises:
            InvalidParameterError: the samples index another trajectory, or a time lies outside
                its span.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> traj = il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 1.0, 0.5]))
            >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
            >>> il.sample(clusters, "alpha", rate=1.0, seed=0).measure(traj).distance.tolist()
            [0.5]
        """
    def to_pandas(self) -> pandas.DataFrame:
        """The samples as a ``pandas.DataFrame``, one row a sample in order of (t, t′): columns
        ``t``, ``t_prime`` (float64, seconds), ``i``, ``j`` (int64; only when placed on a
        trajectory), ``component``, ``cluster``, ``detection`` (int64, −1 where none),
        ``distance`` (float64, NaN where not measured), ``score`` (float64; only when the
        detections had scores) — the getters of the same names — and, when any sample has one,
        the relative pose ``dx, dy, dz, dqx, dqy, dqz, dqw, dtheta_rad`` (:attr:`relative_poses`)
        and where the two poses are, ``i_x, i_y, i_z, j_x, j_y, j_z`` (the trajectory's first three
        coordinates, as ``samples.csv`` has them).

        Raises:
            ImportError: pandas is not installed (it is not a dependency of the library).

        Example:
            >>> import inexact_loops as il
            >>> clusters = il.cluster_detections(il.Detections([0.0, 500.0], [3.0, 900.0]), epsilon_s=1.0)
            >>> frame = il.sample(clusters, "one", budget=2, seed=0).to_pandas()
            >>> list(frame.columns), frame["cluster"].tolist()
            (['t', 't_prime', 'component', 'cluster', 'detection', 'distance'], [0, 1])
        """
    def to_csv(self, path: str | PathLike[str], *, overwrite: bool = False) -> None:
        """Writes the samples as CSV: a header ``t_s,t_prime_s,i,j,component,cluster,detection,
        distance,score,sampler,dx,dy,dz,dqx,dqy,dqz,dqw,dtheta_rad,i_x,i_y,i_z,j_x,j_y,j_z`` (then
        the relative pose, :attr:`relative_poses`, and where the two poses are), then one line a
        sample; unknown values are empty fields.
        Atomic (a temporary file renamed into place).

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.

        Example:
            >>> import os, tempfile, inexact_loops as il
            >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
            >>> samples = il.sample(clusters, "alpha", rate=1.0, seed=0)
            >>> path = os.path.join(tempfile.mkdtemp(), "samples.csv")
            >>> samples.to_csv(path)
            >>> open(path).read().splitlines()[1]
            '0,3,,,,0,0,,,alpha,,,,,,,,,,,,,,'
        """
    def to_json(self, path: str | PathLike[str], *, overwrite: bool = False) -> None:
        """Writes the samples as one JSON object: ``sampler``, ``count``, ``groups``,
        ``available``, ``poses``, ``warnings`` and ``samples`` (a list of objects with the CSV's
        columns; ``null`` for unknown values). Atomic, as :meth:`to_csv`.

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.

        Example:
            >>> import json, os, tempfile, inexact_loops as il
            >>> clusters = il.cluster_detections(il.Detections([0.0], [3.0]), epsilon_s=1.0)
            >>> path = os.path.join(tempfile.mkdtemp(), "samples.json")
            >>> il.sample(clusters, "alpha", rate=1.0, seed=0).to_json(path)
            >>> json.load(open(path))["samples"][0]["t_prime_s"]
            3.0
        """

@final
class SampleQuality:
    """P1, P2 and P3 of a sample (paper, Sec. 5.2), measured against the exact loop components of
    S_γ. Returned by :func:`sample_quality`.

    Components count when they hold a pair (i, j) with i < j (a lone diagonal cell cannot be
    sampled).

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
        >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
        >>> loops = il.find_loops(traj, gamma=4.0, separation=None)
        >>> samples = il.sample(loops, "one", budget=2, seed=0, trajectory=traj)
        >>> quality = il.sample_quality(samples, loops, epsilon_s=1.0)
        >>> quality.covered, quality.components, quality.coverage, quality.per_component.tolist()
        (2, 2, 1.0, [1, 1])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], SampleQuality], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> SampleQuality: ...
    @property
    def samples(self) -> int:
        """Number of samples."""
    @property
    def outside(self) -> int:
        """Samples outside S_γ (δ > γ: false detections)."""
    @property
    def components(self) -> int:
        """Loop components that can be sampled."""
    @property
    def covered(self) -> int:
        """P1: components with at least one sample."""
    @property
    def nontrivial_components(self) -> int:
        """Non-trivial components (revisits proper) that can be sampled."""
    @property
    def nontrivial_covered(self) -> int:
        """P1 over the non-trivial components."""
    @property
    def coverage(self) -> float:
        """P1 as a fraction: covered / components (1 without components)."""
    @property
    def missed(self) -> Table:
        """P1: the components without a sample, largest area first, as a
        :class:`~inexact_loops.Table`: ``id`` (int64), ``trivial`` (bool), ``area_s2``
        (float64, s²), ``pair_count`` (int64).
        """
    @property
    def epsilon_s(self) -> float:
        """The ε of P2, seconds."""
    @property
    def redundant(self) -> int:
        """P2: samples with another sample of the same component within ε."""
    @property
    def redundancy(self) -> float:
        """P2 as a fraction: redundant / samples (0 without samples)."""
    @property
    def median_spacing_s(self) -> float | None:
        """P2: median distance from a sample to the nearest other sample of its component,
        seconds; ``None`` when no component has two samples.
        """
    @property
    def p3_slope(self) -> float | None:
        """P3: least-squares slope of ln(samples) on ln(area) across the covered components (≈ 0
        for σ_1, ≈ 1 for σ_α); ``None`` with fewer than two distinct areas.
        """
    @property
    def p3_components(self) -> int:
        """Number of components in the P3 fit."""
    @property
    def per_component(self) -> npt.NDArray[np.int64]:
        """Samples per component, int64, by component id: one entry per row of
        :attr:`Loops.components`, so it can be added to that table as a column.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
            >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
            >>> loops = il.find_loops(traj, gamma=4.0, separation=None)
            >>> samples = il.sample(loops, "alpha", budget=5, seed=0, trajectory=traj)
            >>> table = loops.components
            >>> table["samples"] = il.sample_quality(samples, loops).per_component
            >>> int(table["samples"].sum()), table.num_rows
            (5, 2)
        """
    @property
    def sample_components(self) -> npt.NDArray[np.int64]:
        """The exact component of each sample, int64, in the samples' order; −1 outside S_γ."""
    @property
    def nearest_spacing_s(self) -> npt.NDArray[np.float64]:
        """Each sample's distance to the nearest other sample of its component, seconds, in the
        samples' order; NaN when alone in its component or outside S_γ.
        """

def draw_detections(
    loops: Loops, *, rate: float | None = None, budget: int | None = None, seed: int
) -> Detections:
    """Detections drawn uniformly from the exact S_γ of ``loops``, without materialising it: the
    off-diagonal pairs (i, j), i < j, of its runs, placed on the trajectory, in row-major order.

    Args:
        loops: from :func:`find_loops`.
        rate: every pair independently with this probability, in (0, 1]; or
        budget: exactly this many distinct pairs (at most the pairs of S_γ). Give one of them.
        seed: the seed (ChaCha8): the same seed gives the same detections on every machine.

    Raises:
        InvalidParameterError: rate and budget both or neither, a rate outside (0, 1], a
            budget of 0 or above the pairs available, an empty draw, more than 5,000,000
            detections (refused before anything is drawn).

    Example:
        >>> import inexact_loops as il
        >>> loops = il.find_loops(il.urban_drive(duration_s=600.0), gamma=40.0, separation=None)
        >>> det = il.draw_detections(loops, budget=1000, seed=7)
        >>> len(det), all(loops.component_of(i, j) is not None for i, j in zip(det.i, det.j))
        (1000, True)
    """

def read_detections(
    path: str | PathLike[str],
    trajectory_or_loops: Trajectory | Loops | None = None,
    *,
    drop_outside_span: bool = False,
) -> Detections:
    """Reads detections from a file: rows of ``t, t_prime[, score]`` (commas, semicolons, tabs or
    spaces; a header row and ``#`` comments allowed), or the TUC datasets' ``loop t1 t2 score``
    lines (other keyword lines skipped).

    Placing them on a trajectory (``trajectory_or_loops``) is strict: a detection outside its
    time span is an error naming the line. With ``drop_outside_span=True`` such detections are
    dropped, and a :class:`DroppedInputWarning` says how many and on which lines (the TUC Corridor's input
    has 39 of its 10,019 detections 0.4 s past the end of the ground truth).

    Args:
        path: the file.
        trajectory_or_loops: a :class:`Trajectory` (or the :class:`Loops` found on it) to place
            the detections on (filling :attr:`Detections.i` and :attr:`Detections.j`), or
            ``None`` to keep times only.
        drop_outside_span: drop the detections outside the trajectory's time span, with a
            warning saying how many (needs ``trajectory_or_loops``).

    Raises:
        OSError: the file cannot be opened. LoopsIOError: a malformed row, no detection, a
        detection outside the trajectory's time span (naming file and line).
        InvalidParameterError: ``drop_outside_span`` without a trajectory.

    Example:
        >>> import pathlib, tempfile, warnings, inexact_loops as il
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "input.txt"
        >>> _ = path.write_text("odom2 0 0 0 0\\nloop 2.5 0.5 1\\nloop 9.5 1.0 0.5\\n")
        >>> traj = il.Trajectory([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
        >>> il.read_detections(path).t.tolist()
        [0.5, 1.0]
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     det = il.read_detections(path, traj, drop_outside_span=True)
        >>> det.i.tolist(), det.j.tolist(), str(caught[0].message).endswith("(line 3)")
        ([0], [2], True)
    """

def cluster_detections(
    detections: Detections, *, epsilon_s: float | None = None, threads: int | None = None
) -> DetectionClusters:
    """Clusters detections exactly: the connected components of the graph with an edge between
    every two detections within ``epsilon_s`` seconds of each other (Euclidean in the (t, t′)
    plane, ``<= ε``): DBSCAN with ``min_samples=1``, without enumerating the ε-pairs.

    Args:
        detections: :class:`Detections`.
        epsilon_s: ε > 0, seconds; ``None`` takes the library default (30 s, the paper's).
        threads: worker threads; ``None`` uses one per core. Results do not depend on it.

    Returns:
        :class:`DetectionClusters`; cluster ids follow each cluster's smallest (t, t′), so they
        do not depend on the order of the detections.

    Raises:
        InvalidParameterError: ε not positive and finite (or below the floating-point
            resolution of the detections' time range), threads = 0.

    Example:
        >>> import inexact_loops as il
        >>> det = il.Detections([0.0, 30.0, 60.0, 500.0], [1000.0, 1000.0, 1000.0, 900.0])
        >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
        >>> clusters.labels.tolist(), clusters.clusters["size"].tolist()
        ([0, 0, 0, 1], [3, 1])
    """

def sample(
    source: DetectionClusters | Loops,
    sampler: _SamplerName | str | None = None,
    *,
    rate: float | None = None,
    budget: int | None = None,
    seed: int,
    trajectory: Trajectory | None = None,
    metric: _MetricArg = None,
    threads: int | None = None,
    skip_trivial: bool = False,
    lio_sam_keyframe_step: float | None = None,
    lio_sam_period_s: float | None = None,
    lio_sam_min_age_s: float | None = None,
    hdl_keyframe_step: float | None = None,
    hdl_min_travel: float | None = None,
    hdl_edge_spacing: float | None = None,
    cartographer_min_gap_s: float | None = None,
    time_gap_s: float | None = None,
) -> Samples:
    """Samples inexact loops (paper, Sec. 5): from detection clusters, or straight from the exact
    loop components of S_γ.

    Args:
        source: :class:`DetectionClusters` (from :func:`cluster_detections`: groups are the
            clusters, picks are detections) or :class:`Loops` (from :func:`find_loops`: groups
            are the exact components, picks are pairs (i, j), i < j, of S_γ; needs
            ``trajectory``).
        sampler: ``"one"`` (σ_1: c per group), ``"rho"`` (σ_ρ: r per group per trajectory
            point), ``"rho-dispersed"`` (σ_ρ's counts spread evenly along each group, each the
            row's closest pair, or best-scored detection), ``"alpha"`` (σ_α: uniform over all
            detections or pairs), ``"closest-first"`` (each group's closest pair, or best-scored
            detection, first; the rest as ``"rho-dispersed"``), ``"closest-then-spread"`` (σ_ρ's
            counts, each group's first pick its closest pair, the rest as ``"rho-dispersed"``),
            ``"nearest-then-uniform"`` (the default, :data:`DEFAULT_SAMPLER`: each group's
            closest pair, then rows' closest pairs up to one row in six, the rest uniform over
            the pairs), or a baseline of a deployed SLAM system (``Loops`` only): ``"lio-sam"``,
            ``"hdl-graph-slam"``, ``"cartographer"``, ``"time-gap"``.
        rate: the sampler's own rate (c, r, or a probability in (0, 1] for σ_α and the
            baselines); or
        budget: exactly this many samples (fewer only when fewer exist, with a warning); every
            sampler but σ_α and the baselines keeps at least one per group whenever the budget
            allows it (P1). Give at most one; neither draws :data:`DEFAULT_BUDGET`.
        seed: the seed (ChaCha8): the same samples on every machine and thread count.
        trajectory: the :class:`Trajectory` the loops were found on (required for ``Loops``);
            with clusters, optional: the samples are then placed on it and their distances
            measured.
        metric: as in :func:`find_loops`; ``None`` takes the loops' own metric (for clusters,
            the trajectory's, :attr:`Trajectory.metric_name`).
        threads: worker threads; ``None`` uses one per core. Results do not depend on it.
        skip_trivial: leave out the trivial loop components (``Loops``, not with a baseline):
            their pairs are simple loops (the next poses, a stop) that odometry already ties
            together, and σ_ρ would otherwise spend a large share of the budget on them.
        lio_sam_keyframe_step, lio_sam_period_s, lio_sam_min_age_s, hdl_keyframe_step,
        hdl_min_travel, hdl_edge_spacing, cartographer_min_gap_s, time_gap_s: parameters of
            the baselines (metric units and seconds); ``None`` takes the library default.

    Returns:
        :class:`Samples`.

    Raises:
        InvalidParameterError: an unknown sampler (the message lists the names), a baseline on
            clusters, both rate and budget, a budget of 0, a rate out of range, a
            trajectory that is not the loops', ``skip_trivial`` with clusters or a baseline; a
            budget or rate that makes more than 5,000,000 samples (the message says how many
            and how much memory they would take), refused before anything is drawn.
        OutOfMemoryError: the samples do not fit in memory.
        TypeError: ``Loops`` without ``trajectory``.

    Warns:
        EmptySampleWarning: no samples (no candidates, e.g. ``skip_trivial`` on loops whose
            every component is trivial, or a rate that kept none).
        SampleBudgetWarning: fewer candidates than the budget (all are returned), or a budget
            below the number of groups (P1 cannot hold). Both also in :attr:`Samples.warnings`.

    Example:
        >>> import inexact_loops as il
        >>> traj = il.urban_drive(duration_s=900.0)
        >>> loops = il.find_loops(traj, gamma=40.0, separation=None)
        >>> samples = il.sample(loops, "rho", budget=200, seed=1, trajectory=traj)
        >>> len(samples), samples.sampler, set(samples.component.tolist()) == set(range(len(loops.components["id"])))
        (200, 'rho', True)
        >>> det = il.draw_detections(loops, rate=0.01, seed=0)
        >>> clusters = il.cluster_detections(det, epsilon_s=30.0)
        >>> samples = il.sample(clusters, "one", budget=len(clusters), seed=0)
        >>> sorted(samples.cluster.tolist()) == list(range(len(clusters)))
        True
    """

def sample_quality(
    samples: Samples, loops: Loops, *, epsilon_s: float | None = None
) -> SampleQuality:
    """Measures how representative ``samples`` are of the loops (paper, Sec. 5.2): P1 (every loop
    component covered), P2 (no redundant samples), P3 (more samples for bigger components),
    against the exact components of ``loops`` — never against the detection clusters. Samples
    given only by times are placed on the nearest poses.

    Args:
        samples: :class:`Samples`.
        loops: the :class:`Loops` to measure against (same trajectory).
        epsilon_s: the P2 radius, seconds: a sample with another sample of its component
            within ε in the (t, t′) plane is redundant; ``None`` takes the library default
            (30 s, the paper's).

    Raises:
        InvalidParameterError: ε not positive and finite, samples of another trajectory, a
            sample time outside its span.

    Example:
        >>> import inexact_loops as il
        >>> traj = il.urban_drive(duration_s=900.0)
        >>> loops = il.find_loops(traj, gamma=40.0, separation=None)
        >>> samples = il.sample(loops, "one", budget=500, seed=0, trajectory=traj)
        >>> quality = il.sample_quality(samples, loops, epsilon_s=30.0)
        >>> quality.covered == quality.components, quality.missed["id"].tolist()
        (True, [])
    """

@final
class PlaneGrid:
    """The poses an image of the (t, t′) plane shows: one pose per column (time t) and one per row
    (time t′), for :func:`distance_image` and :meth:`Loops.label_image`.

    Along each axis: every pose whose time lies in the window when at most ``max_pixels`` do;
    otherwise ``max_pixels`` pixels evenly spaced in time over the window, each showing the pose
    nearest its centre time (ties to the earlier pose; where poses are sparser than pixels, one
    pose shows in neighbouring pixels).

    Args:
        trajectory_or_loops: the :class:`Trajectory`, or the :class:`Loops` found on it.
        max_pixels: the most pixels a side (at least 1).
        window_s: ``((t_min, t_max), (t_prime_min, t_prime_max))``, seconds from the first pose;
            ``None`` is the whole plane.

    Raises:
        InvalidParameterError: ``max_pixels`` = 0, a window side that is not finite with
            min < max, or with no pose in it.
        TypeError: ``trajectory_or_loops`` of another type.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> traj = il.Trajectory(np.arange(10.0), np.zeros(10))
        >>> il.PlaneGrid(traj, 100).columns.tolist()
        [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
        >>> coarse = il.PlaneGrid(traj, 3)  # pixel centres at 1.5, 4.5 and 7.5 s
        >>> coarse.columns.tolist(), coarse.column_edges_s.tolist()
        ([1, 4, 7], [0.0, 3.0, 6.0, 9.0])
        >>> zoom = il.PlaneGrid(traj, 100, window_s=((2.0, 4.0), (6.5, 9.0)))
        >>> zoom.columns.tolist(), zoom.rows.tolist(), zoom.column_edges_s.tolist()
        ([2, 3, 4], [7, 8, 9], [1.5, 2.5, 3.5, 4.5])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], PlaneGrid], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> PlaneGrid: ...
    def __new__(
        cls,
        trajectory_or_loops: Trajectory | Loops,
        max_pixels: int,
        *,
        window_s: tuple[tuple[float, float], tuple[float, float]] | None = None,
    ) -> PlaneGrid: ...
    @property
    def columns(self) -> npt.NDArray[np.int64]:
        """The pose index i of each column (time t), increasing: int64, shape ``(width,)``."""
    @property
    def rows(self) -> npt.NDArray[np.int64]:
        """The pose index j of each row (time t′), increasing (row 0 is the earliest t′): int64,
        shape ``(height,)``.
        """
    @property
    def column_edges_s(self) -> npt.NDArray[np.float64]:
        """The time each column stands for: ``width + 1`` increasing boundaries, seconds from the
        first pose (column a spans ``[edges[a], edges[a + 1]]``). Even steps over the window when
        the axis is downsampled; otherwise the midpoints between the poses' times, half a step
        beyond the first and the last.
        """
    @property
    def row_edges_s(self) -> npt.NDArray[np.float64]:
        """The time each row stands for: ``height + 1`` increasing boundaries, seconds from the
        first pose, as :attr:`column_edges_s`.
        """
    @property
    def width(self) -> int:
        """Number of columns."""
    @property
    def height(self) -> int:
        """Number of rows."""
    @property
    def poses(self) -> int:
        """Number of poses of the trajectory the grid was made for."""

def distance_image(
    trajectory: Trajectory,
    grid: PlaneGrid,
    *,
    metric: _MetricArg = None,
    threads: int | None = None,
) -> npt.NDArray[np.float64]:
    """The pairwise distance π(t, t′) = δ(ξ(t), ξ(t′)) on a grid: ``image[b, a]`` is δ between the
    column pose ``grid.columns[a]`` and the row pose ``grid.rows[b]``, in the metric's unit, for
    any metric (SE(3), SO(3), ...). Rows are computed in parallel without the GIL; the cost is one
    distance per pixel, whatever the trajectory's length.

    Args:
        trajectory: the :class:`Trajectory`.
        grid: a :class:`PlaneGrid` made for it.
        metric: as :func:`find_loops`: ``None`` (the trajectory's own, :attr:`Trajectory.metric_name`),
            a name such as ``"so3"``, an :mod:`inexact_loops.metrics` object, or — slow, one
            Python call per pixel on one thread — a callable ``f(a, b) -> float``.
        threads: worker threads; ``None`` uses one per core.

    Returns:
        float64 array, shape ``(grid.height, grid.width)``.

    Raises:
        InvalidParameterError: a grid made for another number of poses, an unknown metric.
        InvalidTrajectoryError: a trajectory the metric cannot take (e.g. not unit quaternions).

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> s = np.sqrt(0.5)  # rotations about z by 0, 90° and 180°
        >>> traj = il.Trajectory.so3(np.arange(3.0), [[0, 0, 0, 1.0], [0, 0, s, s], [0, 0, 1.0, 0]])
        >>> image = il.distance_image(traj, il.PlaneGrid(traj, 8), metric="so3")
        >>> np.round(image / np.pi, 6).tolist()
        [[0.0, 0.5, 1.0], [0.5, 0.0, 0.5], [1.0, 0.5, 0.0]]
    """

def outline_segments(
    labels: npt.ArrayLike, *, border: Literal["closed", "open"] | str = "closed"
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The edges of the pixel lattice where the label changes: the outlines ∂Ω of the components
    of a label image (as :meth:`Loops.label_image` gives), vertical edges first (row by row,
    left to right), then horizontal ones (bottom to top). In pixel units: column a spans
    x ∈ [a, a + 1], row b spans y ∈ [b, b + 1].

    Args:
        labels: integer array ``(height, width)``, negative where a pixel has no component.
        border: ``"closed"`` (nothing lies outside the image: components touching the border
            are closed along it) or ``"open"`` (the image continues its outermost pixels: no
            edges along the border, a component cut by a zoom window stays open).

    Returns:
        ``(edges, sides)``: int64 arrays ``(k, 2, 2)``, each edge's two vertices ``[x, y]`` (the
        second one up or to the right of the first), and ``(k, 2)``, the labels on its two sides
        (left and right of a vertical edge, below and above a horizontal one; −1 for none).

    Raises:
        ValueError: ``labels`` not 2-dimensional. TypeError: not integers.
        InvalidParameterError: an unknown ``border``.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> labels = np.full((3, 3), -1)
        >>> labels[1, 1] = 7  # one pixel: its four sides
        >>> edges, sides = il.outline_segments(labels)
        >>> edges.shape, sides.tolist()
        ((4, 2, 2), [[-1, 7], [7, -1], [-1, 7], [7, -1]])
        >>> edges[0].tolist()  # the left side of the pixel, upwards
        [[1, 1], [1, 2]]
        >>> len(il.outline_segments(np.ones((2, 2), int), border="open")[0])
        0
    """

def component_outlines(
    labels: npt.ArrayLike, *, border: Literal["closed", "open"] | str = "closed"
) -> dict[int, list[npt.NDArray[np.int64]]]:
    """The outline of each component of a label image as polylines of pixel corners: the edges of
    :func:`outline_segments` with that component on either side, joined by
    :func:`chain_polylines`. With ``border="closed"`` every polyline is closed (its last vertex
    is its first), so it can be filled (even-odd: holes stay empty).

    Args:
        labels, border: as :func:`outline_segments`.

    Returns:
        ``{component id: [polyline, ...]}``, each polyline an int64 array ``(m, 2)`` of
        vertices ``[x, y]`` in pixel units; ids in increasing order.

    Raises:
        As :func:`outline_segments`.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> labels = np.array([[4, 4, -1], [-1, -1, -1]])  # a 2 × 1 component, bottom left
        >>> outlines = il.component_outlines(labels)
        >>> list(outlines), outlines[4][0].tolist()
        ([4], [[0, 0], [0, 1], [1, 1], [2, 1], [2, 0], [1, 0], [0, 0]])
    """

def chain_polylines(edges: npt.ArrayLike) -> list[npt.NDArray[np.int64]]:
    """Joins edges into polylines, each edge used once; a closed polyline ends with its first
    vertex. Deterministic: a polyline starts at the first unused edge in input order and is
    extended forwards, then backwards, each time along the first unused edge at its end.

    Args:
        edges: integer array ``(k, 2)`` of vertex ids, or ``(k, 2, 2)`` of vertices ``[x, y]``
            (the edges of :func:`outline_segments`), either direction.

    Returns:
        A list of int64 arrays: ``(m,)`` vertex ids, or ``(m, 2)`` vertices.

    Raises:
        ValueError: another shape. TypeError: not integers.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> [line.tolist() for line in il.chain_polylines([[0, 1], [2, 3], [1, 2], [3, 0], [5, 6]])]
        [[0, 1, 2, 3, 0], [5, 6]]
    """

def isocontour(values: npt.ArrayLike, level: float) -> list[npt.NDArray[np.float64]]:
    """The ``level`` isocontour of an image by marching squares on the pixel centres (pixel
    (a, b) at (a + ½, b + ½)), as polylines of points ``[x, y]`` in pixel units, crossings placed
    by linear interpolation; saddles resolved by the mean of the cell's corners, NaN counted as
    above the level. For the γ isocontour of π, pass a :func:`distance_image` and γ.

    Args:
        values: real array ``(height, width)``.
        level: the level.

    Returns:
        A list of float64 arrays ``(m, 2)``; a closed line ends with its first point.

    Raises:
        ValueError: ``values`` not 2-dimensional. TypeError: not real numbers.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> b, a = np.mgrid[0:9, 0:9]
        >>> cone = np.hypot(a - 4.0, b - 4.0)  # 0 at the pixel centre (4.5, 4.5)
        >>> (line,) = il.isocontour(cone, 2.5)
        >>> bool((line[0] == line[-1]).all()), bool(np.allclose(np.hypot(*(line - 4.5).T), 2.5, atol=0.3))
        (True, True)
    """

def sampler_symbol(sampler: _SamplerName | str) -> str:
    """The symbol of a sampler in the paper (``"σ_1"``, ``"σ_ρ"``, ``"σ_α"``), or the name of the
    system whose rule a baseline follows (``"LIO-SAM"``, ...): for figures and reports.

    Args:
        sampler: a sampler's name, as :func:`sample` takes it (``"one"``, ``"rho"``, ...).

    Raises:
        InvalidParameterError: an unknown sampler (the message lists the names).

    Example:
        >>> import inexact_loops as il
        >>> il.sampler_symbol("rho"), il.sampler_symbol("lio-sam")
        ('σ_ρ', 'LIO-SAM')
    """

_SessionSource = Trajectory | str | PathLike[str] | list[str | PathLike[str]]
_SessionKey = str | int

@final
class Fleet:
    """Sessions — vehicles, days, robots — in one frame, each a :class:`Trajectory` with a name and
    its own clock: the input of :func:`find_fleet_loops`.

    The sessions keep the order given, which orders the blocks of the fleet's plane (rows of
    session a, columns of session b, a ≤ b). All must have the same dimension and manifold.

    Args:
        sessions: a dict ``{name: session}``, a list of ``(name, session)`` pairs, or a list of
            paths; a session is a :class:`Trajectory` or a path read by :func:`read_trajectory`
            (in a dict or a pair, also a list of paths read as one trajectory). A path given
            alone is named by its file stem (``logs/monday.tum``: ``"monday"``; a rosbag2 bag's
            ``metadata.yaml``: its folder's name).
        format, axes, metric, topic, time, frames, rate_hz, drop_duplicate_stamps,
            quaternion_tolerance: how the paths are read, as in :func:`read_trajectory` (each
            path with the same options). ``metric`` is then each session's metric
            (:attr:`Trajectory.metric_name`).

    Raises:
        InvalidParameterError: no session; two sessions of the same name (for paths named by
            their stem, the message names both paths); sessions of different dimensions or
            manifolds (names the session); more poses in all than one trajectory may hold.
        TypeError: ``sessions`` (or one of its items) of another type.
        OSError, LoopsIOError, InvalidTrajectoryError: a path that cannot be read, as
            :func:`read_trajectory` (the message names the file).

    Warns:
        DroppedInputWarning: as :func:`read_trajectory`, per file.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> monday = il.Trajectory([0.0, 1.0, 2.0], [[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
        >>> tuesday = il.Trajectory([100.0, 101.0], [[10.0, 0.5], [0.0, 0.5]])
        >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
        >>> fleet.names, len(fleet), fleet.starts.tolist(), fleet.locate(3)
        (['monday', 'tuesday'], 2, [0, 3], (1, 0))
        >>> fleet.session("tuesday").timestamps.tolist()
        [100.0, 101.0]
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], Fleet], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Fleet: ...
    def __new__(
        cls,
        sessions: dict[str, _SessionSource]
        | list[tuple[str, _SessionSource]]
        | list[str | PathLike[str]]
        | list[tuple[str, _SessionSource] | str | PathLike[str]],
        *,
        format: str | None = None,
        axes: tuple[int, int] | None = None,
        metric: str | _MetricLike | None = None,
        topic: str | None = None,
        time: Literal["header", "log", "publish"] | str | None = None,
        frames: tuple[str, str] | None = None,
        rate_hz: float | None = None,
        drop_duplicate_stamps: bool = False,
        quaternion_tolerance: float | None = None,
    ) -> Fleet: ...
    def __len__(self) -> int: ...
    @property
    def names(self) -> list[str]:
        """The sessions' names, in order."""
    @property
    def poses(self) -> int:
        """Number of poses in all sessions."""
    @property
    def starts(self) -> npt.NDArray[np.int64]:
        """The first *fleet index* of each session, int64, shape ``(len(fleet),)``: the sessions'
        poses numbered one session after another, as :attr:`FleetLoops.loops` and
        :attr:`FleetSamples.samples` index them.
        """
    @property
    def clock_offsets(self) -> npt.NDArray[np.float64]:
        """Fleet clock minus session clock, seconds, per session (float64): the *fleet clock* runs
        the sessions one after another, each starting an hour after the previous one ends, as
        :attr:`joint` and :attr:`FleetLoops.loops` time them.
        """
    @property
    def joint(self) -> Trajectory:
        """The sessions one after another as one :class:`Trajectory` on the fleet clock (each
        session keeps its own time cells): the trajectory of :attr:`FleetLoops.loops` (a copy).
        """
    def session(self, session: _SessionKey) -> Trajectory:
        """A session's :class:`Trajectory`, on its own clock (a copy).

        Args:
            session: its name or its index.

        Raises:
            KeyError: no session of that name. IndexError: an index out of range.
        """
    def locate(self, index: int) -> tuple[int, int]:
        """The ``(session, pose)`` indices of a fleet index.

        Raises:
            IndexError: a negative index or one past the last pose.
        """
    def index(self, session: _SessionKey, pose: int) -> int:
        """The fleet index of pose ``pose`` of ``session`` (its name or index).

        Raises:
            KeyError: no session of that name. IndexError: a session or pose out of range.
        """

@final
class FleetLoops:
    """The loops of a fleet at one γ: every block's loop components, the sessions' overlap (α per
    session pair) and the loop duration split into own and other sessions. Returned by
    :func:`find_fleet_loops`.

    Times in its tables are on each session's own clock; :attr:`loops` is the result over the
    joint trajectory (:attr:`Fleet.joint`: fleet indices, fleet clock), for everything
    :class:`Loops` does.
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes, Fleet], FleetLoops], tuple[bytes, Fleet]]: ...
    @classmethod
    def _from_state(cls, state: bytes, fleet: Fleet) -> FleetLoops: ...
    @property
    def fleet(self) -> Fleet:
        """The :class:`Fleet` the loops were found on."""
    @property
    def names(self) -> list[str]:
        """The sessions' names, in order (as :attr:`Fleet.names`)."""
    @property
    def gamma(self) -> float:
        """The threshold γ."""
    @property
    def separation(self) -> Separation:
        """The separation the pairs within a session keep (:class:`Separation`)."""
    @property
    def metric_name(self) -> str:
        """The name of the metric the loops were found with (as :attr:`Loops.metric_name`)."""
    @property
    def pruning(self) -> Literal["hierarchy", "kd-tree"]:
        """The far-field pruning the scan used: ``"hierarchy"`` or ``"kd-tree"`` (``"auto"``
        resolved).
        """
    @property
    def warnings(self) -> list[str]:
        """Warnings about the result, as sentences (as :attr:`Loops.warnings`)."""
    @property
    def loops(self) -> Loops:
        """The result over the joint trajectory (:attr:`Fleet.joint`) as :class:`Loops`: fleet
        indices (:attr:`Fleet.starts`), fleet clock; component ids are those of
        :attr:`components`. Made on first use (a copy of the runs), then kept.
        """
    @property
    def components(self) -> Table:
        """The loop components of every block as a :class:`~inexact_loops.Table`, one row a
        component, by id (the ids of :attr:`loops`): ``id`` (int64); ``session_a``,
        ``session_b`` (int64, a ≤ b) and ``name_a``, ``name_b`` (str): the block, rows in session
        a, columns in session b; ``trivial`` (bool, a = b only); ``area_s2`` (float64, s², each
        session's own time cells: within a session, the half t ≤ t′ of a non-trivial
        component, as :attr:`Loops.components`); ``pair_count``, ``holes`` (int64); ``i_min``,
        ``i_max`` (poses of session a), ``j_min``, ``j_max`` (poses of session b), int64;
        ``t_min_s``, ``t_max_s``, ``t_prime_min_s``, ``t_prime_max_s`` (float64, seconds, each
        on its session's clock); ``closest_i``, ``closest_j`` (int64, poses of sessions a and
        b) and ``closest_distance`` (float64, the metric's unit); ``closest_i_x``,
        ``closest_i_y``, ``closest_i_z``, ``closest_j_x``, ``closest_j_y``, ``closest_j_z``
        (float64: where pose ``closest_i`` of session a and pose ``closest_j`` of session b are,
        their points' first three coordinates, 0 past a point's dimension).
        """
    def between_sessions(self) -> npt.NDArray[np.int64]:
        """The ids of the components between two different sessions, int64, increasing."""
    def session_pairs(self) -> Table:
        """The sparse overlap matrix as a :class:`~inexact_loops.Table`, one row per session pair
        (a, b), a ≤ b, with at least one loop component, in order of (a, b): ``session_a``,
        ``session_b`` (int64), ``name_a``, ``name_b`` (str), ``components`` (int64, in the
        block), ``pair_count`` (int64, lattice cells), ``area_s2`` (float64: the loop area α of
        the block, s²) and ``density`` (float64: ρ = α / (T_a T_b), T the sessions' spans: the
        share of the block within γ). For a = b the block is the session's whole square (both
        halves, the diagonal once), so ``area_s2`` is ∫τ over the session alone.
        """
    def overlap_matrix(self, *, sparse: bool = False) -> npt.NDArray[np.float64] | Any:
        """The overlap matrix: α between every two sessions, s², symmetric, rows and columns in
        the order of :attr:`names`; the diagonal is each session's α alone (``area_s2`` of
        :meth:`session_pairs`), 0 where two sessions never come within γ.

        Args:
            sparse: return a ``scipy.sparse.csr_array`` holding only the pairs that overlap
                (both triangles) instead of a dense numpy array: for large fleets, where the
                dense matrix takes 8 bytes per session pair.

        Returns:
            float64 array of shape ``(len(fleet), len(fleet))``, or a ``scipy.sparse.csr_array``.

        Raises:
            ImportError: ``sparse=True`` without scipy.
        """
    def loop_duration(self, session: _SessionKey | None = None) -> Table:
        """Loop duration τ per pose, split: ``own_s``, τ within the pose's session (that session's
        :meth:`Loops.loop_duration` alone), and ``other_s``, τ with the poses of every other
        session; seconds. A :class:`~inexact_loops.Table` of one row per pose, sessions in
        order: ``session`` (int64), ``pose`` (int64, in its session), ``t_s`` (float64, the
        session's clock), ``own_s`` and ``other_s`` (float64). Per session: ∫ own_s dt is the
        session's α alone; summed over the fleet, ∫ other_s dt is twice the α of all blocks
        between sessions (each block counts for the poses of both).

        Args:
            session: only this session's poses (its name or index); ``None``: every pose.

        Raises:
            KeyError: no session of that name. IndexError: an index out of range.
        """

@final
class StoreUpdatePlan:
    """The plan of an update of the fleet store in the folder ``path``, made from the store's
    small tables (settings and sessions; no tile is read): the tiles the update must scan, each
    of which :meth:`scan` scans on its own, on any machine that reads the new sessions and the
    store's folder; :meth:`FleetStore.update` with ``scanned=`` then applies them and writes the
    new state. The three steps are those :meth:`FleetStore.update` makes in one process;
    :func:`inexact_loops.dask.update_store` spreads the scans over a cluster's workers.

    The arguments are :meth:`FleetStore.update`'s (the same for the plan, the scans and the
    update). A plan holds no poses and no stored tile (O(sessions + blocks + tiles to scan)),
    and pickles.

    Example:
        >>> import tempfile, numpy as np, inexact_loops as il
        >>> x = np.arange(21) * 0.5
        >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
        >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
        >>> folder = tempfile.mkdtemp() + "/city"
        >>> _ = il.FleetStore.open(folder).update(add={"monday": monday}, gamma=1.0, block=8)
        >>> plan = il.StoreUpdatePlan(folder, add={"tuesday": tuesday})
        >>> len(plan), plan.tile_sessions[0]
        (10, ('monday', 'tuesday'))
        >>> scanned = [b for k in range(len(plan)) for b in plan.scan([k], add={"tuesday": tuesday})]
        >>> il.FleetStore.open(folder).update(add={"tuesday": tuesday}, scanned=scanned)["tiles_scanned"]
        10
    """
    def __new__(
        cls,
        path: str | PathLike[str],
        *,
        add: dict[str, _SessionSource]
        | list[tuple[str, _SessionSource]]
        | list[str | PathLike[str]]
        | list[tuple[str, _SessionSource] | str | PathLike[str]]
        | None = None,
        remove: list[str] | None = None,
        gamma: float | None = None,
        metric: str | _MetricLike | None = None,
        separation: Separation | float | Literal["auto", "none"] | None = "auto",
        block: int | None = None,
        sampler: _SamplerName | str | None = None,
        rate: float | None = None,
        budget: int | None = None,
        seed: int | None = None,
        between_only: bool = False,
        skip_trivial: bool = False,
        format: str | None = None,
        axes: tuple[int, int] | None = None,
        topic: str | None = None,
        time: Literal["header", "log", "publish"] | str | None = None,
        frames: tuple[str, str] | None = None,
        rate_hz: float | None = None,
        drop_duplicate_stamps: bool = False,
        quaternion_tolerance: float | None = None,
    ) -> StoreUpdatePlan:
        """"""
    def __len__(self) -> int:
        """"""
    @property
    def tile_sessions(self) -> list[tuple[str, str]]:
        """The names of the two sessions of each tile to scan (the same name twice for a tile of
        one session), in tile order.
        """
    @property
    def last_update(self) -> dict[str, Any]:
        """What the update will do, by name (``added``, ``replaced``, ``unchanged``, ``removed``),
        ``tiles_scanned``, and ``changed`` (False: the update writes nothing); the other counts
        are set when it is applied.
        """
    def scan(
        self,
        tiles: list[int],
        *,
        add: dict[str, _SessionSource]
        | list[tuple[str, _SessionSource]]
        | list[str | PathLike[str]]
        | list[tuple[str, _SessionSource] | str | PathLike[str]]
        | None = None,
        metric: str | _MetricLike | None = None,
        threads: int | None = None,
        format: str | None = None,
        axes: tuple[int, int] | None = None,
        topic: str | None = None,
        time: Literal["header", "log", "publish"] | str | None = None,
        frames: tuple[str, str] | None = None,
        rate_hz: float | None = None,
        drop_duplicate_stamps: bool = False,
        quaternion_tolerance: float | None = None,
    ) -> list[bytes]:
        """Scans the tiles ``tiles`` (indices, ``range(len(plan))``) of the plan: the sessions the
        update adds or replaces that they hold are read from ``add`` (the plan's, or only those
        sessions), the stored ones from the store's pose files; each is checked against the
        plan (its fingerprint) before the scan.

        Args:
            tiles: indices of the plan's tiles.
            add, metric, format, ...: as given to the plan.
            threads: worker threads; ``None`` uses one per core. Results do not depend on it.

        Returns:
            One ``bytes`` per tile, in the order of ``tiles``: what ``FleetStore.update(scanned=)``
            takes.

        Raises:
            InvalidParameterError: a tile out of range, a session to scan not in ``add``, or poses
                that are not those planned.
            OSError, LoopsIOError: a file that cannot be read.
        """
    def __reduce__(self) -> tuple[Callable[[bytes], StoreUpdatePlan], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> StoreUpdatePlan: ...

@final
class FleetStore:
    """A fleet's loops kept in a folder and updated at the cost of the new data: each
    :meth:`update` adds sessions (replacing those of the same name) and removes others,
    scans only the tiles that hold a new or replaced session, merges again from the stored tile
    summaries and redraws the samples by keyed draws. After any sequence of updates the tables
    are those of :func:`find_fleet_loops` and :func:`sample_fleet` over the stored sessions in
    name order, whatever the order of the updates.

    The folder is what ``loops fleet --store DIR`` keeps: Parquet tables that pandas, pyarrow
    and DuckDB read (``store.json`` names the current state, ``state-NNNNNN/``, holding
    ``sessions``, ``components``, ``session_pairs``, ``loop_duration`` and ``samples``,
    ``.parquet`` each, and the folders ``tiles/`` and ``merges/`` of the stored tiles and
    session pairs' merges by part); each update makes a new state (linking the parts it keeps,
    writing its new tiles and merges as one more each) and then points at it, so a reader or a
    killed update sees the old state or the new one. Made by :meth:`open` and :meth:`update`.

    Example:
        Monday drives out along a street; Tuesday's drive, added the next day, comes back along
        it half a metre aside: the store's answer is the fleet's.

        >>> import tempfile, numpy as np, inexact_loops as il
        >>> x = np.arange(21) * 0.5
        >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
        >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
        >>> folder = tempfile.mkdtemp() + "/city"
        >>> store = il.FleetStore.open(folder)
        >>> store.update(add=[("monday", monday)], gamma=1.0, separation=None, block=8)["added"]
        ['monday']
        >>> update = store.update(add=[("tuesday", tuesday)])
        >>> update["added"], update["tiles_kept"] > 0
        (['tuesday'], True)
        >>> store.names, store.added.tolist()  # Tuesday's own component and the one with Monday
        (['monday', 'tuesday'], [1, 2])
        >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
        >>> scratch = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
        >>> np.array_equal(store.overlap_matrix(), scratch.overlap_matrix())
        True
    """

    DEFAULT_BLOCK: ClassVar[int]
    @staticmethod
    def open(path: str | PathLike[str]) -> FleetStore:
        """The store in the folder ``path``: its current state, or, for a missing or empty folder,
        a store that the first :meth:`update` makes there (with the settings it gives). Opening
        reads the state's small tables and where its tiles lie; a stored tile is decoded (and
        checked) when an update or a draw first needs it.

        Raises:
            FileNotFoundError: ``path`` holds files but no store (no ``store.json``).
            LoopsIOError: a file of the store that cannot be read back (named).
        """
    def update(
        self,
        *,
        add: dict[str, _SessionSource]
        | list[tuple[str, _SessionSource]]
        | list[str | PathLike[str]]
        | list[tuple[str, _SessionSource] | str | PathLike[str]]
        | None = None,
        remove: list[str] | None = None,
        gamma: float | None = None,
        metric: str | _MetricLike | None = None,
        separation: Separation | float | Literal["auto", "none"] | None = "auto",
        block: int | None = None,
        sampler: _SamplerName | str | None = None,
        rate: float | None = None,
        budget: int | None = None,
        seed: int | None = None,
        between_only: bool = False,
        skip_trivial: bool = False,
        threads: int | None = None,
        format: str | None = None,
        axes: tuple[int, int] | None = None,
        topic: str | None = None,
        time: Literal["header", "log", "publish"] | str | None = None,
        frames: tuple[str, str] | None = None,
        rate_hz: float | None = None,
        drop_duplicate_stamps: bool = False,
        quaternion_tolerance: float | None = None,
        scanned: list[bytes] | None = None,
    ) -> dict[str, Any]:
        """Adds the sessions ``add`` (replacing stored ones of the same name) and removes the
        sessions named in ``remove``, in one update written atomically; a session given with the
        content it has in the store changes nothing. Scans only the tiles that hold an added or
        replaced session (reading the stored sessions they meet from the store's pose files).
        Starts from the store as this object holds it while the folder still holds that state
        (another process may have updated it since: the folder is then read again).

        The settings are fixed when the store is made: the first update gives ``gamma`` and
        whichever others it wants; a later one gives none (the store's own) or all of them as
        the store has them (a check: otherwise an error, the store unchanged).

        Args:
            add: sessions as :class:`Fleet` takes them (a dict ``{name: session}``, ``(name,
                session)`` pairs or paths named by their stem), read with the reading keywords.
            remove: names of stored sessions to remove.
            gamma: γ, in the metric's unit.
            metric: a metric name or object (not a callable); ``None``: the sessions' own.
            separation: within each session, as in :func:`find_fleet_loops`.
            block: poses per block of a session; ``None``: :attr:`DEFAULT_BLOCK`.
            sampler, rate, budget, seed, skip_trivial, between_only: the samples of every state,
                as :func:`sample_fleet` draws them (a component sampler); ``None``: no samples.
            threads: worker threads; ``None`` uses one per core. Results do not depend on it.
            format, axes, topic, time, frames, rate_hz, drop_duplicate_stamps,
                quaternion_tolerance: how paths are read, as in :class:`Fleet`.
            scanned: the update's new tiles scanned elsewhere (:meth:`StoreUpdatePlan.scan` of
                every tile of the :class:`StoreUpdatePlan` with the same arguments, in any
                order); ``None``: scanned here. The update then checks that they are exactly its
                plan's tiles, of this state, and scans nothing.

        Returns:
            What this update did, as :attr:`last_update` holds it. An update of a store that
            changes nothing (nothing given or removed, or every session given stored with this
            content) says ``changed`` False and writes nothing: no new state, no file or time of
            the folder touched, and :attr:`last_update` still that of the last update that
            changed the store.

        Raises:
            InvalidParameterError: no ``gamma`` for a new store; settings other than the store's;
                a name given twice, or removed and given, or removed but not stored; a session of
                another dimension or manifold. The store is then unchanged.
            OSError, LoopsIOError: a path that cannot be read; a store file that cannot be read
                or written (named; a stored tile the update reads, by part file and row).
        """
    def __len__(self) -> int: ...
    @property
    def path(self) -> Path:
        """The store's folder."""
    def __reduce__(self) -> tuple[Callable[[str | PathLike[str]], FleetStore], tuple[Path]]:
        """Pickles as its folder: unpickling opens the store there (:meth:`open`), in the state the
        folder holds then, so a store crosses to another process (a process pool, a Dask worker)
        that sees the same folder, without copying its tables."""
    @property
    def state_path(self) -> Path | None:
        """The folder of the current state (``path / "state-NNNNNN"``), whose ``.parquet`` tables
        are the store's; ``None`` before the first update.
        """
    @property
    def names(self) -> list[str]:
        """The stored sessions' names, in name order (the order of the session indices of the
        tables).
        """
    @property
    def gamma(self) -> float | None:
        """γ; ``None`` before the first update."""
    @property
    def metric_name(self) -> str | None:
        """The name of the store's metric; ``None`` before the first update."""
    @property
    def separation(self) -> Separation | None:
        """The separation within a session (:class:`Separation`); ``None`` before the first update."""
    @property
    def block(self) -> int | None:
        """Poses per block of a session; ``None`` before the first update."""
    @property
    def sampler(self) -> str | None:
        """The name of the store's sampler; ``None`` for a store without samples."""
    @property
    def last_update(self) -> dict[str, Any]:
        """What the last update that changed the store did: a dict of ``added``, ``replaced``,
        ``unchanged``, ``removed`` (session names, each in name order), ``tiles_scanned``,
        ``tiles_kept``, ``tiles_dropped`` (int) and ``changed`` (bool: whether it added,
        replaced or removed a session).
        """
    @property
    def components(self) -> Table:
        """The loop components as a :class:`~inexact_loops.Table`, with the columns of
        :attr:`FleetLoops.components` (sessions by index in :attr:`names`).
        """
    @property
    def added(self) -> npt.NDArray[np.int64]:
        """The ids of the components the last update added: those of a session it added or
        replaced (with itself or another), int64, increasing.
        """
    def near(self, place: npt.ArrayLike, *, radius: float | None = None) -> Table:
        """Which sessions pass near a place, and when: per session, the maximal runs of
        consecutive poses within ``radius`` of ``place`` (poses read from the store's pose
        files). A place lies in the map plane of the positions' first two coordinates (x, y of
        Euclidean points, SE(2) and SE(3) poses), with the plane's distance; a pose is within
        ``radius`` of a polygon when inside it (even-odd rule) or within ``radius`` of its
        boundary.

        Args:
            place: a point ``(x, y)`` or a polygon, an array of shape ``(n, 2)`` of its vertices
                in order (n ≥ 3; the last joins the first).
            radius: in the plane's unit (metres); ``None``: :attr:`gamma`.

        Returns:
            A :class:`~inexact_loops.Table` with a row per pass, in session order and time
            order: ``session`` (index in :attr:`names`), ``name``, ``i_start``, ``i_end`` (its
            first and last pose, both within the radius), ``t_start_s``, ``t_end_s`` (their
            times on the session's clock).

        Raises:
            InvalidParameterError: a place of another shape, a polygon of fewer than 3
                vertices, a coordinate that is not finite, a negative radius, sessions without
                a map plane.

        Example:
            >>> import tempfile, numpy as np, inexact_loops as il
            >>> x = np.arange(21) * 0.5
            >>> store = il.FleetStore.open(tempfile.mkdtemp() + "/city")
            >>> out = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
            >>> _ = store.update(add={"out": out}, gamma=1.0, separation=None)
            >>> passes = store.near((5.0, 0.3), radius=1.0)
            >>> passes["name"].tolist(), passes["i_start"].tolist(), passes["i_end"].tolist()
            (['out'], [9], [11])
            >>> store.near([(0, -1), (2, -1), (2, 1), (0, 1)])["t_end_s"].tolist()  # within γ
            [6.0]
        """
    def revisits(self, session: _SessionKey) -> Table:
        """The sessions that revisit ``session``: those sharing at least one loop component with
        it (other than itself), read from the overlap matrix.

        Args:
            session: its name or index.

        Returns:
            A :class:`~inexact_loops.Table` with a row per revisiting session, in session
            order: ``session`` (index in :attr:`names`), ``name``, ``components`` (shared),
            ``pair_count`` (pose pairs within γ between the two), ``area_s2``, ``density``
            (their block of :meth:`session_pairs`).

        Raises:
            KeyError: no session of that name. IndexError: an index out of range.

        Example:
            >>> import tempfile, numpy as np, inexact_loops as il
            >>> x = np.arange(21) * 0.5
            >>> store = il.FleetStore.open(tempfile.mkdtemp() + "/city")
            >>> there = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
            >>> back = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
            >>> _ = store.update(add={"there": there, "back": back}, gamma=1.0, separation=None)
            >>> store.revisits("there")["name"].tolist()
            ['back']
        """
    def session_pairs(self) -> Table:
        """The sparse overlap matrix as a :class:`~inexact_loops.Table`, as
        :meth:`FleetLoops.session_pairs`.
        """
    def overlap_matrix(self, *, sparse: bool = False) -> npt.NDArray[np.float64] | Any:
        """The overlap matrix, as :meth:`FleetLoops.overlap_matrix`."""
    def loop_duration(self, session: _SessionKey | None = None) -> Table:
        """Loop duration τ per pose, split into own and other sessions, as
        :meth:`FleetLoops.loop_duration` (times read from the store's pose files).

        Args:
            session: only this session's poses (its name or index); ``None``: every pose.

        Raises:
            KeyError: no session of that name. IndexError: an index out of range.
        """
    @property
    def samples(self) -> Table:
        """The samples of the current state as a :class:`~inexact_loops.Table`, with the columns
        of :attr:`FleetSamples.table`; no rows for a store without a sampler.
        """

@final
class FleetSamples:
    """The samples of a fleet's loops, each naming both its sessions (name, pose, time on the
    session's clock). Returned by :func:`sample_fleet`.
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes, Fleet], FleetSamples], tuple[bytes, Fleet]]: ...
    @classmethod
    def _from_state(cls, state: bytes, fleet: Fleet) -> FleetSamples: ...
    def __len__(self) -> int: ...
    @property
    def samples(self) -> Samples:
        """The same samples as :class:`Samples` on the joint trajectory (:attr:`Fleet.joint`:
        fleet indices ``i``, ``j`` and the fleet clock), e.g. for :func:`sample_quality` against
        :attr:`FleetLoops.loops`.
        """
    @property
    def fleet(self) -> Fleet:
        """The :class:`Fleet` sampled."""
    @property
    def sampler(self) -> str:
        """The sampler's name."""
    @property
    def groups(self) -> int:
        """Number of groups sampled from (components with a pair; 0 for σ_α and the baselines)."""
    @property
    def available(self) -> int:
        """Number of candidates the sampler chose from."""
    @property
    def warnings(self) -> list[str]:
        """Warnings, as sentences (as :attr:`Samples.warnings`)."""
    @property
    def table(self) -> Table:
        """The samples as a :class:`~inexact_loops.Table`, one row a sample in order of the fleet
        index of the earlier pose, with the columns of ``loops fleet``'s ``samples.csv`` in its
        order (less ``sampler``: :attr:`sampler`): ``session_a`` and ``session_b`` (int64, the
        sessions of the two poses, a ≤ b; a = b within a session), ``name_a`` and ``name_b``
        (str), ``i`` and ``j`` (int64, the poses in sessions a and b), ``t_s`` and ``t_prime_s``
        (float64, seconds, each on its session's clock), ``component`` (int64, the component id of
        :attr:`FleetLoops.components`, −1 for a baseline's pair outside S_γ) and ``distance``
        (float64, δ between the poses).
        """
    def to_pandas(self) -> pandas.DataFrame:
        """:attr:`table` as a ``pandas.DataFrame``.

        Raises:
            ImportError: pandas is not installed (it is not a dependency of the library).
        """

def find_fleet_loops(
    fleet: Fleet,
    *,
    gamma: float,
    metric: _MetricArg = None,
    separation: Separation | float | Literal["auto", "none"] | None = "auto",
    pruning: Literal["auto", "hierarchy", "kd-tree"] | str = "auto",
    chunk_radius: float | None = None,
    threads: int | None = None,
) -> FleetLoops:
    """Finds every inexact loop of a fleet at threshold ``gamma`` exactly: for every pair of
    sessions (a, b), a ≤ b, the pairs (t_a, t′_b) within γ — a *block* of the fleet's plane —
    grouped into loop components, 4-connected on each block's own lattice, never across
    sessions. A block (a, a) is session a alone (with the revisit separation, component for
    component :func:`find_loops` of that session); a block (a, b), a < b, has no diagonal and
    no separation, and each of its components is one place where the two sessions overlap.

    The same engine as :func:`find_loops`, on the sessions laid one after another; with
    Euclidean positions of 1 to 3 coordinates the far field is pruned by a KD-tree over chunks of
    the paths, so that session pairs that never come within γ cost no distance evaluation.

    Args:
        fleet: a :class:`Fleet`.
        gamma: the distance threshold γ > 0, in the metric's unit.
        metric: as in :func:`find_loops`; ``None`` takes the sessions' own
            (:attr:`Trajectory.metric_name`; they must agree).
        separation: within each session, as in :func:`find_loops` (``"auto"``: 4 γ of path;
            ``None``: the paper's S_γ). Pairs of different sessions are always kept.
        pruning: ``"auto"`` (the KD-tree where it applies, else the hierarchy), ``"hierarchy"``
            (the time-ordered ball hierarchy, any metric) or ``"kd-tree"`` (Euclidean positions
            of 1 to 3 coordinates). The result does not depend on it.
        chunk_radius: the largest radius of a chunk of path in the KD-tree, in the metric's
            unit; ``None``: γ. The result does not depend on it.
        threads: worker threads; ``None`` uses one per core. Results do not depend on it.

    Returns:
        :class:`FleetLoops`.

    Raises:
        InvalidParameterError: as :func:`find_loops`; an unknown pruning; ``"kd-tree"`` with a
            metric it does not serve; sessions measured by different metrics and no ``metric=``.

    Warns:
        DiagonalBrokenWarning, NoLoopsWarning: as :func:`find_loops`, for the fleet's sessions.

    Example:
        Monday drives out along a street; Tuesday drives back along it, half a metre aside: one
        place where the two sessions overlap.

        >>> import numpy as np, inexact_loops as il
        >>> x = np.arange(21) * 0.5
        >>> monday = il.Trajectory(np.arange(21.0), np.c_[x, 0 * x])
        >>> tuesday = il.Trajectory(100 + np.arange(21.0), np.c_[x[::-1], 0 * x + 0.5])
        >>> fleet = il.Fleet({"monday": monday, "tuesday": tuesday})
        >>> loops = il.find_fleet_loops(fleet, gamma=1.0, separation=None)
        >>> c = loops.components
        >>> between = c["session_a"] != c["session_b"]
        >>> c["name_a"][between].tolist(), c["name_b"][between].tolist(), c["pair_count"][between].tolist()
        (['monday'], ['tuesday'], [61])
        >>> loops.overlap_matrix()
        array([[93.5, 57.5],
               [57.5, 93.5]])
    """

def sample_fleet(
    loops: FleetLoops,
    sampler: _SamplerName | str | None = None,
    *,
    rate: float | None = None,
    budget: int | None = None,
    seed: int,
    between_only: bool = False,
    metric: _MetricArg = None,
    threads: int | None = None,
    skip_trivial: bool = False,
    lio_sam_keyframe_step: float | None = None,
    lio_sam_period_s: float | None = None,
    lio_sam_min_age_s: float | None = None,
    hdl_keyframe_step: float | None = None,
    hdl_min_travel: float | None = None,
    hdl_edge_spacing: float | None = None,
    cartographer_min_gap_s: float | None = None,
    time_gap_s: float | None = None,
) -> FleetSamples:
    """Samples the loops of a fleet (paper, Sec. 5) with one budget over all components of all
    blocks, as :func:`sample` samples the components of one trajectory: P1–P3 hold across the
    fleet. With ``between_only``, only the components between different sessions are sampled:
    the pairs that tie sessions together (map merging, multi-session SLAM).

    Args:
        loops: :class:`FleetLoops` (from :func:`find_fleet_loops`).
        sampler, rate, budget, seed, metric, threads, skip_trivial: as in :func:`sample` (a
            baseline rule runs over the joint trajectory, :attr:`Fleet.joint`).
        between_only: sample only the components between two different sessions (not with a
            baseline, whose rule knows no components).
        lio_sam_keyframe_step, lio_sam_period_s, lio_sam_min_age_s, hdl_keyframe_step,
            hdl_min_travel, hdl_edge_spacing, cartographer_min_gap_s, time_gap_s: as in
            :func:`sample`.

    Returns:
        :class:`FleetSamples`.

    Raises:
        InvalidParameterError: as :func:`sample`; ``between_only`` with a baseline.

    Warns:
        EmptySampleWarning, SampleBudgetWarning: as :func:`sample`.

    Example:
        >>> import inexact_loops as il
        >>> fleet = il.urban_fleet(vehicles=3, duration_s=300.0, seed=1)
        >>> loops = il.find_fleet_loops(fleet, gamma=20.0)
        >>> samples = il.sample_fleet(loops, "one", budget=50, seed=0, between_only=True)
        >>> rows = samples.table
        >>> bool((rows["session_a"] != rows["session_b"]).all()), len(samples)
        (True, 50)
    """

def urban_fleet(
    *,
    vehicles: int | None = None,
    days: int | None = None,
    start_spread_s: float | None = None,
    duration_s: float | None = None,
    rate_hz: float | None = None,
    city_size_m: float | None = None,
    block_m: float | None = None,
    min_speed_mps: float | None = None,
    max_speed_mps: float | None = None,
    stop_probability: float | None = None,
    min_stop_s: float | None = None,
    max_stop_s: float | None = None,
    lane_offset_m: float | None = None,
    lateral_noise_m: float | None = None,
    seed: int | None = None,
    district_m: float | None = None,
    district_dwell_s: float | None = None,
) -> Fleet:
    """A seeded synthetic fleet: ``vehicles`` cars driving every one of ``days`` days in one city
    (:func:`urban_drive`'s), each session with its own seed, start time (within
    ``start_spread_s`` of midnight, day d starting at d × 86,400 s) and, with districts, its own
    first district. Sessions are named ``car<v>-day<d>`` (zero-padded), vehicles first within a
    day. The same seed gives the same fleet on any number of threads.

    Every argument left as ``None`` takes the library default: 10 vehicles, one day, 10-minute
    drives (``duration_s=600``) in :func:`urban_drive`'s 1 km² city, starts spread over an hour.
    The other keywords are :func:`urban_drive`'s, for every session's drive; ``seed`` is the
    fleet's, from which each session's own is drawn.

    Raises:
        InvalidParameterError: no vehicles or days, a negative spread, or a drive parameter out
            of range (named).

    Example:
        >>> import inexact_loops as il
        >>> fleet = il.urban_fleet(vehicles=3, days=2, duration_s=120.0, seed=7)
        >>> len(fleet), fleet.names[4], bool(fleet.session(4).timestamps[0] >= 86_400.0)
        (6, 'car1-day1', True)
    """

_MetricName = str | _MetricLike | None

@final
class SessionBlocks:
    """What planning tiles needs of one session, learnt by whoever reads it: its pose count, its
    span, and the bounding balls of its blocks of ``block`` consecutive poses under the metric
    it was measured with. Made by :func:`session_blocks`; :func:`plan_tiles` takes one per
    session. Pickles (as :meth:`to_bytes` and the metric's name).
    """

    def __new__(cls, data: bytes, metric: str) -> SessionBlocks: ...
    def __len__(self) -> int: ...
    def __reduce__(self) -> tuple[type[SessionBlocks], tuple[bytes, str]]: ...
    @property
    def poses(self) -> int:
        """Number of poses of the session."""
    @property
    def span_s(self) -> float:
        """The session's span t_{n−1} − t_0, seconds."""
    @property
    def block(self) -> int:
        """Poses per block."""
    @property
    def metric_name(self) -> str:
        """The name of the metric the balls' radii are measured with."""
    def to_bytes(self) -> bytes:
        """The blocks as bytes (a tag, a format version, then the fields)."""
    def coarsened(self, factor: int) -> SessionBlocks:
        """The same session in blocks ``factor`` times larger, bounded from these blocks' balls
        (each ball still holds every pose of its block): a planner learns every session's
        length first and then chooses the tiles' size without reading the sessions again.
        O(blocks) distances.

        Raises:
            InvalidParameterError: a factor of 0.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> drive = il.Trajectory(np.arange(10.0), np.c_[np.arange(10.0), np.zeros(10)])
            >>> coarse = il.tiles.session_blocks(drive, block=2).coarsened(3)
            >>> coarse.block, len(coarse), coarse.poses
            (6, 2, 10)
        """

def session_blocks(session: Trajectory, *, block: int, metric: _MetricName = None) -> SessionBlocks:
    """Cuts a session into blocks of ``block`` consecutive poses and bounds each by a ball: what
    :func:`plan_tiles` needs of the session, without its poses. O(poses) distances.

    Args:
        session: a :class:`Trajectory`.
        block: poses per block (the tiles' side), at least 1.
        metric: a metric name or an ``inexact_loops.metrics`` object (not a callable);
            ``None``: the session's own (:attr:`Trajectory.metric_name`).

    Returns:
        :class:`SessionBlocks`.

    Raises:
        InvalidParameterError: a block of 0 poses; an unknown metric.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> drive = il.Trajectory(np.arange(10.0), np.c_[np.arange(10.0), np.zeros(10)])
        >>> blocks = il.tiles.session_blocks(drive, block=4)
        >>> blocks.poses, len(blocks), blocks.span_s, blocks.metric_name
        (10, 3, 9.0, 'euclidean')
    """

@final
class Tile:
    """A tile of a fleet's plane: rows ``rows`` of session ``sessions[0]`` against columns
    ``columns`` of session ``sessions[1]``, each a half-open range ``(start, end)`` of *fleet
    indices* (the sessions' poses numbered one session after another, as :attr:`Fleet.starts`).
    Made by :func:`plan_tiles`; pickles; equal tiles are equal and hash alike.
    """

    def __new__(
        cls, sessions: tuple[int, int], rows: tuple[int, int], columns: tuple[int, int]
    ) -> Tile: ...
    def __reduce__(
        self,
    ) -> tuple[type[Tile], tuple[tuple[int, int], tuple[int, int], tuple[int, int]]]: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    @property
    def sessions(self) -> tuple[int, int]:
        """The session pair ``(a, b)``, a ≤ b."""
    @property
    def rows(self) -> tuple[int, int]:
        """The rows' fleet indices, ``(start, end)``, end excluded (poses of session a)."""
    @property
    def columns(self) -> tuple[int, int]:
        """The columns' fleet indices, ``(start, end)``, end excluded (poses of session b)."""

def plan_tiles(
    sessions: list[SessionBlocks], *, gamma: float, metric: _MetricName = None
) -> list[Tile]:
    """The tiles of a fleet whose sessions (in fleet order) have these blocks: every pair of a
    row block and a column block (a ≤ b; on or above the diagonal within a session) whose balls
    come within γ. Every pair of poses within γ lies in one of them; tiles left out hold none.

    Args:
        sessions: one :class:`SessionBlocks` per session, in fleet order, cut into blocks of one
            size.
        gamma: the distance threshold γ > 0.
        metric: ``None``: the metric the blocks were measured with (they must agree); or a name
            or metric object, which must be that metric.

    Returns:
        list of :class:`Tile`, by session pair, then row block, then column block.

    Raises:
        InvalidParameterError: no sessions; blocks of different sizes, dimensions or metrics;
            an invalid γ.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> out = il.Trajectory(np.arange(6.0), np.c_[np.arange(6.0), np.zeros(6)])
        >>> far = il.Trajectory(np.arange(4.0), np.c_[np.arange(4.0), np.full(4, 100.0)])
        >>> blocks = [il.tiles.session_blocks(s, block=3) for s in (out, far)]
        >>> [t.sessions for t in il.tiles.plan_tiles(blocks, gamma=1.0)]  # far meets no one
        [(0, 0), (0, 0), (0, 0), (1, 1), (1, 1), (1, 1)]
    """

@final
class TileSummary:
    """What scanning one tile returns: the statistics of the tile's provisional components and the
    runs on its edges, a few hundred bytes to a few kilobytes. Made by :func:`scan_tile`; merged
    by :func:`merge_tiles`. Pickles as :meth:`to_bytes`.
    """

    def __new__(cls, data: bytes) -> TileSummary: ...
    def __reduce__(self) -> tuple[type[TileSummary], tuple[bytes]]: ...
    @staticmethod
    def from_bytes(data: bytes) -> TileSummary:
        """The summary from :meth:`to_bytes`; as the constructor."""
    def to_bytes(self) -> bytes:
        """The summary as bytes: a 4-byte tag, the format version, then the fields (MessagePack)."""
    @property
    def tile(self) -> Tile:
        """The tile."""
    @property
    def component_count(self) -> int:
        """Number of provisional components."""
    @property
    def edge_count(self) -> int:
        """Number of runs on the tile's edges."""

def scan_tile(
    tile: Tile,
    session_a: Trajectory,
    session_b: Trajectory | None = None,
    *,
    starts: tuple[int, int],
    gamma: float,
    metric: _MetricName = None,
    separation: Separation | float | Literal["auto", "none"] | None = "auto",
    threads: int | None = None,
    duration: bool = False,
    runs: bool = False,
) -> (
    TileSummary
    | tuple[TileSummary, TileDuration]
    | tuple[TileSummary, TileRuns]
    | tuple[TileSummary, TileDuration, TileRuns]
):
    """Scans one tile from its two sessions alone — what a worker that read only those sessions
    can do — without the GIL: the same cells as :func:`find_fleet_loops` finds in the tile,
    summarised for :func:`merge_tiles`; from the same scan, as asked, the tile's share of the loop
    duration τ (for :func:`session_loop_duration`) and its runs (for :func:`draw_tile` to offer a
    draw's pairs without rescanning the tile).

    Args:
        tile: a :class:`Tile` of :func:`plan_tiles`.
        session_a: the :class:`Trajectory` of session ``tile.sessions[0]``.
        session_b: that of session ``tile.sessions[1]``; ``None`` for a tile within one session.
        starts: the two sessions' first fleet indices ``(start_a, start_b)``: the poses of the
            sessions before each in the fleet (the same twice within one session).
        gamma: the distance threshold γ > 0.
        metric: a metric name or an ``inexact_loops.metrics`` object (not a callable); ``None``:
            ``session_a``'s own.
        separation: within a session, as in :func:`find_fleet_loops` (``"auto"``: 4 γ of path;
            ``None``: none), measured over the whole session.
        threads: worker threads; ``None``: one per core.
        duration: also return the tile's :class:`TileDuration`.
        runs: also return the tile's :class:`TileRuns`.

    Returns:
        :class:`TileSummary` alone, or with ``duration`` or ``runs`` a tuple of it and what was
        asked, in that order: ``(TileSummary, TileDuration, TileRuns)`` with both.

    Raises:
        InvalidParameterError: a tile outside its sessions or below the diagonal, sessions of
            different dimensions or manifolds, an invalid γ or separation, a metric that does
            not fit the poses.

    Examples:
        >>> import inexact_loops as il
        >>> drive = il.Trajectory([0.0, 1.0, 2.0, 3.0], [[0, 0], [5, 0], [5, 5], [0, 0.1]])
        >>> tile = il.tiles.plan_tiles([il.tiles.session_blocks(drive, block=4)], gamma=0.5)[0]
        >>> summary, share = il.tiles.scan_tile(tile, drive, starts=(0, 0), gamma=0.5, separation=None, duration=True)
        >>> summary.component_count, share.tile == tile
        (5, True)
    """

def scan_tiles(
    jobs: list[tuple[Tile, Trajectory, Trajectory | None, tuple[int, int]]],
    *,
    gamma: float,
    metric: _MetricName = None,
    separation: Separation | float | Literal["auto", "none"] | None = "auto",
    threads: int | None = None,
    duration: bool = False,
    runs: bool = False,
) -> list[
    TileSummary
    | tuple[TileSummary, TileDuration]
    | tuple[TileSummary, TileRuns]
    | tuple[TileSummary, TileDuration, TileRuns]
]:
    """Scans a group of tiles, in parallel and without the GIL: each the scan :func:`scan_tile`
    makes, the balls that bound each side of a tile made once for the tiles of the group that
    share it (a session given as the same :class:`Trajectory` object to several tiles is bounded
    once, not once a tile).

    Args:
        jobs: ``(tile, session_a, session_b, starts)`` per tile, as :func:`scan_tile` takes them
            (``session_b`` ``None`` for a tile within one session).
        gamma: the distance threshold γ > 0.
        metric: a metric name or an ``inexact_loops.metrics`` object (not a callable); ``None``:
            the first ``session_a``'s own.
        separation: as in :func:`scan_tile`.
        threads: worker threads; ``None``: one per core.
        duration: also return each tile's :class:`TileDuration`.
        runs: also return each tile's :class:`TileRuns`.

    Returns:
        What :func:`scan_tile` returns for each tile, in the order of ``jobs``.

    Raises:
        InvalidParameterError: as :func:`scan_tile`, for the first tile in order that has it;
            sessions whose own metrics differ when ``metric`` is ``None``.

    Examples:
        >>> import inexact_loops as il
        >>> drive = il.Trajectory([0.0, 1.0, 2.0, 3.0], [[0, 0], [5, 0], [5, 5], [0, 0.1]])
        >>> plan = il.tiles.plan_tiles([il.tiles.session_blocks(drive, block=2)], gamma=0.5)
        >>> jobs = [(t, drive, None, (0, 0)) for t in plan]
        >>> summaries = il.tiles.scan_tiles(jobs, gamma=0.5, separation=None)
        >>> [s.component_count for s in summaries] == [
        ...     il.tiles.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None).component_count for t in plan]
        True
    """

@final
class TileMerge:
    """A partial merge of tiles: the components of the tiles it holds with every join between them
    made, and only the edge runs that face tiles it does not hold yet. Merges of disjoint sets
    of tiles merge again (:func:`merge_tiles`), in any grouping and order; the merge of every
    tile of a plan :meth:`finish`\\ es into the fleet's components. Pickles as :meth:`to_bytes`.
    """

    def __new__(cls, data: bytes) -> TileMerge: ...
    def __reduce__(self) -> tuple[type[TileMerge], tuple[bytes]]: ...
    @staticmethod
    def from_bytes(data: bytes) -> TileMerge:
        """The merge from :meth:`to_bytes`; as the constructor."""
    def to_bytes(self) -> bytes:
        """The merge as bytes (as :meth:`TileSummary.to_bytes`, another tag)."""
    @property
    def tile_count(self) -> int:
        """Number of tiles merged."""
    @property
    def component_count(self) -> int:
        """Number of components (final ones and those that may still grow)."""
    @property
    def open_edge_count(self) -> int:
        """Number of edge runs still open (facing tiles not merged yet)."""
    def finish(self, sessions: list[SessionBlocks], *, names: list[str]) -> TiledFleetLoops:
        """The fleet's loop components from the merge of every tile of a plan: numbered, and with
        the same tables, as :func:`find_fleet_loops` gives them (areas to rounding).

        Args:
            sessions: the :class:`SessionBlocks` the plan was made from, in fleet order (their
                pose counts give the fleet indices, their spans the densities).
            names: the sessions' names, in fleet order.

        Returns:
            :class:`TiledFleetLoops`.

        Raises:
            InvalidParameterError: as many names as sessions are needed; a merge whose
                components do not lie in these sessions, or whose counts do not fit together.
        """

def merge_tiles(parts: list[TileSummary | TileMerge]) -> TileMerge:
    """Merges tile summaries and partial merges of disjoint sets of tiles into one partial merge,
    without the GIL: O(their components + open edge runs + tiles). See :class:`TileMerge`.

    Args:
        parts: :class:`TileSummary` and :class:`TileMerge` objects, in any order.

    Returns:
        :class:`TileMerge`.

    Raises:
        InvalidParameterError: a tile in two parts; parts that do not fit together.
        TypeError: a part of another type.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> s = 0.2 * np.arange(40)  # a circle and a third, the second lap over the first
        >>> drive = il.Trajectory(s, np.c_[np.cos(s), np.sin(s)])
        >>> blocks = [il.tiles.session_blocks(drive, block=8)]
        >>> tiles = il.tiles.plan_tiles(blocks, gamma=0.5)
        >>> parts = [il.tiles.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None) for t in tiles]
        >>> merged = il.tiles.merge_tiles([il.tiles.merge_tiles(parts[:2]), *parts[2:]])
        >>> loops = merged.finish(blocks, names=["drive"])
        >>> fleet = il.find_fleet_loops(il.Fleet({"drive": drive}), gamma=0.5, separation=None)
        >>> loops.components["pair_count"].tolist() == fleet.components["pair_count"].tolist()
        True
    """

@final
class TiledFleetLoops:
    """The loops of a fleet merged from tiles (:meth:`TileMerge.finish`): the tables of
    :class:`FleetLoops` that the tiles give — components, the session pairs and the overlap
    matrix — equal to :func:`find_fleet_loops`' (areas to rounding). Not the runs themselves:
    they stayed on the machines that scanned the tiles.
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Callable[[bytes], TiledFleetLoops], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> TiledFleetLoops: ...
    def draw(
        self,
        sampler: str | None = None,
        *,
        rate: float | None = None,
        budget: int | None = None,
        seed: int,
        between_only: bool = False,
        skip_trivial: bool = False,
    ) -> KeyedDraw:
        """Plans a keyed draw of samples (see :class:`KeyedDraw`): the same samples as
        :func:`sample_fleet` on the same sessions, with the samplers of components (``"one"``,
        ``"rho"``, ``"rho-dispersed"``, ``"alpha"``, ``"closest-first"``,
        ``"closest-then-spread"``, ``"nearest-then-uniform"``; not the baselines, whose rules
        run over whole trajectories).

        Args:
            sampler: the sampler's name (``None``: :data:`DEFAULT_SAMPLER`).
            rate, budget: as :func:`sample_fleet` (at most one; neither:
                :data:`DEFAULT_BUDGET`).
            seed: the seed.
            between_only: only the components between two sessions.
            skip_trivial: leave out the trivial components.

        Returns:
            :class:`KeyedDraw`.

        Raises:
            InvalidParameterError: an unknown sampler, a baseline, both rate and budget, a
                budget of 0, a rate out of range, a result read from a pickle (which
                holds no merge); ``TooManySamplesError`` as :func:`sample_fleet`.
        """
    @property
    def tiles(self) -> list[Tile]:
        """The tiles merged, in the merge's order (the indices of :meth:`KeyedDraw.requests`).

        Raises:
            InvalidParameterError: a result read from a pickle, which holds no merge.
        """

    @property
    def names(self) -> list[str]:
        """The sessions' names, in order."""
    @property
    def components(self) -> Table:
        """The loop components, as :attr:`FleetLoops.components` (the same columns)."""
    def between_sessions(self) -> npt.NDArray[np.int64]:
        """The ids of the components between two different sessions, int64, increasing."""
    def session_pairs(self) -> Table:
        """The sparse overlap matrix as a table, as :meth:`FleetLoops.session_pairs`."""
    def overlap_matrix(self, *, sparse: bool = False) -> npt.NDArray[np.float64] | Any:
        """The overlap matrix, as :meth:`FleetLoops.overlap_matrix`.

        Args:
            sparse: a ``scipy.sparse.csr_array`` instead of a dense numpy array.

        Raises:
            ImportError: ``sparse=True`` without scipy.
        """

@final
class KeyedDraw:
    """A keyed draw of samples from a fleet's tiles (:meth:`TiledFleetLoops.draw`): the quotas from
    the merged statistics, then passes in which every tile asked (:meth:`requests`) offers its
    pairs (:func:`draw_tile`), until the draw is :attr:`done`. Its samples are those of
    :func:`sample_fleet` with the same sampler, seed and options, pair for pair. Threads may share
    it: its calls run one at a time.
    """

    @property
    def done(self) -> bool:
        """Whether every pass has run (:meth:`table` then holds the samples)."""
    @property
    def groups(self) -> int:
        """Number of groups (components with a pair to sample; 0 for σ_α)."""
    @property
    def available(self) -> int:
        """Number of candidate pairs."""
    @property
    def warnings(self) -> list[str]:
        """The warnings of the quotas, as text."""
    def requests(self) -> list[tuple[int, TileDrawRequest]]:
        """What the pending pass asks of the tiles: ``(tile index, TileDrawRequest)`` for every
        tile asked something (indices in the merge's order, :attr:`TiledFleetLoops.tiles`);
        empty once :attr:`done`.
        """
    def absorb(self, offers: list[DrawCandidates], *, complete: bool = True) -> None:
        """Takes the tiles' offers to the pending pass (all at once, or in several calls), then,
        with ``complete=True`` (the last call of the pass), ends the pass: the samples, or
        another pass for components whose keyed pairs came back short (rare).

        Raises:
            TypeError: an offer of another type.
        """
    def table(self) -> Table:
        """The samples, as :attr:`FleetSamples.table` gives them (the columns of ``loops fleet``'s
        ``samples.csv`` in its order, less ``sampler``), in order of the pairs.

        Raises:
            InvalidParameterError: before the draw is :attr:`done`.
        """

@final
class TileDrawRequest:
    """What one tile must offer a pass of a :class:`KeyedDraw`: the tile, the component ids of its
    provisional components, and the part of the request about them. Pickles as its bytes.
    """

    def __new__(cls, tile: Tile, labels: bytes, request: bytes) -> TileDrawRequest: ...
    def __reduce__(self) -> tuple[type[TileDrawRequest], tuple[Tile, bytes, bytes]]: ...
    @property
    def tile(self) -> Tile:
        """The tile."""

@final
class DrawCandidates:
    """What one tile offers a pass of a keyed draw (:func:`draw_tile`): its keyed pairs below the
    thresholds and the closest pairs of requested rows. Pickles as its bytes.
    """

    def __new__(cls, data: bytes) -> DrawCandidates: ...
    def __reduce__(self) -> tuple[type[DrawCandidates], tuple[bytes]]: ...
    def __len__(self) -> int: ...
    def to_bytes(self) -> bytes:
        """The offers as bytes (a tag, the tile format version, then MessagePack)."""

def draw_tile(
    request: TileDrawRequest,
    session_a: Trajectory,
    session_b: Trajectory | None = None,
    *,
    starts: tuple[int, int],
    gamma: float,
    metric: _MetricName = None,
    separation: Separation | float | Literal["auto", "none"] | None = "auto",
    threads: int | None = None,
    runs: TileRuns | None = None,
) -> DrawCandidates:
    """Rescans one tile from its two sessions, without the GIL, and offers its pairs to a pass of a
    :class:`KeyedDraw` (the arguments as :func:`scan_tile`'s, which the request's tile must have
    been scanned with). Given the tile's ``runs`` (:func:`scan_tile` with ``runs=True`` and the
    same arguments), it offers the same pairs from them without rescanning.

    Args:
        request: a :class:`TileDrawRequest` of :meth:`KeyedDraw.requests`.
        session_a, session_b, starts, gamma, metric, separation, threads: as :func:`scan_tile`.
        runs: the request's tile's :class:`TileRuns`, or ``None`` (rescan the tile).

    Returns:
        :class:`DrawCandidates`.

    Raises:
        InvalidParameterError: as :func:`scan_tile`; labels that do not fit the tile's scan;
            runs of another tile, metric or starts.
    """

@final
class TileDuration:
    """What one tile's runs add to the loop duration τ of its rows and columns
    (:func:`scan_tile` with ``duration=True``); :func:`session_loop_duration` adds up a session's.
    Pickles as its bytes.
    """

    def __new__(cls, data: bytes) -> TileDuration: ...
    def __reduce__(self) -> tuple[type[TileDuration], tuple[bytes]]: ...
    def to_bytes(self) -> bytes:
        """The share as bytes (a tag, the tile format version, then MessagePack)."""
    @property
    def tile(self) -> Tile:
        """The tile."""

@final
class TileRuns:
    """One tile's runs as its scan made them (:func:`scan_tile` with ``runs=True``), with their
    provisional labels: what :func:`draw_tile` reads of the tile when given them instead of
    rescanning it. About 16 bytes a run; it holds no poses. Lives in the process that scanned the
    tile (it does not pickle): a worker keeps it for the draws of its tiles.
    """

    def __len__(self) -> int: ...
    @property
    def metric_name(self) -> str:
        """The metric's name the tile was scanned with."""
    @property
    def nbytes(self) -> int:
        """The bytes it holds (its runs, 16 bytes each, and 8 bytes a row)."""
    @property
    def tile(self) -> Tile:
        """The tile."""

def session_loop_duration(
    session: int, *, start: int, poses: int, parts: list[TileDuration]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The loop duration τ of one session from the shares of the tiles that hold its rows or
    columns (:func:`scan_tile` with ``duration=True``), as :meth:`FleetLoops.loop_duration` splits it.

    Args:
        session: the session's index in the fleet.
        start: its first fleet index.
        poses: its number of poses.
        parts: :class:`TileDuration` shares, in any order (others are ignored).

    Returns:
        ``(own_s, other_s)``: float64 arrays of ``poses`` seconds, τ within the session and with
        the other sessions.

    Raises:
        InvalidParameterError: a share that does not lie in the session.
    """

def run_cli(args: list[str]) -> int:
    """Runs the ``loops`` command in this process with ``args`` (the arguments after the program
    name) and returns its exit code; the wheel's ``loops`` console script is this call.

    The command is the one ``cargo install --path crates/loops-cli`` builds, compiled into this
    module: the same output on stdout and stderr, ``--help`` and ``--version`` included, and the
    same exit codes (0; 1 when a log of ``loops run`` failed; 2 on an error; 0 when stdout closes
    early). It runs without the GIL. It installs a SIGINT/SIGTERM handler that stays for the
    rest of the process (an interrupt removes unfinished output and exits with 130), so call it
    from a process that runs the command and nothing else.

    Args:
        args: the command's arguments, e.g. ``["demo", "--limit", "5"]``.

    Returns:
        The exit code.
    """

@final
class PoseGraph:
    """A pose graph read from a g2o or TORO file (:func:`read_pose_graph`): its vertices as a
    :class:`Trajectory` and a :class:`~inexact_loops.Table`, and its edges — odometry and loop
    closures, with their relative poses and information matrices — as a table.

    Row k of :attr:`vertices` is pose k of :attr:`trajectory` (vertices sorted by id); the
    edges' ``i`` and ``j`` are those pose indices. The vertex values of the classic data sets
    are odometry guesses, not ground truth.

    Example:
        >>> import pathlib, tempfile, inexact_loops as il
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "square.g2o"
        >>> _ = path.write_text(
        ...     "VERTEX_SE2 0 0 0 0\\nVERTEX_SE2 1 1 0 1.5708\\nVERTEX_SE2 2 1 1 3.1416\\n"
        ...     "EDGE_SE2 0 1 1 0 1.5708 10 0 0 10 0 100\\nEDGE_SE2 1 2 1 0 1.5708 10 0 0 10 0 100\\n"
        ...     "EDGE_SE2 2 0 1 1 -3.1416 5 0 0 5 0 50\\n")
        >>> graph = il.read_pose_graph(path)
        >>> graph
        PoseGraph(3 vertices, 3 edges, 1 loop closures, 2-D)
        >>> edges = graph.edges
        >>> edges["i"].tolist(), edges["j"].tolist(), edges["loop_closure"].tolist()
        ([0, 1, 2], [1, 2, 0], [False, False, True])
        >>> edges["dtheta"].tolist(), edges["info_22"].tolist()
        ([1.5708, 1.5708, -3.1416], [100.0, 100.0, 50.0])
    """

    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(
        self,
    ) -> tuple[Callable[[bytes, Trajectory], PoseGraph], tuple[bytes, Trajectory]]: ...
    @classmethod
    def _from_state(cls, state: bytes, trajectory: Trajectory) -> PoseGraph: ...
    def __repr__(self) -> str: ...
    @property
    def trajectory(self) -> Trajectory:
        """The vertices as a :class:`Trajectory`, built for the ``metric`` and ``axes`` given to
        :func:`read_pose_graph` (positions by default); pose k is vertex ``vertex_ids[k]``.
        """
    @property
    def vertex_ids(self) -> npt.NDArray[np.int64]:
        """The vertex ids, increasing: int64, one per pose."""
    @property
    def dim(self) -> int:
        """2 or 3: the dimension of the graph's poses."""
    @property
    def chained(self) -> bool:
        """Whether the file had no vertices and they were chained from its odometry edges
        (``chain_edges=True``): dead reckoning.
        """
    @property
    def vertices(self) -> Table:
        """The vertices as a :class:`~inexact_loops.Table`, one row per pose of :attr:`trajectory`:
        ``id`` (int64), ``t`` (float64, seconds: the id, or as ``rate_hz`` / ``times`` say),
        ``x``, ``y``, then ``theta`` (2-D: the heading, radians in (−π, π]) or ``z``, ``qx``,
        ``qy``, ``qz``, ``qw`` (3-D), and ``line`` (int64: the vertex's line in the file; for a
        chained graph, the line of the edge that placed it).

        Example:
            >>> import pathlib, tempfile, inexact_loops as il
            >>> path = pathlib.Path(tempfile.mkdtemp()) / "two.graph"
            >>> _ = path.write_text("VERTEX2 7 1.5 2 0.25\\nVERTEX2 3 0 0 0\\n")
            >>> vertices = il.read_pose_graph(path).vertices
            >>> list(vertices), vertices["id"].tolist(), vertices["theta"].tolist()
            (['id', 't', 'x', 'y', 'theta', 'line'], [3, 7], [0.0, 0.25])
        """
    @property
    def edges(self) -> Table:
        """The edges as a :class:`~inexact_loops.Table`, one row per edge in file order: ``line``,
        ``from_id``, ``to_id`` (int64), ``i``, ``j`` (int64: the pose indices of the two
        vertices in :attr:`trajectory`), ``loop_closure`` (bool: the vertices are more than one
        id apart), the measured pose of ``to_id`` in the frame of ``from_id`` — ``dx``, ``dy``,
        ``dtheta`` (2-D, as written) or ``dx``, ``dy``, ``dz``, ``qx``, ``qy``, ``qz``, ``qw``
        (3-D; TORO's roll, pitch, yaw as a quaternion) — and the information matrix's upper
        triangle ``info_ab`` (float64, rows and columns x, y, θ in 2-D; x, y, z and the three
        rotation parameters in 3-D; g2o's order, TORO's ``EDGE2`` reordered; NaN where the line
        gives none).

        The full matrices, shape ``(edges, 3, 3)`` in 2-D::

            info = np.zeros((edges.num_rows, 3, 3))
            for a in range(3):
                for b in range(a, 3):
                    info[:, a, b] = info[:, b, a] = edges[f"info_{a}{b}"]
        """
    def edge_verdicts(
        self,
        loops: Loops,
        *,
        metric: str
        | _MetricLike
        | Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], float]
        | None = None,
    ) -> Table:
        """Where each loop-closure edge (vertices more than one id apart) falls against ``loops``,
        found on :attr:`trajectory`: a :class:`~inexact_loops.Table` with the rows and columns of
        ``loops components --edges-csv`` — ``line``, ``from_id``, ``to_id``, ``i``, ``j``,
        ``t_s``, ``t_prime_s``, ``distance`` (δ under the loops' metric), ``verdict`` (str) and
        ``component`` (int64, −1 in none). The verdicts are those of :meth:`Loops.pair_verdicts`:
        ``"component"``, ``"trivial"``, ``"not-separated"``, ``"outside"``.

        Args:
            loops: :class:`Loops` found on :attr:`trajectory`.
            metric: the metric the loops were found with; ``None`` takes it from the loops (pass
                the same callable for loops found with one).

        Raises:
            InvalidParameterError: loops of another trajectory or metric.

        Example:
            >>> import pathlib, tempfile, inexact_loops as il
            >>> path = pathlib.Path(tempfile.mkdtemp()) / "back.g2o"
            >>> xs = [0, 1, 2, 3, 2, 1, 0.1]
            >>> text = "".join(f"VERTEX_SE2 {k} {x} 0 0\\n" for k, x in enumerate(xs))
            >>> _ = path.write_text(text + "EDGE_SE2 6 0 0 0 0\\nEDGE_SE2 4 2 0 0 0\\nEDGE_SE2 3 0 0 0 0\\n")
            >>> graph = il.read_pose_graph(path)
            >>> loops = il.find_loops(graph.trajectory, gamma=0.5, separation=il.Separation(path=3.0))
            >>> graph.edge_verdicts(loops)["verdict"].tolist()
            ['component', 'not-separated', 'outside']
        """

def read_pose_graph(
    path: str | PathLike[str],
    *,
    metric: str | _MetricLike | None = None,
    axes: tuple[int, int] | None = None,
    rate_hz: float | None = None,
    times: str | PathLike[str] | None = None,
    chain_edges: bool = False,
    quaternion_tolerance: float | None = None,
) -> PoseGraph:
    """Reads a pose graph in g2o or TORO text (``VERTEX_SE2`` / ``VERTEX2``, ``VERTEX_SE3:QUAT``,
    ``VERTEX3`` and their ``EDGE`` lines): its vertices as a trajectory and a table, and its
    edges — relative pose and information matrix — as a table (:class:`PoseGraph`).

    A file of edges without vertices (an ``EDGE3`` list, ``EDGE2`` odometry and loop closures)
    is an error, unless ``chain_edges=True``: then its odometry edges (vertex k to k + 1) are
    composed from the first vertex at the origin, and a :class:`DeadReckoningWarning` says that
    the poses are dead reckoning, whose error grows along the path. A gap in the chain is an
    error naming the vertex no edge reaches.

    Args:
        path: the file (``.g2o``, ``.graph``, or a ``.txt`` whose first line is a vertex or edge).
        metric, axes: the trajectory's points, as in :func:`read_trajectory` (positions by
            default; ``"se2(rotation_weight_m_per_rad=W)"`` for x, y and the heading).
        rate_hz: vertex id k at k / rate_hz seconds (default: the id in seconds).
        times: a file of one time a line, one per vertex in id order.
        chain_edges: chain the odometry edges of a file without vertices (dead reckoning).
        quaternion_tolerance: as in :func:`read_trajectory`.

    Returns:
        :class:`PoseGraph`.

    Raises:
        OSError: the file cannot be opened. LoopsIOError: a malformed line (naming it), edges
        without vertices (naming ``chain_edges``), a gap in the odometry chain.
        InvalidParameterError: both ``rate_hz`` and ``times``; a metric whose points are not
        poses.

    Warns:
        DeadReckoningWarning: the vertices were chained from the edges (``chain_edges=True`` on
            a file without vertices).

    Example:
        >>> import pathlib, tempfile, warnings, inexact_loops as il
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "edges.graph"
        >>> _ = path.write_text("EDGE2 0 1 1 0 1.5707963267948966\\nEDGE2 1 2 1 0 0\\nEDGE2 2 0 -1 1 -1.5707963267948966\\n")
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     graph = il.read_pose_graph(path, chain_edges=True)
        >>> graph.trajectory.positions.round(12).tolist(), caught[0].category.__name__
        ([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], 'DeadReckoningWarning')
    """

@final
class OnlineLoops:
    """The loops of a trajectory that grows pose by pose, as a SLAM front end sees it: S_γ, its
    loop components with their statistics, and the loop duration τ, kept up to date as poses
    are pushed one at a time (:meth:`push`) or in batches (:meth:`push_many`), at a cost that
    follows the answer (the runs near the new pose), not the length of the trajectory.

    After every push, the components equal those of :func:`find_loops` on the poses so far
    with ``separation=None`` (the paper's S_γ; :meth:`to_loops` gives exactly that result).
    Component ids are stable: given in creation order from 0; when two components merge, the
    survivor keeps the smaller id and the other is retired (:attr:`Update.merged`,
    :meth:`resolve`). When the back end corrects the trajectory, :meth:`rebuild` restarts from
    it in one batch computation. An :class:`OnlineSampler` picks loop-closure candidates from
    each :class:`Update`.

    Args:
        gamma: the distance threshold γ > 0, in the metric's unit.
        dim: coordinates per pose (3 for positions, 7 for SE(3) poses ``x y z qx qy qz qw``).
        metric: as in :func:`find_loops`, a name or an :mod:`inexact_loops.metrics` object
            (not a callable); ``None`` is ``"euclidean"``.

    Raises:
        InvalidParameterError: gamma not positive and finite, an unknown metric, a metric that
            does not take ``dim`` coordinates.

    Example:
        A 95% circle of radius 10 m, pushed pose by pose: its ends come within γ of each other.

        >>> import numpy as np, inexact_loops as il
        >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
        >>> points = 10 * np.c_[np.cos(angle), np.sin(angle)]
        >>> online = il.OnlineLoops(gamma=4.0, dim=2)
        >>> for k in range(200):
        ...     update = online.push(0.1 * k, points[k])
        >>> online.components["trivial"].tolist(), online.components["first_pose"].tolist()
        ([True, False], [0, 197])
        >>> online.to_loops() == il.find_loops(online.trajectory, gamma=4.0, separation=None)
        True

    Threads may share an engine: its calls run one at a time, each whole (a call waits, without
    the GIL, while another thread's is in progress).
    """

    def __new__(
        cls, *, gamma: float, dim: int, metric: str | _MetricLike | None = None
    ) -> OnlineLoops: ...
    def __reduce__(self) -> tuple[Callable[[bytes], OnlineLoops], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> OnlineLoops: ...
    def __len__(self) -> int: ...
    def push(self, t: float, point: npt.ArrayLike) -> Update:
        """Adds the pose at time ``t`` (seconds, after the last pose's) with ``point`` (``dim``
        coordinates): row n of the plane, its pairs with every earlier pose. Takes microseconds;
        the GIL is held.

        Args:
            t: its time, seconds.
            point: its coordinates, shape ``(dim,)`` (a list or numpy array).

        Returns:
            :class:`Update`.

        Raises:
            InvalidTrajectoryError: a time or coordinate NaN or infinite, a time not after the
                last pose's, a quaternion that is not unit (for the se3 metrics); the message
                names the pose's index. Nothing changes then.
            ValueError: a point of another number of coordinates.

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=1.0, dim=2)
            >>> online.push(0.0, [0.0, 0.0]).created.tolist(), online.push(1.0, [0.5, 0.0]).pose
            ([0], 1)
        """
    def push_many(self, timestamps: npt.ArrayLike, points: npt.ArrayLike) -> Update:
        """Adds several poses at once, as that many :meth:`push` es, with one :class:`Update`
        covering all of them (an :class:`OnlineSampler` gives the same candidates either way).
        All or nothing: on an error none is added. The GIL is released. Ctrl-C stops it before
        the next pose (``KeyboardInterrupt``): the poses before that one stay added, as their
        pushes would have left them (``len`` says how many), and no :class:`Update` covers them.

        Args:
            timestamps: seconds, shape ``(n,)``, increasing, after the last pose's.
            points: shape ``(n, dim)`` (or ``(n,)`` when ``dim`` is 1).

        Returns:
            :class:`Update`.

        Raises:
            InvalidTrajectoryError: as :meth:`push`, for the first bad pose, named by its index in
                the whole trajectory.
            ValueError: shapes that do not fit (rows, or columns other than ``dim``).

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> online = il.OnlineLoops(gamma=1.0, dim=2)
            >>> update = online.push_many(np.arange(3.0), np.zeros((3, 2)))
            >>> update.first_pose, update.pose, len(online)
            (0, 2, 3)
        """
    def rebuild(self, trajectory: Trajectory) -> None:
        """Restarts from ``trajectory``, the poses so far as the back end corrected them after a
        loop closure, with one batch computation (threads as :func:`find_loops`, GIL released);
        later pushes continue after its last pose. Component ids restart from 0 (in order of
        each component's first pose); :class:`OnlineSampler` s reset themselves at their next
        offer, and updates from before cannot be offered.

        Args:
            trajectory: a :class:`Trajectory` of ``dim`` coordinates.

        Raises:
            InvalidParameterError: a metric that does not fit the trajectory.
            InvalidTrajectoryError: points the metric refuses.

        Example:
            >>> import numpy as np, inexact_loops as il
            >>> online = il.OnlineLoops(gamma=0.5, dim=1)
            >>> _ = online.push_many(np.arange(4.0), [0.0, 1.0, 1.0, 0.0])
            >>> online.rebuild(il.Trajectory(np.arange(4.0), np.array([0.0, 1.0, 2.0, 3.0])))
            >>> online.components["id"].tolist(), online.rebuild_count
            ([0, 1, 2, 3], 1)
        """
    def clear(self) -> None:
        """Forgets every pose: as new (ids restart too; :attr:`rebuild_count` goes up).

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=1.0, dim=1)
            >>> _ = online.push(0.0, [0.0])
            >>> online.clear()
            >>> len(online), online.rebuild_count
            (0, 1)
        """
    def to_loops(self) -> Loops:
        """The loops of the poses so far as :func:`find_loops` gives them with ``separation=None``
        (the same :class:`Loops`, components numbered in the batch's order, not by online id;
        its warnings are in :attr:`Loops.warnings`, not issued).

        Raises:
            InvalidTrajectoryError: fewer than two poses.

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=0.5, dim=1)
            >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
            >>> online.to_loops().components["pair_count"].tolist()
            [1, 1, 4, 1]
        """
    def loop_duration(self, pose: int) -> float:
        """The loop duration τ of pose ``pose`` so far (paper, Eq. 6), seconds: how long the
        trajectory has stayed within γ of it. :meth:`Loops.loop_duration` of :meth:`to_loops`
        gives it for every pose.

        Raises:
            IndexError: not a pose index.

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=0.5, dim=1)
            >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
            >>> online.loop_duration(0), online.loop_duration(1)
            (1.0, 2.0)
        """
    def resolve(self, id: int) -> int:
        """The live id that component ``id`` now belongs to, following merges (``id`` itself for a
        live id).

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=0.5, dim=1)
            >>> update = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 0.8, 0.0, 0.4])
            >>> update.merged["retired"].tolist(), update.merged["survivor"].tolist(), online.resolve(3)
            ([3], [2], 2)
        """
    @property
    def gamma(self) -> float:
        """The threshold γ."""
    @property
    def dim(self) -> int:
        """Coordinates per pose."""
    @property
    def metric_name(self) -> str:
        """The metric's name (its spec, e.g. ``"euclidean"``)."""
    @property
    def rebuild_count(self) -> int:
        """How many times the engine was rebuilt or cleared: ids from before mean nothing now."""
    @property
    def timestamps(self) -> npt.NDArray[np.float64]:
        """The times of the poses pushed, seconds (a copy)."""
    @property
    def trajectory(self) -> Trajectory | None:
        """The poses pushed so far as a :class:`Trajectory` (a copy), or ``None`` before the second."""
    @property
    def components(self) -> Table:
        """The live loop components so far as a :class:`~inexact_loops.Table`, one row a component,
        by id: the columns of :attr:`Loops.components` (``id`` is the online id; the half i ≤ j
        for a non-trivial component, the whole set for a trivial one) and ``first_pose`` (the
        pose whose row created it, the earliest of merged parts) and ``last_pose`` (the last pose
        whose row extended it), int64.

        Example:
            >>> import inexact_loops as il
            >>> online = il.OnlineLoops(gamma=0.5, dim=1)
            >>> _ = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
            >>> table = online.components
            >>> table["id"].tolist(), table["trivial"].tolist(), table["first_pose"].tolist()
            ([0, 1, 2, 3], [True, True, False, True], [0, 1, 3, 3])
        """

@final
class Update:
    """What a push changed. Returned by :meth:`OnlineLoops.push` and :meth:`OnlineLoops.push_many`;
    hand it to :meth:`OnlineSampler.offer` for its loop-closure candidates.

    Example:
        >>> import inexact_loops as il
        >>> online = il.OnlineLoops(gamma=0.5, dim=1)
        >>> update = online.push_many([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 0.0])
        >>> update.first_pose, update.pose, update.created.tolist()
        (0, 3, [0, 1, 2, 3])
        >>> update.runs["row"].tolist(), update.runs["start"].tolist(), update.runs["component"].tolist()
        ([0, 1, 2, 3, 3], [0, 1, 1, 0, 3], [0, 1, 1, 2, 3])
    """

    def __reduce__(self) -> tuple[Callable[[bytes], Update], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> Update: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    @property
    def first_pose(self) -> int:
        """Index of the first pose the push added."""
    @property
    def pose(self) -> int:
        """Index of the last pose pushed: the keyframe."""
    @property
    def loop_duration_s(self) -> float:
        """The loop duration τ of the last pose so far, seconds."""
    @property
    def created(self) -> npt.NDArray[np.int64]:
        """Ids of the components the push created, in order (int64)."""
    @property
    def extended(self) -> npt.NDArray[np.int64]:
        """Ids (after the push) of the components that existed before it and gained pairs,
        increasing (int64).
        """
    @property
    def merged(self) -> Table:
        """The merges, in the order they happened, as a :class:`~inexact_loops.Table` of int64
        columns: ``pose`` (the row whose runs joined them), ``retired`` and ``survivor`` (the
        smaller id, which lives on).
        """
    @property
    def runs(self) -> Table:
        """The new rows' runs, row by row, columns increasing, as a :class:`~inexact_loops.Table`
        of int64 columns: ``row`` (the pose pushed), ``start`` and ``end`` (its earlier poses
        within γ, inclusive; the pose itself when the run reaches the diagonal), ``component``
        (its id once the row was added; a later row of the same batch may merge it) and
        ``closest`` (the run's pose closest to ``row``).
        """

@final
class OnlineSampler:
    """Picks loop-closure candidates from each :class:`Update` of an :class:`OnlineLoops`, as a
    front end needs them while the robot drives: σ_ρ online (each component's pairs in the new
    row drawn at ``rate`` per component per pose), a cap per component (per minute or per metre
    of travel), a candidate the first time a component appears (P1 online) and the revisit
    separation. Every random choice is keyed by (seed, pose, component): pushing poses one at a
    time or in batches gives the same candidates, on every machine.

    Args:
        rate: σ_ρ, the expected number of candidates per component per pose (0: only the
            first-appearance candidates); fractions are rounded randomly.
        cap_per_minute: at most this many candidates per minute per component (a token bucket,
            full at first); or
        cap_per_metre: at most this many per metre of travel (the metric's unit) per component.
            Give at most one.
        first_on_appearance: P1 online: a candidate (the closest pair) in the first row where a
            component has a pair to offer.
        first_offer: where that candidate goes: ``"edge-then-closest"`` (the default: the
            closest pair at the edge of γ as the component appears, and once the path has left
            it the closest pair of that first pass, the closest approach, as a second candidate
            whose :attr:`Candidate.improves` names the first; none when the first was already
            the closest), ``"edge"`` (the edge candidate only) or ``"closest-approach"`` (only
            the closest approach, offered at the keyframe after the path leaves it, beyond the
            cap). A candidate at the closest approach has :attr:`Candidate.k` <
            :attr:`Candidate.keyframe`.
        closest_in_row: the first of a row's draws for a component is its closest pair in the
            row, the others uniform (the default sampler's rule, :data:`DEFAULT_SAMPLER`, per
            keyframe); ``False``: all uniform (the paper's σ_ρ).
        separation: only pairs this far apart along the trajectory: ``None`` (every pair), a path
            length, or a :class:`Separation` (e.g. ``Separation.for_gamma(gamma)``, the
            revisits of :func:`find_loops`' default).
        seed: the seed.

    Raises:
        InvalidParameterError: a rate negative or not finite, a cap not positive and finite,
            both caps, a negative separation, ``separation="auto"`` (it needs γ: pass
            ``Separation.for_gamma(gamma)``).

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> online = il.OnlineLoops(gamma=1.0, dim=2)
        >>> sampler = il.OnlineSampler(rate=0.0, separation=il.Separation(path=3.0))
        >>> angle = np.linspace(0.0, 2.2 * np.pi, 60)
        >>> for k, a in enumerate(angle):
        ...     update = online.push(float(k), [2.0 * np.cos(a), 2.0 * np.sin(a)])
        ...     for c in sampler.offer(online, update):
        ...         print(c.keyframe, c.j, c.first)
        50 0 True

    Threads may share a sampler: its calls run one at a time (as :class:`OnlineLoops`'). It
    pickles with its state (buckets, the components P1 served, the pose it reached): pickled
    with its :class:`OnlineLoops` (or offered the next update of the engine it followed), the
    copy gives the candidates the original would; offered an update that does not start where
    it stopped, it starts afresh.
    """

    def __new__(
        cls,
        *,
        rate: float = 1.0,
        cap_per_minute: float | None = None,
        cap_per_metre: float | None = None,
        first_on_appearance: bool = True,
        first_offer: Literal["edge-then-closest", "edge", "closest-approach"] = "edge-then-closest",
        closest_in_row: bool = True,
        separation: Separation | float | Literal["none"] | None = None,
        seed: int = 0,
    ) -> OnlineSampler: ...
    def __reduce__(self) -> tuple[Callable[[bytes], OnlineSampler], tuple[bytes]]: ...
    @classmethod
    def _from_state(cls, state: bytes) -> OnlineSampler: ...
    def offer(self, online: OnlineLoops, update: Update) -> list[Candidate]:
        """The loop-closure candidates that ``update`` made possible, by keyframe, component and
        pose. Offer every update of ``online``, in order, once each (a sampler follows one
        engine); after a rebuild it starts afresh.

        Args:
            online: the :class:`OnlineLoops` that returned ``update``.
            update: its last push's :class:`Update`.

        Returns:
            list of :class:`Candidate`.

        Raises:
            InvalidParameterError: ``update`` is not ``online``'s last (an older one, another
                engine's, one from before a rebuild, or an unpickled one), or was offered already.

        Example:
            >>> import inexact_loops as il
            >>> online, sampler = il.OnlineLoops(gamma=0.5, dim=1), il.OnlineSampler()
            >>> update = online.push_many([0.0, 1.0, 2.0], [0.0, 0.1, 0.0])
            >>> [c.pair for c in sampler.offer(online, update) if c.first]
            [(0, 1)]
        """
    @property
    def rate(self) -> float:
        """σ_ρ's rate: candidates per component per pose."""
    @property
    def cap_per_minute(self) -> float | None:
        """The cap per minute per component, or ``None``."""
    @property
    def cap_per_metre(self) -> float | None:
        """The cap per metre of travel per component, or ``None``."""
    @property
    def first_on_appearance(self) -> bool:
        """Whether a component's first appearance brings a candidate (P1 online)."""
    @property
    def first_offer(self) -> Literal["edge-then-closest", "edge", "closest-approach"]:
        """Where that candidate goes: ``"edge-then-closest"``, ``"edge"`` or ``"closest-approach"``."""
    @property
    def separation(self) -> Separation:
        """The separation the candidates keep (:class:`Separation`)."""
    @property
    def seed(self) -> int:
        """The seed."""

@final
class Candidate:
    """A loop-closure candidate: the pair (``j``, ``k``), j < k ≤ keyframe, within γ, to match.
    Returned by :meth:`OnlineSampler.offer`.

    Args:
        keyframe: the pose whose push offered it.
        j: the earlier pose.
        k: the later pose (``None``: the keyframe; earlier only for a candidate at the closest
            approach, offered once the pass was over).
        component: its component's id at the keyframe.
        distance: δ(x_j, x_k), the metric's unit.
        first: emitted by the first-appearance rule rather than drawn.
        improves: for the closest approach of a component's first pass, the pair of the first
            candidate it improves (offered at the edge of γ); ``None`` otherwise.

    Example:
        >>> import inexact_loops as il
        >>> c = il.Candidate(keyframe=12, j=3, component=1, distance=0.25, first=True)
        >>> c.pair, c
        ((3, 12), Candidate(keyframe=12, j=3, component=1, distance=0.25, first=True))
    """

    def __new__(
        cls,
        *,
        keyframe: int,
        j: int,
        component: int,
        distance: float,
        first: bool,
        k: int | None = None,
        improves: tuple[int, int] | None = None,
    ) -> Candidate: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, Any]]: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    @property
    def keyframe(self) -> int:
        """The pose whose push made it possible: the later pose of the pair."""
    @property
    def j(self) -> int:
        """The earlier pose of the pair."""
    @property
    def k(self) -> int:
        """The later pose of the pair: the keyframe, but for a candidate at the closest approach
        (offered once the pass was over).
        """
    @property
    def pair(self) -> tuple[int, int]:
        """The pair ``(j, k)``."""
    @property
    def component(self) -> int:
        """Its component's id at the keyframe."""
    @property
    def distance(self) -> float:
        """δ(x_j, x_k), the metric's unit."""
    @property
    def first(self) -> bool:
        """Whether the first-appearance rule (P1 online) emitted it, rather than a draw."""
    @property
    def improves(self) -> tuple[int, int] | None:
        """For the closest approach that improves a component's first candidate (offered at the
        edge of γ, ``first_offer="edge-then-closest"``): that candidate's pair ``(j, k)``; else
        ``None``.
        """

@final
class OutDir:
    """An output folder a command fills with its results, held by this process: the rules of
    ``loops run --out`` (one run at a time, an exclusive lock on the folder; every entry written
    is listed in the command's marker before it is moved into place; ``force`` replaces only
    listed entries, never a file of yours named like one of ours; work in progress is filled in
    the command's scratch folder, and only that folder, as the marker lists it, is removed after
    a killed run). Used by :func:`inexact_loops.dask.run_fleet_dask`.

    Args:
        path: the folder; created (with its parents) when missing.
        force: replace the results of an earlier run of the command.
        tool: the command: ``"loops-dask"``, ``"loops run"`` or ``"loops fleet"``.

    Raises:
        InvalidParameterError: the folder is in use, not empty without ``force``, or holds an
            entry of the command's name that it did not write; an unknown ``tool``.
        OSError: the folder cannot be created, read, locked or written.
    """

    def __new__(
        cls, path: str | PathLike[str], *, force: bool = False, tool: str = "loops-dask"
    ) -> OutDir: ...
    @property
    def path(self) -> Path:
        """The folder, as given."""
    @property
    def scratch(self) -> Path:
        """The scratch folder, where entries are filled before :meth:`place` moves them."""
    @property
    def entries(self) -> list[str]:
        """The entries the command's marker lists (it wrote them), sorted."""
    def owns(self, name: str) -> bool:
        """Whether the entry ``name`` is listed in the marker: the command wrote it."""
    def claim(self, name: str) -> None:
        """Lists ``name`` in the marker, before it is written."""
    def staging_path(self) -> Path:
        """A new path in the scratch folder for one file or folder to fill, then :meth:`place`.
        Nothing is created.
        """
    def place(self, staged: str | PathLike[str], name: str) -> None:
        """Moves the filled file or folder ``staged`` into place as the entry ``name``, listing it
        first. An existing entry is replaced only with ``force`` and only when the marker lists
        it and it is of the same kind; ``staged`` is removed when it cannot be placed.

        Raises:
            InvalidParameterError: the entry exists and may not be replaced.
            OSError: a rename failed.
        """
    def remove(self, name: str) -> bool:
        """Removes the entry ``name`` when the command wrote it; anything else of that name is left
        alone. Returns whether an entry was removed.
        """
    def close(self) -> None:
        """Releases the folder: removes the scratch folder and the lock. Later calls raise."""
    def __enter__(self) -> OutDir: ...
    def __exit__(self, *exc: object) -> None: ...

def refuse_output_on_input(
    what: str, output: str | PathLike[str], inputs: list[str | PathLike[str]]
) -> None:
    """Refuses to write the output ``output`` onto an input, ``force`` or not: when it is, or
    links to, one of ``inputs`` (files or folders), lies inside an input folder, or holds an
    input. ``what`` names the output in the message.

    Raises:
        InvalidParameterError: naming both paths.
    """

def write_file(path: str | PathLike[str], data: bytes, *, overwrite: bool = False) -> None:
    """Writes ``data`` to the file ``path`` whole or not at all: loops-io's one atomic writer, as
    every file of the package is written (a temporary file beside it, synced, renamed into
    place). An existing ``path`` is replaced only with ``overwrite``; a stream (``/dev/null``,
    ``/dev/stdout``, a FIFO, or a link to one) is written into, never replaced.

    Raises:
        FileExistsError: ``path`` exists and ``overwrite`` is false.
        OSError: the folder is missing or not writable, the disk is full, or ``path`` is a block
            device or a socket.
    """

@final
class Scene:
    """What robotics viewers draw of a result: a path per session with τ along it, every loop
    component (its two stretches of path and its closest pair, a colour each), the sampled
    candidate pairs and the (t, t′) plane as an RGB image. Made by :func:`scene`; written as
    MCAP by :meth:`to_mcap` (Foxglove, RViz) and drawn by
    :func:`inexact_loops.viewers.to_rerun` (Rerun).
    """

    def to_mcap(self, path: str | PathLike[str], *, overwrite: bool = False) -> None:
        """Writes the scene as MCAP for Foxglove and RViz: Foxglove's schemas on ``/loops/trajectory``
        (PosesInFrame), ``/loops/tau``, ``/loops/components``, ``/loops/candidates`` (SceneUpdate)
        and ``/loops/plane`` (RawImage), and a ROS 2 ``visualization_msgs/msg/MarkerArray`` on
        ``/loops/markers``. Atomic; beside it, :attr:`foxglove_layout` opens the right panels.

        Raises:
            FileExistsError: ``path`` exists and ``overwrite`` is false.
            OSError: the file cannot be written.
        """
    @property
    def foxglove_layout(self) -> str:
        """The Foxglove layout (JSON text) for the MCAP file: a 3D panel with the scene's topics
        and an Image panel with the plane.
        """
    @property
    def paths(self) -> list[dict[str, Any]]:
        """One dict per session: ``name``, ``timestamps_s`` (n), ``positions`` (n × 3),
        ``loop_duration_s`` (n, τ) and ``tau_rgba`` (n × 4, τ's colour in [0, 1]).
        """
    @property
    def components(self) -> list[dict[str, Any]]:
        """One dict per component, in id order: ``id``, ``trivial``, ``sessions`` (a, b),
        ``poses`` ((i_min, i_max), (j_min, j_max)), ``closest_pair``, ``closest_distance``,
        ``area_s2``, ``pair_count`` and ``rgba`` (its colour in [0, 1]).
        """
    @property
    def candidates(self) -> dict[str, npt.NDArray[np.int64]]:
        """The candidate pairs, in the samples' order: int64 columns ``session_a``, ``session_b``,
        ``i``, ``j`` (poses in their sessions) and ``component`` (−1 when unknown).
        """
    @property
    def plane(self) -> npt.NDArray[np.uint8]:
        """The (t, t′) plane: uint8 array (height, width, 3), row 0 the latest t′ (t′ up), each
        component in its colour, candidates white.
        """
    @property
    def frame_id(self) -> str:
        """The frame every entity is in."""

@final
class LiveServer:
    """A server of the live scene over Foxglove's WebSocket protocol, on the topics and in the
    schemas of ``loops replay --serve`` (see :mod:`inexact_loops.viewers`); made by
    :func:`inexact_loops.viewers.serve`. Each :meth:`send` sends one keyframe's messages to the
    clients subscribed then (no history is kept: :meth:`wait_for_client` first).
    :meth:`close` (or leaving a ``with`` block) stops it and closes its port.
    """

    def __new__(cls, address: str = "127.0.0.1:0", *, name: str = "live") -> LiveServer:
        """Starts serving on ``address`` (``HOST:PORT``; port 0: a free port, see
        :attr:`address`), the log named ``name`` (the τ entity's id, ``tau/<name>``).

        Raises:
            ValueError: an address that is not ``HOST:PORT``.
            OSError: when the address cannot be bound (taken, or not this machine's).
        """
    @property
    def address(self) -> str:
        """Where it serves, ``HOST:PORT`` (the port picked for port 0); a client connects to
        ``ws://HOST:PORT``.
        """
    @property
    def port(self) -> int:
        """Its port."""
    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
    def wait_for_client(self, timeout_s: float | None = None) -> bool:
        """Waits until a client has subscribed to every channel, or a second after a client's first
        subscription (Foxglove subscribes only to what its panels show), at most ``timeout_s``
        seconds (``None``: no limit). The GIL is released while it waits; Ctrl-C stops it
        (``KeyboardInterrupt``).

        Returns:
            ``True`` when a client is there, ``False`` after ``timeout_s``.
        """
    def send(self, online: OnlineLoops, update: Update, candidates: list[Candidate] = ...) -> None:
        """Sends the keyframe that ``update`` reports (``online``'s last push) with the
        ``candidates`` an :class:`OnlineSampler` offered for it: the path so far, τ along it,
        the components it changed, its candidates, the ROS ``MarkerArray`` of the same, and the
        (t, t′) plane each time the poses pass a multiple of 100. Nothing before the second pose
        (one pose draws nothing).

        Raises:
            ValueError: when the server is closed, or ``update`` or ``candidates`` name a pose
                ``online`` does not hold.
        """
    def send_plane(self, online: OnlineLoops) -> None:
        """Sends the (t, t′) plane of the poses ``online`` holds (at the end of a log: the plane
        of all of it), each component in its colour and the candidates sent so far white, as in
        the MCAP file; nothing before the second pose.

        Raises:
            ValueError: when the server is closed.
        """
    def close(self) -> None:
        """Stops the server: its clients are told, its port is closed. Closing twice does nothing."""
    def __enter__(self) -> LiveServer: ...
    def __exit__(
        self, _kind: object = None, _value: object = None, _traceback: object = None
    ) -> None: ...

def scene(
    loops: Loops | FleetLoops,
    samples: Samples | FleetSamples,
    trajectory: Trajectory | None = None,
    *,
    name: str = "trajectory",
) -> Scene:
    """The scene of a result: ``loops`` found on ``trajectory`` with ``samples`` drawn from them,
    or a fleet's :class:`FleetLoops` with its :class:`FleetSamples` (no ``trajectory``).
    Positions are each pose's first three coordinates.

    Args:
        loops: a :class:`Loops` or a :class:`FleetLoops`.
        samples: its :class:`Samples` (a :class:`FleetSamples` for a fleet).
        trajectory: the :class:`Trajectory` of ``loops`` (not for a fleet).
        name: the trajectory's session name.

    Raises:
        TypeError: arguments of other types, or of a fleet and a single trajectory mixed.
        InvalidParameterError: ``trajectory`` or ``samples`` are not those of ``loops``.

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> traj = il.Trajectory(np.arange(6.0), np.array([[0, 0], [5, 0], [5, 5], [0, 0], [5, 0], [5, 5.0]]))
        >>> loops = il.find_loops(traj, gamma=0.5)
        >>> samples = il.sample(loops, "one", budget=3, seed=0, trajectory=traj)
        >>> scene = il.viewers.scene(loops, samples, traj)
        >>> scene.paths[0]["positions"].shape, scene.plane.shape[2]
        ((6, 3), 3)
    """
