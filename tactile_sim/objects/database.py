"""The catalog's recognition database, built once and cached.

This is where the simulator hands its objects to the recognition library (a
``recognition.ModelDatabase`` of the catalog's meshes).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from tactile_sim.errors import AssetError
from tactile_sim.objects.cache import build_lock, generated_dir
from tactile_sim.objects.catalog import (
    MeshingSettings,
    cache_key,
    load_catalog,
    load_object_recipe,
    load_or_build,
    object_names,
)
from tactile_sim.objects.generated import generated_recipe

if TYPE_CHECKING:
    from recognition import MeshModelConfig, ModelDatabase

__all__ = ["cached_database", "catalog_database", "sized_database"]


def cached_database(
    directory: Path,
    build: Callable[[], ModelDatabase],
    what: str,
    *,
    config: MeshModelConfig | None = None,
    progress: bool = True,
) -> ModelDatabase:
    """The database cached in ``directory``, else ``build()`` saved there and loaded back.

    A missing database is built with a one-line message naming ``what``; one that
    cannot be used (damaged, of another format, built with other settings) is rebuilt
    with a one-line notice saying why. Concurrent processes build it once (a lock).

    Raises
    ------
    AssetError
        The database cannot be written.
    """
    from recognition import InvalidModel, ModelDatabase

    try:
        return ModelDatabase.load(directory, config=config)
    except InvalidModel:
        pass
    directory.parent.mkdir(parents=True, exist_ok=True)
    with build_lock(directory.with_suffix(".lock")):
        try:
            return ModelDatabase.load(directory, config=config)
        except InvalidModel as exc:
            if progress and directory.exists():
                print(f"{what}: the cached database cannot be used ({exc}); rebuilding it")
            elif progress:
                print(f"building {what} (once; cached in {directory})", flush=True)
        database = build()
        tmp = directory.with_name(directory.name + ".tmp")
        shutil.rmtree(tmp, ignore_errors=True)
        try:
            database.save(tmp)
            shutil.rmtree(directory, ignore_errors=True)
            tmp.rename(directory)
        except OSError as exc:
            raise AssetError(f"cannot write the database to {directory}: {exc}") from exc
        return ModelDatabase.load(directory, config=config)


def catalog_database(*, progress: bool = True) -> ModelDatabase:
    """The :class:`recognition.ModelDatabase` of the ten catalog objects.

    Cached under ``assets/generated/database/<key>``, the key hashing every object's
    recipe hash, the table settings and the database format; a missing, stale or damaged
    cache is rebuilt (with a progress bar and a one-line message), never trusted
    (:func:`cached_database`).
    """
    from recognition import DATABASE_FORMAT, MeshModelConfig, ModelDatabase

    config = MeshModelConfig()
    settings = MeshingSettings()
    recipes = {n: cache_key(load_object_recipe(n), settings) for n in object_names()}
    payload = json.dumps([sorted(recipes.items()), repr(config), DATABASE_FORMAT])
    key = hashlib.sha256(payload.encode()).hexdigest()[:16]

    def build() -> ModelDatabase:
        catalog = load_catalog()
        return ModelDatabase.from_meshes(
            {name: obj.mesh for name, obj in catalog.items()}, config=config, progress=progress
        )

    return cached_database(
        generated_dir("database") / key,
        build,
        f"the recognition database of the {len(recipes)} catalog objects",
        config=config,
        progress=progress,
    )


def sized_database(size: int, *, seed: int = 0, progress: bool = True) -> ModelDatabase:
    """A database of ``size`` models: the catalog's first, then generated objects
    (:mod:`tactile_sim.objects.generated`, seed ``seed``: ``blob-000``, ``blob-001``, ...).

    Built once, with a progress bar per step, and cached like :func:`catalog_database`
    under ``assets/generated/database/size-<size>-<key>``, the key hashing every model's
    recipe hash, the table settings and the database format. The generated meshes are
    cached one by one (:func:`~tactile_sim.objects.catalog.load_or_build`): an
    interrupted build resumes from the last mesh made.

    Raises
    ------
    ValueError
        ``size`` is below 1.
    """
    from recognition import DATABASE_FORMAT, MeshModelConfig, ModelDatabase

    if isinstance(size, bool) or not isinstance(size, int) or size < 1:
        raise ValueError(f"a database needs a whole number of models >= 1, got {size!r}")
    names = object_names()[:size]
    recipes = [generated_recipe(i, seed) for i in range(size - len(names))]
    config = MeshModelConfig()
    settings = MeshingSettings()
    keys = [cache_key(load_object_recipe(n), settings) for n in names]
    keys += [cache_key(r, settings) for r in recipes]
    payload = json.dumps([keys, repr(config), DATABASE_FORMAT])
    key = hashlib.sha256(payload.encode()).hexdigest()[:16]

    def build() -> ModelDatabase:
        from tqdm.auto import tqdm

        catalog = catalog_database(progress=progress)
        meshes = {
            r.name: load_or_build(r, settings, progress=False).mesh
            for r in tqdm(recipes, desc="generating meshes", unit="object", disable=not progress)
        }
        chosen = {n: catalog[n] for n in names}
        if meshes:
            built = ModelDatabase.from_meshes(meshes, config=config, progress=progress)
            chosen.update(built.models)
        return ModelDatabase(chosen).prepare()

    return cached_database(
        generated_dir("database") / f"size-{size}-{key}",
        build,
        f"a database of {size} models ({len(names)} catalog, {len(recipes)} generated)",
        config=config,
        progress=progress,
    )
