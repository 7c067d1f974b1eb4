"""Poses and rigid motions: the references and estimates of the evaluation."""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .._core import (
    Trajectory,
    read_trajectory,
)
from ..errors import InvalidParameterError

# ---------------------------------------------------------------------------------------------
# Rigid motions, vectorised over a leading axis
# ---------------------------------------------------------------------------------------------


def rot2(theta: npt.ArrayLike) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def rot3(rotvec: npt.ArrayLike) -> np.ndarray:
    """Rotation matrices from rotation vectors (Rodrigues), shape (..., 3) -> (..., 3, 3)."""
    v = np.asarray(rotvec, dtype=float)
    angle = np.linalg.norm(v, axis=-1)[..., None, None]
    k = np.zeros(v.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2] = -v[..., 2], v[..., 1]
    k[..., 1, 0], k[..., 1, 2] = v[..., 2], -v[..., 0]
    k[..., 2, 0], k[..., 2, 1] = -v[..., 1], v[..., 0]
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    a = np.where(small, 1.0 - angle**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - angle**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    return np.eye(3) + a * k + b * (k @ k)


def homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    d = rotation.shape[-1]
    out = np.zeros(rotation.shape[:-2] + (d + 1, d + 1))
    out[..., :d, :d] = rotation
    out[..., :d, d] = translation
    out[..., d, d] = 1.0
    return out


def rigid_inverse(m: np.ndarray) -> np.ndarray:
    d = m.shape[-1] - 1
    rt = np.swapaxes(m[..., :d, :d], -1, -2)
    return homogeneous(rt, -(rt @ m[..., :d, d, None])[..., 0])


def quat_xyzw_to_matrix(q: np.ndarray) -> np.ndarray:
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def _matrix_to_quat_xyzw(r: np.ndarray) -> np.ndarray:
    """Unit quaternions (x, y, z, w) of rotation matrices (Shepperd's method, w >= 0)."""
    r = np.asarray(r, dtype=float)
    out = np.empty(r.shape[:-2] + (4,))
    trace = np.trace(r, axis1=-2, axis2=-1)
    cases = np.stack([trace, r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]], -1).argmax(-1)
    for case in range(4):
        sel = cases == case
        m = r[sel]
        if case == 0:
            s = np.sqrt(1.0 + np.trace(m, axis1=-2, axis2=-1)) * 2
            q = np.stack(
                [
                    (m[:, 2, 1] - m[:, 1, 2]) / s,
                    (m[:, 0, 2] - m[:, 2, 0]) / s,
                    (m[:, 1, 0] - m[:, 0, 1]) / s,
                    0.25 * s,
                ],
                -1,
            )
        else:
            a = case - 1
            b, c = (a + 1) % 3, (a + 2) % 3
            s = np.sqrt(1.0 + m[:, a, a] - m[:, b, b] - m[:, c, c]) * 2
            q = np.empty((len(m), 4))
            q[:, a] = 0.25 * s
            q[:, b] = (m[:, b, a] + m[:, a, b]) / s
            q[:, c] = (m[:, c, a] + m[:, a, c]) / s
            q[:, 3] = (m[:, c, b] - m[:, b, c]) / s
        out[sel] = q
    return out * np.where(out[..., 3:] < 0, -1.0, 1.0)


# ---------------------------------------------------------------------------------------------
# Poses
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Poses:
    """A trajectory of rigid poses: timestamps and homogeneous matrices, SE(2) or SE(3).

    Attributes:
        timestamps: shape ``(n,)``, seconds, strictly increasing.
        matrices: shape ``(n, 3, 3)`` (SE(2)) or ``(n, 4, 4)`` (SE(3)): pose k maps the body
            frame at time k into the world frame (``world_from_body``).

    Build it with :meth:`se2`, :meth:`se3`, :meth:`from_positions` (heading along the motion),
    :meth:`from_trajectory` (an :class:`~inexact_loops.Trajectory`) or :meth:`read` (a pose
    file, as :func:`~inexact_loops.read_trajectory` reads it).

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import Poses
        >>> poses = Poses.se2([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0.5], [2, 1, 1.0]])
        >>> poses.dim, len(poses), poses.positions[2].tolist()
        (2, 3, [2.0, 1.0])
    """

    timestamps: np.ndarray
    matrices: np.ndarray

    def __post_init__(self) -> None:
        t = np.ascontiguousarray(self.timestamps, dtype=float)
        m = np.ascontiguousarray(self.matrices, dtype=float)
        if t.ndim != 1 or m.shape not in ((len(t), 3, 3), (len(t), 4, 4)):
            raise ValueError(
                f"Poses: timestamps of shape (n,) and matrices of shape (n, 3, 3) or (n, 4, 4) "
                f"expected, got {t.shape} and {m.shape}"
            )
        if len(t) < 2:
            raise InvalidParameterError(f"Poses: at least 2 poses needed, got {len(t)}")
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise InvalidParameterError(f"Poses: timestamp {bad[0]} is {t[bad[0]]}")
        steps = np.flatnonzero(np.diff(t) <= 0)
        if steps.size:
            k = steps[0] + 1
            raise InvalidParameterError(
                f"Poses: timestamps must increase: pose {k} at {t[k]} s follows {t[k - 1]} s"
            )
        bad = np.flatnonzero(~np.isfinite(m).all(axis=(1, 2)))
        if bad.size:
            raise InvalidParameterError(f"Poses: pose {bad[0]} is not finite")
        object.__setattr__(self, "timestamps", t)
        object.__setattr__(self, "matrices", m)

    def __len__(self) -> int:
        return len(self.timestamps)

    @property
    def dim(self) -> int:
        """2 for SE(2), 3 for SE(3)."""
        return self.matrices.shape[-1] - 1

    @property
    def positions(self) -> np.ndarray:
        """Shape ``(n, dim)``: the translations, metres."""
        return self.matrices[:, : self.dim, self.dim].copy()

    @property
    def rotations(self) -> np.ndarray:
        """Shape ``(n, dim, dim)``."""
        return self.matrices[:, : self.dim, : self.dim].copy()

    @property
    def xytheta(self) -> np.ndarray:
        """SE(2) only: shape ``(n, 3)``, x, y and the heading theta (rad)."""
        if self.dim != 2:
            raise InvalidParameterError("Poses.xytheta: only for SE(2) poses")
        m = self.matrices
        return np.c_[m[:, 0, 2], m[:, 1, 2], np.arctan2(m[:, 1, 0], m[:, 0, 0])]

    @property
    def quaternions_xyzw(self) -> np.ndarray:
        """SE(3) only: shape ``(n, 4)``, unit quaternions x, y, z, w (w >= 0)."""
        if self.dim != 3:
            raise InvalidParameterError("Poses.quaternions_xyzw: only for SE(3) poses")
        return _matrix_to_quat_xyzw(self.rotations)

    @classmethod
    def se2(cls, timestamps: npt.ArrayLike, xytheta: npt.ArrayLike) -> Poses:
        """SE(2) poses from ``(n, 3)`` rows x, y (metres), theta (rad)."""
        p = np.asarray(xytheta, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"Poses.se2: xytheta of shape (n, 3) expected, got {p.shape}")
        return cls(np.asarray(timestamps, dtype=float), homogeneous(rot2(p[:, 2]), p[:, :2]))

    @classmethod
    def se3(
        cls, timestamps: npt.ArrayLike, positions: npt.ArrayLike, quaternions_xyzw: npt.ArrayLike
    ) -> Poses:
        """SE(3) poses from ``(n, 3)`` positions (metres) and ``(n, 4)`` quaternions x, y, z, w."""
        p = np.asarray(positions, dtype=float)
        q = np.asarray(quaternions_xyzw, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3 or q.shape != (len(p), 4):
            raise ValueError(
                f"Poses.se3: positions (n, 3) and quaternions (n, 4) expected, got {p.shape} "
                f"and {q.shape}"
            )
        norms = np.linalg.norm(q, axis=1)
        bad = np.flatnonzero(~(norms > 0))
        if bad.size:
            raise InvalidParameterError(f"Poses.se3: quaternion {bad[0]} has no direction")
        return cls(np.asarray(timestamps, dtype=float), homogeneous(quat_xyzw_to_matrix(q), p))

    @classmethod
    def from_positions(cls, timestamps: npt.ArrayLike, positions: npt.ArrayLike) -> Poses:
        """SE(2) poses from ``(n, 2)`` positions, the heading along the motion.

        The heading of pose k is the direction from pose k-1 to pose k+1 (one-sided at the ends);
        where the vehicle stands still (the two are less than 1 mm apart) it keeps the heading
        it had, the first motion's before any. For a vehicle that drives forwards (the built-in
        :func:`~inexact_loops.urban_drive`), that is its yaw.
        """
        p = np.asarray(positions, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2:
            raise ValueError(
                f"Poses.from_positions: positions of shape (n, 2) expected (a plane), got {p.shape}"
            )
        ahead = np.r_[p[1:], p[-1:]] - np.r_[p[:1], p[:-1]]
        moving = np.linalg.norm(ahead, axis=1) > 1e-3
        if not moving.any():
            heading = np.zeros(len(p))
        else:
            raw = np.arctan2(ahead[:, 1], ahead[:, 0])
            last = np.maximum.accumulate(np.where(moving, np.arange(len(p)), -1))
            first = int(np.argmax(moving))
            heading = raw[np.where(last >= 0, last, first)]
        return cls.se2(timestamps, np.c_[p, heading])

    @classmethod
    def from_trajectory(cls, trajectory: Trajectory) -> Poses:
        """Poses of an :class:`~inexact_loops.Trajectory`: ``se2`` and ``se3`` ones as they are,
        Euclidean ones of 2 coordinates by :meth:`from_positions`.

        Raises:
            InvalidParameterError: another manifold, or Euclidean points not in a plane.
        """
        x = trajectory.positions
        t = trajectory.timestamps
        if trajectory.manifold == "se2":
            return cls.se2(t, x)
        if trajectory.manifold == "se3":
            return cls.se3(t, x[:, :3], x[:, 3:])
        if trajectory.manifold == "euclidean" and trajectory.dim == 2:
            return cls.from_positions(t, x)
        raise InvalidParameterError(
            f"Poses.from_trajectory: a {trajectory.manifold} trajectory of {trajectory.dim} "
            "coordinates is no rigid motion: give SE(2) or SE(3) poses, or positions in a plane"
        )

    @classmethod
    def read(
        cls,
        path: str | PathLike[str] | list[str | PathLike[str]],
        *,
        dim: Literal[2, 3] = 2,
        axes: tuple[int, int] | None = None,
        **read_options: Any,
    ) -> Poses:
        """Reads a pose file (any format :func:`~inexact_loops.read_trajectory` reads).

        Args:
            path: the file (or files, one trajectory).
            dim: 2 for SE(2) poses in the plane ``axes`` (x-y by default; ``(0, 2)`` for
                KITTI's ground plane, heading about the plane's normal), 3 for SE(3).
            axes: the plane for ``dim=2``.
            read_options: passed to :func:`~inexact_loops.read_trajectory` (``rate_hz``,
                ``times``, ``format``, ``topic``, ...).

        A file of positions without orientations (CSV ``t,x,y``) is read as positions in the
        plane and headed along the motion (:meth:`from_positions`).
        """
        metric = (
            "se2(rotation_weight_m_per_rad=0)" if dim == 2 else "se3(rotation_weight_m_per_rad=0)"
        )
        try:
            traj = read_trajectory(path, metric=metric, axes=axes, **read_options)
        except InvalidParameterError as err:
            if "does not fit" not in str(err) or dim != 2:
                raise
            traj = read_trajectory(path, axes=axes or (0, 1), **read_options)
        return cls.from_trajectory(traj)

    def take(self, indices: npt.ArrayLike) -> Poses:
        """The poses at these indices (increasing)."""
        k = np.asarray(indices, dtype=np.int64)
        return Poses(self.timestamps[k], self.matrices[k])

    def keyframes(self, step_m: float) -> np.ndarray:
        """Indices of keyframes: the first pose, then each pose at least ``step_m`` metres (by
        position) from the previous keyframe, and the last pose. A stop becomes one keyframe.
        ``step_m <= 0`` keeps every pose."""
        if step_m <= 0:
            return np.arange(len(self))
        p = self.positions
        keep = [0]
        last = p[0]
        for k in range(1, len(p)):
            if np.linalg.norm(p[k] - last) >= step_m:
                keep.append(k)
                last = p[k]
        if keep[-1] != len(p) - 1:
            keep.append(len(p) - 1)
        return np.asarray(keep, dtype=np.int64)

    def relative(self, i: npt.ArrayLike, j: npt.ArrayLike) -> np.ndarray:
        """The relative poses ``T_i^-1 T_j`` (pose j in the frame of pose i), shape
        ``(m, d+1, d+1)``."""
        m = self.matrices
        return rigid_inverse(m[np.asarray(i)]) @ m[np.asarray(j)]

    def to_trajectory(self) -> Trajectory:
        """The positions as a Euclidean :class:`~inexact_loops.Trajectory` (what the samplers and
        the baselines measure, in metres)."""
        return Trajectory(self.timestamps, self.positions)

    def to_evo(self) -> Any:
        """An ``evo.core.trajectory.PoseTrajectory3D`` (SE(2) lifted to z = 0); needs evo."""
        from evo.core.trajectory import PoseTrajectory3D

        return PoseTrajectory3D(poses_se3=list(_lift3(self.matrices)), timestamps=self.timestamps)

    def to_tum(self, path: str | PathLike[str]) -> None:
        """Writes the poses as a TUM file (``t x y z qx qy qz qw``; SE(2) at z = 0)."""
        m = _lift3(self.matrices)
        q = _matrix_to_quat_xyzw(m[:, :3, :3])
        rows = np.c_[self.timestamps, m[:, :3, 3], q]
        np.savetxt(path, rows, fmt="%.9f")


def _lift3(m: np.ndarray) -> np.ndarray:
    if m.shape[-1] == 4:
        return m
    out = np.tile(np.eye(4), (len(m), 1, 1))
    out[:, :2, :2] = m[:, :2, :2]
    out[:, :2, 3] = m[:, :2, 2]
    return out
