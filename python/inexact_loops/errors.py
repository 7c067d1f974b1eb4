"""The exceptions raised by inexact_loops; every one is a :class:`LoopsError`."""

__all__ = [
    "InternalError",
    "InvalidParameterError",
    "InvalidTrajectoryError",
    "LoopsError",
    "LoopsIOError",
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


class InternalError(LoopsError, RuntimeError):
    """A bug in inexact_loops (a Rust panic was caught); please report it."""
