"""Reductions of general polynomial parametrisations to canonical form (Section 3.2).

Each test builds a general parametrisation by reparametrising a canonical curve
(``u = p t + q``), rotating it by a random angle and translating it, then checks that the
reduction returns the canonical shape parameters and a rigid motion plus parameter map
that reproduce every point of the given curve. Everything is polynomial arithmetic on
O(1) coefficients, so relative tolerances of 1e-9 are generous.
"""

from collections.abc import Callable, Sequence

import numpy as np
import pytest
from numpy.polynomial import polynomial as P

from recognition.curves.families import CurveKind
from recognition.curves.reduction import (
    CanonicalReduction,
    reduce_cubic_spline,
    reduce_cubical_parabola,
    reduce_parabola,
    reduce_semicubical_parabola,
)
from recognition.errors import DegenerateGeometry, InvalidCurveData

N_CURVES = 100


def place(
    X: Sequence[float], Y: Sequence[float], rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Rotate the coefficient vectors (lowest degree first) of (X, Y) and translate them.

    Returns x, y coefficients (length 4, lowest degree first).
    """
    X, Y = np.pad(X, (0, 4 - len(X))), np.pad(Y, (0, 4 - len(Y)))
    phi = rng.uniform(-np.pi, np.pi)
    c, s = np.cos(phi), np.sin(phi)
    x, y = c * X - s * Y, s * X + c * Y
    x[0] += rng.normal()
    y[0] += rng.normal()
    return x, y


def assert_reproduces(reduction: CanonicalReduction, x: np.ndarray, y: np.ndarray) -> None:
    """The reduction's rigid motion and parameter map reproduce the given curve."""
    T = reduction.T_data_from_canonical
    R = T[:2, :2]
    np.testing.assert_allclose(R.T @ R, np.eye(2), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(T[2], [0.0, 0.0, 1.0], atol=1e-15)
    t = np.linspace(-1.5, 1.5, 13)
    expected = np.column_stack([P.polyval(t, x), P.polyval(t, y)])
    scale = np.abs(expected).max() + 1.0
    np.testing.assert_allclose(reduction.points(t), expected, atol=1e-11 * scale)


def combine(coefficients: Sequence[float], u: np.ndarray) -> np.ndarray:
    """sum_k coefficients[k] u^(k+1) as a polynomial in t (lowest degree first)."""
    total = np.zeros(1)
    for k, value in enumerate(coefficients, start=1):
        total = P.polyadd(total, value * P.polypow(u, k))
    return total


def reparametrisation(rng: np.random.Generator, shift: bool = True) -> np.ndarray:
    p = rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 2.0)
    q = rng.normal() if shift else 0.0
    return np.array([q, p])  # u = q + p t, lowest degree first


def test_parabola_reduction_recovers_a_and_the_placement() -> None:
    """Section 3.2.1.1 with THESIS_ERRATA item 6: a = B1^2 / (4 A2)."""
    rng = np.random.default_rng(30)
    for _ in range(N_CURVES):
        a = rng.uniform(0.1, 5.0)
        u = reparametrisation(rng)
        x, y = place(a * P.polypow(u, 2), 2 * a * u, rng)
        reduction = reduce_parabola(x[2], x[1], x[0], y[2], y[1], y[0])
        assert reduction.kind is CurveKind.PARABOLA
        assert reduction.params[0] == pytest.approx(a, rel=1e-10)
        assert_reproduces(reduction, x, y)
        # u(t) is the canonical parametrisation up to the sign of u (y -> -y mirror is the
        # same parabola only with u -> -u, which the rotation absorbs)
        assert abs(reduction.u_scale) == pytest.approx(abs(u[1]), rel=1e-10)


def test_parabola_printed_formula_is_four_times_too_large() -> None:
    """THESIS_ERRATA item 6: the printed a lacks the factor 4 in the denominator."""
    rng = np.random.default_rng(31)
    for _ in range(20):
        a = rng.uniform(0.1, 5.0)
        u = reparametrisation(rng)
        x, y = place(a * P.polypow(u, 2), 2 * a * u, rng)
        theta = np.arctan2(y[2], x[2])
        printed = (-x[1] * np.sin(theta) + y[1] * np.cos(theta)) ** 2 / (
            x[2] * np.cos(theta) + y[2] * np.sin(theta)
        )
        reduced = reduce_parabola(x[2], x[1], x[0], y[2], y[1], y[0]).params[0]
        assert printed == pytest.approx(4 * reduced, rel=1e-10)
        assert reduced == pytest.approx(a, rel=1e-10)


def test_parabola_rotation_from_arctan_can_give_the_mirror_sign() -> None:
    """tan(theta) = b2 / a2 fixes theta only modulo pi: with arctan and a2 < 0 the
    denominator a2 cos + b2 sin is negative (a < 0, the parabola opening towards -x);
    atan2 keeps a > 0."""
    a2, a1, b2, b1 = -1.5, 0.4, 0.5, 1.0
    theta = np.arctan(b2 / a2)
    assert a2 * np.cos(theta) + b2 * np.sin(theta) < 0
    reduction = reduce_parabola(a2, a1, 0.0, b2, b1, 0.0)
    assert reduction.params[0] > 0
    assert_reproduces(reduction, np.array([0.0, a1, a2, 0.0]), np.array([0.0, b1, b2, 0.0]))


def test_parabola_reduction_rejects_a_straight_line() -> None:
    """a2 b1 - a1 b2 = 0: x and y are affinely dependent, the curve is a line."""
    with pytest.raises(DegenerateGeometry, match="straight line"):
        reduce_parabola(2.0, 1.0, 0.0, 4.0, 2.0, 1.0)


def test_cubical_parabola_reduction_recovers_a_b_and_the_placement() -> None:
    """Section 3.2.2.1: (a, b) from the printed formulas; u = (a1 cos + b1 sin) t."""
    rng = np.random.default_rng(32)
    for _ in range(N_CURVES):
        a = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 3.0)
        b = rng.uniform(-2.0, 2.0)
        u = reparametrisation(rng, shift=False)
        x, y = place(u, combine((b, 0.0, a), u), rng)
        reduction = reduce_cubical_parabola(x[3], x[1], x[0], y[3], y[1], y[0])
        assert reduction.kind is CurveKind.CUBICAL_PARABOLA
        np.testing.assert_allclose(reduction.params, (a, b), rtol=1e-10, atol=1e-12)
        # (x, y) -> (-x, -y) with u -> -u is the same canonical curve
        assert abs(reduction.u_scale) == pytest.approx(abs(u[1]), rel=1e-10)
        assert_reproduces(reduction, x, y)


def test_cubical_parabola_printed_rotation_is_right() -> None:
    """theta = arctan(-a3/b3) cancels the t^3 term of x' = x cos + y sin (the thesis's
    rotation convention), and the printed a, b follow with either branch of arctan."""
    rng = np.random.default_rng(33)
    for _ in range(20):
        a, b = rng.uniform(0.2, 3.0), rng.uniform(-2.0, 2.0)
        u = reparametrisation(rng, shift=False)
        x, y = place(u, combine((b, 0.0, a), u), rng)
        a3, a1, b3, b1 = x[3], x[1], y[3], y[1]
        for theta in (np.arctan(-a3 / b3), np.arctan(-a3 / b3) + np.pi):
            c, s = np.cos(theta), np.sin(theta)
            assert abs(a3 * c + b3 * s) <= 1e-12 * np.hypot(a3, b3)
            printed_a = (-a3 * s + b3 * c) / (a1 * c + b1 * s) ** 3
            printed_b = (-a1 * s + b1 * c) / (a1 * c + b1 * s)
            np.testing.assert_allclose((printed_a, printed_b), (a, b), rtol=1e-10, atol=1e-12)


def test_cubical_parabola_reduction_handles_b3_zero_and_rejects_degenerate() -> None:
    """b3 = 0 (where arctan(-a3/b3) is undefined) works; a3 b1 - a1 b3 = 0 raises."""
    reduction = reduce_cubical_parabola(2.0, 0.5, 0.0, 0.0, 1.0, 0.0)
    assert_reproduces(reduction, np.array([0.0, 0.5, 0.0, 2.0]), np.array([0.0, 1.0, 0.0, 0.0]))
    with pytest.raises(DegenerateGeometry, match="a3 b1 - a1 b3"):
        reduce_cubical_parabola(2.0, 1.0, 0.0, 4.0, 2.0, 0.0)


def test_cubic_spline_reduction_recovers_a_b_c_and_the_placement() -> None:
    """Section 3.2.2.3, Eq. (3.35): (a, b, c) up to the equivalence (a, b, c) ~ (-a, b, -c)."""
    rng = np.random.default_rng(34)
    for _ in range(N_CURVES):
        a = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 3.0)
        b, c = rng.uniform(-2.0, 2.0), rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 2.0)
        u = reparametrisation(rng)
        x, y = place(P.polypow(u, 2), combine((c, b, a), u), rng)
        reduction = reduce_cubic_spline(*x[::-1], *y[::-1])
        assert reduction.kind is CurveKind.CUBIC_SPLINE
        sign = np.sign(a)
        np.testing.assert_allclose(reduction.params, (abs(a), b, sign * c), rtol=1e-9, atol=1e-11)
        assert_reproduces(reduction, x, y)


def test_semicubical_reduction_recovers_a_b_and_the_placement() -> None:
    """Section 3.2.2.2: x = u^2, y = a u^3 + b u^2 (a > 0), from u = p t."""
    rng = np.random.default_rng(35)
    for _ in range(N_CURVES):
        a, b = rng.uniform(0.2, 3.0), rng.uniform(-2.0, 2.0)
        u = reparametrisation(rng, shift=False)
        x, y = place(P.polypow(u, 2), combine((0.0, b, a), u), rng)
        reduction = reduce_semicubical_parabola(x[3], x[2], x[0], y[3], y[2], y[0])
        assert reduction.kind is CurveKind.SEMICUBICAL_PARABOLA
        np.testing.assert_allclose(reduction.params, (a, b), rtol=1e-10, atol=1e-12)
        assert_reproduces(reduction, x, y)


def test_cubic_reductions_reject_degenerate_input() -> None:
    with pytest.raises(DegenerateGeometry, match="a3 = b3 = 0"):
        reduce_cubic_spline(0.0, 1.0, 1.0, 0.0, 0.0, 2.0, 0.5, 0.0)
    with pytest.raises(DegenerateGeometry, match="cubical parabola"):
        reduce_cubic_spline(1.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0)
    with pytest.raises(DegenerateGeometry, match="a3 b2 - a2 b3"):
        reduce_semicubical_parabola(1.0, 2.0, 0.0, 2.0, 4.0, 0.0)


@pytest.mark.parametrize(
    ("reduce", "n"),
    [
        (reduce_parabola, 6),
        (reduce_cubical_parabola, 6),
        (reduce_semicubical_parabola, 6),
        (reduce_cubic_spline, 8),
    ],
)
def test_reductions_reject_non_finite_coefficients(
    reduce: Callable[..., CanonicalReduction], n: int
) -> None:
    coefficients = [1.0, 0.5, 0.0, 0.3, 2.0, 0.0, 1.0, 0.0][:n]
    coefficients[1] = np.nan
    with pytest.raises(InvalidCurveData, match="finite scalar"):
        reduce(*coefficients)
