"""The verifier: a seeded stand-in for the scan matcher, and the matches it returns."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import InvalidParameterError
from ._poses import Poses, homogeneous, quat_xyzw_to_matrix, rot2, rot3

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
            noisy_rot = truth[:, :2, :2] @ rot2(e_r[:, 0])
        else:
            noisy_rot = truth[:, :3, :3] @ rot3(e_r)
        measured = homogeneous(noisy_rot, truth[:, :d, d] + e_t)
        if wrong.any():
            w = u[wrong, base:]
            radius = self.outlier_radius_m * w[:, 0] ** (1.0 / d)
            if d == 2:
                direction = np.c_[np.cos(2 * np.pi * w[:, 1]), np.sin(2 * np.pi * w[:, 1])]
                rot = rot2(2 * np.pi * w[:, 2] - np.pi)
            else:
                z = 2 * w[:, 1] - 1
                phi = 2 * np.pi * w[:, 2]
                direction = np.c_[
                    np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z
                ]
                rot = _uniform_rotations(w[:, 3], w[:, 4], w[:, 5])
            measured[wrong] = homogeneous(rot, direction * radius[:, None])
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


def name_of_verifier(verifier: Verifier) -> str:
    """The name of ``verifier``'s model in :data:`VERIFIER_MODELS` (its outlier rate aside), or
    ``"custom"``."""
    plain = dataclasses.replace(verifier, outlier_rate=0.0)
    return next((k for k, v in VERIFIER_MODELS.items() if v == plain), "custom")


def _uniform_rotations(u1: np.ndarray, u2: np.ndarray, u3: np.ndarray) -> np.ndarray:
    """Rotations uniform on SO(3) from three uniforms each (Shoemake's method)."""
    a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
    q = np.c_[a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2), b * np.sin(2 * np.pi * u3)]
    return quat_xyzw_to_matrix(np.c_[q, b * np.cos(2 * np.pi * u3)])
