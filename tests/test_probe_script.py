"""scripts/probe.py end to end: probe, recognise, report, save; bad input exits 2."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from testing_scripts import load_script

from recognition import DataCurves
from tactile_sim.evaluation import pose_error


def test_pose_error_is_the_rotation_angle_and_the_mean_displacement_of_the_data() -> None:
    rng = np.random.default_rng(0)
    points = rng.normal(scale=0.01, size=(30, 3))
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    T[:3, 3] = (0.4, 0.1, 0.0)
    assert pose_error(T, T, points) == pytest.approx((0.0, 0.0), abs=1e-6)
    shifted = T.copy()
    shifted[:3, 3] += (0.0, 0.0, 0.002)
    assert pose_error(shifted, T, points) == pytest.approx((0.0, 0.002), abs=1e-6)
    turned = T.copy()
    turned[:3, :3] = Rotation.from_euler("z", 10, degrees=True).as_matrix() @ T[:3, :3]
    angle, shift = pose_error(turned, T, points)
    assert angle == pytest.approx(10.0)
    assert 0 < shift < 0.01


@pytest.mark.slow
def test_probing_an_object_recognises_it_and_saves_its_curves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    config = probe.parse_args(["--object", "bird", "--seed", "1", "--rerun", "off"])
    summary = probe.run(dataclasses.replace(config, out=tmp_path))
    assert summary["recognized"] == "bird" and summary["correct"]
    assert summary["location_error_mm"] < 2.0
    ranking = [e for _, e in summary["ranking_mm"] if e is not None]
    assert ranking == sorted(ranking)
    curves = DataCurves.load(summary["curves_file"])
    assert [len(c) for c in curves.curves] == [21, 21, 21]
    out = capsys.readouterr().out
    assert "recognised as bird (correct)" in out and "timings:" in out


def test_an_unknown_object_lists_the_known_ones_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    assert probe.main(["--object", "unicorn", "--rerun", "off", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "unicorn" in err and "cat" in err and "elephant" in err


@pytest.mark.slow
def test_a_model_error_is_probed_reported_and_written_to_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    probe = load_script("probe")
    summary_path = tmp_path / "summary.json"
    args = ["--object", "cat", "--model-error-mm", "0.1", "--rerun", "off", "--touches", "0"]
    config = probe.parse_args([*args, "--out", str(tmp_path), "--json", str(summary_path)])
    summary = probe.run(config)
    error = summary["model_error_mm"]
    assert error["requested_rms"] == 0.1 and error["achieved_rms"] == pytest.approx(0.1, rel=0.1)
    # the curves alone name the cat; where on it they leave uncertain (the next test)
    assert summary["recognized"] == "cat" and summary["confidence"] < 0.99
    assert json.loads(summary_path.read_text())["model_error_mm"] == error
    assert "model error: the object lies" in capsys.readouterr().out


@pytest.mark.slow
def test_touches_resolve_a_session_the_sweeps_leave_unsure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    args = ["--object", "cat", "--seed", "0", "--model-error-mm", "0.1"]
    summary = probe.run(probe.parse_args([*args, "--out", str(tmp_path)]))
    # the three curves put p 1.6 mm off and are not sure of it; the touches are
    assert summary["location_error_mm"] > 1.0 and summary["confidence"] < 0.99
    touches = summary["touches"]
    assert 1 <= len(touches["made"]) <= 5 and touches["stop"] == "sure"
    assert touches["correct"] and touches["confidence"] >= 0.99
    assert touches["location_error_mm"] < 0.5
    out = capsys.readouterr().out
    assert "confidence after the sweeps" in out and "touch 1: contact" in out
    assert summary["timings_s"]["touches"] > 0
    # the recording shows each touch and the hypotheses as ghost models
    from tactile_sim.recording import read_recording

    entities = read_recording(summary["recording"]).entities
    made = len(touches["made"])
    assert {f"world/touches/{k}/approach" for k in range(1, made + 1)} <= set(entities)
    assert "world/hypotheses/0" in entities and "world/hypotheses/0/label" in entities
    # --touches 0: the thesis's three curves alone
    args += ["--rerun", "off", "--touches", "0"]
    summary = probe.run(probe.parse_args([*args, "--out", str(tmp_path)]))
    assert "touches" not in summary


@pytest.mark.parametrize(
    "args",
    [
        ["--model-error-mm", "-0.1"],
        ["--model-error-mm", "nan"],
        ["--model-error-correlation-mm", "0"],
    ],
)
def test_a_bad_model_error_exits_2_before_any_work(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    with pytest.raises(SystemExit) as exit_:
        probe.main(["--object", "cat", "--rerun", "off", *args])
    assert exit_.value.code == 2
    assert "--model-error" in capsys.readouterr().err


def _open_creature(path: Path) -> Path:
    """A blob with its base cut open and a separate eye, in millimetres (PLY)."""
    import trimesh
    from testing_meshes import blob

    body = blob(5)
    keep = body.triangles_center[:, 2] > -0.6 * body.vertices[:, 2].max()
    cut = trimesh.Trimesh(body.vertices, body.faces[keep])
    eye = trimesh.creation.icosphere(3, radius=0.004).apply_translation([0.028, 0.006, 0.005])
    trimesh.util.concatenate([cut, eye]).apply_scale(1e3).export(path)
    return path


@pytest.mark.slow
def test_your_own_open_mesh_in_pieces_is_probed_and_recognised(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    mesh = _open_creature(tmp_path / "creature.ply")
    args = ["--mesh", str(mesh), "--units", "mm", "--rerun", "off", "--out", str(tmp_path)]
    summary = probe.run(probe.parse_args(args))
    assert summary["object"] == "creature" and summary["correct"]
    assert summary["location_error_mm"] < 1.0
    assert any("holes kept open" in n for n in summary["mesh_repairs"])
    assert any("2 separate components" in n for n in summary["mesh_repairs"])
    names = [n for n, _ in summary["ranking_mm"]]
    assert "creature" in names and "cat" in names  # the catalog's models and the mesh's
    out = capsys.readouterr().out
    assert "mesh: open:" in out and "recognised as creature (correct)" in out


def test_a_mesh_that_cannot_be_a_model_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    probe = load_script("probe")
    flat = tmp_path / "sheet.obj"
    flat.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nv 10 10 0\nf 1 2 3\nf 2 4 3\n")
    code = probe.main(["--mesh", str(flat), "--units", "mm", "--rerun", "off"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "flat" in err
