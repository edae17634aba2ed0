"""Convex decomposition of a mesh with CoACD after decimation, cached by a hash of its inputs."""

from __future__ import annotations

import hashlib
import json
import sys
import threading
import time
from dataclasses import asdict
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tactile_sim.collision.config import DecompositionConfig, library_versions
from tactile_sim.collision.deviation import hull_surface_deviation
from tactile_sim.collision.hulls import convex_hull_part, is_closed_manifold, is_convex, mesh_arrays
from tactile_sim.collision.parts import (
    ConvexParts,
    read_parts,
    safe_name,
    shipped_hulls_dir,
    write_parts,
)
from tactile_sim.errors import InvalidMesh
from tactile_sim.objects.cache import build_lock, generated_dir

if TYPE_CHECKING:
    from tactile_sim.objects import ObjectModel

__all__ = [
    "DECOMPOSITION_VERSION",
    "convex_decomposition",
    "decimate",
    "decomposition_key",
    "object_parts",
]


DECOMPOSITION_VERSION = "1"
"""Bumped whenever the decomposition code changes what it produces (part of the cache key)."""


_CACHE_KIND = "hulls"


def decomposition_key(
    mesh: Any, config: DecompositionConfig, geometry_key: str | None = None
) -> str:
    """Returns the hex SHA-256 of a mesh's arrays, the config and the library versions.

    Parameters
    ----------
    mesh : trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        Vertices in metres and triangles.
    config : DecompositionConfig
    geometry_key : str or None
        A key that identifies the mesh by what it was made from (a catalog object's
        recipe hash); it replaces the arrays in the hash, so that the last bits of a
        regenerated mesh (floating-point differences between CPUs) do not matter.
    """
    digest = hashlib.sha256()
    salt = {
        "version": DECOMPOSITION_VERSION,
        "config": asdict(config),
        "libraries": library_versions(),
    }
    digest.update(json.dumps(salt, sort_keys=True).encode())
    if geometry_key is not None:
        digest.update(f"geometry:{geometry_key}".encode())
        return digest.hexdigest()
    vertices, faces = mesh_arrays(mesh)
    digest.update(f"{vertices.shape};".encode())
    digest.update(vertices.tobytes())
    digest.update(f"{faces.shape};".encode())
    digest.update(faces.tobytes())
    return digest.hexdigest()


def decimate(
    vertices: ArrayLike, faces: ArrayLike, target_faces: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns a closed manifold copy of a mesh with at most about ``target_faces`` faces.

    Quadric edge collapse (``fast_simplification``). A collapse can leave an edge shared
    by four faces, and CoACD would then remesh the whole input on a coarse voxel grid
    (errors of a millimetre): such results are rejected and the decimation retried with
    25 % more faces, up to the original mesh. A mesh already small enough is returned
    unchanged.

    Parameters
    ----------
    vertices : (n, 3) float, metres
    faces : (m, 3) int
    target_faces : int

    Returns
    -------
    vertices : (n', 3) float, metres
    faces : (m', 3) int
    """
    import fast_simplification

    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    target = target_faces
    while target < len(faces):
        v, f = fast_simplification.simplify(vertices, faces, target_count=target)
        f = np.asarray(f, dtype=np.int64)
        if is_closed_manifold(f):
            return np.asarray(v, dtype=np.float64), f
        target = int(target * 1.25)
    return vertices, faces


def _run_coacd(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    config: DecompositionConfig,
    label: str,
    progress: bool,
) -> list[tuple[NDArray[np.float64], NDArray[np.int64]]]:
    """CoACD on a mesh, with a progress bar that shows the elapsed time while it runs."""
    import coacd
    from tqdm.auto import tqdm

    coacd.set_log_level("error")
    result: dict[str, Any] = {}

    def work() -> None:
        try:
            result["parts"] = coacd.run_coacd(
                coacd.Mesh(vertices, faces.astype(np.int32)),
                threshold=config.threshold,
                max_convex_hull=config.max_convex_hull,
                preprocess_mode=config.preprocess_mode,
                preprocess_resolution=config.preprocess_resolution,
                resolution=config.resolution,
                mcts_nodes=config.mcts_nodes,
                mcts_iterations=config.mcts_iterations,
                mcts_max_depth=config.mcts_max_depth,
                seed=config.seed,
            )
        except BaseException as error:  # re-raised in the calling thread
            result["error"] = error

    # CoACD runs in C through ctypes (the GIL is released), so the bar can tick meanwhile.
    thread = threading.Thread(target=work, name=f"coacd-{label}", daemon=True)
    bar = (
        tqdm(
            desc=f"{label}: CoACD",
            total=None,
            unit="s",
            bar_format="{desc}: {elapsed} elapsed",
            leave=False,
            file=sys.stderr,
        )
        if progress
        else None
    )
    thread.start()
    while thread.is_alive():
        thread.join(timeout=1.0)
        if bar is not None:
            bar.refresh()
    if bar is not None:
        bar.close()
    if "error" in result:
        raise InvalidMesh(f"{label}: CoACD failed: {result['error']}") from result["error"]
    parts = []
    for part_vertices, _ in result["parts"]:
        points = np.asarray(part_vertices, dtype=np.float64)
        if len(points) < 4:
            continue
        try:
            parts.append(convex_hull_part(points))
        except InvalidMesh:
            continue  # a flat sliver: nothing a probe can touch
    if not parts:
        raise InvalidMesh(f"{label}: CoACD returned no usable convex part")
    return parts


def convex_decomposition(
    mesh: Any,
    config: DecompositionConfig | None = None,
    *,
    name: str = "mesh",
    progress: bool = True,
    measure: bool = True,
    convex: bool | None = None,
    geometry_key: str | None = None,
) -> ConvexParts:
    """Returns the convex collision parts of a closed mesh, from the cache or built.

    The parts come from the shipped hulls, then the generated-assets cache; a convex mesh
    is its own single part (no CoACD, nothing cached); otherwise, on a miss, the mesh is
    decimated to ``config.target_faces`` and decomposed with CoACD (tens of seconds: a
    message and a progress bar go to stderr when ``progress``), then cached atomically.
    Parallel processes asking for the same parts build them once (a file lock).

    Parameters
    ----------
    mesh : trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        Closed surface, metres.
    config : DecompositionConfig or None
        Decomposition parameters; None uses the defaults.
    name : str
        Label used in file names and messages (e.g. the catalog name).
    progress : bool
        Announce a cold build on stderr with a progress bar.
    measure : bool
        On a cold build, also measure the parts' deviation from the mesh
        (:func:`hull_surface_deviation`, a few seconds) and store it with them.
    convex : bool or None
        Whether the mesh is known to be convex (True: its hull is the single part, no
        lookup); None: the caches are looked up first, then the mesh is tested.
    geometry_key : str or None
        Identifies the mesh by what it was made from (see :func:`decomposition_key`);
        :func:`object_parts` passes a catalog object's recipe hash.

    Raises
    ------
    InvalidMesh
        The mesh is malformed or CoACD fails on it.
    """
    config = config or DecompositionConfig()
    vertices, faces = mesh_arrays(mesh)
    key = decomposition_key((vertices, faces), config, geometry_key)
    if convex:
        return ConvexParts(parts=(convex_hull_part(vertices),), key=key, source="convex")

    stem = f"{safe_name(name)}-{key[:16]}"
    shipped = read_parts(shipped_hulls_dir() / f"{stem}.npz", key, "shipped")
    if shipped is not None:
        return shipped
    directory = generated_dir(_CACHE_KIND)
    path = directory / f"{stem}.npz"
    cached = read_parts(path, key, "cache")
    if cached is not None:
        return cached
    if convex is None and is_convex(vertices, faces):
        return ConvexParts(parts=(convex_hull_part(vertices),), key=key, source="convex")

    with build_lock(directory / f".{stem}.lock"):
        cached = read_parts(path, key, "cache")  # another process may have built it
        if cached is not None:
            return cached
        if progress:
            from tqdm.auto import tqdm

            tqdm.write(
                f"tactile_sim: building the convex collision parts of {name!r} "
                f"(CoACD, threshold {config.threshold}, {min(len(faces), config.target_faces)}"
                f" faces; first use, cached in {directory})",
                file=sys.stderr,
            )
        start = time.perf_counter()
        small_vertices, small_faces = decimate(vertices, faces, config.target_faces)
        parts = _run_coacd(small_vertices, small_faces, config, name, progress)
        build_seconds = time.perf_counter() - start
        accuracy = (
            hull_surface_deviation(parts, (vertices, faces), n_samples=20_000) if measure else None
        )
        result = ConvexParts(
            parts=tuple(parts),
            key=key,
            source="built",
            build_seconds=build_seconds,
            accuracy=accuracy,
        )
        write_parts(path, result, name, config)
    return result


def object_parts(
    model: ObjectModel, config: DecompositionConfig | None = None, *, progress: bool = True
) -> ConvexParts:
    """Returns a catalog object's convex parts, keyed by its recipe hash (shipped or cached).

    Parameters
    ----------
    model : tactile_sim.objects.ObjectModel
    config : DecompositionConfig or None
        None: the defaults.
    progress : bool
        Announce a cold build on stderr with a progress bar.
    """
    return convex_decomposition(
        model.mesh, config, name=model.name, progress=progress, geometry_key=model.recipe_hash
    )
