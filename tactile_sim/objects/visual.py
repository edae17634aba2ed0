"""The object's mesh as drawn: a simplified copy of the original, cached by its content.

MuJoCo processes every mesh of a model when it compiles it (about 0.2 s for the catalog's
100k-vertex meshes); the drawn copy needs far fewer triangles. The simplified mesh only
draws the object: the probe touches the original (:mod:`tactile_sim.probing.tip_contact`).
"""

from __future__ import annotations

import hashlib

import numpy as np
import trimesh

from tactile_sim.objects.cache import build_lock, generated_dir, read_npz, write_npz_atomic

__all__ = ["VISUAL_FACES", "visual_mesh"]

#: Triangles of the drawn copy at most.
VISUAL_FACES = 20_000
_KIND = "visual"


def visual_mesh(mesh: trimesh.Trimesh, max_faces: int = VISUAL_FACES) -> trimesh.Trimesh:
    """Returns ``mesh`` simplified to at most ``max_faces`` triangles (itself if it has no
    more), built once and cached under the generated assets, keyed by the mesh's content."""
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    if len(faces) <= max_faces:
        return mesh
    digest = hashlib.sha256(vertices.tobytes() + faces.tobytes() + str(max_faces).encode())
    path = generated_dir(_KIND) / f"{digest.hexdigest()[:24]}.npz"
    cached = read_npz(path, ("vertices", "faces"))
    if cached is None:
        with build_lock(path.with_suffix(".lock")):
            cached = read_npz(path, ("vertices", "faces"))
            if cached is None:
                import fast_simplification

                v, f = fast_simplification.simplify(
                    vertices.astype(np.float32),
                    faces.astype(np.int32),
                    target_reduction=1.0 - max_faces / len(faces),
                )
                arrays = {"vertices": np.asarray(v, np.float64), "faces": np.asarray(f, np.int64)}
                write_npz_atomic(path, arrays, {"faces": len(f)})
                cached = (arrays, {})
    arrays = cached[0]
    return trimesh.Trimesh(arrays["vertices"], arrays["faces"], process=False)
