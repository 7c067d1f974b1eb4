"""Do the samples make better maps? Pose-graph optimisation behind every sampler.

The paper's samplers are judged by coverage (P1-P3); this module judges them by the map they
make. It closes the loop from candidate pairs to a trajectory error, with every piece seeded and
documented, so that you can see on your own data which sampler and which budget to use:

1. a **reference** trajectory (:class:`Poses`): ground truth, or your best estimate;
2. an **odometry** (:class:`Odometry`): yours, or simulated from the reference by a seeded
   :class:`DriftModel` (noise per step in translation and rotation, a heading bias, a scale
   bias), in SE(2) or SE(3);
3. **candidates** from a sampler or a baseline under a budget (:func:`choose_candidates`, which
   calls :func:`inexact_loops.sample`): chosen on the reference, or -- what a user without ground
   truth has -- on the odometry's own estimate with an inflated gamma (:class:`CandidateRule`);
4. a **verifier** standing in for the scan matcher (:class:`Verifier`): it succeeds and errs as
   documented functions of the true distance between the pair's poses, and returns a documented
   share of wrong matches (outliers);
5. a **pose-graph back end** (:func:`optimize`, GTSAM): odometry and verified loop factors,
   Levenberg-Marquardt with a robust kernel (Cauchy by default; Huber, plain Gaussian, or GNC);
6. the **errors**: ATE (:func:`ate`) and RPE (:func:`rpe`) as evo's APE and RPE on the
   translation part (``evo_ape -a``, ``evo_rpe``), tested against evo.

:func:`evaluate` runs the grid (samplers x budgets x seeds x options) and returns a
:class:`Results` table with its summary (median and spread over seeds), CSV/JSON writers and a
plot of the error against the number of matches (:func:`plot_error_vs_matches`). The command
``loops-eval`` runs it on a pose file (``loops-eval --help``).

The fleet case -- several sessions in one frame, each with its own odometry and an unknown
start, candidates from :func:`~inexact_loops.sample_fleet` (within and between sessions, or
between only), a multi-session GTSAM graph, the joint and inter-session errors -- is
:func:`evaluate_fleet` (``loops-eval --fleet``), with :func:`evaluate_fleet_one`,
:func:`optimize_fleet`, :func:`fleet_errors` and :func:`plot_fleet_error_vs_matches`; its
method is in :mod:`inexact_loops._fleet_evaluate`.

Needs GTSAM for the back end: ``pip install '.[maps]'`` in a checkout (the simulation, the
verifier and the errors work without it); matplotlib for the plot.

Example:
    >>> import numpy as np
    >>> from inexact_loops import evaluate as ev
    >>> angle = np.linspace(0, 4 * np.pi, 400)                 # twice round a 50 m circle
    >>> circle = 50 * np.c_[np.cos(angle), np.sin(angle)]
    >>> reference = ev.Poses.from_positions(np.arange(400.0), circle)
    >>> odometry = ev.DriftModel(heading_bias_rad_per_m=1e-3).simulate(reference, seed=0)
    >>> round(ev.ate(reference, odometry.estimate, align=False), 1) > 5.0   # drifted
    True
    >>> matches = ev.Verifier().verify(reference, [10, 50, 120], [210, 250, 320], seed=0)
    >>> len(matches.i) <= 3
    True
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

from ._core import (
    Separation,
    Trajectory,
    cluster_detections,
    draw_detections,
    find_loops,
    read_trajectory,
    sample,
    sampler_symbol,
)
from .errors import InvalidParameterError
from .table import Table

if TYPE_CHECKING:
    from ._fleet_evaluate import (
        FLEET_COLUMNS,
        SESSION_COLUMNS,
        FleetErrors,
        FleetResults,
        FleetRule,
        choose_fleet_candidates,
        evaluate_fleet,
        evaluate_fleet_one,
        fleet_errors,
        fleet_references,
        optimize_fleet,
        place_sessions,
        plot_fleet_error_vs_matches,
        session_key,
        simulate_fleet_odometry,
    )

__all__ = [
    "BASELINES",
    "FLEET_COLUMNS",
    "VERIFIER_MODELS",
    "SAMPLERS",
    "SESSION_COLUMNS",
    "BackEnd",
    "CandidateRule",
    "DriftModel",
    "FleetErrors",
    "FleetResults",
    "FleetRule",
    "Matches",
    "Odometry",
    "Poses",
    "Results",
    "Rounds",
    "Verifier",
    "ape_errors",
    "ate",
    "choose_candidates",
    "choose_fleet_candidates",
    "evaluate",
    "evaluate_fleet",
    "evaluate_fleet_one",
    "evaluate_one",
    "fleet_errors",
    "fleet_references",
    "optimize",
    "optimize_fleet",
    "place_sessions",
    "plot_error_vs_matches",
    "plot_fleet_error_vs_matches",
    "rpe",
    "rpe_errors",
    "session_key",
    "simulate_fleet_odometry",
    "umeyama",
]

#: The samplers of the paper and beyond (:func:`inexact_loops.sample`'s names).
SAMPLERS: tuple[str, ...] = (
    "one",
    "rho",
    "rho-dispersed",
    "closest-first",
    "closest-then-spread",
    "alpha",
)
#: The candidate rules of deployed SLAM systems, under the same budget.
BASELINES: tuple[str, ...] = ("lio-sam", "hdl-graph-slam", "cartographer", "time-gap")

_GTSAM_HINT = (
    "the pose-graph back end needs GTSAM: pip install '.[maps]' in a checkout "
    "(or pip install gtsam)"
)


def _gtsam() -> Any:
    try:
        import gtsam
    except ImportError as err:  # pragma: no cover - exercised only without gtsam
        raise ImportError(_GTSAM_HINT) from err
    return gtsam


# ---------------------------------------------------------------------------------------------
# Rigid motions, vectorised over a leading axis
# ---------------------------------------------------------------------------------------------


def _rot2(theta: npt.ArrayLike) -> np.ndarray:
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def _rot3(rotvec: npt.ArrayLike) -> np.ndarray:
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


def _homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    d = rotation.shape[-1]
    out = np.zeros(rotation.shape[:-2] + (d + 1, d + 1))
    out[..., :d, :d] = rotation
    out[..., :d, d] = translation
    out[..., d, d] = 1.0
    return out


def _inverse(m: np.ndarray) -> np.ndarray:
    d = m.shape[-1] - 1
    rt = np.swapaxes(m[..., :d, :d], -1, -2)
    return _homogeneous(rt, -(rt @ m[..., :d, d, None])[..., 0])


def _quat_xyzw_to_matrix(q: np.ndarray) -> np.ndarray:
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
        return cls(np.asarray(timestamps, dtype=float), _homogeneous(_rot2(p[:, 2]), p[:, :2]))

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
        return cls(np.asarray(timestamps, dtype=float), _homogeneous(_quat_xyzw_to_matrix(q), p))

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
        return _inverse(m[np.asarray(i)]) @ m[np.asarray(j)]

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


# ---------------------------------------------------------------------------------------------
# Odometry
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Odometry:
    """Odometry: the measured motion between consecutive poses, and how sure it is.

    Attributes:
        steps: shape ``(n-1, d+1, d+1)``: step k is the measured pose k+1 in the frame of pose
            k.
        translation_sigma_m: shape ``(n-1,)``: the standard deviation the back end assumes for
            each step's translation, per axis, metres.
        rotation_sigma_rad: shape ``(n-1,)``: the same for its rotation, per axis, radians.
        start: shape ``(d+1, d+1)``: the first pose (where dead reckoning starts, and the
            anchor of the pose graph).
        timestamps: shape ``(n,)``.

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import Odometry, Poses
        >>> poses = Poses.se2(np.arange(3.0), [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
        >>> odometry = Odometry.from_poses(poses, translation_sigma_m=0.1, rotation_sigma_rad=0.01)
        >>> odometry.estimate.positions[-1].tolist()
        [2.0, 0.0]
    """

    steps: np.ndarray
    translation_sigma_m: np.ndarray
    rotation_sigma_rad: np.ndarray
    start: np.ndarray
    timestamps: np.ndarray

    @property
    def dim(self) -> int:
        """2 for SE(2), 3 for SE(3)."""
        return self.steps.shape[-1] - 1

    @property
    def estimate(self) -> Poses:
        """Dead reckoning: the steps composed from the start."""
        out = np.empty((len(self.steps) + 1,) + self.start.shape)
        out[0] = self.start
        for k, step in enumerate(self.steps):
            out[k + 1] = out[k] @ step
        return Poses(self.timestamps, out)

    @classmethod
    def from_poses(
        cls,
        estimate: Poses,
        *,
        translation_sigma_m: float | npt.ArrayLike,
        rotation_sigma_rad: float | npt.ArrayLike,
    ) -> Odometry:
        """Your odometry, given as its estimate (one pose per reference pose, same timestamps):
        its steps, with the standard deviations the back end is to assume (one for all steps,
        or one per step)."""
        n = len(estimate) - 1
        t_sigma = np.broadcast_to(np.asarray(translation_sigma_m, dtype=float), (n,)).copy()
        r_sigma = np.broadcast_to(np.asarray(rotation_sigma_rad, dtype=float), (n,)).copy()
        if not (t_sigma > 0).all() or not (r_sigma > 0).all():
            raise InvalidParameterError("Odometry.from_poses: the sigmas must be positive")
        steps = estimate.relative(np.arange(n), np.arange(1, n + 1))
        return cls(steps, t_sigma, r_sigma, estimate.matrices[0].copy(), estimate.timestamps)

    def take(self, indices: npt.ArrayLike) -> Odometry:
        """The odometry between these poses (increasing indices): steps composed, variances
        added."""
        k = np.asarray(indices, dtype=np.int64)
        est = self.estimate.matrices
        steps = _inverse(est[k[:-1]]) @ est[k[1:]]
        t_var = np.r_[0.0, np.cumsum(self.translation_sigma_m**2)]
        r_var = np.r_[0.0, np.cumsum(self.rotation_sigma_rad**2)]
        return Odometry(
            steps,
            np.sqrt(t_var[k[1:]] - t_var[k[:-1]]),
            np.sqrt(r_var[k[1:]] - r_var[k[:-1]]),
            est[k[0]].copy(),
            self.timestamps[k],
        )


@dataclass(frozen=True)
class DriftModel:
    """Odometry simulated from the reference, seeded: the true step of each pose to the next,
    with noise and biases.

    For the step from pose k to k+1, of true length l (metres) and true relative pose
    ``(R, t)``, the measured step is

    - translation ``(1 + scale_bias) * t + e_t``, ``e_t ~ N(0, s_t**2 * l * I)`` per axis;
    - rotation ``R * Exp(e_r + heading_bias_rad_per_m * l * u)``, ``e_r ~ N(0, s_r**2 * l)`` per
      axis (SE(2): the heading only), ``u`` the body's up axis (SE(3): ``up_axis``);

    with ``s_t = translation_sigma_m_per_sqrt_m`` and ``s_r = rotation_sigma_rad_per_sqrt_m``.
    The noise is a random walk in distance travelled: its variance grows with the path, not with
    the number of poses, so keyframing the trajectory does not change it, and a vehicle standing
    still does not drift. The back end is told the noise's standard deviations (at least
    ``min_translation_sigma_m`` and ``min_rotation_sigma_rad``), not the biases.

    The defaults are a good lidar odometry: 2 cm per sqrt(m) and 1 mrad per sqrt(m) of random
    walk, and 2e-5 rad of heading bias per metre (1.1 degrees per km); after 1 km the
    position is off by a few metres to tens of metres.

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import DriftModel, Poses
        >>> x = np.arange(101.0)
        >>> line = Poses.se2(x, np.c_[x, np.zeros(101), np.zeros(101)])
        >>> exact = DriftModel(translation_sigma_m_per_sqrt_m=0, rotation_sigma_rad_per_sqrt_m=0,
        ...                    heading_bias_rad_per_m=0).simulate(line, seed=1)
        >>> bool(np.allclose(exact.estimate.matrices, line.matrices))
        True
    """

    translation_sigma_m_per_sqrt_m: float = 0.02
    rotation_sigma_rad_per_sqrt_m: float = 0.001
    heading_bias_rad_per_m: float = 2e-5
    scale_bias: float = 0.0
    min_translation_sigma_m: float = 0.005
    min_rotation_sigma_rad: float = 0.0005
    up_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        for name in (
            "translation_sigma_m_per_sqrt_m",
            "rotation_sigma_rad_per_sqrt_m",
            "min_translation_sigma_m",
            "min_rotation_sigma_rad",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InvalidParameterError(f"DriftModel: {name} = {value} must be finite and >= 0")
        for name in ("heading_bias_rad_per_m", "scale_bias"):
            if not math.isfinite(getattr(self, name)):
                raise InvalidParameterError(f"DriftModel: {name} must be finite")

    def simulate(self, reference: Poses, *, seed: int) -> Odometry:
        """The odometry of ``reference`` under this model, seeded (numpy PCG64)."""
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x0D0]))
        n = len(reference) - 1
        d = reference.dim
        truth = reference.relative(np.arange(n), np.arange(1, n + 1))
        length = np.linalg.norm(truth[:, :d, d], axis=1)
        t_sd = self.translation_sigma_m_per_sqrt_m * np.sqrt(length)
        r_sd = self.rotation_sigma_rad_per_sqrt_m * np.sqrt(length)
        translation = (1.0 + self.scale_bias) * truth[:, :d, d] + rng.standard_normal(
            (n, d)
        ) * t_sd[:, None]
        bias = self.heading_bias_rad_per_m * length
        if d == 2:
            rotation = truth[:, :2, :2] @ _rot2(rng.standard_normal(n) * r_sd + bias)
        else:
            up = np.asarray(self.up_axis, dtype=float)
            up = up / np.linalg.norm(up)
            rotvec = rng.standard_normal((n, 3)) * r_sd[:, None] + bias[:, None] * up
            rotation = truth[:, :3, :3] @ _rot3(rotvec)
        return Odometry(
            _homogeneous(rotation, translation),
            np.maximum(t_sd, self.min_translation_sigma_m),
            np.maximum(r_sd, self.min_rotation_sigma_rad),
            reference.matrices[0].copy(),
            reference.timestamps,
        )


# ---------------------------------------------------------------------------------------------
# Candidates
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CandidateRule:
    """How candidates are chosen: which sampler, how many, on what.

    Attributes:
        sampler: a name :func:`~inexact_loops.sample` takes (:data:`SAMPLERS`, :data:`BASELINES`).
        budget: the number of candidates (scan matches to try).
        gamma: gamma of the loops, metres (the revisit radius).
        separation: keep only revisits, pairs at least 4 gamma apart along the path
            (:meth:`~inexact_loops.Separation.for_gamma` of ``gamma``), as the samplers do by
            default; ``False`` samples the paper's S_gamma.
        source: ``"exact"`` samples the exact loop components; ``"detections"`` draws
            detections from S_gamma at ``detection_rate`` and samples their epsilon-graph
            clusters (``epsilon_s``), as the paper's experiment does. Baselines always use
            ``"exact"`` (their own rule).
        on: ``"reference"`` chooses on the reference; ``"estimate"`` on the odometry's own
            estimate with gamma inflated to ``gamma_inflation * gamma`` (the separation stays
            4 gamma of path): what a user without ground truth has, whose estimate has drifted.
        gamma_inflation: the factor for ``on="estimate"`` (2 by default: a pair of poses up to
            gamma apart stays a candidate while the estimate's error between them is below
            gamma).
        detection_rate: for ``source="detections"``.
        epsilon_s: for ``source="detections"``.
        rounds: for ``on="estimate"``: the budget spent in this many rounds, each chosen on
            the estimate the matches of the rounds before corrected (:class:`Rounds`); 1: all
            at once on the odometry's estimate.
    """

    sampler: str
    budget: int
    gamma: float
    separation: bool = True
    source: Literal["exact", "detections"] = "exact"
    on: Literal["reference", "estimate"] = "reference"
    gamma_inflation: float = 2.0
    detection_rate: float = 0.01
    epsilon_s: float = 30.0
    rounds: int = 1

    def __post_init__(self) -> None:
        _check_rule("CandidateRule", self.sampler, self.budget, self.gamma)
        if self.source not in ("exact", "detections"):
            raise InvalidParameterError(
                f"CandidateRule: source {self.source!r}: exact or detections"
            )
        if self.on not in ("reference", "estimate"):
            raise InvalidParameterError(f"CandidateRule: on {self.on!r}: reference or estimate")
        if not (math.isfinite(self.gamma_inflation) and self.gamma_inflation >= 1):
            raise InvalidParameterError(
                f"CandidateRule: gamma_inflation = {self.gamma_inflation} must be >= 1"
            )
        if self.rounds < 1 or (self.rounds > 1 and self.on != "estimate"):
            raise InvalidParameterError(
                f"CandidateRule: rounds = {self.rounds}: at least 1, and more only with "
                'on="estimate"'
            )

    @property
    def is_baseline(self) -> bool:
        """Whether the sampler is a deployed system's rule."""
        return self.sampler in BASELINES


def _check_rule(kind: str, sampler: str, budget: int, gamma: float) -> None:
    """The checks a candidate rule of either kind (``kind``, its class's name) makes of its
    sampler, budget and gamma."""
    if sampler not in SAMPLERS + BASELINES:
        raise InvalidParameterError(
            f"{kind}: unknown sampler {sampler!r}: expected one of "
            + ", ".join(SAMPLERS + BASELINES)
        )
    if budget < 1:
        raise InvalidParameterError(f"{kind}: budget = {budget} must be >= 1")
    if not (math.isfinite(gamma) and gamma > 0):
        raise InvalidParameterError(f"{kind}: gamma = {gamma} must be > 0")


def choose_candidates(
    poses: Poses, rule: CandidateRule, *, seed: int, gamma_inflation: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs ``(i, j)``, i < j, chosen by ``rule`` on ``poses`` (the reference, or the
    odometry's estimate for ``rule.on == "estimate"``: pass the poses the rule is to see).

    Loops are found on the positions (Euclidean, metres) within ``rule.gamma`` times the
    inflation (``gamma_inflation``, else ``rule.gamma_inflation`` on the estimate, 1 on the
    reference); warnings of the samplers (a budget above the candidates, below the components)
    are kept quiet: the returned count says it.
    """
    import warnings

    from .errors import LoopsWarning

    if gamma_inflation is None:
        gamma_inflation = rule.gamma_inflation if rule.on == "estimate" else 1.0
    gamma = rule.gamma * gamma_inflation
    separation: Separation | None = Separation.for_gamma(rule.gamma) if rule.separation else None
    traj = poses.to_trajectory()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LoopsWarning)
        loops = find_loops(traj, gamma=gamma, separation=separation)
        if loops.pair_count == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        if rule.source == "detections" and not rule.is_baseline:
            detections = draw_detections(loops, rate=rule.detection_rate, seed=seed)
            if len(detections) == 0:
                return np.zeros(0, np.int64), np.zeros(0, np.int64)
            clusters = cluster_detections(detections, epsilon_s=rule.epsilon_s)
            samples = sample(clusters, rule.sampler, budget=rule.budget, seed=seed, trajectory=traj)
        else:
            samples = sample(loops, rule.sampler, budget=rule.budget, seed=seed, trajectory=traj)
    i, j = samples.i, samples.j
    if i is None or j is None:  # pragma: no cover - samples on a trajectory always have pairs
        raise RuntimeError("samples without pose indices")
    return np.minimum(i, j), np.maximum(i, j)


class Rounds:
    """Candidates in rounds, for a pipeline without ground truth: choose some pairs on the
    current estimate, match them, optimise, and choose the next ones on the corrected estimate.

    The budget (``rule.budget``) is spent in ``rule.rounds`` rounds of equal shares (the last
    takes what the others left). Round k chooses with ``rule``'s sampler on the estimate it is
    given, gamma inflated by a factor that starts at ``rule.gamma_inflation`` and shrinks as the
    estimate settles: after each round, ``1 + min(gamma_inflation - 1, c / gamma)``, with c the
    median distance (metres) the last optimisation moved the poses. A pair is tried once: the
    pairs of earlier rounds are left out (the sampler is asked for that many more, and a seeded
    draw keeps the round's share). Each round's sampler seed is ``seed + round``.

    Drive it with your own matcher and back end::

        rounds = Rounds(CandidateRule("closest-then-spread", 1000, 15.0, on="estimate",
                                      rounds=3), seed=0)
        estimate = odometry_estimate
        while not rounds.done:
            i, j = rounds.choose(estimate)          # pairs to match, i < j
            ...                                    # match them, add the loop factors
            corrected = ...                        # optimise the pose graph
            rounds.update(estimate, corrected)
            estimate = corrected

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import CandidateRule, Poses, Rounds
        >>> angle = np.linspace(0, 4 * np.pi, 400)
        >>> xy = 50 * np.c_[np.cos(angle), np.sin(angle)]
        >>> circle = Poses.from_positions(np.arange(400.0), xy)
        >>> rounds = Rounds(CandidateRule("closest-then-spread", 30, 10.0, on="estimate", rounds=3),
        ...                 seed=0)
        >>> i, j = rounds.choose(circle)
        >>> len(i), rounds.round, rounds.gamma_inflation
        (10, 1, 2.0)
        >>> rounds.update(circle, circle)               # nothing moved: gamma back to 10 m
        >>> rounds.gamma_inflation
        1.0
    """

    def __init__(self, rule: CandidateRule, *, seed: int) -> None:
        if rule.on != "estimate":
            raise InvalidParameterError('Rounds: the rule chooses on="estimate"')
        self.rule = rule
        self.seed = int(seed)
        #: Rounds chosen so far.
        self.round = 0
        #: The inflation of gamma the next round uses.
        self.gamma_inflation = float(rule.gamma_inflation)
        self._tried: set[tuple[int, int]] = set()

    @property
    def done(self) -> bool:
        """Whether every round is chosen (or the budget is spent)."""
        return self.round >= self.rule.rounds or len(self._tried) >= self.rule.budget

    @property
    def tried(self) -> int:
        """Pairs chosen so far."""
        return len(self._tried)

    def choose(self, estimate: Poses) -> tuple[np.ndarray, np.ndarray]:
        """The next round's pairs ``(i, j)``, i < j, chosen on ``estimate``, none of them chosen
        before; empty once :attr:`done`."""
        if self.done:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        left = self.rule.budget - len(self._tried)
        share = (
            left if self.round == self.rule.rounds - 1 else left // (self.rule.rounds - self.round)
        )
        share = max(share, 1)
        seed = self.seed + self.round
        ask = dataclasses.replace(self.rule, budget=share + len(self._tried), rounds=1)
        i, j = choose_candidates(estimate, ask, seed=seed, gamma_inflation=self.gamma_inflation)
        pairs = zip(i.tolist(), j.tolist(), strict=True)
        fresh = np.array([p not in self._tried for p in pairs], bool)
        i, j = i[fresh], j[fresh]
        if len(i) > share:
            rng = np.random.default_rng(np.random.SeedSequence([seed, 0x0C0]))
            keep = np.sort(rng.choice(len(i), share, replace=False))
            i, j = i[keep], j[keep]
        self._tried.update(zip(i.tolist(), j.tolist(), strict=True))
        self.round += 1
        return i, j

    def update(self, before: Poses, after: Poses) -> None:
        """Tells the rounds how the last optimisation moved the estimate (``before`` to
        ``after``, the same poses): the next round's gamma inflation."""
        moved = np.linalg.norm(after.positions - before.positions, axis=1)
        c = float(np.median(moved)) if len(moved) else 0.0
        top = self.rule.gamma_inflation - 1.0
        self.gamma_inflation = 1.0 + min(top, c / self.rule.gamma)


def _concat_matches(parts: Sequence[Matches]) -> Matches:
    """The matches of several rounds as one."""
    return Matches(
        np.concatenate([m.i for m in parts]),
        np.concatenate([m.j for m in parts]),
        np.concatenate([m.relative for m in parts]),
        np.concatenate([m.translation_sigma_m for m in parts]),
        np.concatenate([m.rotation_sigma_rad for m in parts]),
        np.concatenate([m.wrong for m in parts]),
        sum(m.tried for m in parts),
    )


# ---------------------------------------------------------------------------------------------
# The verifier
# ---------------------------------------------------------------------------------------------


def _splitmix64(x: np.ndarray) -> np.ndarray:
    x = x + np.uint64(0x9E3779B97F4A7C15)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def _pair_uniforms(seed: int, i: np.ndarray, j: np.ndarray, count: int) -> np.ndarray:
    """``count`` uniforms in (0, 1) per pair, a function of (seed, i, j) only: the same pair gets
    the same outcome whichever sampler proposed it."""
    with np.errstate(over="ignore"):
        key = _splitmix64(
            np.uint64(int(seed) & 0xFFFFFFFFFFFFFFFF)
            ^ _splitmix64(i.astype(np.uint64) * np.uint64(0x100000001B3) + j.astype(np.uint64))
        )
        streams = key[:, None] + np.arange(1, count + 1, dtype=np.uint64)[None, :] * np.uint64(
            0xD1B54A32D192ED03
        )
        bits = _splitmix64(streams) >> np.uint64(11)
    return (bits.astype(np.float64) + 0.5) / float(1 << 53)


def _normals(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)


@dataclass(frozen=True)
class Matches:
    """What the verifier returned: the accepted matches, as loop factors.

    Attributes:
        i, j: shape ``(m,)``: the pose indices of each match (i < j).
        relative: shape ``(m, d+1, d+1)``: the measured pose j in the frame of pose i.
        translation_sigma_m, rotation_sigma_rad: shape ``(m,)``: the standard deviations the
            matcher reports (per axis), which the back end uses.
        wrong: shape ``(m,)``: which matches are wrong (outliers); the back end does not see it.
        tried: how many candidates were verified.
    """

    i: np.ndarray
    j: np.ndarray
    relative: np.ndarray
    translation_sigma_m: np.ndarray
    rotation_sigma_rad: np.ndarray
    wrong: np.ndarray
    tried: int

    def __len__(self) -> int:
        return len(self.i)

    @classmethod
    def exact(
        cls,
        reference: Poses,
        i: npt.ArrayLike,
        j: npt.ArrayLike,
        sigma_m: float = 0.01,
        sigma_rad: float = 0.001,
    ) -> Matches:
        """Loop factors at the true relative poses of the reference (a perfect matcher)."""
        i, j = np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64)
        m = len(i)
        return cls(
            i,
            j,
            reference.relative(i, j),
            np.full(m, sigma_m),
            np.full(m, sigma_rad),
            np.zeros(m, bool),
            m,
        )


@dataclass(frozen=True)
class Verifier:
    """A stand-in for the scan matcher, seeded: whether it matches a candidate pair, how well,
    and how often it is wrong, as documented functions of the true distance d (metres) between
    the pair's reference positions.

    For each candidate (i, j), with per-pair random numbers (a function of the seed and the
    pair only, so a pair has the same outcome whichever sampler proposes it):

    - with probability ``outlier_rate`` the match is **wrong** (perceptual aliasing: it locks
      onto another place): the returned relative pose has a translation uniform in a disc
      (SE(3): a ball) of radius ``outlier_radius_m`` and a rotation uniform (a heading in
      [-pi, pi); SE(3): uniform on SO(3)), whatever the true one is;
    - otherwise it **succeeds** with probability
      ``p(d) = success_max * 2 ** (-(d / half_success_distance_m) ** 2)`` for
      ``d <= max_range_m``, 0 beyond (p falls to half at ``half_success_distance_m``: scans far
      apart overlap less; ``half_success_distance_m = inf`` makes it blind to the distance up
      to ``max_range_m``), and returns the true relative
      pose with noise ``N(0, sigma_t(d)**2)`` per translation axis and ``N(0, sigma_r(d)**2)`` per
      rotation axis, ``sigma_t(d) = translation_sigma_m + translation_sigma_per_m * d`` and
      ``sigma_r(d) = rotation_sigma_rad + rotation_sigma_rad_per_m * d``;
    - otherwise it fails (no factor).

    A match reports its standard deviations as the matcher would know them: sigma_t and
    sigma_r at the distance it measured (the norm of its returned translation), so a wrong match
    claims to be as good as a right one of that length.

    :data:`VERIFIER_MODELS` names three matchers, so that a ranking of samplers can be checked
    not to be an artefact of one: ``"distance-aware"`` (the defaults), ``"steep"`` (success
    halves at 8 m instead of 20 m and the noise grows twice as fast with d: a matcher that needs
    the poses close) and ``"blind"`` (success 0.8 at any d up to 40 m, none beyond, a noise that
    does not grow with d: a matcher with a global descriptor and a wide initial search). Each
    with ``outlier_rate=0.1`` gives its version with 10 % wrong matches.

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import Poses, Verifier
        >>> poses = Poses.se2(np.arange(4.0), [[0, 0, 0], [100, 0, 0], [1, 0, 0], [60, 0, 0]])
        >>> matches = Verifier(success_max=1.0).verify(poses, [0, 0], [2, 3], seed=0)
        >>> 0 in matches.i.tolist(), bool(matches.wrong.any())
        (True, False)
    """

    success_max: float = 0.95
    half_success_distance_m: float = 20.0
    translation_sigma_m: float = 0.05
    translation_sigma_per_m: float = 0.005
    rotation_sigma_rad: float = 0.002
    rotation_sigma_rad_per_m: float = 0.0002
    outlier_rate: float = 0.0
    outlier_radius_m: float = 20.0
    max_range_m: float = math.inf

    def __post_init__(self) -> None:
        if not (self.half_success_distance_m > 0 and self.max_range_m > 0):
            raise InvalidParameterError(
                "Verifier: half_success_distance_m and max_range_m must be > 0 (inf allowed)"
            )
        if not 0.0 <= self.success_max <= 1.0:
            raise InvalidParameterError(f"Verifier: success_max = {self.success_max} not in [0, 1]")
        if not 0.0 <= self.outlier_rate <= 1.0:
            raise InvalidParameterError(
                f"Verifier: outlier_rate = {self.outlier_rate} not in [0, 1]"
            )
        for name in ("translation_sigma_m", "rotation_sigma_rad", "outlier_radius_m"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise InvalidParameterError(f"Verifier: {name} must be > 0")
        for name in ("translation_sigma_per_m", "rotation_sigma_rad_per_m"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise InvalidParameterError(f"Verifier: {name} must be >= 0")

    def success_probability(self, distance_m: npt.ArrayLike) -> np.ndarray:
        """p(d): the probability that a right match succeeds."""
        d = np.asarray(distance_m, dtype=float)
        p = self.success_max * np.exp2(-((d / self.half_success_distance_m) ** 2))
        return np.where(d <= self.max_range_m, p, 0.0)

    def sigmas(self, distance_m: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """sigma_t(d) (metres) and sigma_r(d) (radians)."""
        d = np.asarray(distance_m, dtype=float)
        return (
            self.translation_sigma_m + self.translation_sigma_per_m * d,
            self.rotation_sigma_rad + self.rotation_sigma_rad_per_m * d,
        )

    def verify(self, reference: Poses, i: npt.ArrayLike, j: npt.ArrayLike, *, seed: int) -> Matches:
        """Verifies the candidate pairs against the reference."""
        i = np.asarray(i, dtype=np.int64)
        j = np.asarray(j, dtype=np.int64)
        if i.shape != j.shape or i.ndim != 1:
            raise ValueError(
                f"Verifier.verify: i and j of one shape (m,), got {i.shape}, {j.shape}"
            )
        n = len(reference)
        for name, k in (("i", i), ("j", j)):
            bad = np.flatnonzero((k < 0) | (k >= n))
            if bad.size:
                raise IndexError(
                    f"Verifier.verify: {name}[{bad[0]}] = {k[bad[0]]} is not a pose (n = {n})"
                )
        d = reference.dim
        rot_dims = 1 if d == 2 else 3
        # Per pair: wrong?, success?, 2 (d + rot_dims) for the noise, then the wrong match's
        # radius, direction and rotation.
        base = 2 + 2 * (d + rot_dims)
        u = _pair_uniforms(seed, i, j, base + (3 if d == 2 else 6))
        truth = reference.relative(i, j)
        distance = np.linalg.norm(truth[:, :d, d], axis=1)
        wrong = u[:, 0] < self.outlier_rate
        success = ~wrong & (u[:, 1] < self.success_probability(distance))
        keep = wrong | success
        t_sd, r_sd = self.sigmas(distance)
        gauss = _normals(
            u[:, 2 : 2 + d + rot_dims], u[:, 2 + d + rot_dims : 2 + 2 * (d + rot_dims)]
        )
        e_t = gauss[:, :d] * t_sd[:, None]
        e_r = gauss[:, d:] * r_sd[:, None]
        if d == 2:
            noisy_rot = truth[:, :2, :2] @ _rot2(e_r[:, 0])
        else:
            noisy_rot = truth[:, :3, :3] @ _rot3(e_r)
        measured = _homogeneous(noisy_rot, truth[:, :d, d] + e_t)
        if wrong.any():
            w = u[wrong, base:]
            radius = self.outlier_radius_m * w[:, 0] ** (1.0 / d)
            if d == 2:
                direction = np.c_[np.cos(2 * np.pi * w[:, 1]), np.sin(2 * np.pi * w[:, 1])]
                rot = _rot2(2 * np.pi * w[:, 2] - np.pi)
            else:
                z = 2 * w[:, 1] - 1
                phi = 2 * np.pi * w[:, 2]
                direction = np.c_[
                    np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z
                ]
                rot = _uniform_rotations(w[:, 3], w[:, 4], w[:, 5])
            measured[wrong] = _homogeneous(rot, direction * radius[:, None])
        claimed = np.linalg.norm(measured[:, :d, d], axis=1)
        c_t, c_r = self.sigmas(claimed)
        return Matches(i[keep], j[keep], measured[keep], c_t[keep], c_r[keep], wrong[keep], len(i))


#: Named verifier models (:class:`Verifier`): today's distance-aware default, a steeper one and
#: a distance-blind one. ``dataclasses.replace(model, outlier_rate=0.1)`` adds wrong matches.
VERIFIER_MODELS: Mapping[str, Verifier] = {
    "distance-aware": Verifier(),
    "steep": Verifier(
        half_success_distance_m=8.0, translation_sigma_per_m=0.01, rotation_sigma_rad_per_m=0.0004
    ),
    "blind": Verifier(
        success_max=0.8,
        half_success_distance_m=math.inf,
        max_range_m=40.0,
        translation_sigma_m=0.1,
        translation_sigma_per_m=0.0,
        rotation_sigma_rad=0.004,
        rotation_sigma_rad_per_m=0.0,
    ),
}


def _verifier_name(verifier: Verifier) -> str:
    """The name of ``verifier``'s model in :data:`VERIFIER_MODELS` (its outlier rate aside), or
    ``"custom"``."""
    plain = dataclasses.replace(verifier, outlier_rate=0.0)
    return next((k for k, v in VERIFIER_MODELS.items() if v == plain), "custom")


def _uniform_rotations(u1: np.ndarray, u2: np.ndarray, u3: np.ndarray) -> np.ndarray:
    """Rotations uniform on SO(3) from three uniforms each (Shoemake's method)."""
    a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
    q = np.c_[a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2), b * np.sin(2 * np.pi * u3)]
    return _quat_xyzw_to_matrix(np.c_[q, b * np.cos(2 * np.pi * u3)])


# ---------------------------------------------------------------------------------------------
# The back end
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BackEnd:
    """The pose-graph back end (GTSAM): odometry factors between consecutive poses, one loop
    factor per match, a prior on the first pose; solved from the odometry's estimate.

    Attributes:
        kernel: the loop factors' robust kernel: ``"cauchy"`` (the default), ``"huber"``,
            ``"gauss"`` (none: a plain Gaussian), or ``"gnc"`` (graduated non-convexity with a
            truncated-least-squares loss, GTSAM's ``GncLMOptimizer``, odometry known to be
            right). Odometry factors are Gaussian.
        kernel_width: where the kernel bends, in standard deviations of the whitened residual
            (Cauchy's and Huber's k).
        max_iterations: of Levenberg-Marquardt.
        relative_error_tol: Levenberg-Marquardt stops when the error decreases less than this.
    """

    kernel: Literal["cauchy", "huber", "gauss", "gnc"] = "cauchy"
    kernel_width: float = 1.0
    max_iterations: int = 100
    relative_error_tol: float = 1e-6

    def __post_init__(self) -> None:
        if self.kernel not in ("cauchy", "huber", "gauss", "gnc"):
            raise InvalidParameterError(
                f"BackEnd: kernel {self.kernel!r}: expected cauchy, huber, gauss or gnc"
            )
        if not (math.isfinite(self.kernel_width) and self.kernel_width > 0):
            raise InvalidParameterError(f"BackEnd: kernel_width = {self.kernel_width} must be > 0")


def _pose_value(gtsam: Any, m: np.ndarray) -> Any:
    if m.shape == (3, 3):
        return gtsam.Pose2(m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0]))
    return gtsam.Pose3(m)


def _noise(gtsam: Any, dim: int, t_sigma: float, r_sigma: float) -> Any:
    # Pose2's tangent is (x, y, theta); Pose3's is (rotation, translation).
    sigmas = [t_sigma, t_sigma, r_sigma] if dim == 2 else [r_sigma] * 3 + [t_sigma] * 3
    return gtsam.noiseModel.Diagonal.Sigmas(np.asarray(sigmas, dtype=float))


def optimize(
    odometry: Odometry, matches: Matches | None = None, backend: BackEnd | None = None
) -> Poses:
    """The pose graph of ``odometry`` and ``matches`` optimised by ``backend`` (GTSAM).

    Raises:
        ImportError: GTSAM is not installed (``pip install '.[maps]'`` in a checkout).
    """
    gtsam = _gtsam()
    backend = backend or BackEnd()
    dim = odometry.dim
    between = gtsam.BetweenFactorPose2 if dim == 2 else gtsam.BetweenFactorPose3
    prior = gtsam.PriorFactorPose2 if dim == 2 else gtsam.PriorFactorPose3
    graph = gtsam.NonlinearFactorGraph()
    initial = gtsam.Values()
    estimate = odometry.estimate.matrices
    graph.add(prior(0, _pose_value(gtsam, odometry.start), _noise(gtsam, dim, 1e-4, 1e-5)))
    for k, step in enumerate(odometry.steps):
        noise = _noise(gtsam, dim, odometry.translation_sigma_m[k], odometry.rotation_sigma_rad[k])
        graph.add(between(k, k + 1, _pose_value(gtsam, step), noise))
    for k, m in enumerate(estimate):
        initial.insert(k, _pose_value(gtsam, m))
    matrices = _solve(gtsam, graph, initial, backend, dim, matches, list(range(len(estimate))))
    return Poses(odometry.timestamps, matrices)


def _solve(
    gtsam: Any,
    graph: Any,
    initial: Any,
    backend: BackEnd,
    dim: int,
    matches: Matches | None,
    keys: Sequence[int],
) -> np.ndarray:
    """Adds a loop factor per match to ``graph`` (the odometry factors and priors it holds are
    the known inliers of GNC), optimises it from ``initial`` and returns the poses' matrices,
    pose k the one of ``keys[k]`` (match indices index ``keys``)."""
    between = gtsam.BetweenFactorPose2 if dim == 2 else gtsam.BetweenFactorPose3
    known = list(range(graph.size()))
    if matches is not None and len(matches):
        robust = {
            "cauchy": lambda: gtsam.noiseModel.mEstimator.Cauchy.Create(backend.kernel_width),
            "huber": lambda: gtsam.noiseModel.mEstimator.Huber.Create(backend.kernel_width),
        }.get(backend.kernel)
        for a, b, rel, ts, rs in zip(
            matches.i.tolist(),
            matches.j.tolist(),
            matches.relative,
            matches.translation_sigma_m.tolist(),
            matches.rotation_sigma_rad.tolist(),
            strict=True,
        ):
            noise = _noise(gtsam, dim, ts, rs)
            if robust is not None:
                noise = gtsam.noiseModel.Robust.Create(robust(), noise)
            graph.add(between(keys[a], keys[b], _pose_value(gtsam, rel), noise))
    if backend.kernel == "gnc":
        lm = gtsam.LevenbergMarquardtParams()
        lm.setMaxIterations(backend.max_iterations)
        lm.setRelativeErrorTol(backend.relative_error_tol)
        params = gtsam.GncLMParams(lm)
        params.setKnownInliers(known)
        result = gtsam.GncLMOptimizer(graph, initial, params).optimize()
    else:
        params = gtsam.LevenbergMarquardtParams()
        params.setMaxIterations(backend.max_iterations)
        params.setRelativeErrorTol(backend.relative_error_tol)
        result = gtsam.LevenbergMarquardtOptimizer(graph, initial, params).optimize()
    # GTSAM extracts the poses in the order of their keys; put them back in the order of keys.
    order = np.argsort(np.asarray(keys, dtype=np.uint64), kind="stable")
    if dim == 2:
        flat = np.empty((len(keys), 3))
        flat[order] = gtsam.utilities.extractPose2(result)
        return Poses.se2(np.arange(len(keys), dtype=float), flat).matrices
    raw = gtsam.utilities.extractPose3(result)
    matrices = np.tile(np.eye(4), (len(keys), 1, 1))
    matrices[order, :3, :3] = raw[:, :9].reshape(-1, 3, 3)
    matrices[order, :3, 3] = raw[:, 9:]
    return matrices


# ---------------------------------------------------------------------------------------------
# Errors (evo's APE and RPE, translation part)
# ---------------------------------------------------------------------------------------------


def umeyama(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rotation R and translation t minimising sum |R x + t - y|^2 over point pairs (x in
    ``source``, y in ``target``, rows), no scale: Umeyama's method as evo's
    ``umeyama_alignment`` computes it.

    Raises:
        InvalidParameterError: degenerate points (all on a line in 3-D, or one point).
    """
    x = np.asarray(source, dtype=float)
    y = np.asarray(target, dtype=float)
    mx, my = x.mean(axis=0), y.mean(axis=0)
    cov = (y - my).T @ (x - mx) / len(x)
    u, s, vt = np.linalg.svd(cov)
    m = x.shape[1]
    if np.count_nonzero(s > np.finfo(float).eps) < m - 1:
        raise InvalidParameterError("umeyama: degenerate points, no alignment is possible")
    flip = np.eye(m)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        flip[-1, -1] = -1
    r = u @ flip @ vt
    return r, my - r @ mx


def ape_errors(reference: Poses, estimate: Poses, *, align: bool = True) -> np.ndarray:
    """Per pose, the translation error |t_est - t_ref| (metres) of ``estimate`` against
    ``reference`` (same poses), after the rigid alignment of the estimate's positions onto the
    reference's (Umeyama, no scale) when ``align``: evo's APE, translation part (``evo_ape
    -a``)."""
    _check_pair(reference, estimate)
    est = estimate.positions
    ref = reference.positions
    if align:
        r, t = umeyama(est, ref)
        est = est @ r.T + t
    return np.linalg.norm(est - ref, axis=1)


def ate(reference: Poses, estimate: Poses, *, align: bool = True) -> float:
    """The absolute trajectory error: the RMSE of :func:`ape_errors`, metres."""
    e = ape_errors(reference, estimate, align=align)
    return float(np.sqrt(np.mean(e**2)))


def _rpe_pairs(
    reference: Poses, delta: float, unit: str, all_pairs: bool
) -> tuple[np.ndarray, np.ndarray]:
    n = len(reference)
    if unit == "frames":
        step = int(delta)
        if step < 1:
            raise InvalidParameterError(f"rpe: delta = {delta} frames must be >= 1")
        if all_pairs:
            i = np.arange(n - step)
            return i, i + step
        ids = np.arange(0, n, step)
        return ids[:-1], ids[1:]
    if unit != "m":
        raise InvalidParameterError(f"rpe: delta_unit {unit!r}: frames or m")
    if not delta > 0:
        raise InvalidParameterError(f"rpe: delta = {delta} m must be > 0")
    p = reference.positions
    if all_pairs:
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        tol = 0.1 * delta
        ii, jj = [], []
        for a in range(n - 1):
            rest = s[a + 1 :] - s[a]
            k = int(np.argmin(np.abs(rest - delta)))
            if abs(rest[k] - delta) <= tol:
                ii.append(a)
                jj.append(a + 1 + k)
        return np.asarray(ii, dtype=np.int64), np.asarray(jj, dtype=np.int64)
    marks = [0]
    travelled = 0.0
    step_lengths = np.linalg.norm(np.diff(p, axis=0), axis=1)
    for k in range(1, n):
        travelled += float(step_lengths[k - 1])
        if travelled >= delta:
            marks.append(k)
            travelled = 0.0
    at = np.asarray(marks, dtype=np.int64)
    return at[:-1], at[1:]


def rpe_errors(
    reference: Poses,
    estimate: Poses,
    *,
    delta: float = 1,
    delta_unit: Literal["frames", "m"] = "frames",
    all_pairs: bool = False,
) -> np.ndarray:
    """Per pair (i, j), the translation of ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` (Q reference,
    P estimate), metres: evo's RPE, translation part. Pairs are ``delta`` frames apart, or
    ``delta`` metres of the reference's path apart (``delta_unit="m"``; evo's
    ``pairs_from_reference=True``, tolerance 10 % with ``all_pairs``); consecutive such pairs,
    or from every pose with ``all_pairs``, as evo chooses them."""
    _check_pair(reference, estimate)
    i, j = _rpe_pairs(reference, delta, delta_unit, all_pairs)
    if len(i) == 0:
        raise InvalidParameterError(f"rpe: delta = {delta} {delta_unit} gives no pair of poses")
    e = _inverse(reference.relative(i, j)) @ estimate.relative(i, j)
    d = reference.dim
    return np.linalg.norm(e[:, :d, d], axis=1)


def rpe(
    reference: Poses,
    estimate: Poses,
    *,
    delta: float = 1,
    delta_unit: Literal["frames", "m"] = "frames",
    all_pairs: bool = False,
) -> float:
    """The relative pose error: the RMSE of :func:`rpe_errors`, metres."""
    e = rpe_errors(reference, estimate, delta=delta, delta_unit=delta_unit, all_pairs=all_pairs)
    return float(np.sqrt(np.mean(e**2)))


def _check_pair(reference: Poses, estimate: Poses) -> None:
    if len(reference) != len(estimate) or reference.dim != estimate.dim:
        raise InvalidParameterError(
            f"the estimate ({len(estimate)} SE({estimate.dim}) poses) does not match the "
            f"reference ({len(reference)} SE({reference.dim}) poses)"
        )


# ---------------------------------------------------------------------------------------------
# The evaluation
# ---------------------------------------------------------------------------------------------


#: Columns of :class:`Results`, in order.
COLUMNS: tuple[str, ...] = (
    "dataset",
    "sampler",
    "source",
    "on",
    "separation",
    "outlier_rate",
    "verifier",
    "rounds",
    "budget",
    "seed",
    "candidates",
    "matches",
    "wrong",
    "ate_m",
    "rpe_m",
    "odometry_ate_m",
    "seconds",
)


@dataclass
class Results:
    """Rows of an evaluation, one per run (a sampler at a budget, with a seed and options), and
    their summary.

    Columns (:data:`COLUMNS`): ``dataset``; ``sampler`` (``"odometry"`` for the odometry alone);
    ``source`` (``exact`` / ``detections``); ``on`` (``reference`` / ``estimate``);
    ``separation`` (bool); ``outlier_rate``; ``verifier`` (the name of its model in
    :data:`VERIFIER_MODELS`, or ``custom``); ``rounds`` (the candidates' rounds, 0 for the
    odometry alone); ``budget``; ``seed``; ``candidates`` (pairs the
    sampler returned, at most the budget); ``matches`` (accepted by the verifier); ``wrong``
    (of them wrong); ``ate_m``; ``rpe_m`` (RPE over ``rpe_delta_m`` of path); ``odometry_ate_m``
    (the same seed's odometry alone); ``seconds`` (candidates, verification and optimisation).
    """

    rows: list[dict[str, Any]] = field(default_factory=list)
    settings: dict[str, Any] = field(default_factory=dict)

    def table(self) -> Table:
        """The rows as an :class:`~inexact_loops.Table` of numpy columns."""
        return Table({c: np.asarray([r[c] for r in self.rows]) for c in COLUMNS})

    def summary(self) -> list[dict[str, Any]]:
        """Per (dataset, sampler, source, on, separation, outlier_rate, verifier, rounds, budget):
        the number of
        seeds, the median ATE and RPE and the ATE's spread (min, max, and the interquartile
        range), the median candidates, matches and wrong matches."""
        keys = (
            "dataset",
            "sampler",
            "source",
            "on",
            "separation",
            "outlier_rate",
            "verifier",
            "rounds",
            "budget",
        )
        return [
            group
            | {"rpe_median_m": float(np.median([r["rpe_m"] for r in rows]))}
            | _medians(rows, ("candidates", "matches", "wrong", "odometry_ate_m"))
            for group, rows in _summary_groups(self.rows, keys)
        ]

    def to_csv(self, path: str | PathLike[str]) -> None:
        """Writes the rows as CSV (a header of :data:`COLUMNS`)."""
        _write_csv(path, COLUMNS, self.rows)

    def to_json(self, path: str | PathLike[str]) -> None:
        """Writes ``{"settings", "summary", "rows"}`` as JSON."""
        document = {"settings": self.settings, "summary": self.summary(), "rows": self.rows}
        with open(path, "w") as f:
            json.dump(document, f, indent=1, default=_json_default)
            f.write("\n")

    @classmethod
    def from_csv(cls, path: str | PathLike[str]) -> Results:
        """Reads rows written by :meth:`to_csv`."""
        ints = {"budget", "seed", "candidates", "matches", "wrong", "rounds"}
        floats = {"outlier_rate", "ate_m", "rpe_m", "odometry_ate_m", "seconds"}
        return cls(_read_csv(path, COLUMNS, ints=ints, floats=floats, bools={"separation"}))

    def extend(self, other: Results) -> None:
        """Adds the rows of ``other``."""
        self.rows.extend(other.rows)


def _summary_groups(
    rows: Sequence[dict[str, Any]], keys: Sequence[str]
) -> list[tuple[dict[str, Any], list[dict[str, Any]]]]:
    """The rows grouped by their values of ``keys`` (in the order of first appearance): per
    group, those values with the number of seeds and the spread of the ATE (median, quartiles,
    min, max), and the group's rows."""
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    out = []
    for key, members in groups.items():
        ate_m = np.array([r["ate_m"] for r in members])
        head = dict(zip(keys, key, strict=True)) | {
            "seeds": len(members),
            "ate_median_m": float(np.median(ate_m)),
            "ate_q25_m": float(np.quantile(ate_m, 0.25)),
            "ate_q75_m": float(np.quantile(ate_m, 0.75)),
            "ate_min_m": float(ate_m.min()),
            "ate_max_m": float(ate_m.max()),
        }
        out.append((head, members))
    return out


def _medians(rows: Sequence[dict[str, Any]], columns: Iterable[str]) -> dict[str, float]:
    """The median of each of ``columns`` over ``rows``."""
    return {c: float(np.median([r[c] for r in rows])) for c in columns}


def _write_csv(
    path: str | PathLike[str], columns: Sequence[str], rows: Iterable[dict[str, Any]]
) -> None:
    """Writes ``rows`` as CSV: a header of ``columns``, then those columns of each row."""
    import csv

    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(columns))
        writer.writeheader()
        for r in rows:
            writer.writerow({c: r[c] for c in columns})


#: Values of columns that older result files lack.
_MISSING: Mapping[str, str] = {"verifier": "distance-aware", "rounds": "1"}


def _read_csv(
    path: str | PathLike[str],
    columns: Sequence[str],
    *,
    ints: set[str],
    floats: set[str],
    bools: set[str],
) -> list[dict[str, Any]]:
    """The rows :func:`_write_csv` wrote, ``columns`` of each: ``ints``, ``floats`` and
    ``bools`` (``"True"``) converted, the others kept as text."""
    import csv

    rows = []
    with open(path, newline="") as f:
        for raw in csv.DictReader(f):
            row: dict[str, Any] = {}
            for c in columns:
                # Files written before a column existed: its value for them.
                v = raw.get(c) or _MISSING.get(c, "")
                if c in ints:
                    row[c] = int(v)
                elif c in floats:
                    row[c] = float(v)
                elif c in bools:
                    row[c] = v == "True"
                else:
                    row[c] = v
            rows.append(row)
    return rows


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    raise TypeError(f"not JSON: {type(value).__name__}")


def evaluate_one(
    reference: Poses,
    odometry: Odometry,
    rule: CandidateRule | None,
    *,
    seed: int,
    verifier: Verifier | None = None,
    backend: BackEnd | None = None,
) -> tuple[Poses, Matches | None, tuple[np.ndarray, np.ndarray]]:
    """One run: candidates by ``rule`` (``None``: the odometry alone), verified, optimised; in
    ``rule.rounds`` rounds (:class:`Rounds`), each verified and optimised before the next.

    Returns the optimised poses, the matches and the candidate pairs.
    """
    verifier = verifier or Verifier()
    if rule is None:
        empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        return optimize(odometry, None, backend), None, empty
    if rule.rounds > 1:
        rounds = Rounds(rule, seed=seed)
        estimate, parts, chosen = odometry.estimate, [], []
        while not rounds.done:
            i, j = rounds.choose(estimate)
            parts.append(verifier.verify(reference, i, j, seed=seed))
            chosen.append((i, j))
            corrected = optimize(odometry, _concat_matches(parts), backend)
            rounds.update(estimate, corrected)
            estimate = corrected
        pairs = (np.concatenate([c[0] for c in chosen]), np.concatenate([c[1] for c in chosen]))
        return estimate, _concat_matches(parts), pairs
    chooser = reference if rule.on == "reference" else odometry.estimate
    i, j = choose_candidates(chooser, rule, seed=seed)
    matches = verifier.verify(reference, i, j, seed=seed)
    return optimize(odometry, matches, backend), matches, (i, j)


def _grid(
    outlier_rates: Sequence[float],
    on: Sequence[Literal["reference", "estimate"]],
    separations: Sequence[bool],
    sources: Sequence[Literal["exact", "detections"]],
    samplers: Sequence[str],
    detection_samplers: Sequence[str],
    budgets: Sequence[int],
    rounds: int = 1,
    **rule: Any,
) -> Iterable[tuple[float, CandidateRule]]:
    """The runs of :func:`evaluate`, in its order: detections only for ``detection_samplers``
    (never a baseline); LIO-SAM's and hdl_graph_slam's rules, which do not look at the
    separation, only with it."""
    for outlier_rate in outlier_rates:
        for where in on:
            for separation in separations:
                for source in sources:
                    for name in samplers:
                        baseline = name in BASELINES
                        if source == "detections" and (baseline or name not in detection_samplers):
                            continue
                        if not separation and name in ("lio-sam", "hdl-graph-slam"):
                            continue
                        for budget in budgets:
                            yield (
                                outlier_rate,
                                CandidateRule(
                                    name,
                                    int(budget),
                                    separation=bool(separation),
                                    source=source,
                                    on=where,
                                    rounds=rounds if where == "estimate" else 1,
                                    **rule,
                                ),
                            )


def evaluate(
    reference: Poses,
    *,
    gamma: float,
    odometry: Odometry | DriftModel | None = None,
    samplers: Sequence[str] = SAMPLERS + BASELINES,
    budgets: Sequence[int] = (100, 1000, 10000),
    seeds: Iterable[int] = range(5),
    separations: Sequence[bool] = (True,),
    sources: Sequence[Literal["exact", "detections"]] = ("exact",),
    detection_samplers: Sequence[str] | None = None,
    on: Sequence[Literal["reference", "estimate"]] = ("reference",),
    outlier_rates: Sequence[float] = (0.0,),
    verifier: Verifier | str | None = None,
    backend: BackEnd | None = None,
    gamma_inflation: float = 2.0,
    rounds: int = 1,
    detection_rate: float = 0.01,
    epsilon_s: float = 30.0,
    rpe_delta_m: float = 100.0,
    dataset: str = "",
    include_odometry: bool = True,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> Results:
    """Runs every sampler at every budget with every seed (and every option given), and the
    odometry alone per seed, on ``reference``.

    Args:
        reference: the reference poses.
        gamma: the loops' gamma, metres.
        odometry: your :class:`Odometry` (the same for every seed), or a :class:`DriftModel`
            simulated per seed (the default model when ``None``).
        samplers: names from :data:`SAMPLERS` and :data:`BASELINES`.
        budgets: candidates per run.
        seeds: one run per seed: the seed drives the odometry (a drift model), the sampler, the
            detections and the verifier.
        separations: ``True`` (revisits only), ``False`` (S_gamma), or both.
        sources: ``"exact"``, ``"detections"`` or both (baselines run once, on ``"exact"``).
        detection_samplers: the samplers run on detections (default: every non-baseline).
        on: ``"reference"``, ``"estimate"`` or both (:class:`CandidateRule`).
        outlier_rates: the verifier's ``outlier_rate`` values to run.
        verifier: the verifier (its ``outlier_rate`` is replaced by each of ``outlier_rates``),
            or the name of one of :data:`VERIFIER_MODELS`.
        backend: the back end.
        gamma_inflation, rounds, detection_rate, epsilon_s: as in :class:`CandidateRule`
            (``rounds`` for the runs on the estimate).
        rpe_delta_m: the RPE's path delta (metres, pairs from the reference).
        dataset: a name for the rows.
        include_odometry: add a row per seed for the odometry alone (sampler ``"odometry"``).
        progress: called with each row as it is done.

    Returns:
        :class:`Results`.
    """
    if isinstance(verifier, str):
        if verifier not in VERIFIER_MODELS:
            raise InvalidParameterError(
                f"evaluate: unknown verifier model {verifier!r}: expected one of "
                + ", ".join(VERIFIER_MODELS)
            )
        verifier = VERIFIER_MODELS[verifier]
    verifier = verifier or Verifier()
    verifier_name = _verifier_name(verifier)
    backend = backend or BackEnd()
    drift = (
        odometry
        if isinstance(odometry, DriftModel)
        else (DriftModel() if odometry is None else None)
    )
    detection_samplers = tuple(detection_samplers) if detection_samplers is not None else SAMPLERS
    results = Results(
        settings={
            "dataset": dataset,
            "poses": len(reference),
            "dim": reference.dim,
            "gamma": gamma,
            "odometry": dataclasses.asdict(drift) if drift else "given",
            "verifier": dataclasses.asdict(verifier),
            "backend": dataclasses.asdict(backend),
            "gamma_inflation": gamma_inflation,
            "detection_rate": detection_rate,
            "epsilon_s": epsilon_s,
            "rpe_delta_m": rpe_delta_m,
        }
    )

    def errors(estimate: Poses) -> tuple[float, float]:
        return ate(reference, estimate), rpe(reference, estimate, delta=rpe_delta_m, delta_unit="m")

    def record(
        base: dict[str, Any],
        rule: CandidateRule | None,
        outlier_rate: float,
        candidates: int,
        matches: Matches | None,
        ate_m: float,
        rpe_m: float,
        start: float,
    ) -> None:
        """Adds the row of a run (``rule`` None: the odometry alone)."""
        row = base | {
            "sampler": rule.sampler if rule else "odometry",
            "source": rule.source if rule else "",
            "on": rule.on if rule else "",
            "separation": rule.separation if rule else False,
            "outlier_rate": float(outlier_rate),
            "verifier": verifier_name,
            "rounds": rule.rounds if rule else 0,
            "budget": rule.budget if rule else 0,
            "candidates": candidates,
            "matches": 0 if matches is None else len(matches),
            "wrong": 0 if matches is None else int(matches.wrong.sum()),
            "ate_m": ate_m,
            "rpe_m": rpe_m,
            "seconds": time.perf_counter() - start,
        }
        results.rows.append(row)
        if progress:
            progress(row)

    for seed in seeds:
        odo = drift.simulate(reference, seed=seed) if drift else odometry
        assert isinstance(odo, Odometry)
        start = time.perf_counter()
        # The pose graph of the odometry alone is solved by dead reckoning.
        odo_ate, odo_rpe = errors(odo.estimate)
        base = {"dataset": dataset, "seed": int(seed), "odometry_ate_m": odo_ate}
        if include_odometry:
            record(base, None, 0.0, 0, None, odo_ate, odo_rpe, start)
        for outlier_rate, rule in _grid(
            outlier_rates,
            on,
            separations,
            sources,
            samplers,
            detection_samplers,
            budgets,
            rounds,
            gamma=gamma,
            gamma_inflation=gamma_inflation,
            detection_rate=detection_rate,
            epsilon_s=epsilon_s,
        ):
            start = time.perf_counter()
            estimate, matches, pairs = evaluate_one(
                reference,
                odo,
                rule,
                seed=int(seed),
                verifier=dataclasses.replace(verifier, outlier_rate=outlier_rate),
                backend=backend,
            )
            ate_m, rpe_m = errors(estimate)
            assert matches is not None
            record(base, rule, outlier_rate, len(pairs[0]), matches, ate_m, rpe_m, start)
    return results


# ---------------------------------------------------------------------------------------------
# The plot
# ---------------------------------------------------------------------------------------------

#: Colours of the samplers in :func:`plot_error_vs_matches`.
COLOURS: Mapping[str, str] = {
    "one": "deepskyblue",
    "rho": "forestgreen",
    "rho-dispersed": "darkorange",
    "closest-first": "crimson",
    "closest-then-spread": "black",
    "alpha": "magenta",
    "lio-sam": "0.35",
    "hdl-graph-slam": "sienna",
    "cartographer": "slateblue",
    "time-gap": "olive",
}


def plot_error_vs_matches(
    results: Results,
    *,
    ax: Any = None,
    select: Mapping[str, Any] | None = None,
    metric: Literal["ate", "rpe"] = "ate",
    title: str | None = None,
    legend: bool = True,
) -> Any:
    """The error against the number of matches (the budget, log scale), one curve per sampler
    (dashed: on detections): the median over the seeds, and for ATE a band over the middle half
    of them (first to third quartile); the odometry alone as a dotted line. ``select`` keeps the
    rows whose columns have these values (e.g. ``{"separation": True, "outlier_rate": 0.0}``).
    ``legend=False`` leaves the legend to the caller (``ax.get_legend_handles_labels()``).
    Needs matplotlib.
    """
    ax, select, curves = _curves(results, ax, select, "source")
    column = "ate" if metric == "ate" else "rpe"
    for (name, source), points in curves:
        x = [s["budget"] for s in points]
        y = [s[f"{column}_median_m"] for s in points]
        label = sampler_symbol(name) + (" (detections)" if source == "detections" else "")
        style = "--" if source == "detections" else "-"
        colour = COLOURS.get(name)
        ax.plot(
            x,
            y,
            style,
            marker="o",
            ms=3,
            color=colour,
            label=label,
            lw=1.5 if name in SAMPLERS else 1.0,
        )
        if column == "ate":
            ax.fill_between(
                x,
                [s["ate_q25_m"] for s in points],
                [s["ate_q75_m"] for s in points],
                color=colour,
                alpha=0.1,
            )
    odometry = [
        r[f"{column}_m"]
        for r in results.rows
        if r["sampler"] == "odometry"
        and ("dataset" not in select or r["dataset"] == select["dataset"])
    ]
    _finish_axes(ax, odometry, "ATE (m)" if column == "ate" else "RPE (m)", title, legend)
    return ax


def _curves(
    results: Any, ax: Any, select: Mapping[str, Any] | None, style: str
) -> tuple[Any, dict[str, Any], list[tuple[tuple[str, Any], list[dict[str, Any]]]]]:
    """What a plot of the error against the budget draws: the axes (new ones when ``ax`` is
    None), the selection as a dict, and the summary rows (not the odometry's) that ``select``
    keeps, per (sampler, the value of ``style``), in the order of :data:`SAMPLERS` and
    :data:`BASELINES`, each curve's points by budget."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2))
    select = dict(select or {})
    curves: dict[tuple[str, Any], list[dict[str, Any]]] = {}
    for s in results.summary():
        if s["sampler"] != "odometry" and all(s.get(k) == v for k, v in select.items()):
            curves.setdefault((s["sampler"], s[style]), []).append(s)
    order = {name: k for k, name in enumerate(SAMPLERS + BASELINES)}
    for points in curves.values():
        points.sort(key=lambda s: s["budget"])
    ranked = sorted(curves.items(), key=lambda kv: (order.get(kv[0][0], 99), kv[0][1]))
    return ax, select, ranked


def _finish_axes(
    ax: Any, odometry: Sequence[float], ylabel: str, title: str | None, legend: bool
) -> None:
    """Log scales, the odometry alone as a dotted line (the median of ``odometry``, when
    any), the labels, the title, the grid and the legend."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    if odometry:
        level = float(np.median(odometry))
        low, high = ax.get_ylim()
        ax.axhline(level, color="k", ls=":", lw=1, label="odometry alone")
        ax.set_ylim(low, max(high, 1.5 * level))
    ax.set_xlabel("matches tried (budget)")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if legend:
        ax.legend(fontsize=7, ncol=2)


# ---------------------------------------------------------------------------------------------
# The fleet case (its own module, which builds on this one; its names are served from here)
# ---------------------------------------------------------------------------------------------


def __getattr__(name: str) -> Any:
    """The fleet case's names (its ``__all__``), from :mod:`inexact_loops._fleet_evaluate`
    (imported on first use: it imports this module)."""
    if not name.startswith("__"):
        from . import _fleet_evaluate

        if name in _fleet_evaluate.__all__:
            return getattr(_fleet_evaluate, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# ---------------------------------------------------------------------------------------------
# The command line: loops-eval
# ---------------------------------------------------------------------------------------------


def _plot_panels(results: Results, path: str, *, title: str) -> None:
    """:func:`plot_error_vs_matches` per run condition: a row per (on, separation), a column per
    outlier rate."""

    def draw(ax: Any, row: tuple[str, bool], outlier_rate: float) -> None:
        on, separation = row
        plot_error_vs_matches(
            results,
            ax=ax,
            select={"on": on, "separation": separation, "outlier_rate": outlier_rate},
            title=f"{title}: candidates on the {on}, "
            + ("revisits" if separation else "S_gamma")
            + f", {outlier_rate:.0%} wrong matches",
        )

    _save_panels(
        results.rows,
        path,
        lambda runs: sorted(
            {(r["on"], r["separation"]) for r in runs},
            key=lambda k: (k[0] != "reference", not k[1]),
        ),
        draw,
    )


def _save_panels(
    rows: Sequence[dict[str, Any]],
    path: str,
    panel_rows: Callable[[list[dict[str, Any]]], Sequence[Any]],
    draw: Callable[[Any, Any, float], None],
) -> None:
    """Saves to ``path`` a figure of panels: a row per value that ``panel_rows`` finds in the
    runs of ``rows`` (not the odometry's), a column per outlier rate; ``draw(ax, row,
    outlier_rate)`` draws each."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [r for r in rows if r["sampler"] != "odometry"]
    panels = panel_rows(runs)
    columns = sorted({r["outlier_rate"] for r in runs})
    fig, axes = plt.subplots(
        max(len(panels), 1),
        max(len(columns), 1),
        figsize=(6.4 * max(len(columns), 1), 4.2 * max(len(panels), 1)),
        squeeze=False,
    )
    for a, row in enumerate(panels):
        for b, outlier_rate in enumerate(columns):
            draw(axes[a][b], row, outlier_rate)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _csv_list(text: str, kind: Callable[[str], Any]) -> list[Any]:
    return [kind(v) for v in text.split(",") if v.strip()]


def _read_options(args: Any) -> tuple[dict[str, Any], tuple[int, int] | None]:
    """Checks that ``--out`` is empty (or ``--force``), and returns the options of
    :meth:`Poses.read` that the command line gives (``--rate-hz``, ``--times``, ``--format``)
    and its ``--axes``."""
    import os

    if os.path.exists(args.out) and os.listdir(args.out) and not args.force:
        raise InvalidParameterError(
            f"{args.out} exists and is not empty (--force to write into it)"
        )
    options: dict[str, Any] = {}
    if args.rate_hz is not None:
        options["rate_hz"] = args.rate_hz
    if args.times:
        options["times"] = args.times
    if args.format:
        options["format"] = args.format
    axes: tuple[int, int] | None = None
    if args.axes:
        pair = _csv_list(args.axes, int)
        if len(pair) != 2:
            raise InvalidParameterError(f"--axes {args.axes}: two axes, e.g. 0,2")
        axes = (pair[0], pair[1])
    return options, axes


def _write_outputs(
    out: str,
    results: Any,
    csv_names: Sequence[str],
    plot: Callable[[str], None],
    describe: Callable[[dict[str, Any]], str],
) -> None:
    """Writes ``results`` into the folder ``out``: ``results.to_csv`` to ``csv_names``,
    ``results.json``, the plot ``error_vs_matches.png`` (a note on stderr without matplotlib),
    and prints a line per summary row but the odometry's."""
    import os
    import sys

    os.makedirs(out, exist_ok=True)
    results.to_csv(*(os.path.join(out, name) for name in csv_names))
    results.to_json(os.path.join(out, "results.json"))
    try:
        plot(os.path.join(out, "error_vs_matches.png"))
    except ImportError:
        print("loops-eval: matplotlib is not installed: no plot", file=sys.stderr)
    for s in results.summary():
        if s["sampler"] != "odometry":
            print(describe(s))
    print(f"loops-eval: results in {out}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """``loops-eval``: runs :func:`evaluate` on a pose file (:func:`evaluate_fleet` on several,
    one a session, with ``--fleet``); writes ``results.csv``, ``results.json`` and
    ``error_vs_matches.png`` to ``--out`` (and ``sessions.csv`` for a fleet)."""
    import sys

    from . import _console
    from .errors import LoopsError

    parser = _console.ArgumentParser(
        prog="loops-eval",
        description=(
            "Do the samples make better maps? Simulates an odometry from the reference poses (or "
            "takes yours), chooses candidate pairs with each sampler and baseline under each "
            "budget, verifies them with a seeded stand-in for the scan matcher, optimises the pose "
            "graph with GTSAM and reports ATE and RPE (evo's definitions)."
        ),
        epilog=(
            "example: loops-eval kitti_odometry/00.txt --axes 0,2 --gamma 6 --budgets 100,1000 "
            "--seeds 3 --out eval-00"
        ),
    )
    parser.add_argument(
        "poses", nargs="+", help="the reference pose file(s), any format loops reads"
    )
    parser.add_argument("--gamma", type=float, required=True, help="gamma of the loops, metres")
    parser.add_argument(
        "--out", required=True, help="folder for results.csv, results.json, error_vs_matches.png"
    )
    parser.add_argument("--axes", help="the plane, e.g. 0,2 for KITTI (SE(2) in it); default x-y")
    parser.add_argument("--se3", action="store_true", help="evaluate in SE(3) instead of SE(2)")
    parser.add_argument("--rate-hz", type=float, help="for files without times (KITTI, MulRan)")
    parser.add_argument("--times", help="a file of times for files without them")
    parser.add_argument("--format", help="the file format, when the extension does not say")
    parser.add_argument(
        "--keyframe-m",
        type=float,
        default=0.0,
        help="keep a pose every this many metres (the pose graph's nodes); 0: all",
    )
    parser.add_argument(
        "--odometry", help="your odometry as a pose file (one pose per reference pose)"
    )
    parser.add_argument(
        "--odometry-sigma",
        default="0.05,0.005",
        help="with --odometry: translation (m) and rotation (rad) sigma per step",
    )
    parser.add_argument(
        "--samplers",
        default=",".join(SAMPLERS + BASELINES),
        help="comma-separated sampler names (default: all)",
    )
    parser.add_argument("--budgets", default="100,1000,10000", help="comma-separated budgets")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1")
    parser.add_argument(
        "--separation",
        default="on",
        choices=["on", "off", "both"],
        help="revisits only (on), the paper's S_gamma (off), or both",
    )
    parser.add_argument("--source", default="exact", choices=["exact", "detections", "both"])
    parser.add_argument(
        "--on",
        default="reference",
        choices=["reference", "estimate", "both"],
        help="choose candidates on the reference, on the odometry's estimate, or both",
    )
    parser.add_argument("--gamma-inflation", type=float, default=2.0)
    parser.add_argument(
        "--rounds",
        type=int,
        default=1,
        help="with --on estimate: spend the budget in this many rounds, each chosen on the "
        "estimate the earlier rounds' matches corrected (default 1: all at once)",
    )
    parser.add_argument(
        "--verifier",
        default="distance-aware",
        choices=list(VERIFIER_MODELS),
        help="the scan matcher's stand-in (VERIFIER_MODELS in inexact_loops.evaluate)",
    )
    parser.add_argument("--outliers", default="0", help="comma-separated outlier rates")
    parser.add_argument("--kernel", default="cauchy", choices=["cauchy", "huber", "gauss", "gnc"])
    parser.add_argument("--force", action="store_true", help="write into an existing --out")
    fleet = parser.add_argument_group(
        "fleets",
        "--fleet reads each pose file as a session of one fleet (NAME=FILE names it; a file "
        "alone is named by its stem), all in one world frame, and evaluates the multi-session "
        "map: each session's odometry starts in its own frame, only the anchor's start is known, "
        "candidates come from sample_fleet; it writes results.csv, sessions.csv (each session's "
        "own ATE per run), results.json and error_vs_matches.png (joint ATE and inter-session "
        "error). Not with --odometry, --on estimate or --source detections.",
    )
    fleet.add_argument("--fleet", action="store_true", help="the pose files are a fleet's sessions")
    fleet.add_argument(
        "--between-only",
        default="both",
        choices=["on", "off", "both"],
        help="sample the components between sessions only (on), every component (off), or both",
    )
    fleet.add_argument("--anchor", help="the session whose start is known (default: the first)")
    fleet.add_argument(
        "--overlap-m",
        type=float,
        help="radius of the pose pairs of the inter-session error (default: gamma)",
    )
    args = parser.parse_args(argv)
    try:
        if args.fleet:
            from ._fleet_evaluate import main_fleet

            main_fleet(args)
        else:
            _main_one(args)
        return 0
    except (LoopsError, OSError, ValueError, ImportError, MemoryError) as err:
        text = str(err).strip().splitlines()
        print(f"loops-eval: error: {text[0] if text else type(err).__name__}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _console.interrupted("loops-eval")


def _main_one(args: Any) -> None:
    """``loops-eval`` on one trajectory (``args`` parsed by :func:`main`)."""
    import os
    import sys

    def both(value: str, yes: Any, no: Any) -> list[Any]:
        return [yes, no] if value == "both" else [yes if value in ("on", yes) else no]

    options, axes = _read_options(args)
    dim: Literal[2, 3] = 3 if args.se3 else 2
    paths = args.poses if len(args.poses) > 1 else args.poses[0]
    reference = Poses.read(paths, dim=dim, axes=axes, **options)  # type: ignore[arg-type]
    keep = reference.keyframes(args.keyframe_m)
    reference = reference.take(keep)
    odometry: Odometry | DriftModel = DriftModel()
    if args.odometry:
        sigma_t, sigma_r = _csv_list(args.odometry_sigma, float)
        mine = Poses.read(args.odometry, dim=dim, axes=axes, **options).take(keep)
        odometry = Odometry.from_poses(
            mine, translation_sigma_m=sigma_t, rotation_sigma_rad=sigma_r
        )
    samplers = _csv_list(args.samplers, str)
    results = evaluate(
        reference,
        gamma=args.gamma,
        odometry=odometry,
        samplers=samplers,
        budgets=_csv_list(args.budgets, int),
        seeds=range(args.seeds),
        separations=both(args.separation, True, False),
        sources=["exact", "detections"] if args.source == "both" else [args.source],
        on=["reference", "estimate"] if args.on == "both" else [args.on],
        outlier_rates=_csv_list(args.outliers, float),
        verifier=args.verifier,
        backend=BackEnd(kernel=args.kernel),
        gamma_inflation=args.gamma_inflation,
        rounds=args.rounds,
        dataset=os.path.basename(args.poses[0]),
        progress=lambda r: print(
            f"loops-eval: seed {r['seed']} {r['sampler']:>15} {r['on'] or '':>9} "
            f"budget {r['budget']:>6}: {r['matches']:>5} matches ({r['wrong']} wrong), "
            f"ATE {r['ate_m']:.3f} m",
            file=sys.stderr,
        ),
    )
    _write_outputs(
        args.out,
        results,
        ["results.csv"],
        lambda path: _plot_panels(results, path, title=os.path.basename(args.poses[0])),
        lambda s: (
            f"{s['sampler']:>15} {s['source']:>10} {s['on']:>9} sep={int(s['separation'])} "
            f"out={s['outlier_rate']:.2f} budget {s['budget']:>6}: "
            f"ATE {s['ate_median_m']:.3f} m "
            f"[{s['ate_min_m']:.3f}, {s['ate_max_m']:.3f}]"
        ),
    )


if __name__ == "__main__":
    import sys

    sys.exit(main())
