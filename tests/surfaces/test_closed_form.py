"""Closed-form surfaces (thesis Section 4.2): forms, derivatives, curvatures, lookup table.

Every analytic derivative (sigma's, f's gradient and Hessian, the model frame, the
residuals of (4.11) and of the rigid motion, E's gradient) is compared with central
differences; curvatures with the exact values of spheres, cylinders and ellipsoids.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from recognition.errors import InvalidModel
from recognition.surfaces import closed_form as cf
from recognition.surfaces.closed_form.superposition import _phi_terms
from recognition.surfaces.local_geometry import LocalSurfaceGeometry

SURFACES = cf.table_4_1_surfaces() + cf.fig_4_15_solids()
IDS = [s.name for s in SURFACES]


def interior_parameters(surface, rng, n, margin=0.1):
    """n random (u, v) inside the domain, ``margin`` of each interval away from its ends."""
    (u0, u1), (v0, v1) = surface.domain
    u = rng.uniform(u0 + margin * (u1 - u0), u1 - margin * (u1 - u0), n)
    v = rng.uniform(v0 + margin * (v1 - v0), v1 - margin * (v1 - v0), n)
    return u, v


def points_near(surface, rng, n, spread):
    """n random points of the surface's interior moved off it by noise of ``spread``
    times its scale (same draws as sigma(interior_parameters) plus normal noise)."""
    return surface.sigma(*interior_parameters(surface, rng, n)) + rng.normal(
        scale=spread * scale(surface), size=(n, 3)
    )


def scale(surface):
    """Characteristic length of a surface (1 for Table 4.1, tens of mm for Fig. 4.15)."""
    return float(np.linalg.norm(surface.sigma(*[np.mean(d) for d in surface.domain]))) or 1.0


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_sigma_derivatives_match_finite_differences(surface):
    rng = np.random.default_rng(1)
    h = 1e-5
    for u, v in zip(*interior_parameters(surface, rng, 5), strict=True):
        d = surface.sigma_derivatives(u, v)
        dp = surface.sigma_derivatives
        su = (dp(u + h, v).point - dp(u - h, v).point) / (2 * h)
        sv = (dp(u, v + h).point - dp(u, v - h).point) / (2 * h)
        suu = (dp(u + h, v).su - dp(u - h, v).su) / (2 * h)
        suv = (dp(u, v + h).su - dp(u, v - h).su) / (2 * h)
        svv = (dp(u, v + h).sv - dp(u, v - h).sv) / (2 * h)
        for exact, numeric in ((d.su, su), (d.sv, sv), (d.suu, suu), (d.suv, suv), (d.svv, svv)):
            np.testing.assert_allclose(exact, numeric, atol=1e-8)
        np.testing.assert_allclose(d.suv, (dp(u + h, v).sv - dp(u - h, v).sv) / (2 * h), atol=1e-8)


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_implicit_gradient_and_hessian_match_finite_differences(surface):
    rng = np.random.default_rng(2)
    L = scale(surface)
    points = points_near(surface, rng, 6, 0.1)
    h = 1e-6 * L
    g = surface.gradient(points)
    H = surface.hessian(points)
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        g_num = (surface.implicit(points + e) - surface.implicit(points - e)) / (2 * h)
        H_num = (surface.gradient(points + e) - surface.gradient(points - e)) / (2 * h)
        np.testing.assert_allclose(g[:, k], g_num, rtol=1e-6, atol=1e-6 * np.abs(g).max())
        np.testing.assert_allclose(H[:, :, k], H_num, rtol=1e-6, atol=1e-6 * np.abs(H).max())
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2))


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_sigma_lies_on_the_implicit_surface_and_the_normal_points_outward(surface):
    rng = np.random.default_rng(3)
    u, v = interior_parameters(surface, rng, 20)
    p = surface.sigma(u, v)
    g = surface.gradient(p)
    np.testing.assert_allclose(surface.implicit(p) / np.linalg.norm(g, axis=1), 0, atol=1e-12)
    n = surface.normal(u, v)
    np.testing.assert_allclose(n, g / np.linalg.norm(g, axis=1)[:, None], atol=1e-12)
    d = surface.sigma_derivatives(u, v)
    np.testing.assert_allclose(np.sum(n * d.su, axis=1), 0, atol=1e-12)
    np.testing.assert_allclose(np.sum(n * d.sv, axis=1), 0, atol=1e-12)
    eps = 1e-4 * scale(surface)
    assert np.all(surface.implicit(p + eps * n) > 0)
    assert np.all(surface.implicit(p - eps * n) < 0)


def test_closed_solids_have_their_centre_inside():
    for s in (cf.ellipsoid(), *cf.fig_4_15_solids()):
        assert s.implicit(np.zeros((1, 3)))[0] < 0


@pytest.mark.parametrize("radius", [0.01, 0.033, 1.0, 7.5])
def test_sphere_curvatures_from_fundamental_forms(radius):
    s = cf.sphere(radius)
    u, v = interior_parameters(s, np.random.default_rng(4), 50)
    k1, k2 = s.principal_curvatures(u, v)
    np.testing.assert_allclose(k1, 1 / radius, rtol=1e-7)
    np.testing.assert_allclose(k2, 1 / radius, rtol=1e-7)


@pytest.mark.parametrize("radius", [0.0252, 0.047, 2.0])
def test_cylinder_curvatures_from_fundamental_forms(radius):
    s = cf.circular_cylinder(radius, 0.05)
    u, v = interior_parameters(s, np.random.default_rng(5), 50)
    k1, k2 = s.principal_curvatures(u, v)
    np.testing.assert_allclose(k1, 1 / radius, rtol=1e-12)
    np.testing.assert_allclose(k2, 0, atol=1e-12 / radius)


def ellipsoid_curvatures(a, b, c, p):
    """Exact Gaussian and mean curvature of an ellipsoid at surface points p (outward
    normal, convex positive): K = 1 / (abc h^2)^2, H = (a^2 + b^2 + c^2 - |p|^2) /
    (2 (abc)^2 h^3) with h^2 = x^2/a^4 + y^2/b^4 + z^2/c^4."""
    x, y, z = p.T
    h = np.sqrt(x**2 / a**4 + y**2 / b**4 + z**2 / c**4)
    K = 1 / (a * b * c * h**2) ** 2
    H = (a * a + b * b + c * c - np.sum(p * p, axis=1)) / (2 * (a * b * c) ** 2 * h**3)
    return K, H


def test_ellipsoid_curvatures_from_fundamental_forms_match_the_closed_form():
    a, b, c = 1.0, 0.8, 0.5
    s = cf.ellipsoid(a, b, c)
    u, v = interior_parameters(s, np.random.default_rng(6), 200, margin=0.02)
    k1, k2 = s.principal_curvatures(u, v)
    K, H = ellipsoid_curvatures(a, b, c, s.sigma(u, v))
    np.testing.assert_allclose(k1 * k2, K, rtol=1e-10)
    np.testing.assert_allclose((k1 + k2) / 2, H, rtol=1e-10)
    assert np.all(k1 >= k2)
    # at the ends of the axes: k = a/b^2 ... exactly
    k1, k2 = s.principal_curvatures(0.0, np.pi / 2)  # (a, 0, 0)
    np.testing.assert_allclose([k1, k2], sorted([a / b**2, a / c**2], reverse=True))


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_fundamental_forms_agree_with_the_implicit_shape_operator(surface):
    u, v = interior_parameters(surface, np.random.default_rng(7), 40)
    k1, k2 = surface.principal_curvatures(u, v)
    j1, j2 = cf.implicit_principal_curvatures(surface, surface.sigma(u, v))
    tol = 1e-6 * max(np.abs(k1).max(), 1.0)  # sqrt of rounding at umbilics (sphere)
    np.testing.assert_allclose(k1, j1, atol=tol)
    np.testing.assert_allclose(k2, j2, atol=tol)


def test_curvatures_at_special_points():
    # paraboloid apex: 2/b^2 and 2/a^2 (implicit form: the apex is singular in sigma)
    k1, k2 = cf.implicit_principal_curvatures(cf.elliptic_paraboloid(1.5, 1.1), np.zeros((1, 3)))
    np.testing.assert_allclose([k1[0], k2[0]], [2 / 1.1**2, 2 / 1.5**2], rtol=1e-12)
    # monkey saddle: flat umbilic at the origin; crossed trough: saddle off the axes
    k1, k2 = cf.monkey_saddle().principal_curvatures(0.0, 0.0)
    np.testing.assert_allclose([k1, k2], 0, atol=1e-15)
    k1, k2 = cf.crossed_trough().principal_curvatures(0.5, 0.5)
    assert k1 > 0 > k2


@pytest.mark.parametrize("surface", [s for s in SURFACES if s.symmetries], ids=lambda s: s.name)
def test_symmetries_map_the_solid_onto_itself(surface):
    rng = np.random.default_rng(8)
    p = surface.sigma(*interior_parameters(surface, rng, 10))
    g = surface.gradient(p)
    for S in surface.symmetries:
        np.testing.assert_allclose(S @ S.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(S) == pytest.approx(1.0)
        q = p @ S.T
        gq = surface.gradient(q)
        assert np.abs(surface.implicit(q)).max() < 1e-12 * scale(surface)
        np.testing.assert_allclose(
            gq / np.linalg.norm(gq, axis=1)[:, None],
            (g @ S.T) / np.linalg.norm(g, axis=1)[:, None],
            atol=1e-12,
        )


def test_invalid_parameters_raise_invalid_model():
    with pytest.raises(InvalidModel, match="parameter b"):
        cf.ellipsoid(1.0, -0.8, 0.5)
    with pytest.raises(InvalidModel, match="radius"):
        cf.sphere(float("nan"))
    with pytest.raises(InvalidModel, match="2 x 2 grid"):
        cf.ClosedFormModel.build(cf.sphere(1.0), 1, 10)


# --- frames and the superposition error ---------------------------------------------------


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_model_frame_is_a_rotation_with_the_normal_last_and_exact_derivatives(surface):
    rng = np.random.default_rng(9)
    h = 1e-6
    for u, v in zip(*interior_parameters(surface, rng, 4), strict=True):
        q, F, F_u, F_v, s_u, s_v = cf.model_frame(surface, u, v)
        d = surface.sigma_derivatives(u, v)
        np.testing.assert_array_equal(np.stack([q, s_u, s_v]), np.stack([d.point, d.su, d.sv]))
        np.testing.assert_allclose(F.T @ F, np.eye(3), atol=1e-12)
        assert np.linalg.det(F) == pytest.approx(1.0)
        np.testing.assert_allclose(F[:, 2], surface.normal(u, v), atol=1e-12)
        num_u = (cf.model_frame(surface, u + h, v)[1] - cf.model_frame(surface, u - h, v)[1]) / (
            2 * h
        )
        num_v = (cf.model_frame(surface, u, v + h)[1] - cf.model_frame(surface, u, v - h)[1]) / (
            2 * h
        )
        np.testing.assert_allclose(F_u, num_u, atol=1e-7 * max(1, np.abs(F_u).max()))
        np.testing.assert_allclose(F_v, num_v, atol=1e-7 * max(1, np.abs(F_v).max()))


def random_local_points(surface, rng, n=60):
    """Points scattered about a surface patch, in a local frame (off the optimum)."""
    L = 0.2 * scale(surface)
    pts = rng.normal(scale=L, size=(n, 3))
    pts[:, 2] *= 0.1
    return pts


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_point_distance_residual_gradient(surface):
    rng = np.random.default_rng(10)
    L = scale(surface)
    p = points_near(surface, rng, 8, 0.05)
    _, dr = cf.point_distance_residuals(surface, p)
    h = 1e-6 * L
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        num = (
            cf.point_distance_residuals(surface, p + e)[0]
            - cf.point_distance_residuals(surface, p - e)[0]
        ) / (2 * h)
        np.testing.assert_allclose(dr[:, k], num, atol=1e-6)


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_superposition_residual_jacobian_and_error_gradient(surface):
    rng = np.random.default_rng(11)
    X = random_local_points(surface, rng)
    h = 1e-6
    for u, v in zip(*interior_parameters(surface, rng, 3, margin=0.2), strict=True):
        x = np.array([u, v, rng.uniform(0, 2 * np.pi)])
        r, J = cf.superposition_residuals(surface, X, *x)
        E, grad = cf.superposition_error_gradient(surface, X, *x)
        assert E == pytest.approx(np.abs(r).mean())
        assert np.abs(r).min() > 1e-4 * np.abs(r).max()  # |.| is smooth here
        for k in range(3):
            e = np.zeros(3)
            e[k] = h
            r_num = (
                cf.superposition_residuals(surface, X, *(x + e))[0]
                - cf.superposition_residuals(surface, X, *(x - e))[0]
            ) / (2 * h)
            E_num = (
                cf.superposition_error(surface, X, *(x + e))
                - cf.superposition_error(surface, X, *(x - e))
            ) / (2 * h)
            tol = 1e-6 * max(1.0, np.abs(J[:, k]).max())
            np.testing.assert_allclose(J[:, k], r_num, atol=tol)
            assert grad[k] == pytest.approx(E_num, abs=tol)


def test_superposition_error_over_an_array_of_angles_matches_single_angles():
    s = cf.ellipsoid()
    X = random_local_points(s, np.random.default_rng(12))
    phi = np.linspace(0, 2 * np.pi, 7)
    E = cf.superposition_error(s, X, 1.0, 1.2, phi)
    assert E.shape == (7,)
    np.testing.assert_allclose(E, [cf.superposition_error(s, X, 1.0, 1.2, p) for p in phi])
    r, _ = cf.superposition_residuals(s, X, 1.0, 1.2, phi[3])
    assert E[3] == pytest.approx(np.abs(r).mean(), rel=1e-12)


@pytest.mark.parametrize("surface", SURFACES, ids=IDS)
def test_rigid_motion_residual_jacobian(surface):
    rng = np.random.default_rng(13)
    X = random_local_points(surface, rng)
    u, v = (x[0] for x in interior_parameters(surface, rng, 1, margin=0.2))
    R = Rotation.random(random_state=rng).as_matrix()
    c = surface.sigma(u, v)
    _, J = cf.rigid_motion_residuals(surface, X, R, c)
    h = 1e-7
    for k in range(6):
        e = np.zeros(6)
        e[k] = h

        def moved(step):
            return cf.rigid_motion_residuals(
                surface, X, Rotation.from_rotvec(step[:3]).as_matrix() @ R, c + step[3:]
            )[0]

        num = (moved(e) - moved(-e)) / (2 * h)
        np.testing.assert_allclose(J[:, k], num, atol=1e-6 * max(1.0, np.abs(J).max()))


def test_pose_from_parameters_puts_p_on_sigma_with_aligned_normals():
    s = cf.elliptic_paraboloid()
    rng = np.random.default_rng(14)
    frame = Rotation.random(random_state=rng).as_matrix()
    geometry = LocalSurfaceGeometry(
        rng.normal(size=3), frame[:, 2], 1.0, 0.5, frame[:, 0], frame[:, 1], (), np.zeros(3), True
    )
    T = cf.pose_from_parameters(s, geometry, 0.7, 0.4, 1.1)
    np.testing.assert_allclose(T[:3, :3] @ geometry.point + T[:3, 3], s.sigma(0.7, 0.4))
    np.testing.assert_allclose(T[:3, :3] @ frame[:, 2], s.normal(0.7, 0.4), atol=1e-12)
    np.testing.assert_allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-12)


def test_initial_phi_finds_the_global_minimum_over_phi():
    s = cf.ellipsoid()
    X = random_local_points(s, np.random.default_rng(15))
    phi, E = cf.initial_phi(s, X, 0.31, 0.63)
    fine = np.linspace(0, 2 * np.pi, 20001)
    E_fine = cf.superposition_error(s, X, 0.31, 0.63, fine)
    assert E <= E_fine.min() + 1e-9
    assert E == pytest.approx(cf.superposition_error(s, X, 0.31, 0.63, phi))
    assert 0 <= phi < 2 * np.pi


# --- lookup table (4.7) --------------------------------------------------------------------


def test_lookup_table_matches_a_brute_force_range_query():
    s = cf.ellipsoid()
    model = cf.ClosedFormModel.build(s, 60, 30)
    table = model.table
    assert len(table) == 1800 and model.shape == (60, 30)
    assert model.v.min() > 0 and model.v.max() < np.pi  # cell centres: no pole
    for k1, k2, delta in ((1.2, 0.7, 0.1), (3.0, 0.6, 0.3), (9.0, 9.0, 0.5)):
        rows = table.query(k1, k2, delta)
        dist = np.hypot(table.k1 - k1, table.k2 - k2)
        assert set(rows.tolist()) == set(np.flatnonzero(dist < delta).tolist())
        assert np.all(np.diff(dist[rows]) >= 0)
    assert len(table.query(9.0, 9.0, 0.5)) == 0
    assert len(table.query(1.0, 0.5, np.inf)) == len(table)


def test_candidates_are_separated_and_not_symmetric_copies():
    s = cf.ellipsoid()
    model = cf.ClosedFormModel.build(s, 120, 60)
    rows = cf.candidate_rows(model, 1.2, 0.7, 0.2, 0.15, 50)
    plain = cf.candidate_rows(model, 1.2, 0.7, 0.2, 0.15, 50, s.symmetries)
    assert 0 < len(plain) < len(rows) <= 50
    for chosen, maps in ((rows, [np.eye(3)]), (plain, [np.eye(3), *s.symmetries])):
        p = model.points[chosen]
        for i in range(len(p)):
            for j in range(i):
                assert min(np.linalg.norm(S @ p[j] - p[i]) for S in maps) >= 0.15
    assert len(cf.candidate_rows(model, 1.2, 0.7, 0.2, 0.15, 3)) == 3


def test_phi_slope_used_by_the_bisection_matches_finite_differences():
    s = cf.monkey_saddle()
    X = random_local_points(s, np.random.default_rng(16))
    terms = _phi_terms(s, X, 0.3, -0.2)
    phi = np.linspace(0.1, 6.0, 9)
    E, slope = terms(phi)
    h = 1e-6
    numeric = (terms(phi + h)[0] - terms(phi - h)[0]) / (2 * h)
    np.testing.assert_allclose(slope, numeric, atol=1e-6 * max(1.0, np.abs(slope).max()))
    np.testing.assert_allclose(E, cf.superposition_error(s, X, 0.3, -0.2, phi))
