"""Type stubs of the compiled module ``inexact_loops._core``."""

from collections.abc import Callable
from os import PathLike
from typing import Literal, Protocol, final

import numpy as np
import numpy.typing as npt
import pandas  # type: ignore[import-untyped, import-not-found, unused-ignore]

from .table import Table

__all__ = [
    "list_topics",
    "DetectionClusters",
    "Detections",
    "Loops",
    "SampleQuality",
    "Samples",
    "Trajectory",
    "__version__",
    "cluster_detections",
    "draw_detections",
    "find_loops",
    "read_trajectory",
    "sample",
    "sample_quality",
    "urban_drive",
]

__version__: str

_Side = Literal["both", "begin", "end"]
_SamplerName = Literal[
    "one",
    "rho",
    "rho-dispersed",
    "alpha",
    "lio-sam",
    "hdl-graph-slam",
    "cartographer",
    "time-gap",
]

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
    """A sampled trajectory: strictly increasing timestamps (seconds) and one point each."""

    def __new__(cls, timestamps: npt.ArrayLike, positions: npt.ArrayLike) -> Trajectory: ...
    def __len__(self) -> int: ...
    @property
    def dim(self) -> int:
        """Coordinates per point."""
    @property
    def timestamps(self) -> npt.NDArray[np.float64]:
        """Timestamps, seconds, shape ``(n,)`` (a copy)."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Points, shape ``(n, d)`` (a copy)."""
    @property
    def cell_widths(self) -> npt.NDArray[np.float64]:
        """Time-cell widths w_i, seconds, shape ``(n,)``; they sum to ``span_s``."""
    @property
    def span_s(self) -> float:
        """Last minus first timestamp, seconds."""
    @staticmethod
    def se3(
        timestamps: npt.ArrayLike,
        positions: npt.ArrayLike,
        quaternions_xyzw: npt.ArrayLike,
        *,
        quaternion_tolerance: float | None = None,
    ) -> Trajectory:
        """SE(3) poses: positions (n, 3) and quaternions (n, 4) in x, y, z, w order."""
    @staticmethod
    def so3(
        timestamps: npt.ArrayLike,
        quaternions_xyzw: npt.ArrayLike,
        *,
        quaternion_tolerance: float | None = None,
    ) -> Trajectory:
        """Rotations: quaternions (n, 4) in x, y, z, w order."""
    @staticmethod
    def so3_from_rotation_vectors(
        timestamps: npt.ArrayLike, rotation_vectors: npt.ArrayLike
    ) -> Trajectory:
        """Rotations from rotation vectors (n, 3), radians."""
    @staticmethod
    def se2(timestamps: npt.ArrayLike, poses_xy_theta: npt.ArrayLike) -> Trajectory:
        """Planar poses (n, 3): x, y, heading (radians)."""
    @staticmethod
    def torus(timestamps: npt.ArrayLike, angles_rad: npt.ArrayLike) -> Trajectory:
        """Points on a torus: angles (n, k), radians."""
    @staticmethod
    def sphere(timestamps: npt.ArrayLike, vectors: npt.ArrayLike) -> Trajectory:
        """Points on the sphere: non-zero vectors (n, 3), normalised."""
    @staticmethod
    def sphere_from_lat_lon(timestamps: npt.ArrayLike, lat_lon_deg: npt.ArrayLike) -> Trajectory:
        """Points on the sphere from latitude and longitude (n, 2), degrees."""
    @staticmethod
    def gnss(timestamps: npt.ArrayLike, lat_lon_height: npt.ArrayLike) -> Trajectory:
        """GNSS fixes (n, 3): latitude, longitude (degrees), height (metres)."""
    @staticmethod
    def gnss_ecef(timestamps: npt.ArrayLike, lat_lon_height: npt.ArrayLike) -> Trajectory:
        """GNSS fixes as ECEF positions relative to the first fix, metres."""
    @staticmethod
    def descriptors(
        timestamps: npt.ArrayLike, descriptors: npt.ArrayLike, *, normalize: bool = True
    ) -> Trajectory:
        """Descriptor vectors (n, d), normalised for the angular metric."""
    @staticmethod
    def from_evo(
        trajectory: _EvoTrajectory,
        *,
        metric: str | _MetricLike | None = None,
        axes: tuple[int, int] | None = None,
    ) -> Trajectory:
        """A trajectory from an evo ``PoseTrajectory3D`` (quaternions w first), for ``metric``."""

@final
class Loops:
    """The inexact loops of a trajectory at one gamma; returned by :func:`find_loops`."""

    def __len__(self) -> int: ...
    @property
    def gamma(self) -> float:
        """The threshold gamma."""
    @property
    def metric(self) -> str:
        """The metric's name."""
    @property
    def span_s(self) -> float:
        """Last minus first timestamp, seconds."""
    @property
    def pair_count(self) -> int:
        """Lattice cells of S_gamma in the full plane (both halves and the diagonal)."""
    @property
    def warnings(self) -> list[str]:
        """Warnings about the result, as sentences."""
    @property
    def components(self) -> Table:
        """The loop components as a Table of numpy columns, one row a component."""
    def runs(self) -> Table:
        """The runs of S_gamma's upper half (int64): ``row``, ``start``, ``end``, ``component``."""
    def component_of(self, i: int, j: int) -> int | None:
        """The component id of the pair (i, j), or ``None`` when it is not in S_gamma."""
    def is_simple(self, i: int, j: int) -> bool:
        """Whether (i, j) is a simple loop: a pair in a trivial component."""
    def loop_duration(
        self,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> npt.NDArray[np.float64]:
        """Loop duration tau(t_i) for every sample, seconds (or normalized)."""
    def loop_area(
        self,
        a: float,
        b: float,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> float:
        """Loop area alpha(a, b), s^2 (or normalized)."""
    def loop_density(
        self,
        a: float,
        b: float,
        *,
        components: list[int] | None = None,
        side: _Side | str = "both",
        normalized: bool = False,
    ) -> float:
        """Loop density rho(a, b) = alpha(a, b) / (b - a), seconds (or normalized)."""

def find_loops(
    trajectory: Trajectory,
    *,
    gamma: float,
    metric: str
    | _MetricLike
    | Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], float]
    | None = None,
    threads: int | None = None,
) -> Loops:
    """Every inexact loop of ``trajectory`` at threshold ``gamma``, exactly, in components."""

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
    """A seeded synthetic drive on a Manhattan grid (x, y, z metres)."""

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
) -> Trajectory:
    """Reads a trajectory file (TUM, CSV, KITTI, EuRoC, TUC, g2o, MCAP)."""

def list_topics(path: str | PathLike[str]) -> list[dict[str, object]]:
    """The topics of an MCAP file, one dict per channel."""

@final
class Detections:
    """Detections: unordered pairs of times (t, t'), seconds, with optional scores."""

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
        """Detections from pose indices (i, j); the times are the poses' timestamps."""
    def locate(self, trajectory_or_loops: Trajectory | Loops) -> Detections:
        """The same detections placed on the nearest poses of a trajectory."""
    def __len__(self) -> int: ...
    @property
    def t(self) -> npt.NDArray[np.float64]:
        """The earlier time t of each pair, seconds."""
    @property
    def t_prime(self) -> npt.NDArray[np.float64]:
        """The later time t' >= t of each pair, seconds."""
    @property
    def i(self) -> npt.NDArray[np.int64] | None:
        """Pose index i of each pair, or ``None`` when not placed on a trajectory."""
    @property
    def j(self) -> npt.NDArray[np.int64] | None:
        """Pose index j >= i of each pair, or ``None`` when not placed on a trajectory."""
    @property
    def score(self) -> npt.NDArray[np.float64] | None:
        """The score of each pair, or ``None`` without scores."""
    @property
    def poses(self) -> int | None:
        """Poses of the trajectory the detections are placed on, or ``None``."""
    def to_pandas(self) -> pandas.DataFrame:
        """The detections as a DataFrame (needs pandas): t, t_prime[, i, j][, score]."""

@final
class DetectionClusters:
    """The connected components of the epsilon graph of detections."""

    def __len__(self) -> int: ...
    @property
    def epsilon_s(self) -> float:
        """The threshold epsilon, seconds."""
    @property
    def cell_side_s(self) -> float:
        """Side of the grid cells, seconds."""
    @property
    def detections(self) -> Detections:
        """The detections that were clustered."""
    @property
    def labels(self) -> npt.NDArray[np.int64]:
        """The cluster id of each detection."""
    @property
    def clusters(self) -> Table:
        """The clusters as a Table of numpy columns, one row a cluster."""

@final
class Samples:
    """The samples a sampler chose, in order of (t, t'), as numpy columns."""

    def __len__(self) -> int: ...
    @property
    def sampler(self) -> str:
        """The sampler's name."""
    @property
    def groups(self) -> int:
        """Number of groups (clusters or components) sampled from."""
    @property
    def available(self) -> int:
        """Number of candidates the sampler chose from."""
    @property
    def poses(self) -> int | None:
        """Poses of the trajectory the pairs index, or ``None``."""
    @property
    def warnings(self) -> list[str]:
        """Warnings, as sentences."""
    @property
    def t(self) -> npt.NDArray[np.float64]:
        """The earlier time of each sample, seconds."""
    @property
    def t_prime(self) -> npt.NDArray[np.float64]:
        """The later time of each sample, seconds."""
    @property
    def i(self) -> npt.NDArray[np.int64] | None:
        """Pose index i of each sample, or ``None`` when not placed on a trajectory."""
    @property
    def j(self) -> npt.NDArray[np.int64] | None:
        """Pose index j of each sample, or ``None`` when not placed on a trajectory."""
    @property
    def component(self) -> npt.NDArray[np.int64]:
        """The exact loop component of each sample; -1 when unknown or outside S_gamma."""
    @property
    def cluster(self) -> npt.NDArray[np.int64]:
        """The detection cluster of each sample; -1 for samples of Loops."""
    @property
    def detection(self) -> npt.NDArray[np.int64]:
        """The detection index of each sample; -1 for samples of Loops."""
    @property
    def distance(self) -> npt.NDArray[np.float64]:
        """delta(x_i, x_j) of each sample; NaN where not measured."""
    @property
    def score(self) -> npt.NDArray[np.float64] | None:
        """The detection's score of each sample, or ``None``."""
    def locate(self, loops: Loops) -> Samples:
        """The same samples placed on the loops' poses, with their exact components."""
    def measure(self, trajectory: Trajectory, *, metric: _MetricArg = None) -> Samples:
        """The same samples placed on ``trajectory``, with their distances."""
    def to_pandas(self) -> pandas.DataFrame:
        """The samples as a DataFrame (needs pandas), one row a sample."""
    def to_csv(self, path: str | PathLike[str], *, overwrite: bool = False) -> None:
        """Writes the samples as CSV, atomically."""
    def to_json(self, path: str | PathLike[str], *, overwrite: bool = False) -> None:
        """Writes the samples as JSON, atomically."""

@final
class SampleQuality:
    """P1, P2 and P3 of a sample, against the exact loop components."""

    @property
    def samples(self) -> int:
        """Number of samples."""
    @property
    def outside(self) -> int:
        """Samples outside S_gamma."""
    @property
    def components(self) -> int:
        """Loop components that can be sampled."""
    @property
    def covered(self) -> int:
        """P1: components with at least one sample."""
    @property
    def nontrivial_components(self) -> int:
        """Non-trivial components that can be sampled."""
    @property
    def nontrivial_covered(self) -> int:
        """P1 over the non-trivial components."""
    @property
    def coverage(self) -> float:
        """P1 as a fraction."""
    @property
    def missed(self) -> Table:
        """P1: the components without a sample, largest first: id, trivial, area_s2, pair_count."""
    @property
    def epsilon_s(self) -> float:
        """The epsilon of P2, seconds."""
    @property
    def redundant(self) -> int:
        """P2: samples with another sample of their component within epsilon."""
    @property
    def redundancy(self) -> float:
        """P2 as a fraction."""
    @property
    def median_spacing_s(self) -> float | None:
        """P2: median distance to the nearest other sample of the same component, seconds."""
    @property
    def p3_slope(self) -> float | None:
        """P3: slope of ln(samples) on ln(area) across the covered components."""
    @property
    def p3_components(self) -> int:
        """Number of components in the P3 fit."""
    @property
    def per_component(self) -> npt.NDArray[np.int64]:
        """Samples per component, int64, by component id (one per row of Loops.components)."""
    @property
    def sample_components(self) -> npt.NDArray[np.int64]:
        """The exact component of each sample; -1 outside S_gamma."""
    @property
    def nearest_spacing_s(self) -> npt.NDArray[np.float64]:
        """Each sample's distance to the nearest other sample of its component, seconds."""

def draw_detections(
    loops: Loops, *, rate: float | None = None, budget: int | None = None, seed: int
) -> Detections:
    """Detections drawn uniformly from the exact S_gamma of ``loops``."""

def cluster_detections(
    detections: Detections, *, epsilon_s: float | None = None, threads: int | None = None
) -> DetectionClusters:
    """The exact connected components of the epsilon graph of the detections."""

def sample(
    source: DetectionClusters | Loops,
    sampler: _SamplerName | str,
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
    """Samples inexact loops from detection clusters or exact loop components."""

def sample_quality(
    samples: Samples, loops: Loops, *, epsilon_s: float | None = None
) -> SampleQuality:
    """P1, P2 and P3 of ``samples`` against the exact loop components of ``loops``."""
