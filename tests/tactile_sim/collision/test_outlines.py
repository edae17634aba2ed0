"""Closed planar outlines: the periodic cubic spline of the planar experiment."""

from __future__ import annotations

import numpy as np
import pytest

from tactile_sim.collision import DEFAULT_SPLINE_KNOTS_M, closed_spline_coefficients, load_solid


@pytest.mark.parametrize("source", ["function", "solid"])
def test_closed_spline_is_c2_continuous_and_passes_through_its_knots(source: str) -> None:
    if source == "function":
        knots = np.array(DEFAULT_SPLINE_KNOTS_M)
        c = closed_spline_coefficients(knots)
    else:
        parameters = load_solid("planar_spline").parameters
        knots, c = np.array(parameters["knots_m"]), parameters["spline_coefficients_m"]
    assert c.shape == (5, 2, 4)
    for i in range(5):
        j = (i + 1) % 5
        np.testing.assert_allclose(c[i, :, 3], knots[i], atol=1e-15)
        end = c[i] @ [1.0, 1.0, 1.0, 1.0]
        np.testing.assert_allclose(end, knots[j], atol=1e-12)
        # First and second derivatives match at the joint.
        np.testing.assert_allclose(c[i] @ [3.0, 2.0, 1.0, 0.0], c[j, :, 2], atol=1e-12)
        np.testing.assert_allclose(c[i] @ [6.0, 2.0, 0.0, 0.0], 2.0 * c[j, :, 1], atol=1e-12)
