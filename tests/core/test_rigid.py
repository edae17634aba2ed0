"""Rigid motions: exact identities and finite-difference derivatives."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from recognition import rigid


def test_rotation_from_vector_matches_scipy():
    w = np.random.default_rng(0).normal(size=(50, 3)) * 2.0
    R = rigid.rotation_from_vector(w)
    np.testing.assert_allclose(R, Rotation.from_rotvec(w).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(rigid.rotation_from_vector(np.zeros((1, 3)))[0], np.eye(3))


def test_skew_is_the_cross_product():
    rng = np.random.default_rng(1)
    w, x = rng.normal(size=(20, 3)), rng.normal(size=(20, 3))
    np.testing.assert_allclose(np.einsum("bij,bj->bi", rigid.skew(w), x), np.cross(w, x))
    np.testing.assert_allclose(rigid.cross(w, x), np.cross(w, x))
    np.testing.assert_allclose(rigid.cross(w[0], x[0]), np.cross(w[0], x[0]))


def test_point_to_plane_jacobian_is_the_first_order_motion_along_the_normals():
    # points moved by a small turn about a pivot and a shift: J (turn, shift) is how far
    # each moves along its normal, to first order
    rng = np.random.default_rng(2)
    points, pivot = rng.normal(size=(30, 3)), rng.normal(size=3)
    normals = rng.normal(size=(30, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    step = 1e-6 * rng.normal(size=6)
    R = Rotation.from_rotvec(step[:3]).as_matrix()
    moved = (points - pivot) @ R.T + pivot + step[3:]
    along = np.einsum("ij,ij->i", moved - points, normals)
    J = rigid.point_to_plane_jacobian(points, normals, pivot)
    np.testing.assert_allclose(J @ step, along, rtol=0, atol=1e-11)  # second order: 1e-12


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rotation_about_axis_and_its_derivative(axis):
    angle = np.linspace(-3.0, 3.0, 13)
    R = rigid.rotation_about(axis, angle)
    e = np.eye(3)[axis]
    np.testing.assert_allclose(R, Rotation.from_rotvec(angle[:, None] * e).as_matrix(), atol=1e-15)
    h = 1e-6
    fd = (rigid.rotation_about(axis, angle + h) - rigid.rotation_about(axis, angle - h)) / (2 * h)
    np.testing.assert_allclose(rigid.rotation_about_derivative(axis, angle), fd, atol=1e-9)
    np.testing.assert_allclose(rigid.rotation_angle(R), np.abs(angle), atol=1e-7)


def test_poses_and_random_motions_are_rigid():
    rng = np.random.default_rng(2)
    T = rigid.random_rigid_motion(rng, 0.1)
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-14)
    assert np.isclose(np.linalg.det(T[:3, :3]), 1.0)
    points = rng.normal(size=(5, 3))
    np.testing.assert_allclose(rigid.apply_pose(T, points), points @ T[:3, :3].T + T[:3, 3])
    np.testing.assert_array_equal(rigid.pose_matrix(T[:3, :3], T[:3, 3]), T)
    P = rigid.random_planar_motion(rng, 1.0)
    np.testing.assert_allclose(P[:2, :2] @ P[:2, :2].T, np.eye(2), atol=1e-14)
    np.testing.assert_allclose(
        rigid.rotation_2d(0.3) @ rigid.rotation_2d(-0.3), np.eye(2), atol=1e-15
    )
    # the same seed gives the same motion
    np.testing.assert_array_equal(
        rigid.random_rigid_motion(np.random.default_rng(5)),
        rigid.random_rigid_motion(np.random.default_rng(5)),
    )
