"""Point-to-mesh distances: exact closest points and a narrow-band signed distance grid.

:class:`MeshDistance` is exact everywhere: a uniform grid of cell lists and the
point-triangle test (:mod:`~recognition.surfaces.mesh_kernels`: built about ten times
faster than libigl's AABB tree, in a fifth of its memory, answering somewhat fewer
queries per second). :class:`DistanceField` samples the signed distance on a
voxel grid in a band around the surface (point-to-plane distance to the nearest vertex)
and interpolates it trilinearly with its gradient: cheap enough to score thousands of
candidate poses, smooth enough for Gauss-Newton. ``trimesh.proximity`` is not used: its
fixed tolerances fail on sub-millimetre triangles at metre scale (DESIGN.md).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from scipy.spatial import cKDTree

from recognition.rigid import cross

__all__ = [
    "DistanceField",
    "MeshDistance",
    "folded_faces",
    "signed_by_side",
    "triangle_normals",
    "vertex_sums",
]

Array = NDArray[np.float64]
Array32 = NDArray[np.float32]
IntArray = NDArray[np.int64]
Mask = NDArray[np.bool_]


def triangle_normals(triangles: Array) -> Array:
    """Unit normals (f, 3) of triangles (f, 3, 3), by their corners' order."""
    fn = cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)


def signed_by_side(points: Array, closest: Array, normals: Array, distance: Array) -> Array:
    """The unsigned ``distance`` (...) of ``points`` (..., 3) from their ``closest`` points
    (..., 3) on faces of outward unit ``normals`` (..., 3), negative where a point lies
    behind its face (inside)."""
    side = np.einsum("...i,...i->...", points - closest, normals)
    return np.where(side < 0, -distance, distance)


def folded_faces(vertices: Array, faces: IntArray) -> Mask:
    """Faces (f,) whose normal points against the surface around them: against the sum
    of their corners' area-weighted vertex normals.

    Marching cubes leaves slivers of almost no area (a corner a nanometre off the line
    of the other two), and a displacement of the surface can push that corner through
    the line: the sliver's normal then points into the object while its neighbours'
    point out. Area weighting gives such a face no say in its corners' normals, so the
    test finds it; on a closed, consistently oriented mesh no face of real size fails it.
    """
    from recognition.surfaces import mesh_kernels  # numba: imported when first needed

    return np.asarray(
        mesh_kernels.folded_faces(
            np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64)
        )
    )


def vertex_sums(faces: IntArray, per_face: Array, n_vertices: int) -> Array:
    """(n_vertices, 3) sum at each vertex of the vectors ``per_face`` (f, 3) of the faces
    ``faces`` (f, 3) it is a corner of."""
    owner = faces.ravel()
    return np.stack(
        [
            np.bincount(owner, weights=np.repeat(per_face[:, k], 3), minlength=n_vertices)
            for k in range(3)
        ],
        axis=1,
    )


@dataclass(frozen=True)
class _CellGrid:
    """A mesh's grid of cell lists (:mod:`~recognition.surfaces.mesh_kernels`): each face's
    bounding sphere (f, 4), the faces of cell c ``faces_of[start[c]:start[c + 1]]``, the
    lower corner of cell (0, 0, 0), the cell side (metres) and the cells per axis."""

    spheres: Array
    start: NDArray[np.int32]
    faces_of: NDArray[np.int32]
    origin: Array
    cell: float
    shape: IntArray

    @property
    def nbytes(self) -> int:
        """Bytes of its arrays."""
        return self.spheres.nbytes + self.start.nbytes + self.faces_of.nbytes


class MeshDistance:
    """Exact distances from points to a mesh, and first hits of rays: a grid of cell lists
    (built on first use).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (f, 3) int
        At least one face.
    """

    #: Cell side in mean edge lengths (fewest triangle tests near the surface).
    CELL_EDGES = 3.0
    #: At most this many cells, and at most this many list entries per face.
    MAX_CELLS = 2**22
    MAX_ENTRIES_PER_FACE = 16

    def __init__(self, vertices: ArrayLike, faces: ArrayLike) -> None:
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        if self.vertices.ndim != 2 or self.vertices.shape[1:] != (3,):
            raise ValueError(f"a mesh needs (n, 3) vertices, got shape {self.vertices.shape}")
        if not np.isfinite(self.vertices).all():
            raise ValueError("a mesh's vertices must be finite numbers")
        if self.faces.ndim != 2 or self.faces.shape[1:] != (3,) or len(self.faces) == 0:
            raise ValueError(f"a mesh needs (f >= 1, 3) faces, got shape {self.faces.shape}")
        if self.faces.min() < 0 or self.faces.max() >= len(self.vertices):
            raise ValueError(
                f"a mesh's faces must index its {len(self.vertices)} vertices, got indices "
                f"{self.faces.min()}..{self.faces.max()}"
            )
        self._grid: _CellGrid | None = None
        self._face_normals: Array | None = None
        self._folded: Mask | None = None

    @property
    def folded(self) -> Mask:
        """Faces (f,) whose corner order points their normal into the object
        (:func:`folded_faces`; computed on first use and kept)."""
        if self._folded is None:
            self._folded = folded_faces(self.vertices, self.faces)
        return self._folded

    @property
    def face_normals(self) -> Array:
        """Unit outward face normals (f, 3): by the corners' order, turned over on the
        :attr:`folded` faces (computed on first use and kept)."""
        if self._face_normals is None:
            self._face_normals = self.normals_of(np.arange(len(self.faces)))
        return self._face_normals

    def normals_of(self, faces: ArrayLike) -> Array:
        """Unit outward normals (..., 3) of the faces ``faces`` (...,), the same numbers as
        :attr:`face_normals` (NaN for a face of -1: none), computed on each call (a search
        polishes on many models and reads few faces of each: only the :attr:`folded` mask
        is kept)."""
        from recognition.surfaces import mesh_kernels

        f = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1)
        normals = mesh_kernels.outward_normals(self.vertices, self.faces, self.folded, f)
        return normals.reshape(*np.shape(faces), 3)

    @property
    def grid(self) -> _CellGrid:
        """The grid of cell lists the queries search (built on first use)."""
        if self._grid is None:
            self._grid = self._cells()
        return self._grid

    def _cells(self) -> _CellGrid:
        """Builds the grid: the cell side from the faces' sizes, within the limits."""
        from recognition.surfaces import mesh_kernels  # numba: imported when first needed

        spheres, box, low, high, edge = mesh_kernels.face_bounds(self.vertices, self.faces)
        if not edge > 0:
            raise ValueError("every face of the mesh has zero size: it has no surface")
        extent = np.maximum(high - low, 1e-300)
        cell = self.CELL_EDGES * edge
        while np.prod(np.ceil(extent / cell)) > self.MAX_CELLS or np.sum(
            np.prod(np.floor(box / cell) + 2, axis=1)
        ) > self.MAX_ENTRIES_PER_FACE * len(box):
            cell *= 1.5  # a large object or large triangles: fewer, larger cells
        shape = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
        origin = low - 0.5 * (shape * cell - extent)
        start, faces_of = mesh_kernels.build_cells(self.vertices, self.faces, origin, cell, shape)
        return _CellGrid(spheres, start, faces_of, origin, float(cell), shape)

    def closest(self, points: ArrayLike) -> tuple[Array, Array, IntArray]:
        """Closest points on the mesh.

        Parameters
        ----------
        points : (m, 3) float
            Query points, metres.

        Returns
        -------
        distance : (m,) float
            Unsigned distance, metres (NaN for points that are not finite).
        closest : (m, 3) float
            The closest point on the mesh, metres.
        face : (m,) int
            The face it lies on (-1 for points that are not finite).
        """
        from recognition.surfaces import mesh_kernels

        p = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
        return mesh_kernels.closest_points(*self._closest_arrays(), p)

    def closest_to(self, x: float, y: float, z: float) -> tuple[float, float, float, float, int]:
        """The closest point on the mesh to one finite point (x, y, z), metres: its
        distance, coordinates and face; the same numbers as :meth:`closest`, for a
        caller that asks once per step (a probe's tip), without the arrays."""
        from recognition.surfaces import mesh_kernels

        return mesh_kernels.closest_point(*self._closest_arrays(), float(x), float(y), float(z))

    def _closest_arrays(
        self,
    ) -> tuple[
        Array, IntArray, Array, NDArray[np.int32], NDArray[np.int32], Array, float, IntArray
    ]:
        """The mesh and its grid, as the closest-point kernels take them."""
        g = self.grid
        return self.vertices, self.faces, g.spheres, g.start, g.faces_of, g.origin, g.cell, g.shape

    def first_hits(self, origins: ArrayLike, directions: ArrayLike) -> tuple[IntArray, Array]:
        """The face each ray meets first (-1: none) and the distance to it along the ray
        (inf: none), for rays ``origins + t * directions``, t >= 0 (both (m, 3), metres;
        unit directions give the distance in metres)."""
        from recognition.surfaces import mesh_kernels

        g = self.grid
        return mesh_kernels.first_hits(
            self.vertices,
            self.faces,
            g.start,
            g.faces_of,
            g.origin,
            g.cell,
            g.shape,
            np.ascontiguousarray(np.asarray(origins, float).reshape(-1, 3)),
            np.ascontiguousarray(np.asarray(directions, float).reshape(-1, 3)),
        )

    def signed(self, points: ArrayLike) -> Array:
        """Signed distance (positive outside), sign from the closest face's outward
        normal (:attr:`face_normals`).

        Parameters
        ----------
        points : (m, 3) float
            Query points near the surface, metres.

        Returns
        -------
        (m,) float
            Signed distance, metres.
        """
        return self.signed_closest(points)[0]

    def signed_closest(self, points: ArrayLike) -> tuple[Array, Array, IntArray]:
        """Signed distance (m,), closest point (m, 3) and face (m,) of each point (m, 3):
        :meth:`signed` with what it found on the way."""
        d, q, f = self.closest(points)
        p = np.asarray(points, float).reshape(-1, 3)
        return signed_by_side(p, q, self.normals_of(f), d), q, f


@dataclass(frozen=True)
class DistanceField:
    """Signed distance on a voxel grid, exact-ish in a band around the surface.

    Attributes
    ----------
    origin : (3,) float
        Position of voxel (0, 0, 0), metres.
    voxel : float
        Voxel size, metres.
    values : (nx, ny, nz) float32
        Signed distance (positive outside); ``+band`` / ``-band`` beyond the band.
    band : float
        Half width of the band, metres.
    """

    origin: Array
    voxel: float
    values: Array32
    band: float

    @classmethod
    def build(
        cls,
        vertices: ArrayLike,
        normals: Array,
        faces: ArrayLike,
        voxel: float,
        band: float,
        tree: cKDTree | None = None,
    ) -> DistanceField:
        """Sample the signed distance in a band of half width ``band`` around the surface.

        In the band, the distance is the point-to-plane distance to the nearest vertex
        (error about kappa r^2 / 2 for vertex spacing r). Beyond it, voxels outside the
        surface (connected to the grid's boundary) hold ``+band``, inside ``-band``.

        Parameters
        ----------
        vertices : (n, 3) float
            Vertex positions, metres.
        normals : (n, 3) float
            Outward unit vertex normals.
        faces : (f, 3) int
            Triangles, indices into ``vertices``.
        voxel, band : float
            Voxel size and half width of the band, metres.
        tree : cKDTree, optional
            KD-tree of the vertices.
        """
        vertices = np.asarray(vertices, float)
        tree = tree or cKDTree(vertices)
        pad = band + 2 * voxel
        origin = vertices.min(axis=0) - pad
        shape = np.ceil((vertices.max(axis=0) + pad - origin) / voxel).astype(int) + 1
        # voxels near a vertex (or a triangle: sample triangle centres too)
        tri = vertices[np.asarray(faces)]
        seeds = np.concatenate([vertices, tri.mean(axis=1)])
        occupied = np.zeros(shape, bool)
        idx = np.clip(np.round((seeds - origin) / voxel).astype(int), 0, shape - 1)
        occupied[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        reach = ndimage.distance_transform_edt(~occupied) * voxel
        in_band = reach <= band + voxel
        centres = origin + np.argwhere(in_band) * voxel
        _, nearest = tree.query(centres)
        d = np.einsum("ij,ij->i", centres - vertices[nearest], normals[nearest])
        values = np.empty(shape, np.float32)
        values[in_band] = np.clip(d, -band, band)
        labels, _ = ndimage.label(~in_band)
        boundary = np.unique(
            np.concatenate(
                [
                    labels[[0, -1], :, :].ravel(),
                    labels[:, [0, -1], :].ravel(),
                    labels[:, :, [0, -1]].ravel(),
                ]
            )
        )
        outside = np.isin(labels, boundary[boundary > 0])
        values[~in_band] = np.where(outside[~in_band], band, -band)
        return cls(origin, float(voxel), values, float(band))

    def _cell(self, points: ArrayLike) -> tuple[IntArray, Array, Mask]:
        """Lower corner voxel (..., 3), fractions (..., 3) and the off-grid mask of points."""
        g = (np.asarray(points, float) - self.origin) / self.voxel
        shape = np.array(self.values.shape)
        outside = np.any((g < 0) | (g > shape - 1), axis=-1)
        g = np.clip(g, 0, shape - 1 - 1e-9)
        i = np.floor(g).astype(np.int64)
        return i, g - i, outside

    def nearest(self, points: ArrayLike) -> Array32:
        """Signed distance of the nearest voxel centre (no interpolation; +band off the grid).

        Eight times cheaper than :meth:`__call__`, accurate to about half a voxel: for
        screening many poses.

        Parameters
        ----------
        points : (..., 3) float
            Query points, metres.

        Returns
        -------
        (...,) float32
            Signed distance, metres.
        """
        g = np.rint((np.asarray(points, float) - self.origin) / self.voxel).astype(np.int64)
        shape = self.values.shape
        inside = np.all((g >= 0) & (g < shape), axis=-1)
        g = np.clip(g, 0, np.array(shape) - 1)
        flat = (g[..., 0] * shape[1] + g[..., 1]) * shape[2] + g[..., 2]
        return np.where(inside, self.values.ravel()[flat], self.band)

    def __call__(self, points: ArrayLike) -> Array:
        """Trilinearly interpolated signed distance at (..., 3) points (+band off the grid)."""
        i, f, outside = self._cell(points)
        v = self.values
        x, y, z = i[..., 0], i[..., 1], i[..., 2]
        fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
        c00 = v[x, y, z] * (1 - fx) + v[x + 1, y, z] * fx
        c10 = v[x, y + 1, z] * (1 - fx) + v[x + 1, y + 1, z] * fx
        c01 = v[x, y, z + 1] * (1 - fx) + v[x + 1, y, z + 1] * fx
        c11 = v[x, y + 1, z + 1] * (1 - fx) + v[x + 1, y + 1, z + 1] * fx
        out = (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz
        return np.where(outside, self.band, out)

    def value_and_gradient(self, points: ArrayLike) -> tuple[Array, Array]:
        """Interpolated signed distance (...,), metres, and its gradient (..., 3) at (..., 3)
        points, metres (off the grid: ``+band`` and a zero gradient)."""
        i, f, outside = self._cell(points)
        shape = self.values.shape
        flat = (i[..., 0] * shape[1] + i[..., 1]) * shape[2] + i[..., 2]
        v = self.values.ravel()
        sy, sx = shape[2], shape[1] * shape[2]
        c = {
            (a, b, e): v[flat + a * sx + b * sy + e] for a in (0, 1) for b in (0, 1) for e in (0, 1)
        }
        f = f.astype(np.float32)
        fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
        gx, gy, gz = 1 - fx, 1 - fy, 1 - fz
        val = (
            c[0, 0, 0] * gx * gy * gz
            + c[1, 0, 0] * fx * gy * gz
            + c[0, 1, 0] * gx * fy * gz
            + c[1, 1, 0] * fx * fy * gz
            + c[0, 0, 1] * gx * gy * fz
            + c[1, 0, 1] * fx * gy * fz
            + c[0, 1, 1] * gx * fy * fz
            + c[1, 1, 1] * fx * fy * fz
        )
        dx = (
            (c[1, 0, 0] - c[0, 0, 0]) * gy * gz
            + (c[1, 1, 0] - c[0, 1, 0]) * fy * gz
            + (c[1, 0, 1] - c[0, 0, 1]) * gy * fz
            + (c[1, 1, 1] - c[0, 1, 1]) * fy * fz
        )
        dy = (
            (c[0, 1, 0] - c[0, 0, 0]) * gx * gz
            + (c[1, 1, 0] - c[1, 0, 0]) * fx * gz
            + (c[0, 1, 1] - c[0, 0, 1]) * gx * fz
            + (c[1, 1, 1] - c[1, 0, 1]) * fx * fz
        )
        dz = (
            (c[0, 0, 1] - c[0, 0, 0]) * gx * gy
            + (c[1, 0, 1] - c[1, 0, 0]) * fx * gy
            + (c[0, 1, 1] - c[0, 1, 0]) * gx * fy
            + (c[1, 1, 1] - c[1, 1, 0]) * fx * fy
        )
        grad = np.stack([dx, dy, dz], axis=-1).astype(float) / self.voxel
        val = np.where(outside, self.band, val.astype(float))
        grad = np.where(outside[..., None], 0.0, grad)
        return val, grad


@dataclass(frozen=True)
class FieldStack:
    """Several distance fields in one flat array, for batched lookups in which every pose
    names its own field (all models of a database searched in one batch).

    Attributes
    ----------
    values : (N,) float32
        The fields' values (C order), concatenated.
    offset : (m,) int64
        Index in ``values`` of each field's voxel (0, 0, 0).
    shape : (m, 3) int64
        Grid shape of each field.
    origin : (m, 3) float
        Position of each field's voxel (0, 0, 0), metres.
    voxel : (m,) float
        Voxel size of each field, metres.
    band : (m,) float
        Half width of each field's band, metres (the value far from the surface).
    """

    values: Array32
    offset: IntArray
    shape: IntArray
    origin: Array
    voxel: Array
    band: Array

    @classmethod
    def of(cls, fields: Iterable[DistanceField]) -> FieldStack:
        """The stack of ``fields`` (a sequence of :class:`DistanceField`), in order."""
        fields = list(fields)
        sizes = [f.values.size for f in fields]
        if sum(sizes) >= 2**31:
            raise ValueError("distance fields too large to stack (2^31 voxels at most)")
        values = np.concatenate([np.ravel(f.values) for f in fields], dtype=np.float32)
        values.flags.writeable = False  # models read their fields from it (views)
        return cls(
            values,
            np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64),
            np.array([f.values.shape for f in fields], dtype=np.int64),
            np.array([f.origin for f in fields], dtype=float),
            np.array([f.voxel for f in fields], dtype=float),
            np.array([f.band for f in fields], dtype=float),
        )

    def __len__(self) -> int:
        return len(self.offset)

    def field(self, i: int) -> DistanceField:
        """Field ``i`` as a :class:`DistanceField` whose values are a view into the stack."""
        size = int(np.prod(self.shape[i]))
        values = self.values[self.offset[i] : self.offset[i] + size].reshape(self.shape[i])
        return DistanceField(self.origin[i], float(self.voxel[i]), values, float(self.band[i]))

    def nearest_in_frames(
        self, which: ArrayLike, frames: Array, origins: Array, local: Array, paired: bool = False
    ) -> Array32:
        """Signed distance at the nearest voxel centre of points placed by many frames.

        Point ``j`` of pattern ``f`` placed at frame ``c`` is ``origins[c] + frames[c] @
        local[f, j]``, looked up in field ``which[c]``; points off a grid read the value
        of its nearest boundary voxel (which lies beyond the band: ``+band``).

        Parameters
        ----------
        which : (C,) int
            Field of each frame.
        frames : (C, 3, 3) float
            Rotations (columns: the frame's axes in the field's coordinates).
        origins : (C, 3) float
            Frame origins, metres.
        local : (F, P, 3) float
            Point patterns in frame coordinates, metres; with ``paired``, (C, P, 3): one
            pattern per frame.

        Returns
        -------
        (C, F, P) float32, or (C, P) with ``paired``
        """
        from recognition.surfaces import field_kernels  # numba: imported when first needed

        out = field_kernels.nearest_in_frames(
            self.values,
            self.offset,
            self.shape,
            self.origin,
            self.voxel,
            np.ascontiguousarray(which, np.int64),
            np.ascontiguousarray(frames, np.float64),
            np.ascontiguousarray(origins, np.float64),
            np.ascontiguousarray(local, np.float64),
            paired,
        )
        return out[:, 0] if paired else out

    def __call__(self, points: Array, which: ArrayLike) -> Array:
        """Trilinearly interpolated signed distance (B, P) at points (B, P, 3) in fields
        ``which`` (B,), metres (``+band`` off a grid)."""
        return self._interpolate(points, which, gradient=False)[0]

    def value_and_gradient(self, points: Array, which: ArrayLike) -> tuple[Array, Array]:
        """Interpolated signed distance (B, P) and its gradient (B, P, 3) at points (B, P, 3)
        in fields ``which`` (B,); off a grid: ``+band`` and a zero gradient."""
        return self._interpolate(points, which, gradient=True)

    def _interpolate(self, points: Array, which: ArrayLike, gradient: bool) -> tuple[Array, Array]:
        from recognition.surfaces import field_kernels  # numba: imported when first needed

        return field_kernels.interpolate(
            self.values,
            self.offset,
            self.shape,
            self.origin,
            self.voxel,
            self.band,
            np.ascontiguousarray(which, np.int64),
            np.ascontiguousarray(points, np.float64),
            gradient,
        )
