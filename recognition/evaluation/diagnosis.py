"""Why a wrong answer is wrong: the search missed the truth, or the data favour the answer.

A benchmark knows the true pose. Scored as the belief scores any pose a broader search
adds (:meth:`~recognition.surfaces.belief.Belief.with_poses`: each touch counted as it
would have predicted it, refined on the curves and the touches before it, then refined on
all the contact and its valley explored), the truth either explains all the contact
better than the answer, and no search proposed it, or it does not, and the data
themselves favour the answer (a nearly symmetric surface, a rival model within the
noise). :func:`truth_fit` measures which; :func:`cause` names it with a stated threshold.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from recognition.evaluation.records import RIGHT_WITHIN_MM
from recognition.surfaces.belief import Belief
from recognition.surfaces.mesh_model import MeshModel

__all__ = ["CAUSES", "TIE_LOG_RATIO", "cause", "truth_fit"]

#: Within this log-likelihood ratio (ten times likelier) either way, the truth and the
#: answer are a near tie.
TIE_LOG_RATIO = float(np.log(10.0))

#: The causes :func:`cause` names, in the reports' order.
CAUSES = ("search", "tie", "data")


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
    data leave free). None without an answer or when the true model is not in ``models``.
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
