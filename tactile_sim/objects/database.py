"""The catalog's recognition database, built once and cached.

This is where the simulator hands its objects to the recognition library (a
``recognition.ModelDatabase`` of the catalog's meshes).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from typing import TYPE_CHECKING

from tactile_sim.errors import AssetError
from tactile_sim.objects.cache import build_lock, generated_dir
from tactile_sim.objects.catalog import (
    MeshingSettings,
    cache_key,
    load_catalog,
    load_object_recipe,
    object_names,
)

if TYPE_CHECKING:
    from recognition import ModelDatabase

__all__ = ["catalog_database"]


def catalog_database(*, progress: bool = True) -> ModelDatabase:
    """The :class:`recognition.ModelDatabase` of the ten catalog objects.

    Cached under ``assets/generated/database/<key>``, the key hashing every object's
    recipe hash, the table settings and the database format; a missing, stale or corrupt
    cache is rebuilt (with a progress bar and a one-line message), never trusted.
    """
    from recognition import DATABASE_FORMAT, InvalidModel, MeshModelConfig, ModelDatabase

    config = MeshModelConfig()
    settings = MeshingSettings()
    recipes = {n: cache_key(load_object_recipe(n), settings) for n in object_names()}
    payload = json.dumps([sorted(recipes.items()), repr(config), DATABASE_FORMAT])
    key = hashlib.sha256(payload.encode()).hexdigest()[:16]
    directory = generated_dir("database") / key
    try:
        return ModelDatabase.load(directory, config=config)
    except InvalidModel:
        pass
    with build_lock(directory.with_suffix(".lock")):
        try:
            return ModelDatabase.load(directory, config=config)
        except InvalidModel:
            catalog = load_catalog()
            if progress:
                print(
                    f"building the recognition database of {len(catalog)} objects "
                    f"(once; cached in {directory})",
                    flush=True,
                )
            database = ModelDatabase.from_meshes(
                {name: obj.mesh for name, obj in catalog.items()},
                config=config,
                progress=progress,
            )
            tmp = directory.with_name(directory.name + ".tmp")
            shutil.rmtree(tmp, ignore_errors=True)
            try:
                database.save(tmp)
                shutil.rmtree(directory, ignore_errors=True)
                tmp.rename(directory)
            except OSError as exc:
                raise AssetError(
                    f"cannot write the recognition database to {directory}: {exc}"
                ) from exc
            return ModelDatabase.load(directory, config=config)
