"""Markdown reports of the simulated robot's experiments (Tables 4.5-4.7 analogues, sensing)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from recognition.evaluation import CLOSED_FORM_METHOD, MethodSummary, Record
from recognition.evaluation.reports import (
    RunInfo,
    confusion_table,
    error_matrix,
    finite_errors,
    first_instances,
    summary_table,
)
from recognition.reproduction.chapter4_closed_form import TABLE_4_5_THESIS, SolidExperiment
from recognition.reproduction.tables import markdown_table
from tactile_sim.evaluation.accuracy import (
    SCRIPT_PARTS,
    AccuracyResult,
    TimingResult,
)
from tactile_sim.evaluation.sessions import SimulatedSource

__all__ = [
    "SESSION_HEADER",
    "catalog_sessions_report",
    "sensing_report",
    "session_rows",
    "solids_report",
]

#: Columns of the per-session table (:func:`session_rows`).
SESSION_HEADER = [
    "instance",
    "seed",
    "recognised",
    "own error mm",
    "margin mm",
    "localisation error mm",
    "recognised (reference)",
    "localisation error (reference) mm",
    "sensed error mean mm",
    "sensed error max mm",
    "spacing mm",
    "truncated sides",
    "probing s",
    "recognition s",
]


def _session_range(source: SimulatedSource) -> str:
    last = source.first_session + source.sessions_per_object - 1
    return f"sessions {source.first_session}-{last}" if last > 0 else "session 0"


def _header(run: RunInfo, title: str, source: SimulatedSource, records_path: str) -> list[str]:
    other = "true contact" if source.curves == "sensed" else "sensed"
    return [
        *run.header(title),
        f"Probing: {len(source.objects)} objects x {source.sessions_per_object} sessions "
        f"({_session_range(source)}, seeds from --seed {source.seed}); "
        f"{source.n_points} points per curve at d = {source.spacing_m * 1e3:g} mm, "
        f"planes {source.plane_angle_deg:g} deg apart; "
        f"recognised from the {source.curves.replace('_', ' ')} points, and from the "
        f"{other} points of the same session as the reference. Records: `{records_path}`.",
        "",
    ]


def _model_error_lines(source: SimulatedSource, records: Sequence[Record]) -> list[str]:
    """The model error asked for and achieved, when the objects were displaced."""
    if source.model_error_m == 0:
        return []
    achieved = [
        r.info["model_error_rms_mm"]
        for r in records
        if r.method == "fast" and "model_error_rms_mm" in r.info
    ]
    spread = (
        f"achieved {min(achieved):.3f}-{max(achieved):.3f} mm RMS (median "
        f"{float(np.median(achieved)):.3f} mm) over {len(achieved)} sessions"
        if achieved
        else "no session probed"
    )
    return [
        "",
        f"Model error: every probed object is its model displaced along the normals by a "
        f"smooth random field (seeded per session, correlation length "
        f"{source.model_error_correlation_m * 1e3:g} mm) of RMS "
        f"{source.model_error_m * 1e3:g} mm; {spread}. The database holds the models.",
    ]


def _within_line(records: Sequence[Record], summary: Mapping[str, MethodSummary]) -> str:
    """How many sessions each method localised within 1 mm (and 0.1 mm)."""
    parts = []
    for method in summary:
        errors = [r.localization_error_mm for r in records if r.method == method]
        located = [e for e in errors if e is not None]
        parts.append(
            f"{method} {sum(e <= 1.0 for e in located)}/{len(errors)} within 1 mm "
            f"({sum(e <= 0.1 for e in located)} within 0.1 mm)"
        )
    return "Localisation of the sessions: " + "; ".join(parts) + "."


def session_rows(records: Sequence[Record], method: str) -> list[list[Any]]:
    """One row per session recognised with ``method`` (columns :data:`SESSION_HEADER`)."""
    rows = []
    for r in sorted((r for r in records if r.method == method), key=lambda r: (r.model, r.index)):
        errors = finite_errors(r.errors_mm)
        own = errors.get(r.model)
        others = [v for k, v in errors.items() if k != r.model]
        ref = r.reference
        info = r.info
        error = r.instance_error
        rows.append(
            [
                r.instance,
                r.seed,
                str(r.recognized),
                own,
                (min(others) - own) if own is not None and others else None,
                r.localization_error_mm,
                str(ref.recognized) if ref else "-",
                ref.localization_error_mm if ref else None,
                info.get("sensed_error_mean_mm"),
                info.get("sensed_error_max_mm"),
                (
                    f"{info['spacing_mean_mm']:.3f} +- {info['spacing_std_mm']:.3f}"
                    if "spacing_mean_mm" in info
                    else "-"
                ),
                len(info.get("truncated", [])) if error is None else error,
                info.get("probe_time_s"),
                r.time_s,
            ]
        )
    return rows


def catalog_sessions_report(
    run: RunInfo,
    source: SimulatedSource,
    names: Sequence[str],
    records: Sequence[Record],
    summary: Mapping[str, MethodSummary],
    records_path: str,
    *,
    delta_per_mm: float,
    thesis_instances: int,
) -> str:
    """The catalog experiment's report: Tables 4.6 and 4.7 analogues, confusion, sessions.

    Parameters
    ----------
    run : RunInfo
    source : SimulatedSource
        How the sessions were probed.
    names : sequence of str
        The catalog's models, in the database's order.
    records, summary
        The experiment's records and their summary per method.
    records_path : str
        Where the records are, as shown.
    delta_per_mm : float
        The lookup tolerance.
    thesis_instances : int
        Sessions run in thesis mode (0: all).
    """
    lines = _header(
        run,
        "Simulated robot experiment on the catalog: Tables 4.6 and 4.7 analogue",
        source,
        records_path,
    )
    lines += [
        f"Lookup tolerance delta = {delta_per_mm} 1/mm; thesis mode on the first "
        f"{thesis_instances or 'all'} instances. 'reference': the same sessions "
        "recognised from the other point set (see above).",
        *_model_error_lines(source, records),
        "",
        "## Summary",
        "",
        summary_table(summary, reference=True),
        "",
        _within_line(records, summary),
    ]
    method = "fast" if "fast" in summary else next(iter(summary), None)
    if method is None:
        return "\n".join(lines) + "\n"
    first = first_instances(records, method)
    lines += [
        "",
        f"## Table 4.6 analogue: registration errors (mm), {method}, session 0 of each "
        "object (columns: object, rows: model; '-' rejected at table lookup; column "
        "minimum in bold)",
        "",
        error_matrix(first, names, "errors_mm", bold_min=True),
        "",
        f"## Table 4.7 analogue: registration times (s), {method}, same sessions",
        "",
        error_matrix(first, names, "times_s", bold_min=False),
        "",
        "Recognition time (all models, local geometry included): "
        + ", ".join(f"{o} {first[o].time_s:.3g} s" for o in names if o in first)
        + ".",
        "",
        f"## Confusion ({method}, all sessions; rows: object, columns: recognised)",
        "",
        confusion_table(records, method, names),
        "",
        f"## Sessions ({method})",
        "",
        markdown_table(SESSION_HEADER, session_rows(records, method), digits=3),
    ]
    return "\n".join(lines) + "\n"


def solids_report(
    run: RunInfo,
    source: SimulatedSource,
    names: Sequence[str],
    records: Sequence[Record],
    summary: Mapping[str, MethodSummary],
    records_path: str,
    experiment: SolidExperiment,
) -> str:
    """The solids experiment's report: the Table 4.5 analogue (thesis values in
    brackets), every session's errors, confusion, sessions.

    ``experiment`` holds the registration settings (lookup tolerance, candidates).
    """
    lines = _header(
        run,
        "Simulated robot experiment on the Fig. 4.15 solids: Table 4.5 analogue",
        source,
        records_path,
    )
    method = CLOSED_FORM_METHOD
    lines += [
        f"Registration onto the four closed-form models (thesis Section 4.2.2), table "
        f"lookup tolerance {experiment.delta_per_m} 1/m, {experiment.max_candidates} "
        "candidates. The thesis's values are in brackets.",
        "",
        "## Summary",
        "",
        summary_table(summary, reference=True),
    ]
    first = first_instances(records, method)
    diagonal = []
    for o in first:
        finite = finite_errors(first[o].errors_mm)
        if min(finite, key=finite.__getitem__) == o:
            diagonal.append(o)
    lines += [
        "",
        "## Table 4.5 analogue: minimum registration error (mm), session 0 of each solid "
        "(columns: object, rows: model; column minimum in bold)",
        "",
        error_matrix(
            first, names, "errors_mm", bold_min=True, thesis=TABLE_4_5_THESIS["min_error_mm"]
        ),
        "",
        f"Columns whose minimum is on the diagonal: {len(diagonal)} / {len(first)}.",
    ]
    if source.sessions_per_object > 1:
        lines += [
            "",
            "## Every session: registration errors (mm)",
            "",
            markdown_table(
                ["instance", *names, "recognised"],
                [
                    [r.instance, *[r.errors_mm.get(m) for m in names], str(r.recognized)]
                    for r in sorted(records, key=lambda r: (r.model, r.index))
                    if r.method == method
                ],
                digits=3,
            ),
        ]
    lines += [
        "",
        "## Confusion (all sessions; rows: object, columns: recognised)",
        "",
        confusion_table(records, method, names),
        "",
        "## Sessions",
        "",
        markdown_table(SESSION_HEADER, session_rows(records, method), digits=3),
    ]
    return "\n".join(lines) + "\n"


def sensing_report(
    run: RunInfo,
    objects: Sequence[str],
    sessions: int,
    seed: int,
    accuracy: AccuracyResult,
    timing: TimingResult,
    script_seconds: Sequence[dict[str, float]],
) -> str:
    """The sensing experiment's report: each sensed point's error kept apart by cause
    (sensor: sensed point vs MuJoCo's contact on the collider; geometry: that contact vs
    the object's mesh; total: sensed point vs mesh), and wall times of a session and of
    ``scripts/probe.py`` with its parts (the first of ``script_seconds`` a cold or first
    run, the others warm)."""
    figures = accuracy.summary()

    across = ("sensor", "geometry", "total")

    def row(name: str, o: dict[str, Any]) -> list[Any]:
        cells = [o[f"{w}_{k}"] for w in across for k in ("mean_mm", "p95_mm", "max_mm")]
        return [name, o["n_points"], *cells]

    rows = [row(name, o) for name, o in figures["objects"].items()]
    rows.append(row("all", figures))
    counts: list[list[Any]] = [
        [
            name,
            o["lateral_mean_mm"],
            o["lateral_p95_mm"],
            o["lateral_max_mm"],
            o["contacts_missing"],
            o["truncated_sweeps"],
            o["stylus_contacts"],
        ]
        for name, o in figures["objects"].items()
    ]
    warm = list(script_seconds[1:])
    name = timing.name
    walls: list[list[Any]] = [
        [label, len(v), min(v), float(np.median(v)), max(v)]
        for label, v in (
            (f"session on {name}: scene build", timing.build_seconds),
            (f"session on {name}: three sweeps", timing.probe_seconds),
            (f"session on {name}: probe_object total", timing.session_seconds),
            *(
                (f"`scripts/probe.py --object {name}`, warm: {part}", [w[key] for w in warm])
                for part, key in SCRIPT_PARTS
            ),
        )
    ]
    header = ["object", "points"] + [f"{w} {k}" for w in across for k in ("mean", "p95", "max")]
    return "\n".join(
        [
            *run.header("Simulated sensing: accuracy and speed", workers=False),
            f"{len(objects)} objects x {sessions} sessions (3 sweeps x 21 points at "
            "1.2 mm, random pose, p and plane yaw per seed; seeds from "
            f"--seed {seed}). Distances to the meshes are exact "
            "(point-triangle), over the probed regions only.",
            "",
            "## Errors of the sensed points (mm)",
            "",
            "Across the surfaces. sensor: sensed point to the surface the tip touched (the "
            "collider's tangent plane at MuJoCo's contact point); geometry: MuJoCo's contact "
            "point to the object's mesh (how far the collider lies from the object where "
            "the probe touches); total: sensed point to the mesh.",
            "",
            markdown_table(header, rows, digits=4),
            "",
            "Along the surface: the sensed point's offset from MuJoCo's contact point "
            "(the tip's slide under friction between the contact and the reading), and the "
            "session's events.",
            "",
            markdown_table(
                [
                    "object",
                    "lateral mean",
                    "lateral p95",
                    "lateral max",
                    "readings without contact",
                    "truncated sweeps",
                    "shaft contacts",
                ],
                counts,
                digits=4,
            ),
            "",
            "## Wall time (s)",
            "",
            markdown_table(["what", "runs", "min", "median", "max"], walls, digits=3),
            "",
            f"Simulated time per session: {float(np.median(timing.sim_seconds)):.1f} s. "
            f"The first `scripts/probe.py` run took {script_seconds[0]['wall']:.2f} s "
            "(caches already warm unless this was a fresh checkout). The script's parts: "
            "Python start-up and imports (wall less the script's own total), the object's "
            "meshes, the database load, the probing session (scene build included) and "
            "recognition.",
            "",
        ]
    )
