"""Normal and principal curvatures from three data curves, thesis Section 4.1.1.

Noise-free curves are traced on spheres, cylinders and an ellipsoid
(:func:`recognition.synthetic.implicit_data_curves`, random data frame); the estimates
are compared with the exact curvatures. The tolerances are the truncation error of the
degree-4 fits over a window turning by about 0.15 rad (observed errors are 3-10 times
smaller).
"""

import numpy as np
import pytest

from recognition.errors import DegenerateGeometry
from recognition.rigid import random_rigid_motion
from recognition.surfaces import closed_form as cf
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import (
    local_surface_geometry,
    normal_curvature,
    principal_curvatures_from_normal_curvatures,
    principal_curvatures_thesis,
    surface_normal,
)
from recognition.surfaces.registration.config import DataGeometryConfig
from recognition.surfaces.registration.data import data_geometry
from recognition.synthetic import implicit_data_curves


def angle_deg(a, b):
    return float(
        np.degrees(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))
    )


def normal_in_model(synthetic, geometry):
    return synthetic.T_model_from_data[:3, :3] @ geometry.normal


@pytest.mark.parametrize("radius", [0.01, 0.033, 0.1])
def test_sphere(radius):
    s = cf.sphere(radius)
    rng = np.random.default_rng(1)
    synthetic = implicit_data_curves(
        s, s.sigma(0.7, 1.1), n_points=41, spacing=radius / 80, rng=rng
    )
    g = local_surface_geometry(synthetic.curves, half_length_m=0.15 * radius)
    assert g.k1 == pytest.approx(1 / radius, rel=2e-4)
    assert g.k2 == pytest.approx(1 / radius, rel=2e-4)
    assert g.oriented
    assert angle_deg(normal_in_model(synthetic, g), synthetic.normal_in_model) < 1e-4
    np.testing.assert_allclose(
        synthetic.T_model_from_data[:3, :3] @ g.point + synthetic.T_model_from_data[:3, 3],
        synthetic.point_in_model,
        atol=1e-9,
    )


@pytest.mark.parametrize("radius", [0.0252, 0.047])
def test_cylinder(radius):
    s = cf.circular_cylinder(radius, 0.05)
    rng = np.random.default_rng(2)
    synthetic = implicit_data_curves(
        s, s.sigma(0.7, 0.0), n_points=41, spacing=radius / 80, rng=rng
    )
    g = local_surface_geometry(synthetic.curves, half_length_m=0.15 * radius)
    assert g.k1 == pytest.approx(1 / radius, rel=2e-4)
    assert abs(g.k2) < 2e-4 / radius
    assert angle_deg(normal_in_model(synthetic, g), synthetic.normal_in_model) < 1e-4
    axis = synthetic.T_model_from_data[:3, :3] @ g.d2  # zero curvature along the axis
    assert abs(axis[2]) == pytest.approx(1.0, abs=1e-6)


def test_a_straight_data_curve_along_a_cylinder_axis_is_valid():
    """A sampling plane through the axis cuts a straight line: its normal curvature is 0."""
    s = cf.circular_cylinder(0.0252, 0.05)
    p = s.sigma(0.0, 0.0)  # (r, 0, 0), normal +x
    planes = np.array([[0.0, 1.0, 0.0], [0.0, 0.5, -np.sqrt(0.75)], [0.0, 0.5, np.sqrt(0.75)]])
    synthetic = implicit_data_curves(
        s, p, n_points=41, spacing=0.3e-3, plane_normals=planes, rng=np.random.default_rng(3)
    )
    straight = synthetic.clean_curves_in_model[0]
    assert np.ptp(straight[:, 0]) < 1e-12 and np.ptp(straight[:, 1]) < 1e-12
    g = local_surface_geometry(synthetic.curves, half_length_m=6e-3)
    assert abs(g.normal_curvatures[0]) < 1e-6
    assert g.k1 == pytest.approx(1 / 0.0252, rel=2e-4)
    assert abs(g.k2) < 1e-2


@pytest.mark.parametrize("uv", [(1.02, 0.69), (0.3, 1.5), (4.0, 2.5), (2.2, 0.35)])
def test_ellipsoid_matches_the_fundamental_forms(uv):
    s = cf.ellipsoid(1.0, 0.8, 0.5)
    synthetic = implicit_data_curves(
        s, s.sigma(*uv), n_points=41, spacing=0.005, rng=np.random.default_rng(4)
    )
    g = local_surface_geometry(synthetic.curves, half_length_m=0.1)
    k1, k2 = s.principal_curvatures(*uv)
    assert g.k1 == pytest.approx(k1, rel=5e-4)
    assert g.k2 == pytest.approx(k2, rel=5e-4)
    assert angle_deg(normal_in_model(synthetic, g), synthetic.normal_in_model) < 0.01


def test_estimates_are_invariant_under_a_rigid_motion_of_the_data():
    s = cf.ellipsoid()
    rng = np.random.default_rng(5)
    synthetic = implicit_data_curves(s, s.sigma(1.02, 0.69), spacing=0.005, rng=rng)
    T = random_rigid_motion(rng, 1.0)
    a = local_surface_geometry(synthetic.curves, half_length_m=0.1)
    b = local_surface_geometry(synthetic.curves.transformed(T), half_length_m=0.1)
    assert (b.k1, b.k2) == pytest.approx((a.k1, a.k2), rel=1e-9)
    np.testing.assert_allclose(b.normal, T[:3, :3] @ a.normal, atol=1e-10)
    np.testing.assert_allclose(b.point, T[:3, :3] @ a.point + T[:3, 3], atol=1e-10)
    np.testing.assert_allclose(b.frame, T[:3, :3] @ a.frame, atol=1e-8)


def test_four_curves_give_the_least_squares_estimate():
    s = cf.ellipsoid()
    n = s.normal(1.02, 0.69)
    t = np.cross(n, [0.0, 0.0, 1.0])
    t /= np.linalg.norm(t)
    b = np.cross(n, t)
    angles = np.deg2rad([0.0, 45.0, 90.0, 135.0])
    planes = np.cross(np.cos(angles)[:, None] * t + np.sin(angles)[:, None] * b, n)
    synthetic = implicit_data_curves(
        s, s.sigma(1.02, 0.69), spacing=0.005, plane_normals=planes, rng=np.random.default_rng(6)
    )
    assert len(synthetic.curves.curves) == 4
    g = local_surface_geometry(synthetic.curves, half_length_m=0.1)
    assert (g.k1, g.k2) == pytest.approx(s.principal_curvatures(1.02, 0.69), rel=5e-4)


def test_flipped_geometry():
    s = cf.sphere(1.0)
    synthetic = implicit_data_curves(
        s, s.sigma(1.0, 1.0), spacing=0.005, rng=np.random.default_rng(7)
    )
    g = local_surface_geometry(synthetic.curves, half_length_m=0.1)
    f = g.flipped()
    assert (f.k1, f.k2) == (-g.k2, -g.k1)
    np.testing.assert_array_equal(f.normal, -g.normal)
    np.testing.assert_allclose(np.cross(f.d1, f.d2), f.normal, atol=1e-12)
    np.testing.assert_allclose(f.frame @ f.frame.T, np.eye(3), atol=1e-12)


def test_unoriented_data_take_the_convex_side():
    s = cf.sphere(1.0)
    synthetic = implicit_data_curves(
        s, s.sigma(1.0, 1.0), spacing=0.005, rng=np.random.default_rng(8)
    )
    unoriented = DataCurves(synthetic.curves.curves)
    g = local_surface_geometry(unoriented, half_length_m=0.1)
    assert not g.oriented
    assert g.k1 == pytest.approx(1.0, rel=1e-4) and g.k2 == pytest.approx(1.0, rel=1e-4)
    assert normal_in_model(synthetic, g) @ synthetic.normal_in_model > 0.999


# --- the formulas on exact normal curvatures ---------------------------------------------


def euler(k1, k2, theta, angles):
    """Normal curvatures at tangent angles ``angles`` (Euler's theorem (4.2)-(4.4))."""
    return k1 * np.cos(angles - theta) ** 2 + k2 * np.sin(angles - theta) ** 2


@pytest.mark.parametrize("seed", range(5))
def test_thesis_closed_form_and_least_squares_recover_exact_principal_curvatures(seed):
    rng = np.random.default_rng(seed)
    k1, k2 = sorted(rng.uniform(-3, 3, 2), reverse=True)
    theta = rng.uniform(0, np.pi)
    angles = np.array([0.0, *np.sort(rng.uniform(0.3, 2.8, 2))])
    kn = euler(k1, k2, theta, angles)
    a, b, t = principal_curvatures_thesis(kn[0], kn[1], kn[2], angles[1], angles[2])
    assert sorted([a, b], reverse=True) == pytest.approx([k1, k2], rel=1e-9, abs=1e-9)
    # the thesis's theta is the angle from the k1 direction to T_alpha
    np.testing.assert_allclose(euler(a, b, -t, angles), kn, atol=1e-9)
    ls1, ls2, angle1, condition = principal_curvatures_from_normal_curvatures(kn, angles)
    assert (ls1, ls2) == pytest.approx((k1, k2), rel=1e-9, abs=1e-9)
    assert np.cos(angle1 - theta) ** 2 == pytest.approx(1.0, abs=1e-6)
    assert condition < 1e3
    more = np.linspace(0, np.pi, 7, endpoint=False) + 0.1
    ls = principal_curvatures_from_normal_curvatures(euler(k1, k2, theta, more), more)
    assert ls[:2] == pytest.approx((k1, k2), rel=1e-9, abs=1e-9)


def test_surface_normal_is_orthogonal_to_the_tangents():
    rng = np.random.default_rng(9)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    tangents = rng.normal(size=(3, 3))
    tangents -= np.outer(tangents @ n, n)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    assert abs(surface_normal(tangents) @ n) == pytest.approx(1.0, abs=1e-12)


def test_normal_curvature_is_positive_on_a_convex_surface_seen_from_outside():
    s = cf.sphere(0.5)
    synthetic = implicit_data_curves(
        s, s.sigma(1.0, 1.0), spacing=0.005, rng=np.random.default_rng(10)
    )
    g = local_surface_geometry(synthetic.curves, half_length_m=0.075)
    for frame in g.frames:
        assert normal_curvature(frame, g.normal) == pytest.approx(2.0, rel=1e-4)
        assert normal_curvature(frame, -g.normal) == pytest.approx(-2.0, rel=1e-4)


def test_too_few_points_for_the_fit_is_degenerate():
    t = np.linspace(-1, 1, 5)[:, None]
    curves = tuple(np.hstack([t * np.cos(a), t * np.sin(a), -0.5 * t**2]) for a in (0.0, 1.0, 2.0))
    with pytest.raises(DegenerateGeometry, match="5 points near p; the fit needs 6"):
        local_surface_geometry(DataCurves(curves), half_length_m=2.0, degree=4)
    g = local_surface_geometry(DataCurves(curves), half_length_m=2.0, degree=2)
    assert (g.k1, g.k2) == pytest.approx((1.0, 1.0), rel=1e-9)


def test_measured_normals_inform_and_orient_the_normal_at_p():
    """Tangents at p only 10 degrees apart leave the normal poorly determined by noisy
    curves alone (1.4 degrees RMS); the sensor's normals (each about 0.8 degree off, as
    the simulated sensor's) pin it, and orient it outward without an approach
    direction."""
    s = cf.sphere(0.03)
    alone, sensed = [], []
    for seed in range(10):
        rng = np.random.default_rng(seed)
        synthetic = implicit_data_curves(
            s,
            s.sigma(0.7, 1.1),
            n_points=41,
            spacing=0.3e-3,
            plane_angle_deg=10.0,
            noise_std=0.02e-3,
            rng=rng,
        )
        curves = synthetic.curves.curves
        true_normal = synthetic.T_model_from_data[:3, :3].T @ synthetic.normal_in_model
        normals = tuple(true_normal + rng.normal(scale=0.01, size=(len(c), 3)) for c in curves)
        g = local_surface_geometry(DataCurves(curves, normals=normals), half_length_m=3e-3)
        assert g.oriented and g.normal @ true_normal > 0
        sensed.append(angle_deg(g.normal, true_normal))
        g = local_surface_geometry(DataCurves(curves), half_length_m=3e-3)
        alone.append(angle_deg(g.normal, true_normal))
    assert max(sensed) < 1.5
    assert np.sqrt(np.mean(np.square(sensed))) < 0.5 * np.sqrt(np.mean(np.square(alone)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_normal_can_come_from_a_shorter_arc_where_the_data_curve_tightly(seed):
    # an ellipsoid's rim, radius of curvature down to 6 mm along the curves, sampled as the
    # thesis's real data (21 points 1.2 mm apart): the whole arc's fits tilt the normal
    s = cf.ellipsoid(0.03, 0.02, 0.005)
    synthetic = implicit_data_curves(
        s, s.sigma(0.3, 1.2), n_points=21, spacing=1.2e-3, rng=np.random.default_rng(seed)
    )
    whole = data_geometry(synthetic.curves, DataGeometryConfig())
    short = data_geometry(synthetic.curves, DataGeometryConfig(normal_max_turn=0.4))
    exact = synthetic.normal_in_model
    assert angle_deg(normal_in_model(synthetic, whole), exact) > 4.0
    assert angle_deg(normal_in_model(synthetic, short), exact) < 0.5
    # the curvatures still come from the whole arc (the models' maps' scale)
    assert short.k1 == pytest.approx(whole.k1, rel=0.01)
    assert short.k2 == pytest.approx(whole.k2, rel=0.05)
