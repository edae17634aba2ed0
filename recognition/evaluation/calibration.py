"""How far the belief's confidence can be trusted, and what the verification touches bought.

An answer is *right* when the belief's best hypothesis names the true model and puts p
within 1 mm of the truth (up to the model's symmetries,
:meth:`~recognition.evaluation.records.Record.answered_right`). The reliability diagram
bins the answers by confidence and sets each bin's mean confidence against its fraction
right; the expected calibration error (ECE) is the mean gap, weighted by the bins' counts.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from recognition.evaluation.diagnosis import (
    APART_SDS,
    CAUSES,
    TELLING_SHARE,
    cause,
    touch_could_tell,
)
from recognition.evaluation.records import Record, read_results
from recognition.evaluation.reports import machine
from recognition.files import write_json_atomic

__all__ = [
    "SURE",
    "miss_causes",
    "pooled_report",
    "reliability",
    "reliability_figure",
    "touch_summary",
    "touches_section",
]

#: Answers given with at least this confidence are *sure* (the loop stops there).
SURE = 0.99


def _answers(records: Sequence[Record], after_touches: bool) -> tuple[np.ndarray, np.ndarray]:
    """(confidence, right) of every record with a belief."""
    rows = [r for r in records if r.confidence is not None]
    confidence = np.array(
        [
            r.touches["confidence"] if after_touches and r.touches is not None else r.confidence
            for r in rows
        ],
        dtype=float,
    )
    right = np.array([r.answered_right(after_touches) for r in rows], dtype=bool)
    return confidence, right


def reliability(
    records: Sequence[Record], *, after_touches: bool = False, bins: int = 10
) -> dict[str, Any]:
    """The reliability diagram of the records' answers (after the curves, or after the
    touches), JSON-ready: ``answers``, ``right``, ``ece``, ``sure`` (answers with
    confidence >= :data:`SURE`) and ``sure_right`` (the fraction of them right, None
    without one), and per bin ``bins``: ``low``, ``high``, ``count``,
    ``mean_confidence``, ``fraction_right``."""
    confidence, right = _answers(records, after_touches)
    edges = np.linspace(0.0, 1.0, bins + 1)
    index = np.clip(np.digitize(confidence, edges) - 1, 0, bins - 1)
    rows, ece = [], 0.0
    for b in range(bins):
        mine = index == b
        count = int(mine.sum())
        row: dict[str, Any] = {"low": float(edges[b]), "high": float(edges[b + 1]), "count": count}
        if count:
            row["mean_confidence"] = float(confidence[mine].mean())
            row["fraction_right"] = float(right[mine].mean())
            ece += count * abs(row["mean_confidence"] - row["fraction_right"])
        rows.append(row)
    sure = confidence >= SURE
    return {
        "answers": len(confidence),
        "right": float(right.mean()) if len(right) else None,
        "ece": float(ece / len(confidence)) if len(confidence) else None,
        "sure": int(sure.sum()),
        "sure_right": float(right[sure].mean()) if sure.any() else None,
        "bins": rows,
    }


def touch_summary(records: Sequence[Record]) -> dict[str, Any] | None:
    """What the touches did, JSON-ready (None when no record made touches): answers right
    after the curves and after the touches, the median distance of the answer's p from the
    truth after the touches (an answer naming another model counts as infinitely far;
    None when that makes the median infinite), touches made (median, mean, max), the
    sessions sure after the curves that made none, and the planning and update time per
    touch (median, mean, p90, max)."""
    touched = [r for r in records if r.touches is not None and r.confidence is not None]
    if not touched:
        return None
    made = np.array([r.touches["made"] for r in touched if r.touches is not None])
    times = np.array(
        [t for r in touched if r.touches is not None for t in r.touches["recognition_times_s"]]
    )
    sure_first = [r for r in touched if r.confidence is not None and r.confidence >= SURE]
    located = float(np.median([_located_mm(r) for r in touched]))
    return {
        "instances": len(touched),
        "right_after_curves": float(np.mean([r.answered_right() for r in touched])),
        "right_after_touches": float(np.mean([r.answered_right(True) for r in touched])),
        "recognized_after_touches": float(
            np.mean([bool(r.touches and r.touches["success"]) for r in touched])
        ),
        "localisation_after_touches_median_mm": located if np.isfinite(located) else None,
        "touches_median": float(np.median(made)),
        "touches_mean": float(np.mean(made)),
        "touches_max": int(made.max()),
        "sure_after_curves": len(sure_first),
        "sure_after_curves_touched": int(
            sum(1 for r in sure_first if r.touches is not None and r.touches["made"] > 0)
        ),
        "touch_time_median_s": float(np.median(times)) if times.size else None,
        "touch_time_mean_s": float(np.mean(times)) if times.size else None,
        "touch_time_p90_s": float(np.percentile(times, 90)) if times.size else None,
        "touch_time_max_s": float(times.max()) if times.size else None,
    }


def miss_causes(records: Sequence[Record], after_touches: bool = False) -> dict[str, int]:
    """The wrong answers (after the curves, or after the touches) by cause
    (:func:`~recognition.evaluation.diagnosis.cause`): ``wrong``, then the count of each
    of :data:`~recognition.evaluation.diagnosis.CAUSES` and ``unknown`` (no diagnosis:
    the true pose unknown, or a record written without one), ``measured``, those whose
    diagnosis says how far the answer stands apart from the truth, and ``telling``, those a
    touch could still refute (:func:`~recognition.evaluation.diagnosis.touch_could_tell`)."""
    counts = dict.fromkeys(("wrong", *CAUSES, "unknown", "measured", "telling"), 0)
    for r in records:
        if r.confidence is None or r.answered_right(after_touches):
            continue
        fit = r.touches.get("truth_fit") if after_touches and r.touches else r.truth_fit
        counts["wrong"] += 1
        counts[cause(fit) or "unknown"] += 1
        counts["measured"] += fit is not None and "apart" in fit
        counts["telling"] += touch_could_tell(fit)
    return counts


def _causes_text(counts: Mapping[str, int]) -> str:
    """Markdown: the wrong answers by cause, in words."""
    return (
        f"{counts['wrong']} wrong: {counts['search']} where the true pose fits all the "
        f"contact at least ten times likelier than the answer (no search proposed it), "
        f"{counts['tie']} within ten times either way, {counts['data']} where the data "
        f"favour the answer"
        + (f", {counts['unknown']} not diagnosed" if counts["unknown"] else "")
        + (
            f"; {counts['telling']} of the {counts['measured']} measured stand more than "
            f"{APART_SDS:g} noise sd apart from the truth on at least "
            f"{100 * TELLING_SHARE:g} % of their surface (a touch there would tell)"
            if counts["measured"]
            else ""
        )
    )


def _located_mm(record: Record) -> float:
    """How far the answer after the touches puts p from the truth, mm (inf: another model
    or none)."""
    touches = record.touches or {}
    error = touches.get("answer_error_mm")
    return float(error) if touches.get("success") and error is not None else float("inf")


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def touches_section(records: Sequence[Record], figure_name: str | None = None) -> str:
    """Markdown: the belief's calibration after the curves (and after the touches), and
    what the touches did; empty when no record carries a confidence."""
    if not any(r.confidence is not None for r in records):
        return ""
    lines = [
        "## Confidence and verification touches",
        "",
        "An answer is right when the belief's best hypothesis names the true model and puts "
        "p within 1 mm of the truth (up to the model's symmetries). 'sure': confidence "
        f">= {SURE}. ECE: expected calibration error over 10 bins of confidence.",
        "",
        "| answers | right | sure | right among sure | ECE |",
        "|---|---|---|---|---|",
    ]
    stages = [("after the curves", reliability(records))]
    if any(r.touches is not None for r in records):
        stages.append(("after the touches", reliability(records, after_touches=True)))
    lines[-2] = "| stage | answers | right | sure | right among sure | ECE |"
    lines[-1] = "|---|---|---|---|---|---|"
    for name, stage in stages:
        lines.append(
            f"| {name} | {stage['answers']} | {_percent(stage['right'])} | {stage['sure']} | "
            f"{_percent(stage['sure_right'])} | "
            f"{'-' if stage['ece'] is None else format(stage['ece'], '.3f')} |"
        )
    touched = touch_summary(records)
    if touched is not None:
        lines += [
            "",
            f"Touches: median {touched['touches_median']:g}, mean "
            f"{touched['touches_mean']:.2f}, at most {touched['touches_max']}; "
            f"{touched['sure_after_curves']} answers were sure after the curves, "
            f"{touched['sure_after_curves_touched']} of them touched. Planning and update "
            "per touch: median "
            + (
                "-"
                if touched["touch_time_median_s"] is None
                else f"{touched['touch_time_median_s']:.3f} s, mean "
                f"{touched['touch_time_mean_s']:.3f} s, p90 "
                f"{touched['touch_time_p90_s']:.3f} s, max {touched['touch_time_max_s']:.3f} s"
            )
            + f". Recognised after the touches: {_percent(touched['recognized_after_touches'])}"
            + "; localisation after the touches: median "
            + (
                "beyond reach (most answers name another model)"
                if touched["localisation_after_touches_median_mm"] is None
                else f"{touched['localisation_after_touches_median_mm']:.3g} mm"
            )
            + ".",
        ]
    diagnosed = [(name, miss_causes(records, name == "after the touches")) for name, _ in stages]
    if any(c["wrong"] > c["unknown"] for _, c in diagnosed):
        lines += [
            "",
            "Wrong answers by cause (the true pose scored as a broader search's pose, "
            "`recognition.evaluation.diagnosis`): "
            + "; ".join(f"{name}, {_causes_text(c)}" for name, c in diagnosed)
            + ".",
        ]
    if figure_name:
        lines += ["", f"![reliability]({figure_name})"]
    return "\n".join(lines) + "\n"


def reliability_figure(records: Sequence[Record], path: Path) -> None:
    """PNG: the reliability diagram after the curves (and after the touches, if made)."""
    from recognition.evaluation.figures import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(4.6, 4.2))
    ax.plot([0, 1], [0, 1], color="0.7", lw=1, label="calibrated")
    stages = [("after the curves", reliability(records), "o-")]
    if any(r.touches is not None for r in records):
        stages.append(("after the touches", reliability(records, after_touches=True), "s-"))
    for name, stage, style in stages:
        rows = [b for b in stage["bins"] if b["count"]]
        ax.plot(
            [b["mean_confidence"] for b in rows],
            [b["fraction_right"] for b in rows],
            style,
            label=f"{name} (ECE {stage['ece']:.3f})",
        )
    ax.set(
        xlabel="confidence",
        ylabel="fraction right (model, p within 1 mm)",
        xlim=(0, 1),
        ylim=(0, 1.02),
        title="reliability",
    )
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def pooled_report(
    paths: Sequence[Path], out_dir: Path, name: str, arguments: Sequence[str] = ()
) -> dict[str, Any]:
    """The reliability of the fast-mode answers of several records files pooled:
    ``<name>.md``, ``<name>_reliability.json`` and ``.png`` in ``out_dir``; returns the
    JSON payload (per file: answers, right and sure; pooled: the diagrams and touches).

    Raises
    ------
    InvalidRecords
        A file holds a line that is not a record.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    pooled: list[Record] = []
    files: dict[str, Any] = {}
    for path in paths:
        records = [r for r in read_results(path) if r.method == "fast"]
        pooled += records
        files[Path(path).name] = {
            "after_curves": _brief(reliability(records)),
            "after_touches": _brief(reliability(records, after_touches=True)),
            "causes_after_touches": miss_causes(records, after_touches=True),
        }
    command = "python scripts/calibration.py " + " ".join(arguments)
    payload: dict[str, Any] = {
        "command": command,
        "files": files,
        "after_curves": reliability(pooled),
        "after_touches": reliability(pooled, after_touches=True),
        "touches": touch_summary(pooled),
        "causes_after_curves": miss_causes(pooled),
        "causes_after_touches": miss_causes(pooled, after_touches=True),
    }
    write_json_atomic(out_dir / f"{name}_reliability.json", payload)
    figure = out_dir / f"{name}_reliability.png"
    reliability_figure(pooled, figure)
    lines = [
        "# The belief's reliability, pooled over benchmark runs",
        "",
        f"Command: `{command}`  ",
        f"Date: {time.strftime('%Y-%m-%d %H:%M')}; machine: {machine()}.",
        "",
        "| records | answers | right after the curves | sure | right among sure | "
        "right after the touches | sure | right among sure | wrong: search, tie, data |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for file, row in files.items():
        a, b, c = row["after_curves"], row["after_touches"], row["causes_after_touches"]
        lines.append(
            f"| `{file}` | {a['answers']} | {_percent(a['right'])} | {a['sure']} | "
            f"{_percent(a['sure_right'])} | {_percent(b['right'])} | {b['sure']} | "
            f"{_percent(b['sure_right'])} | {c['search']}, {c['tie']}, {c['data']}"
            + (f" ({c['unknown']} not diagnosed)" if c["unknown"] else "")
            + " |"
        )
    text = "\n".join(lines) + "\n\n" + touches_section(pooled, figure.name)
    (out_dir / f"{name}.md").write_text(text)
    return payload


def _brief(stage: dict[str, Any]) -> dict[str, Any]:
    """A reliability payload without its bins."""
    return {k: v for k, v in stage.items() if k != "bins"}
