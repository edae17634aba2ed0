"""Convex collision geometry for MuJoCo: cached CoACD decompositions and closed-form solids.

MuJoCo collides every mesh geom as its convex hull, so a non-convex object is a body of
convex parts. :func:`convex_decomposition` decimates a mesh (``fast_simplification``) and
splits it with CoACD; the parts are cached as ``.npz`` files keyed by a hash of the mesh
and every parameter, written atomically. Lookup order: the hulls shipped with the
repository (``assets/hulls/``), then the generated-assets cache (``assets/generated/hulls/``
or ``$TACTILE_ASSETS_DIR/hulls/``, see :mod:`tactile_sim.objects.cache`). A warm start
reads a file; only a cold start runs CoACD (tens of seconds per object), announced on
stderr with a progress bar.

Parameters (measured on the catalog, 20k faces): see :class:`DecompositionConfig`.

The closed-form solids of thesis Fig. 4.15 (two circular cylinders, an elliptic cylinder,
a sphere) and the extruded outlines of the planar experiments of thesis Section 3.4.2
(an ellipse a = 25 mm, b = 17.5 mm and a closed cubic spline of five segments) are
generated here as meshes (:func:`load_solid`); they are convex and collide as one hull.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
import math
import sys
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull

from tactile_sim.errors import InvalidMesh, UnknownObject
from tactile_sim.objects.cache import (
    build_lock,
    generated_dir,
    is_triangle_arrays,
    read_npz,
    write_npz_atomic,
)

if TYPE_CHECKING:
    from tactile_sim.objects import ObjectModel

__all__ = [
    "DECOMPOSITION_VERSION",
    "SOLID_NAMES",
    "ConvexParts",
    "DecompositionConfig",
    "HullAccuracy",
    "Solid",
    "build_shipped_hulls",
    "closed_spline_coefficients",
    "closed_spline_outline",
    "convex_decomposition",
    "convex_hull_part",
    "decimate",
    "decomposition_key",
    "ellipse_outline",
    "extrude_outline",
    "hull_surface_deviation",
    "load_solid",
    "object_parts",
    "shipped_hulls_dir",
    "solid_names",
    "sphere_mesh",
    "write_shipped_parts",
]

DECOMPOSITION_VERSION = "1"
"""Bumped whenever the decomposition code changes what it produces (part of the cache key)."""

_SHIPPED_HULLS_DIR = Path(__file__).resolve().parent.parent / "assets" / "hulls"
_CACHE_KIND = "hulls"
_CONVEX_VOLUME_TOLERANCE = 1e-6
"""A mesh whose volume is within this fraction of its convex hull's counts as convex."""
_SHARED_FACE_TOLERANCE_M = 1e-5
"""A sampled point this close to (or inside) another part is not on the union's surface
(CoACD's cut faces shared by two parts match to a few micrometres)."""


def shipped_hulls_dir() -> Path:
    """Returns the directory of the hulls shipped with the repository (``assets/hulls``)."""
    return _SHIPPED_HULLS_DIR


@dataclass(frozen=True)
class DecompositionConfig:
    """How a mesh is split into convex parts (CoACD after decimation).

    The defaults were chosen from measured accuracy on the catalog objects (see the module
    docstring and ``hull_surface_deviation``): on 20k-face copies threshold 0.02 keeps the
    union of the parts within a few hundredths of a millimetre of the original surface.

    Attributes
    ----------
    target_faces : int
        The mesh is decimated (quadric edge collapse) to at most this many faces first;
        meshes with fewer faces are used as they are.
    threshold : float
        CoACD concavity threshold, a fraction of the bounding-box diagonal (dimensionless);
        smaller means more, tighter parts and a longer run.
    preprocess_mode : str
        CoACD's manifold pre-processing: ``"auto"`` (only for non-manifold input), ``"on"``
        or ``"off"``.
    preprocess_resolution : int
        Voxel resolution of that pre-processing.
    resolution : int
        CoACD's sampling resolution for the concavity metric.
    mcts_nodes, mcts_iterations, mcts_max_depth : int
        CoACD's Monte-Carlo tree search budget.
    max_convex_hull : int
        Cap on the number of parts (-1: none).
    seed : int
        CoACD's random seed: the same mesh and config give the same parts.
    """

    target_faces: int = 20_000
    threshold: float = 0.015
    preprocess_mode: str = "auto"
    preprocess_resolution: int = 50
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 150
    mcts_max_depth: int = 3
    max_convex_hull: int = -1
    seed: int = 0

    def __post_init__(self) -> None:
        if self.target_faces < 100:
            raise ValueError(f"target_faces must be >= 100, got {self.target_faces}")
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"threshold must lie in (0, 1), got {self.threshold}")
        if self.preprocess_mode not in ("auto", "on", "off"):
            raise ValueError(
                f"preprocess_mode must be 'auto', 'on' or 'off', got {self.preprocess_mode!r}"
            )


@dataclass(frozen=True)
class HullAccuracy:
    """How far the exposed surface of a union of convex parts lies from the original mesh.

    Attributes
    ----------
    n_samples : int
        Points sampled on the parts' surfaces that are not inside another part.
    mean_m, p95_m, max_m : float, metres
        Mean, 95th percentile and maximum distance of those points to the original mesh.
    """

    n_samples: int
    mean_m: float
    p95_m: float
    max_m: float


@dataclass(frozen=True)
class ConvexParts:
    """The convex collision parts of one mesh.

    Attributes
    ----------
    parts : tuple of ((n_i, 3) float, (m_i, 3) int) pairs
        Vertices (metres, the mesh's frame) and outward-wound triangles of each convex part.
    key : str
        Hex SHA-256 of the mesh and the parameters the parts were made from.
    source : str
        Where they came from: ``"shipped"``, ``"cache"``, ``"built"`` or ``"convex"`` (the
        mesh is convex: its own hull, no CoACD).
    build_seconds : float, seconds
        Wall time of the decomposition when it was built (0 for a convex mesh).
    accuracy : HullAccuracy or None
        Deviation of the parts' exposed surface from the mesh, measured at build time.
    """

    parts: tuple[tuple[NDArray[np.float64], NDArray[np.int64]], ...]
    key: str
    source: str
    build_seconds: float = 0.0
    accuracy: HullAccuracy | None = None

    @property
    def n_parts(self) -> int:
        """Returns the number of convex parts."""
        return len(self.parts)

    @property
    def n_vertices(self) -> int:
        """Returns the total number of part vertices."""
        return sum(len(v) for v, _ in self.parts)


def _mesh_arrays(mesh: Any) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Checked (n, 3) float64 vertices and (m, 3) int64 faces of a mesh or (V, F) pair."""
    if isinstance(mesh, tuple):
        vertices, faces = mesh
    else:
        vertices, faces = mesh.vertices, mesh.faces
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
        raise InvalidMesh(f"vertices must be (n >= 4, 3), got shape {vertices.shape}")
    if not np.all(np.isfinite(vertices)):
        raise InvalidMesh("vertices hold NaN or infinite values")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) < 4:
        raise InvalidMesh(f"faces must be (m >= 4, 3), got shape {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMesh(f"face indices must lie in [0, {len(vertices) - 1}]")
    return vertices, faces


def _library_versions() -> dict[str, str]:
    """Versions of the libraries whose output the parts depend on."""
    versions = {}
    for package in ("coacd", "fast_simplification"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = "missing"
    return versions


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
        "libraries": _library_versions(),
    }
    digest.update(json.dumps(salt, sort_keys=True).encode())
    if geometry_key is not None:
        digest.update(f"geometry:{geometry_key}".encode())
        return digest.hexdigest()
    vertices, faces = _mesh_arrays(mesh)
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
        if _is_closed_manifold(f):
            return np.asarray(v, dtype=np.float64), f
        target = int(target * 1.25)
    return vertices, faces


def _is_closed_manifold(faces: NDArray[np.int64]) -> bool:
    """True if every edge of the triangles is shared by exactly two of them."""
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def convex_hull_part(points: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the convex hull of points as (vertices (k, 3), outward faces (m, 3)).

    Parameters
    ----------
    points : (n, 3) float, metres
        At least four points spanning three dimensions.
    """
    points = np.asarray(points, dtype=np.float64)
    try:
        hull = ConvexHull(points)
    except Exception as error:  # scipy raises QhullError (not exported on every version)
        raise InvalidMesh(f"cannot build a convex hull of {len(points)} points: {error}") from error
    used = hull.vertices
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    faces = remap[hull.simplices]
    vertices = points[used]
    # Orient every triangle outward: its normal must agree with the facet's plane normal.
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, ::-1]
    return vertices, faces


def _is_convex(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> bool:
    """True if the closed mesh's volume equals its convex hull's (within a tolerance)."""
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
    try:
        hull_volume = ConvexHull(vertices).volume
    except Exception:
        return False
    volume = abs(float(mesh.volume))
    return hull_volume > 0 and volume >= (1.0 - _CONVEX_VOLUME_TOLERANCE) * hull_volume


def hull_surface_deviation(
    parts: Sequence[tuple[ArrayLike, ArrayLike]],
    mesh: Any,
    n_samples: int = 50_000,
    seed: int = 0,
) -> HullAccuracy:
    """Returns how far the exposed surface of a union of convex parts lies from a mesh.

    Points are sampled uniformly (by area) on every part's hull; those strictly inside
    another part are dropped (they are not on the union's surface, which is what a probe
    can touch); the rest are measured against the mesh with libigl's AABB tree (exact
    point-triangle distances; ``trimesh.proximity`` is not reliable at this scale).

    Parameters
    ----------
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        Convex parts, metres.
    mesh : trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        The original surface, same frame.
    n_samples : int
        Points sampled over all parts before the interior ones are dropped.
    seed : int
        Sampling seed.
    """
    import igl

    rng = np.random.default_rng(seed)
    hulls = []
    for vertices, _ in parts:
        hull = ConvexHull(np.asarray(vertices, dtype=np.float64))
        hulls.append((hull.points[hull.simplices], hull.equations))
    areas = [
        0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
        for t, _ in hulls
    ]
    total = sum(float(a.sum()) for a in areas)
    exposed = []
    for i, ((triangles, _), area) in enumerate(zip(hulls, areas, strict=True)):
        k = max(1, round(n_samples * float(area.sum()) / total))
        index = rng.choice(len(triangles), size=k, p=area / area.sum())
        u, v = rng.random((2, k))
        swap = u + v > 1.0
        u[swap], v[swap] = 1.0 - u[swap], 1.0 - v[swap]
        t = triangles[index]
        points = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
        # Inside or on another part (cut faces shared by two parts are not exposed).
        inside = np.zeros(k, dtype=bool)
        for j, (_, equations) in enumerate(hulls):
            if j != i:
                offsets = points @ equations[:, :3].T + equations[:, 3]
                inside |= np.all(offsets < _SHARED_FACE_TOLERANCE_M, axis=1)
        exposed.append(points[~inside])
    points = np.concatenate(exposed)
    vertices, faces = _mesh_arrays(mesh)
    tree = igl.AABB()
    tree.init(vertices, faces)
    squared, _, _ = tree.squared_distance(vertices, faces, points)
    distance = np.sqrt(squared)
    return HullAccuracy(
        n_samples=len(points),
        mean_m=float(distance.mean()),
        p95_m=float(np.percentile(distance, 95)),
        max_m=float(distance.max()),
    )


def _read_parts(path: Path, key: str, source: str) -> ConvexParts | None:
    """The parts cached at ``path`` if the file is intact and made from ``key``, else None."""
    cached = read_npz(path, ("vertices", "faces", "vertex_counts", "face_counts"))
    if cached is None:
        return None
    arrays, meta = cached
    vertices, faces = arrays["vertices"], arrays["faces"]
    vertex_counts, face_counts = arrays["vertex_counts"], arrays["face_counts"]
    if (
        meta.get("key") != key
        or not is_triangle_arrays(vertices, faces)
        or vertex_counts.shape != face_counts.shape
        or vertex_counts.ndim != 1
        or len(vertex_counts) == 0
        or int(vertex_counts.sum()) != len(vertices)
        or int(face_counts.sum()) != len(faces)
        or np.any(vertex_counts < 4)
        or np.any(face_counts < 4)
    ):
        return None
    parts = []
    v_start = f_start = 0
    for nv, nf in zip(vertex_counts.tolist(), face_counts.tolist(), strict=True):
        v = vertices[v_start : v_start + nv].astype(np.float64)
        f = faces[f_start : f_start + nf].astype(np.int64)
        if f.min() < 0 or f.max() >= nv:
            return None
        parts.append((v, f))
        v_start += nv
        f_start += nf
    accuracy = None
    if isinstance(meta.get("accuracy"), dict):
        try:
            accuracy = HullAccuracy(**meta["accuracy"])
        except TypeError:
            accuracy = None
    return ConvexParts(
        parts=tuple(parts),
        key=key,
        source=source,
        build_seconds=float(meta.get("build_seconds", 0.0)),
        accuracy=accuracy,
    )


def _write_parts(path: Path, parts: ConvexParts, name: str, config: DecompositionConfig) -> None:
    """Writes parts atomically (float32 vertices: below 0.01 um rounding within 1 m)."""
    arrays = {
        "vertices": np.concatenate([v for v, _ in parts.parts]).astype(np.float32),
        "faces": np.concatenate([f for _, f in parts.parts]).astype(np.int32),
        "vertex_counts": np.array([len(v) for v, _ in parts.parts], dtype=np.int64),
        "face_counts": np.array([len(f) for _, f in parts.parts], dtype=np.int64),
    }
    meta = {
        "key": parts.key,
        "name": name,
        "config": asdict(config),
        "libraries": _library_versions(),
        "build_seconds": parts.build_seconds,
        "accuracy": None if parts.accuracy is None else asdict(parts.accuracy),
    }
    write_npz_atomic(path, arrays, meta)


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
    vertices, faces = _mesh_arrays(mesh)
    key = decomposition_key((vertices, faces), config, geometry_key)
    if convex:
        return ConvexParts(parts=(convex_hull_part(vertices),), key=key, source="convex")

    stem = f"{_safe_name(name)}-{key[:16]}"
    shipped = _read_parts(shipped_hulls_dir() / f"{stem}.npz", key, "shipped")
    if shipped is not None:
        return shipped
    directory = generated_dir(_CACHE_KIND)
    path = directory / f"{stem}.npz"
    cached = _read_parts(path, key, "cache")
    if cached is not None:
        return cached
    if convex is None and _is_convex(vertices, faces):
        return ConvexParts(parts=(convex_hull_part(vertices),), key=key, source="convex")

    with build_lock(directory / f".{stem}.lock"):
        cached = _read_parts(path, key, "cache")  # another process may have built it
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
        _write_parts(path, result, name, config)
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


def write_shipped_parts(parts: ConvexParts, name: str, config: DecompositionConfig) -> Path:
    """Writes parts into the shipped-hulls directory, replacing older files of ``name``.

    For maintainers: after the catalog meshes change, rebuild the parts (e.g.
    ``object_parts(load_object(n))``) and ship them with this.

    Returns
    -------
    Path
        The written file.
    """
    directory = shipped_hulls_dir()
    directory.mkdir(parents=True, exist_ok=True)
    stem = f"{_safe_name(name)}-{parts.key[:16]}"
    path = directory / f"{stem}.npz"
    _write_parts(path, parts, name, config)
    for stale in directory.glob(f"{_safe_name(name)}-*.npz"):
        if stale != path:
            stale.unlink(missing_ok=True)
    return path


def build_shipped_hulls(
    names: Sequence[str] | None = None,
    config: DecompositionConfig | None = None,
    *,
    progress: bool = True,
) -> dict[str, Path]:
    """Builds (or reads from the cache) the catalog objects' parts and ships them.

    For maintainers, after a catalog mesh changes: the shipped files are keyed by the
    mesh, so stale ones are simply not used (and replaced here).

    Parameters
    ----------
    names : sequence of str or None
        Catalog names; None: all of them.
    config : DecompositionConfig or None
        None: the defaults.
    progress : bool
        Announce each build with a progress bar.

    Returns
    -------
    dict of str to Path
        The shipped file of each object (convex objects ship nothing).
    """
    from tactile_sim.objects import load_object, object_names

    config = config or DecompositionConfig()
    shipped = {}
    for name in names if names is not None else object_names():
        parts = object_parts(load_object(name), config, progress=progress)
        if parts.source != "convex":
            shipped[name] = write_shipped_parts(parts, name, config)
    return shipped


def _safe_name(name: str) -> str:
    """A file-name-safe version of a label."""
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "mesh"


# Closed-form solids ----------------------------------------------------------------------


def ellipse_outline(
    semi_axis_x_m: float, semi_axis_y_m: float, n_segments: int = 720
) -> NDArray[np.float64]:
    """Returns an ellipse as a closed polygon, (n_segments, 2) metres, counter-clockwise.

    Vertices lie on the ellipse at equal parameter steps (x = a cos t, y = b sin t).
    """
    t = np.linspace(0.0, 2.0 * math.pi, n_segments, endpoint=False)
    return np.column_stack([semi_axis_x_m * np.cos(t), semi_axis_y_m * np.sin(t)])


DEFAULT_SPLINE_KNOTS_M = (
    (0.030, 0.000),
    (0.006, 0.026),
    (-0.024, 0.017),
    (-0.022, -0.019),
    (0.009, -0.028),
)
"""Knots of the closed cubic spline of the planar experiment (thesis Fig. 3.8 shows a
closed spline of five segments; its knots are not published), metres, counter-clockwise."""


def closed_spline_coefficients(knots_m: ArrayLike = DEFAULT_SPLINE_KNOTS_M) -> NDArray[np.float64]:
    """Returns the segments of the periodic cubic spline through ``knots_m``.

    Segment i runs from knot i to knot i + 1 (the last back to the first) as
    ``x(t) = a3 t^3 + a2 t^2 + a1 t + a0``, ``y(t) = b3 t^3 + ...`` for t in [0, 1]
    (thesis Eq. (3.25)), with continuous position, tangent and curvature vector.

    Parameters
    ----------
    knots_m : (k, 2) float, metres
        At least three distinct knots, in order along the curve.

    Returns
    -------
    (k, 2, 4) float
        ``[i, 0] = (a3, a2, a1, a0)`` and ``[i, 1] = (b3, b2, b1, b0)``, metres.
    """
    from scipy.interpolate import CubicSpline

    knots = np.asarray(knots_m, dtype=np.float64)
    if knots.ndim != 2 or knots.shape[1] != 2 or len(knots) < 3:
        raise ValueError(f"knots_m must be (k >= 3, 2), got shape {knots.shape}")
    closed = np.vstack([knots, knots[:1]])
    spline = CubicSpline(np.arange(len(closed), dtype=np.float64), closed, bc_type="periodic")
    # spline.c: (4, k, 2), powers 3..0 of (t - t_i).
    return np.transpose(spline.c, (1, 2, 0)).copy()


def closed_spline_outline(
    knots_m: ArrayLike = DEFAULT_SPLINE_KNOTS_M, samples_per_segment: int = 200
) -> NDArray[np.float64]:
    """Returns the closed cubic spline through ``knots_m`` as a polygon, (n, 2) metres."""
    coefficients = closed_spline_coefficients(knots_m)
    t = np.linspace(0.0, 1.0, samples_per_segment, endpoint=False)
    powers = np.stack([t**3, t**2, t, np.ones_like(t)])  # (4, s)
    return np.concatenate([(segment @ powers).T for segment in coefficients])


def extrude_outline(
    outline_m: ArrayLike, height_m: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the prism over a closed planar outline, from z = 0 to z = height_m.

    The caps are fans from the outline's centroid, so the outline must be star-shaped
    about its centroid (true for every convex outline).

    Parameters
    ----------
    outline_m : (n, 2) float, metres
        Closed polygon (last vertex not repeated), counter-clockwise seen from +z.
    height_m : float, metres

    Returns
    -------
    vertices : (2 n + 2, 3) float, metres
    faces : (4 n, 3) int, outward-wound
    """
    outline = np.asarray(outline_m, dtype=np.float64)
    n = len(outline)
    if outline.ndim != 2 or outline.shape[1] != 2 or n < 3 or not height_m > 0:
        raise ValueError("outline_m must be (n >= 3, 2) and height_m positive")
    x, y = outline.T
    if 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) <= 0:
        raise ValueError("outline_m must run counter-clockwise (positive area)")
    centre = outline.mean(axis=0)
    rel = outline - centre
    nxt = np.roll(rel, -1, axis=0)
    if np.any(rel[:, 0] * nxt[:, 1] - rel[:, 1] * nxt[:, 0] <= 0):
        raise ValueError("outline_m must be star-shaped about its centroid")
    bottom = np.column_stack([outline, np.zeros(n)])
    top = np.column_stack([outline, np.full(n, height_m)])
    vertices = np.vstack([bottom, top, [[*centre, 0.0]], [[*centre, height_m]]])
    i = np.arange(n)
    j = (i + 1) % n
    side = np.concatenate([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i])])
    bottom_cap = np.column_stack([np.full(n, 2 * n), j, i])
    top_cap = np.column_stack([np.full(n, 2 * n + 1), n + i, n + j])
    return vertices, np.concatenate([side, bottom_cap, top_cap]).astype(np.int64)


def sphere_mesh(
    radius_m: float, subdivisions: int = 5
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns an icosphere centred at the origin, vertices on the sphere.

    5 subdivisions: 10242 vertices, faces within 9.4 um of the sphere at r = 33 mm (6: 40962
    vertices, 2.4 um, but MuJoCo then takes seconds to compile the hull).
    """
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius_m)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def _lying_prism(
    outline_yz: NDArray[np.float64], length_m: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The prism over an outline in the (y, z) plane, extruded along x and centred on x = 0,
    lowest point on z = 0."""
    vertices, faces = extrude_outline(outline_yz, length_m)
    # (u, v, w) = (y, z, x): a cyclic permutation keeps the winding.
    lying = np.column_stack([vertices[:, 2] - length_m / 2.0, vertices[:, 0], vertices[:, 1]])
    lying[:, 2] -= lying[:, 2].min()
    return lying, faces


@dataclass(frozen=True)
class Solid:
    """A closed-form test solid as a mesh.

    Model frame (as the catalog's): metres, z up, lowest point on z = 0, bounding box
    centred on the z axis. Cylinders lie on the table with their axis along x, so their
    curved side faces up; the planar-experiment prisms stand on the table, axis along z.

    Attributes
    ----------
    name : str
        One of :func:`solid_names`.
    mesh : trimesh.Trimesh
        Closed, outward-wound surface, metres.
    convex : bool
        True: MuJoCo collides it as one hull, exactly its mesh.
    parameters : Mapping[str, Any]
        The closed-form parameters in metres (``radius_m``, ``semi_axes_m``,
        ``length_m``, ``height_m``, ``spline_coefficients_m`` ...).
    description : str
        What the solid is and where the thesis uses it.
    """

    name: str
    mesh: trimesh.Trimesh
    convex: bool
    parameters: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""


SOLID_NAMES = (
    "cylinder_1",
    "cylinder_2",
    "elliptic_cylinder",
    "sphere",
    "planar_ellipse",
    "planar_spline",
)
"""The four algebraic objects of thesis Fig. 4.15, then the two planar-experiment prisms."""

CYLINDER_LENGTH_M = 0.100
"""Length of the lying cylinders (the thesis gives only their cross-sections)."""
PRISM_HEIGHT_M = 0.030
"""Height of the planar-experiment prisms."""


def solid_names() -> tuple[str, ...]:
    """Returns the names of the closed-form solids."""
    return SOLID_NAMES


def load_solid(name: str) -> Solid:
    """Returns a closed-form solid by name (see :func:`solid_names`).

    Raises
    ------
    UnknownObject
        ``name`` is not a solid's name; the message lists the known names.
    """
    if name == "cylinder_1" or name == "cylinder_2":
        diameter = 0.0504 if name == "cylinder_1" else 0.094
        radius = diameter / 2.0
        vertices, faces = _lying_prism(ellipse_outline(radius, radius), CYLINDER_LENGTH_M)
        parameters = {"radius_m": radius, "length_m": CYLINDER_LENGTH_M}
        description = f"circular cylinder, diameter {diameter * 1e3:.1f} mm (thesis Fig. 4.15)"
    elif name == "elliptic_cylinder":
        semi_axes = (0.0508, 0.03175)
        vertices, faces = _lying_prism(ellipse_outline(*semi_axes), CYLINDER_LENGTH_M)
        parameters = {"semi_axes_m": semi_axes, "length_m": CYLINDER_LENGTH_M}
        description = "elliptic cylinder, semi-axes 50.8 x 31.75 mm (thesis Fig. 4.15)"
    elif name == "sphere":
        radius = 0.033
        vertices, faces = sphere_mesh(radius)
        vertices = vertices + np.array([0.0, 0.0, radius])
        parameters = {"radius_m": radius}
        description = "sphere, radius 33 mm (thesis Fig. 4.15)"
    elif name == "planar_ellipse":
        semi_axes = (0.025, 0.0175)
        vertices, faces = extrude_outline(ellipse_outline(*semi_axes), PRISM_HEIGHT_M)
        parameters = {"semi_axes_m": semi_axes, "height_m": PRISM_HEIGHT_M}
        description = "extruded ellipse a = 25 mm, b = 17.5 mm (thesis Section 3.4.2, Table 3.4)"
    elif name == "planar_spline":
        coefficients = closed_spline_coefficients()
        vertices, faces = extrude_outline(closed_spline_outline(), PRISM_HEIGHT_M)
        parameters = {
            "knots_m": DEFAULT_SPLINE_KNOTS_M,
            "spline_coefficients_m": coefficients,
            "height_m": PRISM_HEIGHT_M,
        }
        description = "extruded closed cubic spline of five segments (thesis Section 3.4.2)"
    else:
        raise UnknownObject(name, SOLID_NAMES)
    # Model frame: bounding box centred on the z axis, lowest point on z = 0.
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    shift = np.array([-(low[0] + high[0]) / 2.0, -(low[1] + high[1]) / 2.0, -low[2]])
    vertices = vertices + shift
    if "spline_coefficients_m" in parameters:
        parameters["spline_coefficients_m"][:, :, 3] += shift[:2]
        parameters["knots_m"] = tuple(
            tuple(float(c) for c in knot + shift[:2]) for knot in np.array(parameters["knots_m"])
        )
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
    convex = _is_convex(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    return Solid(
        name=name,
        mesh=mesh,
        convex=convex,
        parameters=MappingProxyType(parameters),
        description=description,
    )
