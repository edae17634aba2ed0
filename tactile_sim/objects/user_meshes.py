"""Meshes like those users bring: scans with holes and loose pieces, low-poly and huge
meshes, CAD parts with flat faces, fillets, bores and teeth (seeded, deterministic).

The solid shapes are SDF recipes (:mod:`tactile_sim.objects.recipe`) meshed and cached
like the catalog's (:func:`~tactile_sim.objects.catalog.load_or_build`); the damage a
scan has is then done to the mesh: a blind spot where the scanner never looked (the
triangles facing away from it removed), the base left open, loose shells (eyes, chips).
:func:`user_mesh_set` gives the benchmark's folder (:func:`write_user_meshes`), the
single kinds feed the tests.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from tactile_sim.objects.catalog import load_or_build
from tactile_sim.objects.recipe import (
    Ellipsoid,
    HalfSpace,
    Intersect,
    Node,
    ObjectRecipe,
    Subtract,
    Superellipsoid,
    Tube,
    Union,
)

__all__ = [
    "bracket",
    "cad_part",
    "capped_sphere",
    "creature_with_eyes",
    "dense_mesh",
    "free_form",
    "gear",
    "low_poly_solid",
    "scan",
    "user_mesh_set",
    "write_user_meshes",
]

#: Vertices of the generated solids (enough for 1 mm curvature fits at 60-100 mm).
TARGET_VERTICES = 30_000


def _mesh(
    name: str, shape: Node, dims_mm: tuple[float, float, float], vertices: int
) -> trimesh.Trimesh:
    dims = tuple(d * 1e-3 for d in dims_mm)
    recipe = ObjectRecipe(name, f"generated: {name}", dims, vertices, shape, 1e-3)  # type: ignore[arg-type]
    return load_or_build(recipe, progress=False).mesh


def free_form(seed: int, vertices: int = TARGET_VERTICES) -> trimesh.Trimesh:
    """A smooth free-form solid in the style of the catalog (a body of blended ellipsoids
    with a few limbs), 60-100 mm, on a flat base; metres."""
    rng = np.random.default_rng([seed, 101])
    parts: list[Node] = [
        Ellipsoid(
            (0.0, 0.0, 22.0),
            tuple(float(x) for x in rng.uniform([20, 15, 14], [30, 24, 22])),  # type: ignore[arg-type]
        )
    ]
    for _ in range(int(rng.integers(3, 6))):
        direction = rng.normal(size=3)
        direction[2] = abs(direction[2])
        direction /= np.linalg.norm(direction)
        start = direction * 12 + (0, 0, 22)
        end = direction * rng.uniform(24, 38) + (0, 0, 22)
        parts.append(
            Tube(
                (tuple(start.tolist()), tuple(end.tolist())),  # type: ignore[arg-type]
                (float(rng.uniform(6, 10)), float(rng.uniform(3, 6))),
            )
        )
    shape = Intersect((HalfSpace((0.0, 0.0, -1.0), 0.0), Union(tuple(parts), k=6.0)), k=1.0)
    size = rng.uniform(60, 100)
    return _mesh(f"free_form_{seed}", shape, (size, size * 0.8, size * 0.7), vertices)


def scan(mesh: trimesh.Trimesh, seed: int, *, shells: int = 2) -> trimesh.Trimesh:
    """``mesh`` as a scanner leaves it: open at its base, a blind spot where the triangles
    face away from a seeded direction, and ``shells`` loose shells (eyes, chips) on it."""
    rng = np.random.default_rng([seed, 202])
    normals, centres = mesh.face_normals, mesh.triangles_center
    low = centres[:, 2] < mesh.bounds[0, 2] + 1e-3  # the base the object stood on
    away = rng.normal(size=3)
    away[2] = -abs(away[2]) * 0.3
    away /= np.linalg.norm(away)
    blind = normals @ away > 0.92
    kept = mesh.submesh([np.flatnonzero(~(low | blind))], append=True)
    pieces = [kept]
    surface = mesh.vertices[rng.choice(len(mesh.vertices), shells, replace=False)]
    for k, point in enumerate(surface):
        pieces.append(
            trimesh.creation.icosphere(3, radius=float(rng.uniform(2e-3, 4e-3))).apply_translation(
                point + 1e-3 * mesh.vertex_normals[rng.integers(len(mesh.vertices))] * k
            )
        )
    out = trimesh.util.concatenate(pieces)
    assert isinstance(out, trimesh.Trimesh)
    return out


def capped_sphere(radius_m: float = 0.035, cut_m: float = 0.02) -> trimesh.Trimesh:
    """A sphere with its cap above ``z = cut_m`` cut away (open)."""
    sphere = trimesh.creation.icosphere(5, radius=radius_m)
    return sphere.submesh([np.flatnonzero(sphere.triangles_center[:, 2] < cut_m)], append=True)


def creature_with_eyes(seed: int = 0) -> trimesh.Trimesh:
    """A free-form body with two separate eye shells sitting on it."""
    body = free_form(seed)
    top = body.vertices[np.argsort(body.vertices[:, 0] + 0.3 * body.vertices[:, 2])[-2:]]
    eyes = [trimesh.creation.icosphere(3, radius=3e-3).apply_translation(p) for p in top]
    out = trimesh.util.concatenate([body, *eyes])
    assert isinstance(out, trimesh.Trimesh)
    return out


def low_poly_solid(n_vertices: int = 300, seed: int = 0) -> trimesh.Trimesh:
    """A free-form solid decimated to about ``n_vertices`` vertices."""
    import fast_simplification

    mesh = free_form(seed)
    v, f = fast_simplification.simplify(
        np.asarray(mesh.vertices, np.float32),
        np.asarray(mesh.faces, np.int32),
        target_reduction=1.0 - n_vertices / len(mesh.vertices),
    )
    return trimesh.Trimesh(np.asarray(v, float), np.asarray(f, np.int64), process=False)


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float], k: float) -> Node:
    """An axis-aligned box with flat faces and edges rounded over ``k``, recipe units: six
    half-spaces cut from a slightly larger rounded block (which bounds it)."""
    centre = tuple((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    half = tuple((b - a) / 2 * 1.06 + 1.0 for a, b in zip(lo, hi, strict=True))
    faces: list[Node] = [Superellipsoid(centre, half, (0.3, 0.3))]  # type: ignore[arg-type]
    faces += [HalfSpace((-1.0, 0.0, 0.0), -lo[0]), HalfSpace((1.0, 0.0, 0.0), hi[0])]
    faces += [HalfSpace((0.0, -1.0, 0.0), -lo[1]), HalfSpace((0.0, 1.0, 0.0), hi[1])]
    faces += [HalfSpace((0.0, 0.0, -1.0), -lo[2]), HalfSpace((0.0, 0.0, 1.0), hi[2])]
    return Intersect(tuple(faces), k=k)


def bracket(vertices: int = TARGET_VERTICES) -> trimesh.Trimesh:
    """An L-bracket: a base plate and an upright, a fillet where they meet, rounded edges,
    a bore through each."""
    base = _box((-40.0, -20.0, 0.0), (40.0, 20.0, 8.0), 1.5)
    upright = _box((-40.0, -20.0, 0.0), (-32.0, 20.0, 50.0), 1.5)
    body = Union((base, upright), k=8.0)
    holes = (
        Tube(((10.0, 0.0, -10.0), (10.0, 0.0, 20.0)), (6.0, 6.0)),
        Tube(((-60.0, 0.0, 32.0), (-20.0, 0.0, 32.0)), (5.0, 5.0)),
    )
    return _mesh("bracket", Subtract(body, holes, k=1.0), (80.0, 40.0, 50.0), vertices)


def gear(teeth: int = 14, vertices: int = TARGET_VERTICES) -> trimesh.Trimesh:
    """A spur gear: a disc with ``teeth`` teeth and a bore."""
    rim = Intersect(
        (
            HalfSpace((0.0, 0.0, -1.0), 0.0),
            HalfSpace((0.0, 0.0, 1.0), 14.0),
            Tube(((0.0, 0.0, -50.0), (0.0, 0.0, 50.0)), (30.0, 30.0)),
        ),
        k=1.0,
    )
    tooth_parts: list[Node] = [rim]
    for i in range(teeth):
        angle = 360.0 * i / teeth
        c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        tooth_parts.append(
            Superellipsoid(
                (33.0 * c, 33.0 * s, 7.0), (5.0, 2.6, 7.0), (0.2, 0.2), (0.0, 0.0, angle)
            )
        )
    body = Intersect(
        (
            Union(tuple(tooth_parts), k=1.5),
            HalfSpace((0, 0, -1.0), 0.0),
            HalfSpace((0, 0, 1.0), 14.0),
        ),
        k=0.8,
    )
    shape = Subtract(body, (Tube(((0.0, 0.0, -50.0), (0.0, 0.0, 50.0)), (8.0, 8.0)),), k=0.8)
    return _mesh(f"gear_{teeth}", shape, (76.0, 76.0, 14.0), vertices)


def cad_part(seed: int, vertices: int = TARGET_VERTICES) -> trimesh.Trimesh:
    """A block part: a rounded block with seeded bosses on top and bores through it."""
    rng = np.random.default_rng([seed, 303])
    length, width, height = rng.uniform(60, 90), rng.uniform(35, 55), rng.uniform(18, 30)
    parts: list[Node] = [_box((0, 0, 0), (length, width, height), float(rng.uniform(1, 4)))]
    for _ in range(int(rng.integers(1, 3))):
        x, y = rng.uniform(12, length - 12), rng.uniform(12, width - 12)
        r = float(rng.uniform(5, 9))
        parts.append(
            Intersect(
                (
                    Tube(((x, y, 0.0), (x, y, height + 60.0)), (r, r)),
                    HalfSpace((0, 0, 1.0), float(height + rng.uniform(6, 14))),
                ),
                k=1.0,
            )
        )
    holes: list[Node] = []
    for _ in range(int(rng.integers(1, 3))):
        y, z = rng.uniform(8, width - 8), rng.uniform(6, height - 6)
        r = float(rng.uniform(2.5, min(5.0, height / 4)))
        holes.append(Tube(((-20.0, y, z), (length + 20.0, y, z)), (r, r)))
    shape = Subtract(Union(tuple(parts), k=float(rng.uniform(2, 5))), tuple(holes), k=0.8)
    return _mesh(f"part_{seed}", shape, (length, width, height + 14.0), vertices)


def dense_mesh(faces: int = 2_000_000) -> trimesh.Trimesh:
    """A torus of about ``faces`` triangles (a photogrammetry-sized mesh)."""
    minor = int(np.sqrt(faces / 8))
    # made at unit size: at metre scale trimesh merges the rings of a fine revolve away
    torus = trimesh.creation.torus(1.0, 0.4, major_sections=4 * minor, minor_sections=minor)
    return torus.apply_scale(0.03)


def user_mesh_set(seed: int = 0) -> dict[str, trimesh.Trimesh]:
    """Twelve meshes, metres: six free-form scans (holes and loose pieces, one low-poly)
    and six CAD-like parts (a bracket, a gear, four block parts with bosses and bores)."""
    meshes = {f"scan_{k}": scan(free_form(seed + k), seed + k) for k in range(5)}
    meshes["scan_low_poly"] = low_poly_solid(300, seed + 5)
    meshes["bracket"] = bracket()
    meshes["gear"] = gear()
    for k in range(4):
        meshes[f"part_{k}"] = cad_part(seed + k)
    return meshes


#: The file formats the folder cycles through.
_FORMATS = (".ply", ".obj", ".stl", ".off", ".glb")


def write_user_meshes(directory: Path, seed: int = 0, units: str = "mm") -> list[Path]:
    """Writes :func:`user_mesh_set` to ``directory`` in ``units``, cycling through PLY, OBJ,
    STL, OFF and GLB; returns the files."""
    from recognition.surfaces.mesh_files import UNITS

    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, (name, mesh) in enumerate(user_mesh_set(seed).items()):
        path = directory / f"{name}{_FORMATS[i % len(_FORMATS)]}"
        mesh.copy().apply_scale(1.0 / UNITS[units]).export(path)
        paths.append(path)
    return paths
