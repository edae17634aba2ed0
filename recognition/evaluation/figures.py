"""PNG figures of benchmark records: sweeps (Figs. 4.11-4.13) and registration-error images.

matplotlib is imported when a figure is drawn (with the Agg backend), not with the module.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from recognition.evaluation.models import CLOSED_FORM_METHOD
from recognition.evaluation.records import Record
from recognition.evaluation.reports import finite_errors, first_instances
from recognition.evaluation.summary import MethodSummary

__all__ = ["catalog_sessions_figure", "pyplot", "solids_figure", "sweep_figure"]


def pyplot() -> Any:
    """matplotlib.pyplot with the Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def sweep_figure(
    results: Mapping[float, MethodSummary], parameter: str, figure: str, path: Path
) -> None:
    """Success rate and median time against the swept ``parameter`` (thesis ``figure``)."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.5))
    xs = list(results)
    ax[0].plot(xs, [100 * results[v].success_rate for v in xs], "o-")
    ax[0].set(xlabel=parameter, ylabel="success %", ylim=(0, 105), title=f"{figure}: success rate")
    ax[1].plot(xs, [results[v].median_time_s for v in xs], "o-")
    ax[1].set(xlabel=parameter, ylabel="median recognition time s", title="time")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _error_image(ax: Any, first: Mapping[str, Record], names: Sequence[str], title: str) -> Any:
    """log10 registration errors, rows: models, columns: objects; each column's least
    error framed in red."""
    from matplotlib.patches import Rectangle

    columns = [o for o in names if o in first]
    matrix = np.array(
        [[first[o].errors_mm.get(m) or np.nan for o in columns] for m in names], dtype=float
    )
    image = ax.imshow(np.log10(matrix), cmap="viridis")
    ax.set_xticks(range(len(columns)), columns, rotation=60, ha="right")
    ax.set_yticks(range(len(names)), names)
    for j, o in enumerate(columns):
        finite = finite_errors(first[o].errors_mm)
        if finite:
            i = list(names).index(min(finite, key=finite.__getitem__))
            ax.add_patch(
                Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, edgecolor="red", linewidth=2)
            )
    ax.set(xlabel="object", ylabel="model", title=title)
    return image


def catalog_sessions_figure(records: Sequence[Record], names: Sequence[str], path: Path) -> None:
    """Registration errors of session 0 of each object (Table 4.6 analogue) and the
    localisation error of every session, from the data and the reference points."""
    plt = pyplot()
    method = "fast" if any(r.method == "fast" for r in records) else records[0].method
    rs = sorted((r for r in records if r.method == method), key=lambda r: (r.model, r.index))
    first = first_instances(rs, method)
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    image = _error_image(ax[0], first, names, f"log10 registration error mm ({method}, session 0)")
    fig.colorbar(image, ax=ax[0], shrink=0.8)
    x = np.arange(len(rs))
    sensed = [r.localization_error_mm or np.nan for r in rs]
    reference = [(r.reference and r.reference.localization_error_mm) or np.nan for r in rs]
    ax[1].semilogy(x, sensed, "o", label=f"{rs[0].info.get('curves', 'data')} points" if rs else "")
    ax[1].semilogy(x, reference, "x", label="reference points")
    for k, r in enumerate(rs):
        if not r.success:
            ax[1].axvline(k, color="red", alpha=0.3)
    ax[1].set_xticks(x, [r.instance for r in rs], rotation=90, fontsize=7)
    ax[1].set(ylabel="localisation error mm", title="localisation error per session")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def solids_figure(records: Sequence[Record], names: Sequence[str], path: Path) -> None:
    """Least registration errors of session 0 of each Fig. 4.15 solid (Table 4.5 analogue)."""
    plt = pyplot()
    first = first_instances(records, CLOSED_FORM_METHOD)
    fig, ax = plt.subplots(figsize=(6, 5))
    image = _error_image(ax, first, names, "log10 minimum registration error mm (session 0)")
    fig.colorbar(image, ax=ax, shrink=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
