"""Recipe -> watertight triangle mesh: narrow-band SDF sampling and marching cubes.

:func:`build_mesh` runs two passes:

1. *Coarse*: the SDF on a grid of about ``MeshingSettings.coarse_cells`` cells along the
   longest side, meshed by marching cubes, gives the design's bounding box and a
   vertex count at a known voxel size.
2. *Fine*: the per-axis scale that brings the bounding box to the recipe's
   ``dimensions_m`` is applied to the sampling grid, and the voxel size is chosen so
   that the mesh has about ``target_vertices`` vertices (the vertex count of a
   marching-cubes mesh scales as 1 / voxel^2). The SDF is sampled exactly only in
   blocks near the surface (a narrow band found from the SDF at block centres); the
   other blocks take the sign of their centre. Marching cubes
   (``allow_degenerate=False``) gives the surface, which is rescaled per axis to the
   exact target dimensions and placed in the model frame.

Model frame: metres, x forward (the object's front), y to its left, z up; the bounding
box is centred on the z axis and its bottom rests on z = 0.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from skimage.measure import marching_cubes

from tactile_sim.errors import InvalidMesh
from tactile_sim.objects.recipe import Node, ObjectRecipe
from tactile_sim.objects.sdf import blend_margin, evaluate, node_bounds

__all__ = [
    "GENERATOR_VERSION",
    "MeshBuild",
    "MeshingSettings",
    "build_mesh",
    "mesh_problems",
]

#: Bump when a change to the generator code changes its output; it is part of every
#: cache key.
GENERATOR_VERSION = "objects-1"


@dataclass(frozen=True)
class MeshingSettings:
    """Resolution and narrow-band parameters of :func:`build_mesh`.

    Attributes
    ----------
    coarse_cells : int
        Coarse-pass grid cells along the longest side of the design.
    block : int
        Narrow-band block edge, in fine voxels.
    band_factor : float
        A block is sampled finely when ``|sdf(centre)|`` is below ``band_factor`` times
        its half-diagonal (covers SDF estimates that are not exact distances).
    chunk_points : int
        Points per SDF evaluation batch (bounds memory use).
    """

    coarse_cells: int = 72
    block: int = 4
    band_factor: float = 2.0
    chunk_points: int = 1 << 18


@dataclass(frozen=True)
class MeshBuild:
    """A generated mesh and how it was made.

    Attributes
    ----------
    vertices : (n, 3) float, metres
        Model frame (see module docstring).
    faces : (m, 3) int64
        Counter-clockwise seen from outside.
    voxel_size_m : float, metres
        Fine grid spacing.
    fit_scale : (3,) float
        Per-axis scale applied to the recipe design (in metres) to reach the target
        dimensions; near 1 for a recipe designed at the right size.
    build_seconds : float, seconds
        Wall time of the build.
    """

    vertices: np.ndarray
    faces: np.ndarray
    voxel_size_m: float
    fit_scale: tuple[float, float, float]
    build_seconds: float


def _evaluate_chunked(
    node: Node,
    points: np.ndarray,
    exact_within: float,
    chunk: int,
    progress: Callable[[int], None] | None = None,
) -> np.ndarray:
    out = np.empty(len(points))
    for start in range(0, len(points), chunk):
        stop = min(start + chunk, len(points))
        out[start:stop] = evaluate(node, points[start:stop], exact_within)
        if progress is not None:
            progress(stop - start)
    return out


def _marching_cubes(
    volume: np.ndarray, spacing: np.ndarray, origin: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (recipe units) and outward-wound faces of the zero level set."""
    verts, faces, _, _ = marching_cubes(
        volume, level=0.0, spacing=tuple(spacing), allow_degenerate=False
    )
    verts = verts.astype(float) + origin
    faces = faces.astype(np.int64)
    tri = verts[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if np.einsum("ij,ij->i", tri[:, 0], cross).sum() < 0:
        faces = faces[:, ::-1].copy()
    return verts, faces


def _coarse_pass(
    recipe: ObjectRecipe, settings: MeshingSettings, blend: float
) -> tuple[np.ndarray, float]:
    """Coarse mesh vertices (recipe units) and the coarse voxel size."""
    box = node_bounds(recipe.shape)
    if box is None:
        raise InvalidMesh(f"{recipe.name}: the recipe's shape is unbounded")
    lo, hi = box
    h = float((hi - lo).max()) / settings.coarse_cells
    exact_within = 4 * h + blend
    lo = lo - 2 * h
    counts = np.ceil((hi + 2 * h - lo) / h).astype(int) + 1
    axes = [lo[i] + h * np.arange(counts[i]) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    values = _evaluate_chunked(recipe.shape, grid, exact_within, settings.chunk_points)
    verts, _ = _marching_cubes(values.reshape(counts), np.full(3, h), lo)
    return verts, h


def _narrow_band_volume(
    recipe: ObjectRecipe,
    lo: np.ndarray,
    spacing: np.ndarray,
    n_blocks: np.ndarray,
    settings: MeshingSettings,
    exact_within: float,
    progress_factory: Callable[[int], Callable[[int], None]] | None,
) -> np.ndarray:
    """SDF on the fine grid, exact in blocks near the surface, signed fill elsewhere."""
    B = settings.block
    block_size = spacing * B
    # Block centres (between the block's 2nd and 3rd samples for B = 4).
    centre_axes = [
        lo[i] + block_size[i] * np.arange(n_blocks[i]) + spacing[i] * (B - 1) / 2 for i in range(3)
    ]
    centres = np.stack(np.meshgrid(*centre_axes, indexing="ij"), axis=-1).reshape(-1, 3)
    centre_values = _evaluate_chunked(recipe.shape, centres, exact_within, settings.chunk_points)
    half_diag = 0.5 * float(np.linalg.norm(spacing * (B - 1)))
    threshold = settings.band_factor * (half_diag + float(spacing.max()))
    active = np.abs(centre_values) < threshold

    offsets = np.stack(np.meshgrid(*[np.arange(B)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    active_idx = np.flatnonzero(active)
    block_ijk = np.stack(np.unravel_index(active_idx, tuple(n_blocks)), axis=1)
    n_points = len(active_idx) * B**3
    progress = progress_factory(n_points) if progress_factory is not None else None

    blocks = np.empty((len(centres), B, B, B))
    blocks[~active] = (np.sign(centre_values[~active]) * threshold)[:, None, None, None]
    # Active blocks in batches, so the point arrays stay small.
    per_batch = max(1, settings.chunk_points // B**3)
    for start in range(0, len(active_idx), per_batch):
        ijk = block_ijk[start : start + per_batch]
        points = ((ijk[:, None, :] * B + offsets[None, :, :]) * spacing + lo).reshape(-1, 3)
        values = _evaluate_chunked(recipe.shape, points, exact_within, settings.chunk_points)
        blocks[active_idx[start : start + per_batch]] = values.reshape(-1, B, B, B)
        if progress is not None:
            progress(len(points))
    volume = blocks.reshape(*n_blocks, B, B, B).transpose(0, 3, 1, 4, 2, 5)
    return volume.reshape(*(n_blocks * B))


def mesh_problems(vertices: np.ndarray, faces: np.ndarray) -> list[str]:
    """What keeps a mesh from being a closed, single-component, outward-wound surface.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    list of str
        Empty for a good mesh.
    """
    problems = []
    n = len(vertices)
    if faces.size == 0 or faces.min() < 0 or faces.max() >= n:
        return ["face indices out of range or no faces"]
    if not np.all(np.isfinite(vertices)):
        problems.append("non-finite vertex coordinates")
    # Directed edges: a closed, consistently wound 2-manifold has every directed edge
    # exactly once, and its reverse exactly once.
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    keys = np.sort(edges[:, 0] * n + edges[:, 1])
    if np.any(keys[1:] == keys[:-1]):
        problems.append("an edge is used twice in the same direction (non-manifold or flipped)")
    reverse = edges[:, 1] * n + edges[:, 0]
    found = np.searchsorted(keys, reverse).clip(max=len(keys) - 1)
    if not np.all(keys[found] == reverse):
        problems.append("open boundary: an edge has no opposite half-edge (not watertight)")
    used = np.zeros(n, dtype=bool)
    used[faces.ravel()] = True
    if not used.all():
        problems.append(f"{int((~used).sum())} unreferenced vertices")
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    n_components, labels = connected_components(graph, directed=False)
    if n_components != 1:
        sizes = np.bincount(labels)
        strays = [
            f"{sizes[c]} vertices near {np.round(vertices[labels == c].mean(axis=0), 4).tolist()}"
            for c in np.argsort(sizes)[::-1][1:4]
        ]
        problems.append(
            f"{n_components} connected components, expected 1 (smaller: {', '.join(strays)})"
        )
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if np.any(np.einsum("ij,ij->i", cross, cross) == 0.0):
        problems.append("degenerate (zero-area) faces")
    volume = np.einsum("ij,ij->i", tri[:, 0], cross).sum() / 6.0
    if not volume > 0:
        problems.append("faces wound inward (negative enclosed volume)")
    return problems


def build_mesh(
    recipe: ObjectRecipe,
    settings: MeshingSettings | None = None,
    progress_factory: Callable[[int], Callable[[int], None]] | None = None,
) -> MeshBuild:
    """Build the watertight mesh of a recipe (deterministic: same recipe, same mesh).

    Parameters
    ----------
    recipe : ObjectRecipe
    settings : MeshingSettings, optional
    progress_factory : callable, optional
        Called once with the number of fine SDF samples; returns a callable that is
        then called with the number of samples done in each batch (a progress bar).

    Returns
    -------
    MeshBuild

    Raises
    ------
    InvalidMesh
        The recipe does not produce a closed, single-component surface.
    """
    settings = settings or MeshingSettings()
    start = time.perf_counter()
    dims_m = np.asarray(recipe.dimensions_m, dtype=float)
    blend = blend_margin(recipe.shape)

    coarse_verts, coarse_h = _coarse_pass(recipe, settings, blend)
    design_lo, design_hi = coarse_verts.min(axis=0), coarse_verts.max(axis=0)
    design_extent = design_hi - design_lo
    fit = dims_m / (design_extent * recipe.unit_m)
    # Vertex count ~ area / voxel^2: the coarse pass calibrates the constant.
    coarse_voxel_m = coarse_h * recipe.unit_m * float(np.prod(fit)) ** (1 / 3)
    voxel_m = coarse_voxel_m * np.sqrt(len(coarse_verts) / recipe.target_vertices)

    # Fine grid: isotropic in the model frame, so anisotropic (h / fit) in recipe units.
    spacing = voxel_m / (fit * recipe.unit_m)
    B = settings.block
    pad = 3 * spacing
    lo = design_lo - pad
    n_blocks = np.ceil((design_extent + 2 * pad) / (spacing * B)).astype(int) + 1
    half_diag = 0.5 * float(np.linalg.norm(spacing * (B - 1)))
    exact_within = settings.band_factor * (half_diag + float(spacing.max())) + blend
    volume = _narrow_band_volume(
        recipe, lo, spacing, n_blocks, settings, exact_within, progress_factory
    )
    verts, faces = _marching_cubes(volume, spacing, lo)

    # Exact target size, then the model frame: centred in x and y, base on z = 0.
    verts_m = verts * (fit * recipe.unit_m)
    v_lo, v_hi = verts_m.min(axis=0), verts_m.max(axis=0)
    refit = dims_m / (v_hi - v_lo)
    verts_m = (verts_m - v_lo) * refit
    verts_m -= np.array([dims_m[0] / 2, dims_m[1] / 2, 0.0])

    problems = mesh_problems(verts_m, faces)
    if problems:
        raise InvalidMesh(f"{recipe.name}: generated mesh is invalid: {'; '.join(problems)}")
    return MeshBuild(
        vertices=verts_m,
        faces=faces,
        voxel_size_m=float(voxel_m),
        fit_scale=tuple(float(v) for v in fit * refit),
        build_seconds=time.perf_counter() - start,
    )
