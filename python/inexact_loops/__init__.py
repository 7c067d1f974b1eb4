"""Find, measure and sample inexact loops in robot trajectories.

An *inexact loop* is a pair of times (t, t') at which a trajectory comes back within a distance
gamma of itself. :func:`find_loops` finds all of them exactly and groups them into *loop
components* (connected components in the time x time plane); :class:`Loops` measures loop
duration, loop area and loop density over them.

Example:
    >>> import inexact_loops as il
    >>> traj = il.urban_drive(duration_s=600.0, seed=7)
    >>> loops = il.find_loops(traj, gamma=40.0)
    >>> table = loops.components
    >>> bool(table["trivial"][0])
    True
    >>> tau = loops.loop_duration()
    >>> tau.shape == (len(traj),)
    True
"""

from . import metrics
from ._core import (
    Loops,
    Trajectory,
    __version__,
    find_loops,
    read_trajectory,
    urban_drive,
)
from .errors import (
    InternalError,
    InvalidParameterError,
    InvalidTrajectoryError,
    LoopsError,
    LoopsIOError,
)

__all__ = [
    "InternalError",
    "InvalidParameterError",
    "InvalidTrajectoryError",
    "Loops",
    "LoopsError",
    "LoopsIOError",
    "Trajectory",
    "__version__",
    "find_loops",
    "metrics",
    "read_trajectory",
    "urban_drive",
]
