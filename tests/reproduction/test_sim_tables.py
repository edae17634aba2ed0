"""Tables 3.4 and 3.5 from measured tactile points: exact points, then the simulated robot."""

import json
from pathlib import Path

import numpy as np
import pytest
from testing_scripts import load_script

from recognition.reproduction import chapter3

ROOT = Path(__file__).resolve().parents[2]


def _ellipse_arc_m(t0: float, length_m: float, spacing_m: float, theta: float) -> np.ndarray:
    """Points every ``spacing_m`` along the ellipse a = 25 mm, b = 17.5 mm from angle t0,
    rotated by theta and moved (a world frame)."""
    t = np.linspace(t0, t0 + 4.0, 40001)
    p = np.stack([0.025 * np.cos(t), 0.0175 * np.sin(t)], 1)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    s_new = np.arange(0.0, length_m, spacing_m)
    p = np.stack([np.interp(s_new, s, p[:, 0]), np.interp(s_new, s, p[:, 1])], 1)
    R = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    return p @ R.T + np.array([0.4, 0.1])


def test_table_3_4_from_exact_points_recovers_the_ellipse() -> None:
    trials = [
        [_ellipse_arc_m(0.3, 0.06, 0.5e-3, 0.2), _ellipse_arc_m(3.5, 0.06, 0.5e-3, -1.0)],
        [_ellipse_arc_m(1.3, 0.06, 0.5e-3, 2.0), _ellipse_arc_m(4.4, 0.06, 0.5e-3, 0.7)],
    ]
    result = chapter3.table_3_4_from_points(trials)
    errors = result.measured["mean_relative_error_percent"]
    assert errors["a"] < 1.5 and errors["b"] < 1.5  # the estimator's own bias: about 1 %
    assert result.settings["trials"] == 2
    assert set(result.to_json()) >= {"table", "thesis", "measured"}


def _spline_segments() -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    from tactile_sim.collision import closed_spline_outline, load_solid

    solid = load_solid("planar_spline")
    coefficients = np.asarray(solid.parameters["spline_coefficients_m"])
    dense = closed_spline_outline(solid.parameters["knots_m"], samples_per_segment=4000)
    parameter = np.arange(len(dense)) / 4000
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    segments = []
    for k in (1, 3):
        i0, i1 = np.searchsorted(parameter, [k, k + 1])
        s_new = np.arange(s[i0] - 3e-3, s[i1] + 3e-3, 0.5e-3)
        points = np.stack([np.interp(s_new, s, dense[:, i]) for i in (0, 1)], 1)
        on = np.floor(np.interp(s_new, s, parameter)) == k
        segments.append((points + np.array([0.4, 0.0]), on, coefficients[k]))
    return segments


def test_table_3_5_from_exact_points_recovers_the_spline_segments() -> None:
    result = chapter3.table_3_5_from_points(_spline_segments())
    for entry in result.measured.values():
        assert entry["all eight"]["relative_error_percent"] < 1.0


def test_sim_source_is_refused_for_tables_without_one(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        load_script("reproduce_thesis").parse_args(["--table", "3.3", "--source", "sim"])
    assert exit_info.value.code == 2
    assert "--source sim applies to table" in capsys.readouterr().err


@pytest.mark.slow
def test_traced_outline_points_lie_on_the_ellipse() -> None:
    from tactile_sim.evaluation import TraceConfig, trace_outlines

    traces = trace_outlines(TraceConfig(trials=1, arc_length_m=0.01, spacing_m=1e-3))
    accuracy = traces.accuracy()
    assert accuracy["points"] == 2 * 11
    assert accuracy["distance_to_outline_max_mm"] < 0.1
    for arc in traces.trials[0]:
        steps = np.diff(np.unwrap(arc.outline_parameter))
        assert np.all(steps > 0)  # counter-clockwise
        assert arc.points_in_world.shape == (11, 2)
    again = trace_outlines(TraceConfig(trials=1, arc_length_m=0.01, spacing_m=1e-3))
    np.testing.assert_array_equal(
        again.trials[0][1].points_in_world, traces.trials[0][1].points_in_world
    )


@pytest.mark.slow
def test_table_3_4_from_the_simulated_robot(tmp_path: Path) -> None:
    from recognition.reproduction.reproduce import ReproductionConfig
    from tactile_sim.evaluation import ThesisTablesConfig, reproduce_thesis

    path = tmp_path / "table_3_4_sim.json"
    config = ThesisTablesConfig(
        ReproductionConfig(tables=("3.4",), json_path=path), source="sim", sim_trials=2
    )
    (result,) = reproduce_thesis(config)
    payload = json.loads(path.read_text())
    assert set(payload) >= {"table", "thesis", "measured"}
    assert payload["measured"]["source"] == "sim"
    errors = result.measured["mean_relative_error_percent"]
    assert errors["a"] < 2.0 and errors["b"] < 2.0
    assert result.measured["sensing"]["distance_to_outline_mean_mm"] < 0.05
