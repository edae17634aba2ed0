"""Every cubic spline through two contacts by elimination (spline_solve)."""

from __future__ import annotations

import numpy as np
import pytest

from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.recognition.spline_solve import spline_candidates


def _contacts(
    params: tuple[float, float, float], t: np.ndarray, psi: float, sigma: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kappa, kappa_s and tangent angles of the canonical spline at t, rotated by -psi and
    traversed with increasing t (sigma = 1) or decreasing t (sigma = -1, t reversed)."""
    curve = CanonicalCurve(CurveKind.CUBIC_SPLINE, params)
    if sigma < 0:
        t = t[::-1]
    kappa, kappa_s, phi = curve.kappa(t), curve.kappa_s(t), curve.phi(t)
    if sigma < 0:
        kappa, phi = -kappa, phi + np.pi
    return kappa, kappa_s, np.unwrap(phi - psi)


@pytest.mark.parametrize("sigma", [1.0, -1.0])
def test_the_true_spline_is_among_the_candidates_and_agrees_best(sigma: float) -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        params = (
            float(rng.uniform(0.2, 3.0)),
            float(rng.uniform(-4.0, 4.0)),
            float(rng.uniform(-2.0, 2.0)),
        )
        t = np.sort(rng.uniform(-2.0, 2.0, 3))
        psi = float(rng.uniform(-np.pi, np.pi))
        kappa, kappa_s, phi = _contacts(params, t, psi, sigma)
        found = spline_candidates(kappa, kappa_s, phi, (0, 2))
        assert found.mismatch[0] < 1e-9
        np.testing.assert_allclose(found.params[0], params, rtol=1e-7, atol=1e-9)
        assert found.sigma[0] == sigma
        expected_t = t if sigma > 0 else t[::-1]
        np.testing.assert_allclose(found.t[0], expected_t, rtol=1e-7, atol=1e-9)
        # canonical tangent angle = data angle + psi, modulo pi
        np.testing.assert_allclose(
            np.sin(phi[0] + found.psi[0] - curve_angle(params, expected_t[0])), 0.0, atol=1e-8
        )


def curve_angle(params: tuple[float, float, float], t: float) -> float:
    return float(CanonicalCurve(CurveKind.CUBIC_SPLINE, params).phi(np.array([t]))[0])


def test_a_nearly_cubical_parabola_spline_is_found() -> None:
    """|b| in the hundreds of thousands: the canonical shape is ill-conditioned, the
    elimination is not."""
    params = (9765.58678502, -250035.99411902, 2133951.02072382)
    t = -params[1] / (3 * params[0]) + np.array([-0.004, 0.001, 0.005])
    kappa, kappa_s, phi = _contacts(params, t, 0.4, 1.0)
    found = spline_candidates(kappa, kappa_s, phi, (0, 2))
    np.testing.assert_allclose(found.params[0], params, rtol=1e-6)
