"""The object catalog: recipes, SDF primitives, meshing and the generated-mesh cache."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh
from testing_scripts import load_script

from tactile_sim.errors import AssetError, SimulationError, UnknownObject
from tactile_sim.objects import (
    MeshingSettings,
    ObjectModel,
    ObjectRecipe,
    build_mesh,
    load_catalog,
    load_object,
    load_object_recipe,
    load_or_build,
    meshing,
    object_names,
)
from tactile_sim.objects import catalog as catalog_module
from tactile_sim.objects.cache import ENV_ASSETS_DIR, generated_dir
from tactile_sim.objects.meshing import MeshBuild
from tactile_sim.objects.recipe import (
    Ellipsoid,
    HalfSpace,
    Tube,
    load_recipe,
    recipe_from_dict,
    recipe_to_dict,
)
from tactile_sim.objects.sdf import blend_margin, evaluate, rotation_matrix, sd_round_cones

#: Thesis Table 4.4: model -> (vertices, dimensions in mm as printed, largest first).
TABLE_4_4 = {
    "pear": (84656, (83.9, 62.6, 62.4)),
    "stone": (42777, (62.7, 56.3, 43.5)),
    "monkey": (75443, (80.0, 71.9, 51.5)),
    "bird": (63323, (78.6, 61.4, 55.9)),
    "dog": (67101, (90.3, 62.5, 43.2)),
    "frog": (91970, (79.4, 78.9, 58.5)),
    "cat": (64821, (71.9, 67.2, 53.5)),
    "snail": (101268, (94.8, 89.6, 52.2)),
    "fish": (71490, (90.5, 71.5, 61.4)),
    "elephant": (72665, (92.0, 62.1, 61.5)),
}
DIMENSION_RTOL = 0.01
VERTEX_RANGE = (42_000, 101_000)
#: Largest per-axis scale the generator may apply to a recipe's design.
MAX_FIT_DISTORTION = 0.10

#: Low-resolution vertex targets that still resolve each object's thinnest parts.
COARSE_VERTICES = {"snail": 8000}


@pytest.fixture(scope="session")
def catalog() -> dict[str, ObjectModel]:
    """All ten objects, built once per session if the cache is cold."""
    return load_catalog()


@pytest.fixture
def tmp_assets(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A fresh generated-assets directory for this test."""
    monkeypatch.setenv(ENV_ASSETS_DIR, str(tmp_path))
    return tmp_path


def coarse_recipe(name: str = "pear") -> ObjectRecipe:
    """A low-resolution variant of a catalog recipe, quick to build."""
    target = COARSE_VERTICES.get(name, 3000)
    return dataclasses.replace(load_object_recipe(name), target_vertices=target)


# --- catalog ----------------------------------------------------------------------------


def test_names_follow_table_4_4() -> None:
    assert object_names() == tuple(TABLE_4_4)


def test_catalog_has_every_object(catalog: dict[str, ObjectModel]) -> None:
    assert list(catalog) == list(object_names())
    assert all(model.name == name for name, model in catalog.items())


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_mesh_is_closed_single_component(catalog: dict[str, ObjectModel], name: str) -> None:
    mesh = catalog[name].mesh
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0
    labels = trimesh.graph.connected_component_labels(
        mesh.face_adjacency, node_count=len(mesh.faces)
    )
    assert labels.max() == 0
    assert meshing.mesh_problems(np.asarray(mesh.vertices), np.asarray(mesh.faces)) == []


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_vertex_count_in_range(catalog: dict[str, ObjectModel], name: str) -> None:
    n = len(catalog[name].mesh.vertices)
    assert VERTEX_RANGE[0] <= n <= VERTEX_RANGE[1]
    thesis_vertices = TABLE_4_4[name][0]
    clipped = min(max(thesis_vertices, VERTEX_RANGE[0]), VERTEX_RANGE[1])
    assert abs(n - clipped) / clipped < 0.10


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_dimensions_match_table_4_4(catalog: dict[str, ObjectModel], name: str) -> None:
    dims_mm = np.sort(catalog[name].dimensions_m * 1e3)[::-1]
    np.testing.assert_allclose(dims_mm, TABLE_4_4[name][1], rtol=DIMENSION_RTOL)


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_model_frame(catalog: dict[str, ObjectModel], name: str) -> None:
    """Metres, base on z = 0, bounding box centred on the z axis."""
    vertices = np.asarray(catalog[name].mesh.vertices)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    assert 0.03 < (hi - lo).max() < 0.1
    assert abs(lo[2]) < 1e-9
    np.testing.assert_allclose((lo + hi)[:2] / 2, 0.0, atol=1e-9)


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_recipe_designed_near_target_size(catalog: dict[str, ObjectModel], name: str) -> None:
    """The fit to Table 4.4 only fine-tunes the design (no visible stretching)."""
    fit = np.asarray(catalog[name].build.fit_scale)
    assert np.all(np.abs(fit - 1.0) < MAX_FIT_DISTORTION)


def test_unknown_object_lists_names() -> None:
    with pytest.raises(UnknownObject) as info:
        load_object("unicorn")
    message = str(info.value)
    assert "unicorn" in message
    for name in object_names():
        assert name in message
    assert isinstance(info.value, SimulationError)
    assert isinstance(info.value, KeyError)


def test_import_does_not_load_mujoco() -> None:
    code = (
        "import sys, tactile_sim, tactile_sim.objects; "
        "assert 'mujoco' not in sys.modules and 'dm_control' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


# --- recipes ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(TABLE_4_4))
def test_recipe_round_trips_through_json(name: str) -> None:
    recipe = load_object_recipe(name)
    assert recipe.name == name
    again = recipe_from_dict(json.loads(json.dumps(recipe_to_dict(recipe))))
    assert again == recipe
    assert again.content_hash() == recipe.content_hash()


def test_recipe_hash_follows_geometry_only() -> None:
    recipe = load_object_recipe("pear")
    assert coarse_recipe().content_hash() != recipe.content_hash()
    assert recipe.content_hash("a") != recipe.content_hash("b")
    moved = dataclasses.replace(recipe, shape=dataclasses.replace(recipe.shape, k=2.9))
    assert moved.content_hash() != recipe.content_hash()
    reworded = dataclasses.replace(recipe, description="A pear.")
    assert reworded.content_hash() == recipe.content_hash()


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        (lambda d: d["shape"].update(type="blob"), "unknown node type"),
        (lambda d: d["shape"].pop("base"), "missing field 'base'"),
        (lambda d: d["shape"].update(colour="red"), "unknown fields"),
        (lambda d: d["shape"]["cuts"][0].update(radii=[1, -1, 1]), "radii must be positive"),
        (lambda d: d["shape"]["cuts"][0].update(radii=[1, 1]), "expected 3 values"),
        (lambda d: d.update(dimensions_m=[0.1, 0.1, "a"]), "expected a finite number"),
    ],
)
def test_malformed_recipe_raises_asset_error(
    tmp_path: Path, change: Callable[[dict[str, Any]], object], fragment: str
) -> None:
    data = recipe_to_dict(load_object_recipe("pear"))
    change(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(AssetError, match=fragment):
        load_recipe(path)


def test_missing_recipe_file_raises_asset_error(tmp_path: Path) -> None:
    with pytest.raises(AssetError, match="cannot read"):
        load_recipe(tmp_path / "nothing.json")


# --- SDF primitives ---------------------------------------------------------------------


def test_sphere_and_capsule_distances_are_exact() -> None:
    rng = np.random.default_rng(0)
    points = rng.uniform(-30, 30, size=(2000, 3))
    sphere = Ellipsoid(center=(1.0, 2.0, 3.0), radii=(10.0, 10.0, 10.0))
    expected = np.linalg.norm(points - [1, 2, 3], axis=1) - 10.0
    np.testing.assert_allclose(evaluate(sphere, points), expected, atol=1e-9)

    a, b = np.array([-8.0, 0.0, 0.0]), np.array([8.0, 2.0, 0.0])
    t = np.clip((points - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    capsule = np.linalg.norm(points - (a + t[:, None] * (b - a)), axis=1) - 4.0
    np.testing.assert_allclose(sd_round_cones(points.T, a, b, 4.0, 4.0), capsule, atol=1e-9)
    tube = Tube(points=(tuple(a), tuple(b)), radii=(4.0, 4.0))
    np.testing.assert_allclose(evaluate(tube, points), capsule, atol=1e-9)


def test_round_cone_matches_dense_hull() -> None:
    """Round cone = distance to the union of spheres swept between the two ends."""
    rng = np.random.default_rng(1)
    points = rng.uniform(-25, 25, size=(500, 3))
    a, b, ra, rb = np.array([-10.0, 0, 0]), np.array([12.0, 3, -2]), 6.0, 2.0
    s = np.linspace(0, 1, 4001)[:, None]
    centres, radii = a + s * (b - a), ra + s[:, 0] * (rb - ra)
    dense = (np.linalg.norm(points[:, None] - centres[None], axis=2) - radii).min(axis=1)
    exact = sd_round_cones(points.T, a, b, ra, rb)
    # The swept spheres underestimate the hull only between samples: tiny.
    np.testing.assert_allclose(exact, dense, atol=2e-3)


def test_half_space_and_culling_keep_sign() -> None:
    rng = np.random.default_rng(2)
    points = rng.uniform(-40, 40, size=(3000, 3))
    plane = HalfSpace(normal=(0.0, 0.0, 2.0), offset=5.0)
    np.testing.assert_allclose(evaluate(plane, points), points[:, 2] - 5.0)
    shape = load_object_recipe("cat").shape
    exact = evaluate(shape, points)
    culled = evaluate(shape, points, exact_within=3.0 + blend_margin(shape))
    assert np.array_equal(np.sign(exact), np.sign(culled))
    near = np.abs(exact) < 3.0
    np.testing.assert_allclose(culled[near], exact[near], atol=1e-9)


def recipe_rotations() -> list[tuple[float, float, float]]:
    """Every ``rotation_deg`` of the catalog's recipes."""
    found = []

    def walk(value: object) -> None:
        if isinstance(value, dict):
            if "rotation_deg" in value:
                found.append(tuple(value["rotation_deg"]))
            for child in value.values():
                walk(child)
        elif isinstance(value, list):
            for child in value:
                walk(child)

    for name in object_names():
        walk(recipe_to_dict(load_object_recipe(name)))
    return found


def test_rotation_matrix_is_bit_identical_to_the_explicit_product() -> None:
    # Meshes are cached by recipe hash: a change in the last bit of a primitive's frame
    # would differ silently from the cached meshes.
    rng = np.random.default_rng(0)
    rotations = [*recipe_rotations(), *map(tuple, rng.uniform(-180.0, 180.0, (500, 3)))]
    assert len(rotations) > 500
    for rotation_deg in rotations:
        ax, ay, az = np.radians(rotation_deg)
        cx, sx, cy, sy = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay)
        cz, sz = np.cos(az), np.sin(az)
        Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        assert np.array_equal(rotation_matrix(rotation_deg), Rz @ Ry @ Rx)


# --- meshing ----------------------------------------------------------------------------


def test_build_is_deterministic() -> None:
    recipe = coarse_recipe("snail")
    first, second = build_mesh(recipe), build_mesh(recipe)
    assert np.array_equal(first.vertices, second.vertices)
    assert np.array_equal(first.faces, second.faces)
    assert first.fit_scale == second.fit_scale
    assert catalog_module.cache_key(recipe, MeshingSettings()) == catalog_module.cache_key(
        dataclasses.replace(recipe), MeshingSettings()
    )


def test_coarse_build_is_valid_and_sized() -> None:
    recipe = coarse_recipe("elephant")
    built = build_mesh(recipe)
    assert meshing.mesh_problems(built.vertices, built.faces) == []
    np.testing.assert_allclose(np.ptp(built.vertices, axis=0), recipe.dimensions_m, rtol=1e-9)
    assert abs(len(built.vertices) - recipe.target_vertices) < 0.25 * recipe.target_vertices


@pytest.mark.parametrize("name", ["cat", "snail"])
def test_narrow_band_matches_dense_sampling(name: str) -> None:
    """Sampling every block (a huge band) gives the same surface as the narrow band."""
    recipe = coarse_recipe(name)
    band = build_mesh(recipe)
    dense = build_mesh(recipe, dataclasses.replace(MeshingSettings(), band_factor=1e3))
    np.testing.assert_array_equal(band.faces, dense.faces)
    np.testing.assert_allclose(band.vertices, dense.vertices, rtol=0, atol=1e-12)


def test_mesh_problems_detects_defects() -> None:
    box = trimesh.creation.box()
    vertices, faces = np.asarray(box.vertices), np.asarray(box.faces)
    assert meshing.mesh_problems(vertices, faces) == []
    assert any("watertight" in p for p in meshing.mesh_problems(vertices, faces[1:]))
    assert any("inward" in p for p in meshing.mesh_problems(vertices, faces[:, ::-1]))
    two = np.vstack([vertices, vertices + 5.0]), np.vstack([faces, faces + len(vertices)])
    assert any("2 connected components" in p for p in meshing.mesh_problems(*two))


# --- cache ------------------------------------------------------------------------------


class BuildCounter:
    """Wraps build_mesh and counts the calls."""

    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, *args: Any, **kwargs: Any) -> MeshBuild:
        self.calls += 1
        return build_mesh(*args, **kwargs)


@pytest.fixture
def counted_builds(monkeypatch: pytest.MonkeyPatch) -> BuildCounter:
    counter = BuildCounter()
    monkeypatch.setattr(catalog_module, "build_mesh", counter)
    return counter


def _cache_files(directory: Path, name: str) -> list[Path]:
    return sorted((directory / "objects").glob(f"{name}-*.npz"))


def test_env_var_selects_generated_dir(tmp_assets: Path) -> None:
    assert generated_dir("objects") == tmp_assets / "objects"
    assert (tmp_assets / ".gitignore").read_text().strip().endswith("*")


def test_cache_round_trip(tmp_assets: Path, counted_builds: BuildCounter) -> None:
    recipe = coarse_recipe()
    built = load_or_build(recipe, progress=False)
    assert counted_builds.calls == 1
    (path,) = _cache_files(tmp_assets, "pear")
    assert path.name.startswith(f"pear-{built.recipe_hash[:16]}")
    assert not list(path.parent.glob("*.tmp"))

    loaded = load_or_build(recipe, progress=False)
    assert counted_builds.calls == 1
    assert loaded.recipe_hash == built.recipe_hash
    assert loaded.build == built.build
    np.testing.assert_array_equal(loaded.mesh.vertices, built.mesh.vertices)
    np.testing.assert_array_equal(loaded.mesh.faces, built.mesh.faces)


@pytest.mark.parametrize("damage", ["garbage", "truncate", "flip_byte", "empty"])
def test_corrupt_cache_is_rebuilt(
    tmp_assets: Path,
    counted_builds: BuildCounter,
    damage: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    recipe = coarse_recipe()
    built = load_or_build(recipe, progress=False)
    (path,) = _cache_files(tmp_assets, "pear")
    data = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not an npz file")
    elif damage == "truncate":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    else:
        # Rewrite the file uncompressed with one vertex moved: only the checksum can tell.
        with np.load(path) as npz:
            arrays = {key: npz[key] for key in npz.files}
        arrays["vertices"] = arrays["vertices"].copy()
        arrays["vertices"][0, 0] += 1e-3
        np.savez(path, **arrays)

    capsys.readouterr()
    rebuilt = load_or_build(recipe, progress=False)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and path.name in err and "damaged" in err
    assert counted_builds.calls == 2
    np.testing.assert_array_equal(rebuilt.mesh.vertices, built.mesh.vertices)
    assert load_or_build(recipe, progress=False).recipe_hash == built.recipe_hash
    assert counted_builds.calls == 2


def test_stale_cache_is_replaced(tmp_assets: Path, counted_builds: BuildCounter) -> None:
    old = coarse_recipe()
    load_or_build(old, progress=False)
    new = dataclasses.replace(old, target_vertices=old.target_vertices + 500)
    model = load_or_build(new, progress=False)
    assert counted_builds.calls == 2
    (path,) = _cache_files(tmp_assets, "pear")
    assert model.recipe_hash[:16] in path.name


def test_build_prints_one_line_message(
    tmp_assets: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    load_or_build(coarse_recipe("stone"), progress=True)
    err = capsys.readouterr().err
    assert "building the 'stone' object mesh" in err
    assert os.fspath(tmp_assets) in err


# --- render script ----------------------------------------------------------------------


def test_render_script_writes_pngs(catalog: dict[str, ObjectModel], tmp_path: Path) -> None:
    module = load_script("render_objects")
    config = module.RenderConfig(
        objects=("stone", "pear"), out_dir=tmp_path, faces=1500, image_size_in=2.0, dpi=50
    )
    written = module.run(config)
    assert [p.name for p in written] == ["stone.png", "pear.png", "contact_sheet.png"]
    assert all(p.stat().st_size > 1000 for p in written)


def test_the_drawn_copy_is_simplified_once_and_cached(tmp_assets: Path) -> None:
    from tactile_sim.objects.visual import visual_mesh

    tmp_path = tmp_assets
    mesh = trimesh.creation.icosphere(subdivisions=6, radius=0.03)  # 81920 faces
    drawn = visual_mesh(mesh, max_faces=5000)
    assert 4000 < len(drawn.faces) <= 5000
    np.testing.assert_allclose(drawn.bounds, mesh.bounds, atol=0.3e-3)
    (cached,) = (tmp_path / "visual").glob("*.npz")
    again = visual_mesh(mesh, max_faces=5000)
    np.testing.assert_array_equal(again.faces, drawn.faces)
    assert cached.stat().st_mtime_ns == next((tmp_path / "visual").glob("*.npz")).stat().st_mtime_ns
    small = trimesh.creation.icosphere(subdivisions=2)
    assert visual_mesh(small, max_faces=5000) is small
