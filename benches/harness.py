"""Shared pieces of the benchmark harnesses (``compare.py``, ``scale.py``, ``cluster_compare.py``,
``bag_compare.py``, ``mcap_compare.py``, ...).

- Worker side: the memory cap (``RLIMIT_AS``), the resident-set readings from
  ``/proc/self/status`` and the reset of the peak through ``/proc/self/clear_refs``,
  :func:`measure`, which times one call and reports its peak resident set above the baseline,
  and what the drivers compare of our result (:func:`result_facts`, :func:`reference_loops`).
- Driver side: :func:`run_process` runs one worker under a timeout and classifies how it ended
  (finished, out of memory, timed out, failed); :func:`run_worker` runs one of the calling
  script's workers so; :func:`refused` stops a report whose results differ or whose compiled
  module was rebuilt during the run (:func:`rebuild_problems`).
- The report: the machine's facts, and the marker convention of ``BENCHMARKS.md``. A line
  ``<!-- name -->`` starts the section that the script ``name`` owns, up to the next marker line
  or the end of the file. :func:`write_head` replaces the text before the first marker (the
  part ``compare.py`` owns) and :func:`write_section` the text of one marker; both keep
  everything else, re-read the file right before writing and replace it atomically.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import fcntl
import gc
import hashlib
import importlib.metadata
import json
import os
import platform
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

# Exit code of a worker that ran out of memory (a MemoryError under the address-space cap).
EXIT_OUT_OF_MEMORY = 3

#: A marker line of BENCHMARKS.md: ``<!-- name -->`` alone on its line.
MARKER = re.compile(r"^<!--\s*(.*?)\s*-->[ \t]*$", re.MULTILINE)

# Signs, in a worker's stderr, that an allocation failed under the cap (Python, C++, Rust).
OUT_OF_MEMORY_SIGNS = ("MemoryError", "bad_alloc", "memory allocation of", "Cannot allocate")


# --------------------------------------------------------------------------------------------
# Worker side.
# --------------------------------------------------------------------------------------------


def cap_address_space(limit_gb: float) -> None:
    """Caps this process's address space (``RLIMIT_AS``) at `limit_gb` GiB."""
    limit = int(limit_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def proc_status_kib() -> dict[str, int]:
    """VmRSS and VmHWM of this process, KiB."""
    status: dict[str, int] = {}
    with open("/proc/self/status") as lines:
        for line in lines:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM"):
                status[key] = int(value.split()[0])
    return status


def reset_peak_rss() -> bool:
    """Resets VmHWM to the current RSS (Linux ≥ 4.0); False where not permitted."""
    try:
        with open("/proc/self/clear_refs", "w") as clear_refs:
            clear_refs.write("5")
    except OSError:
        return False
    return True


def measure(run: Callable[[], object]) -> tuple[object, dict]:
    """Times one call of `run` and reads its peak resident set above the baseline.

    The baseline is the resident set right before the call (after a garbage collection), and
    the peak is reset to it first. Exits the process with :data:`EXIT_OUT_OF_MEMORY` after
    printing a JSON status line if the call raises ``MemoryError``.

    Returns the call's result and ``time_s``, ``cpu_s`` (user + system time of the process,
    all threads), ``peak_above_baseline_mb``, ``baseline_mb``, ``peak_mb`` (the absolute peak)
    and ``peak_reset``.
    """
    gc.collect()
    baseline = proc_status_kib()["VmRSS"]
    peak_reset = reset_peak_rss()
    try:
        cpu_start = os.times()
        start = time.perf_counter()
        result = run()
        elapsed_s = time.perf_counter() - start
        cpu_end = os.times()
    except MemoryError:
        print(json.dumps({"status": "out of memory"}), flush=True)
        sys.exit(EXIT_OUT_OF_MEMORY)
    peak = proc_status_kib()["VmHWM"]
    cpu_s = (cpu_end.user - cpu_start.user) + (cpu_end.system - cpu_start.system)
    return result, {
        "time_s": elapsed_s,
        "cpu_s": cpu_s,
        "peak_above_baseline_mb": (peak - baseline) / 1024,
        "baseline_mb": baseline / 1024,
        "peak_mb": peak / 1024,
        "peak_reset": peak_reset,
    }


def table_digest(*tables: dict) -> str:
    """A fingerprint of dicts of numpy arrays (e.g. runs and component tables)."""
    hasher = hashlib.sha256()
    for table in tables:
        for key in sorted(table):
            hasher.update(key.encode())
            hasher.update(table[key].tobytes())
    return hasher.hexdigest()


def result_facts(loops, components: dict, poses: int) -> dict:
    """What the drivers compare of our result on `poses` poses: the pairs and cells of S_γ's
    upper half, its components and the non-trivial ones, its runs, and a digest of the runs and
    the component table (the same for every thread count)."""
    runs = loops.runs()
    return {
        "pairs_upper": (loops.pair_count - poses) // 2,
        "cells_upper": (loops.pair_count + poses) // 2,
        "components": len(components["id"]),
        "nontrivial": int((~components["trivial"]).sum()),
        "runs": len(runs["row"]),
        "digest": table_digest(runs, components),
    }


def reference_loops(traj, gamma_m: float) -> tuple[object, dict, int]:
    """Our S_γ of `traj` without a separation (the paper's), its runs and its number of
    components: what a peer's partition is checked against."""
    import inexact_loops as il

    loops = il.find_loops(traj, gamma=gamma_m, separation=None)
    return loops, loops.runs(), len(loops.components["id"])


# --------------------------------------------------------------------------------------------
# Driver side.
# --------------------------------------------------------------------------------------------


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def add_contender_options(
    parser: argparse.ArgumentParser,
    *,
    repeat_help: str,
    output_help: str,
    budget_s: float | None = None,
) -> None:
    """The options every comparison driver takes: ``--repeat``, ``--timeout-s``,
    ``--mem-limit-gb``, ``--output`` and, with a default ``budget_s``, ``--budget-s``."""
    parser.add_argument("--repeat", type=_positive_int, default=3, metavar="N", help=repeat_help)
    if budget_s is not None:
        parser.add_argument(
            "--budget-s",
            type=float,
            default=budget_s,
            metavar="SECONDS",
            help=f"stop repeating a contender after this much time (default {budget_s:g})",
        )
    parser.add_argument(
        "--timeout-s",
        type=float,
        default=600.0,
        metavar="SECONDS",
        help="kill a contender after this long and record a timeout (default 600)",
    )
    parser.add_argument(
        "--mem-limit-gb",
        type=float,
        default=16.0,
        metavar="GB",
        help="address-space cap per contender (default 16)",
    )
    parser.add_argument(
        "--output", type=Path, default=REPO / "BENCHMARKS.md", metavar="PATH", help=output_help
    )


def run_process(
    command: list[str], *, timeout_s: float, mem_limit_gb: float
) -> tuple[str, dict | None, str]:
    """Runs one worker; returns (status, its JSON report or None, its stderr).

    The status is ``ok``, ``out of memory (> N GB address space)``, ``killed (SIGKILL: out of
    memory?)``, ``timeout (> N s)``, ``crashed (SIGNAME)`` or ``failed (exit status N)``. The
    worker prints its report as the last line of its stdout.
    """
    try:
        done = subprocess.run(
            command, capture_output=True, text=True, timeout=timeout_s, check=False, cwd=REPO
        )
    except subprocess.TimeoutExpired:
        return f"timeout (> {timeout_s:.0f} s)", None, ""
    lines = done.stdout.strip().splitlines()
    report = json.loads(lines[-1]) if lines and lines[-1].startswith("{") else None
    out_of_memory = f"out of memory (> {mem_limit_gb:g} GB address space)"
    if done.returncode == EXIT_OUT_OF_MEMORY:
        return out_of_memory, None, done.stderr
    if done.returncode == -9:
        return "killed (SIGKILL: out of memory?)", None, done.stderr
    if done.returncode != 0 or report is None:
        tail = done.stderr.strip().splitlines()[-5:]
        if any(sign in line for line in tail for sign in OUT_OF_MEMORY_SIGNS):
            return out_of_memory, None, done.stderr
        if done.returncode < 0:
            try:
                name = signal.Signals(-done.returncode).name
            except ValueError:
                name = f"signal {-done.returncode}"
            return f"crashed ({name})", None, done.stderr
        return f"failed (exit status {done.returncode})", None, done.stderr
    return "ok", report, done.stderr


def run_script(
    args: argparse.Namespace,
    worker: Callable[[argparse.Namespace], None],
    driver: Callable[[argparse.Namespace], int],
) -> int:
    """The entry of a script that is a driver and its own workers: `worker(args)` in a worker
    process (``--worker`` given; exit status 0), else `driver(args)` and its exit status."""
    if args.worker:
        worker(args)
        return 0
    return driver(args)


def run_worker(
    script: str, label: str, options: list[str], args: argparse.Namespace
) -> tuple[str, dict | None, str]:
    """Runs `script` (the calling driver) as a worker in a fresh process, with `options` and
    ``--mem-limit-gb``, under the ``--timeout-s`` and ``--mem-limit-gb`` of `args`, after
    ``label ...`` on stderr; returns what :func:`run_process` returns."""
    command = [sys.executable, str(Path(script).resolve()), *options]
    command += ["--mem-limit-gb", str(args.mem_limit_gb)]
    print(f"  {label} ...", end=" ", flush=True, file=sys.stderr)
    return run_process(command, timeout_s=args.timeout_s, mem_limit_gb=args.mem_limit_gb)


def rebuild_problems(build_at_start: tuple[str, float]) -> list[str]:
    """A problem when the compiled module was rebuilt since `build_at_start` (its
    :func:`build_stamp` then): the run measured two builds."""
    if build_stamp() == build_at_start:
        return []
    return [f"{build_at_start[0]} was rebuilt during the run; rerun"]


def refused(problems: list[str], output: Path) -> bool:
    """Whether the report must not be written to `output` because of `problems` (results that
    differ, a rebuild), which are then printed on stderr."""
    if not problems:
        return False
    print(f"RESULTS DIFFER; not writing {output}", file=sys.stderr)
    for problem in problems:
        print("  " + problem, file=sys.stderr)
    return True


def load_average() -> str:
    """The 1 min load average."""
    with open("/proc/loadavg") as loadavg:
        return loadavg.read().split()[0]


def build_stamp() -> tuple[str, float]:
    """The compiled module's path and modification time, to notice a rebuild during a run."""
    import importlib.util

    spec = importlib.util.find_spec("inexact_loops._core")
    path = Path(spec.origin) if spec and spec.origin else None
    return (str(path), path.stat().st_mtime) if path else ("", 0.0)


def machine_facts(packages: tuple[str, ...] = ("numpy", "scipy")) -> list[str]:
    """Markdown bullet lines: date, CPUs, memory, kernel, Python, the build and `packages`."""
    import inexact_loops
    import inexact_loops._core

    cpu = "unknown"
    with open("/proc/cpuinfo") as lines:
        for line in lines:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    with open("/proc/meminfo") as lines:
        memory_kib = next(int(line.split()[1]) for line in lines if line.startswith("MemTotal"))
    nproc = subprocess.run(["nproc"], capture_output=True, text=True, check=True).stdout.strip()
    now = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    module = Path(inexact_loops._core.__file__)
    built = dt.datetime.fromtimestamp(module.stat().st_mtime, dt.timezone.utc)
    commit = subprocess.run(
        ["git", "describe", "--always", "--dirty"], capture_output=True, text=True, cwd=REPO
    ).stdout.strip()
    versions = ", ".join(f"{name} {package_version(name)}" for name in packages)
    return [
        f"- Date: {now}",
        f"- `nproc`: {nproc}; CPU: {cpu}; memory: {memory_kib / 2**20:.1f} GiB",
        f"- Linux {platform.release()}, Python {platform.python_version()}",
        f"- inexact_loops {inexact_loops.__version__} (`{module.name}` built "
        f"{built:%Y-%m-%d %H:%M} UTC; working tree at git `{commit or 'unknown'}`), "
        f"{versions}",
    ]


def package_version(name: str) -> str:
    """The installed version of distribution `name`, or ``not installed``."""
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


# --------------------------------------------------------------------------------------------
# The report file and its marker sections.
# --------------------------------------------------------------------------------------------


def marker_line(name: str) -> str:
    return f"<!-- {name} -->"


def replace_head(existing: str, head: str) -> str:
    """`existing` with the text before its first marker line replaced by `head`."""
    first = MARKER.search(existing)
    if first is None:
        return head
    return head.rstrip("\n") + "\n\n" + existing[first.start() :]


def replace_section(existing: str, name: str, body: str, *, first: bool = False) -> str:
    """`existing` with the section of marker `name` replaced by its marker line and `body`.

    The section runs from the marker line to the next marker line or the end of the file. An
    absent section is appended at the end, or with `first` inserted before the first marker
    line (right after the head). Everything else is kept as it is.
    """
    section = marker_line(name) + "\n\n" + body.strip("\n") + "\n"
    markers = list(MARKER.finditer(existing))
    mine = next((k for k, match in enumerate(markers) if match.group(1) == name), None)
    if mine is None:
        if not existing.strip():
            return section
        if first and markers:
            head = existing[: markers[0].start()].rstrip("\n")
            return head + "\n\n" + section + "\n" + existing[markers[0].start() :]
        return existing.rstrip("\n") + "\n\n" + section
    start = markers[mine].start()
    end = markers[mine + 1].start() if mine + 1 < len(markers) else len(existing)
    following = existing[end:]
    return existing[:start] + section + ("\n" + following if following else "")


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """An advisory lock for read-modify-write of `path` among the scripts that use it."""
    key = hashlib.sha256(str(path.resolve()).encode()).hexdigest()[:16]
    lock_path = Path(tempfile.gettempdir()) / f"inexact-loops-report-{key}.lock"
    with open(lock_path, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(
        "w", dir=path.parent, prefix=f".{path.name}.", suffix=".tmp", delete=False, encoding="utf-8"
    ) as temporary:
        temporary.write(text)
        temporary.flush()
        os.fsync(temporary.fileno())
    os.replace(temporary.name, path)


def update_file(path: Path, change: Callable[[str], str]) -> None:
    """Re-reads `path` (empty if absent), applies `change` and replaces the file atomically."""
    with locked(path):
        existing = path.read_text(encoding="utf-8") if path.exists() else ""
        write_atomically(path, change(existing))


def write_head(path: Path, head: str) -> None:
    """Replaces the text before the first marker line of `path`; keeps the marker sections."""
    update_file(path, lambda existing: replace_head(existing, head))


def write_section(path: Path, name: str, body: str, *, first: bool = False) -> None:
    """Replaces (or adds) the section of marker `name` in `path`; keeps everything else."""
    update_file(path, lambda existing: replace_section(existing, name, body, first=first))


def publish_section(path: Path, name: str, lines: list[str]) -> None:
    """Prints the section of `lines` and writes it as the section of marker `name` in `path`."""
    body = "\n".join(lines)
    print(body)
    write_section(path, name, body)
