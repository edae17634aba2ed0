"""Each class of the tree fitted to the sampled points themselves.

The thesis decides a class from invariants of local estimates (Section 3.3); on sampled
tactile data those estimates are far noisier than the points they come from (kappa_s is
a third derivative). Here every class is fitted to all the points by orthogonal distance
regression: each point's foot parameter is its closest point on the curve, and the
curve's unknowns minimise the sum of squared distances (damped Gauss-Newton on the
distances, the feet re-found after every step).

Each class is a curve ``c(u; g)`` in the data frame:

- ellipse and hyperbola: the canonical forms of Section 3.2.1 placed by a proper rigid
  motion, ``g = (a, b, theta, T)``;
- the polynomial classes: parametric polynomials in the points' own frame (centred and
  scaled, the parameter about [-1, 1], well conditioned where the canonical form's origin
  lies far from the arc), constrained to the class: the parabola is quadratic (Eq. 3.4);
  the cubic spline is any cubic (Eq. 3.25); the cubical parabola's quadratic coefficient
  is parallel to its cubic one, ``c = A0 + A1 u - 3 beta P3 u^2 + P3 u^3`` (an inflection
  at ``u = beta``, Section 3.2.2.1); the semi-cubical parabola's velocity vanishes at
  ``u = beta``, ``c'(beta) = 0`` (a cusp, Section 3.2.2.2). A fitted polynomial is
  reduced to its canonical form by :mod:`recognition.curves.reduction`.

Every class is closed under reflection, so proper motions suffice. The reparametrisations
that leave a polynomial curve unchanged are directions of no change of the distances; the
solver's least-norm steps take no step along them. For data of the class with isotropic
noise of variance sigma^2 per coordinate, the sum of squared distances over sigma^2 is
chi-square with n - k degrees of freedom, k the class's shape parameters plus 3.

Limit: a semi-cubical piece that runs close to its cusp (speed below a tenth of its
largest, where no probe can trace it) can end in a local minimum of the fit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import ArrayLike
from scipy.linalg import orth

from recognition.curves.families import (
    N_PARAMETERS,
    TREE_CLASSES,
    CanonicalCurve,
    CurveKind,
    canonical_derivatives,
)
from recognition.curves.reduction import (
    CanonicalReduction,
    reduce_cubic_spline,
    reduce_cubical_parabola,
    reduce_parabola,
    reduce_semicubical_parabola,
)
from recognition.errors import DegenerateGeometry
from recognition.least_squares import (
    Damping,
    LeastSquaresConfig,
    LinearSolve,
    damped_least_squares,
)
from recognition.rigid import rotation_2d

__all__ = ["PointFit", "fit_classes"]

#: The fit's solver: Marquardt's scaling makes it independent of the unknowns' units; the
#: least-norm solve takes no step along a reparametrisation.
SOLVER = LeastSquaresConfig(
    max_iterations=100,
    damping=Damping.DIAGONAL,
    rtol=1e-7,
    retry=True,
    max_damping=1e10,
    solve=LinearSolve.LEAST_NORM,
)
#: With more starts than ``FINISHED``, all take ``SCREEN``'s steps and the best
#: ``FINISHED`` go on to convergence.
SCREEN = replace(SOLVER, max_iterations=12)
FINISHED = 3
#: Newton steps of the foot-point search after each move of the curve.
FOOT_ITERATIONS = 4
#: Singular values of a fit's Jacobian below this fraction of the largest are
#: reparametrisations of the curve (no change of the distances).
RANK_TOLERANCE = 1e-6
#: Rounds of parameter correction (Hoschek) of the polynomial fits that start the search.
CORRECTION_ROUNDS = 20

#: Grid of the inflection's or cusp's parameter searched for the starts of the cubical
#: and semi-cubical parabolas (the points' parameter spans about [-1, 1]), and the number
#: of its local minima that start the fit.
BETA_GRID = np.sinh(np.linspace(-4.0, 4.0, 161))
BETA_STARTS = 4
#: Gaps between the points' end and a cusp beyond it, in arc lengths, that start the
#: semi-cubical parabola's fit too (:func:`_cusp_starts`).
CUSP_GAPS = (0.0, 0.1)

_J = np.array([[0.0, -1.0], [1.0, 0.0]])
_POLYNOMIAL = (
    CurveKind.PARABOLA,
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)


@dataclass(frozen=True)
class PointFit:
    """One class fitted to the points by least squares.

    Attributes
    ----------
    kind : CurveKind
    reduction : CanonicalReduction
        The fitted curve's canonical shape parameters (as fitted, not normalised) and the
        rigid motion placing the canonical form on the points.
    u : (n,) float
        Canonical parameter of each point's foot.
    distances : (n,) float
        Signed distance of each point from the fitted curve: positive to the left of the
        curve's direction of increasing parameter.
    fitted : (n, r) float
        Orthonormal basis of the changes of ``distances`` that the fit's unknowns make
        (the range of their Jacobian at the fit): noise in these directions the fit
        absorbs, and the residuals are orthogonal to them.
    """

    kind: CurveKind
    reduction: CanonicalReduction
    u: np.ndarray
    distances: np.ndarray
    fitted: np.ndarray

    @property
    def sum_of_squares(self) -> float:
        """Sum of the squared distances."""
        return float(self.distances @ self.distances)

    @property
    def n_unknowns(self) -> int:
        """Shape parameters plus the three of the rigid motion."""
        return N_PARAMETERS[self.kind] + 3


def _polynomial_coefficients(kind: CurveKind, g: np.ndarray) -> np.ndarray:
    """Coefficients (B, 4, 2), constant first, of the polynomial classes' unknowns."""
    B = g.shape[0]
    c = np.zeros((B, 4, 2))
    if kind is CurveKind.PARABOLA:
        c[:, :3] = g.reshape(B, 3, 2)
    elif kind is CurveKind.CUBIC_SPLINE:
        c[:] = g.reshape(B, 4, 2)
    elif kind is CurveKind.CUBICAL_PARABOLA:  # (A0, A1, P3, beta)
        beta = g[:, 6, None]
        c[:, 0], c[:, 1], c[:, 3] = g[:, 0:2], g[:, 2:4], g[:, 4:6]
        c[:, 2] = -3.0 * beta * g[:, 4:6]
    else:  # semi-cubical parabola: (P0, P2, P3, beta), P1 = -2 beta P2 - 3 beta^2 P3
        beta = g[:, 6, None]
        c[:, 0], c[:, 2], c[:, 3] = g[:, 0:2], g[:, 2:4], g[:, 4:6]
        c[:, 1] = -2.0 * beta * g[:, 2:4] - 3.0 * beta**2 * g[:, 4:6]
    return c


def _polynomial_curve(
    kind: CurveKind, g: np.ndarray, u: np.ndarray, jacobian: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Position, first and second derivative (B, n, 2) and, if asked, d position / d g
    (B, n, 2, k)."""
    c = _polynomial_coefficients(kind, g)[:, None]  # (B, 1, 4, 2)
    x = u[..., None]
    pos = c[..., 0, :] + x * (c[..., 1, :] + x * (c[..., 2, :] + x * c[..., 3, :]))
    vel = c[..., 1, :] + x * (2.0 * c[..., 2, :] + 3.0 * x * c[..., 3, :])
    acc = 2.0 * c[..., 2, :] + 6.0 * x * c[..., 3, :]
    if not jacobian:
        return pos, vel, acc, None
    powers = x ** np.arange(4)  # (B, n, 4)
    B, n = u.shape
    eye = np.eye(2)
    if kind in (CurveKind.PARABOLA, CurveKind.CUBIC_SPLINE):
        m = 3 if kind is CurveKind.PARABOLA else 4
        # unknown 2 k + d is coordinate d of the t^k coefficient
        jac = np.einsum("bnk,cd->bnckd", powers[..., :m], eye).reshape(B, n, 2, 2 * m)
        return pos, vel, acc, jac
    beta = g[:, 6, None]
    jac = np.zeros((B, n, 2, 7))
    jac[..., 0, 0] = jac[..., 1, 1] = 1.0
    if kind is CurveKind.CUBICAL_PARABOLA:
        w1, w3 = u, u**3 - 3.0 * beta * u * u
        jac[..., 0, 2] = jac[..., 1, 3] = w1
        jac[..., 0, 4] = jac[..., 1, 5] = w3
        jac[..., 6] = -3.0 * (u * u)[..., None] * g[:, None, 4:6]
    else:
        w2, w3 = u * u - 2.0 * beta * u, u**3 - 3.0 * beta**2 * u
        jac[..., 0, 2] = jac[..., 1, 3] = w2
        jac[..., 0, 4] = jac[..., 1, 5] = w3
        jac[..., 6] = u[..., None] * (
            -2.0 * g[:, None, 2:4] - 6.0 * beta[..., None] * g[:, None, 4:6]
        )
    return pos, vel, acc, jac


def _conic_curve(
    kind: CurveKind, g: np.ndarray, u: np.ndarray, jacobian: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """The same for ``R(theta) q(u; a, b) + T``, ``g = (a, b, theta, T)``."""
    d = np.moveaxis(canonical_derivatives(kind, [g[:, 0], g[:, 1]], u), 1, -1)  # (4, B, n, 2)
    R = rotation_2d(g[:, 2])[:, None]  # (B, 1, 2, 2)
    pos, vel, acc = ((R @ d[k][..., None])[..., 0] for k in range(3))
    pos = pos + g[:, None, 3:5]
    if not jacobian:
        return pos, vel, acc, None
    B, n = u.shape
    jac = np.zeros((B, n, 2, 5))
    hyperbolic = kind is CurveKind.HYPERBOLA
    cos = np.cosh(u) if hyperbolic else np.cos(u)
    sin = np.sinh(u) if hyperbolic else np.sin(u)
    jac[..., 0] = R[..., :, 0] * cos[..., None]
    jac[..., 1] = R[..., :, 1] * sin[..., None]
    jac[..., 2] = (pos - g[:, None, 3:5]) @ _J.T
    jac[..., 0, 3] = jac[..., 1, 4] = 1.0
    return pos, vel, acc, jac


def _curve(
    kind: CurveKind, g: np.ndarray, u: np.ndarray, jacobian: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Position, derivatives and Jacobian of the class's curve (the two kinds above)."""
    if kind in _POLYNOMIAL:
        return _polynomial_curve(kind, g, u, jacobian)
    return _conic_curve(kind, g, u, jacobian)


def _feet(kind: CurveKind, g: np.ndarray, u: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Foot parameters: Newton's method on (c(u) - p) . c'(u) = 0 from ``u``, each step
    at most a tenth of the parameter span of the points."""
    span = np.ptp(u, axis=1, keepdims=True) + 1e-300
    for _ in range(FOOT_ITERATIONS):
        pos, vel, acc, _ = _curve(kind, g, u, jacobian=False)
        diff = pos - points
        grad = np.sum(diff * vel, axis=-1)
        curv = np.sum(vel * vel, axis=-1) + np.sum(diff * acc, axis=-1)
        step = np.where(curv > 0, -grad / np.where(curv > 0, curv, 1.0), -np.sign(grad) * span)
        u = u + np.clip(step, -0.1 * span, 0.1 * span)
    return u


def _residuals(
    kind: CurveKind, g: np.ndarray, u: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Distances (B, n) of the points from their feet and their Jacobian (B, n, k) along
    the direction from point to foot (the normal there; defined at a cusp too)."""
    pos, vel, _, jac = _curve(kind, g, u)
    assert jac is not None
    diff = pos - points
    r = np.linalg.norm(diff, axis=-1)
    speed = np.linalg.norm(vel, axis=-1, keepdims=True)
    normal = vel @ _J.T / np.where(speed > 0, speed, 1.0)
    e = np.where(r[..., None] > 0, diff / np.where(r > 0, r, 1.0)[..., None], normal)
    return r, np.einsum("bnc,bnck->bnk", e, jac)


def _solve(
    kind: CurveKind, starts: np.ndarray, u: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The least-squares fit from each start; the best (g, u), or None."""
    with np.errstate(all="ignore"):
        u = _feet(kind, starts, u, points)
        r, J = _residuals(kind, starts, u, points)
        finite = np.isfinite(r).all(axis=1) & np.isfinite(J).all(axis=(1, 2))
        if not finite.any():
            return None

        def cost(state: tuple[np.ndarray, ...]) -> np.ndarray:
            pos = _curve(kind, state[0], state[1], jacobian=False)[0]
            out = np.sum((pos - points) ** 2, axis=(1, 2))
            return np.where(np.isfinite(out), out, np.inf)

        def linearize(state: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
            return _residuals(kind, state[0], state[1], points)

        def retract(state: tuple[np.ndarray, ...], step: np.ndarray) -> tuple[np.ndarray, ...]:
            g = state[0] + step
            return g, _feet(kind, g, state[1], points)

        state: tuple[np.ndarray, ...] = (starts[finite], u[finite])
        if len(state[0]) > FINISHED:  # a few steps from every start, then the best on
            first = damped_least_squares(
                state, cost=cost, linearize=linearize, retract=retract, config=SCREEN
            )
            kept = np.argsort(first.cost)[:FINISHED]
            state = tuple(a[kept] for a in first.state)
        result = damped_least_squares(
            state, cost=cost, linearize=linearize, retract=retract, config=SOLVER
        )
    best = int(np.argmin(result.cost))
    if not np.isfinite(result.cost[best]):
        return None
    return result.state[0][best], result.state[1][best]


def _better(
    kind: CurveKind,
    a: tuple[np.ndarray, np.ndarray] | None,
    b: tuple[np.ndarray, np.ndarray] | None,
    points: np.ndarray,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Of two fits of ``kind`` (either may be None), the one of least squared distance."""
    fits = [f for f in (a, b) if f is not None]
    if len(fits) < 2:
        return fits[0] if fits else None
    costs = [float(np.sum(_residuals(kind, g[None], u[None], points)[0] ** 2)) for g, u in fits]
    return fits[int(np.argmin(costs))]


def _chord_parameter(points: np.ndarray) -> np.ndarray:
    """Cumulative chord length, scaled to [-1, 1]."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    return 2.0 * s / s[-1] - 1.0


def _corrected_polynomial(points: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (degree + 1, 2) and parameters of a parametric polynomial fitted by
    parameter correction: from the chord-length parameter, alternately the linear
    least-squares coefficients and one Newton step of each point's foot."""
    t = _chord_parameter(points)
    for _ in range(CORRECTION_ROUNDS):
        coef = np.linalg.lstsq(t[:, None] ** np.arange(degree + 1), points, rcond=None)[0]
        diff = P.polyval(t, coef).T - points
        v1, v2 = P.polyval(t, P.polyder(coef, 1)).T, P.polyval(t, P.polyder(coef, 2)).T
        curv = np.sum(v1 * v1, axis=1) + np.sum(diff * v2, axis=1)
        t = t - np.sum(diff * v1, axis=1) / np.where(curv > 0, curv, np.inf)
    coef = np.linalg.lstsq(t[:, None] ** np.arange(degree + 1), points, rcond=None)[0]
    return coef, t


def _special_point_starts(
    kind: CurveKind, points: np.ndarray, t: np.ndarray, spline: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Starting unknowns (S, 7) of the cubical or semi-cubical parabola: for each
    candidate inflection or cusp parameter beta, the other coefficients by linear least
    squares at the points' parameters ``t``; the ``BETA_STARTS`` best of the local minima
    over ``BETA_GRID`` and of the special points of the fitted cubic ``spline`` (4, 2)
    (its inflections, where c' x c'' = 0; the minima of |c'|, a cusp's place)."""
    d1, d2 = P.polyder(spline, 1), P.polyder(spline, 2)
    special: np.ndarray
    if kind is CurveKind.CUBICAL_PARABOLA:
        special = P.polysub(P.polymul(d1[:, 0], d2[:, 1]), P.polymul(d1[:, 1], d2[:, 0]))
    else:
        special = P.polyder(P.polymul(d1[:, 0], d1[:, 0]) + P.polymul(d1[:, 1], d1[:, 1]))
    roots = P.polyroots(special) if np.any(special) else np.zeros(0)
    betas = np.concatenate([BETA_GRID, roots[np.abs(roots.imag) < 1e-9].real])
    rows = []
    for beta in betas:
        V = _constrained_basis(kind, t, beta)  # (n, 3)
        coef = np.linalg.lstsq(V, points, rcond=None)[0]
        rows.append((float(np.sum((V @ coef - points) ** 2)), [*coef.ravel(), beta]))
    costs = np.array([r[0] for r in rows])
    grid = costs[: BETA_GRID.size]
    lower = np.concatenate([[True], grid[1:] <= grid[:-1]])
    upper = np.concatenate([grid[:-1] <= grid[1:], [True]])
    candidates = np.concatenate(
        [np.flatnonzero(lower & upper), np.arange(BETA_GRID.size, betas.size)]
    )
    best = candidates[np.argsort(costs[candidates])][:BETA_STARTS]
    return np.array([rows[i][1] for i in best]), np.repeat(t[None], best.size, axis=0)


def _cusp_starts(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starting unknowns (S, 7) and parameters (S, n) of the semi-cubical parabola with
    its cusp just beyond either end of the points: the speed vanishes at a cusp, so the
    arc length from it grows as the square of the parameter, and the parameter is
    sqrt(arc length from the cusp) (scaled to at most 1). An arc that runs up to a cusp
    is parameterised far from its chord length there, and the fits started from the
    chord length end in a local minimum (a noise-free arc left 61 noise variances)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    starts, params = [], []
    for from_cusp in (s, s[-1] - s):
        for gap in CUSP_GAPS:
            t = np.sqrt(from_cusp + gap * s[-1])
            t /= t.max()
            V = _constrained_basis(CurveKind.SEMICUBICAL_PARABOLA, t, 0.0)
            coef = np.linalg.lstsq(V, points, rcond=None)[0]
            starts.append([*coef.ravel(), 0.0])
            params.append(t)
    return np.array(starts), np.array(params)


def _constrained_basis(kind: CurveKind, t: np.ndarray, beta: float) -> np.ndarray:
    """The basis (n, 3) in which a cubical (semi-cubical) parabola with its inflection
    (cusp) at ``beta`` is linear: the coefficients (A0, A1, P3) (or (P0, P2, P3))."""
    one = np.ones_like(t)
    if kind is CurveKind.CUBICAL_PARABOLA:
        return np.stack([one, t, t**3 - 3.0 * beta * t * t], axis=1)
    return np.stack([one, t * t - 2.0 * beta * t, t**3 - 3.0 * beta**2 * t], axis=1)


def _conic_starts(kind: CurveKind, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starting unknowns of an ellipse or hyperbola from the algebraic conic fit (the
    smallest singular vector of [x^2, xy, y^2, x, y, 1]); none when that conic is of the
    other kind (the arc is then closer to the other conic or, near the boundary between
    them, to the parabola, which is tested apart)."""
    x, y = points.T
    D = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], axis=1)
    A, B, C, Dx, Ey, F = np.linalg.svd(D, full_matrices=False)[2][-1]
    M = np.array([[A, B / 2], [B / 2, C]])
    det = float(np.linalg.det(M))
    ellipse = kind is CurveKind.ELLIPSE
    starts: list[np.ndarray] = []
    if det != 0.0 and (det > 0) == ellipse:
        centre = np.linalg.solve(M, -0.5 * np.array([Dx, Ey]))
        level = -(F + 0.5 * (Dx * centre[0] + Ey * centre[1]))
        w, V = np.linalg.eigh(M)
        axes = level / w  # squared semi-axes (one negative for a hyperbola)
        if ellipse and np.all(axes > 0):
            starts.append(_conic_unknowns(np.sqrt(axes), V, centre))
        elif not ellipse:
            i = int(np.argmax(axes))
            if axes[i] > 0:
                rot = V[:, [i, 1 - i]]
                ab = np.sqrt([axes[i], -axes[1 - i]])
                starts.append(_conic_unknowns(ab, rot, centre))
    if not starts:
        return np.zeros((0, 5)), np.zeros((0, points.shape[0]))
    g = np.array(starts)
    return g, _conic_parameters(kind, g, points)


def _conic_unknowns(ab: np.ndarray, rot: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(a, b, theta, centre) of a conic with semi-axes ``ab`` along the columns of ``rot``."""
    if np.linalg.det(rot) < 0:
        rot = rot * np.array([1.0, -1.0])
    return np.array([ab[0], ab[1], np.arctan2(rot[1, 0], rot[0, 0]), *centre])


def _conic_parameters(kind: CurveKind, g: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Each point's parameter on the conics ``g`` (S, 5) from its angle about the centre;
    a hyperbola whose points lie on the other branch is turned by pi."""
    local = np.einsum("sji,snj->sni", rotation_2d(g[:, 2]), points[None] - g[:, None, 3:5])
    if kind is CurveKind.ELLIPSE:
        return np.unwrap(np.arctan2(local[..., 1] / g[:, 1:2], local[..., 0] / g[:, 0:1]))
    flip = np.median(local[..., 0], axis=1) < 0
    g[flip, 2] += np.pi
    local[flip] = -local[flip]
    return np.arcsinh(local[..., 1] / g[:, 1:2])


def _reduced(
    kind: CurveKind, g: np.ndarray, centre: np.ndarray, scale: float
) -> CanonicalReduction:
    """The canonical form of a fitted polynomial class, in the data's units."""
    c = _polynomial_coefficients(kind, g[None])[0] * scale
    c[0] += centre
    if kind is CurveKind.PARABOLA:
        return reduce_parabola(c[2, 0], c[1, 0], c[0, 0], c[2, 1], c[1, 1], c[0, 1])
    if kind is CurveKind.CUBIC_SPLINE:
        return reduce_cubic_spline(*c[::-1, 0], *c[::-1, 1])
    # shift the parameter to the inflection or cusp, u = tau + beta
    beta = float(g[6])
    s = np.stack([_compose(c[:, j], beta) for j in range(2)], axis=1)
    if kind is CurveKind.CUBICAL_PARABOLA:
        reduction = reduce_cubical_parabola(s[3, 0], s[1, 0], s[0, 0], s[3, 1], s[1, 1], s[0, 1])
    else:
        reduction = reduce_semicubical_parabola(
            s[3, 0], s[2, 0], s[0, 0], s[3, 1], s[2, 1], s[0, 1]
        )
    return CanonicalReduction(
        reduction.curve,
        reduction.theta,
        reduction.T_data_from_canonical,
        reduction.u_scale,
        reduction.u_offset - reduction.u_scale * beta,
    )


def _conic_reduction(
    kind: CurveKind, g: np.ndarray, u: np.ndarray, centre: np.ndarray, scale: float
) -> tuple[CanonicalReduction, np.ndarray]:
    """The canonical form (a, b > 0) of a fitted conic, in the data's units, and the
    points' parameters on it: a negative a is the hyperbola's other branch (turned by pi)
    or the ellipse run from the other side (u -> pi - u); a negative b, u -> -u."""
    a, b, theta = g[0], g[1], float(g[2])
    if a < 0:
        if kind is CurveKind.HYPERBOLA:
            theta, b = theta + np.pi, -b
        else:
            u = np.pi - u
    if b < 0:
        u = -u
    T = np.eye(3)
    T[:2, :2] = rotation_2d(theta)
    T[:2, 2] = centre + scale * g[3:5]
    curve = CanonicalCurve(kind, (abs(a) * scale, abs(b) * scale))
    return CanonicalReduction(curve, theta, T, 1.0, 0.0), u


def _compose(c: np.ndarray, beta: float) -> np.ndarray:
    """Coefficients of sum_k c_k (tau + beta)^k in tau."""
    out = np.zeros_like(c)
    for k, ck in enumerate(c):
        out[: k + 1] += ck * P.polypow([beta, 1.0], k)
    return out


def _as_spline(kind: CurveKind, g: np.ndarray) -> np.ndarray:
    """The unknowns of the cubic spline that is the same curve as a polynomial class's."""
    return _polynomial_coefficients(kind, g[None])[0].reshape(8)


def _fit(
    kind: CurveKind,
    solved: tuple[np.ndarray, np.ndarray] | None,
    q: np.ndarray,
    centre: np.ndarray,
    scale: float,
) -> PointFit | None:
    """A solved class in the data's units and canonical form."""
    if solved is None:
        return None
    g, u = solved
    r, jacobian = (a[0] for a in _residuals(kind, g[None], u[None], q))
    pos, vel, _, _ = _curve(kind, g[None], u[None], jacobian=False)
    sign = np.where(np.einsum("nc,nc->n", q - pos[0], vel[0] @ _J.T) < 0, -1.0, 1.0)
    r = sign * r * scale
    fitted = np.zeros((len(r), 0))
    if np.isfinite(jacobian).all():
        fitted = orth(sign[:, None] * jacobian, rcond=RANK_TOLERANCE)
    try:
        if kind in _POLYNOMIAL:
            reduction = _reduced(kind, g, centre, scale)
            u = reduction.canonical_parameter(u)
        else:
            reduction, u = _conic_reduction(kind, g, u, centre, scale)
    except DegenerateGeometry:
        return None
    return PointFit(kind, reduction, u, r, fitted)


def fit_classes(points: ArrayLike) -> dict[CurveKind, PointFit | None]:
    """Every class of the tree fitted to ordered ``points`` (n, 2) by orthogonal distance
    regression (module docstring); None for a class when no start gives a finite fit or
    the fitted curve is degenerate (e.g. a cubic whose cubic term vanished).

    The classes: the conics of Section 3.2.1 placed by a rigid motion; the parabola as a
    parametric quadratic (3.4); the cubic spline as any parametric cubic (3.25), reduced to
    its canonical form (3.35); the cubical and semi-cubical parabolas as cubics with an
    inflection or a cusp (Section 3.2.2).

    Starts: the conics from the algebraic conic fit; the parabola and a first cubic
    spline from parametric polynomials fitted by parameter correction; the cubical and
    semi-cubical parabolas from the best special points at that spline's parameters
    (:func:`_special_point_starts`), the semi-cubical parabola also from a cusp just
    beyond either end (:func:`_cusp_starts`); the cubic spline, which holds every polynomial class,
    from its first fit and from the other polynomial classes' fits, so that it fits at
    least as well as each of them.
    """
    p = np.asarray(points, dtype=float)
    centre = p.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((p - centre) ** 2, axis=1))))
    q = (p - centre) / scale
    solved: dict[CurveKind, tuple[np.ndarray, np.ndarray] | None] = {}
    for kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        g, u = _conic_starts(kind, q)
        solved[kind] = _solve(kind, g, u, q) if len(g) else None
    c, t = _corrected_polynomial(q, 2)
    solved[CurveKind.PARABOLA] = _solve(CurveKind.PARABOLA, c.reshape(1, 6), t[None], q)
    c, t = _corrected_polynomial(q, 3)
    first = _solve(CurveKind.CUBIC_SPLINE, c.reshape(1, 8), t[None], q)
    if first is not None:
        c, t = first[0].reshape(4, 2), first[1]
    for kind in (CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA):
        g, u = _special_point_starts(kind, q, t, c)
        solved[kind] = _solve(kind, g, u, q)
    # apart, so that the screen of the special points' starts cannot drop them
    solved[CurveKind.SEMICUBICAL_PARABOLA] = _better(
        CurveKind.SEMICUBICAL_PARABOLA,
        solved[CurveKind.SEMICUBICAL_PARABOLA],
        _solve(CurveKind.SEMICUBICAL_PARABOLA, *_cusp_starts(q), q),
        q,
    )
    starts = [(c.reshape(8), t)]
    for kind in (CurveKind.PARABOLA, CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA):
        done = solved[kind]
        if done is not None:
            starts.append((_as_spline(kind, done[0]), done[1]))
    g = np.array([s[0] for s in starts])
    u = np.array([s[1] for s in starts])
    solved[CurveKind.CUBIC_SPLINE] = _solve(CurveKind.CUBIC_SPLINE, g, u, q)
    return {kind: _fit(kind, solved[kind], q, centre, scale) for kind in TREE_CLASSES}
