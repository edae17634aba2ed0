"""Why a wrong answer is wrong: the search missed the truth, or the data favour the answer.

A benchmark knows the true pose. Scored as the belief scores any pose a broader search
adds (:meth:`~recognition.surfaces.belief.Belief.with_poses`: each touch counted as it
would have predicted it, refined on the curves and the touches before it, then refined on
all the contact and its valley explored), the truth either explains all the contact
better than the answer, and no search proposed it, or it does not, and the data
themselves favour the answer (a nearly symmetric surface, a rival model within the
noise). :func:`truth_fit` measures which; :func:`cause` names it with a stated threshold.

Where the data favour a wrong answer, more contact may still tell: :func:`truth_fit` also
gives the share of the answer's surface that its pose puts more than ``APART_SDS``
standard deviations of a contact's noise from the true surface (a touch there would tell
them apart; a nearly symmetric body turned about its near-axis stands apart almost
nowhere), and :func:`touch_could_tell` names the answers a touch could still refute.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from recognition.evaluation.records import RIGHT_WITHIN_MM
from recognition.rigid import apply_pose
from recognition.surfaces.belief import Belief
from recognition.surfaces.mesh_model import MeshModel

__all__ = [
    "APART_SDS",
    "CAUSES",
    "TELLING_SHARE",
    "TIE_LOG_RATIO",
    "cause",
    "surface_apart",
    "touch_could_tell",
    "truth_fit",
]

#: Within this log-likelihood ratio (ten times likelier) either way, the truth and the
#: answer are a near tie.
TIE_LOG_RATIO = float(np.log(10.0))

#: The causes :func:`cause` names, in the reports' order.
CAUSES = ("search", "tie", "data")

#: A posed surface stands apart from the truth where it lies farther than this many
#: standard deviations of a contact's noise (sensor and mismatch) from the true surface.
APART_SDS = 3.0
#: A touch could refute an answer whose surface stands apart on at least this share.
TELLING_SHARE = 0.1
#: Every this many vertices of a model sample its surface for :func:`surface_apart`.
_VERTEX_STRIDE = 8


def surface_apart(
    answer: MeshModel,
    T_answer: NDArray[np.float64],
    truth: MeshModel,
    T_truth: NDArray[np.float64],
    threshold_m: float,
) -> float:
    """The share of ``answer``'s surface (every eighth vertex) that the pose ``T_answer``
    (model from data) puts farther than ``threshold_m`` from ``truth``'s surface at
    ``T_truth``: where a touch would tell them apart (anywhere on the surface, whether or
    not a robot may reach it)."""
    T = np.asarray(T_truth, float) @ np.linalg.inv(np.asarray(T_answer, float))
    placed = apply_pose(T, np.asarray(answer.vertices)[::_VERTEX_STRIDE])
    return float(np.mean(np.abs(truth.distance.signed(placed)) > threshold_m))


def truth_fit(
    models: Mapping[str, MeshModel],
    belief: Belief,
    true_model: str,
    T_model_from_data: NDArray[np.float64],
    point_in_model: NDArray[np.float64],
) -> dict[str, Any] | None:
    """How the true pose fits all the belief's contact against its answer, JSON-ready:
    ``log_ratio``, the log-likelihood of the truth (scored as above; of the poses that
    scoring ends with, the one that puts p nearest the truth) less the answer's, and
    ``error_mm``, how far that pose puts p from the truth (it may slide along a valley the
    data leave free), and ``apart``, the share of the answer's surface that stands
    ``APART_SDS`` standard deviations of a contact's noise apart from the truth's
    (:func:`surface_apart`). None without an answer or when the true model is not in
    ``models``.
    """
    best = belief.best
    if best is None or true_model not in models:
        return None
    alone = replace(belief, hypotheses=(), broadened=None)
    scored = alone.with_poses(models, [(true_model, np.asarray(T_model_from_data, float))])
    mine = [h for h in scored.hypotheses if h.model == true_model]
    if not mine:
        return None
    truth = min(mine, key=lambda h: h.location_error_m(point_in_model))
    return {
        "log_ratio": float(truth.log_likelihood - best.log_likelihood),
        "error_mm": float(truth.location_error_m(point_in_model) * 1e3),
        "apart": surface_apart(
            models[best.model],
            best.T_model_from_data,
            models[true_model],
            T_model_from_data,
            APART_SDS * belief.noise.point_sigma_m(belief.sensor_m),
        ),
    }


def cause(fit: Mapping[str, Any] | None, radius_mm: float = RIGHT_WITHIN_MM) -> str | None:
    """The cause of a wrong answer from its :func:`truth_fit`: ``"search"`` (the truth,
    still within ``radius_mm`` after its refinement, at least ten times likelier than
    the answer: no search proposed it), ``"tie"`` (within ten times either way) or
    ``"data"`` (the answer ten times likelier, or the truth slides away from itself:
    the data favour another place); None without a fit."""
    if fit is None:
        return None
    if fit["error_mm"] > radius_mm or fit["log_ratio"] < -TIE_LOG_RATIO:
        return "data"
    return "search" if fit["log_ratio"] > TIE_LOG_RATIO else "tie"


def touch_could_tell(fit: Mapping[str, Any] | None) -> bool:
    """Whether a wrong answer's surface stands apart from the truth's on at least
    ``TELLING_SHARE`` of it (:func:`truth_fit`'s ``apart``; False without one)."""
    return fit is not None and fit.get("apart", 0.0) >= TELLING_SHARE
