"""The closed-form test solids of thesis Fig. 4.15 and Section 3.4.2, as meshes."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from tactile_sim.collision.hulls import is_convex
from tactile_sim.collision.outlines import (
    DEFAULT_SPLINE_KNOTS_M,
    closed_spline_coefficients,
    closed_spline_outline,
    ellipse_outline,
    extrude_outline,
)
from tactile_sim.errors import UnknownObject

__all__ = [
    "CYLINDER_LENGTH_M",
    "PRISM_HEIGHT_M",
    "SOLID_NAMES",
    "Solid",
    "load_solid",
    "solid_names",
    "sphere_mesh",
]


SOLID_NAMES = (
    "cylinder_1",
    "cylinder_2",
    "elliptic_cylinder",
    "sphere",
    "planar_ellipse",
    "planar_spline",
)
"""The four algebraic objects of thesis Fig. 4.15, then the two planar-experiment prisms."""


CYLINDER_LENGTH_M = 0.100
"""Length of the lying cylinders (the thesis gives only their cross-sections)."""


PRISM_HEIGHT_M = 0.030
"""Height of the planar-experiment prisms."""


@dataclass(frozen=True)
class Solid:
    """A closed-form test solid as a mesh.

    Model frame (as the catalog's): metres, z up, lowest point on z = 0, bounding box
    centred on the z axis. Cylinders lie on the table with their axis along x, so their
    curved side faces up; the planar-experiment prisms stand on the table, axis along z.

    Attributes
    ----------
    name : str
        One of :func:`solid_names`.
    mesh : trimesh.Trimesh
        Closed, outward-wound surface, metres.
    convex : bool
        True: MuJoCo collides it as one hull, exactly its mesh.
    parameters : Mapping[str, Any]
        The closed-form parameters in metres (``radius_m``, ``semi_axes_m``,
        ``length_m``, ``height_m``, ``spline_coefficients_m`` ...).
    description : str
        What the solid is and where the thesis uses it.
    """

    name: str
    mesh: trimesh.Trimesh
    convex: bool
    parameters: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""


def solid_names() -> tuple[str, ...]:
    """Returns the names of the closed-form solids."""
    return SOLID_NAMES


def load_solid(name: str) -> Solid:
    """Returns a closed-form solid by name (see :func:`solid_names`).

    Raises
    ------
    UnknownObject
        ``name`` is not a solid's name; the message lists the known names.
    """
    if name == "cylinder_1" or name == "cylinder_2":
        diameter = 0.0504 if name == "cylinder_1" else 0.094
        radius = diameter / 2.0
        vertices, faces = _lying_prism(ellipse_outline(radius, radius), CYLINDER_LENGTH_M)
        parameters = {"radius_m": radius, "length_m": CYLINDER_LENGTH_M}
        description = f"circular cylinder, diameter {diameter * 1e3:.1f} mm (thesis Fig. 4.15)"
    elif name == "elliptic_cylinder":
        semi_axes = (0.0508, 0.03175)
        vertices, faces = _lying_prism(ellipse_outline(*semi_axes), CYLINDER_LENGTH_M)
        parameters = {"semi_axes_m": semi_axes, "length_m": CYLINDER_LENGTH_M}
        description = "elliptic cylinder, semi-axes 50.8 x 31.75 mm (thesis Fig. 4.15)"
    elif name == "sphere":
        radius = 0.033
        vertices, faces = sphere_mesh(radius)
        vertices = vertices + np.array([0.0, 0.0, radius])
        parameters = {"radius_m": radius}
        description = "sphere, radius 33 mm (thesis Fig. 4.15)"
    elif name == "planar_ellipse":
        semi_axes = (0.025, 0.0175)
        vertices, faces = extrude_outline(ellipse_outline(*semi_axes), PRISM_HEIGHT_M)
        parameters = {"semi_axes_m": semi_axes, "height_m": PRISM_HEIGHT_M}
        description = "extruded ellipse a = 25 mm, b = 17.5 mm (thesis Section 3.4.2, Table 3.4)"
    elif name == "planar_spline":
        coefficients = closed_spline_coefficients()
        vertices, faces = extrude_outline(closed_spline_outline(), PRISM_HEIGHT_M)
        parameters = {
            "knots_m": DEFAULT_SPLINE_KNOTS_M,
            "spline_coefficients_m": coefficients,
            "height_m": PRISM_HEIGHT_M,
        }
        description = "extruded closed cubic spline of five segments (thesis Section 3.4.2)"
    else:
        raise UnknownObject(name, SOLID_NAMES)
    # Model frame: bounding box centred on the z axis, lowest point on z = 0.
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    shift = np.array([-(low[0] + high[0]) / 2.0, -(low[1] + high[1]) / 2.0, -low[2]])
    vertices = vertices + shift
    if "spline_coefficients_m" in parameters:
        parameters["spline_coefficients_m"][:, :, 3] += shift[:2]
        parameters["knots_m"] = tuple(
            tuple(float(c) for c in knot + shift[:2]) for knot in np.array(parameters["knots_m"])
        )
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
    convex = is_convex(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    return Solid(
        name=name,
        mesh=mesh,
        convex=convex,
        parameters=MappingProxyType(parameters),
        description=description,
    )


def sphere_mesh(
    radius_m: float, subdivisions: int = 5
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns an icosphere centred at the origin, vertices on the sphere.

    5 subdivisions: 10242 vertices, faces within 9.4 um of the sphere at r = 33 mm (6: 40962
    vertices, 2.4 um, but MuJoCo then takes seconds to compile the hull).
    """
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius_m)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def _lying_prism(
    outline_yz: NDArray[np.float64], length_m: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The prism over an outline in the (y, z) plane, extruded along x and centred on x = 0,
    lowest point on z = 0."""
    vertices, faces = extrude_outline(outline_yz, length_m)
    # (u, v, w) = (y, z, x): a cyclic permutation keeps the winding.
    lying = np.column_stack([vertices[:, 2] - length_m / 2.0, vertices[:, 0], vertices[:, 1]])
    lying[:, 2] -= lying[:, 2].min()
    return lying, faces
