"""The command line: ``loops-eval`` (and ``loops-eval --fleet``)."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, Literal

from ..errors import InvalidParameterError, LoopsError
from ._backend import BackEnd
from ._candidates import BASELINES, SAMPLERS
from ._fleet import FleetResults, evaluate_fleet, plot_fleet_error_vs_matches
from ._grid import Results, evaluate
from ._odometry import DriftModel, Odometry
from ._plot import plot_error_vs_matches
from ._poses import Poses
from ._verifier import VERIFIER_MODELS

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

    from .. import _console

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
        "--rounds-order",
        default="any",
        choices=["any", "time"],
        help="with --rounds: each round over the whole estimate (any), or round r on the r-th "
        "stretch of the path only, as an online front end (time; samplers, not baselines)",
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
        "map: each session's odometry starts in its own frame, only the anchor's start is known "
        "(every session's with --known-starts), candidates come from sample_fleet, on the "
        "references or (--on estimate, --rounds) on the sessions' estimates; it writes "
        "results.csv, sessions.csv (each session's own ATE per run), results.json and "
        "error_vs_matches.png (joint ATE and inter-session error). Not with --odometry or "
        "--source detections.",
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
        "--known-starts",
        action="store_true",
        help="every session's odometry starts at its reference's first pose (all in the map's "
        "frame); otherwise only the anchor's, and on the estimates two sessions have pairs "
        "between them only once matches placed them",
    )
    fleet.add_argument(
        "--overlap-m",
        type=float,
        help="radius of the pose pairs of the inter-session error (default: gamma)",
    )
    args = parser.parse_args(argv)
    try:
        if args.fleet:
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
        rounds_order=args.rounds_order,
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


# ---------------------------------------------------------------------------------------------
# The command line: loops-eval --fleet
# ---------------------------------------------------------------------------------------------


def _plot_fleet_panels(results: FleetResults, path: str, *, title: str) -> None:
    """:func:`plot_fleet_error_vs_matches`: a row per error (joint ATE, inter-session) and
    separation, a column per outlier rate."""

    def draw(ax: Any, row: tuple[str, bool], outlier_rate: float) -> None:
        metric, separation = row
        plot_fleet_error_vs_matches(
            results,
            ax=ax,
            metric=metric,  # type: ignore[arg-type]
            select={"separation": separation, "outlier_rate": outlier_rate},
            title=f"{title}: "
            + ("joint ATE" if metric == "ate" else "inter-session error")
            + (", revisits" if separation else ", S_gamma")
            + f", {outlier_rate:.0%} wrong matches",
        )

    _save_panels(
        results.rows,
        path,
        lambda runs: [
            (m, sep)
            for m in ("ate", "inter")
            for sep in sorted({r["separation"] for r in runs}, reverse=True)
        ],
        draw,
    )


def _session_sources(paths: Sequence[str]) -> list[tuple[str, str]]:

    out: list[tuple[str, str]] = []
    for text in paths:
        name, sep, path = text.partition("=")
        if not sep or os.path.exists(text):
            name, path = os.path.splitext(os.path.basename(text))[0], text
        if any(n == name for n, _ in out):
            raise InvalidParameterError(
                f"two sessions are named {name!r}: name them with NAME=FILE"
            )
        out.append((name, path))
    return out


def main_fleet(args: Any) -> None:
    """``loops-eval --fleet``: :func:`evaluate_fleet` on the pose files given, one a session
    (``args`` parsed by :func:`inexact_loops.evaluate.main`, which reports the errors)."""

    def both(value: str) -> list[bool]:
        return [False, True] if value == "both" else [value == "on"]

    if len(args.poses) < 2:
        raise InvalidParameterError(
            f"--fleet needs the pose files of at least two sessions, got {len(args.poses)}: "
            "without --fleet, loops-eval evaluates one trajectory"
        )
    if args.odometry:
        raise InvalidParameterError("--fleet takes no --odometry: each session's is simulated")
    if args.source != "exact":
        raise InvalidParameterError(
            "--fleet chooses candidates on the exact components: not with --source detections"
        )
    if args.rounds_order != "any":
        raise InvalidParameterError(
            f"--fleet chooses each round over every session: not with --rounds-order "
            f"{args.rounds_order}"
        )
    options, axes = _read_options(args)
    dim = 3 if args.se3 else 2
    references = {
        name: Poses.read(path, dim=dim, axes=axes, **options)  # type: ignore[arg-type]
        for name, path in _session_sources(args.poses)
    }
    label = "+".join(references)
    results = evaluate_fleet(
        references,
        gamma=args.gamma,
        samplers=_csv_list(args.samplers, str),
        budgets=_csv_list(args.budgets, int),
        seeds=range(args.seeds),
        between_only=both(args.between_only),
        separations=[True, False] if args.separation == "both" else [args.separation == "on"],
        on=["reference", "estimate"] if args.on == "both" else [args.on],
        rounds=args.rounds,
        gamma_inflation=args.gamma_inflation,
        known_starts=args.known_starts,
        outlier_rates=_csv_list(args.outliers, float),
        backend=BackEnd(kernel=args.kernel),
        anchor=args.anchor,
        overlap_m=args.overlap_m,
        keyframe_m=args.keyframe_m,
        dataset=label,
        progress=lambda r: print(
            f"loops-eval: seed {r['seed']} {r['sampler']:>15} "
            f"{'between' if r['between_only'] else 'all':>7} {r['on'] or '-':>9} "
            f"budget {r['budget']:>6}: "
            f"{r['matches']:>5} matches ({r['between_matches']} between sessions, "
            f"{r['wrong']} wrong), joint ATE {r['ate_m']:.3f} m, inter {r['inter_m']:.3f} m",
            file=sys.stderr,
        ),
    )
    _write_outputs(
        args.out,
        results,
        ["results.csv", "sessions.csv"],
        lambda path: _plot_fleet_panels(results, path, title=label),
        lambda s: (
            f"{s['sampler']:>15} {'between' if s['between_only'] else 'all':>7} "
            f"on={s['on']} rounds={s['rounds']} "
            f"sep={int(s['separation'])} out={s['outlier_rate']:.2f} "
            f"budget {s['budget']:>6}: joint ATE {s['ate_median_m']:.3f} m "
            f"[{s['ate_min_m']:.3f}, {s['ate_max_m']:.3f}], "
            f"inter {s['inter_median_m']:.3f} m"
        ),
    )
