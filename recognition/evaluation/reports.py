"""Markdown reports of benchmark records: summary, Tables 4.4, 4.6 and 4.7 analogues, sweeps."""

from __future__ import annotations

import os
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from recognition.evaluation.records import Record
from recognition.evaluation.summary import MethodSummary
from recognition.reproduction.tables import markdown_table
from recognition.surfaces.database import ModelDatabase

__all__ = [
    "RunInfo",
    "catalog_report",
    "confusion_table",
    "error_matrix",
    "finite_errors",
    "first_instances",
    "machine",
    "summary_table",
    "sweep_report",
]

#: Databases of more models than this get no model-by-object matrices in their report.
MAX_MATRIX_MODELS = 20


def machine() -> str:
    """The machine a report was measured on: architecture, cores, Python."""
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


@dataclass(frozen=True)
class RunInfo:
    """How a benchmark was run, for the head of its reports.

    Attributes
    ----------
    command : str
        The command line, as Markdown (e.g. in backticks).
    started : str
        Date and time the run started.
    workers : int
    backend : str
    """

    command: str
    started: str
    workers: int
    backend: str

    def header(self, title: str, *, workers: bool = True) -> list[str]:
        """The report's title, command and date lines (each date line ends a paragraph
        line with two spaces)."""
        date = f"Date: {self.started}; machine: {machine()}"
        date += f"; workers: {self.workers} ({self.backend}).  " if workers else ".  "
        return [f"# {title}", "", f"Command: {self.command}  ", date]


def finite_errors(errors: Mapping[str, float | None]) -> dict[str, float]:
    """The models with an error (those not rejected at table lookup)."""
    return {k: v for k, v in errors.items() if v is not None}


def first_instances(records: Sequence[Record], method: str) -> dict[str, Record]:
    """Instance 0 of every model recognised with ``method`` (models without errors left out)."""
    return {r.model: r for r in records if r.method == method and r.index == 0 and r.errors_mm}


def summary_table(summary: Mapping[str, MethodSummary], *, reference: bool = False) -> str:
    """One row per method; ``reference`` adds the reference curves' success rate."""
    header = ["method", "instances", "success %"]
    header += ["reference success %"] if reference else []
    header += ["median time s", "p90 time s", "median localisation error mm"]
    rows = []
    for m, s in summary.items():
        row: list[Any] = [m, s.instances, 100 * s.success_rate]
        if reference:
            rate = s.reference_success_rate
            row.append(None if rate is None else 100 * rate)
        row += [s.median_time_s, s.p90_time_s, s.median_localization_error_mm]
        rows.append(row)
    return markdown_table(header, rows, digits=4)


def error_matrix(
    first: Mapping[str, Record],
    names: Sequence[str],
    field: str,
    *,
    bold_min: bool,
    thesis: Mapping[str, Mapping[str, float]] | None = None,
) -> str:
    """Rows: models, columns: objects (thesis layout) of ``field`` (``errors_mm`` or
    ``times_s``) of each object's record; the column minimum in bold; the thesis's values
    in brackets."""
    columns = [o for o in names if o in first]
    rows = []
    for m in names:
        row = [m]
        for o in columns:
            values: Mapping[str, float | None] = getattr(first[o], field)
            value = values.get(m)
            cell = "-" if value is None else f"{value:.3g}"
            if thesis is not None:
                cell += f" ({thesis[o][m]:.3f})"
            finite = finite_errors(values)
            if bold_min and value is not None and m == min(finite, key=finite.__getitem__):
                cell = f"**{cell}**"
            row.append(cell)
        rows.append(row)
    return markdown_table(["model \\ object", *columns], rows)


def confusion_table(
    records: Sequence[Record], method: str, names: Sequence[str], *, every_model: bool = False
) -> str:
    """Rows: true object, columns: recognised (``None``: no model fits), counts of
    ``method``'s records; ``every_model`` keeps rows without records."""
    confusion: dict[str, dict[str, int]] = {}
    for r in records:
        if r.method == method:
            row = confusion.setdefault(r.model, {})
            row[str(r.recognized)] = row.get(str(r.recognized), 0) + 1
    labels = [*names, "None"]
    return markdown_table(
        ["object", *labels],
        [
            [o, *[confusion.get(o, {}).get(c, 0) for c in labels]]
            for o in names
            if every_model or o in confusion
        ],
    )


def catalog_report(
    name: str,
    run: RunInfo,
    settings: str,
    database: ModelDatabase,
    records: Sequence[Record],
    summary: Mapping[str, MethodSummary],
) -> str:
    """The report of a synthetic benchmark (thesis Section 4.3.4) on a mesh database.

    Parameters
    ----------
    name : str
        The database's name (title).
    run : RunInfo
    settings : str
        The instances' settings, one paragraph (ends with where the records are).
    database : ModelDatabase
        For the models' table sizes and build times (Table 4.4 analogue).
    records, summary
        The run's records and their summary per method.
    """
    lines = [
        *run.header(f"Recognition benchmark: {name}"),
        settings,
        "",
        "## Summary",
        "",
        summary_table(summary),
    ]
    if "fast" in summary:
        for other in ("icp-baseline", "thesis"):
            if other in summary:
                both = {r.instance for r in records if r.method == other}
                fast_t = [r.time_s for r in records if r.method == "fast" and r.instance in both]
                other_t = [r.time_s for r in records if r.method == other]
                lines += [
                    "",
                    f"fast vs {other} on the same {len(both)} instances: median time "
                    f"{np.median(fast_t):.3g} s vs {np.median(other_t):.3g} s "
                    f"({np.median(other_t) / np.median(fast_t):.1f}x).",
                ]
    names = database.names
    first = {r.model: r for r in records if r.method == "fast" and r.instance.endswith("/0")}
    if first and len(names) > MAX_MATRIX_MODELS:
        lines += [
            "",
            f"Tables 4.6-4.7 analogues (every model against every object) left out for "
            f"{len(names)} models; the records hold every model's error and time.",
        ]
    elif first:
        lines += [
            "",
            "## Registration errors (mm), Table 4.6 analogue (fast, instance 0 of "
            "each object; columns: object, rows: model; '-' rejected at table lookup)",
            "",
        ]
        rows: list[list[Any]] = [
            [m, *[first[o].errors_mm.get(m) if o in first else None for o in names]] for m in names
        ]
        lines.append(markdown_table(["model \\ object", *names], rows, digits=3))
        lines += ["", "## Registration times (s), Table 4.7 analogue (same instances)", ""]
        rows = [
            [m, *[first[o].times_s.get(m) if o in first else None for o in names]] for m in names
        ]
        rows.append(["recognition", *[first[o].time_s if o in first else None for o in names]])
        lines.append(markdown_table(["model \\ object", *names], rows, digits=3))
    lines += ["", "## Model tables, Table 4.4 analogue", ""]
    rows = []
    for m in names:
        model = database[m]
        t = model.timings
        rows.append(
            [
                m,
                len(model.vertices),
                len(model.faces),
                " x ".join(f"{x * 1e3:.1f}" for x in np.ptp(model.vertices, axis=0)),
                len(model.table),
                t.get("sampling_s"),
                t.get("curvatures_s"),
                (t.get("sampling_s") or 0) + (t.get("curvatures_s") or 0),
                t.get("vertex_curvatures_s"),
                t.get("distance_field_s"),
            ]
        )
    lines.append(
        markdown_table(
            [
                "model",
                "vertices",
                "triangles",
                "dimension mm",
                "sample vertices",
                "sampling s",
                "curvatures s",
                "table s",
                "vertex curvature map s",
                "distance field s",
            ],
            rows,
            digits=3,
        )
    )
    if any(r.method == "fast" for r in records):
        lines += ["", "## Confusion (fast, all instances; rows: object, columns: recognised)", ""]
        lines.append(confusion_table(records, "fast", names, every_model=True))
    return "\n".join(lines) + "\n"


def sweep_report(
    parameter: str,
    figure: str,
    name: str,
    run: RunInfo,
    settings: str,
    results: Mapping[float, MethodSummary],
    image: str,
    thesis: str,
) -> str:
    """The report of a sweep of one parameter (thesis Figs. 4.11-4.13), fast mode.

    Parameters
    ----------
    parameter : str
        The swept setting (the table's first column).
    figure : str
        The thesis figure (e.g. ``"Fig. 4.11"``).
    name : str
        The database's name.
    run : RunInfo
    settings : str
        The other settings, one paragraph.
    results : mapping of value to MethodSummary
    image : str
        File name of the sweep's figure.
    thesis : str
        What the thesis reports of this sweep.
    """
    table = markdown_table(
        [parameter, "instances", "success %", "median time s", "p90 time s", "median loc. err. mm"],
        [
            [
                v,
                r.instances,
                100 * r.success_rate,
                r.median_time_s,
                r.p90_time_s,
                r.median_localization_error_mm,
            ]
            for v, r in results.items()
        ],
    )
    return "\n".join(
        [
            *run.header(f"Sweep of {parameter}, thesis {figure} ({name}, fast mode)"),
            settings,
            "",
            f"![{figure}]({image})",
            "",
            table,
            "",
            f"Thesis ({figure}): {thesis}.",
            "",
        ]
    )
