"""Reproduce the thesis's tables and figures: thesis and measured values side by side.

python scripts/reproduce_thesis.py --table 3.3 --json out/table_3_3.json
python scripts/reproduce_thesis.py --table 4.2 --table 4.3 --json out/chapter4.json
python scripts/reproduce_thesis.py --table all --figures docs/figures
python scripts/reproduce_thesis.py --table 3.4 --source sim --json docs/results/table_3_4_sim.json
"""

from __future__ import annotations

import sys
from functools import partial
from pathlib import Path

from recognition.reproduction.reproduce import TABLES, ReproductionConfig
from tactile_sim.cli import ArgumentParser, integer, require_writable, run_cli
from tactile_sim.evaluation import SIM_TABLES, ThesisTablesConfig, reproduce_thesis


def parse_args(argv: list[str] | None = None) -> ThesisTablesConfig:
    """The tables and outputs from the command line (``argv``: default ``sys.argv``); a bad
    option or an output path that cannot be written exits 2 here, before any table."""
    defaults = ThesisTablesConfig()
    parser = ArgumentParser(description=(__doc__ or "").splitlines()[0])
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
    parser.add_argument(
        "--curves",
        type=integer(1),
        default=defaults.reproduction.curves,
        help="random curves per class",
    )
    parser.add_argument(
        "--workers", type=integer(1), default=None, help="worker processes (default: the cores)"
    )
    parser.add_argument("--seed", type=integer(0), default=0)
    parser.add_argument(
        "--source",
        choices=("synthetic", "sim"),
        default="synthetic",
        help=f"tactile points sampled on the closed form or sensed by the simulated robot "
        f"(tables {', '.join(SIM_TABLES)})",
    )
    parser.add_argument(
        "--sim-trials",
        type=integer(1),
        help=f"with --source sim: experiments ({defaults.sim_trials})",
    )
    args = parser.parse_args(argv)
    tables = TABLES if not args.table or "all" in args.table else tuple(args.table)
    if args.source == "sim":
        tables = SIM_TABLES if not args.table or "all" in args.table else tables
        others = [t for t in tables if t not in SIM_TABLES]
        if others:
            parser.error(
                f"--source sim applies to table {', '.join(SIM_TABLES)} only, not {others}"
            )
    elif args.sim_trials is not None:
        parser.error("--sim-trials applies to --source sim only")
    require_writable(parser, "--json", args.json)
    require_writable(parser, "--figures", args.figures, directory=True)
    return ThesisTablesConfig(
        ReproductionConfig(
            tables=tuple(dict.fromkeys(tables)),
            json_path=args.json,
            figures_dir=args.figures,
            curves=args.curves,
            workers=args.workers,
            seed=args.seed,
        ),
        source=args.source,
        sim_trials=defaults.sim_trials if args.sim_trials is None else args.sim_trials,
    )


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and reproduce the tables; 2 on bad input, 130 on Ctrl-C."""
    config = parse_args(argv)
    return run_cli(lambda: reproduce_thesis(config, echo=partial(print, flush=True)))


if __name__ == "__main__":
    sys.exit(main())
