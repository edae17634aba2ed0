"""The plan: sampling planes, and p chosen or snapped onto the mesh."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tactile_sim.probing import ProbeScene, probe_object, sampling_planes


def test_sampling_planes_are_vertical_and_plane_angle_apart() -> None:
    planes = sampling_planes([0.4, 0.0, 0.05], 0.3, math.radians(60))
    assert len(planes) == 3
    for k, plane in enumerate(planes):
        np.testing.assert_allclose(plane.up_in_world, [0.0, 0.0, 1.0])
        assert plane.normal_in_world[2] == pytest.approx(0.0)
        yaw = math.atan2(plane.forward_in_world[1], plane.forward_in_world[0])
        assert yaw == pytest.approx(0.3 + k * math.radians(60))
        assert plane.distance([[0.4, 0.0, 0.05]])[0] == pytest.approx(0.0)


def test_given_point_is_snapped_to_the_model_and_probed(sphere_scene: ProbeScene) -> None:
    point = np.array([0.005, -0.004, 0.07])  # above the sphere, model frame
    session = probe_object("sphere", seed=1, n_points=5, point=point, probe_scene=sphere_scene)
    p = session.ground_truth.point_in_object
    assert np.linalg.norm(p - [0.0, 0.0, 0.033]) == pytest.approx(0.033, abs=10e-6)
    assert np.linalg.norm(session.curves.intersection - session.ground_truth.point_in_world) < (
        0.05e-3
    )


def test_point_on_the_underside_is_rejected(sphere_scene: ProbeScene) -> None:
    with pytest.raises(ValueError, match="upward-facing"):
        probe_object("sphere", seed=1, point=(0.0, 0.0, -0.01), probe_scene=sphere_scene)


def test_a_lowered_sphere_rests_where_it_first_touches(sphere_scene: ProbeScene) -> None:
    """Over the 33 mm sphere (resting on the table, its centre 33 mm up): the tip's centre
    comes to rest at R + r from the sphere's centre, its contact normal radial (to the
    facets, within 2 degrees); beyond the sphere it reaches the table."""
    r, R = 1e-3, 0.033
    x = np.array([0.0, 5e-3, 20e-3, 30e-3, 33.5e-3, 40e-3])
    starts = np.column_stack([0.40 + x, np.zeros_like(x), np.full_like(x, 0.08)])
    centres, normals, touched = sphere_scene.sphere_rests_in_world(starts, r)
    on = x < R + r
    np.testing.assert_array_equal(touched, on)
    height = R + np.sqrt((R + r) ** 2 - x[on] ** 2)
    np.testing.assert_allclose(centres[on, 2], height, atol=0.05e-3)
    radial = (centres[on] - [0.40, 0.0, R]) / (R + r)
    assert np.all(np.einsum("ij,ij->i", normals[on], radial) > math.cos(math.radians(2)))
    np.testing.assert_allclose(centres[~on, 2], r)


def test_sweeps_fit_counts_the_contacts_a_sweep_can_take(sphere_scene: ProbeScene) -> None:
    from tactile_sim.probing.plan import sweeps_fit

    top = np.array([0.40, 0.0, 0.066])
    yaws = np.radians([0.0, 60.0, 120.0])
    assert sweeps_fit(sphere_scene, top, yaws, 10e-3, 60.0) == 1.0
    # out to 31.8 mm each side, 0.6 mm apart: the contact normal tilts beyond 60 degrees
    # past 0.866 (R + r) = 29.0 mm from the top, at 2 x 5 of the 107 points of a sweep
    fit = sweeps_fit(sphere_scene, top, yaws, 31.8e-3, 60.0)
    offsets = np.arange(-31.8e-3, 31.8e-3 + 1e-9, 0.6e-3)
    expected = np.mean(np.abs(offsets) < math.sin(math.radians(60)) * 0.034)
    assert fit == pytest.approx(expected, abs=1.5 / len(offsets))
    assert fit < 1.0


def test_the_compiled_scene_is_cached_and_a_damaged_entry_compiled_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tactile_sim.objects.cache import ENV_ASSETS_DIR
    from tactile_sim.probing import build_probe_scene

    monkeypatch.setenv(ENV_ASSETS_DIR, str(tmp_path))
    first = probe_object("sphere", seed=3, n_points=5)
    (entry,) = (tmp_path / "scenes").glob("*.npz")
    size = entry.stat().st_size
    cached = probe_object("sphere", seed=3, n_points=5)
    for a, b in zip(first.curves.curves, cached.curves.curves, strict=True):
        np.testing.assert_array_equal(a, b)
    entry.write_bytes(entry.read_bytes()[:-100])  # truncated: compiled again, same scene
    again = build_probe_scene("sphere", seed=3, progress=False)
    np.testing.assert_array_equal(again.T_world_from_object, first.ground_truth.T_world_from_object)
    assert entry.stat().st_size == size
