"""Odometry: yours, or simulated from the reference by a seeded drift model."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import InvalidParameterError
from ._poses import Poses, homogeneous, rigid_inverse, rot2, rot3

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
        steps = rigid_inverse(est[k[:-1]]) @ est[k[1:]]
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
            rotation = truth[:, :2, :2] @ rot2(rng.standard_normal(n) * r_sd + bias)
        else:
            up = np.asarray(self.up_axis, dtype=float)
            up = up / np.linalg.norm(up)
            rotvec = rng.standard_normal((n, 3)) * r_sd[:, None] + bias[:, None] * up
            rotation = truth[:, :3, :3] @ rot3(rotvec)
        return Odometry(
            homogeneous(rotation, translation),
            np.maximum(t_sd, self.min_translation_sigma_m),
            np.maximum(r_sd, self.min_rotation_sigma_rad),
            reference.matrices[0].copy(),
            reference.timestamps,
        )
