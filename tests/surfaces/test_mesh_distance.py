"""Exact closest points on meshes (the grid of cell lists) against libigl's AABB tree."""

import igl
import numpy as np
import pytest
import trimesh
from testing_meshes import blob, cylinder, torus

from recognition.surfaces.distance import MeshDistance, folded_faces
from recognition.synthetic import ray_contact


def reference(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distances by libigl (an independent exact implementation)."""
    d2, _, _ = igl.point_mesh_squared_distance(points, vertices, faces)
    return np.sqrt(d2)


def queries(mesh: trimesh.Trimesh, rng: np.random.Generator) -> np.ndarray:
    """Points on, near, inside, far from and well outside the mesh's bounding box."""
    v = mesh.vertices[rng.integers(len(mesh.vertices), size=300)]
    size = float(np.ptp(mesh.vertices, axis=0).max())
    return np.concatenate(
        [
            v,
            v + rng.normal(scale=1e-5, size=v.shape),
            v + rng.normal(scale=1e-3, size=v.shape),
            v + rng.normal(scale=0.3 * size, size=v.shape),
            rng.normal(scale=3 * size, size=(30, 3)),
            mesh.vertices.mean(axis=0) + rng.normal(scale=1e-4, size=(30, 3)),
        ]
    )


def assert_exact(mesh: trimesh.Trimesh, points: np.ndarray) -> None:
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    d, q, f = MeshDistance(vertices, faces).closest(points)
    np.testing.assert_allclose(d, reference(vertices, faces, points), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(points - q, axis=1), d, rtol=1e-12, atol=1e-15)
    # the closest point lies on the face named, in its plane and within its corners
    tri = vertices[faces[f]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    assert np.all(np.abs(np.einsum("ij,ij->i", q - tri[:, 0], normal)) < 1e-12)
    e1, e2, r = tri[:, 0] - tri[:, 2], tri[:, 1] - tri[:, 2], q - tri[:, 2]
    gram = np.stack(
        [
            np.einsum("ij,ij->i", e1, e1),
            np.einsum("ij,ij->i", e1, e2),
            np.einsum("ij,ij->i", e2, e2),
        ]
    )
    rhs = np.stack([np.einsum("ij,ij->i", e1, r), np.einsum("ij,ij->i", e2, r)])
    det = gram[0] * gram[2] - gram[1] ** 2
    u = (gram[2] * rhs[0] - gram[1] * rhs[1]) / det
    w = (gram[0] * rhs[1] - gram[1] * rhs[0]) / det
    assert np.all(u >= -1e-9) and np.all(w >= -1e-9) and np.all(u + w <= 1 + 1e-9)


def small_cylinder() -> trimesh.Trimesh:
    """A cylinder with long thin triangles on its caps."""
    return cylinder(n_theta=60, n_z=40, n_cap=8)


@pytest.mark.parametrize("make", [blob, torus, small_cylinder], ids=["blob", "torus", "cylinder"])
def test_closest_points_are_exact_at_every_distance(make):
    mesh = make()
    assert_exact(mesh, queries(mesh, np.random.default_rng(0)))


def test_one_point_at_a_time_gives_the_same_numbers_as_a_batch():
    mesh = torus()
    points = queries(mesh, np.random.default_rng(2))
    distance = MeshDistance(mesh.vertices, mesh.faces)
    d, q, f = distance.closest(points)
    one = np.array([distance.closest_to(*p) for p in points])
    assert np.array_equal(one[:, 0], d)
    assert np.array_equal(one[:, 1:4], q)
    assert np.array_equal(one[:, 4].astype(np.int64), f)


def test_closest_points_are_exact_among_triangles_of_very_different_sizes():
    # a box of two-triangle faces with one face finely subdivided: the cells must grow
    box = trimesh.creation.box(extents=(0.3, 0.02, 0.01))
    fine = box.subdivide_to_size(0.001)
    vertices = np.concatenate([box.vertices, fine.vertices[fine.faces[:2000]].reshape(-1, 3)])
    faces = np.concatenate([box.faces, len(box.vertices) + np.arange(6000).reshape(-1, 3)])
    mixed = trimesh.Trimesh(vertices, faces, process=False)
    assert_exact(mixed, queries(mixed, np.random.default_rng(1)))


def test_a_single_triangle_and_a_degenerate_one():
    points = np.random.default_rng(2).normal(scale=0.05, size=(500, 3))
    one = trimesh.Trimesh([[0, 0, 0], [0.01, 0, 0], [0, 0.02, 0]], [[0, 1, 2]], process=False)
    assert_exact(one, points)
    flat = np.array([[0.0, 0, 0], [0.01, 0, 0], [0.02, 0, 0], [0, 0.01, 0.001]])
    d, _, _ = MeshDistance(flat, [[0, 1, 2], [0, 1, 3]]).closest(points)
    np.testing.assert_allclose(d, reference(flat, np.array([[0, 1, 2], [0, 1, 3]]), points))


def test_triangles_with_coincident_corners_are_their_segments_and_points():
    # a scan's welded seam can leave a face with two corners (or all three) at one place:
    # it is the segment (or the point) between them, whichever corner comes first, and
    # never a division by zero
    points = np.random.default_rng(3).normal(scale=0.05, size=(500, 3))
    a, c, d = np.array([0.0, 0, 0]), np.array([0.01, 0.02, 0]), np.array([0.03, 0, 0.01])
    t = np.clip((points - a) @ (c - a) / ((c - a) @ (c - a)), 0.0, 1.0)
    to_segment = np.linalg.norm(points - (a + t[:, None] * (c - a)), axis=1)
    far = [[10.0, 0, 0], [10.0, 0.01, 0], [10.0, 0, 0.01]]  # a face that is never nearest
    for corners in ([a, a, c], [a, c, a], [c, a, a], [a, c, c], [d, d, d]):
        expected = to_segment if corners[0] is not d else np.linalg.norm(points - d, axis=1)
        mesh = MeshDistance(np.vstack([corners, far]), [[0, 1, 2], [3, 4, 5]])
        distance, closest, face = mesh.closest(points)
        np.testing.assert_allclose(distance, expected, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(np.linalg.norm(points - closest, axis=1), distance, rtol=1e-12)
        assert np.all(face == 0)


def test_points_that_are_not_finite_get_no_answer():
    mesh = blob(subdivisions=3)
    d, q, f = MeshDistance(mesh.vertices, mesh.faces).closest(
        [[np.nan, 0, 0], [0, np.inf, 0], [0, 0, 0.1]]
    )
    assert np.isnan(d[:2]).all() and np.isnan(q[:2]).all() and list(f[:2]) == [-1, -1]
    assert np.isfinite(d[2]) and f[2] >= 0


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        (np.eye(3), np.zeros((0, 3), int), "faces"),
        (np.eye(3), [[0, 1, 3]], "index its 3 vertices"),
        (np.eye(3), [[0, -1, 2]], "index its 3 vertices"),
        ([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]], "finite"),
        (np.zeros((3, 2)), [[0, 1, 2]], "vertices"),
        (np.zeros((3, 3)), [[0, 1, 2]], "zero size"),
    ],
)
def test_a_mesh_that_is_not_one_is_refused(vertices, faces, message):
    with pytest.raises(ValueError, match=message):
        MeshDistance(vertices, faces).closest([[0.0, 0.0, 0.0]])


def test_a_large_flat_mesh_of_small_triangles_keeps_its_grid_bounded():
    plane = trimesh.creation.box(extents=(1.0, 1.0, 1e-6)).subdivide_to_size(0.002)
    distance = MeshDistance(plane.vertices, plane.faces)
    d, _, _ = distance.closest([[0.1, 0.2, 0.05], [0.3, -0.4, -0.01]])
    np.testing.assert_allclose(d, [0.05 - 5e-7, 0.01 - 5e-7], rtol=1e-9)
    assert np.prod(distance.grid.shape) <= MeshDistance.MAX_CELLS


def first_hit_by_every_triangle(
    vertices: np.ndarray, faces: np.ndarray, origins: np.ndarray, directions: np.ndarray
) -> np.ndarray:
    """Reference: the least t >= 0 at which each ray meets any triangle (inf: none),
    testing every triangle (barycentric coordinates within 1e-9 of the triangle)."""
    tri = vertices[faces][None]
    e1, e2 = tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :]
    d, o = directions[:, None], origins[:, None]
    p = np.cross(d, e2)
    det = np.einsum("rfi,rfi->rf", e1 + 0 * p, p)
    s = o - tri[..., 0, :]
    q = np.cross(s, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.einsum("rfi,rfi->rf", s, p) / det
        v = np.einsum("rfi,rfi->rf", d + 0 * q, q) / det
        t = np.einsum("rfi,rfi->rf", e2 + 0 * q, q) / det
    hit = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9) & (t >= 0)
    return np.where(hit, t, np.inf).min(axis=1)


def test_first_ray_hits_are_the_nearest_of_all_triangles():
    mesh = blob(subdivisions=3)
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    rng = np.random.default_rng(3)
    # from outside towards vertices (through edges and vertices), from inside outwards,
    # and rays that miss the mesh
    targets = vertices[rng.integers(len(vertices), size=200)]
    outside = targets + rng.normal(size=(200, 3)) * 0.1
    inside = np.repeat(vertices.mean(axis=0, keepdims=True), 200, axis=0)
    origins = np.concatenate([outside, inside, outside + 1.0])
    directions = np.concatenate([targets - outside, rng.normal(size=(200, 3)), targets - outside])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    face, t = MeshDistance(vertices, faces).first_hits(origins, directions)
    assert np.all(face[:400] >= 0) and np.all(face[400:] == -1)
    np.testing.assert_allclose(
        t, first_hit_by_every_triangle(vertices, faces, origins, directions), rtol=1e-12
    )
    hit = origins[:400] + t[:400, None] * directions[:400]
    np.testing.assert_allclose(MeshDistance(vertices, faces).closest(hit)[0], 0, atol=1e-12)
    # libigl (float32 distances) agrees but where it misses a crossing: never nearer
    tree = igl.AABB()  # its ray test has absolute tolerances: cast in millimetres
    tree.init(vertices * 1e3, faces)
    ref_face, ref_t, _ = tree.intersect_ray_first(vertices * 1e3, faces, origins * 1e3, directions)
    found = np.asarray(ref_face)[:400] >= 0
    ref_t = np.asarray(ref_t)[:400][found] * 1e-3
    assert np.isclose(t[:400][found], ref_t, rtol=1e-6).sum() >= 380
    assert np.all(t[:400][found] <= ref_t * (1 + 1e-6))


def test_normals_of_some_faces_are_those_of_all_faces():
    mesh = blob(subdivisions=3)
    distance = MeshDistance(mesh.vertices, mesh.faces)
    faces = np.random.default_rng(4).integers(len(mesh.faces), size=(7, 5))
    np.testing.assert_array_equal(distance.normals_of(faces), distance.face_normals[faces])
    np.testing.assert_allclose(distance.face_normals, mesh.face_normals, atol=1e-12)
    assert np.all(np.isnan(distance.normals_of([3, -1])[1]))  # -1: no face


def folded_sphere() -> tuple[np.ndarray, np.ndarray, int]:
    """An icosphere whose first face is split at a corner just past one of its edges (by
    a nanometre): the sliver on that edge points into the sphere, as marching cubes'
    slivers do once a surface is displaced. Returns vertices, faces and that corner."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.02)
    vertices, faces = sphere.vertices, sphere.faces
    a, b, c = faces[0]
    middle = 0.5 * (vertices[a] + vertices[b])
    across = (vertices[c] - middle) / np.linalg.norm(vertices[c] - middle)
    k = len(vertices)
    vertices = np.vstack([vertices, middle - 1e-9 * across])
    faces = np.vstack([[[a, b, k], [b, c, k], [c, a, k]], faces[1:]])
    return vertices, faces, k


def test_a_folded_sliver_is_turned_over_and_signs_stay_right():
    vertices, faces, corner = folded_sphere()
    assert trimesh.Trimesh(vertices, faces, process=False).is_watertight
    np.testing.assert_array_equal(np.flatnonzero(folded_faces(vertices, faces)), [0])
    distance = MeshDistance(vertices, faces)
    outward = vertices[corner] / np.linalg.norm(vertices[corner])
    assert distance.face_normals[0] @ outward > 0.99
    np.testing.assert_array_equal(distance.normals_of([0, 5]), distance.face_normals[[0, 5]])
    points = vertices[corner] + np.random.default_rng(0).normal(size=(2000, 3)) * 1e-3
    signed, _, face = distance.signed_closest(points)
    assert np.sum(face == 0) >= 10  # the sliver is the closest face of some points
    inside = igl.winding_number(vertices, faces, points) > 0.5
    np.testing.assert_array_equal(signed < 0, inside)


def test_a_touch_by_ray_lands_on_the_surface_past_a_folded_sliver():
    vertices, faces, corner = folded_sphere()
    distance = MeshDistance(vertices, faces)
    rng = np.random.default_rng(1)
    outward = vertices[corner] / np.linalg.norm(vertices[corner])
    for _ in range(50):
        direction = -outward + 0.3 * rng.normal(size=3)
        start = vertices[corner] - 2e-3 * direction / np.linalg.norm(direction)
        start += rng.normal(size=3) * 0.3e-3
        point = ray_contact(distance, np.eye(4), start, direction, 0.01)
        assert point is not None
        assert distance.closest(point[None])[0][0] < 1e-8


def test_normals_between_the_corners_are_weighed_by_the_barycentric_coordinates():
    from recognition.surfaces.mesh_kernels import interpolated_normals

    mesh = blob()
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)
    corner_normals = np.asarray(mesh.vertex_normals)
    rng = np.random.default_rng(5)
    face = rng.integers(len(faces), size=400)
    weights = rng.dirichlet(np.ones(3), size=400)
    weights[:50] = np.eye(3)[rng.integers(3, size=50)]  # at corners
    points = np.einsum("nk,nki->ni", weights, vertices[faces[face]])
    got = interpolated_normals(vertices, faces, corner_normals, points, face)
    expected = np.einsum("nk,nki->ni", weights, corner_normals[faces[face]])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(got, expected, atol=1e-9)
    # a point beside its face counts its nearest corners; a face without area, all alike
    beside = vertices[faces[:1, 0]] + 5.0 * (vertices[faces[:1, 0]] - vertices[faces[:1, 1]])
    n0 = corner_normals[faces[0, 0]]
    np.testing.assert_allclose(
        interpolated_normals(vertices, faces, corner_normals, beside, np.zeros(1, np.int64))[0],
        n0 / np.linalg.norm(n0),
        atol=1e-9,
    )
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    tilted = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])
    got = interpolated_normals(flat, np.array([[0, 1, 2]]), tilted, flat[:1], np.zeros(1, np.int64))
    np.testing.assert_allclose(got[0], np.ones(3) / np.sqrt(3), atol=1e-12)
