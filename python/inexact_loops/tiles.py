"""A fleet's plane in tiles: the plumbing under :mod:`inexact_loops.dask`, for a scheduler of
your own.

:func:`inexact_loops.find_fleet_loops` computes a fleet in one process; the same answer comes
from tiles (blocks of rows x columns of one session pair) computed apart and merged, which is
how :func:`inexact_loops.dask.find_fleet_loops_dask` runs on a cluster:

- **Plan** from what each session's reader learns alone: :func:`session_blocks` gives a
  :class:`SessionBlocks` (pose count, span, bounding balls of its blocks), and
  :func:`plan_tiles` the :class:`Tile` objects whose balls come within gamma.
- **Scan** each tile from its two sessions (:func:`scan_tiles` for a group of tiles that share
  sessions): :func:`scan_tile` returns a :class:`TileSummary`,
  and, when asked, the tile's share of loop duration (:class:`TileDuration`, added up per session
  by :func:`session_loop_duration`) and its runs for the draws (:class:`TileRuns`).
- **Merge** in a tree: :func:`merge_tiles` joins summaries or partial merges
  (:class:`TileMerge`), in any order and grouping; :meth:`TileMerge.finish` gives the fleet's
  components.
- **Draw** samples by keys: a :class:`KeyedDraw` asks tiles for pairs
  (:class:`TileDrawRequest`), :func:`draw_tile` offers them (:class:`DrawCandidates`); the
  samples are :func:`inexact_loops.sample_fleet`'s, pair for pair.

Every object here pickles (as its bytes), so it travels between processes and machines.

Example:
    A circle and a third, in tiles of 8 poses: the components of the fleet in one process.

    >>> import numpy as np, inexact_loops as il
    >>> from inexact_loops import tiles
    >>> s = 0.2 * np.arange(40)
    >>> drive = il.Trajectory(s, np.c_[np.cos(s), np.sin(s)])
    >>> blocks = [tiles.session_blocks(drive, block=8)]
    >>> plan = tiles.plan_tiles(blocks, gamma=0.5)
    >>> parts = [tiles.scan_tile(t, drive, starts=(0, 0), gamma=0.5, separation=None) for t in plan]
    >>> loops = tiles.merge_tiles(parts).finish(blocks, names=["drive"])
    >>> fleet = il.find_fleet_loops(il.Fleet({"drive": drive}), gamma=0.5, separation=None)
    >>> loops.components["pair_count"].tolist() == fleet.components["pair_count"].tolist()
    True
"""

from ._core import (
    DrawCandidates,
    KeyedDraw,
    SessionBlocks,
    Tile,
    TileDrawRequest,
    TileDuration,
    TileMerge,
    TileRuns,
    TileSummary,
    draw_tile,
    merge_tiles,
    plan_tiles,
    scan_tile,
    scan_tiles,
    session_blocks,
    session_loop_duration,
)

__all__ = [
    "DrawCandidates",
    "KeyedDraw",
    "SessionBlocks",
    "Tile",
    "TileDrawRequest",
    "TileDuration",
    "TileMerge",
    "TileRuns",
    "TileSummary",
    "draw_tile",
    "merge_tiles",
    "plan_tiles",
    "scan_tile",
    "scan_tiles",
    "session_blocks",
    "session_loop_duration",
]
