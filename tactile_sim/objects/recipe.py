"""Object recipes: trees of implicit primitives and blends, read from JSON.

A recipe describes one object as a signed distance field (SDF) built from smooth
primitives (ellipsoids, tubes, superellipsoids, a spiral shell) combined by sharp or
smooth unions, subtractions, intersections and mirrors. Recipes are data: they live as
JSON files in ``assets/objects/`` and parse into the frozen dataclasses below. The SDF
evaluation is in :mod:`tactile_sim.objects.sdf`, the meshing in
:mod:`tactile_sim.objects.meshing`.

Primitive coordinates are in *recipe units* of ``ObjectRecipe.unit_m`` metres each
(millimetres in the shipped recipes). The design need not have the exact target size:
the generator scales the surface, per axis, to ``ObjectRecipe.dimensions_m`` and
records the scale it applied.

JSON form of a node: an object with ``"type"`` (one of :data:`NODE_TYPES`) and the
dataclass's fields; child nodes nest under ``children``, ``child``, ``base`` and
``cuts``. Omitted fields take their defaults.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, get_args, get_origin, get_type_hints

from tactile_sim.errors import AssetError

__all__ = [
    "NODE_TYPES",
    "Ellipsoid",
    "HalfSpace",
    "Intersect",
    "Mirror",
    "Node",
    "ObjectRecipe",
    "SpiralShell",
    "Subtract",
    "Superellipsoid",
    "Tube",
    "Union",
    "load_recipe",
    "node_from_dict",
    "node_to_dict",
    "recipe_from_dict",
    "recipe_to_dict",
]

Vec3 = tuple[float, float, float]
ZERO3: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Ellipsoid:
    """Solid ellipsoid.

    Attributes
    ----------
    center : (3,) float, recipe units
    radii : (3,) float, recipe units
        Semi-axes along the local x, y, z axes.
    rotation_deg : (3,) float, degrees
        Extrinsic rotations about the x, then y, then z axes (``R = Rz @ Ry @ Rx``),
        applied to the local frame.
    """

    center: Vec3
    radii: Vec3
    rotation_deg: Vec3 = ZERO3


@dataclass(frozen=True)
class Superellipsoid:
    """Solid superellipsoid (Barr's superquadric), rounded-box shapes such as pebbles.

    Attributes
    ----------
    center : (3,) float, recipe units
    radii : (3,) float, recipe units
    exponents : (2,) float
        ``(e1, e2)``: squareness along local z and in the local xy plane; 1 is an
        ellipsoid, towards 0 a box, 2 a bicone.
    rotation_deg : (3,) float, degrees
        As :class:`Ellipsoid`.
    """

    center: Vec3
    radii: Vec3
    exponents: tuple[float, float] = (1.0, 1.0)
    rotation_deg: Vec3 = ZERO3


@dataclass(frozen=True)
class Tube:
    """Tube of varying radius along a polyline or a smooth curve (legs, tails, trunks).

    Attributes
    ----------
    points : (m, 3) float, recipe units, m >= 2
        Centreline control points.
    radii : (m,) float, recipe units
        Radius at each control point, interpolated linearly in between.
    smooth : bool
        False: straight segments between the points (round cones). True: a centripetal
        Catmull-Rom spline through the points, resampled into ``subdivisions`` round
        cones per span.
    subdivisions : int
        Round cones per span of a smooth tube.
    """

    points: tuple[Vec3, ...]
    radii: tuple[float, ...]
    smooth: bool = False
    subdivisions: int = 8


@dataclass(frozen=True)
class SpiralShell:
    """Coiled shell: an elliptic tube swept along a conical logarithmic spiral.

    In the local frame the spiral coils about +z, counter-clockwise towards the
    aperture at angle 0 on the +x axis. At ``t`` turns before the aperture the
    centreline has radius ``aperture_radius * growth_per_turn**-t`` and height
    ``spire * (aperture_radius - radius)``; the tube's half-widths are
    ``tube_ratio * radius`` radially and ``tube_ratio * tube_aspect * radius`` along z.

    Attributes
    ----------
    center : (3,) float, recipe units
        Coiling axis origin (the aperture's centreline height is 0 there).
    aperture_radius : float, recipe units
        Centreline radius at the aperture.
    growth_per_turn : float
        Ratio of centreline radii one turn apart (> 1).
    turns : float
        Number of turns from apex to aperture.
    tube_ratio : float
        Radial tube half-width over centreline radius.
    tube_aspect : float
        Axial over radial tube half-width.
    spire : float
        Axial rise per unit of radius lost towards the apex (0 for a flat coil).
    rotation_deg : (3,) float, degrees
        As :class:`Ellipsoid`.
    """

    center: Vec3
    aperture_radius: float
    growth_per_turn: float
    turns: float
    tube_ratio: float
    tube_aspect: float = 1.0
    spire: float = 0.0
    rotation_deg: Vec3 = ZERO3


@dataclass(frozen=True)
class HalfSpace:
    """Half-space ``dot(normal, p) <= offset`` (flat bases, cuts).

    Attributes
    ----------
    normal : (3,) float
        Outward normal; normalised on evaluation.
    offset : float, recipe units
    """

    normal: Vec3
    offset: float


@dataclass(frozen=True)
class Union:
    """Union of the children, smooth over a blend width ``k`` (0: sharp).

    Attributes
    ----------
    children : tuple of nodes
    k : float, recipe units
        Width of the polynomial smooth-minimum blend.
    """

    children: tuple[Node, ...]
    k: float = 0.0


@dataclass(frozen=True)
class Subtract:
    """``base`` minus the union of ``cuts``, smooth over a blend width ``k`` (0: sharp)."""

    base: Node
    cuts: tuple[Node, ...]
    k: float = 0.0


@dataclass(frozen=True)
class Intersect:
    """Intersection of the children, smooth over a blend width ``k`` (0: sharp)."""

    children: tuple[Node, ...]
    k: float = 0.0


@dataclass(frozen=True)
class Mirror:
    """The child and its mirror image: the child evaluated at ``|p[axis]|``.

    Attributes
    ----------
    child : node
        Designed on the positive side of the mirror plane.
    axis : int
        0, 1 or 2: the mirror plane is ``p[axis] = 0``.
    """

    child: Node
    axis: int = 1


Node = (
    Union
    | Subtract
    | Intersect
    | Mirror
    | Ellipsoid
    | Superellipsoid
    | Tube
    | SpiralShell
    | HalfSpace
)

#: JSON ``"type"`` tag of each node class.
NODE_TYPES: dict[str, type] = {
    "union": Union,
    "subtract": Subtract,
    "intersect": Intersect,
    "mirror": Mirror,
    "ellipsoid": Ellipsoid,
    "superellipsoid": Superellipsoid,
    "tube": Tube,
    "spiral_shell": SpiralShell,
    "half_space": HalfSpace,
}
_TYPE_OF_CLASS = {cls: tag for tag, cls in NODE_TYPES.items()}


@dataclass(frozen=True)
class ObjectRecipe:
    """Everything the generator needs to build one object's mesh.

    Attributes
    ----------
    name : str
        Catalog name (lower case).
    description : str
        One sentence saying what the object is and how it is posed.
    dimensions_m : (3,) float, metres
        Bounding-box size along the model frame's x (front), y (left), z (up) axes;
        the thesis's Table 4.4 dimensions, assigned to axes.
    target_vertices : int
        Vertex count the meshing resolution is chosen for (met to a few per cent).
    shape : node
        The SDF tree, in recipe units, x forward and z up.
    unit_m : float, metres
        Length of one recipe unit.
    """

    name: str
    description: str
    dimensions_m: Vec3
    target_vertices: int
    shape: Node
    unit_m: float = 1e-3

    def content_hash(self, salt: str = "") -> str:
        """Hex SHA-256 of the canonical JSON of this recipe and ``salt``.

        Covers every field that shapes the mesh; the prose ``description`` is left out.
        """
        geometry = {k: v for k, v in recipe_to_dict(self).items() if k != "description"}
        text = json.dumps(
            {"recipe": geometry, "salt": salt},
            sort_keys=True,
            separators=(",", ":"),
        )
        return hashlib.sha256(text.encode()).hexdigest()


def node_to_dict(node: Node) -> dict[str, Any]:
    """The JSON-ready dict of a node (lists for tuples, ``"type"`` tag first)."""
    out: dict[str, Any] = {"type": _TYPE_OF_CLASS[type(node)]}
    for field in dataclasses.fields(node):
        out[field.name] = _to_json(getattr(node, field.name))
    return out


def _to_json(value: Any) -> Any:
    if type(value) in _TYPE_OF_CLASS:
        return node_to_dict(value)
    if isinstance(value, tuple):
        return [_to_json(v) for v in value]
    if isinstance(value, bool | int | str):
        return value
    return float(value)


def node_from_dict(data: Any, where: str = "shape") -> Node:
    """Parse a node from its JSON dict; raise AssetError naming the bad field."""
    if not isinstance(data, dict) or "type" not in data:
        raise AssetError(f"{where}: expected an object with a 'type', got {data!r:.80}")
    tag = data["type"]
    cls = NODE_TYPES.get(tag)
    if cls is None:
        raise AssetError(
            f"{where}: unknown node type {tag!r}; expected one of {sorted(NODE_TYPES)}"
        )
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = set(data) - set(fields) - {"type"}
    if unknown:
        raise AssetError(f"{where} ({tag}): unknown fields {sorted(unknown)}")
    kwargs = {}
    for name, field in fields.items():
        if name not in data:
            if field.default is dataclasses.MISSING:
                raise AssetError(f"{where} ({tag}): missing field {name!r}")
            continue
        kwargs[name] = _from_json(data[name], hints[name], f"{where}.{name}")
    node = cls(**kwargs)
    _validate(node, where)
    return node


def _from_json(value: Any, hint: Any, where: str) -> Any:
    if hint is Node:
        return node_from_dict(value, where)
    if get_origin(hint) is tuple:
        args = get_args(hint)
        if not isinstance(value, list):
            raise AssetError(f"{where}: expected a list, got {value!r:.80}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_from_json(v, args[0], f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise AssetError(f"{where}: expected {len(args)} values, got {len(value)}")
        return tuple(
            _from_json(v, a, f"{where}[{i}]")
            for i, (v, a) in enumerate(zip(value, args, strict=True))
        )
    if hint is bool:
        if not isinstance(value, bool):
            raise AssetError(f"{where}: expected true/false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise AssetError(f"{where}: expected an integer, got {value!r}")
        return value
    if hint is float:
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise AssetError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise AssetError(f"{where}: expected a string, got {value!r}")
        return value
    raise TypeError(f"{where}: no JSON conversion for type {hint!r}")


def _validate(node: Node, where: str) -> None:
    """Check the value ranges the SDF code relies on."""
    problems = []
    if isinstance(node, Ellipsoid | Superellipsoid) and min(node.radii) <= 0:
        problems.append("radii must be positive")
    if isinstance(node, Superellipsoid) and min(node.exponents) <= 0:
        problems.append("exponents must be positive")
    if isinstance(node, Tube):
        if len(node.points) < 2 or len(node.radii) != len(node.points):
            problems.append("needs >= 2 points and one radius per point")
        if node.radii and min(node.radii) <= 0:
            problems.append("radii must be positive")
        if node.subdivisions < 1:
            problems.append("subdivisions must be >= 1")
    if isinstance(node, SpiralShell):
        if node.growth_per_turn <= 1 or node.turns <= 0:
            problems.append("growth_per_turn must be > 1 and turns > 0")
        if node.aperture_radius <= 0 or node.tube_ratio <= 0 or node.tube_aspect <= 0:
            problems.append("aperture_radius, tube_ratio and tube_aspect must be positive")
    if isinstance(node, HalfSpace) and math.hypot(*node.normal) == 0:
        problems.append("normal must be non-zero")
    if isinstance(node, Union | Intersect) and not node.children:
        problems.append("needs at least one child")
    if isinstance(node, Union | Subtract | Intersect) and node.k < 0:
        problems.append("k must be >= 0")
    if isinstance(node, Mirror) and node.axis not in (0, 1, 2):
        problems.append("axis must be 0, 1 or 2")
    if problems:
        raise AssetError(f"{where} ({_TYPE_OF_CLASS[type(node)]}): {'; '.join(problems)}")


def recipe_to_dict(recipe: ObjectRecipe) -> dict[str, Any]:
    """The JSON-ready dict of a recipe."""
    return {
        "name": recipe.name,
        "description": recipe.description,
        "dimensions_m": [float(v) for v in recipe.dimensions_m],
        "target_vertices": recipe.target_vertices,
        "unit_m": float(recipe.unit_m),
        "shape": node_to_dict(recipe.shape),
    }


def recipe_from_dict(data: Any, where: str = "recipe") -> ObjectRecipe:
    """Parse and check a recipe dict; raise AssetError naming what is wrong."""
    if not isinstance(data, dict):
        raise AssetError(f"{where}: expected a JSON object")
    required = {"name", "description", "dimensions_m", "target_vertices", "shape"}
    missing = required - set(data)
    unknown = set(data) - required - {"unit_m"}
    if missing or unknown:
        raise AssetError(f"{where}: missing fields {sorted(missing)}, unknown {sorted(unknown)}")
    dims = _from_json(data["dimensions_m"], Vec3, f"{where}.dimensions_m")
    target = _from_json(data["target_vertices"], int, f"{where}.target_vertices")
    unit = _from_json(data.get("unit_m", 1e-3), float, f"{where}.unit_m")
    if min(dims) <= 0 or target < 100 or unit <= 0:
        raise AssetError(f"{where}: dimensions, target_vertices and unit_m must be positive")
    return ObjectRecipe(
        name=_from_json(data["name"], str, f"{where}.name"),
        description=_from_json(data["description"], str, f"{where}.description"),
        dimensions_m=dims,
        target_vertices=target,
        shape=node_from_dict(data["shape"], f"{where}.shape"),
        unit_m=unit,
    )


def load_recipe(path: Path) -> ObjectRecipe:
    """Read a recipe JSON file; raise AssetError if it is missing or malformed."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise AssetError(f"cannot read object recipe {path}: {exc}") from exc
    return recipe_from_dict(data, where=Path(path).name)
