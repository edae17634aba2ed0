"""A model database on disk: one .npz per model and a manifest, verified whole on load.

The manifest (``manifest.json``) lists the models in order, each with its file, the
SHA-256 of the file's bytes, its mesh hash and table settings, and carries the SHA-256 of
its own content. Loading reads nothing outside the database's folder, checks every digest
before it parses a file, binds each file to its model by the name stored inside it, and
checks every array's shape, type, range and finiteness: damage of any kind is an
:class:`~recognition.errors.InvalidModel` naming the file and what is wrong.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import zipfile
import zlib
from dataclasses import asdict, fields
from pathlib import Path
from typing import IO, Any

import numpy as np
import trimesh

from recognition.errors import InvalidModel
from recognition.files import write_atomic
from recognition.surfaces.distance import DistanceField
from recognition.surfaces.lookup import CurvatureTable
from recognition.surfaces.mesh_model import MeshModel, MeshModelConfig
from recognition.surfaces.mesh_repair import MeshReport
from recognition.surfaces.rings import DESCRIPTOR_SIZE, RADII_M

__all__ = ["DATABASE_FORMAT", "MANIFEST", "read_models", "write_models"]

#: Version of the on-disk format; a different version is rebuilt, never read.
DATABASE_FORMAT = 12
#: The manifest's file name.
MANIFEST = "manifest.json"

_ARRAYS = (
    "name",
    "vertices",
    "faces",
    "normals",
    "table_vertex",
    "table_k1",
    "table_k2",
    "table_d1",
    "vertex_index",
    "vertex_k1",
    "vertex_k2",
    "vertex_d1",
    "field_origin",
    "field_voxel",
    "field_band",
    "field_values",
    "symmetries",
    "rings",
)


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _manifest_digest(manifest: dict[str, Any]) -> str:
    body = {k: v for k, v in manifest.items() if k != "digest"}
    return _digest(json.dumps(body, sort_keys=True).encode())


def _write_bytes(f: IO[bytes], data: bytes) -> None:
    f.write(data)


def _arrays(model: MeshModel) -> dict[str, np.ndarray]:
    table, df, dense = model.table, model.distance_field, model.candidate_curvatures
    assert table.d1 is not None and dense.d1 is not None
    return {
        "name": np.array(model.name),
        "vertices": model.vertices,
        "faces": model.faces,
        "normals": model.normals,
        "table_vertex": table.site,
        "table_k1": table.k1,
        "table_k2": table.k2,
        "table_d1": table.d1,
        "vertex_index": dense.site,
        "vertex_k1": dense.k1.astype(np.float32),
        "vertex_k2": dense.k2.astype(np.float32),
        "vertex_d1": dense.d1.astype(np.float32),
        "field_origin": df.origin,
        "field_voxel": np.array(df.voxel),
        "field_band": np.array(df.band),
        "field_values": df.values,
        "symmetries": model.symmetries,
        "rings": model.rings,
    }


def write_models(models: list[MeshModel], directory: Path) -> Path:
    """Writes the models (mesh, tables, distance field) and the manifest to ``directory``,
    each file atomically (the manifest last); returns the directory."""
    entries = []
    for i, model in enumerate(models):
        buffer = io.BytesIO()
        # uncompressed: a database loads at the speed of the disk, not of zlib
        np.savez(buffer, allow_pickle=False, **_arrays(model))
        data = buffer.getvalue()
        file = f"model_{i:04d}.npz"
        write_atomic(directory / file, functools.partial(_write_bytes, data=data))
        config = asdict(model.config)
        config["fit_sizes"] = list(config["fit_sizes"])
        entries.append(
            {
                "name": model.name,
                "file": file,
                "sha256": _digest(data),
                "mesh_hash": model.hash,
                "config": config,
                "report": model.report.to_json(),
                "timings_s": model.timings,
            }
        )
    manifest: dict[str, Any] = {"format": DATABASE_FORMAT, "models": entries}
    manifest["digest"] = _manifest_digest(manifest)
    text = json.dumps(manifest, indent=2).encode()
    write_atomic(directory / MANIFEST, functools.partial(_write_bytes, data=text))
    return directory


def _manifest(directory: Path) -> list[dict[str, Any]]:
    path = directory / MANIFEST
    try:
        manifest = json.loads(path.read_text())
    except FileNotFoundError as exc:
        raise InvalidModel(f"no model database in {directory}: {MANIFEST} is missing") from exc
    except (OSError, ValueError) as exc:
        raise InvalidModel(f"{path} is not a readable manifest: {exc}") from exc
    if not isinstance(manifest, dict) or not isinstance(manifest.get("models"), list):
        raise InvalidModel(f"{path} is not a model database manifest (no list of models)")
    if manifest.get("format") != DATABASE_FORMAT:
        raise InvalidModel(
            f"{path} has format {manifest.get('format')!r}; expected {DATABASE_FORMAT}: "
            "rebuild the database"
        )
    if manifest.get("digest") != _manifest_digest(manifest):
        raise InvalidModel(f"{path} is damaged: its content does not match its digest")
    entries = manifest["models"]
    names = [e.get("name") if isinstance(e, dict) else None for e in entries]
    files = [e.get("file") if isinstance(e, dict) else None for e in entries]
    if len(set(map(str, names))) != len(names) or len(set(map(str, files))) != len(files):
        raise InvalidModel(f"{path} names a model or a file twice")
    return list(entries)


def _config(entry: dict[str, Any], path: Path) -> MeshModelConfig:
    raw = entry.get("config")
    known = {f.name for f in fields(MeshModelConfig)}
    if not isinstance(raw, dict) or set(raw) != known:
        raise InvalidModel(
            f"{path}: model {entry.get('name')!r} has table settings {raw!r}; expected the "
            f"keys {sorted(known)}"
        )
    try:
        return MeshModelConfig(**{**raw, "fit_sizes": tuple(raw["fit_sizes"])})
    except TypeError as exc:
        raise InvalidModel(f"{path}: model {entry.get('name')!r}: bad settings: {exc}") from exc


def _read(directory: Path, entry: dict[str, Any]) -> dict[str, np.ndarray]:
    name, file = entry.get("name"), entry.get("file")
    if not isinstance(name, str) or not name:
        raise InvalidModel(f"{directory / MANIFEST}: a model has no name")
    if not isinstance(file, str) or Path(file).name != file or file in ("", ".", ".."):
        raise InvalidModel(
            f"{directory / MANIFEST}: model {name!r} names the file {file!r}; expected a "
            "file in the database's folder"
        )
    path = directory / file
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InvalidModel(f"{path} (model {name!r}) cannot be read: {exc}") from exc
    if _digest(data) != entry.get("sha256"):
        raise InvalidModel(
            f"{path} (model {name!r}) is damaged: its bytes do not match the manifest"
        )
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            arrays = {k: z[k] for k in _ARRAYS}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise InvalidModel(f"{path} (model {name!r}) cannot be read: {exc}") from exc
    if str(arrays["name"]) != name:
        raise InvalidModel(f"{path} holds model {str(arrays['name'])!r}, the manifest {name!r}")
    _check_arrays(arrays, f"{path} (model {name!r})")
    return arrays


def _check_arrays(a: dict[str, np.ndarray], label: str) -> None:
    """Shapes, types, index ranges and finiteness of a model file's arrays."""

    def fail(what: str) -> None:
        raise InvalidModel(f"{label}: {what}")

    n = len(a["vertices"])
    for key, width in (("vertices", 3), ("normals", 3), ("table_d1", 3), ("vertex_d1", 3)):
        if a[key].ndim != 2 or a[key].shape[1] != width or a[key].dtype.kind != "f":
            fail(f"{key} must be a float (k, {width}) array, got {a[key].dtype} {a[key].shape}")
    if len(a["normals"]) != n:
        fail(f"{len(a['normals'])} normals for {n} vertices")
    faces = a["faces"]
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu" or not len(faces):
        fail(f"faces must be an integer (m, 3) array, got {faces.dtype} {faces.shape}")
    for key in ("faces", "table_vertex", "vertex_index"):
        index = a[key]
        if index.dtype.kind not in "iu" or (index.size and not 0 <= index.min() <= index.max() < n):
            fail(f"{key} must index the {n} vertices")
    for table, size in (("table", len(a["table_vertex"])), ("vertex", len(a["vertex_index"]))):
        for part in ("k1", "k2", "d1"):
            if len(a[f"{table}_{part}"]) != size:
                fail(f"{table}_{part} has {len(a[f'{table}_{part}'])} rows, expected {size}")
    rings = a["rings"]
    if rings.ndim != 3 or rings.shape[0] != len(a["vertex_index"]) or rings.dtype.kind != "f":
        rows = len(a["vertex_index"])
        fail(f"rings must be a float ({rows}, k, {DESCRIPTOR_SIZE}) array, got {rings.shape}")
    if rings.shape[1:] != (len(RADII_M), DESCRIPTOR_SIZE):
        expected = (len(RADII_M), DESCRIPTOR_SIZE)
        fail(f"rings hold {rings.shape[1:]} values per vertex, expected {expected}")
    if np.isinf(rings).any():
        fail("rings hold infinite values")
    for key in _ARRAYS[1:]:
        if key != "rings" and a[key].dtype.kind == "f" and not np.all(np.isfinite(a[key])):
            fail(f"{key} holds NaN or infinite values")
    if a["field_values"].ndim != 3 or a["field_origin"].shape != (3,):
        fail("the distance field must be a 3-D grid with a (3,) origin")
    if a["field_values"].dtype != np.float32:
        fail(f"the distance field must hold float32 values, got {a['field_values'].dtype}")
    if not (float(a["field_voxel"]) > 0 and float(a["field_band"]) > 0):
        fail("the distance field's voxel and band must be positive")
    symmetries = a["symmetries"]
    if symmetries.ndim != 3 or symmetries.shape[1:] != (4, 4) or symmetries.dtype.kind != "f":
        fail(f"symmetries must be a float (k, 4, 4) array, got {symmetries.shape}")
    rotations = symmetries[:, :3, :3]
    if np.any(np.abs(rotations @ np.swapaxes(rotations, 1, 2) - np.eye(3)) > 1e-6):
        fail("symmetries must be rigid motions")
    unit = np.linalg.norm(a["normals"], axis=1)
    if np.any(np.abs(unit - 1) > 1e-6):
        fail("normals must be unit vectors")


def read_models(directory: Path, config: MeshModelConfig | None = None) -> list[MeshModel]:
    """The models of the database in ``directory``, in order, verified whole.

    Raises
    ------
    InvalidModel
        The manifest or a model file is missing, damaged, of another format, refers
        outside the folder, or (with ``config``) the tables were built with other
        settings; the message names the file.
    """
    models = []
    for entry in _manifest(directory):
        if not isinstance(entry, dict):
            raise InvalidModel(f"{directory / MANIFEST}: a model entry is not an object")
        model_config = _config(entry, directory / MANIFEST)
        if config is not None and model_config != config:
            raise InvalidModel(
                f"{directory / MANIFEST}: model {entry['name']!r} was built with other table "
                "settings; rebuild the database"
            )
        a = _read(directory, entry)
        mesh = trimesh.Trimesh(a["vertices"], a["faces"], process=False)
        table = CurvatureTable(a["table_vertex"], a["table_k1"], a["table_k2"], a["table_d1"])
        field = DistanceField(
            a["field_origin"], float(a["field_voxel"]), a["field_values"], float(a["field_band"])
        )
        dense = CurvatureTable(
            a["vertex_index"],
            a["vertex_k1"].astype(float),
            a["vertex_k2"].astype(float),
            a["vertex_d1"].astype(float),
        )
        try:
            report = MeshReport.from_json(entry["report"])
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidModel(
                f"{directory / MANIFEST}: model {entry['name']!r} has no valid mesh report"
            ) from exc
        model = MeshModel(
            entry["name"],
            mesh,
            model_config,
            table,
            field,
            validate=False,
            candidate_curvatures=dense,
            normals=a["normals"],
            report=report,
            symmetries=a["symmetries"],
            rings=a["rings"],
        )
        if model.hash != entry.get("mesh_hash"):
            raise InvalidModel(
                f"{directory / entry['file']} (model {entry['name']!r}): the mesh does not "
                "match its hash; rebuild the database"
            )
        timings = entry.get("timings_s", {})
        if isinstance(timings, dict):
            model.timings.update({k: v for k, v in timings.items() if isinstance(v, float)})
        models.append(model)
    return models
