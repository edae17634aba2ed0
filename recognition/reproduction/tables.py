"""A reproduced table: the thesis's values, the measured ones, the settings, and Markdown."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["TableResult", "markdown_table", "save_figure"]


@dataclass(frozen=True)
class TableResult:
    """One reproduced table or experiment.

    Attributes
    ----------
    table : str
        Thesis table name, e.g. ``"3.3"``.
    thesis : dict
        The values printed in the thesis.
    measured : dict
        The values measured here, same keys where they correspond.
    settings : dict
        Everything the measurement depended on (sampling, noise, estimator, seeds).
    markdown : str
        Human-readable side-by-side table.
    """

    table: str
    thesis: dict[str, Any]
    measured: dict[str, Any]
    settings: dict[str, Any] = field(default_factory=dict)
    markdown: str = ""

    def to_json(self) -> dict[str, Any]:
        """The JSON form ``{"table", "thesis", "measured", "settings"}`` (finite floats)."""
        return _finite(
            {
                "table": self.table,
                "thesis": self.thesis,
                "measured": self.measured,
                "settings": self.settings,
            }
        )

    def dumps(self) -> str:
        """:meth:`to_json` as indented JSON text."""
        return json.dumps(self.to_json(), indent=2)


def _finite(value: Any) -> Any:
    """Replace NaN/inf by None recursively so the JSON is standard."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
        return _finite(value.item())
    return value


def _cell(value: Any, digits: int) -> str:
    """One Markdown cell: ``-`` for None and non-finite numbers."""
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if isinstance(value, int):
        return str(value)
    if not math.isfinite(value):
        return "-"
    return f"{value:.{digits}g}"


def markdown_table(header: list[str], rows: list[list[Any]], digits: int = 5) -> str:
    """A Markdown table; numbers shown with ``digits`` significant digits."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(v, digits) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def save_figure(fig: Any, path: Path) -> Path:
    """Writes a matplotlib figure as a PNG (tight layout, 110 dpi), closes it, returns path."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
