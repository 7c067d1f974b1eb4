"""Metrics by name, with parameters: pass one as ``find_loops(..., metric=...)``.

Each object only records what you set; its :attr:`spec` is the text the library parses (the
same text the command line's ``--metric`` takes), and anything left as ``None`` takes the
library's default. Build the trajectory with the matching constructor, e.g.
:meth:`inexact_loops.Trajectory.se3` for :class:`SE3`.

Example:
    >>> import inexact_loops as il
    >>> il.metrics.SE3(rotation_weight_m_per_rad=10.0).spec
    'se3(rotation_weight_m_per_rad=10.0)'
    >>> il.metrics.SO3(rotation="chordal").spec
    'so3(rotation=chordal)'
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

__all__ = [
    "SE2",
    "SE3",
    "SO3",
    "Angular",
    "Euclidean",
    "Haversine",
    "Metric",
    "SE3Rotation",
    "Sphere",
    "Torus",
]

RotationDistance = Literal["geodesic", "chordal"]


class Metric:
    """Base of the metric objects: :attr:`spec` is ``name(key=value, ...)``."""

    _name: str = ""

    @property
    def spec(self) -> str:
        """The metric as text, e.g. ``"se3(rotation_weight_m_per_rad=10.0)"``."""
        given = [
            f"{f.name}={getattr(self, f.name)}"
            for f in fields(self)  # type: ignore[arg-type]
            if getattr(self, f.name) is not None
        ]
        return f"{self._name}({', '.join(given)})" if given else self._name

    def __str__(self) -> str:
        return self.spec


@dataclass(frozen=True)
class Euclidean(Metric):
    """L2 distance on R^n (positions, raw descriptors)."""

    _name = "euclidean"


@dataclass(frozen=True)
class SO3(Metric):
    """Rotations: geodesic angle (radians, default) or chordal ``||R_a - R_b||_F`` (the paper's).

    Points: :meth:`~inexact_loops.Trajectory.so3` or
    :meth:`~inexact_loops.Trajectory.so3_from_rotation_vectors`.
    """

    rotation: RotationDistance | None = None
    _name = "so3"


@dataclass(frozen=True)
class SE3(Metric):
    """Rigid motions: ``||p_a - p_b|| + w * rotation distance`` (metres).

    ``rotation_weight_m_per_rad`` (w >= 0, required) says how many metres one radian of rotation
    counts for; 0 compares translations only. Points: :meth:`~inexact_loops.Trajectory.se3`.
    """

    rotation_weight_m_per_rad: float
    rotation: RotationDistance | None = None
    _name = "se3"


@dataclass(frozen=True)
class SE3Rotation(Metric):
    """The rotation part of SE(3) poses only (radians or chordal units)."""

    rotation: RotationDistance | None = None
    _name = "se3_rotation"


@dataclass(frozen=True)
class SE2(Metric):
    """Planar poses: ``||p_a - p_b|| + w * |theta_a - theta_b|`` (least angular difference)."""

    rotation_weight_m_per_rad: float
    _name = "se2"


@dataclass(frozen=True)
class Torus(Metric):
    """The flat torus: L2 norm of the least angular differences (radians)."""

    _name = "torus"


@dataclass(frozen=True)
class Sphere(Metric):
    """Great-circle distance on S^2, ``radius * angle`` (radius default 1: radians)."""

    radius: float | None = None
    _name = "sphere"


@dataclass(frozen=True)
class Haversine(Metric):
    """GNSS: haversine distance on a sphere (default the mean Earth radius), with heights (m)."""

    radius_m: float | None = None
    _name = "haversine"


@dataclass(frozen=True)
class Angular(Metric):
    """The angle between unit descriptor vectors (radians): place recognition's pseudometric."""

    _name = "angular"
