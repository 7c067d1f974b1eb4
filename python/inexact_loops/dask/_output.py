"""The output folder of a run: the tables as Parquet (:func:`run_fleet_dask`)."""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from .._core import DEFAULT_SAMPLER
from ..table import Table
from ._parquet import import_pyarrow
from ._run import clock_s, find_fleet_loops_dask
from ._scheduling import Runner
from ._tasks import session_tau, session_times

# ---------------------------------------------------------------------------------------------
# The output folder
# ---------------------------------------------------------------------------------------------

# The marker (``loops-dask.json``), the scratch folder and the files of the folder are
# loops-io's ``out_dir::DASK``, reached through :class:`_core.OutDir`.


def _write_entry(out: _core.OutDir, name: str, write: Callable[[str], None]) -> None:
    """Writes the file ``name`` of ``out`` through ``write(path)`` into the folder's scratch
    folder, then moves it into place (listed in the marker first; see :class:`_core.OutDir`)."""
    staged = out.staging_path()
    try:
        write(str(staged))
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(staged)
        raise
    out.place(staged, name)


def path_inputs(sessions: Any) -> list[str]:
    """The files and folders among ``sessions`` (a mapping or list of paths, lists of paths or
    trajectories): what the output must not be written onto."""
    values = sessions.values() if isinstance(sessions, Mapping) else sessions
    paths: list[str] = []
    for value in values:
        for item in value if isinstance(value, list | tuple) else [value]:
            if isinstance(item, str | os.PathLike):
                paths.append(os.fspath(item))
    return paths


def _write_table(out: _core.OutDir, name: str, table: Mapping[str, Any]) -> None:
    pa = import_pyarrow()
    arrow = pa.table({k: np.asarray(v) for k, v in table.items()})
    _write_entry(out, name, lambda tmp: pa.parquet.write_table(arrow, tmp))


def run_fleet_dask(
    sessions: Any,
    gamma: float,
    *,
    out: str | os.PathLike[str],
    force: bool = False,
    sampler: str | None = DEFAULT_SAMPLER,
    rate: float | None = None,
    budget: int | None = None,
    seed: int = 0,
    between_only: bool = False,
    skip_trivial: bool = False,
    loop_duration: bool = True,
    client: Any = None,
    **options: Any,
) -> dict[str, Any]:
    """:func:`find_fleet_loops_dask`, samples and tau, with the tables written as Parquet into
    the folder ``out``: ``components.parquet``, ``session_pairs.parquet``,
    ``samples.parquet`` (with a sampler), ``failures.parquet`` (the sessions left out: name,
    source, error), ``loop_duration/<session>.parquet`` (pose, t_s, own_s, other_s; written
    by the workers where the tiles' shares are, never sent to the client) and
    ``summary.json``. Each file is written to a temporary file and renamed; ``out`` is kept as
    ``loops fleet`` keeps its ``--out`` (``loops-dask.json`` lists what this tool wrote there,
    ``force`` replaces only that, one run holds the folder at a time). With ``client=``, the
    workers must reach ``out`` (a shared file system) for tau.

    Args:
        sessions, gamma, client: as :func:`find_fleet_loops_dask`; ``options`` its other
            keywords (``block``, ``separation``, ``metric``, read options, ...).
        out: the output folder (made if missing).
        force: replace what an earlier run of this tool wrote into ``out``.
        sampler, rate, budget, seed, between_only, skip_trivial: as :meth:`FleetRun.sample`
            (``sampler=None``: no samples).
        loop_duration: write tau per session.

    Returns:
        The summary (as ``summary.json``): counts, the sessions and those left out, timings,
        bytes.

    Raises:
        InvalidParameterError: ``out`` not empty without ``force``; a file in ``out`` that this
            tool did not write; ``out`` on an input (a session's file, a folder holding one);
            as :func:`find_fleet_loops_dask`.
    """
    _core.refuse_output_on_input("out", Path(out), path_inputs(sessions))
    folder = _core.OutDir(Path(out), force=force, tool="loops-dask")
    try:
        run = find_fleet_loops_dask(
            sessions, gamma, client=client, loop_duration=loop_duration, **options
        )
        components = run.components
        _write_table(folder, "components.parquet", components)
        _write_table(folder, "session_pairs.parquet", run.session_pairs())
        failures = Table()
        failures["session"] = np.array([f[0] for f in run.failures] or [], dtype=str)
        failures["source"] = np.array([f[1] for f in run.failures] or [], dtype=str)
        failures["error"] = np.array([f[2] for f in run.failures] or [], dtype=str)
        _write_table(folder, "failures.parquet", failures)
        samples = None
        if sampler is not None:
            samples = run.sample(
                sampler,
                rate=rate,
                budget=budget,
                seed=seed,
                between_only=between_only,
                skip_trivial=skip_trivial,
            )
            _write_table(folder, "samples.parquet", samples)
        else:
            folder.remove("samples.parquet")
        if loop_duration:
            started = clock_s()
            staging = folder.staging_path()
            staging.mkdir()
            c = run._context
            runner: Runner = c["runner"]
            futures = []
            for k, b in enumerate(c["blocks"]):
                source = c["sources"][k]
                t_s = runner.submit("session-times", session_times, source, c["options"])
                mine = [
                    s for s, tile in zip(c["shares"], c["tiles"], strict=True) if k in tile.sessions
                ]
                futures.append(
                    runner.submit(
                        "session-tau",
                        session_tau,
                        k,
                        c["starts"][k],
                        b.poses,
                        str(staging),
                        run.names[k],
                        t_s,
                        *mine,
                    )
                )
            runner.gather(futures)
            folder.place(staging, "loop_duration")
            run.stats["loop_duration_s"] = clock_s() - started
        else:
            folder.remove("loop_duration")
        between = int(np.sum(components["session_a"] != components["session_b"]))
        summary = {
            "gamma": gamma,
            "sessions": [
                {"name": n, "poses": int(b.poses), "span_s": float(b.span_s)}
                for n, b in zip(run.names, run._context["blocks"], strict=True)
            ],
            "failures": [{"session": n, "source": s, "error": e} for n, s, e in run.failures],
            "components": len(components["id"]),
            "between_sessions": between,
            "session_pairs": len(run.session_pairs()["components"]),
            "samples": None if samples is None else len(samples["i"]),
            "sampler": sampler,
            "stats": run.stats,
        }
        text = json.dumps(summary, indent=2, default=float) + "\n"
        _write_entry(folder, "summary.json", lambda tmp: Path(tmp).write_text(text))
        return summary
    finally:
        folder.close()
