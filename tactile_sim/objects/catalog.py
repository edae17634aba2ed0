"""The ten free-form objects of the thesis's model database (Table 4.4).

The thesis's scans are not public: each object is a stand-in built from smooth implicit
primitives (``assets/objects/<name>.json``) with the bounding dimensions of Table 4.4
and about its vertex count. Meshes are generated on first use and cached under the
generated-assets directory (see :mod:`tactile_sim.objects.cache`), keyed by a hash of
the recipe, the meshing settings and the generator version.

Model frame of every object: metres, x forward (the object's front: head, nose, beak,
stalk), y to its left, z up; the bounding box is centred on the z axis and the base
rests on z = 0, so the object stands on a table at z = 0 as placed.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import trimesh
from tqdm.auto import tqdm

from tactile_sim.errors import UnknownObject
from tactile_sim.objects.cache import (
    build_lock,
    generated_dir,
    is_triangle_arrays,
    read_npz,
    recipes_dir,
    write_npz_atomic,
)
from tactile_sim.objects.meshing import GENERATOR_VERSION, MeshingSettings, build_mesh
from tactile_sim.objects.recipe import ObjectRecipe, load_recipe

__all__ = [
    "OBJECT_NAMES",
    "BuildInfo",
    "ObjectModel",
    "cache_key",
    "load_catalog",
    "load_object",
    "load_object_recipe",
    "load_or_build",
    "object_names",
]

#: Catalog names, in the order of the thesis's Table 4.4.
OBJECT_NAMES = (
    "pear",
    "stone",
    "monkey",
    "bird",
    "dog",
    "frog",
    "cat",
    "snail",
    "fish",
    "elephant",
)


@dataclass(frozen=True)
class BuildInfo:
    """How an object's mesh was generated.

    Attributes
    ----------
    generator_version : str
        :data:`tactile_sim.objects.meshing.GENERATOR_VERSION` at build time.
    voxel_size_m : float, metres
        Marching-cubes grid spacing.
    fit_scale : (3,) float
        Per-axis scale from the recipe's design to the target dimensions.
    build_seconds : float, seconds
        Wall time of the (cold) build.
    """

    generator_version: str
    voxel_size_m: float
    fit_scale: tuple[float, float, float]
    build_seconds: float


@dataclass(frozen=True)
class ObjectModel:
    """One catalog object.

    Attributes
    ----------
    name : str
        Catalog name.
    mesh : trimesh.Trimesh
        Closed, single-component, outward-wound surface in metres, in the model frame
        (x forward, y left, z up; bounding box centred on the z axis, base on z = 0).
    recipe_hash : str
        Hex SHA-256 of the recipe, meshing settings and generator version (the cache
        key); identifies the geometry.
    build : BuildInfo
        How the mesh was generated.
    """

    name: str
    mesh: trimesh.Trimesh
    recipe_hash: str
    build: BuildInfo

    @property
    def dimensions_m(self) -> np.ndarray:
        """(3,) bounding-box size along x, y, z, metres."""
        return np.ptp(np.asarray(self.mesh.vertices), axis=0)


def object_names() -> tuple[str, ...]:
    """Names of the catalog objects, in the thesis's Table 4.4 order."""
    return OBJECT_NAMES


def load_object_recipe(name: str) -> ObjectRecipe:
    """The recipe of a catalog object; raise UnknownObject for other names."""
    if name not in OBJECT_NAMES:
        raise UnknownObject(name, OBJECT_NAMES)
    return load_recipe(recipes_dir() / f"{name}.json")


def cache_key(recipe: ObjectRecipe, settings: MeshingSettings) -> str:
    """Hex SHA-256 of everything a mesh is made from."""
    salt = json.dumps(
        {"generator": GENERATOR_VERSION, "settings": asdict(settings)}, sort_keys=True
    )
    return recipe.content_hash(salt)


def _model_from_arrays(name: str, key: str, arrays: dict, meta: dict) -> ObjectModel | None:
    try:
        build = BuildInfo(
            generator_version=str(meta["generator_version"]),
            voxel_size_m=float(meta["voxel_size_m"]),
            fit_scale=tuple(float(v) for v in meta["fit_scale"]),
            build_seconds=float(meta["build_seconds"]),
        )
    except (KeyError, TypeError, ValueError):
        return None
    vertices, faces = arrays["vertices"], arrays["faces"]
    if (
        meta.get("key") != key
        or not is_triangle_arrays(vertices, faces)
        or faces.size == 0
        or faces.min() < 0
        or faces.max() >= len(vertices)
        or len(build.fit_scale) != 3
    ):
        return None
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
    return ObjectModel(name=name, mesh=mesh, recipe_hash=key, build=build)


def _read_model(path: Path, name: str, key: str) -> ObjectModel | None:
    """The cached model at ``path`` if it is readable, intact and made from ``key``."""
    cached = read_npz(path, ("vertices", "faces"))
    return None if cached is None else _model_from_arrays(name, key, *cached)


def load_or_build(
    recipe: ObjectRecipe,
    settings: MeshingSettings | None = None,
    *,
    progress: bool = True,
) -> ObjectModel:
    """The object of a recipe: read from the cache, or built and cached.

    Parameters
    ----------
    recipe : ObjectRecipe
    settings : MeshingSettings, optional
    progress : bool
        Print a one-line message and a progress bar (stderr) when building.

    Returns
    -------
    ObjectModel

    Raises
    ------
    InvalidMesh
        The recipe does not produce a valid mesh.
    """
    settings = settings or MeshingSettings()
    key = cache_key(recipe, settings)
    directory = generated_dir("objects")
    path = directory / f"{recipe.name}-{key[:16]}.npz"
    model = _read_model(path, recipe.name, key)
    if model is not None:
        return model

    with build_lock(directory / f".{recipe.name}.lock"):
        model = _read_model(path, recipe.name, key)  # another process may have built it
        if model is not None:
            return model
        bars: list[tqdm] = []

        def progress_factory(total: int) -> Callable[[int], None]:
            bar = tqdm(
                total=total,
                desc=recipe.name,
                unit="pt",
                unit_scale=True,
                leave=False,
                file=sys.stderr,
            )
            bars.append(bar)
            return bar.update

        if progress:
            tqdm.write(
                f"tactile_sim: building the {recipe.name!r} object mesh (first use; "
                f"cached in {directory})",
                file=sys.stderr,
            )
        try:
            built = build_mesh(recipe, settings, progress_factory if progress else None)
        finally:
            for bar in bars:
                bar.close()
        meta = {
            "key": key,
            "name": recipe.name,
            "generator_version": GENERATOR_VERSION,
            "voxel_size_m": built.voxel_size_m,
            "fit_scale": list(built.fit_scale),
            "build_seconds": built.build_seconds,
        }
        arrays = {"vertices": built.vertices, "faces": built.faces}
        write_npz_atomic(path, arrays, meta)
        for stale in directory.glob(f"{recipe.name}-*.npz"):
            if stale != path:
                stale.unlink(missing_ok=True)
    model = _model_from_arrays(recipe.name, key, arrays, meta)
    assert model is not None
    return model


def load_object(name: str) -> ObjectModel:
    """A catalog object by name, built on first use (see :func:`load_or_build`).

    Raises
    ------
    UnknownObject
        ``name`` is not in :func:`object_names`; the message lists the known names.
    """
    return load_or_build(load_object_recipe(name))


def load_catalog() -> dict[str, ObjectModel]:
    """Every catalog object, by name, in :func:`object_names` order."""
    return {name: load_object(name) for name in object_names()}
