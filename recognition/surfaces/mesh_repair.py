"""Any real mesh made a model: repaired where it is safe, refused only when it cannot be one.

Scans have holes where the scanner never looked, characters come in several shells,
CAD exports are low-poly with seams, photogrammetry gives millions of triangles.
:func:`prepare_mesh` keeps the surface as it is (holes are kept open, not faked shut)
and makes it usable: duplicate vertices merged, duplicate and degenerate triangles
dropped, each component's winding made consistent and turned outward (by its volume when
it is closed, by the generalised winding number of the whole mesh when it is open),
long edges split to a working resolution (curvature fits and distances need vertices a
millimetre or so apart), very large meshes simplified (with the loss measured). Every
change is listed in the :class:`MeshReport`. Refused, with one message that says why:
no faces, NaN or infinite coordinates, every triangle degenerate, no extent in some
direction (a flat sheet), implausible size for metres.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from recognition.errors import InvalidModel

__all__ = [
    "MAX_DIAGONAL_M",
    "MAX_EDGE_M",
    "MAX_FACES",
    "MIN_DIAGONAL_M",
    "MeshReport",
    "prepare_mesh",
]

#: Largest plausible bounding-box diagonal of a model in metres (a mm mesh read as m is
#: 1000 times too large).
MAX_DIAGONAL_M = 2.0
#: Smallest plausible bounding-box diagonal in metres.
MIN_DIAGONAL_M = 5.0e-3
#: A mesh whose RMS extent across its flattest direction is below this fraction of its
#: diagonal is flat.
MIN_THICKNESS = 1e-3
#: In a coarse mesh (a tenth of its edges longer than 1/COARSE of its diagonal and than
#: MAX_EDGE_M), edges longer than MAX_EDGE_M (metres) are split: the distance field needs
#: vertices about a millimetre apart, and a faceted surface's curvature is that of its
#: facets.
MAX_EDGE_M = 1.5e-3
COARSE = 25.0
#: Meshes with more triangles are simplified to this many.
MAX_FACES = 400_000


def _split_size(longest: np.ndarray, max_edge_m: float, max_faces: int) -> float:
    """The smallest edge length, from ``max_edge_m`` up in doublings, to which splitting
    keeps the mesh within ``max_faces`` triangles: each triangle of longest edge L splits
    in four per halving, 4^ceil(log2(L / size)) pieces (a fan of long slivers, like a
    tessellated cylinder, would otherwise become millions)."""
    size = max_edge_m
    while True:
        halvings = np.ceil(np.log2(np.maximum(longest / size, 1.0)))
        if float(np.sum(4.0**halvings)) <= max_faces:
            return size
        size *= 2


@dataclass(frozen=True)
class MeshReport:
    """What was done to a mesh to make it a model (all counts; lengths in metres).

    Attributes
    ----------
    input_vertices, input_faces : int
    vertices, faces : int
        Of the model.
    merged_vertices : int
        Duplicate vertices merged (seams).
    removed_faces : int
        Duplicate and degenerate (zero-area) triangles dropped.
    components : int
        Connected pieces (all of them kept, all touchable).
    open_edges : int
        Boundary edges (holes are kept open): 0 for a closed surface.
    non_manifold_edges : int
        Edges shared by more than two triangles (kept).
    winding_fixed : int
        Components whose triangles were re-wound consistently.
    turned_outward : int
        Components whose normals were flipped to point out of the object.
    split_edges : bool
        Long edges were split to at most :data:`MAX_EDGE_M`.
    simplification_error_m : (float, float) or None
        Mean and largest distance of the input's vertices from the simplified model.
    notes : tuple of str
        One line per change, for people.
    """

    input_vertices: int
    input_faces: int
    vertices: int = 0
    faces: int = 0
    merged_vertices: int = 0
    removed_faces: int = 0
    components: int = 1
    open_edges: int = 0
    non_manifold_edges: int = 0
    winding_fixed: int = 0
    turned_outward: int = 0
    split_edges: bool = False
    simplification_error_m: tuple[float, float] | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def closed(self) -> bool:
        """True when the surface has no hole."""
        return self.open_edges == 0

    def to_json(self) -> dict[str, Any]:
        """The report as JSON-ready values."""
        d = asdict(self)
        d["notes"] = list(self.notes)
        if self.simplification_error_m is not None:
            d["simplification_error_m"] = list(self.simplification_error_m)
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> MeshReport:
        """The report written by :meth:`to_json`."""
        d = dict(d)
        d["notes"] = tuple(d.get("notes", ()))
        if d.get("simplification_error_m") is not None:
            d["simplification_error_m"] = tuple(d["simplification_error_m"])
        return cls(**d)


def _edge_counts(mesh: trimesh.Trimesh) -> tuple[int, int]:
    """Boundary (one triangle) and non-manifold (more than two) edges."""
    edges = np.asarray(mesh.edges_sorted, dtype=np.int64)
    _, counts = np.unique(edges[:, 0] * len(mesh.vertices) + edges[:, 1], return_counts=True)
    return int(np.count_nonzero(counts == 1)), int(np.count_nonzero(counts > 2))


def _outward(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int, int]:
    """Each component wound consistently and facing out; the counts of both repairs.

    A single component is repaired in place (its vertex order kept).
    """
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, len(mesh.faces))
    pieces = [mesh] if labels.max(initial=0) == 0 else mesh.split(only_watertight=False)
    fixed = flipped = 0
    whole_v = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    whole_f = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    for piece in pieces:
        if not piece.is_winding_consistent:
            trimesh.repair.fix_winding(piece)
            fixed += 1
        if _faces_inward(piece, whole_v, whole_f):
            piece.invert()
            flipped += 1
    if len(pieces) == 1:
        return pieces[0], fixed, flipped
    merged = trimesh.util.concatenate(pieces)
    assert isinstance(merged, trimesh.Trimesh)
    return merged, fixed, flipped


def _faces_inward(
    piece: trimesh.Trimesh, whole_v: NDArray[np.float64], whole_f: NDArray[np.int64]
) -> bool:
    """Whether a consistently wound piece faces into the object: by its volume when it is
    closed; else by the generalised winding number of the whole mesh just in front of and
    behind its faces (inside, its magnitude is near 1, outside near 0; the sign follows
    the winding, which is what is in question)."""
    if piece.is_watertight:
        return bool(piece.volume < 0)
    import igl

    rng = np.random.default_rng(0)
    sample = rng.choice(len(piece.faces), min(len(piece.faces), 512), replace=False)
    step = 1e-4 * float(np.linalg.norm(piece.extents))
    centres, normals = piece.triangles_center[sample], piece.face_normals[sample]
    queries = np.concatenate([centres + step * normals, centres - step * normals])
    w = np.abs(igl.fast_winding_number(whole_v, whole_f, np.ascontiguousarray(queries)))
    return bool(np.mean(w[: len(sample)]) > np.mean(w[len(sample) :]))


def prepare_mesh(
    mesh: trimesh.Trimesh,
    name: str = "mesh",
    *,
    max_edge_m: float = MAX_EDGE_M,
    max_faces: int = MAX_FACES,
) -> tuple[trimesh.Trimesh, MeshReport]:
    """Returns the model's mesh made from ``mesh`` (metres) and what was done to it.

    Raises
    ------
    InvalidModel
        The mesh cannot be a model: no faces, NaN or infinite vertices, face indices out of
        range, every triangle degenerate, flat, or of implausible size (e.g. millimetres
        read as metres); the message says which.
    """
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InvalidModel(f"{name}: expected a non-empty triangle mesh")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    if not np.all(np.isfinite(vertices)):
        bad = int(np.count_nonzero(~np.all(np.isfinite(vertices), axis=1)))
        raise InvalidModel(f"{name}: {bad} vertices hold NaN or infinite coordinates")
    if faces.dtype.kind not in "iu" or faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidModel(f"{name}: face indices must lie in [0, {len(vertices) - 1}]")
    notes: list[str] = []
    m = trimesh.Trimesh(vertices, faces.astype(np.int64), process=False)
    n_vertices, n_faces = len(m.vertices), len(m.faces)
    m.remove_unreferenced_vertices()
    merged = removed = 0
    if not m.is_watertight:  # duplicated vertices along seams, repeated triangles
        before_v, before_f = len(m.vertices), len(m.faces)
        m.merge_vertices()
        m.update_faces(m.unique_faces())
        merged, removed = before_v - len(m.vertices), before_f - len(m.faces)
    degenerate = ~m.nondegenerate_faces(height=1e-12)
    if degenerate.all():
        raise InvalidModel(f"{name}: every triangle is degenerate (zero area)")
    if degenerate.any():
        # zero-area triangles have no normal; dropping them is safe only if the surface
        # stays closed (else they are kept: they change neither distances nor (4.13))
        trial = m.copy()
        trial.update_faces(~degenerate)
        trial.remove_unreferenced_vertices()
        if trial.is_watertight or not m.is_watertight:
            removed += int(np.count_nonzero(degenerate))
            m = trial
    diagonal = float(np.linalg.norm(m.extents))
    if diagonal > MAX_DIAGONAL_M:
        raise InvalidModel(
            f"{name}: bounding box diagonal is {diagonal:.3g} m; expected an object of "
            f"{MIN_DIAGONAL_M * 1e3:.0f} mm to {MAX_DIAGONAL_M:.0f} m. It looks like a mesh "
            "in millimetres read as metres: scale it by 1e-3 (scripts: --units mm)"
        )
    if diagonal < MIN_DIAGONAL_M:
        raise InvalidModel(
            f"{name}: bounding box diagonal is {diagonal * 1e3:.3g} mm; expected at least "
            f"{MIN_DIAGONAL_M * 1e3:.0f} mm. Is the mesh in kilometres or already scaled twice?"
        )
    centred = m.vertices - m.vertices.mean(axis=0)
    thickness = float(np.linalg.svd(centred, compute_uv=False)[-1]) / np.sqrt(len(centred))
    if thickness < MIN_THICKNESS * diagonal:
        raise InvalidModel(
            f"{name}: the mesh has no extent in one direction (it is flat); expected a "
            "surface a probe can trace in three dimensions"
        )
    if merged:
        notes.append(f"merged {merged} duplicate vertices (seams)")
    if removed:
        notes.append(f"dropped {removed} duplicate or degenerate triangles")
    simplified: tuple[float, float] | None = None
    if len(m.faces) > max_faces:
        simplified_mesh = _simplified(m, max_faces)
        from recognition.surfaces.distance import MeshDistance

        probe = m.vertices[:: max(1, len(m.vertices) // 200_000)]
        loss = MeshDistance(simplified_mesh.vertices, simplified_mesh.faces).closest(probe)[0]
        simplified = (float(loss.mean()), float(loss.max()))
        notes.append(
            f"simplified from {len(m.faces)} to {len(simplified_mesh.faces)} triangles: the "
            f"input lies {simplified[0] * 1e3:.4f} mm (mean), {simplified[1] * 1e3:.3f} mm "
            "(max) from the model"
        )
        m = simplified_mesh
    edges = m.edges_unique_length
    # coarse for its size (a tenth of its edges longer than 1/COARSE of its diagonal), not
    # only a few long edges: split them to a working resolution
    split = bool(np.percentile(edges, 90) > max(max_edge_m, diagonal / COARSE))
    if split:
        longest = np.asarray(m.edges_unique_length[m.faces_unique_edges].max(axis=1))
        size = _split_size(longest, max_edge_m, max_faces)
        v, f = trimesh.remesh.subdivide_to_size(m.vertices, m.faces, max_edge=size)
        notes.append(
            f"split edges longer than {size * 1e3:g} mm (longest "
            f"{edges.max() * 1e3:.3g} mm): {len(m.faces)} -> {len(f)} triangles"
        )
        m = trimesh.Trimesh(v, f, process=False)
        m.merge_vertices()
    m, winding_fixed, turned = _outward(m)
    if winding_fixed:
        notes.append(f"re-wound {winding_fixed} components consistently")
    if turned:
        notes.append(f"turned {turned} components outward")
    open_edges, non_manifold = _edge_counts(m)
    components = int(
        trimesh.graph.connected_component_labels(m.face_adjacency, len(m.faces)).max(initial=0) + 1
    )
    if components > 1:
        notes.append(f"{components} separate components, all kept")
    if open_edges:
        notes.append(f"open: {open_edges} boundary edges (holes kept open)")
    if non_manifold:
        notes.append(f"{non_manifold} non-manifold edges (kept)")
    report = MeshReport(
        input_vertices=n_vertices,
        input_faces=n_faces,
        vertices=len(m.vertices),
        faces=len(m.faces),
        merged_vertices=merged,
        removed_faces=removed,
        components=components,
        open_edges=open_edges,
        non_manifold_edges=non_manifold,
        winding_fixed=winding_fixed,
        turned_outward=turned,
        split_edges=split,
        simplification_error_m=simplified,
        notes=tuple(notes),
    )
    return m, report


def _simplified(mesh: trimesh.Trimesh, max_faces: int) -> trimesh.Trimesh:
    import fast_simplification

    v, f = fast_simplification.simplify(
        np.asarray(mesh.vertices, np.float32),
        np.asarray(mesh.faces, np.int32),
        target_reduction=1.0 - max_faces / len(mesh.faces),
    )
    return trimesh.Trimesh(np.asarray(v, np.float64), np.asarray(f, np.int64), process=False)
