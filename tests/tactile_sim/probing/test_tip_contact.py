"""The tip's contact box: its top face is the mesh's tangent plane under the tip centre."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from tactile_sim import scene
from tactile_sim.probing import ProbeScene
from tactile_sim.probing.tip_contact import TipContact


def box_top(probe_scene: ProbeScene, contact: TipContact) -> tuple[np.ndarray, np.ndarray]:
    """The centre of the box's top face and its outward normal, world frame."""
    data = probe_scene.physics.data.ptr
    mocap = contact._mocap
    frame = np.empty(9)
    mujoco.mju_quat2Mat(frame, data.mocap_quat[mocap])
    normal = frame.reshape(3, 3)[:, 2]
    return data.mocap_pos[mocap] + scene.TIP_CONTACT_HALF_SIZE_M[2] * normal, normal


@pytest.mark.parametrize("direction", [(0, 0, 1), (1, 0, 0), (0.3, -0.9, 0.3), (-1, 0, -0.2)])
def test_the_box_top_is_tangent_to_the_mesh_at_the_point_nearest_the_tip(
    sphere_scene: ProbeScene, direction: tuple[float, ...]
) -> None:
    contact = TipContact(sphere_scene)
    T = sphere_scene.T_world_from_object
    centre_of_object = T[:3, 3] + T[:3, :3] @ sphere_scene.mesh_distance.vertices.mean(axis=0)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    radius = float(np.max(np.linalg.norm(sphere_scene.mesh_distance.vertices, axis=1)))
    tip = centre_of_object + (radius + 1.2e-3) * u
    contact._query(sphere_scene.physics.data.ptr, tip)
    nearest, distance = sphere_scene.closest_points_in_world(tip[None])
    top, normal = box_top(sphere_scene, contact)
    np.testing.assert_allclose(top, nearest[0], atol=1e-12)
    np.testing.assert_allclose(normal, (tip - nearest[0]) / distance[0], atol=1e-12)
    assert contact._distance == pytest.approx(distance[0], abs=1e-15)


def test_a_centre_under_the_surface_is_pushed_out_along_the_face_normal(
    sphere_scene: ProbeScene,
) -> None:
    contact = TipContact(sphere_scene)
    T = sphere_scene.T_world_from_object
    mesh = sphere_scene.mesh_distance
    face = int(np.argmax(mesh.face_normals[:, 2]))  # a face on top
    centroid = mesh.vertices[mesh.faces[face]].mean(axis=0)
    inside = T[:3, :3] @ (centroid - 0.2e-3 * mesh.face_normals[face]) + T[:3, 3]
    contact._query(sphere_scene.physics.data.ptr, inside)
    _, normal = box_top(sphere_scene, contact)
    np.testing.assert_allclose(normal, T[:3, :3] @ mesh.face_normals[face], atol=1e-12)
