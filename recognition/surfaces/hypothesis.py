"""One answer of a belief over (model, pose): a model at a pose, with its fit, its posterior
and the uncertainty of where it puts p (:mod:`recognition.surfaces.belief`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from recognition.rigid import pose_matrix, rotation_from_vector

__all__ = ["Hypothesis", "within_probability"]

Array = NDArray[np.float64]

#: Fixed standard normal samples: the probability that a location lies within a radius
#: is the fraction of these, scaled by its covariance, that do (same belief, same value).
_NORMAL_SAMPLES = np.random.default_rng(0).standard_normal((4096, 3))


def within_probability(offset: Array, covariance: Array, radius_m: float) -> float:
    """P(|offset + e| <= radius) for e ~ N(0, covariance) (3, 3), by fixed samples."""
    w, V = np.linalg.eigh(0.5 * (covariance + covariance.T))
    e = (_NORMAL_SAMPLES * np.sqrt(np.maximum(w, 0.0))) @ V.T
    return float(np.mean(np.linalg.norm(offset + e, axis=1) <= radius_m))


@dataclass(frozen=True)
class Hypothesis:
    """One answer: a model at a pose, with its fit and posterior.

    Attributes
    ----------
    model : str
    T_model_from_data : (4, 4) float
    location : (3,) float
        The data's p on the model, model frame, metres.
    error_m : float
        Mean distance of all contact points from the model (4.8), outliers at the
        outlier level, metres.
    log_likelihood : float
        Of all the contact (:mod:`recognition.surfaces.belief`): the curves' clipped
        residuals whitened by Sigma, each counted by Huber's loss, ``touch_evidence`` and
        the misses (:mod:`~recognition.surfaces.touch_evidence`); up to a constant.
    posterior : float
    outliers : (k,) int
        Indices (into :attr:`Belief.points`) of the points beyond the outlier level.
    pivot : (3,) float
        The centroid of the data on the model, model frame: the centre of the turns of
        ``pose_covariance``.
    pose_covariance : (6, 6) float
        Laplace covariance of a small motion of the pose, (turn (rad), shift (m)) about
        ``pivot``, model frame.
    location_covariance : (3, 3) float
        Covariance of ``location`` that it implies, metres^2.
    location_images : (k, 3) float
        ``location`` and its images under the model's symmetries
        (:attr:`MeshModel.symmetries`): answers that are the same up to a symmetry of
        the object.
    touch_evidence : float
        Log ratio against "none of these" of the touches' contacts, each as this
        hypothesis (or the pose it was refined from) predicted it before it was made;
        counted again in turn where a refinement moved it beyond its uncertainty
        (:attr:`BeliefConfig.drift_sds`).
    """

    model: str
    T_model_from_data: Array
    location: Array
    error_m: float
    log_likelihood: float
    posterior: float
    outliers: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    pivot: Array = field(default_factory=lambda: np.zeros(3))
    pose_covariance: Array = field(default_factory=lambda: np.zeros((6, 6)))
    location_covariance: Array = field(default_factory=lambda: np.zeros((3, 3)))
    location_images: Array = field(default_factory=lambda: np.zeros((0, 3)))
    touch_evidence: float = 0.0

    @property
    def location_sd_m(self) -> float:
        """Standard deviation of ``location`` along its least determined direction,
        metres."""
        return float(np.sqrt(max(float(np.linalg.eigvalsh(self.location_covariance).max()), 0.0)))

    def nearest_location(self, point: Array) -> Array:
        """Of ``location`` and its symmetric images, the one nearest ``point`` (3,)."""
        images = self.location_images if len(self.location_images) else self.location[None]
        return np.asarray(images[int(np.argmin(np.linalg.norm(images - point, axis=1)))])

    def location_error_m(self, point: Array) -> float:
        """Distance of p from ``point`` (3,), model frame, up to the model's symmetries."""
        return float(np.linalg.norm(self.nearest_location(point) - point))

    def moved(self, motion: Array) -> Array:
        """T_model_from_data after the small motion (turn, shift) (6,) about ``pivot``."""
        dR = rotation_from_vector(np.asarray(motion[:3], float)[None])[0]
        T = self.T_model_from_data
        t = dR @ (T[:3, 3] - self.pivot) + self.pivot + motion[3:]
        return pose_matrix(dR @ T[:3, :3], t)
