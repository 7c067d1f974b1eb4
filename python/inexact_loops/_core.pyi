"""Type stubs of the compiled module ``inexact_loops._core``."""

from os import PathLike
from typing import Literal, final

import numpy as np
import numpy.typing as npt

__all__ = ["Loops", "Trajectory", "__version__", "find_loops", "read_trajectory", "urban_drive"]

__version__: str

_Side = Literal["both", "begin", "end"]

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
    metric: str | None = None,
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
) -> Trajectory:
    """A seeded synthetic drive on a Manhattan grid (x, y, z metres)."""

def read_trajectory(
    path: str | PathLike[str],
    *,
    format: Literal["tum", "csv"] | str | None = None,
    axes: tuple[int, int] | None = None,
) -> Trajectory:
    """Reads a TUM or CSV trajectory file."""
