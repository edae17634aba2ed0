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
