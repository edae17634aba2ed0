"""Time and score the Chapter 3 recognition on exact local geometry or on sampled curves.

python scripts/benchmark_curves.py --curves 100 --contacts 3 --out docs/benchmarks/curves_exact
python scripts/benchmark_curves.py --curves 100 --spacing 0.05 --noise 0.003 --window 9 \
    --out docs/benchmarks/curves_sampled

For every class (and the quartic, a curve of no class) random curves, mirrored and
reversed at random. Without ``--spacing``: exact kappa, kappa_s and tangent rotations at
``--contacts`` random points go to ``recognize_curve`` with the relative uncertainty
``--precision``. With ``--spacing``: points every SPACING of arc length with Gaussian
noise ``--noise`` per coordinate go to ``recognize_points`` (local fits over
``--window`` points; ``--decide-by invariants`` for the thesis's tree on the estimates).
Reports the rate of correct decisions and the wall time per call.
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
    p.add_argument(
        "--spacing", type=real(0.0, low_open=True), help="sampled mode: arc length between points"
    )
    p.add_argument(
        "--noise", type=real(0.0), default=0.0, help="sampled mode: noise per coordinate"
    )
    p.add_argument("--window", type=integer(5), default=21, help="sampled mode: local fit points")
    p.add_argument(
        "--decide-by",
        choices=("points", "invariants"),
        default="points",
        help="sampled mode: recognize_points's decision",
    )
    p.add_argument("--out", type=Path, help="write OUT.json and OUT.md")
    a = p.parse_args(argv)
    if a.out is not None:
        require_writable(p, "--out", a.out.with_suffix(".json"))
    arguments = tuple(sys.argv[1:] if argv is None else argv)
    if a.spacing is None and (
        a.noise or any(x.startswith(("--window", "--decide-by")) for x in arguments)
    ):
        p.error("--noise, --window and --decide-by need --spacing (the sampled mode)")
    if a.window % 2 == 0:
        p.error(f"--window must be odd, got {a.window}")
    config = CurveBenchmarkConfig(
        a.curves,
        a.contacts,
        a.precision,
        a.seed,
        a.out,
        arguments,
        a.spacing,
        a.noise,
        a.window,
        a.decide_by,
    )
    return run_cli(lambda: print(markdown(run(config))))


if __name__ == "__main__":
    sys.exit(main())
