"""What a belief over (model, pose) keeps, how it refines its hypotheses and when its
answer is right (:mod:`recognition.surfaces.belief`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["BeliefConfig"]


@dataclass(frozen=True)
class BeliefConfig:
    """Which hypotheses a belief keeps and how it refines them.

    Attributes
    ----------
    error_ratio, error_margin_m : float
        A pose of a recognition becomes a hypothesis when its registration error (4.8) is
        within ``error_ratio`` times the best plus ``error_margin_m``.
    max_hypotheses : int
        At most this many hypotheses (least error first).
    refine_iterations : int
        Levenberg-Marquardt steps on exact closest points per update.
    refine_clip_m : float
        In the refinement a residual counts at most this (metres): a touch far off a
        slid pose pulls it back, a gross outlier does not pull.
    drift_sds : float
        A hypothesis whose refinement after a touch moves p farther than this many
        standard deviations of where it put p (along its least determined direction;
        at least ``radius_m``) has come to another place, and its touches are counted
        again there (:meth:`drift_reach_m`, :meth:`Belief._recounted`).
    min_posterior : float
        Hypotheses whose posterior falls below this are dropped after an update.
    unexplained_p : float
        The alternative "none of these" is as likely as a hypothesis whose curves' whitened
        residuals reach the (1 - ``unexplained_p``) quantile of their chi-square law: the
        rate at which the true hypothesis is doubted. When the search missed the truth,
        the curves fit no hypothesis that well, or touches that no hypothesis predicted
        raise "none" (:attr:`touch_window_m`), and the confidence falls.
    radius_m : float
        An answer is right when it names the right model and puts p within this of the
        truth (the confidence's sense), metres.
    points_per_curve : int
        Longer curves are scored on this many of their points, evenly spaced
        (:func:`curve_points`): denser points add little once neighbours' mismatch
        correlates, and every update solves with their covariance.
    explore_hypotheses, explore_log_gap, explore_sd_m, explore_steps_m
        The valleys of the most probable hypotheses whose p is uncertain by more than
        ``explore_sd_m`` (standard deviation along its least determined direction)
        explored at each update (:meth:`Belief._explored`). The threshold is low: on a
        faceted mesh a fit of micrometre residuals has local minima a millimetre or two
        apart along a shallow valley, each reporting a location uncertainty of a tenth of
        a millimetre.
    prior_rotation_rad, prior_translation_m : float
        Standard deviations of the weak prior on each hypothesis's pose about its fit
        (keeps the Laplace covariance finite where the data leave a motion free).
    touch_window_m : float
        Were none of the hypotheses right, a touch's contact could lie anywhere along its
        approach: this long, metres, for a touch given without its approach's length
        (:meth:`Belief.with_contacts`; the planner's default standoff plus travel,
        :class:`~recognition.surfaces.touch_planning.TouchLimits`). A touch scores each
        hypothesis by the density it predicted for the contact against this spread.
    """

    error_ratio: float = 3.0
    error_margin_m: float = 0.02e-3
    max_hypotheses: int = 24
    refine_iterations: int = 4
    refine_clip_m: float = 2.0e-3
    drift_sds: float = 3.0
    min_posterior: float = 1e-9
    unexplained_p: float = 1e-3
    radius_m: float = 1.0e-3
    points_per_curve: int = 41
    explore_hypotheses: int = 3
    explore_sd_m: float = 0.05e-3
    explore_log_gap: float = 10.0
    explore_steps_m: tuple[float, ...] = (2.0e-3, 4.0e-3, 7.0e-3)
    prior_rotation_rad: float = 0.2
    prior_translation_m: float = 0.01
    touch_window_m: float = 16.0e-3

    def drift_reach_m(self, location_sd_m: float) -> float:
        """How far (metres) a refinement may move p of a hypothesis whose location is
        this uncertain (:attr:`Hypothesis.location_sd_m`) before it counts as another
        place (``drift_sds``)."""
        return max(self.drift_sds * location_sd_m, self.radius_m)

    def within_window(
        self,
        candidates: Sequence[tuple[str, NDArray[np.float64], float]],
        most: int | None = None,
    ) -> list[tuple[str, NDArray[np.float64]]]:
        """Of the poses ``(model, T_model_from_data, error_m)`` of a search (registration
        error (4.8), metres), those that may become hypotheses: a finite error within
        ``error_ratio`` times the least plus ``error_margin_m``, least error first, at
        most ``most`` (None: all)."""
        usable = [c for c in candidates if np.isfinite(c[2])]
        if not usable:
            return []
        limit = self.error_ratio * min(c[2] for c in usable) + self.error_margin_m
        kept = sorted((c for c in usable if c[2] <= limit), key=lambda c: c[2])
        return [(name, T) for name, T, _ in kept[:most]]
