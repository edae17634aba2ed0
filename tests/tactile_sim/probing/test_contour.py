"""Outline traces in a horizontal plane (thesis Section 3.4.2)."""

from __future__ import annotations

import numpy as np

from recognition.rigid import pose_matrix
from tactile_sim.collision import load_solid
from tactile_sim.probing import trace_contour
from tactile_sim.probing.placement import MOUNT_IN_WORLD

AT_MOUNT = pose_matrix(np.eye(3), MOUNT_IN_WORLD)
"""T_world_from_object: upright on the object mount, axes parallel to the world's."""


def test_outline_of_the_planar_ellipse() -> None:
    trace = trace_contour(
        "planar_ellipse", seed=0, n_points=12, start_angle_rad=0.4, T_world_from_object=AT_MOUNT
    )
    points = trace.points_in_object
    assert len(points) == 12 and not trace.sweep.truncated
    # On the ellipse x^2/a^2 + y^2/b^2 = 1 (a = 25 mm, b = 17.5 mm), in the plane.
    a, b = load_solid("planar_ellipse").parameters["semi_axes_m"]
    level = (points[:, 0] / a) ** 2 + (points[:, 1] / b) ** 2
    # The level-set value changes by about 2 d / b per distance d off the curve.
    np.testing.assert_allclose(level, 1.0, atol=2 * 20e-6 / b)
    # Heights scatter along the wall with the axial force noise (it tilts the sensed
    # normal, which moves the point along the surface, not off it).
    np.testing.assert_allclose(points[:, 2], points[0, 2], atol=0.4e-3)
    # Counter-clockwise seen from above.
    angles = np.unwrap(np.arctan2(points[:, 1] / b, points[:, 0] / a))
    assert np.all(np.diff(angles) > 0)
