"""The belief's reliability over the records of several benchmark runs, as one diagram.

python scripts/calibration.py runs/benchmark/a.jsonl runs/benchmark/b.jsonl --name calibration
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tactile_sim.cli import ArgumentParser, require_writable, run_cli


@dataclass(frozen=True)
class CalibrationConfig:
    """Which records to pool and where the report goes.

    Attributes
    ----------
    records : tuple of Path
        Benchmark records files (JSONL, as ``scripts/benchmark.py`` writes them).
    out_dir : Path
        Where ``<name>.md``, ``<name>_reliability.json`` and ``.png`` are written.
    name : str
    arguments : tuple of str
        The command line, for the report.
    """

    records: tuple[Path, ...]
    out_dir: Path = Path("runs/benchmark")
    name: str = "calibration"
    arguments: tuple[str, ...] = ()


def run(config: CalibrationConfig) -> dict[str, Any]:
    """Pool the records' fast-mode answers; write and return the reliability payload."""
    from recognition.evaluation.calibration import pooled_report

    return pooled_report(config.records, config.out_dir, config.name, config.arguments)


def parse_args(argv: list[str] | None = None) -> CalibrationConfig:
    """The settings from the command line; a missing records file exits 2 here."""
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("records", type=Path, nargs="+", help="benchmark records files (JSONL)")
    p.add_argument("--out-dir", type=Path, default=Path("runs/benchmark"))
    p.add_argument("--name", default="calibration", help="file name stem of the report")
    a = p.parse_args(argv)
    for path in a.records:
        if not path.is_file():
            p.error(f"records file {path} does not exist")
    require_writable(p, "--out-dir", a.out_dir, directory=True)
    arguments = tuple(sys.argv[1:] if argv is None else argv)
    return CalibrationConfig(tuple(a.records), a.out_dir, a.name, arguments)


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and write the report; 2 on bad input."""
    config = parse_args(argv)
    return run_cli(lambda: run(config))


if __name__ == "__main__":
    sys.exit(main())
