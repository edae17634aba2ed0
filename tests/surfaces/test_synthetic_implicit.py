"""Synthetic data curves on closed-form (implicit) surfaces, thesis Section 4.2.3."""

import numpy as np
import pytest

from recognition.errors import DegenerateGeometry, InvalidCurveData
from recognition.surfaces import closed_form as cf
from recognition.surfaces.sections import resample_around
from recognition.synthetic import implicit_data_curves, sampling_plane_normals


@pytest.mark.parametrize(
    ("surface", "uv", "spacing"),
    [
        (cf.ellipsoid(), (1.02, 0.69), 0.01),
        (cf.monkey_saddle(), (0.3, -0.4), 0.01),
        (cf.sphere(0.033), (0.4, 2.0), 0.5e-3),
        (cf.elliptic_cylinder(0.0508, 0.03175, 0.05), (1.0, 0.0), 0.5e-3),
    ],
    ids=["ellipsoid", "monkey_saddle", "sphere", "elliptic_cylinder"],
)
def test_implicit_curves_lie_on_the_surface_at_equal_spacing(surface, uv, spacing):
    rng = np.random.default_rng(1)
    p = surface.sigma(*uv)
    synthetic = implicit_data_curves(surface, p, n_points=41, spacing=spacing, rng=rng)
    T = synthetic.T_model_from_data
    np.testing.assert_allclose(synthetic.normal_in_model, surface.normal(*uv), atol=1e-12)
    for data, clean, m in zip(
        synthetic.curves.curves,
        synthetic.clean_curves_in_model,
        synthetic.plane_normals_in_model,
        strict=True,
    ):
        g = surface.gradient(clean)
        distance = surface.implicit(clean) / np.linalg.norm(g, axis=1)
        assert np.abs(distance).max() < 1e-9 * spacing / 0.01
        step = np.linalg.norm(np.diff(clean, axis=0), axis=1)
        np.testing.assert_allclose(step, spacing, rtol=2e-3)  # chords of equal arcs
        np.testing.assert_allclose(clean[20], p, atol=1e-9 * spacing / 0.01)  # p in the middle
        np.testing.assert_allclose((clean - p) @ m, 0, atol=1e-12)  # in its plane
        np.testing.assert_allclose(data @ T[:3, :3].T + T[:3, 3], clean, atol=1e-12)
        assert abs(m @ synthetic.normal_in_model) < 1e-12  # planes contain the normal
    np.testing.assert_allclose(
        T[:3, :3] @ synthetic.curves.approach, -synthetic.normal_in_model, atol=1e-12
    )


def test_sampling_planes_are_spaced_by_the_plane_angle_about_the_normal():
    n = np.array([0.0, 0.6, 0.8])
    planes = sampling_plane_normals(n, [1.0, 0.0, 0.0], np.deg2rad(60.0))
    np.testing.assert_allclose(np.linalg.norm(planes, axis=1), 1.0)
    np.testing.assert_allclose(planes @ n, 0.0, atol=1e-12)
    cosines = [abs(planes[i] @ planes[j]) for i, j in ((0, 1), (1, 2), (0, 2))]
    np.testing.assert_allclose(cosines, 0.5, atol=1e-12)


@pytest.mark.parametrize("angle_deg", [0.0, 90.0, 180.0])
def test_sampling_planes_that_coincide_are_refused(angle_deg):
    with pytest.raises(InvalidCurveData, match="coincide"):
        sampling_plane_normals([0, 0, 1.0], plane_angle_rad=np.deg2rad(angle_deg))


def test_explicit_planes_and_noise():
    s = cf.ellipsoid()
    p = s.sigma(1.02, 0.69)
    planes = sampling_plane_normals(s.normal(1.02, 0.69), [0.0, 0.0, 1.0], np.deg2rad(45.0))
    # noise_std is in model units; DataCurves' default meet tolerance (1e-3) caps it
    a = implicit_data_curves(
        s, p, plane_normals=planes, noise_std=1e-4, rng=np.random.default_rng(2)
    )
    b = implicit_data_curves(
        s, p, plane_normals=planes, noise_std=1e-4, rng=np.random.default_rng(2)
    )
    np.testing.assert_array_equal(a.curves.points, b.curves.points)  # seeded
    np.testing.assert_allclose(a.plane_normals_in_model, planes)
    T = a.T_model_from_data
    residual = (a.curves.points @ T[:3, :3].T + T[:3, 3]) - np.concatenate(a.clean_curves_in_model)
    assert 0.8e-4 < residual.std() < 1.2e-4


def test_noise_needs_a_generator():
    s = cf.sphere(1.0)
    p = s.sigma(1.0, 1.0)
    with pytest.raises(InvalidCurveData, match="Generator"):
        implicit_data_curves(s, p, noise_std=1e-4, transform=False)
    untransformed = implicit_data_curves(s, p, transform=False)
    np.testing.assert_array_equal(untransformed.T_model_from_data, np.eye(4))


def test_a_random_frame_needs_a_generator():
    s = cf.sphere(1.0)
    with pytest.raises(InvalidCurveData, match="Generator"):
        implicit_data_curves(s, s.sigma(1.0, 1.0))


def test_resampling_beyond_the_section_is_degenerate():
    line = np.column_stack([np.linspace(0, 1, 11), np.zeros(11), np.zeros(11)])
    out = resample_around(line, np.array([0.5, 0.0, 0.0]), 5, 0.2)
    np.testing.assert_allclose(out[:, 0], [0.1, 0.3, 0.5, 0.7, 0.9])
    with pytest.raises(DegenerateGeometry, match="section through p is too short"):
        resample_around(line, np.array([0.9, 0.0, 0.0]), 5, 0.2)
