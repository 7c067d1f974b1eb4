"""The pose-graph back end (GTSAM): odometry and verified loop factors, a robust kernel."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ..errors import InvalidParameterError
from ._odometry import Odometry
from ._poses import Poses
from ._verifier import Matches

_GTSAM_HINT = (
    "the pose-graph back end needs GTSAM: pip install '.[maps]' in a checkout "
    "(or pip install gtsam)"
)


def import_gtsam() -> Any:
    try:
        import gtsam
    except ImportError as err:  # pragma: no cover - exercised only without gtsam
        raise ImportError(_GTSAM_HINT) from err
    return gtsam


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


def pose_value(gtsam: Any, m: np.ndarray) -> Any:
    if m.shape == (3, 3):
        return gtsam.Pose2(m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0]))
    return gtsam.Pose3(m)


def noise_model(gtsam: Any, dim: int, t_sigma: float, r_sigma: float) -> Any:
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
    gtsam = import_gtsam()
    backend = backend or BackEnd()
    dim = odometry.dim
    between = gtsam.BetweenFactorPose2 if dim == 2 else gtsam.BetweenFactorPose3
    prior = gtsam.PriorFactorPose2 if dim == 2 else gtsam.PriorFactorPose3
    graph = gtsam.NonlinearFactorGraph()
    initial = gtsam.Values()
    estimate = odometry.estimate.matrices
    graph.add(prior(0, pose_value(gtsam, odometry.start), noise_model(gtsam, dim, 1e-4, 1e-5)))
    for k, step in enumerate(odometry.steps):
        noise = noise_model(
            gtsam, dim, odometry.translation_sigma_m[k], odometry.rotation_sigma_rad[k]
        )
        graph.add(between(k, k + 1, pose_value(gtsam, step), noise))
    for k, m in enumerate(estimate):
        initial.insert(k, pose_value(gtsam, m))
    matrices = solve_graph(gtsam, graph, initial, backend, dim, matches, list(range(len(estimate))))
    return Poses(odometry.timestamps, matrices)


def solve_graph(
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
            noise = noise_model(gtsam, dim, ts, rs)
            if robust is not None:
                noise = gtsam.noiseModel.Robust.Create(robust(), noise)
            graph.add(between(keys[a], keys[b], pose_value(gtsam, rel), noise))
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
