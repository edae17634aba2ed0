"""Mesh files read as models' meshes: OBJ, PLY, STL, OFF, GLB and glTF, in any units."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh

from recognition.errors import InvalidArgument, InvalidModel

__all__ = ["MESH_SUFFIXES", "UNITS", "read_mesh"]

#: File suffixes read (lower case).
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
#: Length units a mesh file may be in, metres per unit.
UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}


def read_mesh(path: str | os.PathLike[str], units: str = "m") -> trimesh.Trimesh:
    """Returns the triangles of a mesh file in metres, as stored (nothing merged or
    dropped: :func:`~recognition.surfaces.mesh_repair.prepare_mesh` does that and says
    so); a scene's meshes (glTF, OBJ groups) are put together in its frame.

    Raises
    ------
    InvalidArgument
        Unknown units.
    InvalidModel
        The file is missing, of another format, unreadable, or holds no triangles.
    """
    if units not in UNITS:
        raise InvalidArgument(f"units must be one of {', '.join(UNITS)}, got {units!r}")
    path = Path(path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InvalidModel(
            f"{path}: not a mesh file this reads; expected one of {', '.join(MESH_SUFFIXES)}"
        )
    if not path.is_file():
        raise InvalidModel(f"{path}: no such file")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh's loaders raise anything from KeyError to IndexError
        raise InvalidModel(
            f"{path}: cannot read it as a mesh: {type(exc).__name__}: {exc}"
        ) from exc
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise InvalidModel(f"{path}: holds no triangles")
    vertices = np.asarray(loaded.vertices, dtype=np.float64) * UNITS[units]
    return trimesh.Trimesh(vertices, np.asarray(loaded.faces), process=False)
