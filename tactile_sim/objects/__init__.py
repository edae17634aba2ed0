"""The object catalog: the thesis's ten free-form models as watertight meshes.

``load_object("cat")`` returns an :class:`ObjectModel` whose mesh is in metres in the
model frame (x forward, y left, z up; base on z = 0, bounding box centred on the z
axis). Meshes are generated from the recipes in ``assets/objects/`` on first use and
cached (:mod:`tactile_sim.objects.cache`).

Modules: :mod:`~tactile_sim.objects.recipe` (recipe schema and JSON),
:mod:`~tactile_sim.objects.sdf` (signed distance fields),
:mod:`~tactile_sim.objects.meshing` (SDF -> watertight mesh),
:mod:`~tactile_sim.objects.cache` (asset paths, content-keyed atomic cache) and
:mod:`~tactile_sim.objects.catalog` (the ten objects). Convex collision hulls are not
built here yet; they belong in this package, cached with
:mod:`~tactile_sim.objects.cache` and keyed by ``ObjectModel.recipe_hash``.
"""

from tactile_sim.objects.catalog import (
    OBJECT_NAMES,
    BuildInfo,
    ObjectModel,
    load_catalog,
    load_object,
    load_object_recipe,
    load_or_build,
    object_names,
)
from tactile_sim.objects.meshing import GENERATOR_VERSION, MeshingSettings, build_mesh
from tactile_sim.objects.recipe import ObjectRecipe

__all__ = [
    "GENERATOR_VERSION",
    "OBJECT_NAMES",
    "BuildInfo",
    "MeshingSettings",
    "ObjectModel",
    "ObjectRecipe",
    "build_mesh",
    "load_catalog",
    "load_object",
    "load_object_recipe",
    "load_or_build",
    "object_names",
]
