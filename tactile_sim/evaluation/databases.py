"""The model database a benchmark recognises against: the catalog's, or one built from meshes."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from recognition import ModelDatabase, RecognitionError
from tactile_sim.evaluation.benchmark_config import MeshSettings

__all__ = ["MESH_SUFFIXES", "benchmark_database"]

#: Mesh files a mesh directory may hold.
MESH_SUFFIXES = (".obj", ".ply", ".stl")


def benchmark_database(meshes: MeshSettings) -> tuple[ModelDatabase, str]:
    """The catalog's database, or one built from ``meshes.mesh_dir`` (cached), and its name.

    A mesh directory's database is kept under ``meshes.cache_dir`` by a hash of the
    files' names and contents and the units, and loaded from there on the next run.

    Raises
    ------
    RecognitionError
        The directory holds no mesh, or a mesh is not a usable model (e.g. millimetres
        read as metres).
    """
    from tactile_sim.objects.database import cached_database, catalog_database

    if meshes.mesh_dir is None:
        return catalog_database(), "catalog"
    import trimesh

    mesh_dir = Path(meshes.mesh_dir)
    files = sorted(p for p in mesh_dir.iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    if not files:
        raise RecognitionError(f"no OBJ, PLY or STL files in {mesh_dir}")
    scale = {"m": 1.0, "mm": 1e-3}[meshes.units]
    digest = hashlib.sha256()
    for p in files:
        digest.update(p.name.encode())
        digest.update(p.read_bytes())
    digest.update(str(scale).encode())
    directory = Path(meshes.cache_dir) / digest.hexdigest()[:16]

    def build() -> ModelDatabase:
        models: dict[str, Any] = {}
        for p in files:
            mesh = trimesh.load(p, force="mesh")
            mesh.apply_scale(scale)
            models[p.stem] = mesh
        return ModelDatabase.from_meshes(models, progress=True)

    what = f"a database of {len(files)} meshes from {mesh_dir}"
    return cached_database(directory, build, what), mesh_dir.name
