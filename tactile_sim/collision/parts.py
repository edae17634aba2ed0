"""The convex collision parts of a mesh and their files, shipped or cached."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tactile_sim.collision.config import DecompositionConfig, library_versions
from tactile_sim.collision.deviation import HullAccuracy
from tactile_sim.objects.cache import is_triangle_arrays, read_npz, write_npz_atomic

__all__ = [
    "ConvexParts",
    "read_parts",
    "safe_name",
    "shipped_hulls_dir",
    "write_parts",
]


_SHIPPED_HULLS_DIR = Path(__file__).resolve().parents[2] / "assets" / "hulls"


def shipped_hulls_dir() -> Path:
    """Returns the directory of the hulls shipped with the repository (``assets/hulls``)."""
    return _SHIPPED_HULLS_DIR


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


def read_parts(path: Path, key: str, source: str) -> ConvexParts | None:
    """Returns the parts stored at ``path`` if the file is intact and made from ``key``, else
    None; ``source`` says where they came from."""
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


def write_parts(path: Path, parts: ConvexParts, name: str, config: DecompositionConfig) -> None:
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
        "libraries": library_versions(),
        "build_seconds": parts.build_seconds,
        "accuracy": None if parts.accuracy is None else asdict(parts.accuracy),
    }
    write_npz_atomic(path, arrays, meta)


def safe_name(name: str) -> str:
    """Returns a file-name-safe version of a label."""
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "mesh"
