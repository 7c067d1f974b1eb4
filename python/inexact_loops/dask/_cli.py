"""The command line: ``loops-dask``."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .. import _console, _core
from .._core import DEFAULT_BUDGET, DEFAULT_SAMPLER, SAMPLER_NAMES
from ..errors import InvalidParameterError
from . import _settings
from ._output import path_inputs, run_fleet_dask
from ._parquet import atomic
from ._scheduling import one_line
from ._store import update_store

# ---------------------------------------------------------------------------------------------
# The command line: loops-dask
# ---------------------------------------------------------------------------------------------


def _parser() -> argparse.ArgumentParser:
    p = _console.ArgumentParser(
        prog="loops-dask",
        description=(
            "Find the loops of several pose logs as one fleet, from tiles, on this machine or "
            "on a Dask cluster (--scheduler): the components, the session-overlap matrix, "
            "samples and loop duration, written as Parquet into --out. The options are those "
            "of `loops fleet`; the Rust command has no Dask option, this one is its switch."
        ),
        epilog=(
            "examples:\n"
            "  loops-dask fleet/*.mcap --gamma 40 --out results\n"
            "  loops-dask fleet/*.mcap --gamma 40 --scheduler tcp://10.0.0.5:8786 \\\n"
            "      --out /shared/results\n"
            "  loops-dask day31/*.mcap --store /shared/city --scheduler tcp://10.0.0.5:8786\n"
            "\nIn --out: components.parquet, session_pairs.parquet, samples.parquet,\n"
            "failures.parquet (sessions left out, with their error),\n"
            "loop_duration/<session>.parquet, summary.json.\n"
            "With --store DIR instead of --out: the logs are added to (or replace sessions\n"
            "of) the fleet store in DIR: its new tiles scanned across the workers, then\n"
            "merged and written by one (see `loops fleet --store`).\n"
            "Exit code 0; 1 when a session was left out; 2 on an error."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "logs",
        nargs="*",
        metavar="LOG",
        help="the pose logs, one session each, named by the file's stem",
    )
    p.add_argument(
        "--session",
        action="append",
        default=[],
        metavar="NAME=FILE[,FILE...]",
        help="a session of several files, or a name of your choice",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a Dask scheduler (tcp://host:8786); without it: this machine, no Dask needed",
    )
    p.add_argument(
        "--format",
        help="file format (as `loops fleet`), or parquet for a pose store "
        "(t, x, y[, z][, qx, qy, qz, qw])",
    )
    p.add_argument("--topic", help="topic to read from MCAP files and bags")
    p.add_argument(
        "--time", help="time of each pose from MCAP files and bags: header, log or publish"
    )
    p.add_argument(
        "--frames", metavar="PARENT,CHILD", help="parent and child frame of a transform topic"
    )
    p.add_argument(
        "--rate-hz", type=float, help="for files without times: pose i at i / RATE_HZ seconds"
    )
    p.add_argument(
        "--axes", metavar="A,B", help="a plane of two position axes (0 = x, 1 = y, 2 = z)"
    )
    p.add_argument(
        "--drop-duplicate-stamps",
        action="store_true",
        help="drop poses whose timestamp repeats the one before",
    )
    p.add_argument(
        "--quaternion-tolerance",
        type=float,
        metavar="TOLERANCE",
        help="how far from unit length a quaternion may be",
    )
    p.add_argument(
        "--gamma",
        type=float,
        help="the distance threshold γ, in the metric's unit (with --store: only to make it)",
    )
    p.add_argument("--metric", help="the metric (as `loops fleet`); default: the sessions' own")
    p.add_argument(
        "--separation-path",
        type=float,
        metavar="LENGTH",
        help="revisits only: pairs at least this path length apart [default: 4 x gamma]",
    )
    p.add_argument(
        "--separation-time",
        type=float,
        metavar="SECONDS",
        help="revisits only: pairs at least this many seconds apart [default: 0]",
    )
    p.add_argument(
        "--no-separation", action="store_true", help="the paper's S_gamma: no separation"
    )
    p.add_argument(
        "--threads",
        type=int,
        help="threads of each tile's scan (default: one per core here, one per task on a cluster)",
    )
    p.add_argument(
        "--sampler",
        default=DEFAULT_SAMPLER,
        help=f"{', '.join(SAMPLER_NAMES)} [default: {DEFAULT_SAMPLER}]; none for no samples",
    )
    p.add_argument(
        "--budget",
        type=int,
        help=f"exactly this many samples [default: {DEFAULT_BUDGET} without --rate]",
    )
    p.add_argument("--rate", type=float, help="the sampler's rate instead of a budget")
    p.add_argument("--seed", type=int, default=0, help="seed of the random choices [default: 0]")
    p.add_argument(
        "--skip-trivial", action="store_true", help="leave out the trivial loop components"
    )
    p.add_argument(
        "--between-only", action="store_true", help="sample only pairs of two different sessions"
    )
    p.add_argument("--no-loop-duration", action="store_true", help="do not write loop_duration/")
    p.add_argument(
        "--block",
        type=int,
        default=None,
        help=(
            "poses per block, the side of a tile [default: the longest session, "
            f"{_settings.DEFAULT_BLOCK:,} to {_settings.MAX_AUTO_BLOCK:,}]"
        ),
    )
    p.add_argument(
        "--fan-in",
        type=int,
        default=_settings.DEFAULT_FAN_IN,
        help=f"summaries per merge task [default: {_settings.DEFAULT_FAN_IN}]",
    )
    p.add_argument("--out", metavar="DIR", help="the folder for the results")
    p.add_argument(
        "--store",
        metavar="DIR",
        help="update the fleet store in DIR instead (made by the first update, with --gamma)",
    )
    p.add_argument(
        "--remove",
        action="append",
        default=[],
        metavar="NAME",
        help="with --store: remove the stored session NAME",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="replace the results of an earlier loops-dask in --out (only what it wrote there)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    p.add_argument(
        "--json",
        metavar="FILE",
        help="also write summary.json to FILE; - prints it instead of the table",
    )
    return p


def _pair(text: str | None, what: str, kind: Callable[[str], Any]) -> Any:
    if text is None:
        return None
    parts = text.split(",")
    if len(parts) != 2:
        raise InvalidParameterError(f"--{what} {text!r}: give two values separated by a comma")
    return tuple(kind(p) for p in parts)


def _separation(args: argparse.Namespace) -> Any:
    if args.no_separation:
        return None
    if args.separation_path is not None or args.separation_time is not None:
        return _core.Separation(
            path=args.separation_path or 0.0, time_s=args.separation_time or 0.0
        )
    return "auto"


def _client(args: argparse.Namespace) -> Any:
    """The client of ``--scheduler``, or ``None``."""
    if not args.scheduler:
        return None
    try:
        from distributed import Client  # type: ignore[import-untyped, import-not-found, unused-ignore]
    except ImportError as error:
        raise InvalidParameterError(
            f"--scheduler needs dask.distributed: pip install '.[dask]' in a checkout ({error})"
        ) from None
    return Client(args.scheduler)


def _update_store(args: argparse.Namespace, sessions: dict[str, Any]) -> int:
    """``--store DIR``: the update of the store, on a worker of ``--scheduler`` or here."""
    if args.out is not None:
        raise InvalidParameterError("--store and --out: give one")
    if not sessions and not args.remove:
        raise InvalidParameterError("no sessions: give LOG files, --session NAME=FILE or --remove")
    # The settings go only with --gamma: a store keeps those it was made with.
    settings: dict[str, Any] = {}
    if args.gamma is not None:
        sampler = None if args.sampler == "none" else args.sampler
        settings = {
            "gamma": args.gamma,
            "metric": args.metric,
            "separation": _separation(args),
            "block": args.block,
            "sampler": sampler,
        }
        if sampler is not None:
            settings.update(
                budget=args.budget,
                rate=args.rate,
                seed=args.seed,
                skip_trivial=args.skip_trivial,
                between_only=args.between_only,
            )
    read = {
        "format": args.format,
        "axes": _pair(args.axes, "axes", int),
        "topic": args.topic,
        "time": args.time,
        "frames": _pair(args.frames, "frames", str),
        "rate_hz": args.rate_hz,
        "drop_duplicate_stamps": args.drop_duplicate_stamps,
        "quaternion_tolerance": args.quaternion_tolerance,
    }
    client = _client(args)
    try:
        summary = update_store(
            args.store,
            add=sessions or None,
            remove=args.remove or None,
            client=client,
            threads=args.threads,
            **settings,
            **read,
        )
    finally:
        if client is not None:
            client.close()
    text = json.dumps(summary, indent=2, default=float)
    if args.json == "-":
        print(text)
    elif args.json:
        atomic(Path(args.json), lambda tmp: Path(tmp).write_text(text + "\n"))
    if not args.quiet and args.json != "-":
        u = summary["last_update"]
        where = args.scheduler or "this machine"
        if not u["changed"]:
            print(
                f"loops-dask: store {args.store}: nothing changed, nothing written: "
                f"{len(u['unchanged'])} stored as given; {len(summary['names'])} sessions, "
                f"{summary['components']} components"
            )
            return 0
        print(
            f"loops-dask: store {args.store}: {len(u['added'])} added, {len(u['replaced'])} "
            f"replaced, {len(u['removed'])} removed; {u['tiles_scanned']} tiles scanned, "
            f"{u['tiles_kept']} kept on {where}; {summary['components']} components "
            f"({summary['added_components']} of the changed sessions)"
        )
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """The command ``loops-dask`` (``[project.scripts]``): ``loops fleet``'s options plus
    ``--scheduler ADDRESS``. Returns the exit code: 0, 1 when a session was left out, 2 on an
    error."""
    args = _parser().parse_intermixed_args(argv)
    try:
        sessions: dict[str, Any] = {}
        for log in args.logs:
            name = _core.log_name(log)
            if name in sessions:
                raise InvalidParameterError(
                    f"{sessions[name]} and {log} are both named {name!r} by their file stem: "
                    "use --session NAME=FILE to name them"
                )
            sessions[name] = log
        for spec in args.session:
            name, eq, files = spec.partition("=")
            if not eq or not name or not files:
                raise InvalidParameterError(f"--session {spec!r}: give NAME=FILE[,FILE...]")
            if name in sessions:
                raise InvalidParameterError(f"two sessions are named {name!r}")
            parts = files.split(",")
            sessions[name] = parts[0] if len(parts) == 1 else parts
        if args.store is not None:
            return _update_store(args, sessions)
        if args.out is None or args.gamma is None:
            raise InvalidParameterError("give --out DIR and --gamma (or --store DIR)")
        if args.remove:
            raise InvalidParameterError("--remove goes with --store")
        if not sessions:
            raise InvalidParameterError("no sessions: give LOG files or --session NAME=FILE")
        separation = _separation(args)
        sampler = None if args.sampler == "none" else args.sampler
        if args.json and args.json != "-":
            _core.refuse_output_on_input("--json", Path(args.json), path_inputs(sessions))
            if os.path.lexists(args.json) and not args.force:
                raise InvalidParameterError(
                    f"--json {args.json} exists; pass --force to replace it"
                )
        client = _client(args)
        try:
            summary = run_fleet_dask(
                sessions,
                args.gamma,
                out=args.out,
                force=args.force,
                sampler=sampler,
                rate=args.rate,
                budget=args.budget,
                seed=args.seed,
                between_only=args.between_only,
                skip_trivial=args.skip_trivial,
                loop_duration=not args.no_loop_duration,
                client=client,
                block=args.block,
                fan_in=args.fan_in,
                separation=separation,
                metric=args.metric,
                threads=args.threads,
                format=args.format,
                axes=_pair(args.axes, "axes", int),
                topic=args.topic,
                time=args.time,
                frames=_pair(args.frames, "frames", str),
                rate_hz=args.rate_hz,
                drop_duplicate_stamps=args.drop_duplicate_stamps,
                quaternion_tolerance=args.quaternion_tolerance,
            )
        finally:
            if client is not None:
                client.close()
    except (OSError, ValueError, TypeError, ImportError, MemoryError) as error:
        print(f"loops-dask: error: {one_line(error).split(': ', 1)[-1]}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _console.interrupted("loops-dask")
    text = json.dumps(summary, indent=2, default=float)
    if args.json == "-":
        print(text)
    elif args.json:
        atomic(Path(args.json), lambda tmp: Path(tmp).write_text(text + "\n"))
    for f in summary["failures"]:
        print(
            f"loops-dask: session {f['session']} ({f['source']}) left out: {f['error']}",
            file=sys.stderr,
        )
    if not args.quiet and args.json != "-":
        where = args.scheduler or "this machine"
        stats = summary["stats"]
        print(
            f"loops-dask: {len(summary['sessions'])} session(s), {stats['poses']} poses, "
            f"{stats['tiles']} tiles of {stats['block']} poses on {where}: "
            f"{summary['components']} components "
            f"({summary['between_sessions']} between sessions), "
            f"{summary['samples'] if summary['samples'] is not None else 'no'} samples; "
            f"results in {args.out} ({stats['total_s']:.1f} s)"
        )
    return 1 if summary["failures"] else 0
