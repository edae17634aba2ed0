"""Exceptions raised by the simulator."""

from __future__ import annotations

import enum
from collections.abc import Iterable

__all__ = [
    "AssetError",
    "InvalidMesh",
    "InvalidRecording",
    "InvalidSettings",
    "PortInUse",
    "RecordingError",
    "SimulationError",
    "SimulationUnstable",
    "SweepTruncated",
    "UnknownObject",
    "UnreachablePoint",
    "UnusableCurves",
    "WorkspaceLimit",
]


class SimulationError(Exception):
    """Base class of every error the simulator raises on purpose."""


class UnknownObject(SimulationError, KeyError):
    """An object name that is not in the catalog; the message lists the known names."""

    def __init__(self, name: str, known: Iterable[str]) -> None:
        self.name = name
        self.known = tuple(known)
        super().__init__(f"unknown object {name!r}; known objects: {', '.join(self.known)}")

    def __str__(self) -> str:
        # KeyError would print the message quoted; show it as written.
        return str(self.args[0])


class InvalidMesh(SimulationError, ValueError):
    """A generated or loaded mesh is not a closed, single-component, consistently wound surface."""


class InvalidSettings(SimulationError, ValueError):
    """Probing or experiment settings out of range (points per curve, their spacing, the
    plane angle, sessions): the message names the setting, its value and its range."""


class AssetError(SimulationError, OSError):
    """An asset file (object recipe, generated cache) is missing, malformed or unreadable."""


class RecordingError(SimulationError):
    """A rerun recording could not be written, read or shown (the viewer failed to start)."""


class InvalidRecording(RecordingError, ValueError):
    """A recording file is missing, truncated or not an .rrd file."""


class PortInUse(RecordingError, OSError):
    """A port the viewer needs is taken; the message names a free alternative."""

    def __init__(self, port: int, option: str, alternative: int) -> None:
        self.port = port
        self.option = option
        self.alternative = alternative
        super().__init__(f"port {port} in use; pass {option} {alternative}")

    def __str__(self) -> str:
        return str(self.args[0])


class SimulationUnstable(SimulationError, RuntimeError):
    """MuJoCo warned (diverging state, contact buffer full, ...) or the state is not finite."""


class WorkspaceLimit(enum.Enum):
    """The limit a point or joint vector breaks (carried by :class:`UnreachablePoint`)."""

    RADIUS_TOO_LARGE = "radius_too_large"
    RADIUS_TOO_SMALL = "radius_too_small"
    SHOULDER = "shoulder"
    ELBOW = "elbow"
    QUILL = "quill"
    ROLL = "roll"


class UnreachablePoint(SimulationError, ValueError):
    """A tip pose outside the robot's workspace; ``limit`` names the limit it breaks.

    Parameters
    ----------
    message : str
        What was asked, what limit it breaks and what the limit is.
    limit : WorkspaceLimit
        The limit broken (for the preferred branch when no elbow branch works).
    """

    def __init__(self, message: str, limit: WorkspaceLimit) -> None:
        super().__init__(message)
        self.limit = limit

    def __reduce__(self) -> tuple[type[UnreachablePoint], tuple[str, WorkspaceLimit]]:
        # Pickled across processes (parallel experiments) with its limit.
        return type(self), (str(self), self.limit)


class SweepTruncated(SimulationError, RuntimeError):
    """A sweep lost so many points (edges, steep surfaces) that no data curve is left."""


class UnusableCurves(SimulationError, RuntimeError):
    """The sensed curves are not data curves recognition can use (e.g. their tangents at
    the common point are parallel): names what is wrong with them."""
