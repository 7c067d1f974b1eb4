"""The errors: evo's APE and RPE on the translation part, and the alignment."""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import InvalidParameterError
from ._poses import Poses, rigid_inverse

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
    e = rigid_inverse(reference.relative(i, j)) @ estimate.relative(i, j)
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
