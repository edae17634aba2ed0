"""A probing session with one gross outlier is still recognised and located; the point is named."""

import numpy as np
import pytest

from recognition import DataCurves
from recognition.rigid import apply_pose
from recognition.surfaces.registration import common_point
from tactile_sim.objects.database import catalog_database
from tactile_sim.probing import probe_object


@pytest.fixture(scope="module")
def cat_session():
    return probe_object("cat", seed=0, progress=False)


@pytest.mark.slow
@pytest.mark.parametrize("offset_m", [0.02, 0.1, 1.0])
def test_one_point_moved_along_its_normal_is_rejected(cat_session, offset_m):
    session = cat_session
    curves = [c.copy() for c in session.curves.curves]
    normals = session.curves.normals
    assert normals is not None
    k = 4  # a point of the second curve, away from p
    curves[1][k] += offset_m * normals[1][k]
    moved = DataCurves(tuple(curves), approach=session.curves.approach, normals=normals)
    result = catalog_database(progress=False).recognize(moved)
    assert result.name == "cat"
    T_object_from_world = np.linalg.inv(session.ground_truth.T_world_from_object)
    truth = apply_pose(T_object_from_world, common_point(moved)[None])[0]
    assert np.linalg.norm(result.location - truth) < 1e-3
    index = len(session.curves.curves[0]) + k
    assert index in result.outliers
    assert len(result.outliers) <= 2
