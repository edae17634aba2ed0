"""Registration of data curves on mesh models and recognition over a small database."""

import numpy as np
import pytest
from testing_meshes import blob, ellipsoid, torus

from recognition.errors import InvalidCurveData, InvalidModel
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration import register
from recognition.synthetic import mesh_data_curves


@pytest.fixture(scope="module")
def models():
    return {
        "blob": MeshModel("blob", blob()),
        "ellipsoid": MeshModel("ellipsoid", ellipsoid()),
        "torus": MeshModel("torus", torus(sections=(200, 80))),
    }


@pytest.fixture(scope="module")
def database(models):
    return ModelDatabase(models)


def _curves(model, vertex, seed, noise=0.0, **kw):
    return mesh_data_curves(
        model.mesh,
        vertex,
        normal=model.normals[vertex],
        n_points=41,
        spacing_m=0.4e-3,
        noise_std_m=noise,
        rng=np.random.default_rng(seed),
        **kw,
    )


@pytest.mark.parametrize("vertex", [100, 2500, 7000])
def test_fast_registration_recovers_the_pose_from_noise_free_curves(models, vertex):
    model = models["blob"]
    synthetic = _curves(model, vertex, seed=vertex)
    result = register(model, synthetic.curves)
    # the distance field it is refined on is exact to a few micrometres at this resolution
    assert result.error_m < 1e-5
    np.testing.assert_allclose(result.location, synthetic.point_in_model, atol=0.05e-3)
    np.testing.assert_allclose(result.T_model_from_data, synthetic.T_model_from_data, atol=5e-3)


def test_registration_is_unchanged_by_a_rigid_motion_of_the_data(models):
    model = models["blob"]
    synthetic = _curves(model, 4000, seed=1, noise=0.02e-3)
    a = register(model, synthetic.curves)
    rng = np.random.default_rng(5)
    from recognition.synthetic import random_rigid_transform

    T = random_rigid_transform(rng)
    b = register(model, synthetic.curves.transformed(T))
    np.testing.assert_allclose(b.location, a.location, atol=0.05e-3)
    assert abs(b.error_m - a.error_m) < 1e-6


@pytest.mark.parametrize("mode", ["thesis", "icp-baseline"])
def test_other_modes_register_on_the_right_place(models, mode):
    from dataclasses import replace

    from recognition.surfaces.registration import RegistrationConfig

    model = models["blob"]
    synthetic = _curves(model, 2500, seed=2500, noise=0.01e-3)
    config = replace(RegistrationConfig(), thesis_max_candidates=3)
    result = register(model, synthetic.curves, mode=mode, config=config)
    assert np.isfinite(result.error_m)
    assert np.linalg.norm(result.location - synthetic.point_in_model) < 1.5e-3


def test_unknown_mode_is_named(models):
    synthetic = _curves(models["blob"], 100, seed=0)
    with pytest.raises(InvalidCurveData, match="unknown registration mode 'slow'"):
        register(models["blob"], synthetic.curves, mode="slow")


def test_small_database_recognises_each_model(database, models):
    for name, model in models.items():
        vertex = int(np.argmax(model.vertices[:, 0]))  # a well-curved, unambiguous place
        synthetic = _curves(model, vertex, seed=3, noise=0.01e-3)
        result = database.recognize(synthetic.curves)
        assert result.name == name
        assert result.ranking[0][0] == name
        assert result.margin_m > 0
        assert set(result.timings_s) == set(models)


def test_curves_that_fit_no_model_are_not_recognised(database):
    # a flat patch: no model has a curvature within delta of zero on all three curves
    t = np.linspace(-0.01, 0.01, 41)
    curves = DataCurves(
        tuple(np.stack([np.cos(a) * t, np.sin(a) * t, 0 * t], 1) for a in (0.0, 1.0, 2.0)),
        approach=np.array([0, 0, -1.0]),
    )
    result = database.recognize(curves)
    assert result.name is None
    assert all(not np.isfinite(e) or e > 0.5e-3 for _, e in result.ranking)


def test_database_round_trip(tmp_path, database, models):
    database.save(tmp_path / "db")
    loaded = ModelDatabase.load(tmp_path / "db")
    assert loaded.names == database.names
    for name in models:
        a, b = database[name], loaded[name]
        np.testing.assert_array_equal(a.table.vertex, b.table.vertex)
        np.testing.assert_allclose(a.table.k1, b.table.k1)
        np.testing.assert_allclose(a.distance_field.values, b.distance_field.values)
        assert a.hash == b.hash
    synthetic = _curves(models["blob"], 2500, seed=9, noise=0.01e-3)
    r1, r2 = database.recognize(synthetic.curves), loaded.recognize(synthetic.curves)
    assert r1.name == r2.name == "blob"
    np.testing.assert_allclose(r1.location, r2.location, atol=1e-5)


def test_corrupt_or_stale_database_is_refused(tmp_path, database):
    directory = database.save(tmp_path / "db")
    (directory / "blob.npz").write_bytes(b"not a zip file")
    with pytest.raises(InvalidModel, match="cannot read"):
        ModelDatabase.load(directory)
    with pytest.raises(InvalidModel, match="no readable model database"):
        ModelDatabase.load(tmp_path / "missing")
    manifest = directory / "manifest.json"
    manifest.write_text(manifest.read_text().replace('"format": 3', '"format": 1'))
    with pytest.raises(InvalidModel, match="rebuild"):
        ModelDatabase.load(directory)
