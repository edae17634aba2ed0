"""Reproduce the thesis's tables and figures: thesis and measured values side by side.

python scripts/reproduce_thesis.py --table 3.3 --json out/table_3_3.json
python scripts/reproduce_thesis.py --table 4.2 --table 4.3 --json out/chapter4.json
python scripts/reproduce_thesis.py --table all --figures docs/figures
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from recognition.errors import RecognitionError
from recognition.reproduction import chapter3, chapter4_closed_form

TABLES = ("3.1", "3.2", "3.3", "3.4", "3.5", "recognition", "fig4.5", "4.2", "4.3", "4.5")


@dataclass(frozen=True)
class Config:
    """What to reproduce.

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


def run(config: Config) -> list[chapter3.TableResult]:
    """Compute the requested tables (and figures); returns the results."""
    experiment = chapter3.CurveExperiment(seed=config.seed)
    joystick = chapter3.JoystickExperiment(seed=config.seed)
    surfaces = chapter4_closed_form.SurfaceExperiment(seed=config.seed)
    solids = chapter4_closed_form.SolidExperiment(seed=config.seed)
    results = []
    records = None
    for name in config.tables:
        start = time.perf_counter()
        if name == "3.1":
            result = chapter3.table_3_1(experiment)
        elif name == "3.2":
            result = chapter3.table_3_2(experiment)
        elif name in ("3.3", "recognition"):
            if records is None:
                records = chapter3.classify_random_curves(
                    experiment, config.curves, workers=config.workers
                )
            if name == "3.3":
                result = chapter3.table_3_3(records, experiment)
            else:
                result = chapter3.recognition_rates(records, experiment)
        elif name == "3.4":
            result = chapter3.table_3_4(joystick)
        elif name == "3.5":
            result = chapter3.table_3_5(replace(experiment, spacing=0.005))
        elif name == "fig4.5":
            result = chapter4_closed_form.fig_4_5(surfaces)
        elif name == "4.2":
            result = chapter4_closed_form.table_4_2(surfaces, config.workers)
        elif name == "4.3":
            result = chapter4_closed_form.table_4_3(surfaces, config.workers)
        elif name == "4.5":
            result = chapter4_closed_form.table_4_5(solids)
        else:
            raise ValueError(f"unknown table {name!r}; expected one of {', '.join(TABLES)}")
        print(result.markdown)
        print(f"\n({time.perf_counter() - start:.1f} s)\n", flush=True)
        results.append(result)
    if config.figures_dir is not None:
        paths = chapter3.figures(config.figures_dir, joystick)
        paths += chapter4_closed_form.figures(config.figures_dir, surfaces, config.workers)
        for path in paths:
            print(f"wrote {path}")
    if config.json_path is not None:
        payload = [r.to_json() for r in results]
        config.json_path.parent.mkdir(parents=True, exist_ok=True)
        tmp = config.json_path.with_suffix(config.json_path.suffix + ".tmp")
        tmp.write_text(json.dumps(payload[0] if len(payload) == 1 else payload, indent=2))
        tmp.replace(config.json_path)
        print(f"wrote {config.json_path}")
    return results


def parse_args(argv=None) -> Config:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--table",
        action="append",
        choices=(*TABLES, "all"),
        help="table to reproduce (repeatable; default all)",
    )
    parser.add_argument("--json", type=Path, help="write thesis and measured values as JSON")
    parser.add_argument(
        "--figures", type=Path, help="write Figs. 3.1-3.3, 3.7, 4.3, 4.5 and 4.7 as PNGs here"
    )
    parser.add_argument("--curves", type=int, default=100, help="random curves per class")
    parser.add_argument("--workers", type=int, default=None, help="worker processes")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    tables = TABLES if not args.table or "all" in args.table else tuple(args.table)
    if args.curves < 1:
        parser.error("--curves must be at least 1")
    return Config(tables, args.json, args.figures, args.curves, args.workers, args.seed)


def main(argv=None) -> int:
    config = parse_args(argv)
    try:
        run(config)
    except (RecognitionError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
