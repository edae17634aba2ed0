"""What a registration returns: the fit of the data curves on one model, thesis Eq. (4.12)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from recognition.surfaces.closed_form.search import LocalSearch

__all__ = [
    "ClosedFormRegistration",
    "Registration",
    "RegistrationMode",
    "RegistrationStatus",
    "rejected",
]


class RegistrationMode(StrEnum):
    """The registration methods (one config class each)."""

    FAST = "fast"
    THESIS = "thesis"
    ICP = "icp-baseline"
    CLOSED_FORM = "closed-form"


class RegistrationStatus(StrEnum):
    """How a registration (or one local search of it) ended."""

    CONVERGED = "converged"
    """The step or the decrease of the error fell below its tolerance."""
    MAX_ITERATIONS = "max_iterations"
    """The iteration limit was reached first."""
    NO_CANDIDATES = "no_candidates"
    """The table lookup (4.7) found no candidate: the model was not searched."""
    PRUNED = "pruned"
    """Fast mode: stopped after the coarse stage, far worse than the best model."""


@dataclass(frozen=True)
class Registration:
    """Result of registering data curves on one model.

    Attributes
    ----------
    model : str
    error_m : float
        Registration error, metres (model units for unit-free surfaces): the mean
        distance from the data points to a mesh model (4.8), the superposition error E
        (4.11) on a closed-form model; ``inf`` when the model was rejected at table
        lookup.
    T_model_from_data : (4, 4) float
        Rigid transform taking data points onto the model (NaN when rejected).
    location : (3,) float
        The data curves' common point p mapped onto the model, model frame (NaN when
        rejected).
    candidates : (k,) int or (k, 2) float
        Candidate sites of the table lookup: mesh vertices, or the (u, v) of a
        closed-form model's candidate points (least initial error first).
    iterations : int
    status : RegistrationStatus
    time_s : float
        Wall time; in a search of several models at once, this model's share of the
        batched work (in proportion to the point evaluations made for it).
    mode : RegistrationMode
    trace : tuple of float
        Error after each refinement step of the best start (diagnostics).
    error_is_exact : bool
        False when ``error_m`` was read off a distance field (within about 0.01 mm of
        the exact distance), see
        :func:`~recognition.surfaces.registration.exact.with_exact_error`.
    outliers : (k,) int
        Indices (into ``curves.points``) of the data points farther than
        ``outlier_threshold_m`` from the model at the pose: counted at the threshold in
        ``error_m`` (fast mode), and left out of the pose's last polish.
    outlier_threshold_m : float
        The outlier threshold, metres (``inf``: none).
    poses : (k, 4, 4) float
        Fast mode: the best distinct poses the search ended with on this model (at most
        its last pass's ``n_final``; the registration's own first), T_model_from_data
        each.
    pose_errors_m : (k,) float
        Their errors (4.8), metres, exact where ``error_is_exact``.
    equivalent_poses : int
        The first this many ``poses`` fit the data equally well (within what the data's
        noise resolves, :attr:`FastConfig.equivalent_log_ratio`): distinct answers that
        the data cannot tell apart (a symmetric part, a flat face, a sphere), the
        registration's own among them. 1: no other pose found fits as well.
    free_motions : int
        Degrees of freedom (0-6) of the pose that the data leave free (a flat face: 3, a
        cylinder: 1, a sphere: 3; see
        :meth:`~recognition.surfaces.registration.ambiguity.Resolution.free_motions`):
        the pose could slide or turn that way by a millimetre and fit as well.
    """

    model: str
    error_m: float
    T_model_from_data: NDArray[np.float64]
    location: NDArray[np.float64]
    candidates: NDArray[np.int64] | NDArray[np.float64]
    iterations: int
    status: RegistrationStatus
    time_s: float
    mode: RegistrationMode
    trace: tuple[float, ...] = field(default_factory=tuple)
    error_is_exact: bool = True
    outliers: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    outlier_threshold_m: float = float("inf")
    poses: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 4, 4)))
    pose_errors_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    equivalent_poses: int = 1
    free_motions: int = 0

    @property
    def equivalent_locations(self) -> NDArray[np.float64]:
        """Where each of the ``equivalent_poses`` puts the data's p, (k, 3) model frame,
        metres (the registration's own ``location`` first)."""
        T = self.T_model_from_data
        p = T[:3, :3].T @ (self.location - T[:3, 3])
        poses = self.poses[: self.equivalent_poses] if len(self.poses) else T[None]
        return np.asarray(poses[:, :3, :3] @ p + poses[:, :3, 3], dtype=np.float64)

    @property
    def ambiguous(self) -> bool:
        """True when the data do not fix the pose: other distinct poses fit as well, or
        the pose is free along some direction."""
        return self.equivalent_poses > 1 or self.free_motions > 0

    @property
    def rejected(self) -> bool:
        """True when the table lookup found no candidate on the model."""
        return self.status is RegistrationStatus.NO_CANDIDATES


@dataclass(frozen=True)
class ClosedFormRegistration(Registration):
    """Registration onto a closed-form model, thesis Section 4.2.2.2.

    Attributes
    ----------
    u, v, phi : float
        Location of p on the model and the turn about the normal (radians); NaN if
        rejected.
    searches : tuple of LocalSearch
        One per candidate, in the order of ``candidates``.
    normal_flipped : bool
        True when the winning data normal is the opposite of the estimated one (only
        tried when the data carry no approach direction).
    """

    u: float = float("nan")
    v: float = float("nan")
    phi: float = float("nan")
    searches: tuple[LocalSearch, ...] = field(default=(), repr=False)
    normal_flipped: bool = False


def rejected(
    model: str,
    mode: RegistrationMode,
    start: float,
    candidates: NDArray[np.int64] | NDArray[np.float64] | None = None,
    elapsed: float | None = None,
) -> Registration:
    """The registration of a model that the table lookup rejected (error ``inf``).

    ``start`` is the ``time.perf_counter()`` at which the work began (unless ``elapsed``
    gives the time taken).
    """
    candidates = np.zeros(0, np.int64) if candidates is None else candidates
    arguments = (
        model,
        float("inf"),
        np.full((4, 4), np.nan),
        np.full(3, np.nan),
        candidates,
        0,
        RegistrationStatus.NO_CANDIDATES,
        time.perf_counter() - start if elapsed is None else elapsed,
        mode,
    )
    if mode is RegistrationMode.CLOSED_FORM:
        return ClosedFormRegistration(*arguments)
    return Registration(*arguments)
