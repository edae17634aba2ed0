"""The probe's sensor model: readings, noise, contact force and point, error against truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from tactile_sim import probing, scene
from tactile_sim.kinematics import probe_tip_position
from tactile_sim.probing import ProbeScene
from tactile_sim.probing.rig import Rig
from tactile_sim.sensor import (
    ContactEstimate,
    GroundTruthContact,
    GroundTruthReader,
    NoiseModel,
    SensorConfig,
    SensorReader,
    SensorReading,
    contact_force_in_tip_frame,
    estimate_contact,
    ground_truth_contact,
)

NOISELESS = SensorConfig(noise=NoiseModel.noiseless())


def tilted_slab_pose(slope_deg: float, azimuth_deg: float) -> np.ndarray:
    """T_world_from_object of a slab on the mount, its top tilted by ``slope_deg``."""
    axis = np.array([-math.sin(math.radians(azimuth_deg)), math.cos(math.radians(azimuth_deg)), 0])
    T = np.eye(4)
    T[:3, :3] = trimesh.transformations.rotation_matrix(math.radians(slope_deg), axis)[:3, :3]
    T[:3, 3] = (0.40, 0.0, 0.0)
    return T


@pytest.fixture(scope="module")
def slab() -> trimesh.Trimesh:
    """A 60 x 60 x 20 mm slab (model frame: top face at z = 0.02 m)."""
    mesh = trimesh.creation.box(extents=(0.06, 0.06, 0.02))
    mesh.apply_translation((0.0, 0.0, 0.01))
    return mesh


def press_on(
    probe_scene: ProbeScene,
    normal: np.ndarray,
    sensor: SensorConfig = NOISELESS,
    frictionless: bool = False,
) -> tuple[ContactEstimate, GroundTruthContact]:
    """Touches the slab top at the mount with the controller's approach; returns the
    estimate and the ground truth."""
    if frictionless:
        tip = probe_scene.physics.model.name2id(scene.PROBE_TIP_GEOM, "geom")
        probe_scene.physics.model.geom_friction[tip, 0] = 0.0
    rig = Rig(probe_scene, probing.ProbingConfig(), sensor, np.random.default_rng(0))
    T = probe_scene.T_world_from_object
    top_point = T[:3, :3] @ [0.0, 0.0, 0.02] + T[:3, 3]
    start = top_point + (0.001 + 0.0006) * normal
    rig.teleport(start)
    rig.settle(0.05)
    estimate = rig.approach(start, -normal, 0.003)
    return estimate, ground_truth_contact(probe_scene.physics)


@pytest.mark.parametrize(("slope_deg", "azimuth_deg"), [(0, 0), (20, 0), (35, 120), (55, -60)])
def test_contact_normal_and_point_from_readings_without_friction(
    slab: trimesh.Trimesh, slope_deg: float, azimuth_deg: float
) -> None:
    T = tilted_slab_pose(slope_deg, azimuth_deg)
    probe_scene = probing.build_probe_scene(slab, T, progress=False)
    normal = T[:3, :3] @ [0.0, 0.0, 1.0]
    estimate, truth = press_on(probe_scene, normal, frictionless=True)
    assert estimate.normal_from_force
    angle = math.degrees(math.acos(min(1.0, float(estimate.normal_in_world @ normal))))
    assert angle < 0.2
    # The sensed point lies on the slab's top within the contact's sink (micrometres).
    height = normal @ (estimate.point_in_world - T[:3, 3]) - 0.02
    assert abs(height) < 5e-6
    # Noise-free readings put the tip centre exactly where the simulator has it.
    np.testing.assert_allclose(estimate.tip_centre_in_world, truth.tip_centre_in_world, atol=1e-6)
    assert truth.stylus_contacts == 0
    assert len(truth.contact_points_in_world) >= 1
    np.testing.assert_allclose(truth.contact_normals_in_world[0], normal, atol=1e-6)


@pytest.mark.parametrize("slope_deg", [0.0, 30.0])
def test_friction_moves_the_point_along_the_surface_not_off_it(
    slab: trimesh.Trimesh, slope_deg: float
) -> None:
    T = tilted_slab_pose(slope_deg, 45.0)
    probe_scene = probing.build_probe_scene(slab, T, progress=False)
    normal = T[:3, :3] @ [0.0, 0.0, 1.0]
    estimate, _ = press_on(probe_scene, normal)
    height = normal @ (estimate.point_in_world - T[:3, 3]) - 0.02
    assert abs(height) < 5e-6
    angle = math.degrees(math.acos(min(1.0, float(estimate.normal_in_world @ normal))))
    # Friction tilts the force by up to atan(0.1) = 5.7 deg; the component along the
    # slide (sensed before and after the press) is removed.
    assert angle < 1.5


def test_contact_force_model_inverts_the_spring_balance() -> None:
    # A reading of a tilted stylus: the force the model returns produces that tilt.
    reading = SensorReading(
        time_s=0.0,
        joints=np.array([0.3, 1.2, 0.1, -0.4]),
        deflection_rad=np.array([0.004, -0.002]),
        axial_force_n=0.05,
    )
    config = SensorConfig()
    force = contact_force_in_tip_frame(reading, config)
    # Axial: the contact pushes the tip back along the stylus by the force cell's reading.
    assert force[2] == pytest.approx(-0.05, abs=1e-3)
    # Lateral: about k theta / L, with deflection_y tilting towards +x (positive F_x).
    k_over_l = config.pivot_stiffness_n_m_per_rad / config.robot.probe.stylus_length_m
    assert force[0] == pytest.approx(k_over_l * -0.002, rel=0.05)
    assert force[1] == pytest.approx(-k_over_l * 0.004, rel=0.05)


def test_weak_contact_falls_back_to_the_given_normal() -> None:
    reading = SensorReading(0.0, np.array([0.3, 1.2, 0.1, 0.0]), np.zeros(2), 0.0)
    estimate = estimate_contact(reading, SensorConfig(), fallback_normal=(0.0, 1.0, 0.0))
    assert not estimate.normal_from_force
    np.testing.assert_allclose(estimate.normal_in_world, [0.0, 1.0, 0.0])
    centre = probe_tip_position(reading.joints)
    np.testing.assert_allclose(estimate.point_in_world, centre - [0.0, 0.001, 0.0])


def test_readings_are_seeded_and_noise_has_the_documented_magnitude() -> None:
    physics = scene.load_scene()
    noise = NoiseModel()
    first = SensorReader(physics, noise, np.random.default_rng(7))
    second = SensorReader(physics, noise, np.random.default_rng(7))
    samples = np.array([first.raw() for _ in range(5000)])
    np.testing.assert_array_equal(samples[:50], [second.raw() for _ in range(50)])
    exact = SensorReader(physics, NoiseModel.noiseless(), np.random.default_rng(7)).raw()
    np.testing.assert_allclose(samples.std(axis=0), noise.sigmas, rtol=0.06)
    assert np.all(np.abs(samples.mean(axis=0) - exact) < 4.0 * noise.sigmas / math.sqrt(5000))


def test_ground_truth_reader_reads_the_scene_it_was_made_for() -> None:
    scenes = [scene.load_scene(), scene.load_scene()]
    scene.set_arm_joints(scenes[1], [0.3, 1.0, 0.05, 0.0])
    readers = [GroundTruthReader(physics) for physics in scenes]
    for physics, reader in zip(scenes, readers, strict=True):
        truth = reader.read()
        expected = probe_tip_position(scene.arm_joints(physics))
        np.testing.assert_allclose(truth.tip_centre_in_world, expected, atol=1e-6)
        assert truth.stylus_contacts == 0 and len(truth.contact_points_in_world) == 0
        assert ground_truth_contact(physics).stylus_contacts == truth.stylus_contacts


def test_noise_model_rejects_negative_sigmas() -> None:
    with pytest.raises(ValueError, match="quill_m"):
        NoiseModel(quill_m=-1e-6)


def test_sensed_points_against_ground_truth_on_the_sphere() -> None:
    session = probing.probe_object("sphere", seed=3, n_points=9)
    centre_of = session.ground_truth.T_world_from_object[:3, 3] + [0.0, 0.0, 0.033]
    for sweep in session.sweeps:
        radial = np.linalg.norm(sweep.points_in_world - centre_of, axis=1) - 0.033
        # Inscribed icosphere facets (<= 9.4 um) and the contact's sink (a few um).
        assert np.all(np.abs(radial) < 20e-6)
        error = np.linalg.norm(sweep.points_in_world - sweep.true_contact_points_in_world, axis=1)
        assert error.mean() < 0.1e-3
        assert np.all(sweep.stylus_contacts == 0)
