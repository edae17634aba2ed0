"""Seeded recipes of further objects: free-form blobs and CAD-like parts.

A database larger than the catalog needs many distinct objects. Each generated recipe is
drawn from ``numpy.random.default_rng((seed, index))`` alone, so the same (seed, index)
always gives the same object, and builds through the catalog's own meshing
(:func:`~tactile_sim.objects.catalog.load_or_build`: watertight, cached):

- a *free-form* object (``blob-NNN``), in the style of the catalog's recipes: a body
  ellipsoid with three to six limbs (ellipsoids and tapered tubes anchored on its
  surface, some mirrored left-right), smoothly united, sometimes with a dent, cut flat
  at the base;
- a *CAD-like part* (``part-NNN``): a block with filleted edges (a superellipsoid of
  small exponents), one to three bores through it, one to three bosses or a step on its
  top, each blended over about a millimetre.

Every fourth object is a part. Sizes: largest side 60-100 mm, as the catalog's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from tactile_sim.objects.recipe import (
    Ellipsoid,
    HalfSpace,
    Intersect,
    Mirror,
    Node,
    ObjectRecipe,
    Subtract,
    Superellipsoid,
    Tube,
    Union,
    Vec3,
)
from tactile_sim.objects.sdf import node_bounds

__all__ = ["GENERATED_VERTICES", "PART_EVERY", "generated_name", "generated_recipe"]

#: Vertex count of a generated object's mesh (the catalog's run 30-100k).
GENERATED_VERTICES = 30_000

#: Every this-many-th generated object (index 3, 7, ...) is a CAD-like part.
PART_EVERY = 4

#: Largest side of a generated object, mm.
SIZE_RANGE_MM = (60.0, 100.0)


def _is_part(index: int) -> bool:
    return index % PART_EVERY == PART_EVERY - 1


def generated_name(index: int) -> str:
    """The name of generated object ``index``: ``blob-NNN`` or ``part-NNN``."""
    return f"{'part' if _is_part(index) else 'blob'}-{index:03d}"


def _round(values: ArrayLike, digits: int = 2) -> tuple[float, ...]:
    return tuple(float(v) for v in np.round(np.atleast_1d(values), digits))


def _vec(values: ArrayLike, digits: int = 2) -> Vec3:
    x, y, z = _round(values, digits)
    return (x, y, z)


def _direction(rng: np.random.Generator, min_z: float = -0.3) -> np.ndarray:
    """A random unit vector with z at least ``min_z`` (limbs do not grow into the table)."""
    while True:
        v = rng.normal(size=3)
        v /= np.linalg.norm(v)
        if v[2] >= min_z:
            return v


def _blob(rng: np.random.Generator) -> Node:
    """Body ellipsoid, limbs anchored on its surface, a dent, a flat base (mm)."""
    radii = rng.uniform([18.0, 14.0, 14.0], [32.0, 26.0, 28.0])
    body = np.array([0.0, 0.0, radii[2] * rng.uniform(0.6, 0.9)])
    parts: list[Node] = [Ellipsoid(_vec(body), _vec(radii), _vec(rng.uniform(-15, 15, 3)))]
    for _ in range(int(rng.integers(3, 7))):
        u = _direction(rng)
        anchor = body + 0.85 * radii * u
        if rng.random() < 0.5:
            size = rng.uniform(5.0, 14.0, 3)
            limb: Node = Ellipsoid(
                _vec(anchor + 0.4 * size.min() * u),
                _vec(size),
                _vec(rng.uniform(-60, 60, 3)),
            )
        else:
            length = rng.uniform(12.0, 30.0)
            bend = _direction(rng, -1.0) * rng.uniform(0.0, 0.4)
            tip = anchor + length * (u + bend) / np.linalg.norm(u + bend)
            middle = 0.5 * (anchor + tip) + rng.normal(scale=2.0, size=3)
            r0 = rng.uniform(4.0, 8.0)
            limb = Tube(
                tuple(_vec(p) for p in (anchor - 3.0 * u, middle, tip)),
                _round([r0, r0 * rng.uniform(0.6, 0.9), r0 * rng.uniform(0.4, 0.7)]),
                smooth=True,
            )
        if rng.random() < 0.4 and abs(anchor[1]) > 4.0:
            limb = Mirror(limb, axis=1)
        parts.append(limb)
    shape: Node = Union(tuple(parts), k=float(np.round(rng.uniform(2.0, 7.0), 2)))
    if rng.random() < 0.3:
        u = _direction(rng, 0.0)
        dent = Ellipsoid(_vec(body + radii * u), _vec(rng.uniform(4.0, 8.0, 3)), (0.0, 0.0, 0.0))
        shape = Subtract(shape, (dent,), k=1.0)
    return Intersect((HalfSpace((0.0, 0.0, -1.0), 0.0), shape), k=1.0)


def _part(rng: np.random.Generator) -> Node:
    """A filleted block with bores and bosses (mm); its bottom face is the base."""
    half = rng.uniform([25.0, 18.0, 8.0], [45.0, 35.0, 20.0])
    e1, e2 = _round(rng.uniform(0.12, 0.3, 2))
    squareness = (e1, e2)
    block = Superellipsoid(_vec([0.0, 0.0, half[2]]), _vec(half), squareness)
    top = 2.0 * half[2]
    bosses: list[Node] = []
    if rng.random() < 0.3:  # a step: a smaller block on the top face
        step = half * rng.uniform([0.3, 0.4, 0.5], [0.6, 0.9, 1.0])
        at = [
            rng.uniform(-1, 1) * (half[0] - step[0]),
            rng.uniform(-1, 1) * (half[1] - step[1]),
            top,
        ]
        bosses.append(Superellipsoid(_vec(at), _vec(step), squareness))
    for _ in range(int(rng.integers(1, 4))):
        r = rng.uniform(4.0, 9.0)
        x, y = rng.uniform(-1, 1, 2) * (half[:2] - r - 4.0)
        height = rng.uniform(5.0, 18.0)
        bosses.append(Tube((_vec([x, y, top - 4.0]), _vec([x, y, top + height])), _round([r, r])))
    shape: Node = Union((block, *bosses), k=1.5)
    bores: list[Node] = []
    for _ in range(int(rng.integers(1, 4))):
        axis = int(rng.integers(0, 3))
        r = rng.uniform(2.5, 0.35 * min(half[(axis + 1) % 3], half[(axis + 2) % 3]) + 2.5)
        centre = np.array([0.0, 0.0, half[2]])
        for k in {0, 1, 2} - {axis}:
            centre[k] += rng.uniform(-0.5, 0.5) * (half[k] - r)
        a, b = centre.copy(), centre.copy()
        a[axis] -= 3.0 * half[axis] + 30.0
        b[axis] += 3.0 * half[axis] + 30.0
        bores.append(Tube((_vec(a), _vec(b)), _round([r, r])))
    shape = Subtract(shape, tuple(bores), k=1.0)
    return Intersect((HalfSpace((0.0, 0.0, -1.0), -0.5), shape), k=0.0)


def generated_recipe(index: int, seed: int = 0) -> ObjectRecipe:
    """The recipe of generated object ``index`` (a part every :data:`PART_EVERY`-th).

    Drawn from ``default_rng((seed, index))`` only; sized so that its largest side is
    60-100 mm, with the design's own proportions.
    """
    if index < 0 or seed < 0:
        raise ValueError(f"index and seed must be non-negative, got {index}, {seed}")
    rng = np.random.default_rng((seed, index))
    part = _is_part(index)
    shape = _part(rng) if part else _blob(rng)
    box = node_bounds(shape)
    assert box is not None  # both kinds are bounded
    extent = box[1] - box[0]
    extent[2] = box[1][2] - max(box[0][2], 0.0)  # the base cut at z = 0
    size = rng.uniform(*SIZE_RANGE_MM)
    dimensions = _vec(extent * size / extent.max() * 1e-3, 5)
    kind = "a CAD-like part (filleted block, bores, bosses)" if part else "a free-form blob"
    return ObjectRecipe(
        name=generated_name(index),
        description=f"Generated object {index} (seed {seed}): {kind}, resting on its base.",
        dimensions_m=dimensions,
        target_vertices=GENERATED_VERTICES,
        shape=shape,
        unit_m=1e-3,
    )
