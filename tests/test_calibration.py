"""The reliability diagram and the touches' summary, on hand-made records."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from recognition.evaluation.calibration import (
    miss_causes,
    reliability,
    touch_summary,
    touches_section,
)
from recognition.evaluation.diagnosis import cause
from recognition.evaluation.records import Record


def _record(
    confidence: float,
    error_mm: float | None,
    *,
    after: float | None = None,
    after_error_mm: float | None = None,
    after_model: str = "cat",
    made: int = 0,
) -> Record:
    touches = None
    if after is not None:
        touches = {
            "made": made,
            "stop": "sure",
            "recognized": after_model,
            "success": after_model == "cat",
            "confidence": after,
            "answer_error_mm": after_error_mm if after_model == "cat" else None,
            "confidences": [after] * made,
            "recognition_times_s": [0.1 * (k + 1) for k in range(made)],
        }
    return Record(
        instance="cat/0",
        model="cat",
        index=0,
        vertex=None,
        seed=0,
        info={},
        instance_time_s=0.0,
        method="fast",
        recognized="cat" if error_mm is not None else "dog",
        success=error_mm is not None,
        time_s=0.1,
        confidence=confidence,
        answer_error_mm=error_mm,
        touches=touches,
    )


def test_reliability_bins_and_ece() -> None:
    # two answers at 0.95 (one right), two at 0.25 (none right): each bin's gap weighted
    records = [
        _record(0.95, 0.2),
        _record(0.95, 3.0),  # the right model, p 3 mm off: wrong
        _record(0.25, None),
        _record(0.25, None),
    ]
    out = reliability(records)
    assert out["answers"] == 4 and out["right"] == pytest.approx(0.25)
    assert out["ece"] == pytest.approx((2 * abs(0.95 - 0.5) + 2 * abs(0.25 - 0.0)) / 4)
    assert out["sure"] == 0 and out["sure_right"] is None
    counts = [b["count"] for b in out["bins"]]
    assert counts[9] == 2 and counts[2] == 2 and sum(counts) == 4


def test_touch_summary_counts_other_models_as_infinitely_far() -> None:
    records = [
        _record(0.5, 2.0, after=0.999, after_error_mm=0.1, made=2),
        _record(0.5, 2.0, after=0.999, after_error_mm=0.3, made=3),
        _record(0.5, None, after=0.4, after_model="dog", made=5),
        _record(0.999, 0.05, after=0.999, after_error_mm=0.05, made=0),
    ]
    out = touch_summary(records)
    assert out is not None
    # localisation after the touches: 0.05, 0.1, 0.3 and inf -> median (0.1 + 0.3) / 2
    assert out["localisation_after_touches_median_mm"] == pytest.approx(0.2)
    assert out["right_after_touches"] == pytest.approx(0.75)
    assert out["recognized_after_touches"] == pytest.approx(0.75)
    assert out["touches_median"] == pytest.approx(2.5) and out["touches_max"] == 5
    assert out["sure_after_curves"] == 1 and out["sure_after_curves_touched"] == 0
    times = np.array([0.1, 0.2, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert out["touch_time_median_s"] == pytest.approx(np.median(times))
    assert out["touch_time_mean_s"] == pytest.approx(np.mean(times))
    text = touches_section(records)
    assert "localisation after the touches: median 0.2 mm" in text
    # most answers naming another model: no finite median, and the report says why
    wrong = [_record(0.5, None, after=0.4, after_model="dog", made=5)] * 3
    most_wrong = touch_summary(wrong + records[:1])
    assert most_wrong is not None and most_wrong["localisation_after_touches_median_mm"] is None
    assert "most answers name another model" in touches_section(wrong + records[:1])


def test_wrong_answers_are_counted_by_the_cause_their_truth_fit_names() -> None:
    # the truth ten times likelier than the answer: the search missed it; within ten
    # times: a tie; the answer ten times likelier, or the truth sliding off itself: the data
    fits = [
        {"log_ratio": 3.0, "error_mm": 0.2},
        {"log_ratio": -1.0, "error_mm": 0.2},
        {"log_ratio": -3.0, "error_mm": 0.2, "apart": 0.4},
        {"log_ratio": 5.0, "error_mm": 4.0, "apart": 0.05},
        None,
    ]
    assert [cause(f) for f in fits] == ["search", "tie", "data", "data", None]
    records = [replace(_record(0.3, 5.0), truth_fit=f) for f in fits]
    records.append(_record(0.999, 0.1))  # right: no diagnosis, not counted
    counts = miss_causes(records)
    # a touch could refute the answer that stands apart on 40 % of its surface, not 5 %
    assert counts == {
        "wrong": 5,
        "search": 1,
        "tie": 1,
        "data": 2,
        "unknown": 1,
        "measured": 2,
        "telling": 1,
    }
    touched = [replace(_record(0.3, 5.0, after=0.4, after_model="dog", made=5), truth_fit=None)]
    touched[0].touches["truth_fit"] = {"log_ratio": 4.0, "error_mm": 0.1}  # type: ignore[index]
    assert miss_causes(touched, after_touches=True)["search"] == 1
    assert miss_causes(touched)["unknown"] == 1
    assert "1 where the true pose fits all the contact" in touches_section(touched)
    # a diagnosis without the measure of how far it stands apart says nothing of it
    assert "noise sd apart" not in touches_section(touched)
    touched[0].touches["truth_fit"]["apart"] = 0.3  # type: ignore[index]
    assert "1 of the 1 measured stand more than 3 noise sd apart" in touches_section(touched)
