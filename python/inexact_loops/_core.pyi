"""Type stubs of the compiled module ``inexact_loops._core``."""

from collections.abc import Callable
from os import PathLike
from typing import Literal, Protocol, final

import numpy as np
import numpy.typing as npt

__all__ = ["Loops", "Trajectory", "__version__", "find_loops", "read_trajectory", "urban_drive"]

__version__: str

_Side = Literal["both", "begin", "end"]

class _MetricLike(Protocol):
    @property
    def spec(self) -> str: ...

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
    def pairs(self) -> int:
        """Lattice cells of S_gamma in the full plane (both halves and the diagonal)."""
    @property
    def warnings(self) -> list[str]:
        """Warnings about the result, as sentences."""
    @property
    def components(self) -> dict[str, npt.NDArray[np.generic]]:
        """The loop components as numpy columns, one row a component."""
    def runs(self) -> dict[str, npt.NDArray[np.int64]]:
        """The runs of S_gamma's upper half: ``row``, ``start``, ``end``, ``component``."""
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
    se3: bool = False,
) -> Trajectory:
    """A seeded synthetic drive on a Manhattan grid (x, y, z metres)."""

def read_trajectory(
    path: str | PathLike[str],
    *,
    format: Literal["tum", "csv"] | str | None = None,
    axes: tuple[int, int] | None = None,
    metric: str | _MetricLike | None = None,
) -> Trajectory:
    """Reads a TUM or CSV trajectory file."""
