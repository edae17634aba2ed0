"""The model database a benchmark recognises against: the catalog's, one built from a
folder of meshes, or both together."""

from __future__ import annotations

import hashlib
from pathlib import Path

from recognition import DATABASE_FORMAT, MeshModelConfig, ModelDatabase, RecognitionError
from recognition.surfaces.mesh_files import MESH_SUFFIXES, read_mesh
from tactile_sim.evaluation.benchmark_config import MeshSettings

__all__ = ["benchmark_database", "mesh_files"]


def mesh_files(mesh_dir: Path) -> list[Path]:
    """The mesh files of a folder, sorted by name (:data:`MESH_SUFFIXES`).

    Raises
    ------
    RecognitionError
        The folder holds none.
    """
    files = sorted(p for p in Path(mesh_dir).iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    if not files:
        raise RecognitionError(
            f"no mesh files in {mesh_dir}; expected files ending in {', '.join(MESH_SUFFIXES)}"
        )
    return files


def benchmark_database(meshes: MeshSettings, size: int | None = None) -> tuple[ModelDatabase, str]:
    """The catalog's database, one of ``size`` models (the catalog's and generated ones:
    :func:`~tactile_sim.objects.database.sized_database`), or one built from
    ``meshes.mesh_dir`` (with the catalog's models too when ``meshes.with_catalog``),
    cached, and its name.

    A folder's database is kept under ``meshes.cache_dir`` by a hash of the files' names
    and contents, the units, the table settings, the database format (and the catalog's
    database), and loaded from there on the next run: an edited mesh is a new database.
    Each model's repairs are in its ``report``.

    Raises
    ------
    RecognitionError
        The folder holds no mesh file, or a mesh cannot be a model (e.g. millimetres read
        as metres).
    """
    from tactile_sim.objects.database import cached_database, catalog_database, sized_database

    if size is not None:
        return sized_database(size), f"database_{size}"
    if meshes.mesh_dir is None:
        return catalog_database(), "catalog"
    mesh_dir = Path(meshes.mesh_dir)
    files = mesh_files(mesh_dir)
    config = MeshModelConfig()
    catalog = catalog_database() if meshes.with_catalog else None
    digest = hashlib.sha256(repr((meshes.units, config, DATABASE_FORMAT)).encode())
    for p in files:
        digest.update(p.name.encode())
        digest.update(p.read_bytes())
    if catalog is not None:
        assert catalog.directory is not None
        digest.update(catalog.directory.name.encode())
    directory = Path(meshes.cache_dir) / digest.hexdigest()[:16]

    def build() -> ModelDatabase:
        models = {p.stem: read_mesh(p, meshes.units) for p in files}
        built = ModelDatabase.from_meshes(models, config=config, progress=True)
        if catalog is None:
            return built
        return ModelDatabase({**catalog.models, **built.models}).prepare()

    what = f"a database of {len(files)} meshes from {mesh_dir}"
    if catalog is not None:
        what += " and the catalog's"
    database = cached_database(directory, build, what, config=config)
    return database, mesh_dir.name + ("_and_catalog" if catalog is not None else "")
