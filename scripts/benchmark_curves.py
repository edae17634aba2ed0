"""Time and score the Chapter 3 recognition tree on exact local geometry at a few contacts.

python scripts/benchmark_curves.py --curves 100 --contacts 3 --out docs/benchmarks/curves_exact

For every class (and the quartic, a curve of no class) random curves of
``recognition.curves.random_curve``, each at ``--contacts`` random points of its
interval, mirrored and reversed at random; exact kappa, kappa_s and tangent rotations go
to ``recognize_curve`` with the relative uncertainty ``--precision``. Reports the rate of
correct decisions and the wall time per call (median, 90th percentile, max).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from recognition.curves import CurveKind, InputUncertainty, random_curve, recognize_curve
from recognition.curves.families import TREE_CLASSES
from recognition.files import write_atomic


@dataclass(frozen=True)
class CurveBenchmarkConfig:
    """Settings of the benchmark.

    Attributes
    ----------
    curves : int
        Random curves per class.
    contacts : int
        Contacts per curve.
    precision : float
        Relative uncertainty of kappa, kappa_s (and radians of the tangent angles).
    seed : int
    out : Path or None
        Write ``<out>.json`` and ``<out>.md``.
    """

    curves: int = 100
    contacts: int = 3
    precision: float = 1e-9
    seed: int = 0
    out: Path | None = None


def _exact_contacts(
    kind: CurveKind, rng: np.random.Generator, m: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kappa, kappa_s and tangent rotations at m random contacts of a random curve."""
    curve, t0, t1 = random_curve(kind, rng)
    t = np.sort(rng.uniform(min(t0, t1), max(t0, t1), m))
    dense = np.unique(np.concatenate([t, np.linspace(t[0], t[-1], 2001)]))
    phi = np.unwrap(curve.phi(dense))[np.searchsorted(dense, t)]
    kappa, kappa_s = curve.kappa(t), curve.kappa_s(t)
    if rng.integers(2):  # mirror image
        kappa, kappa_s, phi = -kappa, -kappa_s, -phi
    if rng.integers(2):  # the other direction of traversal
        kappa, kappa_s, phi = -kappa[::-1], kappa_s[::-1], phi[::-1]
    return kappa, kappa_s, phi - phi[0]


def run(config: CurveBenchmarkConfig) -> dict[str, object]:
    """Rates and timings per class; written to ``config.out`` when given."""
    rng = np.random.default_rng(config.seed)
    uncertainty = InputUncertainty.relative(config.precision)
    per_class: dict[str, dict[str, object]] = {}
    all_ms: list[float] = []
    for kind in (*TREE_CLASSES, CurveKind.QUARTIC):
        expected = kind if kind in TREE_CLASSES else CurveKind.UNCLASSIFIED
        ms, correct = [], 0
        for _ in range(config.curves):
            kappa, kappa_s, dphi = _exact_contacts(kind, rng, config.contacts)
            start = time.perf_counter()
            result = recognize_curve(kappa, kappa_s, dphi, uncertainty=uncertainty)
            ms.append(1e3 * (time.perf_counter() - start))
            correct += result.kind is expected
        all_ms += ms
        per_class[kind.value] = {
            "correct_rate": correct / config.curves,
            "median_ms": float(np.median(ms)),
            "p90_ms": float(np.percentile(ms, 90)),
            "max_ms": float(np.max(ms)),
        }
    report: dict[str, object] = {
        "command": "python scripts/benchmark_curves.py " + " ".join(sys.argv[1:]),
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": f"{platform.machine()} {platform.processor() or ''} {platform.system()} "
        f"python {platform.python_version()}, {os.cpu_count()} cores, load average "
        f"{os.getloadavg()[0]:.1f} at the start",
        "config": {k: str(v) if isinstance(v, Path) else v for k, v in asdict(config).items()},
        "classes": per_class,
        "all": {
            "median_ms": float(np.median(all_ms)),
            "p90_ms": float(np.percentile(all_ms, 90)),
            "max_ms": float(np.max(all_ms)),
        },
    }
    if config.out is not None:
        for suffix, text in (
            (".json", json.dumps(report, indent=2) + "\n"),
            (".md", _markdown(report)),
        ):
            write_atomic(
                config.out.with_suffix(suffix), lambda f, text=text: f.write(text.encode())
            )
    return report


def _markdown(report: dict[str, object]) -> str:
    lines = [
        "# Chapter 3 recognition tree: exact local geometry",
        "",
        f"`{report['command']}`, {report['date']}, {report['machine']}.",
        "",
        "| class | correct | median ms | p90 ms | max ms |",
        "| :-- | --: | --: | --: | --: |",
    ]
    classes = report["classes"]
    assert isinstance(classes, dict)
    for name, row in classes.items():
        lines.append(
            f"| {name} | {100 * row['correct_rate']:.0f} % | {row['median_ms']:.1f} | "
            f"{row['p90_ms']:.1f} | {row['max_ms']:.1f} |"
        )
    total = report["all"]
    assert isinstance(total, dict)
    lines.append(
        f"| all | | {total['median_ms']:.1f} | {total['p90_ms']:.1f} | {total['max_ms']:.1f} |"
    )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--curves", type=int, default=100, help="random curves per class")
    parser.add_argument("--contacts", type=int, default=3, help="contacts per curve")
    parser.add_argument("--precision", type=float, default=1e-9, help="relative uncertainty")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, help="write OUT.json and OUT.md")
    a = parser.parse_args(argv)
    report = run(CurveBenchmarkConfig(a.curves, a.contacts, a.precision, a.seed, a.out))
    print(_markdown(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
