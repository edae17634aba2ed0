"""Convex decomposition: convex meshes, the cache key, cold builds, shipped hulls."""

from __future__ import annotations

from pathlib import Path
from typing import Never

import numpy as np
import pytest
import trimesh

from tactile_sim.collision import (
    ConvexParts,
    DecompositionConfig,
    convex_decomposition,
    decomposition,
    decomposition_key,
    hull_surface_deviation,
    load_solid,
    object_parts,
)
from tactile_sim.errors import InvalidMesh
from tactile_sim.objects import load_object, object_names
from tactile_sim.objects.cache import ENV_ASSETS_DIR


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


def test_convex_mesh_is_its_own_single_part() -> None:
    solid = load_solid("cylinder_2")
    parts = convex_decomposition(solid.mesh, name="cylinder_2", progress=False)
    assert parts.source == "convex" and parts.n_parts == 1
    accuracy = hull_surface_deviation(parts.parts, solid.mesh, n_samples=5000)
    assert accuracy.max_m < 1e-9


def test_decomposition_key_depends_on_mesh_and_parameters() -> None:
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


def test_decomposition_config_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="threshold"):
        DecompositionConfig(threshold=0.0)
    with pytest.raises(ValueError, match="preprocess_mode"):
        DecompositionConfig(preprocess_mode="maybe")


@pytest.mark.slow
def test_cold_build_is_cached_and_a_corrupt_cache_is_rebuilt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
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


def test_malformed_mesh_is_rejected() -> None:
    with pytest.raises(InvalidMesh, match="vertices"):
        convex_decomposition((np.zeros((2, 3)), np.zeros((1, 3), dtype=int)))


@pytest.mark.parametrize("name", object_names())
def test_catalog_hulls_are_shipped_so_a_warm_start_never_runs_coacd(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    def forbidden(*args: object, **kwargs: object) -> Never:
        raise AssertionError("CoACD ran on a warm start")

    monkeypatch.setattr(decomposition, "_run_coacd", forbidden)
    parts = object_parts(load_object(name), progress=False)
    assert isinstance(parts, ConvexParts)
    assert parts.source in ("shipped", "convex"), (
        f"{name}: the shipped hulls do not match the catalog mesh; rebuild them with "
        "tactile_sim.collision.build_shipped_hulls()"
    )
