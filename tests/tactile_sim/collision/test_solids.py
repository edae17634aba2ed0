"""The closed-form solids of thesis Fig. 4.15 and Section 3.4.2."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_sim.collision import load_solid, solid_names
from tactile_sim.errors import UnknownObject


@pytest.mark.parametrize("name", solid_names())
def test_solids_are_closed_convex_and_sit_on_the_table(name: str) -> None:
    solid = load_solid(name)
    mesh = solid.mesh
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert solid.convex
    bounds = mesh.bounds
    assert bounds[0, 2] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(bounds[0, :2], -bounds[1, :2], atol=1e-9)


@pytest.mark.parametrize(
    ("name", "expected_volume"),
    [
        ("cylinder_1", math.pi * 0.0252**2 * 0.1),
        ("cylinder_2", math.pi * 0.047**2 * 0.1),
        ("elliptic_cylinder", math.pi * 0.0508 * 0.03175 * 0.1),
        ("sphere", 4.0 / 3.0 * math.pi * 0.033**3),
        ("planar_ellipse", math.pi * 0.025 * 0.0175 * 0.03),
    ],
)
def test_solid_dimensions_match_thesis_figure_4_15_and_section_3_4_2(
    name: str, expected_volume: float
) -> None:
    # Polygonal approximations are inscribed: slightly smaller, by well under 0.2 %.
    volume = load_solid(name).mesh.volume
    assert volume == pytest.approx(expected_volume, rel=2e-3)
    assert volume < expected_volume


def test_solid_extents() -> None:
    assert np.ptp(load_solid("cylinder_1").mesh.vertices[:, 2]) == pytest.approx(0.0504)
    assert np.ptp(load_solid("cylinder_2").mesh.vertices[:, 2]) == pytest.approx(0.094)
    ellipse = np.ptp(load_solid("elliptic_cylinder").mesh.vertices, axis=0)
    np.testing.assert_allclose(ellipse, [0.1, 2 * 0.0508, 2 * 0.03175], rtol=1e-9)
    planar = np.ptp(load_solid("planar_ellipse").mesh.vertices, axis=0)
    np.testing.assert_allclose(planar, [0.05, 0.035, 0.03], rtol=1e-9)


def test_unknown_solid_lists_the_known_names() -> None:
    with pytest.raises(UnknownObject, match=r"cylinder_1.*sphere"):
        load_solid("cube")
