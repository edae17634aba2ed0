"""Generated objects: seeded, watertight, sized like the catalog, distinct."""

from __future__ import annotations

import numpy as np
import pytest

from tactile_sim.objects.generated import (
    PART_EVERY,
    SIZE_RANGE_MM,
    generated_name,
    generated_recipe,
)
from tactile_sim.objects.meshing import MeshingSettings, build_mesh, mesh_problems
from tactile_sim.objects.recipe import recipe_to_dict

#: Coarse meshing: the checks need shape, not detail.
COARSE = MeshingSettings(coarse_cells=40)


def _coarse(index: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    recipe = generated_recipe(index, seed)
    recipe = type(recipe)(**{**recipe.__dict__, "target_vertices": 4000})
    built = build_mesh(recipe, COARSE)
    return built.vertices, built.faces


def test_same_seed_same_recipe_other_seed_other_recipe() -> None:
    assert recipe_to_dict(generated_recipe(5, 0)) == recipe_to_dict(generated_recipe(5, 0))
    assert recipe_to_dict(generated_recipe(5, 0)) != recipe_to_dict(generated_recipe(5, 1))
    assert recipe_to_dict(generated_recipe(5, 0)) != recipe_to_dict(generated_recipe(6, 0))


def test_names_and_kinds() -> None:
    assert generated_name(0) == "blob-000"
    assert generated_name(PART_EVERY - 1) == f"part-{PART_EVERY - 1:03d}"
    assert "CAD-like" in generated_recipe(PART_EVERY - 1).description


@pytest.mark.parametrize("index", range(12))
def test_meshes_are_watertight_single_bodies_of_the_catalog_size(index: int) -> None:
    vertices, faces = _coarse(index)
    assert mesh_problems(vertices, faces) == []
    size_mm = np.ptp(vertices, axis=0) * 1e3
    low, high = SIZE_RANGE_MM
    assert low - 1e-6 <= size_mm.max() <= high + 1e-6
    assert vertices[:, 2].min() == pytest.approx(0.0, abs=1e-9)  # resting on its base


def test_objects_are_distinct() -> None:
    """Twelve objects differ pairwise in size, volume or area by more than 2 %."""
    import trimesh

    def features(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        return np.array(
            [*np.sort(np.ptp(vertices, axis=0)), mesh.volume ** (1 / 3), mesh.area**0.5]
        )

    f = np.array([features(*_coarse(i)) for i in range(12)])
    for i in range(12):
        for j in range(i + 1, 12):
            assert np.abs(f[i] / f[j] - 1).max() > 0.02, (i, j)


def test_negative_index_or_seed_is_refused() -> None:
    with pytest.raises(ValueError, match="non-negative"):
        generated_recipe(-1)
