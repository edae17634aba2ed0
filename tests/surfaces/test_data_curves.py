"""DataCurves: validation with typed errors that name the problem, transforms, .npz files."""

import numpy as np
import pytest

from recognition.errors import DegenerateGeometry, InvalidCurveData, RecognitionError
from recognition.surfaces.data_curves import DataCurves, closest_points_between_polylines


def bowl_curve(angle, n=21, half=5e-3, offset=(0.0, 0.0, 0.0)):
    """A curve through the origin on z = -(x^2 + y^2) / (2 r), r = 20 mm, metres."""
    t = np.linspace(-half, half, n)[:, None]
    d = np.array([np.cos(angle), np.sin(angle), 0.0])
    return t * d + np.column_stack([0 * t, 0 * t, -(t**2) / 0.04]) + np.asarray(offset)


def three(**kwargs):
    return tuple(bowl_curve(a, **kwargs) for a in (0.0, np.pi / 3, 2 * np.pi / 3))


def test_valid_curves_meet_at_the_common_point():
    curves = DataCurves(three(), approach=[0, 0, -2.0])
    np.testing.assert_allclose(curves.intersection, 0, atol=1e-12)
    assert curves.gap_m < 1e-12
    assert curves.points.shape == (63, 3) and curves.n_points == 63
    np.testing.assert_allclose(curves.approach, [0, 0, -1])
    with pytest.raises(ValueError):  # read-only arrays
        curves.curves[0][0, 0] = 1.0


def test_fewer_than_three_curves():
    with pytest.raises(InvalidCurveData, match=r"expected three data curves.*got 2"):
        DataCurves(three()[:2])


def test_curves_that_do_not_meet():
    a, b, c = three()
    lifted = c + np.array([0.0, 0.0, 2e-3])
    with pytest.raises(InvalidCurveData, match=r"do not meet at one point.*2 mm apart"):
        DataCurves((a, b, lifted))
    # within a looser tolerance they do
    gap = DataCurves((a, b, lifted), meet_tolerance_m=3e-3).gap_m
    assert gap == pytest.approx(2e-3, rel=1e-3)


def test_nan_and_infinite_coordinates():
    a, b, c = three()
    bad = a.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InvalidCurveData, match="curve 0 has NaN"):
        DataCurves((bad, b, c))
    bad[3, 1] = np.inf
    with pytest.raises(InvalidCurveData, match="NaN or infinite"):
        DataCurves((bad, b, c))


def test_malformed_curves():
    a, b, c = three()
    with pytest.raises(InvalidCurveData, match=r"curve 1 must be an \(n, 3\) array"):
        DataCurves((a, b[:, :2], c))
    with pytest.raises(InvalidCurveData, match="curve 2 has 4 points; expected at least 5"):
        DataCurves((a, b, c[8:12]))
    repeated = np.insert(a, 5, a[5], axis=0)
    with pytest.raises(InvalidCurveData, match="curve 0 repeats a point"):
        DataCurves((repeated, b, c))
    with pytest.raises(InvalidCurveData, match="approach"):
        DataCurves((a, b, c), approach=[0.0, 0.0, 0.0])


def test_tangents_that_do_not_span_a_plane():
    """Two curves with the same tangent at p but different sampling planes."""
    a = bowl_curve(0.0)
    tilted = a.copy()
    tilted[:, 1] = 0.5 * tilted[:, 2]  # same tangent (x) at p, plane tilted about x
    with pytest.raises(DegenerateGeometry, match="curves 0 and 1 have parallel tangents"):
        DataCurves((a, tilted, bowl_curve(np.pi / 2)))


def test_two_identical_sampling_planes():
    """Two traces in the plane y = 0 through p (different shapes, same plane)."""
    a, b, _ = three()
    flatter = a.copy()
    flatter[:, 2] *= 0.5
    with pytest.raises(DegenerateGeometry, match="curves 0 and 2 lie in the same sampling plane"):
        DataCurves((a, b, flatter))


def test_errors_share_the_library_base_class():
    with pytest.raises(RecognitionError):
        DataCurves(three()[:1])


def test_transformed_moves_points_intersection_and_approach():
    rng = np.random.default_rng(1)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = q, [0.1, -0.2, 0.3]
    curves = DataCurves(three(offset=(0.01, 0.02, 0.03)), approach=[0, 0, -1.0])
    moved = curves.transformed(T)
    np.testing.assert_allclose(moved.intersection, q @ curves.intersection + T[:3, 3], atol=1e-12)
    np.testing.assert_allclose(moved.approach, q @ curves.approach, atol=1e-12)
    np.testing.assert_allclose(moved.points, curves.points @ q.T + T[:3, 3], atol=1e-12)


def test_npz_round_trip(tmp_path):
    curves = DataCurves(three(), meet_tolerance_m=2e-3, approach=[0.0, 0.0, -1.0])
    path = curves.save(tmp_path / "sub" / "curves.npz")
    loaded = DataCurves.load(path)
    for a, b in zip(curves.curves, loaded.curves, strict=True):
        np.testing.assert_array_equal(a, b)
    assert loaded.meet_tolerance_m == 2e-3
    np.testing.assert_array_equal(loaded.approach, curves.approach)
    plain = DataCurves(three()).save(tmp_path / "plain.npz")
    assert DataCurves.load(plain).approach is None
    assert list(tmp_path.glob("**/*.tmp")) == []


def test_loading_a_bad_file_is_a_typed_error(tmp_path):
    path = tmp_path / "bad.npz"
    path.write_bytes(b"not an npz file")
    with pytest.raises(InvalidCurveData, match="cannot read data curves"):
        DataCurves.load(path)
    with pytest.raises(InvalidCurveData, match="cannot read data curves"):
        DataCurves.load(tmp_path / "missing.npz")
    objects = tmp_path / "objects.npz"
    np.savez(objects, curve_0=np.array([None, 1], dtype=object))
    with pytest.raises(InvalidCurveData, match="cannot read data curves"):
        DataCurves.load(objects)


def test_closest_points_between_crossing_segments():
    a = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    b = np.array([[0.25, -1.0, 0.5], [0.25, 1.0, 0.5]])
    pa, pb, d = closest_points_between_polylines(a, b)
    np.testing.assert_allclose(pa, [0.25, 0.0, 0.0])
    np.testing.assert_allclose(pb, [0.25, 0.0, 0.5])
    assert d == pytest.approx(0.5)


def bowl_normals(curve):
    """Outward unit normals of z = -(x^2 + y^2) / 0.04 at the curve's points."""
    n = np.column_stack([curve[:, 0] / 0.02, curve[:, 1] / 0.02, np.ones(len(curve))])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_normals_are_validated_made_unit_moved_and_saved(tmp_path):
    curves = three()
    normals = tuple(3.0 * bowl_normals(c) for c in curves)
    data = DataCurves(curves, normals=normals)
    np.testing.assert_allclose(np.linalg.norm(np.concatenate(data.normals), axis=1), 1.0)
    with pytest.raises(InvalidCurveData, match="one normal array per curve"):
        DataCurves(curves, normals=normals[:2])
    with pytest.raises(InvalidCurveData, match="must have the curve's shape"):
        DataCurves(curves, normals=(normals[0][:-1], *normals[1:]))
    bad = normals[0].copy()
    bad[3] = 0.0
    with pytest.raises(InvalidCurveData, match="finite non-zero"):
        DataCurves(curves, normals=(bad, *normals[1:]))
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = q, [0.1, -0.2, 0.3]
    moved = data.transformed(T)
    for a, b in zip(data.normals, moved.normals, strict=True):
        np.testing.assert_allclose(b, a @ q.T, atol=1e-12)
    loaded = DataCurves.load(data.save(tmp_path / "normals.npz"))
    for a, b in zip(data.normals, loaded.normals, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-15)
    assert DataCurves.load(DataCurves(curves).save(tmp_path / "none.npz")).normals is None


def test_damaged_or_foreign_curve_files_are_typed_errors(tmp_path):
    path = DataCurves(three(), approach=[0.0, 0.0, -1.0]).save(tmp_path / "c.npz")
    data = path.read_bytes()
    (tmp_path / "truncated.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidCurveData, match="cannot read data curves"):
        DataCurves.load(tmp_path / "truncated.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["curve_1"] = arrays["curve_1"] * 1.001  # edited without its digest
    np.savez(tmp_path / "edited.npz", **arrays)
    with pytest.raises(InvalidCurveData, match="damaged"):
        DataCurves.load(tmp_path / "edited.npz")
    np.savez(tmp_path / "two.npz", curve_0=three()[0], curve_1=three()[1])
    with pytest.raises(InvalidCurveData, match="holds 2 data curves"):
        DataCurves.load(tmp_path / "two.npz")
    # curves written by another tool (no digest) are read
    np.savez(tmp_path / "foreign.npz", **{f"curve_{i}": c for i, c in enumerate(three())})
    assert DataCurves.load(tmp_path / "foreign.npz").n_points == 63
