"""Random planar curves of every class and of none, written apart from the library.

Each curve is a parametric polynomial or trigonometric map placed in the plane by a
random rotation, translation and (at random) a mirror, and traversed forwards or
backwards at random. Its exact curvature, curvature derivative and tangent angle come
from its own derivatives here, and the expected canonical shape parameters from its own
reduction; nothing is taken from ``recognition.curves``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Classes of the generator (the tree's names) and the non-members.
MEMBER_KINDS = (
    "parabola",
    "ellipse",
    "hyperbola",
    "cubical_parabola",
    "semicubical_parabola",
    "cubic_spline",
)
NON_MEMBER_KINDS = ("quartic", "sinusoid")

Derivatives = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class TestCurve:
    """A planar curve with its first three derivatives.

    Attributes
    ----------
    kind : str
        A class name of the tree, or a non-member's name.
    params : tuple of float
        Expected canonical shape parameters (empty for non-members).
    derivatives : callable
        ``derivatives(t)`` -> (4, 2, n): position and derivatives 1-3 in the data frame.
    t_range : (float, float)
        Interval the contacts are drawn from.
    """

    kind: str
    params: tuple[float, ...]
    derivatives: Derivatives
    t_range: tuple[float, float]


def _polynomial(coefficients: np.ndarray) -> Derivatives:
    """Derivatives of ``sum_k coefficients[k] t^k`` (coefficients (K, 2))."""

    def derivatives(t: np.ndarray) -> np.ndarray:
        out = np.zeros((4, 2, t.size))
        for order in range(4):
            c = coefficients.copy()
            for _ in range(order):
                c = c[1:] * np.arange(1, c.shape[0])[:, None]
            for k in range(c.shape[0]):
                out[order] += c[k][:, None] * t[None, :] ** k
        return out

    return derivatives


def _placed(local: Derivatives, rng: np.random.Generator, mirror: bool) -> Derivatives:
    """``local`` rotated, translated and optionally mirrored (y -> -y first)."""
    angle = rng.uniform(-np.pi, np.pi)
    c, s = np.cos(angle), np.sin(angle)
    M = np.array([[c, -s], [s, c]]) @ np.diag([1.0, -1.0 if mirror else 1.0])
    shift = rng.uniform(-5.0, 5.0, 2)

    def derivatives(t: np.ndarray) -> np.ndarray:
        d = np.einsum("ij,kjn->kin", M, local(t))
        d[0] += shift[:, None]
        return d

    return derivatives


def reduce_cubic(P: np.ndarray) -> tuple[float, float, float]:
    """(a, b, c), a >= 0, of ``x = u^2, y = a u^3 + b u^2 + c u`` congruent (by a proper
    rigid motion and an affine change of parameter) to ``P1 t + P2 t^2 + P3 t^3``
    (P (4, 2), row k the t^k coefficient)."""
    P3 = P[3]
    e = np.array([P3[1], -P3[0]]) / np.hypot(*P3)  # the x axis: no t^3 term
    if e @ P[2] < 0:
        e = -e
    f = np.array([-e[1], e[0]])  # proper rotation: y axis is e turned by +90 degrees
    A1, A2 = e @ P[1], e @ P[2]
    r = np.sqrt(A2)
    shift = A1 / (2.0 * A2)
    # t = u / r - shift; y(t) as a polynomial in u
    y = np.polynomial.Polynomial([0.0, f @ P[1], f @ P[2], f @ P[3]])
    y_u = y(np.polynomial.Polynomial([-shift, 1.0 / r]))
    coef = np.zeros(4)
    coef[: y_u.coef.size] = y_u.coef
    a, b, c = coef[3], coef[2], coef[1]
    if a < 0:  # u -> -u
        a, c = -a, -c
    return float(a), float(b), float(c)


def random_curve(kind: str, rng: np.random.Generator) -> TestCurve:
    """One random curve of ``kind`` (a member class or a non-member), placed at random."""
    mirror = bool(rng.integers(2))
    size = float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    P = np.zeros((4, 2))
    params: tuple[float, ...] = ()
    if kind == "parabola":  # y = x^2 / (4 f): focal distance f
        f = size * rng.uniform(0.3, 1.5)
        local = _polynomial(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0 / (4.0 * f)]]))
        params, t_range = (f,), (-4.0 * f, 4.0 * f)
    elif kind in ("ellipse", "hyperbola"):
        a = size * rng.uniform(1.0, 2.0)
        b = a * rng.uniform(0.25, 0.85) if kind == "ellipse" else a * rng.uniform(0.3, 3.0)
        trig = (np.cos, np.sin) if kind == "ellipse" else (np.cosh, np.sinh)
        sign = -1.0 if kind == "ellipse" else 1.0

        def local(t: np.ndarray, a: float = a, b: float = b) -> np.ndarray:
            C, S = trig[0](t), trig[1](t)
            x = [a * C, sign * a * S, sign * a * C, a * S]
            y = [b * S, b * C, sign * b * S, sign * b * C]
            return np.stack([np.stack([x[k], y[k]]) for k in range(4)])

        params = (a, b)
        t_range = (0.0, 2.0 * np.pi) if kind == "ellipse" else (-1.5, 1.5)
    elif kind == "cubical_parabola":  # y = A x^3 + B x after a proper rotation
        A = rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 2.0) / size**2
        B = rng.uniform(-2.0, 2.0)
        local = _polynomial(np.array([[0.0, 0.0], [1.0, B], [0.0, 0.0], [0.0, A]]))
        params, t_range = (A, B), (-1.5 * size, 1.5 * size)
    elif kind in ("semicubical_parabola", "cubic_spline"):
        # a general parametric cubic; no linear term for the semi-cubical parabola (cusp)
        P[1:] = rng.uniform(-1.0, 1.0, (3, 2)) * size
        if kind == "semicubical_parabola":
            P[1] = 0.0
        local = _polynomial(P)
        a, b, c = reduce_cubic(P)
        params = (a, b) if kind == "semicubical_parabola" else (a, b, c)
        t_range = (0.0, 1.5) if kind == "semicubical_parabola" else (-1.0, 1.0)
    elif kind == "quartic":  # y = c4 x^4 + c3 x^3 + c2 x^2, quartic term not small
        c4 = rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0)
        c3, c2 = rng.uniform(-1.0, 1.0, 2)
        local = _polynomial(np.array([[0, 0], [1, 0], [0, c2], [0, c3], [0, c4]], float) / 1.0)
        local = _scaled(local, size)
        t_range = (-1.0, 1.0)
    elif kind == "sinusoid":  # y = A sin(x)
        amplitude = rng.uniform(0.3, 1.5)

        def local(t: np.ndarray, A: float = amplitude) -> np.ndarray:
            s, c = np.sin(t), np.cos(t)
            one, zero = np.ones_like(t), np.zeros_like(t)
            return np.stack(
                [
                    np.stack([t, A * s]),
                    np.stack([one, A * c]),
                    np.stack([zero, -A * s]),
                    np.stack([zero, -A * c]),
                ]
            )

        local = _scaled(local, size)
        t_range = (-np.pi, np.pi)
    else:
        raise ValueError(kind)
    if mirror and kind in ("cubical_parabola",):
        params = (-params[0], -params[1])
    if mirror and kind in ("semicubical_parabola", "cubic_spline"):
        params = (params[0], -params[1], *params[2:])
    return TestCurve(kind, params, _placed(local, rng, mirror), t_range)


def _scaled(local: Derivatives, size: float) -> Derivatives:
    """``local`` scaled by ``size`` about the origin."""
    return lambda t: size * local(t)


def curvature_terms(d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kappa, d kappa / ds and the tangent angle of increasing t from (4, 2, n)."""
    (x1, y1), (x2, y2), (x3, y3) = d[1], d[2], d[3]
    v2 = x1 * x1 + y1 * y1
    v = np.sqrt(v2)
    w = x1 * y2 - y1 * x2
    kappa = w / v**3
    dkappa_dt = (x1 * y3 - y1 * x3) / v**3 - 3.0 * w * (x1 * x2 + y1 * y2) / v**5
    return kappa, dkappa_dt / v, np.arctan2(y1, x1)


def random_contacts(
    curve: TestCurve, m: int, rng: np.random.Generator, min_gap: float = 0.1
) -> np.ndarray:
    """m sorted parameters in the curve's range, at least ``min_gap`` of the range apart,
    with no point between them where the speed falls below a quarter of its median over
    the range (near a cusp, where the curvature grows without bound and no probe can
    measure it)."""
    lo, hi = curve.t_range
    d = curve.derivatives(np.linspace(lo, hi, 201))
    typical = np.median(np.hypot(d[1, 0], d[1, 1]))
    while True:
        t = np.sort(rng.uniform(lo, hi, m))
        if np.min(np.diff(t)) < min_gap * (hi - lo):
            continue
        d = curve.derivatives(np.linspace(t[0], t[-1], 401))
        if np.all(np.hypot(d[1, 0], d[1, 1]) > 0.25 * typical):
            return t


def exact_geometry(
    curve: TestCurve, t: np.ndarray, reverse: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kappa, kappa_s and tangent rotations from the first contact, in the order of
    traversal (decreasing t when ``reverse``)."""
    kappa, kappa_s, _ = curvature_terms(curve.derivatives(t))
    # the tangent angle followed continuously along the curve between the contacts
    dense = np.unique(np.concatenate([t, np.linspace(t[0], t[-1], 4001)]))
    phi = np.unwrap(curvature_terms(curve.derivatives(dense))[2])[np.searchsorted(dense, t)]
    if reverse:
        kappa, kappa_s, phi = -kappa[::-1], kappa_s[::-1], phi[::-1]
    return kappa, kappa_s, phi - phi[0]


def noisy_samples(
    curve: TestCurve,
    rng: np.random.Generator,
    spacing: float = 0.05,
    noise: float = 0.003,
    length: float = 3.0,
) -> np.ndarray:
    """Points every ``spacing`` of arc length along a random piece of ``length`` (or the
    whole range, if shorter) away from cusps, with Gaussian noise of ``noise`` per
    coordinate, in the order of a random direction of traversal: the thesis's
    joystick data (Section 3.4.2, Table 3.4: 0.05 cm, 0.003 cm)."""
    lo, hi = curve.t_range
    t = np.linspace(lo, hi, 20001)
    d = curve.derivatives(t)
    speed = np.hypot(d[1, 0], d[1, 1])
    fast = speed > 0.1 * np.median(speed)
    t, speed, d = t[fast], speed[fast], d[:, :, fast]
    s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
    start = rng.uniform(0.0, max(s[-1] - length, 0.0))
    wanted = np.arange(start, min(start + length, s[-1]), spacing)
    x = np.interp(wanted, s, d[0, 0])
    y = np.interp(wanted, s, d[0, 1])
    points = np.stack([x, y], axis=1) + rng.normal(scale=noise, size=(wanted.size, 2))
    return points[::-1] if rng.integers(2) else points


#: The thesis's joystick experiment (Section 3.4.2, Table 3.4): arcs of 6 cm sampled
#: every 0.05 cm with 0.003 cm noise on an ellipse of 25 x 17.5 mm.
JOYSTICK_ARC = 6.0
JOYSTICK_SPACING = 0.05
JOYSTICK_NOISE = 0.003
#: The arc turns its tangent by this much in all (radians): the thesis's 6 cm arcs of
#: its 25 x 17.5 mm ellipse turn by 2.2 to 3.4.
JOYSTICK_TURN = 2.5


def _longest_run(mask: np.ndarray) -> slice:
    """The longest stretch of True in ``mask`` (empty if none)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    starts, stops = edges[::2], edges[1::2]
    if starts.size == 0:
        return slice(0, 0)
    i = int(np.argmax(stops - starts))
    return slice(int(starts[i]), int(stops[i]))


def joystick_samples(
    curve: TestCurve, rng: np.random.Generator, noise: float = JOYSTICK_NOISE
) -> np.ndarray:
    """The thesis's joystick data on ``curve``: on its longest stretch away from cusps
    (speed above a tenth of the median) a random arc whose tangent turns by
    ``JOYSTICK_TURN`` in all (or the whole stretch, if it turns less), scaled to
    ``JOYSTICK_ARC`` cm, a point every ``JOYSTICK_SPACING`` cm with Gaussian noise
    ``noise`` cm per coordinate, in a random direction of traversal (the same arc and
    direction for the same state of ``rng``, whatever the noise)."""
    lo, hi = curve.t_range
    t = np.linspace(lo, hi, 20001)
    d = curve.derivatives(t)
    speed = np.hypot(d[1, 0], d[1, 1])
    run = _longest_run(speed > 0.1 * np.median(speed))
    speed, d = speed[run], d[:, :, run]
    ds = 0.5 * (speed[1:] + speed[:-1]) * np.diff(t[run])
    s = np.concatenate([[0.0], np.cumsum(ds)])
    kappa = np.abs(curvature_terms(d)[0])
    turn = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)])
    if turn[-1] <= JOYSTICK_TURN:
        s0, s1 = 0.0, s[-1]
    else:
        turn0 = rng.uniform(0.0, turn[-1] - JOYSTICK_TURN)
        s0, s1 = np.interp([turn0, turn0 + JOYSTICK_TURN], turn, s)
    scale = JOYSTICK_ARC / (s1 - s0)
    wanted = np.arange(0.0, JOYSTICK_ARC + 1e-9, JOYSTICK_SPACING) / scale + s0
    points = scale * np.stack([np.interp(wanted, s, d[0, 0]), np.interp(wanted, s, d[0, 1])], 1)
    points = points + noise * rng.normal(size=points.shape)
    return points[::-1] if rng.integers(2) else points
