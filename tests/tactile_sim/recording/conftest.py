"""Fixtures of the recording tests: a short sphere session, its recognition and recording."""

from __future__ import annotations

from pathlib import Path

import pytest

from recognition import ModelDatabase, Recognition
from tactile_sim.probing import ProbeSession, probe_object, resolve_object
from tactile_sim.recording import record_probe_run


@pytest.fixture(scope="package")
def session() -> ProbeSession:
    return probe_object("sphere", seed=3, n_points=7, trajectory_hz=200.0, progress=False)


@pytest.fixture(scope="package")
def recognized(session: ProbeSession) -> tuple[Recognition, ModelDatabase]:

    database = ModelDatabase.from_meshes(
        {name: resolve_object(name, progress=False).mesh for name in ("sphere", "cylinder_1")}
    )
    return database.recognize(session.curves), database


@pytest.fixture(scope="package")
def recording(
    session: ProbeSession,
    recognized: tuple[Recognition, ModelDatabase],
    tmp_path_factory: pytest.TempPathFactory,
) -> Path:
    result, database = recognized
    path = tmp_path_factory.mktemp("recording") / "sphere_seed3.rrd"
    assert record_probe_run(session, result, database, mode="save", path=path) == str(path)
    return path
