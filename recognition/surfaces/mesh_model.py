"""Triangle-mesh models (thesis Section 4.3): normals, adaptive sampling, curvature table.

A :class:`MeshModel` holds a validated mesh (metres), its vertex normals (4.13), the
lookup table of principal curvatures at adaptively sampled vertices (4.3.2) and, built
on first use, a narrow-band signed distance field and exact point-to-mesh distances for
registration.

Conventions as in :mod:`recognition.surfaces.local_geometry`: normals point out of the
object, convex regions have positive curvature, k1 >= k2.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from recognition.surfaces.distance import (
    DistanceField,
    MeshDistance,
    triangle_normals,
    vertex_sums,
)
from recognition.surfaces.lookup import CurvatureTable
from recognition.surfaces.mesh_repair import MeshReport, prepare_mesh
from recognition.surfaces.rings import model_ring_descriptors
from recognition.surfaces.symmetry import rotational_symmetries

__all__ = [
    "MeshModel",
    "MeshModelConfig",
    "adaptive_sample",
    "mesh_hash",
    "paraboloid_curvatures",
    "vertex_normals",
]

Array = NDArray[np.float64]
Array32 = NDArray[np.float32]
IntArray = NDArray[np.int64]

#: Neighbours of the single paraboloid fit at each candidate vertex of the fast mode
#: (about 2.5 mm around it on the catalog's meshes: the scale of the data's curve fits).
CANDIDATE_FIT_SIZE = 100
#: The fast mode's candidate vertices: one per cubic cell of this side, metres.
CANDIDATE_SPACING_M = 1.0e-3
#: A motion is a symmetry of a model when it maps the surface within this of itself
#: (99 % of it), metres: a tessellation is symmetric to within its chords, the data
#: then decide between the images.
SYMMETRY_TOLERANCE_M = 0.5e-3


@dataclass(frozen=True)
class MeshModelConfig:
    """Settings of the lookup table (thesis Section 4.3.2).

    Attributes
    ----------
    sample_angle_rad : float
        theta: largest angle between the normal at a sample and the normals of the
        triangles of its neighbourhood (thesis: pi/8).
    max_ring, min_ring : int
        Ring sizes of the neighbourhood, shrunk from max to min (thesis: 6 and 2).
    marked_fraction : float
        Sampling stops when this fraction of vertices is marked (thesis: 1/2).
    fit_sizes : tuple of int
        Neighbourhood sizes of the paraboloid fits (4.14) (thesis: 30..70).
    seed : int
        Seed of the random visiting order.
    voxel_m, band_m : float
        Voxel size and half width of the narrow-band distance field.
    """

    sample_angle_rad: float = np.pi / 8
    max_ring: int = 6
    min_ring: int = 2
    marked_fraction: float = 0.5
    fit_sizes: tuple[int, ...] = (30, 40, 50, 60, 70)
    seed: int = 0
    voxel_m: float = 0.75e-3
    band_m: float = 3.0e-3


def mesh_hash(vertices: ArrayLike, faces: ArrayLike) -> str:
    """SHA-256 of the vertex (n, 3) and face (f, 3) arrays (float64 / int64, C order)."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    return h.hexdigest()


def vertex_normals(vertices: Array, faces: IntArray) -> Array:
    """Unit vertex normals: the normalised sum of the incident triangles' unit normals (4.13).

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex positions, metres.
    faces : (f, 3) int
        Triangles, indices into ``vertices``.

    Returns
    -------
    (n, 3) float
        Unit vertex normals.
    """
    n = vertex_sums(faces, triangle_normals(vertices[faces]), len(vertices))
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _adjacency(n_vertices: int, faces: IntArray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Vertex adjacency (CSR) and vertex-to-face incidence (CSR)."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(e), bool), (e[:, 0], e[:, 1])), (n_vertices,) * 2)
    A = (A + A.T).tocsr()
    rows = faces.ravel()
    cols = np.repeat(np.arange(len(faces)), 3)
    VF = sp.csr_matrix((np.ones(len(rows), bool), (rows, cols)), (n_vertices, len(faces)))
    return A, VF


def _padded_rows(M: sp.csr_matrix) -> IntArray:
    """The column indices of each CSR row in a (rows, max_row_length) array, -1 padded."""
    counts = np.diff(M.indptr)
    out = np.full((M.shape[0], max(int(counts.max(initial=0)), 1)), -1, np.int64)
    slot = np.arange(M.indices.size) - np.repeat(M.indptr[:-1], counts)
    out[np.repeat(np.arange(M.shape[0]), counts), slot] = M.indices
    return out


def _gather(padded: IntArray, rows: IntArray) -> IntArray:
    """Concatenated rows of a padded index table, padding dropped."""
    out = padded[rows].ravel()
    return out[out >= 0]


def adaptive_sample(
    vertices: Array,
    faces: IntArray,
    normals: Array,
    config: MeshModelConfig = MeshModelConfig(),
) -> IntArray:
    """Vertices sampled densely where the normal turns fast (thesis Section 4.3.2.1).

    Vertices are visited in a seeded random order. For an unmarked vertex v the ring
    size of its neighbourhood N starts at ``max_ring`` and shrinks while some triangle
    in N has a normal more than ``sample_angle_rad`` from v's normal, down to
    ``min_ring``. If no vertex of N is marked, v is sampled and N marked. Sampling stops
    when ``marked_fraction`` of the vertices are marked (or every vertex was visited).
    Rings come from the mesh's sparse adjacency matrix; since N always contains the
    2-ring, a vertex with a marked vertex in its 2-ring is skipped at once.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex positions, metres.
    faces : (f, 3) int
        Triangles, indices into ``vertices``.
    normals : (n, 3) float
        Unit vertex normals (4.13).
    config : MeshModelConfig

    Returns
    -------
    (m,) int64
        The sampled vertices, in the order they were sampled.
    """
    n = len(vertices)
    A, VF = _adjacency(n, faces)
    R2 = ((A + sp.identity(n, dtype=bool, format="csr")) @ (A + sp.identity(n, dtype=bool))).tocsr()
    fn = triangle_normals(vertices[faces])
    cos_theta = np.cos(config.sample_angle_rad)
    marked = np.zeros(n, bool)
    stamp = np.full(n, -1, np.int64)
    n_marked, target = 0, config.marked_fraction * n
    samples = []
    order = np.random.default_rng(config.seed).permutation(n)
    neighbours, incident = _padded_rows(A), _padded_rows(VF)
    r_ptr, r_idx = R2.indptr, R2.indices
    for it, v in enumerate(order):
        if marked[v] or marked[r_idx[r_ptr[v] : r_ptr[v + 1]]].any():
            continue
        # grow rings layer by layer: the ring size is the last before a layer whose
        # triangles turn more than theta from v's normal (at least min_ring); a marked
        # vertex within that ring rejects v. Growth stops as soon as both are decided.
        nv = normals[v]
        layer = np.array([v])
        stamp[v] = it
        layers = [layer]
        ring = None
        rejected = False
        for k in range(config.max_ring + 1):
            if k > 0:
                nb = _gather(neighbours, layer)
                layer = np.unique(nb[stamp[nb] != it])
                stamp[layer] = it
                layers.append(layer)
            if ring is None and np.min(fn[_gather(incident, layer)] @ nv, initial=1.0) < cos_theta:
                ring = max(k - 1, config.min_ring)
            if ring is not None and k > ring:
                break
            if marked[layer].any():
                rejected = True
                break
            if ring is not None and k == ring:
                break
        if rejected:
            continue
        ring = config.max_ring if ring is None else ring
        neighbourhood = np.concatenate(layers[: ring + 1])
        marked[neighbourhood] = True
        n_marked += neighbourhood.size
        samples.append(v)
        if n_marked >= target:
            break
    return np.array(samples, dtype=np.int64)


def _tangent_basis(normals: Array) -> tuple[Array, Array]:
    """Two unit tangents per normal, (m, 3) each, right-handed with the normal."""
    helper = np.where(np.abs(normals[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(normals, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(normals, e1)


def paraboloid_curvatures(
    vertices: Array,
    normals: Array,
    sample: IntArray,
    fit_sizes: Sequence[int] = (30, 40, 50, 60, 70),
    tree: cKDTree | None = None,
) -> tuple[Array, Array, Array]:
    """Principal curvatures at sampled vertices by paraboloid fits, thesis Eq. (4.14).

    ``z = a x^2 + b x y + c y^2 + d x + e y + f`` is fitted in the local frame (two
    tangents, the normal) over the ``s`` nearest vertices, for each ``s`` in
    ``fit_sizes``; each fit gives principal curvatures in closed form (the shape operator
    of the graph at the origin); k1 and k2 are the medians over the fits, chosen
    independently (thesis). Neighbours whose normal faces away from the sample's (the
    other side of a thin part) are left out.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex positions, metres.
    normals : (n, 3) float
        Unit vertex normals (4.13).
    sample : (m,) int
        The vertices at which the curvatures are fitted.
    fit_sizes : sequence of int
        Neighbourhood sizes of the fits.
    tree : cKDTree, optional
        KD-tree of the vertices.

    Returns
    -------
    k1, k2 : (m,) float
        Principal curvatures (1/m), k1 >= k2, convex positive.
    d1 : (m, 3) float
        Unit principal direction of k1 from the middle fit.
    """
    tree = tree or cKDTree(vertices)
    kmax = max(fit_sizes)
    query = min(2 * kmax, len(vertices))
    _, nb = tree.query(vertices[sample], k=query)
    n0 = normals[sample]
    facing = np.einsum("mkj,mj->mk", normals[nb], n0) > 0.0
    # keep the first kmax facing neighbours, in distance order
    rank = np.cumsum(facing, axis=1)
    keep = facing & (rank <= kmax)
    pos = np.argsort(~keep, axis=1, kind="stable")[:, :kmax]
    nb = np.take_along_axis(nb, pos, axis=1)
    e1, e2 = _tangent_basis(n0)
    rel = vertices[nb] - vertices[sample][:, None, :]
    x = np.einsum("mkj,mj->mk", rel, e1)
    y = np.einsum("mkj,mj->mk", rel, e2)
    z = np.einsum("mkj,mj->mk", rel, n0)
    scale = np.sqrt(np.mean(x**2 + y**2, axis=1, keepdims=True)) + 1e-300
    xs, ys = x / scale, y / scale
    D = np.stack([xs * xs, xs * ys, ys * ys, xs, ys, np.ones_like(xs)], axis=-1)
    k1s, k2s, dirs = [], [], []
    for s in fit_sizes:
        Ds, zs = D[:, :s], z[:, :s]
        G = np.einsum("mki,mkj->mij", Ds, Ds) + 1e-12 * np.eye(6)
        coef = np.linalg.solve(G, np.einsum("mki,mk->mi", Ds, zs)[..., None])[..., 0]
        sc = scale[:, 0]
        a, b, c = coef[:, 0] / sc**2, coef[:, 1] / sc**2, coef[:, 2] / sc**2
        d, e = coef[:, 3] / sc, coef[:, 4] / sc
        w = np.sqrt(1 + d * d + e * e)
        first = np.stack([np.stack([1 + d * d, d * e], -1), np.stack([d * e, 1 + e * e], -1)], -2)
        second = (
            np.stack([np.stack([2 * a, b], -1), np.stack([b, 2 * c], -1)], -2) / w[:, None, None]
        )
        # curvature positive where the surface bends away from +z (the outward normal)
        S = -np.linalg.solve(first, second)
        ev, evec = np.linalg.eig(S)
        ev, evec = ev.real, evec.real
        order = np.argsort(-ev, axis=1)
        ev = np.take_along_axis(ev, order, axis=1)
        v1 = np.take_along_axis(evec, order[:, None, :], axis=2)[:, :, 0]
        k1s.append(ev[:, 0])
        k2s.append(ev[:, 1])
        t = (
            v1[:, [0]] * e1
            + v1[:, [1]] * e2
            + (v1[:, [0]] * d[:, None] + v1[:, [1]] * e[:, None]) * n0
        )
        t -= n0 * np.einsum("mj,mj->m", t, n0)[:, None]
        dirs.append(t / np.linalg.norm(t, axis=1, keepdims=True))
    k1 = np.median(np.array(k1s), axis=0)
    k2 = np.median(np.array(k2s), axis=0)
    return np.maximum(k1, k2), np.minimum(k1, k2), dirs[len(fit_sizes) // 2]


class MeshModel:
    """A validated mesh with its curvature table and distance queries (built lazily).

    Parameters
    ----------
    name : str
    mesh : trimesh.Trimesh
        The surface in metres (open or in pieces as it may be); made a model on
        construction (:func:`~recognition.surfaces.mesh_repair.prepare_mesh`).
    config : MeshModelConfig
    table : CurvatureTable, optional
        A table built earlier for the same mesh and config (e.g. loaded from a cache).
    distance_field : DistanceField, optional
    validate : bool
        Prepare (check and repair) the mesh; False for a mesh loaded from a database.
    candidate_curvatures : CurvatureTable, optional
        The fast mode's candidate map built earlier (see :attr:`candidate_curvatures`).
    normals : (n, 3) float, optional
        Vertex normals (4.13) computed earlier.
    report : MeshReport, optional
        What preparing the mesh did (with ``validate=False``: as recorded then).
    symmetries : (k, 4, 4) float, optional
        The rotational symmetries found earlier (see :attr:`symmetries`).
    rings : (m, k, DESCRIPTOR_SIZE) float32, optional
        The candidate map's ring descriptors computed earlier (see :attr:`rings`).

    Attributes
    ----------
    report : MeshReport
        What was repaired, split or simplified to make the mesh a model.
    """

    def __init__(
        self,
        name: str,
        mesh: trimesh.Trimesh,
        config: MeshModelConfig = MeshModelConfig(),
        table: CurvatureTable | None = None,
        distance_field: DistanceField | None = None,
        validate: bool = True,
        candidate_curvatures: CurvatureTable | None = None,
        normals: ArrayLike | None = None,
        report: MeshReport | None = None,
        symmetries: ArrayLike | None = None,
        rings: ArrayLike | None = None,
    ) -> None:
        self.name = name
        self.config = config
        if validate:
            self.mesh, self.report = prepare_mesh(mesh, name)
        else:
            self.mesh = mesh
            self.report = report or MeshReport(len(mesh.vertices), len(mesh.faces))
        self.vertices = np.ascontiguousarray(self.mesh.vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(self.mesh.faces, dtype=np.int64)
        self.normals = (
            vertex_normals(self.vertices, self.faces) if normals is None else np.asarray(normals)
        )
        self.hash = mesh_hash(self.vertices, self.faces)
        self._table = table
        self._dense = candidate_curvatures
        self._field = distance_field
        self._distance: MeshDistance | None = None
        self._symmetries = None if symmetries is None else np.asarray(symmetries, float)
        self._rings = None if rings is None else np.asarray(rings, np.float32)
        self._tree: cKDTree | None = None
        self._cell_keys: dict[float, IntArray] = {}
        self.timings: dict[str, float] = {}

    @property
    def tree(self) -> cKDTree:
        """KD-tree of the vertices."""
        if self._tree is None:
            self._tree = cKDTree(self.vertices)
        return self._tree

    @property
    def table(self) -> CurvatureTable:
        """The lookup table (built on first use: adaptive sampling + paraboloid fits)."""
        if self._table is None:
            start = time.perf_counter()
            sample = adaptive_sample(self.vertices, self.faces, self.normals, self.config)
            self.timings["sampling_s"] = time.perf_counter() - start
            start = time.perf_counter()
            k1, k2, d1 = paraboloid_curvatures(
                self.vertices, self.normals, sample, self.config.fit_sizes, self.tree
            )
            self.timings["curvatures_s"] = time.perf_counter() - start
            self._table = CurvatureTable(sample, k1, k2, d1)
        return self._table

    @property
    def candidate_curvatures(self) -> CurvatureTable:
        """Principal curvatures at the fast mode's candidate vertices (built on first use).

        One vertex per cubic cell of side ``CANDIDATE_SPACING_M`` (the first in vertex
        order), one paraboloid fit (4.14) over its ``CANDIDATE_FIT_SIZE`` nearest vertices.
        Not part of the thesis's method, whose table holds only the adaptively sampled
        vertices: the fast mode draws its candidates from this denser map.
        """
        if self._dense is None:
            start = time.perf_counter()
            vertices = self.one_per_cell(CANDIDATE_SPACING_M)
            parts = [
                paraboloid_curvatures(
                    self.vertices, self.normals, chunk, (CANDIDATE_FIT_SIZE,), self.tree
                )
                for chunk in np.array_split(vertices, max(1, len(vertices) // 10000))
            ]
            k1, k2, d1 = (np.concatenate(x) for x in zip(*parts, strict=True))
            self._dense = CurvatureTable(vertices, k1, k2, d1)
            self.timings["vertex_curvatures_s"] = time.perf_counter() - start
        return self._dense

    @property
    def rings(self) -> Array32:
        """(m, len(RADII_M), DESCRIPTOR_SIZE) float32 ring descriptors at the candidate
        map's vertices, in its row order (:mod:`~recognition.surfaces.rings`; computed on
        first use)."""
        if self._rings is None:
            start = time.perf_counter()
            dense = self.candidate_curvatures
            assert dense.d1 is not None  # the candidate map carries principal directions
            self._rings = model_ring_descriptors(
                self.distance_field, self.vertices[dense.site], self.normals[dense.site], dense.d1
            )
            self.timings["rings_s"] = time.perf_counter() - start
        return self._rings

    @property
    def distance_field(self) -> DistanceField:
        """Narrow-band signed distance grid (built on first use)."""
        if self._field is None:
            start = time.perf_counter()
            self._field = DistanceField.build(
                self.vertices,
                self.normals,
                self.faces,
                self.config.voxel_m,
                self.config.band_m,
                tree=self.tree,
            )
            self.timings["distance_field_s"] = time.perf_counter() - start
        return self._field

    def share_distance_field(self, field: DistanceField) -> None:
        """Read the distance field from ``field`` (the same grid held elsewhere, for
        example a view into a database's :class:`~recognition.surfaces.distance.FieldStack`)."""
        own = self.distance_field
        same = (field.values.shape, field.values.dtype, field.voxel, field.band) == (
            own.values.shape,
            own.values.dtype,
            own.voxel,
            own.band,
        )
        if not same or not np.allclose(field.origin, own.origin):
            raise ValueError(f"{self.name}: the shared distance field is not this model's grid")
        self._field = field

    @property
    def distance(self) -> MeshDistance:
        """Exact point-to-mesh distances."""
        if self._distance is None:
            self._distance = MeshDistance(self.vertices, self.faces)
        return self._distance

    @property
    def symmetries(self) -> Array:
        """The rigid motions (k, 4, 4) other than the identity that map the surface onto
        itself to within ``SYMMETRY_TOLERANCE_M`` (a gear's turns by one tooth and flips;
        empty for most objects), model frame; found on first use
        (:func:`~recognition.surfaces.symmetry.rotational_symmetries`)."""
        if self._symmetries is None:
            start = time.perf_counter()
            self._symmetries = rotational_symmetries(
                self.vertices, self.faces, self.distance, tolerance_m=SYMMETRY_TOLERANCE_M
            )
            self.timings["symmetries_s"] = time.perf_counter() - start
        return self._symmetries

    def cell_keys(self, spacing: float) -> IntArray:
        """(n,) int64 key of the cubic cell (side ``spacing``, metres) of each vertex (cached)."""
        keys = self._cell_keys.get(spacing)
        if keys is None:
            cell = np.floor((self.vertices - self.vertices.min(0)) / spacing).astype(np.int64)
            dims = cell.max(0) + 1
            keys = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
            self._cell_keys[spacing] = keys
        return keys

    def one_per_cell(self, spacing: float) -> IntArray:
        """(m,) int64 indices of one vertex per occupied cubic cell of side ``spacing``
        (metres), the first in vertex order, in the order of the cells' keys."""
        _, first = np.unique(self.cell_keys(spacing), return_index=True)
        return np.asarray(first, dtype=np.int64)

    @property
    def extent_m(self) -> float:
        """Bounding-box diagonal, metres."""
        return float(np.linalg.norm(self.vertices.max(0) - self.vertices.min(0)))

    def __repr__(self) -> str:
        return f"MeshModel({self.name!r}, {len(self.vertices)} vertices)"
