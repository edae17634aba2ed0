"""The Chapter 3 tree's benchmark (scripts/benchmark_curves.py): rates and timings,
written as JSON and Markdown."""

import json
from pathlib import Path

from recognition.evaluation.curve_benchmark import CurveBenchmarkConfig, run


def test_benchmark_writes_rates_and_timings(tmp_path: Path) -> None:
    out = tmp_path / "curves"
    report = run(CurveBenchmarkConfig(curves=2, out=out))
    payload = json.loads(out.with_suffix(".json").read_text())
    assert set(payload["classes"]) == set(report["classes"])
    assert {"command", "date", "machine"} <= set(payload)
    assert all(0.0 <= row["correct_rate"] <= 1.0 for row in payload["classes"].values())
    assert "| all |" in out.with_suffix(".md").read_text()


def test_sampled_mode_scores_recognize_points(tmp_path: Path) -> None:
    out = tmp_path / "sampled"
    report = run(CurveBenchmarkConfig(curves=1, spacing=0.05, noise=0.0005, out=out))
    classes = report["classes"]
    assert isinstance(classes, dict)
    for row in classes.values():
        assert sum(row["decisions"].values()) == 1
    # conics sampled at a sixth of the joystick's noise are decided right (short arcs of
    # the cubic classes may be within the noise of a conic: docs/benchmarks/curves_sampled)
    for name in ("parabola", "ellipse", "hyperbola"):
        assert classes[name]["correct_rate"] == 1.0, (name, classes[name]["decisions"])
    assert "noise 0.0005" in out.with_suffix(".md").read_text()
