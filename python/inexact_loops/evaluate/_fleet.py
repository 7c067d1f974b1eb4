"""The fleet case of :mod:`inexact_loops.evaluate`: several sessions, one map.

Re-exported by :mod:`inexact_loops.evaluate`; read its docstring first. A fleet's sessions --
vehicles, days, robots -- are each a reference (:class:`~inexact_loops.evaluate.Poses`) in one
world frame. What a fleet adds to the single trajectory:

1. **Unknown starts.** Each session's odometry is simulated from its own reference with its own
   seed (:func:`simulate_fleet_odometry`), and -- as a robot's odometry does -- starts at the
   identity of its own frame: the back end does not know where a session starts, except for the
   *anchor* (the first session unless told), whose start is the reference's and fixes the map's
   frame. Nothing else ties the sessions together: every other session's first pose has only a
   weak prior at its initial guess (1 km and pi rad by default), which fixes the gauge of a
   session that no match ties to the others and is negligible against a match.
2. **Candidates between sessions.** :func:`choose_fleet_candidates` samples the fleet's loops
   (:func:`~inexact_loops.find_fleet_loops` on the positions, then
   :func:`~inexact_loops.sample_fleet`): over all components within and between sessions, or
   with ``between_only`` over the components between sessions only. On the references, or
   (``FleetRule(on="estimate")``) on the sessions' estimates, with gamma inflated and in rounds
   (:class:`FleetRounds`): only sessions that share a frame have pairs between them there --
   before the first match between two sessions of unknown starts, their estimates share none
   (that is place recognition's job); with ``known_starts`` every session's odometry starts at
   its reference's first pose (a fix at the start), so that all share the map's frame.
3. **The same verifier** (:class:`~inexact_loops.evaluate.Verifier`), on the pair's true
   relative pose, whichever sessions the poses belong to.
4. **A multi-robot pose graph** (:func:`optimize_fleet`, GTSAM): pose j of the s-th session is
   ``gtsam.Symbol(c, j)`` with c = ``a``, ``b``, ... (``A``... after ``z``): the keys of the
   ``samples.g2o`` that ``loops fleet`` writes. Its initial guess places each session by its
   matches to the sessions already placed (from the anchor outwards, the placement most matches
   agree with), so that Levenberg-Marquardt starts near the answer, as a multi-robot back end
   does after its first inter-robot loop closure; a session with no match keeps its own frame.
5. **Errors per session and joint** (:func:`fleet_errors`): each session's ATE after its own
   alignment (its shape), the joint ATE after one alignment of all sessions together (the map:
   misplaced sessions count), and the **inter-session relative error**, evo's RPE over pose
   pairs of two sessions that lie within ``overlap_m`` of each other in the references: where a
   map built from several sessions shows a doubled wall when they are misplaced, which is what
   the loops between sessions fix.

:func:`evaluate_fleet` runs the grid and returns :class:`FleetResults`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Literal

import numpy as np

from .._core import (
    Fleet,
    FleetLoops,
    Separation,
    find_fleet_loops,
    sample_fleet,
    sampler_symbol,
)
from ..errors import InvalidParameterError, LoopsWarning
from ..table import Table
from ._backend import BackEnd, import_gtsam, noise_model, pose_value, solve_graph
from ._candidates import (
    BASELINES,
    SAMPLERS,
    _concat_matches,
    _RoundsRule,
    check_on,
    check_rule,
)
from ._grid import json_default, medians, read_csv, summary_groups, write_csv
from ._metrics import ape_errors
from ._odometry import DriftModel, Odometry
from ._plot import COLOURS, error_curves, finish_axes
from ._poses import Poses, rigid_inverse
from ._verifier import Matches, Verifier

Sessions = Mapping[str, Poses]
#: A fleet's estimates as :class:`FleetRounds` takes them: per session a :class:`Poses` or an
#: array (matrices or positions), in a list or by name.
_Estimates = Sequence[Poses | np.ndarray] | Mapping[str, Poses | np.ndarray]


def _checked(references: Sessions) -> list[tuple[str, Poses]]:
    items = list(references.items())
    if not items:
        raise InvalidParameterError("a fleet evaluation needs at least one session")
    dims = {p.dim for _, p in items}
    if len(dims) != 1:
        raise InvalidParameterError(
            "the sessions mix SE(2) and SE(3) poses: "
            + ", ".join(f"{n}: SE({p.dim})" for n, p in items)
        )
    return items


def _anchor_index(names: Sequence[str], anchor: str | None) -> int:
    if anchor is None:
        return 0
    if anchor not in names:
        raise InvalidParameterError(
            f"anchor {anchor!r} is not a session; the sessions are {list(names)}"
        )
    return list(names).index(anchor)


def _starts(items: Sequence[tuple[str, Poses]]) -> np.ndarray:
    return np.r_[0, np.cumsum([len(p) for _, p in items])].astype(np.int64)


def _joint(items: Sequence[tuple[str, Poses]]) -> Poses:
    """The sessions' poses one after another (fleet indices), on a clock of one second a pose
    (only the verifier reads it, by index)."""
    matrices = np.concatenate([p.matrices for _, p in items])
    return Poses(np.arange(len(matrices), dtype=float), matrices)


def fleet_references(
    fleet: Fleet | Mapping[str, Poses], *, keyframe_m: float = 0.0
) -> dict[str, Poses]:
    """The sessions of ``fleet`` as references: an :class:`~inexact_loops.Fleet`'s sessions by
    :meth:`Poses.from_trajectory` (SE(2) and SE(3) ones as they are, positions in a plane
    headed along the motion; Euclidean positions of 3 coordinates, as
    :func:`~inexact_loops.urban_fleet` makes them, by their x and y), or ``{name: Poses}`` as
    given; keyframed every ``keyframe_m`` metres (:meth:`Poses.keyframes`; 0 keeps every
    pose)."""
    if isinstance(fleet, Fleet):
        sessions = {}
        for name in fleet.names:
            traj = fleet.session(name)
            if traj.manifold == "euclidean" and traj.dim == 3:
                sessions[name] = Poses.from_positions(traj.timestamps, traj.positions[:, :2])
            else:
                sessions[name] = Poses.from_trajectory(traj)
    else:
        sessions = dict(fleet)
    return {n: p.take(p.keyframes(keyframe_m)) for n, p in sessions.items()}


def session_key(session: int, pose: int) -> int:
    """The GTSAM key of pose ``pose`` of the ``session``-th session: ``gtsam.Symbol(c, pose)``,
    c = ``a`` for the first session ... ``z`` for the 26th, then ``A`` ... ``Z`` (52 sessions
    at most): ``(ord(c) << 56) | pose``, GTSAM's ``Symbol::key()``.

    Raises:
        InvalidParameterError: a 53rd session.
    """
    if not 0 <= session < 52:
        raise InvalidParameterError(
            f"session {session}: the pose graph names sessions a-z, A-Z (52 at most)"
        )
    letter = ord("a") + session if session < 26 else ord("A") + session - 26
    return (letter << 56) | int(pose)


# ---------------------------------------------------------------------------------------------
# Odometry and candidates
# ---------------------------------------------------------------------------------------------


def simulate_fleet_odometry(
    references: Sessions,
    *,
    seed: int,
    drift: DriftModel | None = None,
    anchor: str | None = None,
    known_starts: bool = False,
) -> dict[str, Odometry]:
    """Each session's odometry simulated by ``drift`` (the default :class:`DriftModel`) with its
    own seed (drawn from ``seed`` and the session's index), starting at the identity of its own
    frame -- except the anchor's (the first session unless named), which starts at its
    reference's first pose; with ``known_starts`` every session starts at its reference's
    first pose (all in the map's frame)."""
    items = _checked(references)
    drift = drift or DriftModel()
    a = _anchor_index([n for n, _ in items], anchor)
    out = {}
    for s, (name, poses) in enumerate(items):
        session_seed = int(np.random.SeedSequence([int(seed), s]).generate_state(1)[0])
        odometry = drift.simulate(poses, seed=session_seed)
        if s != a and not known_starts:
            odometry = dataclasses.replace(odometry, start=np.eye(poses.dim + 1))
        out[name] = odometry
    return out


@dataclass(frozen=True)
class FleetRule:
    """How a fleet's candidates are chosen.

    Attributes:
        sampler: a name :func:`~inexact_loops.sample_fleet` takes (:data:`SAMPLERS`; a
            baseline of :data:`BASELINES` runs over the joint trajectory, never with
            ``between_only``).
        budget: the number of candidates (scan matches to try), over the whole fleet.
        gamma: gamma of the loops, metres.
        separation: the revisit separation within each session (4 gamma of path), as the
            samplers do by default; pairs of two sessions are always kept.
        between_only: spend the budget on the components between sessions only (map merging);
            otherwise one sampling covers every component, within and between sessions.
        on: ``"reference"`` chooses on the references; ``"estimate"`` on the sessions'
            estimates, gamma inflated to ``gamma_inflation * gamma`` (the separation stays
            4 gamma of path), pairs between two sessions only where they share a frame
            (:class:`FleetRounds`).
        gamma_inflation: the factor for ``on="estimate"`` (as in
            :class:`~inexact_loops.evaluate.CandidateRule`).
        rounds: for ``on="estimate"``: the budget spent in this many rounds, each chosen on the
            estimates the matches of the rounds before corrected (:class:`FleetRounds`).
    """

    sampler: str
    budget: int
    gamma: float
    separation: bool = True
    between_only: bool = False
    on: Literal["reference", "estimate"] = "reference"
    gamma_inflation: float = 2.0
    rounds: int = 1

    def __post_init__(self) -> None:
        # An unknown sampler is no baseline: check_rule names it.
        if self.between_only and self.sampler in BASELINES:
            raise InvalidParameterError(
                f"FleetRule: {self.sampler} is a baseline, whose rule knows no components: "
                "not with between_only"
            )
        check_rule("FleetRule", self.sampler, self.budget, self.gamma)
        check_on("FleetRule", self.on, self.gamma_inflation, self.rounds)


def _fleet_loops(
    sessions: Sessions, gamma: float, separation: bool, *, separation_gamma: float | None = None
) -> FleetLoops:
    """The fleet loops of ``sessions`` within ``gamma``, the separation (when asked) that of
    ``separation_gamma`` (default: ``gamma``)."""
    fleet = Fleet({n: p.to_trajectory() for n, p in sessions.items()})
    within = Separation.for_gamma(separation_gamma or gamma) if separation else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LoopsWarning)
        return find_fleet_loops(fleet, gamma=gamma, separation=within)


def _frames_apart(sessions: Sessions, frames: Sequence[int], gap_m: float) -> dict[str, Poses]:
    """``sessions`` with those of different ``frames`` (a label per session) moved apart along
    the first axis, the frames' extents more than ``gap_m`` apart, so that no pair between
    sessions of different frames is within ``gap_m``; sessions of one frame keep their places
    relative to each other."""
    labels = {f: k for k, f in enumerate(dict.fromkeys(frames))}
    if len(labels) == 1:
        return dict(sessions)
    first = np.concatenate([p.positions[:, 0] for p in sessions.values()])
    step = float(first.max() - first.min()) + 2.0 * gap_m
    out = {}
    for (name, poses), frame in zip(sessions.items(), frames, strict=True):
        m = poses.matrices.copy()
        m[:, 0, poses.dim] += labels[frame] * step
        out[name] = Poses(poses.timestamps, m)
    return out


def choose_fleet_candidates(
    sessions: Sessions,
    rule: FleetRule,
    *,
    seed: int,
    loops: FleetLoops | None = None,
    gamma_inflation: float | None = None,
    frames: Sequence[int] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs ``(i, j)``, i < j, in *fleet indices* (the sessions' poses one after
    another, in the order of ``sessions``), chosen by ``rule`` on the sessions' positions (the
    references, or the estimates for ``rule.on == "estimate"``: pass the poses the rule is to
    see).

    Loops are found within ``rule.gamma`` times the inflation (``gamma_inflation``, else
    ``rule.gamma_inflation`` on the estimate, 1 on the references); ``frames``: a label per
    session, sessions of different labels sharing no frame (no pair between them); default:
    all in one frame. ``loops``: the :func:`~inexact_loops.find_fleet_loops` of these poses at
    that gamma and separation, when already found (it does not depend on the sampler, budget
    or seed). Warnings of the samplers are kept quiet: the returned count says it.
    """
    items = _checked(sessions)
    if loops is None:
        if gamma_inflation is None:
            gamma_inflation = rule.gamma_inflation if rule.on == "estimate" else 1.0
        gamma = rule.gamma * gamma_inflation
        if frames is not None:
            if len(frames) != len(items):
                raise InvalidParameterError(
                    f"choose_fleet_candidates: {len(frames)} frames for {len(items)} sessions"
                )
            sessions = _frames_apart(sessions, frames, gamma)
        loops = _fleet_loops(sessions, gamma, rule.separation, separation_gamma=rule.gamma)
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if loops.loops.pair_count == 0:
        return empty
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LoopsWarning)
        samples = sample_fleet(
            loops, rule.sampler, budget=rule.budget, seed=seed, between_only=rule.between_only
        ).samples
    i, j = samples.i, samples.j
    # An empty sample (no component between the sessions) has no pose columns.
    if i is None or j is None:
        return empty
    return np.minimum(i, j), np.maximum(i, j)


def _session_list(
    kind: str, sessions: Sequence[Poses | np.ndarray] | Mapping[str, Poses | np.ndarray]
) -> list[tuple[str, Poses]]:
    """The sessions as ``(name, poses)`` (``s0``, ``s1``, ... for a list): a :class:`Poses`
    as it is, an array of matrices ``(n, 3, 3)`` or ``(n, 4, 4)`` or of positions ``(n, 2)``
    (:meth:`Poses.from_positions`) on a clock of a pose a second; a one-line error naming the
    first session that is empty or of another shape."""
    named = (
        list(sessions.items())
        if isinstance(sessions, Mapping)
        else [(f"s{k}", p) for k, p in enumerate(sessions)]
    )
    if not named:
        raise InvalidParameterError(f"{kind}: no session")
    items = []
    for k, (name, poses) in enumerate(named):
        if len(poses) == 0:
            raise InvalidParameterError(f"{kind}: session {k} has no pose")
        if not isinstance(poses, Poses):
            a = np.asarray(poses, dtype=float)
            clock = np.arange(len(a), dtype=float)
            try:
                if a.ndim == 3:
                    poses = Poses(clock, a)
                else:
                    poses = Poses.from_positions(clock, a)
            except (ValueError, InvalidParameterError) as e:
                raise InvalidParameterError(f"{kind}: session {k}: {e}") from None
        items.append((name, poses))
    return _checked(dict(items))


class FleetRounds(_RoundsRule):
    """Candidates in rounds for a fleet, for a pipeline without ground truth: choose some pairs
    on the sessions' current estimates, match them, optimise the multi-session graph, and choose
    the next ones on the corrected estimates.

    The rule is :class:`~inexact_loops.evaluate.Rounds`'s: the budget (``rule.budget``, over
    the whole fleet) in ``rule.rounds`` equal shares, gamma inflated by a factor that starts at
    ``rule.gamma_inflation`` and shrinks as the optimisation stops moving the poses (the median
    over every pose of every session), each round's sampler seed ``seed + round``, no pair
    twice. A round samples the estimates' fleet loops with :func:`~inexact_loops.sample_fleet`
    (``rule.sampler``, ``rule.between_only``), as :func:`choose_fleet_candidates` does.

    Sessions that do not share a frame have no pair between them: pass ``frames``, a label per
    session (equal labels: one frame), to :meth:`choose` -- before the first match between two
    sessions whose starts are unknown, each is in its own frame; after your back end has placed
    them (:func:`place_sessions`), they share the anchor's. By default all share one frame.

    Attributes:
        rule: the fleet's candidate rule (``on="estimate"``).
        seed: the first round's seed.
        round: rounds chosen so far.
        gamma_inflation: the inflation of gamma the next round uses.
        done: whether every round is chosen (or the budget is spent).
        tried: pairs chosen so far.

    Drive it with your own matcher and back end::

        rounds = FleetRounds(FleetRule(DEFAULT_SAMPLER, 1000, 15.0, on="estimate", rounds=3),
                             seed=0)
        estimates = [odometry.estimate for odometry in sessions]   # one Poses per session
        frames = [0, 1, 2]                                  # each session in its own frame
        while not rounds.done:
            a, i, b, j = rounds.choose(estimates, frames=frames)   # pose i of session a ...
            ...                                   # match them, add the loop factors
            corrected = ...                       # optimise the multi-session graph
            rounds.update(estimates, corrected)
            estimates, frames = corrected, ...    # the frames your back end put them in

    Example:
        >>> import numpy as np
        >>> from inexact_loops.evaluate import FleetRounds, FleetRule, Poses
        >>> angle = np.linspace(0, 4 * np.pi, 200)
        >>> lap = Poses.from_positions(np.arange(200.0), 50 * np.c_[np.cos(angle), np.sin(angle)])
        >>> rounds = FleetRounds(FleetRule("closest-first", 30, 10.0, on="estimate", rounds=3),
        ...                      seed=0)
        >>> a, i, b, j = rounds.choose([lap, lap])          # two sessions in one frame
        >>> len(a), rounds.round, bool((a != b).any())
        (10, 1, True)
        >>> a, i, b, j = rounds.choose([lap, lap], frames=[0, 1])   # in frames of their own
        >>> bool((a == b).all())
        True
        >>> rounds.update([lap, lap], [lap, lap])           # nothing moved: gamma back to 10 m
        >>> rounds.gamma_inflation
        1.0
    """

    rule: FleetRule

    def __init__(self, rule: FleetRule, *, seed: int) -> None:
        super().__init__(rule, seed=seed)
        self._sizes: list[int] | None = None

    def _sessions(self, kind: str, estimates: _Estimates) -> dict[str, Poses]:
        """``estimates`` checked against the sessions of the first round (their number and
        sizes): a one-line error naming the first session that differs."""
        items = _session_list(kind, estimates)
        sizes = [len(p) for _, p in items]
        if self._sizes is None:
            self._sizes = sizes
        for k in range(max(len(sizes), len(self._sizes))):
            if k >= len(sizes) or k >= len(self._sizes):
                raise InvalidParameterError(
                    f"{kind}: {len(sizes)} sessions, the rounds began with {len(self._sizes)} "
                    f"(session {k} is {'missing' if k >= len(sizes) else 'new'})"
                )
            if sizes[k] != self._sizes[k]:
                raise InvalidParameterError(
                    f"{kind}: session {k} has {sizes[k]} poses, the rounds began with "
                    f"{self._sizes[k]}"
                )
        return dict(items)

    def choose(
        self, estimates: _Estimates, *, frames: Sequence[int] | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The next round's pairs ``(session_a, i, session_b, j)`` -- pose i of the
        session_a-th session and pose j of the session_b-th, session_a <= session_b and i < j
        within a session -- chosen on ``estimates`` (per session, in the order of the first
        round, a :class:`Poses`, or an array of its matrices ``(n, 3, 3)`` / ``(n, 4, 4)`` or
        of its positions ``(n, 2)``, on a clock of a pose a second), none of them chosen
        before; empty once :attr:`done`.

        ``frames``: a label per session; only sessions of equal labels (one frame) have pairs
        between them. Default: all in one frame.

        Raises:
            InvalidParameterError: no session, an empty session, sessions of another number or
                size than the first round's, ``frames`` of another length (each naming the
                session index).
        """
        sessions = self._sessions("FleetRounds.choose", estimates)
        if frames is not None and len(frames) != len(sessions):
            raise InvalidParameterError(
                f"FleetRounds.choose: {len(frames)} frames for {len(sessions)} sessions "
                f"(session {min(len(frames), len(sessions))} has "
                f"{'none' if len(frames) < len(sessions) else 'no estimate'})"
            )
        empty = np.zeros(0, np.int64)
        if self.done:
            return empty, empty, empty, empty
        share, seed = self._next_round()
        ask = dataclasses.replace(self.rule, budget=share + self.tried, rounds=1)
        i, j = choose_fleet_candidates(
            sessions, ask, seed=seed, gamma_inflation=self.gamma_inflation, frames=frames
        )
        starts = _starts(list(sessions.items()))
        a = np.searchsorted(starts, i, side="right") - 1
        b = np.searchsorted(starts, j, side="right") - 1
        i, j = i - starts[a], j - starts[b]
        pairs = list(zip(a.tolist(), i.tolist(), b.tolist(), j.tolist(), strict=True))
        keep = self._keep(pairs, share, seed)
        return a[keep], i[keep], b[keep], j[keep]

    def update(self, before: _Estimates, after: _Estimates) -> None:
        """Tells the rounds how the last optimisation moved the estimates (``before`` to
        ``after``, the same sessions and poses): the next round's gamma inflation.

        Raises:
            InvalidParameterError: as :meth:`choose`, for either.
        """
        old = self._sessions("FleetRounds.update", before)
        new = self._sessions("FleetRounds.update", after)
        moved = [
            np.linalg.norm(q.positions - p.positions, axis=1)
            for p, q in zip(old.values(), new.values(), strict=True)
        ]
        self._settle(np.concatenate(moved))


# ---------------------------------------------------------------------------------------------
# The back end
# ---------------------------------------------------------------------------------------------


def _rotation_angle(r: np.ndarray) -> np.ndarray:
    """The angle of rotation matrices (..., d, d), radians."""
    if r.shape[-1] == 2:
        return np.abs(np.arctan2(r[..., 1, 0], r[..., 0, 0]))
    cos = (np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.arccos(np.clip(cos, -1.0, 1.0))


def place_sessions(
    estimates: Sequence[Poses],
    matches: Matches | None,
    *,
    anchor: int = 0,
    tolerance_m: float = 10.0,
    tolerance_rad: float = 0.2,
) -> tuple[list[np.ndarray], list[bool]]:
    """The initial guess of a multi-session pose graph: per session, the rigid motion ``O``
    (world from its own frame) that places its estimate, ``O @ estimate``, and whether a match
    placed it.

    The anchor stays where it is (``O`` = identity). Then, again and again, the unplaced
    session with the most matches to the placed ones is placed: every such match proposes
    ``O_b = O_a E_a[i] T E_b[j]^-1`` (E the estimates, T the measured pose of j in the frame of
    i), and the proposal that the most others agree with -- they move the session's centroid
    by less than ``tolerance_m`` and turn it by less than ``tolerance_rad`` -- is taken, so that
    a few wrong matches do not decide. A session with no match to a placed one keeps its own
    frame (identity). ``matches`` are in fleet indices (the estimates one after another).
    """
    n = len(estimates)
    offsets = [np.eye(estimates[0].dim + 1) for _ in range(n)]
    placed = [False] * n
    placed[anchor] = True
    if matches is None or len(matches) == 0 or n == 1:
        return offsets, placed
    starts = np.r_[0, np.cumsum([len(e) for e in estimates])]
    session_i = np.searchsorted(starts, matches.i, side="right") - 1
    session_j = np.searchsorted(starts, matches.j, side="right") - 1
    d = estimates[0].dim
    while True:
        best: tuple[int, list[np.ndarray]] | None = None
        for b in range(n):
            if placed[b]:
                continue
            proposals = []
            for k in np.flatnonzero(
                ((session_j == b) & np.isin(session_i, np.flatnonzero(placed)))
                | ((session_i == b) & np.isin(session_j, np.flatnonzero(placed)))
            ):
                si, sj = int(session_i[k]), int(session_j[k])
                ei = estimates[si].matrices[matches.i[k] - starts[si]]
                ej = estimates[sj].matrices[matches.j[k] - starts[sj]]
                t = matches.relative[k]
                if sj == b:  # pose j of session b in the frame of placed pose i
                    proposals.append(offsets[si] @ ei @ t @ rigid_inverse(ej))
                else:  # pose i of session b: the inverse measurement
                    proposals.append(offsets[sj] @ ej @ rigid_inverse(t) @ rigid_inverse(ei))
            if proposals and (best is None or len(proposals) > len(best[1])):
                best = (b, proposals)
        if best is None:
            return offsets, placed
        b, proposals = best
        stack = np.asarray(proposals)
        centroid = np.r_[estimates[b].positions.mean(axis=0), 1.0]
        moved = stack @ centroid
        shift = np.linalg.norm(moved[:, None, :d] - moved[None, :, :d], axis=-1)
        turn = _rotation_angle(np.swapaxes(stack[:, None, :d, :d], -1, -2) @ stack[None, :, :d, :d])
        support = ((shift < tolerance_m) & (turn < tolerance_rad)).sum(axis=1)
        offsets[b] = stack[int(np.argmax(support))]
        placed[b] = True


def optimize_fleet(
    odometries: Sequence[Odometry],
    matches: Matches | None = None,
    backend: BackEnd | None = None,
    *,
    anchor: int = 0,
    start_sigma_m: float = 1000.0,
    start_sigma_rad: float = math.pi,
    known_starts: bool = False,
) -> list[Poses]:
    """The multi-session pose graph of ``odometries`` (one per session) and ``matches`` (in
    fleet indices: the sessions' poses one after another) optimised by ``backend`` (GTSAM).

    Pose j of the s-th session is :func:`session_key` (s, j). The anchor's first pose has a
    tight prior at its odometry's start (the map's frame); every other session's first pose a
    weak one (``start_sigma_m`` per axis, ``start_sigma_rad``) at its initial guess, which
    :func:`place_sessions` makes from the matches. With ``known_starts`` every session's start
    is known (its odometry's start, in the map's frame, as with a fix at the start): each first
    pose has the anchor's tight prior at it, and the initial guess is the estimates as they are
    (no match moves a session, so wrong matches between sessions cannot displace one). Odometry
    factors are Gaussian; the loop factors -- within and between sessions -- take the back
    end's robust kernel (GNC: odometry and priors known to be right).

    Returns:
        the optimised poses of each session, in order.

    Raises:
        ImportError: GTSAM is not installed (``pip install '.[maps]'`` in a checkout).
        InvalidParameterError: no session, sessions of different dimensions, more than 52
            sessions, an anchor out of range.
    """
    gtsam = import_gtsam()
    backend = backend or BackEnd()
    if not odometries:
        raise InvalidParameterError("optimize_fleet: no session")
    dim = odometries[0].dim
    if any(o.dim != dim for o in odometries):
        raise InvalidParameterError("optimize_fleet: sessions of different dimensions")
    if not 0 <= anchor < len(odometries):
        raise InvalidParameterError(
            f"optimize_fleet: anchor {anchor} out of range ({len(odometries)} sessions)"
        )
    between = gtsam.BetweenFactorPose2 if dim == 2 else gtsam.BetweenFactorPose3
    prior = gtsam.PriorFactorPose2 if dim == 2 else gtsam.PriorFactorPose3
    estimates = [o.estimate for o in odometries]
    if known_starts:
        offsets = [np.eye(dim + 1) for _ in estimates]
    else:
        offsets, _ = place_sessions(estimates, matches, anchor=anchor)
    graph = gtsam.NonlinearFactorGraph()
    initial = gtsam.Values()
    starts = np.r_[0, np.cumsum([len(e) for e in estimates])]
    keys: list[int] = []
    for s, (odometry, estimate) in enumerate(zip(odometries, estimates, strict=True)):
        session_keys = [session_key(s, k) for k in range(len(estimate))]
        keys.extend(session_keys)
        guess = offsets[s] @ estimate.matrices
        if s == anchor or known_starts:
            noise = noise_model(gtsam, dim, 1e-4, 1e-5)
            graph.add(prior(session_keys[0], pose_value(gtsam, odometry.start), noise))
        else:
            noise = noise_model(gtsam, dim, start_sigma_m, start_sigma_rad)
            graph.add(prior(session_keys[0], pose_value(gtsam, guess[0]), noise))
        for k, step in enumerate(odometry.steps):
            noise = noise_model(
                gtsam, dim, odometry.translation_sigma_m[k], odometry.rotation_sigma_rad[k]
            )
            graph.add(between(session_keys[k], session_keys[k + 1], pose_value(gtsam, step), noise))
        for key, m in zip(session_keys, guess, strict=True):
            initial.insert(key, pose_value(gtsam, m))
    if matches is not None and len(matches):
        if matches.i.max(initial=0) >= starts[-1] or matches.j.max(initial=0) >= starts[-1]:
            raise InvalidParameterError(
                f"optimize_fleet: a match past the last pose ({starts[-1]} poses in all)"
            )
    matrices = solve_graph(gtsam, graph, initial, backend, dim, matches, keys)
    return [
        Poses(odometry.timestamps, matrices[starts[s] : starts[s + 1]])
        for s, odometry in enumerate(odometries)
    ]


# ---------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FleetErrors:
    """The errors of a fleet's estimate against its references.

    Attributes:
        ate_m: the joint ATE: the RMSE of the translation errors of every pose of every session
            after one rigid alignment of all of them together (Umeyama, no scale): the map.
        session_ate_m: per session, its ATE after its own alignment: its shape alone.
        inter_m: the inter-session relative error: the RMSE, over the pose pairs of
            :attr:`inter_pairs`, of the translation of ``(Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` (Q
            references, P estimates), evo's RPE across two sessions; NaN without such pairs.
        inter_pairs: how many pairs: for every two sessions a < b, every pose of a whose
            nearest pose of b lies within ``overlap_m`` in the references, with that pose.
    """

    ate_m: float
    session_ate_m: dict[str, float]
    inter_m: float
    inter_pairs: int

    @property
    def session_rms_m(self) -> float:
        """The sessions' own ATEs pooled: their root mean square over the sessions."""
        v = np.array(list(self.session_ate_m.values()))
        return float(np.sqrt(np.mean(v**2)))


def _inter_pairs(
    items: Sequence[tuple[str, Poses]], overlap_m: float
) -> tuple[np.ndarray, np.ndarray]:
    starts = _starts(items)
    ii: list[np.ndarray] = []
    jj: list[np.ndarray] = []
    for a in range(len(items)):
        pa = items[a][1].positions
        for b in range(a + 1, len(items)):
            pb = items[b][1].positions
            lo, hi = pb.min(axis=0) - overlap_m, pb.max(axis=0) + overlap_m
            near_box = np.flatnonzero(((pa >= lo) & (pa <= hi)).all(axis=1))
            for chunk in np.array_split(near_box, max(1, len(near_box) // 512)):
                if len(chunk) == 0:
                    continue
                d2 = ((pa[chunk, None, :] - pb[None, :, :]) ** 2).sum(axis=-1)
                nearest = d2.argmin(axis=1)
                keep = d2[np.arange(len(chunk)), nearest] <= overlap_m**2
                ii.append(starts[a] + chunk[keep])
                jj.append(starts[b] + nearest[keep])
    if not ii:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(ii).astype(np.int64), np.concatenate(jj).astype(np.int64)


def fleet_errors(
    references: Sessions,
    estimates: Mapping[str, Poses] | Sequence[Poses],
    *,
    overlap_m: float,
    pairs: tuple[np.ndarray, np.ndarray] | None = None,
) -> FleetErrors:
    """The joint ATE, each session's ATE and the inter-session relative error (see
    :class:`FleetErrors`) of ``estimates`` (one per session, in the order of ``references``)
    against ``references``. ``pairs``: the inter-session pairs in fleet indices, when already
    found for these references and ``overlap_m``."""
    items = _checked(references)
    est = list(estimates.values()) if isinstance(estimates, Mapping) else list(estimates)
    if len(est) != len(items):
        raise InvalidParameterError(f"fleet_errors: {len(est)} estimates for {len(items)} sessions")
    per = {
        n: float(np.sqrt(np.mean(ape_errors(p, e) ** 2)))
        for (n, p), e in zip(items, est, strict=True)
    }
    ref_joint = _joint(items)
    est_joint = Poses(ref_joint.timestamps, np.concatenate([e.matrices for e in est]))
    joint = float(np.sqrt(np.mean(ape_errors(ref_joint, est_joint) ** 2)))
    i, j = pairs if pairs is not None else _inter_pairs(items, overlap_m)
    if len(i):
        e = rigid_inverse(ref_joint.relative(i, j)) @ est_joint.relative(i, j)
        d = ref_joint.dim
        inter = float(np.sqrt(np.mean(np.linalg.norm(e[:, :d, d], axis=1) ** 2)))
    else:
        inter = math.nan
    return FleetErrors(joint, per, inter, len(i))


# ---------------------------------------------------------------------------------------------
# The evaluation
# ---------------------------------------------------------------------------------------------

#: Columns of :class:`FleetResults`, in order.
FLEET_COLUMNS: tuple[str, ...] = (
    "dataset",
    "sampler",
    "between_only",
    "separation",
    "starts",
    "on",
    "rounds",
    "outlier_rate",
    "budget",
    "seed",
    "candidates",
    "between_candidates",
    "matches",
    "between_matches",
    "wrong",
    "placed",
    "ate_m",
    "session_ate_m",
    "inter_m",
    "odometry_ate_m",
    "odometry_inter_m",
    "seconds",
)

#: Columns of :attr:`FleetResults.sessions`, in order.
SESSION_COLUMNS: tuple[str, ...] = ("run", "session", "poses", "ate_m")


@dataclass
class FleetResults:
    """Rows of a fleet evaluation, one per run, and per run and session.

    Columns (:data:`FLEET_COLUMNS`): ``dataset``; ``sampler`` (``"odometry"`` for the odometry
    alone); ``between_only`` and ``separation`` (bool); ``starts`` (``unknown``: only the
    anchor's, or ``known``: every session's); ``on`` (``reference`` / ``estimate``, empty for
    the odometry alone); ``rounds`` (the candidates' rounds, 0 for the odometry alone);
    ``outlier_rate``; ``budget``; ``seed``;
    ``candidates`` and ``between_candidates`` (pairs the sampler returned, of them between two
    sessions); ``matches`` and ``between_matches`` (accepted by the verifier); ``wrong`` (of the
    matches); ``placed`` (sessions that matches placed in the initial guess, the anchor
    included); ``ate_m`` (joint ATE); ``session_ate_m`` (the sessions' own ATEs, RMS over the
    sessions); ``inter_m`` (the inter-session relative error); ``odometry_ate_m`` and
    ``odometry_inter_m`` (the same seed's odometry alone); ``seconds``.

    :attr:`sessions` has a row per run and session (:data:`SESSION_COLUMNS`): ``run`` (the row's
    index in :attr:`rows`), ``session``, ``poses``, ``ate_m`` (its own ATE).
    """

    rows: list[dict[str, Any]] = field(default_factory=list)
    sessions: list[dict[str, Any]] = field(default_factory=list)
    settings: dict[str, Any] = field(default_factory=dict)

    def table(self) -> Table:
        """The rows as an :class:`~inexact_loops.Table` of numpy columns."""
        return Table({c: np.asarray([r[c] for r in self.rows]) for c in FLEET_COLUMNS})

    def summary(self) -> list[dict[str, Any]]:
        """Per (dataset, sampler, between_only, separation, starts, on, rounds, outlier_rate,
        budget): the number of
        seeds, the median joint ATE with its spread (quartiles, min, max), the median
        inter-session error with its quartiles, the median of the sessions' own ATEs, and the
        median candidates and matches (all and between sessions)."""
        keys = FLEET_COLUMNS[: FLEET_COLUMNS.index("budget") + 1]
        out = []
        for group, rows in summary_groups(self.rows, keys):
            inter = np.array([r["inter_m"] for r in rows])
            finite = inter[np.isfinite(inter)]
            q = {
                p: float(np.quantile(finite, p)) if finite.size else math.nan
                for p in (0.25, 0.5, 0.75)
            }
            out.append(
                group
                | {
                    "inter_median_m": q[0.5],
                    "inter_q25_m": q[0.25],
                    "inter_q75_m": q[0.75],
                    "session_ate_median_m": float(np.median([r["session_ate_m"] for r in rows])),
                }
                | medians(
                    rows,
                    (
                        "candidates",
                        "between_candidates",
                        "matches",
                        "between_matches",
                        "wrong",
                        "odometry_ate_m",
                    ),
                )
            )
        return out

    def to_csv(
        self, path: str | PathLike[str], sessions_path: str | PathLike[str] | None = None
    ) -> None:
        """Writes the rows as CSV (a header of :data:`FLEET_COLUMNS`), and the per-session rows
        to ``sessions_path`` when given."""
        write_csv(path, FLEET_COLUMNS, self.rows)
        if sessions_path is not None:
            write_csv(sessions_path, SESSION_COLUMNS, self.sessions)

    def to_json(self, path: str | PathLike[str]) -> None:
        """Writes ``{"settings", "summary", "rows", "sessions"}`` as JSON (NaN as null)."""
        document = {
            "settings": self.settings,
            "summary": self.summary(),
            "rows": self.rows,
            "sessions": self.sessions,
        }
        with open(path, "w") as f:
            json.dump(_nan_to_none(document), f, indent=1, default=json_default)
            f.write("\n")

    @classmethod
    def from_csv(cls, path: str | PathLike[str]) -> FleetResults:
        """Reads rows written by :meth:`to_csv` (not the per-session rows)."""
        ints = {"budget", "seed", "candidates", "between_candidates", "matches", "rounds"}
        ints |= {"between_matches", "wrong", "placed"}
        bools = {"between_only", "separation"}
        floats = set(FLEET_COLUMNS) - ints - bools - {"dataset", "sampler", "starts", "on"}
        return cls(read_csv(path, FLEET_COLUMNS, ints=ints, floats=floats, bools=bools))

    def extend(self, other: FleetResults) -> None:
        """Adds the rows of ``other`` (its per-session rows renumbered)."""
        shift = len(self.rows)
        self.rows.extend(other.rows)
        self.sessions.extend(r | {"run": r["run"] + shift} for r in other.sessions)


def _nan_to_none(value: Any) -> Any:
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {k: _nan_to_none(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_nan_to_none(v) for v in value]
    return value


def evaluate_fleet_one(
    references: Sessions,
    odometries: Mapping[str, Odometry],
    rule: FleetRule | None,
    *,
    seed: int,
    verifier: Verifier | None = None,
    backend: BackEnd | None = None,
    anchor: str | None = None,
    loops: FleetLoops | None = None,
    known_starts: bool = False,
) -> tuple[list[Poses], Matches | None, tuple[np.ndarray, np.ndarray], int]:
    """One fleet run: candidates by ``rule`` (``None``: the odometry alone) on the references
    or the estimates, verified against the references, and the multi-session pose graph
    optimised; on the estimates in ``rule.rounds`` rounds (:class:`FleetRounds`), each verified
    and optimised before the next. There, sessions share a frame once matches placed them
    (:func:`place_sessions`), or all from the start with ``known_starts`` (the odometries start
    at the references' first poses: :func:`simulate_fleet_odometry`), where the back end holds
    every session at its start too (:func:`optimize_fleet`).

    Returns the optimised poses of each session (in the order of ``references``), the matches
    and the candidate pairs (fleet indices), and the number of sessions placed by matches (the
    anchor included).
    """
    items = _checked(references)
    names = [n for n, _ in items]
    missing = [n for n in names if n not in odometries]
    if missing:
        raise InvalidParameterError(f"evaluate_fleet_one: no odometry for session(s) {missing}")
    odos = [odometries[n] for n in names]
    for (name, poses), odometry in zip(items, odos, strict=True):
        if len(odometry.timestamps) != len(poses):
            raise InvalidParameterError(
                f"evaluate_fleet_one: session {name!r}: {len(odometry.timestamps)} odometry "
                f"poses for {len(poses)} reference poses"
            )
    a = _anchor_index(names, anchor)
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if rule is None:
        alone = optimize_fleet(odos, None, backend, anchor=a, known_starts=known_starts)
        return alone, None, empty, 1
    verifier = verifier or Verifier()
    joint = _joint(items)
    starts = _starts(items)
    if rule.on == "estimate":
        rounds = FleetRounds(rule, seed=seed)
        estimates = [o.estimate for o in odos]
        parts: list[Matches] = []
        chosen: list[tuple[np.ndarray, np.ndarray]] = []
        placed = [k == a for k in range(len(odos))]
        while not rounds.done:
            frames = None if known_starts else [0 if p else k + 1 for k, p in enumerate(placed)]
            sa, pi, sb, pj = rounds.choose(estimates, frames=frames)
            i, j = starts[sa] + pi, starts[sb] + pj
            parts.append(verifier.verify(joint, i, j, seed=seed))
            chosen.append((i, j))
            matches = _concat_matches(parts)
            _, placed = place_sessions([o.estimate for o in odos], matches, anchor=a)
            corrected = optimize_fleet(odos, matches, backend, anchor=a, known_starts=known_starts)
            rounds.update(estimates, corrected)
            estimates = corrected
        pairs = (np.concatenate([c[0] for c in chosen]), np.concatenate([c[1] for c in chosen]))
        return estimates, _concat_matches(parts), pairs, int(sum(placed))
    i, j = choose_fleet_candidates(references, rule, seed=seed, loops=loops)
    matches = verifier.verify(joint, i, j, seed=seed)
    _, placed = place_sessions([o.estimate for o in odos], matches, anchor=a)
    estimates = optimize_fleet(odos, matches, backend, anchor=a, known_starts=known_starts)
    return estimates, matches, (i, j), int(sum(placed))


def _fleet_grid(
    outlier_rates: Sequence[float],
    on: Sequence[Literal["reference", "estimate"]],
    separations: Sequence[bool],
    between_only: Sequence[bool],
    samplers: Sequence[str],
    budgets: Sequence[int],
    gamma: float,
    rounds: int,
    gamma_inflation: float,
) -> Iterable[tuple[float, FleetRule]]:
    for outlier_rate in outlier_rates:
        for where in on:
            for separation in separations:
                for between in between_only:
                    for name in samplers:
                        if between and name in BASELINES:
                            continue
                        for budget in budgets:
                            yield (
                                outlier_rate,
                                FleetRule(
                                    name,
                                    int(budget),
                                    gamma,
                                    bool(separation),
                                    bool(between),
                                    on=where,
                                    gamma_inflation=gamma_inflation,
                                    rounds=rounds if where == "estimate" else 1,
                                ),
                            )


def evaluate_fleet(
    references: Fleet | Mapping[str, Poses],
    *,
    gamma: float,
    odometry: Mapping[str, Odometry] | DriftModel | None = None,
    samplers: Sequence[str] = SAMPLERS,
    budgets: Sequence[int] = (100, 1000),
    seeds: Iterable[int] = range(5),
    between_only: Sequence[bool] = (False, True),
    separations: Sequence[bool] = (True,),
    on: Sequence[Literal["reference", "estimate"]] = ("reference",),
    rounds: int = 1,
    gamma_inflation: float = 2.0,
    known_starts: bool = False,
    outlier_rates: Sequence[float] = (0.0,),
    verifier: Verifier | None = None,
    backend: BackEnd | None = None,
    anchor: str | None = None,
    overlap_m: float | None = None,
    keyframe_m: float = 0.0,
    dataset: str = "",
    include_odometry: bool = True,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> FleetResults:
    """Runs every sampler at every budget with every seed (both with ``between_only`` and
    without, and every other option given), and the odometry alone per seed, on a fleet.

    Args:
        references: the sessions' reference poses ``{name: Poses}`` in one world frame, or an
            :class:`~inexact_loops.Fleet` (:func:`fleet_references`).
        gamma: the loops' gamma, metres.
        odometry: your odometry per session ``{name: Odometry}`` (the same for every seed; its
            starts are yours: the anchor's is the map's frame, the others' the guesses the
            weak priors hold), or a :class:`DriftModel` simulated per seed and session with
            unknown starts (:func:`simulate_fleet_odometry`; the default model when ``None``).
        samplers: names from :data:`SAMPLERS` (and :data:`BASELINES`, run without
            ``between_only`` only).
        budgets: candidates per run, over the whole fleet.
        seeds: one run per seed: the seed drives the odometry, the sampler and the verifier.
        between_only: ``False`` (one sampling over every component), ``True`` (the components
            between sessions only), or both.
        separations: the revisit separation within sessions: ``True``, ``False`` or both.
        on: ``"reference"``, ``"estimate"`` or both (:class:`FleetRule`).
        rounds, gamma_inflation: as in :class:`FleetRule` (``rounds`` for the runs on the
            estimates).
        known_starts: every session's simulated odometry starts at its reference's first pose
            (all in the map's frame; :func:`simulate_fleet_odometry`); otherwise only the
            anchor's does. Not with your own ``odometry``, whose starts are yours.
        outlier_rates: the verifier's ``outlier_rate`` values to run.
        verifier, backend: as in :func:`evaluate`.
        anchor: the session whose start is known (default: the first).
        overlap_m: the radius of the inter-session pairs of :class:`FleetErrors` (default:
            gamma).
        keyframe_m: keep a pose every this many metres of each reference
            (:meth:`Poses.keyframes`), and the same poses of a given odometry
            (:meth:`Odometry.take`); 0 keeps every pose.
        dataset: a name for the rows.
        include_odometry: add a row per seed for the odometry alone (sampler ``"odometry"``).
        progress: called with each row as it is done.

    Returns:
        :class:`FleetResults`.
    """
    full = fleet_references(references)
    keep = {n: p.keyframes(keyframe_m) for n, p in full.items()}
    refs = {n: p.take(keep[n]) for n, p in full.items()}
    items = _checked(refs)
    names = [n for n, _ in items]
    verifier = verifier or Verifier()
    backend = backend or BackEnd()
    overlap = float(gamma if overlap_m is None else overlap_m)
    drift = (
        odometry
        if isinstance(odometry, DriftModel)
        else (DriftModel() if odometry is None else None)
    )
    a = _anchor_index(names, anchor)
    if known_starts and drift is None:
        raise InvalidParameterError(
            "evaluate_fleet: known_starts simulates the odometry; a given odometry's starts "
            "are its own"
        )
    starts_label = "known" if known_starts else "unknown"
    pairs = _inter_pairs(items, overlap)
    starts = _starts(items)
    results = FleetResults(
        settings={
            "dataset": dataset,
            "sessions": {n: len(p) for n, p in items},
            "anchor": names[a],
            "dim": items[0][1].dim,
            "gamma": gamma,
            "overlap_m": overlap,
            "inter_pairs": len(pairs[0]),
            "odometry": dataclasses.asdict(drift) if drift else "given",
            "starts": starts_label,
            "gamma_inflation": gamma_inflation,
            "verifier": dataclasses.asdict(verifier),
            "backend": dataclasses.asdict(backend),
        }
    )
    loops_cache: dict[bool, FleetLoops] = {}

    def loops_for(separation: bool) -> FleetLoops:
        if separation not in loops_cache:
            loops_cache[separation] = _fleet_loops(refs, gamma, separation)
        return loops_cache[separation]

    def record(
        base: dict[str, Any],
        rule: FleetRule | None,
        outlier_rate: float,
        candidates: tuple[np.ndarray, np.ndarray],
        matches: Matches | None,
        placed: int,
        errors: FleetErrors,
        start: float,
    ) -> None:
        """Adds the row of a run (``rule`` None: the odometry alone) and its sessions' rows."""
        row = base | {
            "sampler": rule.sampler if rule else "odometry",
            "between_only": rule.between_only if rule else False,
            "separation": rule.separation if rule else False,
            "starts": starts_label,
            "on": rule.on if rule else "",
            "rounds": rule.rounds if rule else 0,
            "outlier_rate": float(outlier_rate),
            "budget": rule.budget if rule else 0,
            "candidates": len(candidates[0]),
            "between_candidates": between_count(*candidates),
            "matches": 0 if matches is None else len(matches),
            "between_matches": 0 if matches is None else between_count(matches.i, matches.j),
            "wrong": 0 if matches is None else int(matches.wrong.sum()),
            "placed": placed,
            "ate_m": errors.ate_m,
            "session_ate_m": errors.session_rms_m,
            "inter_m": errors.inter_m,
            "seconds": time.perf_counter() - start,
        }
        run = len(results.rows)
        results.rows.append(row)
        for name, poses in items:
            results.sessions.append(
                {
                    "run": run,
                    "session": name,
                    "poses": len(poses),
                    "ate_m": errors.session_ate_m[name],
                }
            )
        if progress:
            progress(row)

    def between_count(i: np.ndarray, j: np.ndarray) -> int:
        return int(
            (
                np.searchsorted(starts, i, side="right") != np.searchsorted(starts, j, side="right")
            ).sum()
        )

    for seed in seeds:
        if drift is not None:
            odos = simulate_fleet_odometry(
                refs, seed=int(seed), drift=drift, anchor=names[a], known_starts=known_starts
            )
        else:
            assert isinstance(odometry, Mapping)
            odos = dict(odometry)
            if keyframe_m > 0:
                odos = {n: o.take(keep[n]) if n in keep else o for n, o in odos.items()}
        start = time.perf_counter()
        alone, _, _, _ = evaluate_fleet_one(
            refs,
            odos,
            None,
            seed=int(seed),
            backend=backend,
            anchor=names[a],
            known_starts=known_starts,
        )
        odo_errors = fleet_errors(refs, alone, overlap_m=overlap, pairs=pairs)
        base = {
            "dataset": dataset,
            "seed": int(seed),
            "odometry_ate_m": odo_errors.ate_m,
            "odometry_inter_m": odo_errors.inter_m,
        }
        if include_odometry:
            empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
            record(base, None, 0.0, empty, None, 1, odo_errors, start)
        for outlier_rate, rule in _fleet_grid(
            outlier_rates,
            on,
            separations,
            between_only,
            samplers,
            budgets,
            gamma,
            rounds,
            gamma_inflation,
        ):
            start = time.perf_counter()
            estimates, matches, (i, j), placed = evaluate_fleet_one(
                refs,
                odos,
                rule,
                seed=int(seed),
                verifier=dataclasses.replace(verifier, outlier_rate=outlier_rate),
                backend=backend,
                anchor=names[a],
                loops=loops_for(rule.separation) if rule.on == "reference" else None,
                known_starts=known_starts,
            )
            assert matches is not None
            errors = fleet_errors(refs, estimates, overlap_m=overlap, pairs=pairs)
            record(base, rule, outlier_rate, (i, j), matches, placed, errors, start)
    return results


# ---------------------------------------------------------------------------------------------
# The plot
# ---------------------------------------------------------------------------------------------


def plot_fleet_error_vs_matches(
    results: FleetResults,
    *,
    ax: Any = None,
    select: Mapping[str, Any] | None = None,
    metric: Literal["ate", "inter", "session_ate"] = "ate",
    title: str | None = None,
    legend: bool = True,
) -> Any:
    """The fleet's error against the number of matches (the budget, log scale), one curve per
    sampler: solid over every component, dashed between sessions only; the median over the
    seeds with a band over the middle half (joint ATE and inter-session error); the odometry
    alone as a dotted line. ``metric``: ``"ate"`` (joint ATE), ``"inter"`` (the inter-session
    relative error) or ``"session_ate"`` (the sessions' own ATEs). ``select`` keeps the rows
    whose columns have these values. Needs matplotlib.
    """
    ax, select, curves = error_curves(results, ax, select, "between_only")
    column = {"ate": "ate", "inter": "inter", "session_ate": "session_ate"}[metric]
    for (name, between), points in curves:
        x = [s["budget"] for s in points]
        y = [s[f"{column}_median_m"] for s in points]
        colour = COLOURS.get(name)
        label = sampler_symbol(name) + (" (between sessions only)" if between else "")
        ax.plot(x, y, "--" if between else "-", marker="o", ms=3, color=colour, label=label)
        if column in ("ate", "inter"):
            ax.fill_between(
                x,
                [s[f"{column}_q25_m"] for s in points],
                [s[f"{column}_q75_m"] for s in points],
                color=colour,
                alpha=0.08,
            )
    odometry_column = {"ate": "ate_m", "inter": "inter_m", "session_ate": "session_ate_m"}[metric]
    odometry = [
        r[odometry_column]
        for r in results.rows
        if r["sampler"] == "odometry"
        and ("dataset" not in select or r["dataset"] == select["dataset"])
        and np.isfinite(r[odometry_column])
    ]
    ylabel = {
        "ate": "joint ATE (m)",
        "inter": "inter-session error (m)",
        "session_ate": "session ATE (m)",
    }[metric]
    finish_axes(ax, odometry, ylabel, title, legend)
    return ax
