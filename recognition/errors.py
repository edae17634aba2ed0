"""Exceptions raised by the recognition library."""

__all__ = [
    "BackendUnavailable",
    "DegenerateGeometry",
    "InvalidArgument",
    "InvalidCurveData",
    "InvalidModel",
    "InvalidRecords",
    "NoRealSolution",
    "RecognitionError",
]


class RecognitionError(Exception):
    """Base class of every error the recognition library raises on purpose."""


class InvalidCurveData(RecognitionError, ValueError):
    """Input points or estimates are malformed: too few, NaN, repeated or unordered."""


class DegenerateGeometry(RecognitionError, ValueError):
    """The geometry is valid input but cannot be processed (e.g. a straight segment, kappa = 0)."""


class NoRealSolution(RecognitionError, ArithmeticError):
    """An equation the method relies on (e.g. the slope quartic (3.31)) has no real root."""


class InvalidModel(RecognitionError, ValueError):
    """A model mesh that cannot be used: open, several components, implausible size."""


class InvalidArgument(RecognitionError, ValueError):
    """An argument of a library call lies outside its domain (a NaN or negative threshold,
    an unknown model name, an empty selection)."""


class InvalidRecords(RecognitionError, ValueError):
    """A benchmark records file (JSONL) holds a line that is not a record: the message
    names the file, the line number and what a line must be."""


class BackendUnavailable(RecognitionError, ConnectionError):
    """A benchmark backend cannot be reached (e.g. no Ray cluster answers at the address
    given): the message names the address and what was expected there."""
