"""Table 3.3 and the recognition rates, from the records of random curves of every class."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from recognition.curves.families import CurveKind
from recognition.reproduction.chapter3.experiments import CurveExperiment
from recognition.reproduction.chapter3.measures import summary
from recognition.reproduction.chapter3.reference import CLASSES, TABLE_3_3_THESIS
from recognition.reproduction.tables import TableResult, markdown_table

__all__ = [
    "recognition_rates",
    "table_3_3",
]


def table_3_3(records: list[dict[str, Any]], experiment: CurveExperiment) -> TableResult:
    """Table 3.3: relative error of the recovered shape parameters, per class, from the
    records of :func:`~recognition.reproduction.chapter3.experiments.classify_random_curves`."""
    measured: dict[str, dict[str, float]] = {
        "min_relative_error_percent": {},
        "max_relative_error_percent": {},
        "mean_relative_error_percent": {},
        "curves": {},
    }
    for kind in CLASSES:
        errors = [100 * r["own_class_error"] for r in records if r["kind"] == kind.value]
        s = summary(errors)
        measured["min_relative_error_percent"][kind.value] = s["min"]
        measured["max_relative_error_percent"][kind.value] = s["max"]
        measured["mean_relative_error_percent"][kind.value] = s["mean"]
        measured["curves"][kind.value] = len(errors)
    header = ["", *[k.value for k in CLASSES]]
    rows = []
    for stat in ("min", "max", "mean"):
        key = f"{stat}_relative_error_percent"
        rows.append([f"thesis {stat} %", *[TABLE_3_3_THESIS[key][k.value] for k in CLASSES]])
        rows.append([f"{stat} %", *[measured[key][k.value] for k in CLASSES]])
    rows.append(["curves", *[measured["curves"][k.value] for k in CLASSES]])
    text = (
        "**Table 3.3** relative error sqrt(sum(((p - p_hat)/p)^2)) of the recovered shape "
        f"parameters over random curves of each class; {experiment.describe()}.\n\n"
        + markdown_table(header, rows, digits=3)
    )
    return TableResult("3.3", TABLE_3_3_THESIS, measured, asdict(experiment), text)


def recognition_rates(records: list[dict[str, Any]], experiment: CurveExperiment) -> TableResult:
    """Confusion matrix of the recognition tree (thesis Fig. 3.4) over random curves of
    every class, from the records of ``classify_random_curves``."""
    labels = [*(k.value for k in CLASSES), CurveKind.UNCLASSIFIED.value]
    truths = list(dict.fromkeys(r["kind"] for r in records))
    matrix = {t: dict.fromkeys(labels, 0) for t in truths}
    for r in records:
        matrix[r["kind"]][r["recognized"]] += 1
    rate: dict[str, float] = {}
    for t in truths:
        expected = t if t in labels else CurveKind.UNCLASSIFIED.value
        rate[t] = matrix[t][expected] / max(sum(matrix[t].values()), 1)
    header = ["true \\ recognised", *labels, "correct %"]
    rows = [[t, *matrix[t].values(), 100 * rate[t]] for t in truths]
    text = (
        "**Recognition rates** of the tree (Fig. 3.4) from sampled points; a quartic "
        f"belongs to no class and should be unclassified; {experiment.describe()}.\n\n"
        + markdown_table(header, rows, digits=4)
    )
    measured: dict[str, Any] = {"confusion": matrix, "correct_rate": rate}
    return TableResult("recognition", {}, measured, asdict(experiment), text)
