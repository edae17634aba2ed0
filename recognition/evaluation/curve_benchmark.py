"""The Chapter 3 recognition timed and scored on random curves of every class (and the
quartic, a curve of no class) from :func:`~recognition.curves.random_curve`, mirrored and
reversed at random, in one of two modes:

- exact local geometry at a few random contacts of the curve's interval: exact kappa,
  kappa_s and tangent rotations go to :func:`~recognition.curves.recognize_curve` with a
  stated relative uncertainty;
- sampled (``spacing`` given): points every ``spacing`` of arc length over the interval
  with Gaussian noise ``noise`` per coordinate go to
  :func:`~recognition.curves.recognize_points` (its default: every class fitted to the
  points, the noise estimated by its local fits over ``window`` points).

Reports the rate of correct decisions and the wall time per call (median, 90th
percentile, max).
"""

from __future__ import annotations

import os
import platform
import time
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from recognition.curves import (
    CurveKind,
    InputUncertainty,
    random_curve,
    recognize_curve,
    recognize_points,
    sample_by_arc_length,
)
from recognition.curves.families import TREE_CLASSES
from recognition.errors import InvalidArgument
from recognition.files import write_atomic, write_json_atomic
from recognition.rigid import random_planar_motion

__all__ = ["CurveBenchmarkConfig", "markdown", "run"]


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
    spacing : float or None
        Sampled mode: arc length between samples (curve units); None: exact contacts.
    noise : float
        Sampled mode: noise per coordinate (curve units).
    window : int
        Sampled mode: points of each local fit (cubic, kappa_s over as many estimates).
    decide_by : str
        Sampled mode: ``recognize_points``'s decision, "points" or "invariants" (the
        thesis's tree on the local estimates with their propagated uncertainty).
    out : Path or None
        Write ``<out>.json`` and ``<out>.md``.
    arguments : tuple of str
        The command line, for the report.
    """

    curves: int = 100
    contacts: int = 3
    precision: float = 1e-9
    seed: int = 0
    out: Path | None = None
    arguments: tuple[str, ...] = ()
    spacing: float | None = None
    noise: float = 0.0
    window: int = 21
    decide_by: str = "points"


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


def _sampled_points(
    kind: CurveKind, rng: np.random.Generator, spacing: float, noise: float
) -> np.ndarray:
    """Noisy samples of a random curve over its interval, placed, mirrored and reversed
    at random."""
    curve, t0, t1 = random_curve(kind, rng)
    T = random_planar_motion(rng, 3.0)
    if rng.integers(2):
        T[:2, :2] = T[:2, :2] @ np.diag([1.0, -1.0])
    sampled = sample_by_arc_length(
        curve, t0, t1, spacing, rng=rng, noise_std=noise, T_data_from_canonical=T
    )
    return sampled.points[::-1] if rng.integers(2) else sampled.points


def _decide(
    kind: CurveKind, rng: np.random.Generator, config: CurveBenchmarkConfig
) -> tuple[CurveKind, float]:
    """The decision on one random curve of ``kind`` and its wall time (s)."""
    if config.spacing is None:
        kappa, kappa_s, dphi = _exact_contacts(kind, rng, config.contacts)
        uncertainty = InputUncertainty.relative(config.precision)
        start = time.perf_counter()
        decided = recognize_curve(kappa, kappa_s, dphi, uncertainty=uncertainty).kind
        return decided, time.perf_counter() - start
    points = _sampled_points(kind, rng, config.spacing, config.noise)
    w = config.window
    if points.shape[0] < 2 * w + 1:
        raise InvalidArgument(
            f"a {kind} sampled every {config.spacing:g} has {points.shape[0]} points, fewer "
            f"than the {2 * w + 1} the local fits over --window {w} need: lower the spacing "
            "or the window"
        )
    start = time.perf_counter()
    decided = recognize_points(
        points, window=w, degree=3, kappa_window=w, decide_by=config.decide_by
    )[0].kind
    return decided, time.perf_counter() - start


def run(config: CurveBenchmarkConfig) -> dict[str, object]:
    """Rates and timings per class; written to ``config.out`` when given."""
    rng = np.random.default_rng(config.seed)
    per_class: dict[str, dict[str, object]] = {}
    all_ms: list[float] = []
    for kind in (*TREE_CLASSES, CurveKind.QUARTIC):
        expected = kind if kind in TREE_CLASSES else CurveKind.UNCLASSIFIED
        ms, correct = [], 0
        decisions: dict[str, int] = {}
        for _ in range(config.curves):
            decided, seconds = _decide(kind, rng, config)
            ms.append(1e3 * seconds)
            correct += decided is expected
            decisions[decided.value] = decisions.get(decided.value, 0) + 1
        all_ms += ms
        per_class[kind.value] = {
            "correct_rate": correct / config.curves,
            "median_ms": float(np.median(ms)),
            "p90_ms": float(np.percentile(ms, 90)),
            "max_ms": float(np.max(ms)),
            "decisions": decisions,
        }
    report: dict[str, object] = {
        "command": " ".join(("python scripts/benchmark_curves.py", *config.arguments)),
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
        write_json_atomic(config.out.with_suffix(".json"), report)
        data = markdown(report).encode()
        write_atomic(config.out.with_suffix(".md"), lambda f: f.write(data))
    return report


def markdown(report: dict[str, object]) -> str:
    config = report["config"]
    assert isinstance(config, dict)
    title = (
        "exact local geometry"
        if config.get("spacing") is None
        else f"points every {config['spacing']:g} with noise {config['noise']:g} per "
        f"coordinate, decided by the {config.get('decide_by', 'points')}"
    )
    lines = [
        f"# Chapter 3 recognition: {title}",
        "",
        f"`{report['command']}`, {report['date']}, {report['machine']}.",
        "",
        "| class | correct | median ms | p90 ms | max ms | decisions |",
        "| :-- | --: | --: | --: | --: | :-- |",
    ]
    classes = report["classes"]
    assert isinstance(classes, dict)
    for name, row in classes.items():
        decisions = ", ".join(f"{k} {v}" for k, v in row.get("decisions", {}).items())
        lines.append(
            f"| {name} | {100 * row['correct_rate']:.0f} % | {row['median_ms']:.1f} | "
            f"{row['p90_ms']:.1f} | {row['max_ms']:.1f} | {decisions} |"
        )
    total = report["all"]
    assert isinstance(total, dict)
    lines.append(
        f"| all | | {total['median_ms']:.1f} | {total['p90_ms']:.1f} | {total['max_ms']:.1f} | |"
    )
    return "\n".join(lines) + "\n"
