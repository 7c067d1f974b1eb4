"""The evaluation: the grid of samplers x budgets x seeds x options, and its results table."""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Literal

import numpy as np

from ..errors import InvalidParameterError
from ..table import Table
from ._backend import BackEnd, optimize
from ._candidates import (
    BASELINES,
    SAMPLERS,
    CandidateRule,
    Rounds,
    _concat_matches,
    choose_candidates,
)
from ._metrics import ate, rpe
from ._odometry import DriftModel, Odometry
from ._poses import Poses
from ._verifier import VERIFIER_MODELS, Matches, Verifier, name_of_verifier

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
        keys = COLUMNS[: COLUMNS.index("budget") + 1]  # a run's conditions: dataset ... budget
        return [
            group
            | {"rpe_median_m": float(np.median([r["rpe_m"] for r in rows]))}
            | medians(rows, ("candidates", "matches", "wrong", "odometry_ate_m"))
            for group, rows in summary_groups(self.rows, keys)
        ]

    def to_csv(self, path: str | PathLike[str]) -> None:
        """Writes the rows as CSV (a header of :data:`COLUMNS`)."""
        write_csv(path, COLUMNS, self.rows)

    def to_json(self, path: str | PathLike[str]) -> None:
        """Writes ``{"settings", "summary", "rows"}`` as JSON."""
        document = {"settings": self.settings, "summary": self.summary(), "rows": self.rows}
        with open(path, "w") as f:
            json.dump(document, f, indent=1, default=json_default)
            f.write("\n")

    @classmethod
    def from_csv(cls, path: str | PathLike[str]) -> Results:
        """Reads rows written by :meth:`to_csv`."""
        ints = {"budget", "seed", "candidates", "matches", "wrong", "rounds"}
        floats = {"outlier_rate", "ate_m", "rpe_m", "odometry_ate_m", "seconds"}
        return cls(read_csv(path, COLUMNS, ints=ints, floats=floats, bools={"separation"}))

    def extend(self, other: Results) -> None:
        """Adds the rows of ``other``."""
        self.rows.extend(other.rows)


def summary_groups(
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


def medians(rows: Sequence[dict[str, Any]], columns: Iterable[str]) -> dict[str, float]:
    """The median of each of ``columns`` over ``rows``."""
    return {c: float(np.median([r[c] for r in rows])) for c in columns}


def write_csv(
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
_MISSING: Mapping[str, str] = {
    "verifier": "distance-aware",
    "rounds": "1",
    "starts": "unknown",
    "on": "reference",
}


def read_csv(
    path: str | PathLike[str],
    columns: Sequence[str],
    *,
    ints: set[str],
    floats: set[str],
    bools: set[str],
) -> list[dict[str, Any]]:
    """The rows :func:`write_csv` wrote, ``columns`` of each: ``ints``, ``floats`` and
    ``bools`` (``"True"``) converted, the others kept as text."""
    import csv

    rows = []
    with open(path, newline="") as f:
        for raw in csv.DictReader(f):
            row: dict[str, Any] = {}
            for c in columns:
                # Files written before a column existed: its value for them.
                v = raw[c] if c in raw else _MISSING.get(c, "")
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


def json_default(value: Any) -> Any:
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
    rounds_order: Literal["any", "time"] = "any",
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
                                    rounds_order=rounds_order,
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
    rounds_order: Literal["any", "time"] = "any",
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
        gamma_inflation, rounds, rounds_order, detection_rate, epsilon_s: as in
            :class:`CandidateRule` (``rounds`` and ``rounds_order`` for the runs on the
            estimate; ``rounds_order="time"`` in rounds refuses the baselines).
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
    verifier_name = name_of_verifier(verifier)
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
            "rounds_order": rounds_order,
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

    # Every rule is made (and checked) before the first run: a bad combination is refused
    # before any work.
    grid = list(
        _grid(
            outlier_rates,
            on,
            separations,
            sources,
            samplers,
            detection_samplers,
            budgets,
            rounds,
            rounds_order,
            gamma=gamma,
            gamma_inflation=gamma_inflation,
            detection_rate=detection_rate,
            epsilon_s=epsilon_s,
        )
    )
    for seed in seeds:
        odo = drift.simulate(reference, seed=seed) if drift else odometry
        assert isinstance(odo, Odometry)
        start = time.perf_counter()
        # The pose graph of the odometry alone is solved by dead reckoning.
        odo_ate, odo_rpe = errors(odo.estimate)
        base = {"dataset": dataset, "seed": int(seed), "odometry_ate_m": odo_ate}
        if include_odometry:
            record(base, None, 0.0, 0, None, odo_ate, odo_rpe, start)
        for outlier_rate, rule in grid:
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
