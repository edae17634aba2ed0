"""The thesis's tables and figures reproduced in one call: which ones, and where they go."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from recognition.files import write_json_atomic
from recognition.reproduction import chapter3, chapter4_closed_form
from recognition.reproduction.tables import TableResult

__all__ = ["TABLES", "ReproductionConfig", "TableMaker", "reproduce"]

#: Every table that can be reproduced, in order (``recognition``: the confusion matrix of
#: Chapter 3's recognition tree).
TABLES = ("3.1", "3.2", "3.3", "3.4", "3.5", "recognition", "fig4.5", "4.2", "4.3", "4.5")

#: Makes one table.
TableMaker = Callable[[], TableResult]


@dataclass(frozen=True)
class ReproductionConfig:
    """What to reproduce, and where to write it.

    Attributes
    ----------
    tables : tuple of str
        Table names (``3.1`` ... ``3.5``, ``recognition`` for the confusion matrix;
        ``fig4.5``, ``4.2``, ``4.3``, ``4.5`` for the closed-form surfaces of Chapter 4).
    json_path : Path or None
        Write the JSON here: one object for one table, a list for several.
    figures_dir : Path or None
        Write the PNG figures here.
    curves : int
        Random curves per class for Table 3.3 and the recognition rates.
    workers : int or None
        Worker processes (default: all cores) for Table 3.3, the recognition rates and
        the 40 recognition tests of Tables 4.2-4.3.
    seed : int
    """

    tables: tuple[str, ...] = TABLES
    json_path: Path | None = None
    figures_dir: Path | None = None
    curves: int = 100
    workers: int | None = None
    seed: int = 0


def _makers(config: ReproductionConfig) -> dict[str, TableMaker]:
    """How each table is made from synthetic data (Tables 3.3 and ``recognition`` share
    their random curves)."""
    experiment = chapter3.CurveExperiment(seed=config.seed)
    joystick = chapter3.JoystickExperiment(seed=config.seed)
    surfaces = chapter4_closed_form.SurfaceExperiment(seed=config.seed)
    solids = chapter4_closed_form.SolidExperiment(seed=config.seed)
    shared: dict[str, Any] = {}

    def records() -> Any:
        if "records" not in shared:
            shared["records"] = chapter3.classify_random_curves(
                experiment, config.curves, workers=config.workers
            )
        return shared["records"]

    return {
        "3.1": lambda: chapter3.table_3_1(experiment),
        "3.2": lambda: chapter3.table_3_2(experiment),
        "3.3": lambda: chapter3.table_3_3(records(), experiment),
        "recognition": lambda: chapter3.recognition_rates(records(), experiment),
        "3.4": lambda: chapter3.table_3_4(joystick),
        "3.5": lambda: chapter3.table_3_5(replace(experiment, spacing=0.005)),
        "fig4.5": lambda: chapter4_closed_form.fig_4_5(surfaces),
        "4.2": lambda: chapter4_closed_form.table_4_2(surfaces, config.workers),
        "4.3": lambda: chapter4_closed_form.table_4_3(surfaces, config.workers),
        "4.5": lambda: chapter4_closed_form.table_4_5(solids),
    }


def reproduce(
    config: ReproductionConfig,
    *,
    makers: Mapping[str, TableMaker] | None = None,
    echo: Callable[[str], object] = print,
) -> list[TableResult]:
    """Compute the requested tables (and figures, and the JSON); returns the results.

    Parameters
    ----------
    config : ReproductionConfig
    makers : mapping of str to callable, optional
        Tables made otherwise than from synthetic data (e.g. from a simulated robot's
        points), by name.
    echo : callable
        Shows each table's Markdown and time, and each file written.
    """
    made = _makers(config) | dict(makers or {})
    results = []
    for name in config.tables:
        if name not in made:
            raise ValueError(f"unknown table {name!r}; expected one of {', '.join(TABLES)}")
        start = time.perf_counter()
        result = made[name]()
        echo(result.markdown)
        echo(f"\n({time.perf_counter() - start:.1f} s)\n")
        results.append(result)
    if config.figures_dir is not None:
        joystick = chapter3.JoystickExperiment(seed=config.seed)
        surfaces = chapter4_closed_form.SurfaceExperiment(seed=config.seed)
        paths = chapter3.figures(config.figures_dir, joystick)
        paths += chapter4_closed_form.figures(config.figures_dir, surfaces, config.workers)
        for path in paths:
            echo(f"wrote {path}")
    if config.json_path is not None:
        payload = [r.to_json() for r in results]
        write_json_atomic(config.json_path, payload[0] if len(payload) == 1 else payload)
        echo(f"wrote {config.json_path}")
    return results
