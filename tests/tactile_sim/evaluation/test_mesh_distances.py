"""The exact-distance benchmark: the grid and libigl agree on a catalog mesh, and the
script writes its report."""

from testing_scripts import load_script

from tactile_sim.evaluation.mesh_distances import OFFSETS_MM, compare_with_libigl


def test_the_grid_and_libigl_give_the_same_distances_on_a_catalog_mesh():
    (row,) = compare_with_libigl(["cat"], queries=300, seed=1)
    assert row["faces"] > 100_000
    assert row["largest_difference_m"] < 1e-12
    for offset_mm in OFFSETS_MM:
        assert row[f"grid_points_per_s_{offset_mm:g}mm"] > 0
    assert 0 < row["grid_bytes_per_face"] < 100


def test_the_script_writes_its_report(tmp_path):
    script = load_script("benchmark_mesh_distance")
    config = script.parse_args(["--queries", "50", "--out-dir", str(tmp_path)])
    rows = script.run(config)
    text = (tmp_path / "mesh_distance.md").read_text()
    assert "--queries 50" in text and len(rows) == 10
    assert all(r["largest_difference_m"] < 1e-12 for r in rows)
    assert text.count("\n| ") == 1 + len(rows)
