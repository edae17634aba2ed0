"""Ring descriptors (mean height and anisotropy on rings about p) and the database-wide
candidate budget they rank for."""

from dataclasses import replace

import numpy as np
import pytest
from testing_meshes import blob, ellipsoid, sphere

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration import FastConfig, data_geometry
from recognition.surfaces.rings import (
    ALIAS_HARMONICS,
    MAX_COST,
    RADII_M,
    alias_gains,
    data_ring_descriptors,
    model_ring_descriptors,
    ring_invariants,
    ring_scores,
)
from recognition.synthetic import SyntheticCurves, mesh_data_curves


@pytest.fixture(scope="module")
def ball():
    return MeshModel("sphere", sphere(radius=0.03))


def _sphere_height(radius: float, rho: float) -> float:
    """Height over the tangent plane of a sphere at tangent distance rho (outward +)."""
    return -(radius - np.sqrt(radius**2 - rho**2))


def test_harmonic_fit_recovers_mean_and_anisotropy():
    theta = np.linspace(0, 2 * np.pi, 6, endpoint=False) + 0.3
    height = 0.4 + 0.02 * np.cos(theta) + 0.1 * np.cos(2 * (theta - 0.7))
    np.testing.assert_allclose(ring_invariants(theta, height), [0.4, 0.1], atol=1e-12)
    assert np.isnan(ring_invariants(theta[:4], height[:4])).all()


def test_a_sphere_s_rings_are_its_exact_heights(ball):
    expected = [_sphere_height(0.03, rho) for rho in RADII_M]
    np.testing.assert_allclose(ball.rings[:, :, 0].mean(axis=0), expected, atol=0.02e-3)
    assert np.abs(ball.rings[:, :, 1]).max() < 0.03e-3  # isotropic
    assert np.abs(ball.rings[:, :, 2:]).max() < 0.03e-3  # no higher harmonics


def test_six_samples_alias_the_fourth_and_sixth_harmonics_by_their_gains():
    """At six equally spaced angles a ring's sixth harmonic is read as mean height and its
    fourth as anisotropy, each whole (gain 1), the others not at all; with the planes 10
    degrees apart the fit takes several times more; fewer than five angles give none."""
    theta = np.linspace(0, 2 * np.pi, 6, endpoint=False) + 0.3
    gains = alias_gains(theta)  # rows: a0, anisotropy; columns: harmonics 3, 4, 5, 6
    np.testing.assert_allclose(gains, [[0, 0, 0, 1], [0, 1, 0, 0]], atol=1e-12)
    close = np.deg2rad([0.0, 180.0, 10.0, 190.0, 20.0, 200.0])
    assert (alias_gains(close)[:, 1:].max(axis=1) > 5.0).all()
    assert np.isnan(alias_gains(theta[:4])).all()


@pytest.mark.parametrize("arms", [5, 6])
def test_alias_gains_are_the_spread_of_the_invariants_over_the_harmonic_s_phase(arms):
    """At irregular angles, a harmonic of RMS R moves a0 by R times the first gain (RMS
    over its phase) and the anisotropy of a clearly anisotropic ring by R times the
    second (RMS over its phase and the direction of (a2, b2))."""
    theta = np.sort(np.random.default_rng(arms).uniform(0, 2 * np.pi, arms))
    gains = alias_gains(theta)
    rms, anisotropy = 1e-3, 1.0
    psi = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    beta = np.linspace(0, np.pi, 30, endpoint=False)
    for j, k in enumerate(ALIAS_HARMONICS):
        wave = np.sqrt(2) * rms * np.cos(k * theta[None] + psi[:, None])  # (psi, arms)
        a0 = np.array([ring_invariants(theta, w)[0] for w in wave])
        assert np.sqrt(np.mean(a0**2)) == pytest.approx(gains[0, j] * rms, rel=1e-6, abs=1e-12)
        moved = [
            ring_invariants(theta, anisotropy * np.cos(2 * (theta - b)) + w)[1] - anisotropy
            for b in beta
            for w in wave
        ]
        assert np.sqrt(np.mean(np.square(moved))) == pytest.approx(gains[1, j] * rms, rel=0.01)


def _rings_of_exact_curves(model, vertex, n_points):
    """The data's rings of exact curves (0.4 mm apart) through ``vertex``."""
    curves = mesh_data_curves(
        model.mesh,
        vertex,
        normal=model.normals[vertex],
        n_points=n_points,
        spacing_m=0.4e-3,
        noise_std_m=0.0,
        transform=False,
    ).curves
    return data_ring_descriptors(curves, data_geometry(curves))


def test_data_rings_match_the_model_s_at_the_true_place(ball):
    data = _rings_of_exact_curves(ball, 100, 41)
    expected = [_sphere_height(0.03, rho) for rho in RADII_M]
    # arms 8 mm long reach the 3 and 6 mm rings
    np.testing.assert_allclose(data[:, 0], expected, atol=0.02e-3)
    # arms of 4 mm, the 3 mm ring only
    assert np.isnan(_rings_of_exact_curves(ball, 100, 21)[1:]).all()


def test_scores_rank_the_matching_surface_first_and_bound_a_spoiled_ring():
    # the data's rings at six equally spaced angles: the sixth harmonic goes into a0,
    # the fourth into the anisotropy
    gains = [0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0]
    data = np.array([[-0.15e-3, 0.0, *gains], [-0.6e-3, 0.0, *gains], [np.nan] * 10])
    smooth = [0.0] * 4
    models = np.array(
        [
            [[-0.15e-3, 0.0, *smooth], [-0.6e-3, 0.0, *smooth], [-1.7e-3, 0.0, *smooth]],
            [[-0.30e-3, 0.0, *smooth], [-1.2e-3, 0.0, *smooth], [-3.4e-3, 0.0, *smooth]],
            [[-0.15e-3, 0.0, *smooth], [np.nan] * 6, [-1.7e-3, 0.0, *smooth]],
            [[-0.15e-3, 0.0, *smooth], [0.6e-3, 0.0, *smooth], [-1.7e-3, 0.0, *smooth]],
            # twice as curved, but its 6 mm ring's sixth harmonic (RMS 0.6 mm) could
            # make up the difference in a0: it counts one standard unit there
            [[-0.30e-3, 0.0, *smooth], [-1.2e-3, 0.0, 0, 0, 0, 0.6e-3], [-3.4e-3, 0.0, *smooth]],
            # a fifth harmonic goes into neither invariant at these angles
            [[-0.30e-3, 0.0, *smooth], [-1.2e-3, 0.0, 0, 0, 0.6e-3, 0], [-3.4e-3, 0.0, *smooth]],
        ],
        np.float32,
    )
    scores = ring_scores(models, data)
    assert scores[0] == pytest.approx(0.0, abs=1e-6)
    assert scores[0] < scores[2] < scores[1]
    assert scores[3] == pytest.approx(MAX_COST, rel=1e-6)
    assert scores[4] == pytest.approx(scores[1] - MAX_COST + 1.0, rel=0.05)
    assert scores[5] == pytest.approx(scores[1], rel=1e-6)


def _blob_curves(model: MeshModel, noise_std_m: float, seed: int) -> SyntheticCurves:
    """Three curves of 41 points 0.4 mm apart through vertex 2500 of the blob."""
    vertex = 2500
    return mesh_data_curves(
        model.mesh,
        vertex,
        normal=model.normals[vertex],
        n_points=41,
        spacing_m=0.4e-3,
        rng=np.random.default_rng(seed),
        noise_std_m=noise_std_m,
    )


def test_a_small_budget_still_recognises_and_locates():
    """With a candidate budget of a few hundred rows across the database (of a few
    thousand within the tolerance), the rings keep the true place among them."""
    models = {
        "sphere": MeshModel("sphere", sphere(radius=0.03)),
        "ellipsoid": MeshModel("ellipsoid", ellipsoid()),
        "blob": MeshModel("blob", blob()),
    }
    database = ModelDatabase(models).prepare()
    synthetic = _blob_curves(models["blob"], noise_std_m=0.01e-3, seed=2)
    default = FastConfig()
    tight = replace(
        default,
        search=replace(default.search, candidate_budget=300, screened_budget=64),
        fallbacks=(),
    )
    assert len(database.candidate_index.row) > 10 * 300
    result = database.recognize(synthetic.curves, tight)
    assert result.name == "blob"
    np.testing.assert_allclose(result.location, synthetic.point_in_model, atol=0.1e-3)


def test_an_arm_that_drops_over_an_edge_gives_no_ring_sample():
    """Three lines on a plane; one arm falls off a step 5.5 mm out: at the 6 mm ring
    that arm is steep and left out, so the ring is the plane's (height 0)."""
    s = np.linspace(-8e-3, 8e-3, 81)
    curves = []
    for angle in (0.0, np.pi / 3, 2 * np.pi / 3):
        c = np.stack([np.cos(angle) * s, np.sin(angle) * s, np.zeros_like(s)], axis=1)
        if angle == 0.0:
            c[:, 2] = np.where(s > 5.5e-3, -(s - 5.5e-3) * 4.0, 0.0)  # 76 degrees down
        curves.append(c)
    data_curves = DataCurves(tuple(curves), approach=np.array([0.0, 0.0, -1.0]))
    geometry = data_geometry(data_curves)
    rings = data_ring_descriptors(data_curves, geometry)
    assert abs(rings[1, 0]) < 1e-6 and abs(rings[1, 1]) < 1e-6


def test_lookup_scans_the_k1_window_and_keeps_what_a_full_scan_keeps():
    """The index is ordered by k1, so a lookup (4.7) scans only the rows whose k1 lies
    within the tolerance; its rows per model are those a scan of every row keeps, in
    ascending order, and the budget keeps the rows of least score."""
    models = {"ball": MeshModel("ball", sphere(radius=0.03)), "blob": MeshModel("blob", blob())}
    index = ModelDatabase(models).prepare().candidate_index
    assert np.all(np.diff(index.k1) >= 0)
    curves = _blob_curves(models["blob"], noise_std_m=0.0, seed=3).curves
    geometry = data_geometry(curves)
    rings = data_ring_descriptors(curves, geometry)
    fields = np.arange(2)
    tolerance = 8.0  # 1/m: a narrow window of the table
    chosen, matched = index.select(geometry, rings, tolerance, None, fields)
    within = np.hypot(index.k1 - geometry.k1, index.k2 - geometry.k2) < tolerance
    assert within.sum() < 0.5 * index.k1.size
    for field in fields:
        expected = np.sort(index.row[within & (index.owner == field)])
        np.testing.assert_array_equal(chosen[field], expected)
        assert matched[field] == (expected.size > 0)
    assert sum(c.size for c in chosen) > 0
    budget = 20
    kept, _ = index.select(geometry, rings, tolerance, budget, fields)
    assert sum(k.size for k in kept) == budget
    for field in fields:
        assert np.isin(kept[field], chosen[field]).all()
        assert np.all(np.diff(kept[field]) > 0)


def test_a_model_ring_stores_the_rms_of_its_fourth_harmonic():
    """A sphere whose radius varies near its pole as c rho^4 cos(4 phi) (0.05 mm at 6 mm
    from the pole): at the pole, the 6 mm ring's fourth harmonic has RMS 0.05 / sqrt 2 mm
    and its other harmonics little; the invariants are the sphere's."""
    import trimesh

    radius, rho6, bump = 0.03, 6.0e-3, 0.05e-3
    mesh = trimesh.creation.icosphere(subdivisions=6, radius=radius)
    x, y, z = mesh.vertices.T
    rho = np.hypot(x, y)
    wave = bump * (rho / rho6) ** 4 * np.cos(4 * np.arctan2(y, x)) * (z > 0)
    mesh = trimesh.Trimesh(mesh.vertices * (1 + wave / radius)[:, None], mesh.faces)
    model = MeshModel("bumped", mesh)
    rings = model_ring_descriptors(
        model.distance_field,
        np.array([[0.0, 0.0, radius]]),
        np.array([[0.0, 0, 1]]),
        np.array([[1.0, 0, 0]]),
    )[0]
    six = RADII_M.index(rho6)
    assert rings[six, 0] == pytest.approx(_sphere_height(radius, rho6), abs=5e-6)
    assert abs(rings[six, 1]) < 5e-6
    harmonics = dict(zip(ALIAS_HARMONICS, rings[six, 2:], strict=True))
    assert harmonics[4] == pytest.approx(bump / np.sqrt(2), rel=0.1)
    assert max(harmonics[3], harmonics[5], harmonics[6]) < 5e-6
