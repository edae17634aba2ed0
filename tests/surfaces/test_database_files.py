"""A saved model database is verified whole: any damage is a typed error naming the file."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from testing_meshes import blob, ellipsoid

from recognition.errors import InvalidModel
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.database_files import DATABASE_FORMAT, MANIFEST, _manifest_digest
from recognition.surfaces.mesh_model import MeshModel


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    models = {"a b": MeshModel("a b", blob()), "a_b": MeshModel("a_b", ellipsoid())}
    return ModelDatabase(models).save(tmp_path_factory.mktemp("db") / "db")


@pytest.fixture
def copy(saved: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(saved, tmp_path / "db"))


def _manifest(directory: Path) -> dict:
    return json.loads((directory / MANIFEST).read_text())


def _rewrite_manifest(directory: Path, manifest: dict, *, digest: bool = True) -> None:
    if digest:
        manifest["digest"] = _manifest_digest(manifest)
    (directory / MANIFEST).write_text(json.dumps(manifest))


def _file_of(directory: Path, name: str) -> Path:
    (entry,) = [e for e in _manifest(directory)["models"] if e["name"] == name]
    return directory / entry["file"]


def test_names_that_clean_to_one_file_name_round_trip(saved: Path) -> None:
    loaded = ModelDatabase.load(saved)
    assert loaded.names == ["a b", "a_b"]
    assert loaded["a b"].hash == MeshModel("a b", blob()).hash


def test_a_truncated_model_file_is_named(copy: Path) -> None:
    path = _file_of(copy, "a b")
    path.write_bytes(path.read_bytes()[:-1000])
    with pytest.raises(InvalidModel, match=rf"{path.name}.*'a b'.*damaged"):
        ModelDatabase.load(copy)


def test_a_flipped_bit_is_found(copy: Path) -> None:
    path = _file_of(copy, "a_b")
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10
    path.write_bytes(bytes(data))
    with pytest.raises(InvalidModel, match="damaged"):
        ModelDatabase.load(copy)


def test_swapped_manifest_entries_are_found(copy: Path) -> None:
    manifest = _manifest(copy)
    a, b = manifest["models"]
    a["file"], b["file"] = b["file"], a["file"]
    _rewrite_manifest(copy, manifest, digest=False)
    with pytest.raises(InvalidModel, match=r"manifest.*damaged"):
        ModelDatabase.load(copy)
    # even with a fresh digest the files are bound to their names
    a["sha256"], b["sha256"] = b["sha256"], a["sha256"]
    _rewrite_manifest(copy, manifest)
    with pytest.raises(InvalidModel, match="holds model"):
        ModelDatabase.load(copy)


def _rewrite_model(copy: Path, name: str, change) -> None:
    """Rewrites a model file with ``change(arrays)`` applied, and a matching digest."""
    import hashlib

    path = _file_of(copy, name)
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    change(arrays)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())
    manifest = _manifest(copy)
    for entry in manifest["models"]:
        if entry["name"] == name:
            entry["sha256"] = hashlib.sha256(buffer.getvalue()).hexdigest()
    _rewrite_manifest(copy, manifest)


def test_an_edited_table_is_found_by_its_digest(copy: Path) -> None:
    path = _file_of(copy, "a b")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["table_k1"] = arrays["table_k1"] * 10
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())
    with pytest.raises(InvalidModel, match="damaged"):
        ModelDatabase.load(copy)


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        (lambda a: a["field_values"].__setitem__((0, 0, 0), np.nan), "field_values holds NaN"),
        (
            lambda a: a.__setitem__("field_values", a["field_values"].astype(np.float64)),
            "float32 values",
        ),
        (lambda a: a.__setitem__("faces", a["faces"] + 10**6), "faces must index"),
        (lambda a: a.__setitem__("normals", a["normals"] * 2), "unit vectors"),
        (lambda a: a.__setitem__("table_k2", a["table_k2"][:-1]), "table_k2 has"),
        (lambda a: a.__setitem__("field_voxel", np.array(-1.0)), "voxel and band"),
        # rings of an older format: (a0, anisotropy) alone
        (lambda a: a.__setitem__("rings", a["rings"][:, :, :2]), "rings hold"),
        (lambda a: a.pop("normals"), "cannot be read"),
    ],
)
def test_arrays_that_cannot_be_a_model_are_refused(copy: Path, change, fragment: str) -> None:
    _rewrite_model(copy, "a_b", change)
    with pytest.raises(InvalidModel, match=fragment):
        ModelDatabase.load(copy)


def test_nothing_outside_the_folder_is_read(copy: Path) -> None:
    outside = copy.parent / "outside.npz"
    shutil.copy(_file_of(copy, "a b"), outside)
    manifest = _manifest(copy)
    manifest["models"][0]["file"] = "../outside.npz"
    _rewrite_manifest(copy, manifest)
    with pytest.raises(InvalidModel, match="expected a file in the database's folder"):
        ModelDatabase.load(copy)


@pytest.mark.parametrize(
    ("manifest", "fragment"),
    [
        ([1, 2], "no list of models"),
        ({"format": DATABASE_FORMAT}, "no list of models"),
        ({"format": 1, "models": []}, r"has format 1.*rebuild"),
        ("not json", "not a readable manifest"),
    ],
)
def test_a_manifest_that_is_no_manifest_is_refused(copy: Path, manifest, fragment) -> None:
    text = manifest if isinstance(manifest, str) else json.dumps(manifest)
    (copy / MANIFEST).write_text(text)
    with pytest.raises(InvalidModel, match=fragment):
        ModelDatabase.load(copy)


def test_unknown_table_settings_are_refused(copy: Path) -> None:
    manifest = _manifest(copy)
    manifest["models"][1]["config"]["bogus"] = 1
    _rewrite_manifest(copy, manifest)
    with pytest.raises(InvalidModel, match="table settings"):
        ModelDatabase.load(copy)


def test_a_missing_database_says_so(tmp_path: Path) -> None:
    with pytest.raises(InvalidModel, match=r"no model database.*missing"):
        ModelDatabase.load(tmp_path / "nowhere")
