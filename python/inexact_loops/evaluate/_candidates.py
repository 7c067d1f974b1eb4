"""Candidate pairs: a sampler or a baseline under a budget, chosen on the reference or the
estimate, in one or several rounds."""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .._core import (
    Separation,
    Trajectory,
    cluster_detections,
    draw_detections,
    find_loops,
    path_length,
    sample,
)
from ..errors import InvalidParameterError, LoopsWarning
from ._poses import Poses
from ._verifier import Matches

#: The samplers of the paper and beyond (:func:`inexact_loops.sample`'s names).
SAMPLERS: tuple[str, ...] = (
    "one",
    "rho",
    "rho-dispersed",
    "closest-first",
    "closest-then-spread",
    "nearest-then-uniform",
    "alpha",
)
#: The candidate rules of deployed SLAM systems, under the same budget.
BASELINES: tuple[str, ...] = ("lio-sam", "hdl-graph-slam", "cartographer", "time-gap")

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
        rounds_order: ``"any"``: each round chooses over the whole estimate; ``"time"``: as an
            online front end does, round r chooses only pairs whose later pose lies in the r-th
            stretch of the path (equal shares of its length), on the estimate the earlier
            rounds corrected; in rounds, not with a baseline or ``source="detections"``, which
            read the poses' times.
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
    rounds_order: Literal["any", "time"] = "any"

    def __post_init__(self) -> None:
        check_rule("CandidateRule", self.sampler, self.budget, self.gamma)
        if self.source not in ("exact", "detections"):
            raise InvalidParameterError(
                f"CandidateRule: source {self.source!r}: exact or detections"
            )
        check_on("CandidateRule", self.on, self.gamma_inflation, self.rounds)
        if self.rounds_order not in ("any", "time"):
            raise InvalidParameterError(
                f"CandidateRule: rounds_order {self.rounds_order!r}: any or time"
            )
        time_rounds = self.rounds_order == "time" and self.rounds > 1
        if time_rounds and (self.is_baseline or self.source != "exact"):
            raise InvalidParameterError(
                f'CandidateRule: rounds_order="time" with {self.sampler!r} on {self.source!r}: '
                'only a sampler of SAMPLERS on source="exact"'
            )

    @property
    def is_baseline(self) -> bool:
        """Whether the sampler is a deployed system's rule."""
        return self.sampler in BASELINES


def check_rule(kind: str, sampler: str, budget: int, gamma: float) -> None:
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


def check_on(kind: str, on: str, gamma_inflation: float, rounds: int) -> None:
    """The checks a candidate rule of either kind (``kind``, its class's name) makes of where it
    chooses, its inflation of gamma and its rounds."""
    if on not in ("reference", "estimate"):
        raise InvalidParameterError(f"{kind}: on {on!r}: reference or estimate")
    if not (math.isfinite(gamma_inflation) and gamma_inflation >= 1):
        raise InvalidParameterError(f"{kind}: gamma_inflation = {gamma_inflation} must be >= 1")
    if rounds < 1 or (rounds > 1 and on != "estimate"):
        raise InvalidParameterError(
            f'{kind}: rounds = {rounds}: at least 1, and more only with on="estimate"'
        )


def choose_candidates(
    poses: Poses,
    rule: CandidateRule,
    *,
    seed: int,
    gamma_inflation: float | None = None,
    later_in: tuple[int, int] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs ``(i, j)``, i < j, chosen by ``rule`` on ``poses`` (the reference, or the
    odometry's estimate for ``rule.on == "estimate"``: pass the poses the rule is to see).

    Loops are found on the positions (Euclidean, metres) within ``rule.gamma`` times the
    inflation (``gamma_inflation``, else ``rule.gamma_inflation`` on the estimate, 1 on the
    reference); warnings of the samplers (a budget above the candidates, below the components)
    are kept quiet: the returned count says it. ``later_in=(a, b)``: only the pairs whose later
    pose j lies in ``a <= j < b`` (:func:`_later_in`), the whole budget spent on them.
    """

    if gamma_inflation is None:
        gamma_inflation = rule.gamma_inflation if rule.on == "estimate" else 1.0
    gamma = rule.gamma * gamma_inflation
    separation: Separation | None = Separation.for_gamma(rule.gamma) if rule.separation else None
    if later_in is None:
        traj = poses.to_trajectory()
    else:
        traj, separation = _later_in(poses.positions, *later_in, separation)
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


def _later_in(
    positions: np.ndarray, a: int, b: int, separation: Separation | None
) -> tuple[Trajectory, Separation]:
    """A trajectory and separation whose loops are exactly those of ``positions[:b]`` (under
    ``separation``) with the later pose j in ``a <= j < b``, so that a sampler spends its whole
    budget on them (the library has no window of its own). The poses keep their positions; their
    times become a clock under which a time separation of ``a + 1`` parts the pairs before
    ``a``: poses k < a tick 1 s apart (any two at most a - 1 s apart), poses k >= a tick
    ``2 a + 2`` s apart (any pair with j >= a at least that far apart). The times are pose
    indices, not seconds: no sampler that reads times may be used on it."""
    k = np.arange(b, dtype=float)
    tick = 2.0 * a + 2.0
    clock = np.where(k < a, k, a + (k - a + 1) * tick)
    path = separation.path if separation is not None else 0.0
    return Trajectory(clock, positions[:b]), Separation(path=path, time_s=a + 1.0)


class _RoundsRule:
    """The rule of candidates in rounds, whatever a pair is: the budget's shares, the rounds'
    seeds, the pairs already tried and the inflation of gamma. :class:`Rounds` (one
    trajectory) and :class:`~inexact_loops.evaluate.FleetRounds` (a fleet) are this rule with
    their own way of choosing, so that both spend a budget alike.

    The budget is spent in ``rounds`` rounds of equal shares (the last takes what the others
    left). Round k asks its sampler, with seed ``seed + k``, for its share plus the pairs
    already tried, leaves those out, and keeps the share by a seeded draw. The inflation of
    gamma starts at ``gamma_inflation`` and, after each round, is ``1 + min(gamma_inflation - 1,
    c / gamma)``, with c the median distance (metres) the last optimisation moved the poses.
    """

    def __init__(self, rule: Any, *, seed: int) -> None:
        """``rule``: a :class:`CandidateRule` or a fleet's rule, ``on="estimate"``."""
        if rule.on != "estimate":
            raise InvalidParameterError(f'{type(self).__name__}: the rule chooses on="estimate"')
        #: The candidate rule.
        self.rule = rule
        self._budget, self._rounds = int(rule.budget), int(rule.rounds)
        self._gamma = float(rule.gamma)
        self._top = float(rule.gamma_inflation) - 1.0
        #: The first round's seed.
        self.seed = int(seed)
        #: Rounds chosen so far.
        self.round = 0
        #: The inflation of gamma the next round uses.
        self.gamma_inflation = float(rule.gamma_inflation)
        self._tried: set[tuple[int, ...]] = set()
        #: ``"any"`` (each round over the whole estimate) or ``"time"`` (one stretch each).
        self.order: str = getattr(rule, "rounds_order", "any")
        self._bounds: np.ndarray | None = None

    def _window(self, estimate: Poses) -> tuple[int, int]:
        """The poses ``a <= j < b`` the next round's later poses lie in, for ``order="time"``:
        the stretches split the path of the first estimate the rounds see into ``rounds``
        equal lengths, fixed from then on."""
        if self._bounds is None:
            path_m = np.asarray(path_length(estimate.to_trajectory()))
            edges = path_m[-1] * np.arange(1, self._rounds) / self._rounds
            inner = np.searchsorted(path_m, edges, side="left")
            self._bounds = np.r_[0, inner, len(path_m)].astype(np.int64)
        return int(self._bounds[self.round]), int(self._bounds[self.round + 1])

    @property
    def done(self) -> bool:
        """Whether every round is chosen (or the budget is spent)."""
        return self.round >= self._rounds or len(self._tried) >= self._budget

    @property
    def tried(self) -> int:
        """Pairs chosen so far."""
        return len(self._tried)

    def _next_round(self) -> tuple[int, int]:
        """The next round's share of the budget and its seed; the sampler is asked for the
        share plus :attr:`tried` pairs."""
        left = self._budget - len(self._tried)
        share = left if self.round == self._rounds - 1 else left // (self._rounds - self.round)
        return max(share, 1), self.seed + self.round

    def _keep(self, pairs: Sequence[tuple[int, ...]], share: int, seed: int) -> np.ndarray:
        """The indices (ascending) of the ``pairs`` the sampler returned that the round keeps:
        those not tried before, thinned to ``share`` by a draw of ``seed``; they count as tried
        from now on, and the round is done."""
        fresh = np.flatnonzero(np.array([p not in self._tried for p in pairs], bool))
        if len(fresh) > share:
            rng = np.random.default_rng(np.random.SeedSequence([seed, 0x0C0]))
            fresh = fresh[np.sort(rng.choice(len(fresh), share, replace=False))]
        self._tried.update(pairs[int(k)] for k in fresh)
        self.round += 1
        return fresh

    def _settle(self, moved_m: np.ndarray) -> None:
        """The next round's inflation of gamma from the distances (metres) the last
        optimisation moved the poses."""
        c = float(np.median(moved_m)) if len(moved_m) else 0.0
        self.gamma_inflation = 1.0 + min(self._top, c / self._gamma)


class Rounds(_RoundsRule):
    """Candidates in rounds, for a pipeline without ground truth: choose some pairs on the
    current estimate, match them, optimise, and choose the next ones on the corrected estimate.

    The budget (``rule.budget``) is spent in ``rule.rounds`` rounds of equal shares (the last
    takes what the others left). Round k chooses with ``rule``'s sampler on the estimate it is
    given, gamma inflated by a factor that starts at ``rule.gamma_inflation`` and shrinks as the
    estimate settles: after each round, ``1 + min(gamma_inflation - 1, c / gamma)``, with c the
    median distance (metres) the last optimisation moved the poses. A pair is tried once: the
    pairs of earlier rounds are left out (the sampler is asked for that many more, and a seeded
    draw keeps the round's share). Each round's sampler seed is ``seed + round``. With
    ``rule.rounds_order="time"``, as an online front end: round r chooses only pairs whose
    later pose lies in the r-th of ``rule.rounds`` stretches of equal path length (of the first
    estimate), its whole share on them, so that a pair's two poses differ mostly by the drift
    since the part the earlier rounds corrected. A fleet's
    :class:`~inexact_loops.evaluate.FleetRounds` follows the same rule (in any order).

    Attributes:
        rule: the candidate rule.
        seed: the first round's seed.
        round: rounds chosen so far.
        gamma_inflation: the inflation of gamma the next round uses.
        done: whether every round is chosen (or the budget is spent).
        tried: pairs chosen so far.

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

    rule: CandidateRule

    def choose(self, estimate: Poses) -> tuple[np.ndarray, np.ndarray]:
        """The next round's pairs ``(i, j)``, i < j, chosen on ``estimate``, none of them chosen
        before; empty once :attr:`done`."""
        if self.done:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        share, seed = self._next_round()
        if self.order == "time":
            # Pairs of earlier rounds end before this stretch: the share is all the sampler
            # is asked for, on the loops of the estimate whose later pose is in the stretch.
            window = self._window(estimate)
            ask = dataclasses.replace(self.rule, budget=share, rounds=1)
            i, j = choose_candidates(
                estimate, ask, seed=seed, gamma_inflation=self.gamma_inflation, later_in=window
            )
        else:
            ask = dataclasses.replace(self.rule, budget=share + self.tried, rounds=1)
            i, j = choose_candidates(estimate, ask, seed=seed, gamma_inflation=self.gamma_inflation)
        keep = self._keep(list(zip(i.tolist(), j.tolist(), strict=True)), share, seed)
        return i[keep], j[keep]

    def update(self, before: Poses, after: Poses) -> None:
        """Tells the rounds how the last optimisation moved the estimate (``before`` to
        ``after``, the same poses): the next round's gamma inflation."""
        self._settle(np.linalg.norm(after.positions - before.positions, axis=1))


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
