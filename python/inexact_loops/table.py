"""Tables of results: a dict of equal-length numpy columns, with :meth:`Table.to_pandas`.

The tabular results (:attr:`Loops.components <inexact_loops.Loops.components>`,
:meth:`Loops.runs <inexact_loops.Loops.runs>`,
:meth:`Loops.pair_verdicts <inexact_loops.Loops.pair_verdicts>`,
:attr:`PoseGraph.vertices <inexact_loops.PoseGraph.vertices>`,
:attr:`PoseGraph.edges <inexact_loops.PoseGraph.edges>`,
:attr:`DetectionClusters.clusters <inexact_loops.DetectionClusters.clusters>`,
:attr:`SampleQuality.missed <inexact_loops.SampleQuality.missed>`) are :class:`Table` objects:
plain ``dict`` s of plain numpy arrays, so ``table["area_s2"]``, ``table.items()`` and
``np.savez(path, **table)`` work without pandas. pandas is imported only by
:meth:`Table.to_pandas`, and is not a dependency of the library.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    import pandas  # type: ignore[import-untyped, import-not-found, unused-ignore]

__all__ = ["Table"]

_PANDAS_MISSING = (
    "to_pandas() needs pandas, which is not installed: `pip install pandas` "
    "(without pandas, the columns are plain numpy arrays: use the Table as a dict)"
)


class Table(dict[str, npt.NDArray[Any]]):
    """Columns of a result: a ``dict`` from column name to a 1-D numpy array, all of the same
    length (one row per item), in a fixed column order. Each result documents its columns and
    their dtypes (``int64``, ``float64``, ``bool``, or ``str`` for names such as a pair's
    verdict).

    Example:
        >>> import numpy as np, inexact_loops as il
        >>> angle = np.linspace(0, 0.95 * 2 * np.pi, 200)
        >>> traj = il.Trajectory(np.arange(200) * 0.1, 10 * np.c_[np.cos(angle), np.sin(angle)])
        >>> table = il.find_loops(traj, gamma=4.0, separation=None).components
        >>> isinstance(table, dict), table.num_rows, str(table["area_s2"].dtype)
        (True, 2, 'float64')
        >>> list(table)[:3]
        ['id', 'trivial', 'area_s2']
    """

    @property
    def num_rows(self) -> int:
        """Number of rows: the length of the columns (0 for a table without columns)."""
        return len(next(iter(self.values()))) if self else 0

    def to_pandas(self) -> pandas.DataFrame:
        """The table as a ``pandas.DataFrame`` with the same columns, in the same order, and
        dtypes (a copy; the index is ``0..num_rows``).

        Raises:
            ImportError: pandas is not installed (the message says how to install it).

        Example:
            >>> import inexact_loops as il
            >>> det = il.Detections([0.0, 20.0, 500.0], [100.0, 100.0, 900.0])
            >>> frame = il.cluster_detections(det, epsilon_s=30.0).clusters.to_pandas()
            >>> frame[["id", "size", "t_max_s"]].to_dict("list")
            {'id': [0, 1], 'size': [2, 1], 't_max_s': [20.0, 500.0]}
        """
        try:
            import pandas
        except ImportError as error:
            raise ImportError(_PANDAS_MISSING, name="pandas") from error
        return pandas.DataFrame({name: np.asarray(column) for name, column in self.items()})
