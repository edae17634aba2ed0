"""A session logged to a recording, read back: entities, rows, quaternion order."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from recognition import ModelDatabase, Recognition
from tactile_sim.probing import ProbeSession
from tactile_sim.recording import read_recording


def test_recording_round_trip(
    recording: Path, session: ProbeSession, recognized: tuple[Recognition, ModelDatabase]
) -> None:
    result, _ = recognized
    summary = read_recording(recording)
    trajectory = session.trajectory
    n = len(trajectory)
    assert summary.application_id == "tactile_sim"
    assert summary.has_blueprint
    for body in trajectory.body_names:
        assert summary.rows[f"world/robot/{body}"] == n
    for entity in ("world/probe/tip", "sensors/deflection", "sensors/force"):
        assert summary.rows[entity] == n
    sensed = sum(s.n_points for s in session.sweeps)
    assert sensed == 21
    for entity in ("world/probe/sensed", "world/probe/contacts", "world/probe/normals"):
        assert summary.rows[entity] == sensed
    for curve in ("alpha", "beta", "gamma"):
        assert summary.rows[f"world/curves/{curve}"] == 1
    static = summary.static
    assert {
        "world/object",
        "world/object/visual",
        "world/table/table_top",
        "world/robot/base",
        "world/robot/inner_link/inner_link_beam",
        "world/robot/joystick_probe/tip/tip_visual",
        "recognition/ranking",
    } <= static
    for name in result.registrations:
        assert f"recognition/models/{name}/candidates" in static
    assert result.name == "sphere"
    assert {f"recognition/models/sphere/curves/{c}" for c in ("alpha", "beta", "gamma")} <= static


def test_body_quaternions_are_stored_xyzw(recording: Path, session: ProbeSession) -> None:
    from rerun.chunk import RrdReader

    trajectory = session.trajectory
    b = trajectory.body_names.index("inner_link")
    for chunk in RrdReader(recording).stream():
        if chunk.entity_path == "/world/robot/inner_link" and not chunk.is_static:
            batch = chunk.to_record_batch()
            columns = dict(zip(batch.schema.names, batch.columns, strict=True))
            steps = columns["step"].to_numpy()
            quats = np.array(columns["Transform3D:quaternion"].to_pylist()).reshape(-1, 4)
            break
    else:
        pytest.fail("no temporal chunk for world/robot/inner_link")
    index = np.searchsorted(trajectory.steps, steps)
    wxyz = trajectory.body_quats_wxyz_in_world[index, b]
    np.testing.assert_allclose(quats, wxyz[:, [1, 2, 3, 0]], atol=1e-6)
