"""Parquet pose stores: a session as a table of ``t``, ``x``, ``y``, optional ``z`` and
quaternion columns; files written atomically."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidParameterError, LoopsIOError

_PARQUET_TIME = "t"
_PARQUET_POSITION = ("x", "y", "z")
_PARQUET_QUATERNION = ("qx", "qy", "qz", "qw")


def import_pyarrow() -> Any:
    try:
        import pyarrow  # type: ignore[import-untyped, import-not-found, unused-ignore]
        import pyarrow.parquet  # type: ignore[import-untyped, import-not-found, unused-ignore]
    except ImportError as error:
        raise ImportError(
            "Parquet needs pyarrow, which is not installed: pip install '.[dask]' in a checkout "
            f"(or pip install pyarrow) ({error})"
        ) from error
    return pyarrow


def read_pose_parquet(path: str | os.PathLike[str], *, axes: tuple[int, int] | None = None) -> Any:
    """Reads a session from a Parquet pose store: a column ``t`` (seconds, increasing), the
    position ``x``, ``y`` and optionally ``z``, and optionally the orientation ``qx``, ``qy``,
    ``qz``, ``qw`` (then an SE(3) trajectory, measured by its translation unless a metric says
    otherwise). Read with pyarrow, only those columns.

    Args:
        path: the ``.parquet`` file.
        axes: a plane of two position axes (0 = x, 1 = y, 2 = z), as :func:`read_trajectory`.

    Returns:
        :class:`Trajectory`.

    Raises:
        LoopsIOError: a missing column, a null or non-numeric value, naming the file and column.
        InvalidTrajectoryError: times not increasing, non-finite values (naming the pose).
        ImportError: without pyarrow.

    Example:
        >>> import tempfile, pathlib, numpy as np, inexact_loops as il
        >>> from inexact_loops.dask import read_pose_parquet, write_pose_parquet
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "drive.parquet"
        >>> write_pose_parquet(path, il.Trajectory(np.arange(3.0), np.eye(3)))
        >>> len(read_pose_parquet(path))
        3
    """
    pa = import_pyarrow()
    path = os.fspath(path)
    try:
        schema = pa.parquet.read_schema(path)
    except FileNotFoundError:
        raise
    except Exception as error:  # pyarrow's own errors: not a Parquet file, corrupt footer
        raise LoopsIOError(f"{path}: not a Parquet pose store: {error}") from error
    names = set(schema.names)
    missing = [c for c in (_PARQUET_TIME, "x", "y") if c not in names]
    if missing:
        raise LoopsIOError(
            f"{path}: a Parquet pose store needs the columns t, x, y (z, qx, qy, qz, qw optional); "
            f"missing {', '.join(missing)} (columns: {', '.join(schema.names)})"
        )
    position = [c for c in _PARQUET_POSITION if c in names]
    orientation = all(c in names for c in _PARQUET_QUATERNION)
    columns = [_PARQUET_TIME, *position, *(_PARQUET_QUATERNION if orientation else ())]
    try:
        table = pa.parquet.read_table(path, columns=columns)
    except Exception as error:
        raise LoopsIOError(f"{path}: cannot read the Parquet pose store: {error}") from error

    def column(name: str) -> np.ndarray:
        data = table.column(name)
        if data.null_count:
            raise LoopsIOError(f"{path}: column {name} has {data.null_count} null value(s)")
        try:
            return np.ascontiguousarray(data.to_numpy(), dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise LoopsIOError(f"{path}: column {name} is not numeric ({data.type})") from error

    t = column(_PARQUET_TIME)
    xyz = np.column_stack([column(c) for c in position])
    if orientation:
        if len(position) != 3:
            raise LoopsIOError(
                f"{path}: an orientation (qx, qy, qz, qw) needs the position x, y, z"
            )
        q = np.column_stack([column(c) for c in _PARQUET_QUATERNION])
        traj = _core.Trajectory.se3(t, xyz, q)
    else:
        traj = _core.Trajectory(t, xyz)
    if axes is not None:
        a, b = axes
        if max(a, b) >= xyz.shape[1] or a == b or min(a, b) < 0:
            raise InvalidParameterError(
                f"axes {axes} do not name two position axes of {path} ({xyz.shape[1]} coordinates)"
            )
        traj = _core.Trajectory(t, xyz[:, [a, b]])
    return traj


def write_pose_parquet(path: str | os.PathLike[str], trajectory: Any) -> None:
    """Writes a trajectory's times and positions (the first three coordinates, or two) as a
    Parquet pose store that :func:`read_pose_parquet` reads: columns ``t``, ``x``, ``y`` (and
    ``z``). Written to a temporary file beside ``path``, then renamed.

    Raises:
        ImportError: without pyarrow.
    """
    pa = import_pyarrow()
    points = np.asarray(trajectory.positions)
    columns = {_PARQUET_TIME: np.asarray(trajectory.timestamps)}
    for k, name in enumerate(_PARQUET_POSITION[: min(3, points.shape[1])]):
        columns[name] = np.ascontiguousarray(points[:, k])
    table = pa.table(columns)
    atomic(Path(path), lambda tmp: pa.parquet.write_table(table, tmp))


def atomic(path: Path, write: Callable[[str], None]) -> None:
    """Writes ``path`` whole or not at all: ``write`` fills a scratch file (named by the string
    it is given), whose bytes go through loops-io's one atomic writer
    (:func:`inexact_loops._core.write_file`), replacing ``path``: a reader sees the old file or
    the new one, never half of one, and a stream such as ``/dev/null`` is written into, never
    replaced."""
    with tempfile.TemporaryDirectory(prefix="loops-") as scratch:
        tmp = os.path.join(scratch, path.name or "file")
        write(tmp)
        _core.write_file(path, Path(tmp).read_bytes(), overwrite=True)
