"""Time and score the Chapter 3 recognition tree on exact local geometry at a few contacts.

python scripts/benchmark_curves.py --curves 100 --contacts 3 --out docs/benchmarks/curves_exact

For every class (and the quartic, a curve of no class) random curves, each at
``--contacts`` random points, mirrored and reversed at random; exact kappa, kappa_s and
tangent rotations go to ``recognize_curve`` with the relative uncertainty
``--precision``. Reports the rate of correct decisions and the wall time per call.
"""

from __future__ import annotations

import sys
from pathlib import Path

from recognition.evaluation.curve_benchmark import CurveBenchmarkConfig, markdown, run
from tactile_sim.cli import ArgumentParser, integer, real, require_writable, run_cli


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments, run the benchmark and print its table; 2 on bad input."""
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--curves", type=integer(1), default=100, help="random curves per class")
    p.add_argument("--contacts", type=integer(3), default=3, help="contacts per curve")
    p.add_argument(
        "--precision", type=real(0.0, low_open=True), default=1e-9, help="relative uncertainty"
    )
    p.add_argument("--seed", type=integer(0), default=0)
    p.add_argument("--out", type=Path, help="write OUT.json and OUT.md")
    a = p.parse_args(argv)
    if a.out is not None:
        require_writable(p, "--out", a.out.with_suffix(".json"))
    arguments = tuple(sys.argv[1:] if argv is None else argv)
    config = CurveBenchmarkConfig(a.curves, a.contacts, a.precision, a.seed, a.out, arguments)
    return run_cli(lambda: print(markdown(run(config))))


if __name__ == "__main__":
    sys.exit(main())
