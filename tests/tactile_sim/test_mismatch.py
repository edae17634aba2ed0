"""An object displaced from its model on purpose: RMS, smoothness, seeds, and probing it."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from recognition.surfaces.distance import MeshDistance
from tactile_sim.errors import SimulationError
from tactile_sim.objects.mismatch import DisplacementField, displaced_mesh


@pytest.fixture(scope="module")
def sphere() -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=5, radius=0.03)


def test_the_displacement_has_the_asked_rms_and_moves_along_the_normals(sphere) -> None:
    field = DisplacementField(0.1e-3, correlation_m=5e-3, seed=1)
    moved, achieved = displaced_mesh(sphere, field)
    radial = np.linalg.norm(moved.vertices, axis=1) - np.linalg.norm(sphere.vertices, axis=1)
    offsets = np.linalg.norm(moved.vertices - sphere.vertices, axis=1)
    np.testing.assert_allclose(np.abs(radial), offsets, atol=1e-9)  # along the normals
    assert achieved == pytest.approx(0.1e-3, rel=0.05)
    assert np.sqrt(np.mean(radial**2)) == pytest.approx(0.1e-3, rel=0.05)
    distance = MeshDistance(sphere.vertices, sphere.faces).closest(moved.vertices)[0]
    assert np.sqrt(np.mean(distance**2)) == pytest.approx(achieved, rel=0.01)  # area-weighted


def test_the_displacement_is_smooth_over_its_correlation_length(sphere) -> None:
    field = DisplacementField(0.1e-3, correlation_m=5e-3, seed=2)
    values = field.unit_values(sphere.vertices)
    d = np.linalg.norm(sphere.vertices[:, None] - sphere.vertices[None, :400], axis=2)
    product = values[:, None] * values[None, :400]
    near = np.mean(product[(d > 0.5e-3) & (d < 1.5e-3)])
    far = np.mean(product[(d > 20e-3) & (d < 25e-3)])
    assert near > 0.9 * np.mean(values**2)  # neighbours 1 mm apart move together
    assert abs(far) < 0.2 * np.mean(values**2)  # 20 mm apart, independently


def test_same_seed_same_object_other_seed_other_and_zero_is_the_model(sphere) -> None:
    a, _ = displaced_mesh(sphere, DisplacementField(0.1e-3, seed=3))
    b, _ = displaced_mesh(sphere, DisplacementField(0.1e-3, seed=3))
    c, _ = displaced_mesh(sphere, DisplacementField(0.1e-3, seed=4))
    np.testing.assert_array_equal(a.vertices, b.vertices)
    assert np.abs(a.vertices - c.vertices).max() > 0.05e-3
    same, achieved = displaced_mesh(sphere, DisplacementField(0.0))
    assert same is sphere and achieved == 0.0


@pytest.mark.parametrize(
    ("rms", "correlation", "fragment"),
    [(-0.1e-3, 5e-3, "RMS >= 0"), (np.nan, 5e-3, "RMS >= 0"), (0.1e-3, 0.0, "correlation")],
)
def test_bad_fields_are_refused(rms, correlation, fragment) -> None:
    with pytest.raises(SimulationError, match=fragment):
        DisplacementField(rms, correlation_m=correlation)


def test_the_robot_probes_the_displaced_object_and_says_how_far_it_is() -> None:
    from tactile_sim.probing import displaced_target, probe_object, resolve_object

    target = displaced_target(resolve_object("sphere"), DisplacementField(0.1e-3, seed=5))
    assert target.model_error_rms_m == pytest.approx(0.1e-3, rel=0.1)
    session = probe_object(target, seed=5, n_points=7, progress=False)
    assert session.ground_truth.model_error_rms_m == target.model_error_rms_m
    T = np.linalg.inv(session.ground_truth.T_world_from_object)
    contacts = np.concatenate(session.ground_truth.true_contact_points_in_world)
    in_object = contacts @ T[:3, :3].T + T[:3, 3]
    on_object = MeshDistance(target.mesh.vertices, target.mesh.faces).closest(in_object)[0]
    model = resolve_object("sphere").mesh
    off_model = MeshDistance(model.vertices, model.faces).closest(in_object)[0]
    assert on_object.max() < 2e-6  # the tip touches the displaced surface
    assert off_model.mean() > 0.02e-3  # which is not the model's
