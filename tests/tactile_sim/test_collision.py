"""Convex collision geometry: closed-form solids, the CoACD hull cache, every object's scene."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh

from tactile_sim import collision, scene
from tactile_sim.collision import (
    ConvexParts,
    DecompositionConfig,
    closed_spline_coefficients,
    convex_decomposition,
    convex_hull_part,
    decomposition,
    decomposition_key,
    hull_surface_deviation,
    load_solid,
    object_parts,
    solid_names,
)
from tactile_sim.errors import InvalidMesh, UnknownObject
from tactile_sim.kinematics import inverse_kinematics
from tactile_sim.objects import load_object, object_names
from tactile_sim.objects.cache import ENV_ASSETS_DIR

SIMULATED_SECONDS = 1.0
CONTROL_NOISE = 0.01
"""Standard deviation of the control noise, a fraction of each actuator's control range."""


def notched_box() -> trimesh.Trimesh:
    """A closed, non-convex box with a V notch in its top, metres (no boolean engine)."""
    # Profile in (x, z), counter-clockwise, extruded along y.
    profile = np.array(
        [[-0.02, 0.0], [0.02, 0.0], [0.02, 0.02], [0.005, 0.02], [0.0, 0.01], [-0.005, 0.02],
         [-0.02, 0.02]]
    )  # fmt: skip
    n = len(profile)
    front = np.column_stack([profile[:, 0], np.full(n, -0.01), profile[:, 1]])
    back = np.column_stack([profile[:, 0], np.full(n, 0.01), profile[:, 1]])
    vertices = np.vstack([front, back])
    faces = []
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, n + j, j], [i, n + i, n + j]]
    # Caps: the profile split into convex pieces (fan from the notch tip and corners).
    front_tris = [[0, 1, 4], [1, 2, 3], [1, 3, 4], [0, 4, 5], [0, 5, 6]]
    faces += front_tris
    faces += [[n + c, n + b, n + a] for a, b, c in front_tris]
    mesh = trimesh.Trimesh(vertices, np.array(faces), process=True)
    trimesh.repair.fix_normals(mesh)
    return mesh.subdivide().subdivide().subdivide()


# Closed-form solids ------------------------------------------------------------------------


@pytest.mark.parametrize("name", solid_names())
def test_solids_are_closed_convex_and_sit_on_the_table(name):
    solid = load_solid(name)
    mesh = solid.mesh
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert solid.convex
    bounds = mesh.bounds
    assert bounds[0, 2] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(bounds[0, :2], -bounds[1, :2], atol=1e-9)


@pytest.mark.parametrize(
    ("name", "expected_volume"),
    [
        ("cylinder_1", math.pi * 0.0252**2 * 0.1),
        ("cylinder_2", math.pi * 0.047**2 * 0.1),
        ("elliptic_cylinder", math.pi * 0.0508 * 0.03175 * 0.1),
        ("sphere", 4.0 / 3.0 * math.pi * 0.033**3),
        ("planar_ellipse", math.pi * 0.025 * 0.0175 * 0.03),
    ],
)
def test_solid_dimensions_match_thesis_figure_4_15_and_section_3_4_2(name, expected_volume):
    # Polygonal approximations are inscribed: slightly smaller, by well under 0.2 %.
    volume = load_solid(name).mesh.volume
    assert volume == pytest.approx(expected_volume, rel=2e-3)
    assert volume < expected_volume


def test_solid_extents():
    assert np.ptp(load_solid("cylinder_1").mesh.vertices[:, 2]) == pytest.approx(0.0504)
    assert np.ptp(load_solid("cylinder_2").mesh.vertices[:, 2]) == pytest.approx(0.094)
    ellipse = np.ptp(load_solid("elliptic_cylinder").mesh.vertices, axis=0)
    np.testing.assert_allclose(ellipse, [0.1, 2 * 0.0508, 2 * 0.03175], rtol=1e-9)
    planar = np.ptp(load_solid("planar_ellipse").mesh.vertices, axis=0)
    np.testing.assert_allclose(planar, [0.05, 0.035, 0.03], rtol=1e-9)


@pytest.mark.parametrize("source", ["function", "solid"])
def test_closed_spline_is_c2_continuous_and_passes_through_its_knots(source):
    if source == "function":
        knots = np.array(collision.DEFAULT_SPLINE_KNOTS_M)
        c = closed_spline_coefficients(knots)
    else:
        parameters = load_solid("planar_spline").parameters
        knots, c = np.array(parameters["knots_m"]), parameters["spline_coefficients_m"]
    assert c.shape == (5, 2, 4)
    for i in range(5):
        j = (i + 1) % 5
        np.testing.assert_allclose(c[i, :, 3], knots[i], atol=1e-15)
        end = c[i] @ [1.0, 1.0, 1.0, 1.0]
        np.testing.assert_allclose(end, knots[j], atol=1e-12)
        # First and second derivatives match at the joint.
        np.testing.assert_allclose(c[i] @ [3.0, 2.0, 1.0, 0.0], c[j, :, 2], atol=1e-12)
        np.testing.assert_allclose(c[i] @ [6.0, 2.0, 0.0, 0.0], 2.0 * c[j, :, 1], atol=1e-12)


def test_unknown_solid_lists_the_known_names():
    with pytest.raises(UnknownObject, match=r"cylinder_1.*sphere"):
        load_solid("cube")


# Decomposition and cache -------------------------------------------------------------------


def test_convex_mesh_is_its_own_single_part():
    solid = load_solid("cylinder_2")
    parts = convex_decomposition(solid.mesh, name="cylinder_2", progress=False)
    assert parts.source == "convex" and parts.n_parts == 1
    accuracy = hull_surface_deviation(parts.parts, solid.mesh, n_samples=5000)
    assert accuracy.max_m < 1e-9


def test_convex_hull_part_faces_point_outward():
    rng = np.random.default_rng(0)
    vertices, faces = convex_hull_part(rng.normal(size=(200, 3)))
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0


def test_decomposition_key_depends_on_mesh_and_parameters():
    mesh = load_solid("planar_ellipse").mesh
    key = decomposition_key(mesh, DecompositionConfig())
    assert key == decomposition_key(mesh.copy(), DecompositionConfig())
    assert key != decomposition_key(mesh, DecompositionConfig(threshold=0.03))
    moved = mesh.copy()
    moved.apply_translation((1e-6, 0.0, 0.0))
    assert key != decomposition_key(moved, DecompositionConfig())
    # A recipe key replaces the arrays: the same recipe matches however the mesh rounds.
    by_recipe = decomposition_key(mesh, DecompositionConfig(), geometry_key="abc")
    assert by_recipe == decomposition_key(moved, DecompositionConfig(), geometry_key="abc")
    assert by_recipe != decomposition_key(mesh, DecompositionConfig(), geometry_key="abd")


def test_decomposition_config_rejects_bad_values():
    with pytest.raises(ValueError, match="threshold"):
        DecompositionConfig(threshold=0.0)
    with pytest.raises(ValueError, match="preprocess_mode"):
        DecompositionConfig(preprocess_mode="maybe")


@pytest.mark.slow
def test_cold_build_is_cached_and_a_corrupt_cache_is_rebuilt(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(ENV_ASSETS_DIR, str(tmp_path))
    mesh = notched_box()
    config = DecompositionConfig(threshold=0.05, target_faces=2000)
    built = convex_decomposition(mesh, config, name="notch")
    assert built.source == "built" and built.n_parts >= 2
    assert "building the convex collision parts of 'notch'" in capsys.readouterr().err
    # The union of the parts stays close to the notched surface.
    assert built.accuracy is not None and built.accuracy.mean_m < 2e-4

    warm = convex_decomposition(mesh, config, name="notch")
    assert warm.source == "cache" and warm.n_parts == built.n_parts
    for (v0, f0), (v1, f1) in zip(built.parts, warm.parts, strict=True):
        np.testing.assert_allclose(v0, v1, atol=1e-8)  # stored as float32
        np.testing.assert_array_equal(f0, f1)

    (path,) = (tmp_path / "hulls").glob("notch-*.npz")
    path.write_bytes(b"not a zip file")
    rebuilt = convex_decomposition(mesh, config, name="notch", progress=False)
    assert rebuilt.source == "built"


def test_malformed_mesh_is_rejected():
    with pytest.raises(InvalidMesh, match="vertices"):
        convex_decomposition((np.zeros((2, 3)), np.zeros((1, 3), dtype=int)))


@pytest.mark.parametrize("name", object_names())
def test_catalog_hulls_are_shipped_so_a_warm_start_never_runs_coacd(name, monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("CoACD ran on a warm start")

    monkeypatch.setattr(decomposition, "_run_coacd", forbidden)
    parts = object_parts(load_object(name), progress=False)
    assert isinstance(parts, ConvexParts)
    assert parts.source in ("shipped", "convex"), (
        f"{name}: the shipped hulls do not match the catalog mesh; rebuild them with "
        "tactile_sim.collision.build_shipped_hulls()"
    )


# Every object's scene compiles and steps without warnings ----------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", [*object_names(), *solid_names()])
def test_object_scene_steps_one_second_with_control_noise_without_warnings(name):
    solid = name in solid_names()
    mesh = load_solid(name).mesh if solid else load_object(name).mesh
    if solid:
        parts = convex_decomposition(mesh, name=name, progress=False, convex=True)
    else:
        parts = object_parts(load_object(name), progress=False)
    physics = scene.load_scene(list(parts.parts), visual_mesh=mesh, name=name)
    model, data = physics.model.ptr, physics.data.ptr
    # Hover 3 mm above the object's top at the mount, then add seeded control noise.
    height = float(np.max(mesh.vertices[:, 2]))
    q = inverse_kinematics([0.4, 0.0, height + 0.003])
    scene.set_arm_joints(physics, q)
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    for _ in range(int(SIMULATED_SECONDS / model.opt.timestep)):
        data.ctrl[:] = np.clip(
            q + CONTROL_NOISE * 0.05 * (high - low) * rng.standard_normal(model.nu), low, high
        )
        mujoco.mj_step(model, data)
    assert scene.warning_counts(physics) == {}, f"{name}: MuJoCo warned"
    for field in ("qpos", "qvel", "qacc"):
        assert np.isfinite(getattr(data, field)).all()
