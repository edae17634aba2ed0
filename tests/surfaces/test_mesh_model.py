"""Mesh models: validation, normals (4.13), sampling, paraboloid curvatures (4.14), distances."""

import numpy as np
import pytest
import trimesh
from testing_meshes import blob, cylinder, sphere, torus

from recognition.errors import InvalidModel
from recognition.rigid import rotation_from_vector
from recognition.surfaces.distance import MeshDistance
from recognition.surfaces.mesh_model import (
    MeshModel,
    MeshModelConfig,
    adaptive_sample,
    paraboloid_curvatures,
    vertex_normals,
)
from recognition.surfaces.mesh_repair import prepare_mesh


def closest_point_on_triangles(
    p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> np.ndarray:
    """Reference: closest points on triangles (a, b, c) to points p, all (..., 3)
    (Ericson, Real-Time Collision Detection, 5.1.5).

    Parameters
    ----------
    p : (..., 3) float
        The points, metres.
    a, b, c : (..., 3) float
        The triangles' corners, metres (broadcast against ``p``).

    Returns
    -------
    (..., 3) float
        The closest point of each triangle, metres.
    """
    ab, ac, ap = b - a, c - a, p - a
    d1 = np.einsum("...i,...i", ab, ap)
    d2 = np.einsum("...i,...i", ac, ap)
    bp = p - b
    d3 = np.einsum("...i,...i", ab, bp)
    d4 = np.einsum("...i,...i", ac, bp)
    cp = p - c
    d5 = np.einsum("...i,...i", ab, cp)
    d6 = np.einsum("...i,...i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = 1.0 / (va + vb + vc)
        v_in = vb * denom
        w_in = vc * denom
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    out = a + ab * v_in[..., None] + ac * w_in[..., None]  # interior
    # edges, then vertices (later assignments win, in Ericson's order reversed)
    on_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    out = np.where(on_bc[..., None], b + (c - b) * t_bc[..., None], out)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    out = np.where(on_ac[..., None], a + ac * t_ac[..., None], out)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    out = np.where(on_ab[..., None], a + ab * t_ab[..., None], out)
    out = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, out)
    out = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, out)
    out = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, out)
    return out


@pytest.mark.parametrize("radius", [0.02, 0.035])
def test_sphere_curvatures_and_normals(radius):
    m = sphere(radius)
    v, f = m.vertices, m.faces
    n = vertex_normals(v, f)
    # the unweighted mean of face normals (4.13) is off by ~0.2 deg at valence-5 vertices
    np.testing.assert_allclose(n, v / np.linalg.norm(v, axis=1, keepdims=True), atol=5e-3)
    sample = np.arange(0, len(v), 97)
    k1, k2, _ = paraboloid_curvatures(v, n, sample)
    # the quadric fit over ~70 vertices (about 0.25 r across at this resolution) reads
    # a sphere 0.5 % too curved: the quartic term of the sphere is fitted by the quadric
    np.testing.assert_allclose(k1, 1 / radius, rtol=1e-2)
    np.testing.assert_allclose(k2, 1 / radius, rtol=1e-2)


def test_cylinder_curvatures():
    r = 0.02
    m = cylinder(radius=r)
    v = m.vertices
    n = vertex_normals(v, m.faces)
    middle = np.flatnonzero((np.abs(v[:, 2]) < 0.02) & (np.hypot(v[:, 0], v[:, 1]) > 0.999 * r))
    assert middle.size > 100
    k1, k2, d1 = paraboloid_curvatures(v, n, middle[::7])
    np.testing.assert_allclose(k1, 1 / r, rtol=1e-2)
    np.testing.assert_allclose(k2, 0.0, atol=0.01 / r)
    # the direction of k1 goes round the cylinder: orthogonal to its axis
    assert np.max(np.abs(d1[:, 2])) < 0.05


def test_torus_curvatures():
    R, r = 0.04, 0.015
    m = torus(R, r)
    v = m.vertices
    n = vertex_normals(v, m.faces)
    sample = np.arange(0, len(v), 53)
    k1, k2, _ = paraboloid_curvatures(v, n, sample)
    # tube angle from the distance to the ring's centre line
    rho = np.hypot(v[sample, 0], v[sample, 1])
    cos_v = (rho - R) / r
    ring = cos_v / (R + r * cos_v)
    exact = np.sort(np.column_stack([np.full_like(ring, 1 / r), ring]), axis=1)[:, ::-1]
    np.testing.assert_allclose(k1, exact[:, 0], rtol=1e-2, atol=0.3)
    np.testing.assert_allclose(k2, exact[:, 1], rtol=2e-2, atol=0.5)


def test_adaptive_sampling_is_seeded_and_denser_where_the_normal_turns():
    m = blob(subdivisions=4)
    v, f = m.vertices, m.faces
    n = vertex_normals(v, f)
    a = adaptive_sample(v, f, n, MeshModelConfig(seed=3))
    b = adaptive_sample(v, f, n, MeshModelConfig(seed=3))
    c = adaptive_sample(v, f, n, MeshModelConfig(seed=4))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    # the bumpy blob needs more samples than a sphere of the same connectivity
    s = sphere(0.03, subdivisions=4)
    n_sphere = len(adaptive_sample(s.vertices, s.faces, vertex_normals(s.vertices, s.faces)))
    assert len(a) > n_sphere


def test_closest_points_exact():
    rng = np.random.default_rng(0)
    a, b, c = (rng.normal(size=(500, 3)) for _ in range(3))
    p = rng.normal(size=(500, 3)) * 2
    q = closest_point_on_triangles(p, a, b, c)
    # q lies in the triangle and no sampled point of the triangle is closer
    w = rng.dirichlet(np.ones(3), size=(500, 2000))
    inside = w[..., :1] * a[:, None] + w[..., 1:2] * b[:, None] + w[..., 2:] * c[:, None]
    brute = np.min(np.linalg.norm(inside - p[:, None], axis=-1), axis=1)
    d = np.linalg.norm(q - p, axis=1)
    assert np.all(d <= brute + 1e-12)


def test_mesh_distance_is_exact_near_the_surface():
    m = blob(subdivisions=3)
    dist = MeshDistance(m.vertices, m.faces)
    rng = np.random.default_rng(1)
    p = m.vertices[rng.integers(len(m.vertices), size=200)] + rng.normal(scale=2e-3, size=(200, 3))
    d, _q, _ = dist.closest(p)
    tri = m.vertices[m.faces]
    brute = closest_point_on_triangles(
        p[:, None], tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
    )
    d_brute = np.min(np.linalg.norm(brute - p[:, None], axis=-1), axis=1)
    np.testing.assert_allclose(d, d_brute, atol=1e-12)
    n = vertex_normals(m.vertices, m.faces)
    off = m.vertices[:100] + 1e-3 * np.array([[1.0], [-1.0]])[:, None] * n[:100]
    s = dist.signed(off.reshape(-1, 3)).reshape(2, 100)
    assert np.all(s[0] > 0) and np.all(s[1] < 0)


def test_distance_field_agrees_with_exact_distance_in_its_band():
    model = MeshModel("blob", blob())
    rng = np.random.default_rng(2)
    v = model.vertices[rng.integers(len(model.vertices), size=400)]
    p = v + rng.normal(scale=1e-3, size=v.shape)
    exact = model.distance.signed(p)
    approx = model.distance_field(p)
    near = np.abs(exact) < 2e-3
    assert np.max(np.abs(approx[near] - exact[near])) < 0.05e-3
    value, grad = model.distance_field.value_and_gradient(p)
    # gradient against central differences of the interpolant, away from cell faces
    # (trilinear interpolation is only piecewise smooth)
    h = 1e-7
    cell = (p - model.distance_field.origin) / model.distance_field.voxel
    inner = np.all(np.abs(cell - np.round(cell)) > 1e-3, axis=1)
    p, value, grad = p[inner], value[inner], grad[inner]
    approx = approx[inner]
    fd = np.stack(
        [
            (model.distance_field(p + h * e) - model.distance_field(p - h * e)) / (2 * h)
            for e in np.eye(3)
        ],
        axis=-1,
    )
    np.testing.assert_allclose(grad, fd, atol=1e-3)
    np.testing.assert_allclose(value, approx, rtol=1e-6, atol=1e-9)


def test_only_what_cannot_be_a_model_is_refused_with_a_clear_message():
    m = blob(subdivisions=4)
    with pytest.raises(InvalidModel, match="millimetres"):
        prepare_mesh(trimesh.Trimesh(m.vertices * 1000, m.faces), "cat")
    with pytest.raises(InvalidModel, match="non-empty"):
        prepare_mesh(trimesh.Trimesh(), "empty")
    nan = m.vertices.copy()
    nan[5] = np.nan
    with pytest.raises(InvalidModel, match="1 vertices hold NaN"):
        prepare_mesh(trimesh.Trimesh(nan, m.faces, process=False), "nan")
    flat = m.vertices * [1.0, 1.0, 0.0]
    with pytest.raises(InvalidModel, match="flat"):
        prepare_mesh(trimesh.Trimesh(flat, m.faces, process=False), "flat")
    line = np.repeat(m.vertices[:1], len(m.vertices), axis=0)
    line[:, 0] += np.linspace(0, 0.05, len(line))
    with pytest.raises(InvalidModel, match="degenerate"):
        prepare_mesh(trimesh.Trimesh(line, m.faces, process=False), "line")


def test_open_and_multi_component_meshes_are_kept_and_reported():
    m = blob(subdivisions=4)
    two = trimesh.util.concatenate([m, m.copy().apply_translation([0.2, 0, 0])])
    kept, report = prepare_mesh(two, "pair")
    assert report.components == 2 and report.closed and len(kept.faces) == len(two.faces)
    # a cap cut away: the hole stays open, the normals point out of the object
    keep = m.triangles_center[:, 2] < 0.5 * m.vertices[:, 2].max()
    cut = trimesh.Trimesh(m.vertices, m.faces[keep])
    cut.invert()  # wound inward, as some exporters do
    model = MeshModel("cut", cut)
    assert not model.report.closed and model.report.open_edges > 0
    assert model.report.turned_outward == 1
    centre = m.vertices.mean(axis=0)
    outward = np.einsum("ij,ij->i", model.normals, model.vertices - centre)
    assert np.mean(outward > 0) > 0.99
    assert any("holes kept open" in n for n in model.report.notes)


def test_seams_are_merged_and_reported():
    m = sphere(0.03, subdivisions=4)
    # unshare every vertex: the surface is open until the seam vertices are merged
    tri = m.vertices[m.faces].reshape(-1, 3)
    split = trimesh.Trimesh(tri, np.arange(len(tri)).reshape(-1, 3), process=False)
    assert not split.is_watertight
    fixed, report = prepare_mesh(split, "split")
    assert fixed.is_watertight and len(fixed.vertices) == len(m.vertices)
    assert report.merged_vertices == len(tri) - len(m.vertices) and report.closed


def test_a_low_poly_mesh_is_refined_and_a_huge_one_simplified_with_its_loss():
    coarse = trimesh.creation.icosphere(subdivisions=1, radius=0.03)  # 42 vertices
    refined, report = prepare_mesh(coarse, "low poly")
    assert report.split_edges and refined.edges_unique_length.max() <= 1.5e-3 + 1e-12
    assert report.closed and report.components == 1
    fine = trimesh.creation.icosphere(subdivisions=6, radius=0.03)  # 81920 faces
    simplified, report = prepare_mesh(fine, "fine", max_faces=20_000)
    mean, largest = report.simplification_error_m
    assert len(simplified.faces) <= 20_000 and 0 < mean < 0.01e-3 and largest < 0.1e-3
    assert any("simplified from 81920" in n for n in report.notes)


def test_database_holds_each_distance_field_once():
    from recognition.surfaces.database import ModelDatabase

    models = {
        "blob": MeshModel("blob", blob(subdivisions=3)),
        "ball": MeshModel("ball", sphere(0.02, 3)),
    }
    own = {name: m.distance_field.values.copy() for name, m in models.items()}
    stack = ModelDatabase(models).field_stack
    for name, m in models.items():
        assert np.shares_memory(m.distance_field.values, stack.values)
        assert not m.distance_field.values.flags.writeable
        np.testing.assert_array_equal(m.distance_field.values, own[name])
    other = MeshModel("other ball", sphere(0.025, 3))
    with pytest.raises(ValueError, match="not this model's grid"):
        models["ball"].share_distance_field(other.distance_field)


def test_field_stack_reads_each_field_as_the_field_itself():
    from recognition.surfaces.distance import FieldStack

    models = [MeshModel("blob", blob(subdivisions=4)), MeshModel("sphere", sphere(0.02, 4))]
    stack = FieldStack.of([m.distance_field for m in models])
    rng = np.random.default_rng(4)
    for k, m in enumerate(models):
        p = m.vertices[rng.integers(len(m.vertices), size=(6, 30))]
        p = p + rng.normal(scale=1.5e-3, size=p.shape)
        p[0, 0] = [1.0, 1.0, 1.0]  # off the grid: +band, no gradient
        which = np.full(6, k)
        field = m.distance_field
        np.testing.assert_allclose(stack(p, which), field(p), atol=1e-9)
        value, grad = stack.value_and_gradient(p, which)
        v_ref, g_ref = field.value_and_gradient(p)
        np.testing.assert_allclose(value, v_ref, atol=1e-9)
        np.testing.assert_allclose(grad, g_ref, atol=1e-5)
        assert value[0, 0] == field.band and np.all(grad[0, 0] == 0)
        # screening: patterns placed by frames, nearest voxel
        frames = np.repeat(np.eye(3)[None], 6, axis=0)
        near = stack.nearest_in_frames(which, frames, np.zeros((6, 3)), p)
        np.testing.assert_allclose(near[0], field.nearest(p), atol=1e-9)
        paired = stack.nearest_in_frames(which, frames, np.zeros((6, 3)), p, paired=True)
        np.testing.assert_allclose(paired, field.nearest(p), atol=1e-9)
        # turned frames and shifted origins place the pattern where the field reads it
        turned = rotation_from_vector(rng.normal(size=(6, 3)))
        origins = rng.normal(scale=2e-3, size=(6, 3))
        local = np.einsum("cji,cpj->cpi", turned, p - origins[:, None, :])  # frames^T (p - o)
        placed = stack.nearest_in_frames(which, turned, origins, local, paired=True)
        assert np.mean(placed == field.nearest(p)) > 0.99  # half-way points may round apart
    # a point that is not a number reads as off the grid, in every lookup
    bad = np.full((1, 1, 3), np.nan)
    assert stack(bad, [0])[0, 0] == models[0].distance_field.band
    assert np.all(stack.value_and_gradient(bad, [0])[1] == 0)
    assert np.isfinite(stack.nearest_in_frames([0], np.eye(3)[None], np.zeros((1, 3)), bad)).all()


def test_rigid_normal_equations_are_those_of_the_pose_jacobian():
    from recognition.rigid import cross
    from recognition.surfaces.field_kernels import rigid_normal_equations

    rng = np.random.default_rng(2)
    X = rng.normal(scale=0.01, size=(5, 12, 3))
    r = rng.normal(scale=1e-4, size=(5, 12))
    g = rng.normal(size=(5, 12, 3))
    clip = np.full((5, 12), 1.2e-4)
    clip[:, -2:] = np.inf  # points never clipped
    c = X.mean(axis=1, keepdims=True)
    J = np.concatenate([cross(X - c, g), g], axis=-1)  # rotation about c, then translation
    inlier = np.abs(r) <= clip
    J, r_in = np.where(inlier[..., None], J, 0.0), np.where(inlier, r, 0.0)
    H, b = rigid_normal_equations(X, r, g, clip)
    np.testing.assert_allclose(H, np.swapaxes(J, 1, 2) @ J, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(b, np.einsum("kpi,kp->ki", J, r_in), rtol=1e-12, atol=1e-20)
    assert 0 < inlier.mean() < 1  # the clip leaves some residuals out
