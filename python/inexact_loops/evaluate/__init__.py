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
:class:`FleetRounds` (candidates in rounds on the sessions' estimates),
:func:`optimize_fleet`, :func:`fleet_errors` and :func:`plot_fleet_error_vs_matches`; its
method is in the docstring of ``inexact_loops.evaluate._fleet``.

The package's modules, each importing only those above it: ``_poses`` (rigid motions,
:class:`Poses`), ``_odometry``, ``_verifier``, ``_candidates``, ``_backend``, ``_metrics``,
``_grid`` (:func:`evaluate`, :class:`Results`), ``_plot``, ``_fleet`` and ``_cli``
(``loops-eval``). Every name is served from this package, where pickles find it too.

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

from ._backend import BackEnd, optimize
from ._candidates import BASELINES, SAMPLERS, CandidateRule, Rounds, choose_candidates
from ._cli import main as main
from ._fleet import (
    FLEET_COLUMNS,
    SESSION_COLUMNS,
    FleetErrors,
    FleetResults,
    FleetRounds,
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
from ._fleet import (
    Sessions as Sessions,
)
from ._grid import COLUMNS as COLUMNS
from ._grid import Results, evaluate, evaluate_one
from ._metrics import ape_errors, ate, rpe, rpe_errors, umeyama
from ._odometry import DriftModel, Odometry
from ._plot import COLOURS as COLOURS
from ._plot import plot_error_vs_matches
from ._poses import Poses
from ._verifier import VERIFIER_MODELS, Matches, Verifier

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
    "FleetRounds",
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

# Served from here: pickles and Dask name the classes and functions by this module.
for _name in (*__all__, "main"):
    _obj = globals()[_name]
    if isinstance(_obj, type) or callable(_obj):
        _obj.__module__ = __name__
del _name, _obj
