"""The exceptions raised by inexact_loops (every one is a :class:`LoopsError`) and the warnings
it issues (every one is a :class:`LoopsWarning`).

A result that is correct but deserves a second look -- a broken diagonal of S_gamma, no revisit
at all, a sample smaller than asked or empty -- is issued with :func:`warnings.warn`, attributed
to the line of your code that called :func:`find_loops` or :func:`sample`, and kept on the result
as sentences (``Loops.warnings``, ``Samples.warnings``). Input that a lenient reading option
dropped is issued the same way. Filter them by category::

    import warnings
    warnings.simplefilter("error", il.LoopsWarning)          # every one raises
    warnings.simplefilter("ignore", il.SampleBudgetWarning)  # a short sample is fine here

Each warning of the engine (``loops_core::Warning``, ``loops_core::SampleWarning``) has its
category in one table, ``crates/loops-py/src/warning.rs``; a warning the table does not name yet
is issued as :class:`LoopsWarning` itself.
"""

__all__ = [
    "DeadReckoningWarning",
    "DiagonalBrokenWarning",
    "DroppedInputWarning",
    "EmptyResultWarning",
    "EmptySampleWarning",
    "InternalError",
    "InvalidParameterError",
    "InvalidTrajectoryError",
    "LoopsError",
    "LoopsIOError",
    "LoopsWarning",
    "NoLoopsWarning",
    "OutOfMemoryError",
    "SampleBudgetWarning",
]


class LoopsError(Exception):
    """Base class of every error raised by inexact_loops."""


class InvalidTrajectoryError(LoopsError, ValueError):
    """The poses or timestamps are not a valid trajectory.

    NaN or infinite values, unsorted or duplicate timestamps, fewer than two poses. The message
    names the first bad index (or file and line).
    """


class InvalidParameterError(LoopsError, ValueError):
    """A parameter is out of range: gamma, an interval, a name, a component id."""


class LoopsIOError(LoopsError, OSError):
    """A file could not be read or parsed; the message names the file and line."""


class OutOfMemoryError(LoopsError, MemoryError):
    """The answer does not fit in memory (or under a limit such as ``ulimit -v``).

    Raised instead of letting the process abort: the message names what the memory was for and
    the size that could not be allocated (``out of memory: 3.1 GiB (3328599040 bytes) for the
    runs of S_gamma could not be allocated; ...``). The interpreter and its data are untouched;
    a smaller gamma, a separation, fewer poses, a smaller budget or image needs less.
    """


class InternalError(LoopsError, RuntimeError):
    """A bug in inexact_loops (a Rust panic was caught); please report it."""


class LoopsWarning(UserWarning):
    """Base class of every warning issued by inexact_loops."""


class DiagonalBrokenWarning(LoopsWarning):
    """Consecutive poses farther apart than gamma (:func:`find_loops`).

    The diagonal of S_gamma breaks there, so there is more than one trivial component: usually a
    data gap, or gamma below the step length. The message names the first such pose and the
    largest step.
    """


class DroppedInputWarning(LoopsWarning):
    """A lenient reading option dropped part of a file: ``drop_duplicate_stamps=True`` (poses
    repeating the stamp before) in :func:`read_trajectory`, ``drop_outside_span=True``
    (detections outside the trajectory's time span) in :func:`read_detections`. The message names
    the file, the count and the lines."""


class DeadReckoningWarning(LoopsWarning):
    """A pose graph without vertices was read with ``chain_edges=True``
    (:func:`read_pose_graph`, :func:`read_trajectory`): its poses are its odometry edges composed
    from the first vertex, dead reckoning, whose error grows along the path; loops that its
    loop-closure edges close may not close in it. The message names the file and the vertices
    chained."""


class EmptyResultWarning(LoopsWarning):
    """A result with nothing in it, which is rarely what was meant."""


class NoLoopsWarning(EmptyResultWarning):
    """:func:`find_loops` with a separation found no revisit: no pair within gamma is that far
    apart along the trajectory, so there is no loop component. A larger gamma, a smaller
    separation, or ``separation=None`` (the paper's S_gamma, simple loops included) finds some.
    """


class EmptySampleWarning(EmptyResultWarning):
    """:func:`sample` returned no samples: no candidates (e.g. ``skip_trivial`` on loops whose
    every component is trivial), or a rate that kept none."""


class SampleBudgetWarning(LoopsWarning):
    """:func:`sample` could not spend its budget as asked: fewer candidates than the budget (all
    of them were returned), or a budget below the number of groups (P1 cannot hold)."""
