"""The closed-form surfaces of the thesis: Table 4.1's families and the solids of Fig. 4.15."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from recognition.errors import InvalidModel
from recognition.surfaces.closed_form.surface import (
    ClosedFormSurface,
    ImplicitTerms,
    SigmaDerivatives,
    stack_columns,
)

__all__ = [
    "circular_cylinder",
    "crossed_trough",
    "ellipsoid",
    "elliptic_cylinder",
    "elliptic_paraboloid",
    "fig_4_15_solids",
    "monkey_saddle",
    "sphere",
    "table_4_1_surfaces",
]

Array = NDArray[np.float64]
Height = Callable[[Array, Array], tuple[Array, ...]]


def _positive(name: str, **values: float) -> dict[str, float]:
    for key, value in values.items():
        if not (np.isfinite(value) and value > 0):
            raise InvalidModel(f"{name}: parameter {key} must be finite and > 0, got {value}")
    return {k: float(v) for k, v in values.items()}


def _rotations_about(axis: int, count: int) -> tuple[Array, ...]:
    """The ``count - 1`` non-trivial rotations by multiples of 2 pi / count about an axis."""
    return tuple(
        Rotation.from_rotvec(2 * np.pi * k / count * np.eye(3)[axis]).as_matrix()
        for k in range(1, count)
    )


def _quadric_terms(
    scales: Array, offset: float, linear_z: float = 0.0
) -> Callable[[Array, int], ImplicitTerms]:
    """f = sum_i s_i x_i^2 - offset - linear_z z, with its gradient and Hessian."""

    hessian = np.diag(2.0 * scales)

    def terms(points: Array, order: int = 2) -> ImplicitTerms:
        f = (points * points) @ scales - offset
        if linear_z:
            f -= linear_z * points[:, 2]
        if order < 1:
            return f, None, None
        g = 2.0 * points * scales
        g[:, 2] -= linear_z
        if order < 2:
            return f, g, None
        return f, g, np.broadcast_to(hessian, (points.shape[0], 3, 3))

    return terms


def ellipsoid(
    a: float = 1.0, b: float = 0.8, c: float = 0.5, name: str = "ellipsoid"
) -> ClosedFormSurface:
    """x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 (thesis Table 4.1).

    sigma = (a cos u sin v, b sin u sin v, c cos v), (u, v) in [0, 2 pi] x [0, pi].
    """
    p = _positive(name, a=a, b=b, c=c)
    a, b, c = p["a"], p["b"], p["c"]

    def sigma_terms(u: Array, v: Array) -> SigmaDerivatives:
        cu, su_, cv, sv_ = np.cos(u), np.sin(u), np.cos(v), np.sin(v)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            stack_columns(a * cu * sv_, b * su_ * sv_, c * cv + z),
            stack_columns(-a * su_ * sv_, b * cu * sv_, z),
            stack_columns(a * cu * cv, b * su_ * cv, -c * sv_ + z),
            stack_columns(-a * cu * sv_, -b * su_ * sv_, z),
            stack_columns(-a * su_ * cv, b * cu * cv, z),
            stack_columns(-a * cu * sv_, -b * su_ * sv_, -c * cv + z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (0.0, np.pi)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 1 / c**2]), 1.0),
        symmetries=tuple(np.diag(d) for d in ((1, -1, -1), (-1, 1, -1), (-1, -1, 1))),
    )


def sphere(radius: float, name: str = "sphere") -> ClosedFormSurface:
    """Sphere of radius ``radius`` about the origin (an ellipsoid with a = b = c)."""
    _positive(name, radius=radius)
    s = ellipsoid(radius, radius, radius, name)
    return replace(s, parameters=MappingProxyType({"radius": float(radius)}), symmetries=())


def elliptic_paraboloid(
    a: float = 1.5, b: float = 1.1, name: str = "elliptic_paraboloid"
) -> ClosedFormSurface:
    """x^2/a^2 + y^2/b^2 = z (thesis Table 4.1); f = x^2/a^2 + y^2/b^2 - z.

    sigma = (a v cos u, b v sin u, v^2), (u, v) in [0, 2 pi] x [-1, 1] (every point is
    covered twice: (u, v) and (u + pi, -v)).
    """
    p = _positive(name, a=a, b=b)
    a, b = p["a"], p["b"]

    def sigma_terms(u: Array, v: Array) -> SigmaDerivatives:
        cu, su_ = np.cos(u), np.sin(u)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            stack_columns(a * v * cu, b * v * su_, v**2 + z),
            stack_columns(-a * v * su_, b * v * cu, z),
            stack_columns(a * cu + 0 * v, b * su_ + 0 * v, 2 * v + z),
            stack_columns(-a * v * cu, -b * v * su_, z),
            stack_columns(-a * su_ + 0 * v, b * cu + 0 * v, z),
            stack_columns(z, z, 2.0 + z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (-1.0, 1.0)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 0.0]), 0.0, linear_z=1.0),
        symmetries=_rotations_about(2, 2),
    )


def _graph_surface(name: str, height: Height, rotations: int) -> ClosedFormSurface:
    """The graph z = h(x, y) over [-1, 1]^2: sigma = (u, v, h(u, v)), f = h(x, y) - z.

    ``height(x, y)`` returns h and its partial derivatives (h, h_x, h_y, h_xx, h_xy,
    h_yy); the surface is symmetric under ``rotations`` turns about the z axis.
    """

    def sigma_terms(u: Array, v: Array) -> SigmaDerivatives:
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        one = 1.0 + z
        h, hu, hv, huu, huv, hvv = height(u, v)
        return SigmaDerivatives(
            stack_columns(u + z, v + z, h + z),
            stack_columns(one, z, hu + z),
            stack_columns(z, one, hv + z),
            stack_columns(z, z, huu + z),
            stack_columns(z, z, huv + z),
            stack_columns(z, z, hvv + z),
        )

    def implicit_terms(points: Array, order: int = 2) -> ImplicitTerms:
        x, y, zc = points.T
        h, hx, hy, hxx, hxy, hyy = height(x, y)
        f = h - zc
        if order < 1:
            return f, None, None
        g = np.empty_like(points)
        g[:, 0], g[:, 1], g[:, 2] = hx, hy, -1.0
        if order < 2:
            return f, g, None
        H = np.zeros((points.shape[0], 3, 3))
        H[:, 0, 0], H[:, 1, 1] = hxx, hyy
        H[:, 0, 1] = H[:, 1, 0] = hxy
        return f, g, H

    return ClosedFormSurface(
        name,
        MappingProxyType({}),
        ((-1.0, 1.0), (-1.0, 1.0)),
        (False, False),
        sigma_terms,
        implicit_terms,
        symmetries=_rotations_about(2, rotations),
    )


def monkey_saddle(name: str = "monkey_saddle") -> ClosedFormSurface:
    """x^3 - 3 x y^2 = z (thesis Table 4.1); f = x^3 - 3 x y^2 - z.

    sigma = (u, v, u^3 - 3 u v^2), (u, v) in [-1, 1] x [-1, 1].
    """

    def height(x: Array, y: Array) -> tuple[Array, ...]:
        return x**3 - 3 * x * y**2, 3 * x**2 - 3 * y**2, -6 * x * y, 6 * x, -6 * y, -6 * x

    return _graph_surface(name, height, rotations=3)


def crossed_trough(name: str = "crossed_trough") -> ClosedFormSurface:
    """x^2 y^2 = z (thesis Table 4.1); f = x^2 y^2 - z.

    sigma = (u, v, u^2 v^2), (u, v) in [-1, 1] x [-1, 1].
    """

    def height(x: Array, y: Array) -> tuple[Array, ...]:
        return x**2 * y**2, 2 * x * y**2, 2 * x**2 * y, 2 * y**2, 4 * x * y, 2 * x**2

    return _graph_surface(name, height, rotations=4)


def elliptic_cylinder(
    a: float, b: float, half_length: float, name: str = "elliptic_cylinder"
) -> ClosedFormSurface:
    """x^2/a^2 + y^2/b^2 = 1 about the z axis; sigma = (a cos u, b sin u, v).

    The implicit form is the infinite cylinder; the table covers |v| <= ``half_length``.
    Registration ignores the end faces: the model is the lateral surface only.
    """
    p = _positive(name, a=a, b=b, half_length=half_length)
    a, b = p["a"], p["b"]

    def sigma_terms(u: Array, v: Array) -> SigmaDerivatives:
        cu, su_ = np.cos(u), np.sin(u)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            stack_columns(a * cu + z, b * su_ + z, v + z),
            stack_columns(-a * su_ + z, b * cu + z, z),
            stack_columns(z, z, 1.0 + z),
            stack_columns(-a * cu + z, -b * su_ + z, z),
            stack_columns(z, z, z),
            stack_columns(z, z, z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (-half_length, half_length)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 0.0]), 1.0),
        note="infinite cylinder in implicit form (no end faces); table over |z| <= half_length",
        symmetries=tuple(np.diag(d) for d in ((1, -1, -1), (-1, 1, -1), (-1, -1, 1))),
    )


def circular_cylinder(
    radius: float, half_length: float, name: str = "cylinder"
) -> ClosedFormSurface:
    """Circular cylinder of radius ``radius`` about the z axis (see :func:`elliptic_cylinder`)."""
    s = elliptic_cylinder(radius, radius, half_length, name)
    return replace(
        s,
        parameters=MappingProxyType({"radius": float(radius), "half_length": float(half_length)}),
    )


def table_4_1_surfaces() -> tuple[ClosedFormSurface, ...]:
    """The four surfaces of thesis Table 4.1 / Figs. 4.5-4.6 with the thesis's parameters."""
    return (
        ellipsoid(1.0, 0.8, 0.5),
        elliptic_paraboloid(1.5, 1.1),
        monkey_saddle(),
        crossed_trough(),
    )


def fig_4_15_solids(half_length_m: float = 0.05) -> tuple[ClosedFormSurface, ...]:
    """The four algebraic objects of thesis Fig. 4.15, in metres.

    Two circular cylinders of diameter 50.4 mm and 94 mm, an elliptic cylinder of
    semi-axes 50.8 mm x 31.75 mm, a sphere of radius 33 mm. Cylinders are infinite in
    implicit form and tabulated over |z| <= ``half_length_m``.
    """
    return (
        circular_cylinder(0.0252, half_length_m, "cylinder_1"),
        circular_cylinder(0.047, half_length_m, "cylinder_2"),
        elliptic_cylinder(0.0508, 0.03175, half_length_m, "elliptic_cylinder"),
        sphere(0.033, "sphere"),
    )
