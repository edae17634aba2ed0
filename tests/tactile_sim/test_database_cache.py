"""A cached database is built once, and rebuilt with a notice when it cannot be used."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from testing_meshes import blob

from recognition import ModelDatabase
from recognition.surfaces.database_files import MANIFEST
from tactile_sim.objects.database import cached_database


def test_a_damaged_cache_is_rebuilt_with_a_notice_and_answers_as_before(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    builds = []

    def build() -> ModelDatabase:
        builds.append(1)
        return ModelDatabase.from_meshes({"blob": blob()})

    directory = tmp_path / "db"
    first = cached_database(directory, build, "the test database")
    assert "building the test database (once" in capsys.readouterr().out
    assert cached_database(directory, build, "the test database").names == ["blob"]
    assert len(builds) == 1 and capsys.readouterr().out == ""
    (model_file,) = directory.glob("model_*.npz")
    model_file.write_bytes(model_file.read_bytes()[:-5000])
    again = cached_database(directory, build, "the test database")
    out = capsys.readouterr().out
    assert len(builds) == 2 and out.count("\n") == 1
    assert "cannot be used" in out and model_file.name in out and "rebuilding" in out
    a, b = first["blob"], again["blob"]
    np.testing.assert_array_equal(a.table.k1, b.table.k1)
    np.testing.assert_array_equal(a.distance_field.values, b.distance_field.values)
    (directory / MANIFEST).write_text("[]")
    cached_database(directory, build, "the test database")
    assert len(builds) == 3 and "no list of models" in capsys.readouterr().out
