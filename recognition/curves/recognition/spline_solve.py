"""Every cubic spline (3.35) through two contacts, by elimination: starts of the spline fit.

A spline is any polynomial curve ``P(t) = P1 t + P2 t^2 + P3 t^3`` with ``P3 != 0`` up to
a rigid motion and an affine change of t (thesis Eq. (3.25) and Section 3.2.2.3). Put the
first contact at ``t = 0``, its tangent along +x and ``|P'(0)| = 1``; then, with the
first contact's curvature ``k1`` and its derivative ``ks1`` (thesis Eqs. (3.1)-(3.2)),

    P1 = (1, 0),  P2 = (u, k1 / 2),  P3 = (v, ks1 / 6 + k1 u),

and the second contact, at an unknown t, turned by ``d`` from the first with curvature
``k2`` and derivative ``ks2``, gives three polynomial equations in (u, v, t), with
``e = (cos d, sin d)`` and ``w = e . P'(t)`` (the speed there, > 0 for traversal with
increasing t):

    E1 = e x P'(t) = 0                                   (the tangent),
    E2 = k2 w^2 - e x P''(t) = 0                          (the curvature),
    E3 = ks2 w^3 - e x P'''(t) + 3 k2 w (e . P''(t)) = 0  (its arc-length derivative).

E1 fixes u and v as functions of w and t; E2 and E3 become polynomials in (w, t) of
degree 2 and 3 in w, and their resultant in w is ``t^13 q(t)`` with q of degree 8 (the
factor t^13 is the first contact itself). The real roots of q, each with the common
root w > 0 of E2 and E3 and then u and v, polished by Newton steps on E1-E3, are every
spline through the two contacts: nothing is missed, whatever the shape. Each is reduced
to the canonical form (:func:`~recognition.curves.reduction.reduce_cubic_spline`), the
other contacts are placed on it where its tangent turns as theirs (a quadratic in t),
and the candidates are ranked by how well the other contacts' kappa and kappa_s agree:
the consistency check of THESIS_ERRATA item 7.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as npoly

from recognition.curves.reduction import reduce_cubic_spline
from recognition.errors import DegenerateGeometry

__all__ = ["RESULTANT_DEGREE", "SplineCandidates", "spline_candidates"]

#: The resultant in t is ``t^ROOT_AT_CONTACT q(t)`` with q of degree RESULTANT_DEGREE.
ROOT_AT_CONTACT = 13
RESULTANT_DEGREE = 8
#: A root w of E2 is the common root of E2 and E3 when |E3| is below this fraction of the
#: sum of its terms' magnitudes.
COMMON_ROOT_TOL = 1e-3
#: Newton steps on E1-E3 after the roots of the resultant.
POLISH_STEPS = 3
#: A root counts as real when its imaginary part is below this fraction of its modulus
#: (double roots of exact data split by rounding; the fit refines every start).
REAL_ROOT_TOL = 1e-5


@dataclass(frozen=True)
class SplineCandidates:
    """Splines through the contacts, best first.

    Attributes
    ----------
    params : (S, 3) float
        Canonical (a, b, c), ``a > 0``.
    t : (S, m) float
        Canonical parameter of every contact.
    psi : (S,) float
        Rotation taking the data's tangent angles to the canonical ones.
    sigma : (S,) float
        +1 when the data traverse the spline with increasing canonical t, else -1.
    mismatch : (S,) float
        RMS relative disagreement of the other contacts' kappa and kappa_s.
    """

    params: np.ndarray
    t: np.ndarray
    psi: np.ndarray
    sigma: np.ndarray
    mismatch: np.ndarray


def _times(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Product of polynomials in (w, t), arrays [w power, t power], truncated to (4, 6).

    The 2-D convolution as one 1-D convolution: rows padded to the product's width and
    laid end to end, so that w^i t^j lies at i * width + j in both factors and product.
    """
    rows, width = p.shape[0] + q.shape[0] - 1, p.shape[1] + q.shape[1] - 1
    a, b = np.zeros((p.shape[0], width)), np.zeros((q.shape[0], width))
    a[:, : p.shape[1]], b[:, : q.shape[1]] = p, q
    full = np.convolve(a.ravel(), b.ravel())[: rows * width].reshape(rows, width)
    return full[:4, :6]


def _polynomial(terms: dict[tuple[int, int], float]) -> np.ndarray:
    """A polynomial in (w, t) from ``{(w power, t power): coefficient}``."""
    out = np.zeros((4, 6))
    for (i, j), value in terms.items():
        out[i, j] += value
    return out


def _equations_in_w_t(
    k1: float, ks1: float, k2: float, ks2: float, d: float
) -> tuple[np.ndarray, np.ndarray]:
    """``T E2`` and ``T E3`` (module docstring) as polynomials in the speed w and t,
    arrays [w power, t power], with ``T = 3 k1 t^3``.

    E1 holds with ``P'(t) = w e``: then ``3 k1 t^2 u = A = w sin d - k1 t - ks1 t^2 / 2``
    and ``3 t^2 v = w cos d - 1 - 2 u t``, so ``T u = t A`` and
    ``T v = k1 t (w cos d - 1) - 2 A / 3`` are polynomials, and so are T P'' and T P'''.
    """
    c, s = np.cos(d), np.sin(d)
    A = _polynomial({(1, 0): s, (0, 1): -k1, (0, 2): -0.5 * ks1})
    T = _polynomial({(0, 3): 3.0 * k1})
    t = _polynomial({(0, 1): 1.0})
    w = _polynomial({(1, 0): 1.0})
    Tu = _times(t, A)
    Tv = _polynomial({(1, 1): k1 * c, (0, 1): -k1}) - 2.0 / 3.0 * A
    x2 = 2.0 * Tu + 6.0 * _times(t, Tv)  # T times the second derivative, x and y
    y2 = k1 * T + ks1 * _times(t, T) + 6.0 * k1 * _times(t, Tu)
    x3 = 6.0 * Tv  # T times the third derivative
    y3 = ks1 * T + 6.0 * k1 * Tu
    w2 = _times(w, w)
    E2 = k2 * _times(w2, T) - (c * y2 - s * x2)
    E3 = ks2 * _times(_times(w2, w), T) - (c * y3 - s * x3) + 3.0 * k2 * _times(w, c * x2 + s * y2)
    return E2, E3


def _resultant_in_w(E2: np.ndarray, E3: np.ndarray) -> np.ndarray:
    """Resultant in w of E2 (quadratic) and E3 (cubic), up to powers of E2's leading
    coefficient, as a polynomial in t (ascending): ``p2^2 E3`` reduced modulo E2 is
    ``l w + m``, and the resultant of E2 with it is ``p2 m^2 - p1 l m + p0 l^2``."""
    mul, sub = npoly.polymul, npoly.polysub
    p0, p1, p2 = E2[0], E2[1], E2[2]
    q0, q1, q2, q3 = E3[0], E3[1], E3[2], E3[3]
    r2, r1, r0 = sub(mul(p2, q2), mul(q3, p1)), sub(mul(p2, q1), mul(q3, p0)), mul(p2, q0)
    lin, const = sub(mul(p2, r1), mul(r2, p1)), sub(mul(p2, r0), mul(r2, p0))
    return np.asarray(
        npoly.polyadd(
            sub(mul(p2, mul(const, const)), mul(p1, mul(lin, const))), mul(p0, mul(lin, lin))
        )
    )


def _residuals(x: np.ndarray, k1: float, ks1: float, k2: float, ks2: float, d: float) -> np.ndarray:
    """E1, E2 and E3 at the rows (u, v, t) of ``x`` (n, 3), (n, 3)."""
    c, s = np.cos(d), np.sin(d)
    u, v, t = x[:, 0], x[:, 1], x[:, 2]
    x1, y1 = 1.0 + (2.0 * u + 3.0 * v * t) * t, (k1 + (0.5 * ks1 + 3.0 * k1 * u) * t) * t
    x2, y2 = 2.0 * u + 6.0 * v * t, k1 + (ks1 + 6.0 * k1 * u) * t
    x3, y3 = 6.0 * v, ks1 + 6.0 * k1 * u
    w = c * x1 + s * y1
    e2 = k2 * w * w - (c * y2 - s * x2)
    e3 = ks2 * w**3 - (c * y3 - s * x3) + 3.0 * k2 * w * (c * x2 + s * y2)
    return np.stack([c * y1 - s * x1, e2, e3], axis=1)


def _polish(uvt: np.ndarray, *coefficients: float, iterations: int = POLISH_STEPS) -> np.ndarray:
    """Newton steps on E1-E3 from the rows (u, v, t) of ``uvt`` (n, 3), Jacobian by
    central differences."""
    x = uvt.copy()
    for _ in range(iterations):
        h = 1e-7 * np.maximum(1.0, np.abs(x))
        steps = np.concatenate([[np.zeros(3)], np.eye(3), -np.eye(3)])  # (7, 3)
        F = _residuals((x[None] + steps[:, None] * h[None]).reshape(-1, 3), *coefficients)
        F = F.reshape(7, -1, 3)
        J = ((F[1:4] - F[4:7]) / (2.0 * h.T[:, :, None])).transpose(1, 2, 0)
        ok = np.abs(np.linalg.det(J)) > 0
        if not ok.any():
            break
        dx = np.zeros_like(x)
        dx[ok] = np.linalg.solve(J[ok], -F[0][ok][..., None])[..., 0]
        x = np.where(np.isfinite(dx), x + dx, x)
    return x


def _second_contact_roots(k1: float, ks1: float, k2: float, ks2: float, d: float) -> np.ndarray:
    """Real (u, v, t) solving E1-E3 with w > 0, (n, 3)."""
    E2, E3 = _equations_in_w_t(k1, ks1, k2, ks2, d)
    g = _resultant_in_w(E2, E3)[ROOT_AT_CONTACT : ROOT_AT_CONTACT + RESULTANT_DEGREE + 1]
    nonzero = np.flatnonzero(g)
    if nonzero.size == 0 or nonzero[-1] == 0:
        return np.zeros((0, 3))
    roots = npoly.polyroots(g[: nonzero[-1] + 1])
    t = roots.real[np.abs(roots.imag) <= REAL_ROOT_TOL * np.maximum(np.abs(roots), 1.0)]
    out = []
    for ti in t[t != 0.0]:
        powers = ti ** np.arange(6)
        e2, e3 = E2 @ powers, E3 @ powers  # coefficients in w, ascending
        for w in np.roots(e2[2::-1]):
            if abs(np.imag(w)) > REAL_ROOT_TOL * max(abs(w), 1.0) or not np.real(w) > 0:
                continue
            w = float(np.real(w))
            if abs(np.polyval(e3[::-1], w)) > COMMON_ROOT_TOL * np.polyval(np.abs(e3[::-1]), w):
                continue
            u = (w * np.sin(d) - k1 * ti - 0.5 * ks1 * ti * ti) / (3.0 * k1 * ti * ti)
            v = (w * np.cos(d) - 1.0 - 2.0 * u * ti) / (3.0 * ti * ti)
            out.append((u, v, ti))
    if not out:
        return np.zeros((0, 3))
    return _polish(np.array(out), k1, ks1, k2, ks2, d)


def _place_contacts(
    coefficients: np.ndarray, kappa: np.ndarray, kappa_s: np.ndarray, phi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Parameter of each contact on ``P(t) = sum_k coefficients[k] t^k`` ((4, 2), the
    first contact at t = 0 with tangent +x): among the roots of the tangent condition
    (a quadratic) with positive speed, the one whose kappa and kappa_s agree best; and
    the RMS relative disagreement over the contacts."""
    P1, P2, P3 = coefficients[1], coefficients[2], coefficients[3]
    t_out = np.zeros(kappa.size)
    err = np.zeros(kappa.size)
    for i in range(1, kappa.size):
        c, s = np.cos(phi[i]), np.sin(phi[i])
        # e x P'(t) = 0 with P'(t) = P1 + 2 P2 t + 3 P3 t^2
        quad = [3.0 * (c * P3[1] - s * P3[0]), 2.0 * (c * P2[1] - s * P2[0]), c * P1[1] - s * P1[0]]
        roots = np.roots(quad) if quad[0] != 0 else np.array([-quad[2] / quad[1]])
        best, best_t = np.inf, np.nan
        for r in roots:
            if abs(np.imag(r)) > REAL_ROOT_TOL * max(abs(r), 1.0):
                continue
            t = float(np.real(r))
            d1 = P1 + 2.0 * P2 * t + 3.0 * P3 * t * t
            d2 = 2.0 * P2 + 6.0 * P3 * t
            d3 = 6.0 * P3
            speed = np.hypot(*d1)
            if not c * d1[0] + s * d1[1] > 0:
                continue
            cross = d1[0] * d2[1] - d1[1] * d2[0]
            k = cross / speed**3
            dk = (d1[0] * d3[1] - d1[1] * d3[0]) / speed**3 - 3.0 * cross * (d1 @ d2) / speed**5
            ks = dk / speed
            scale_k = abs(kappa[i]) + abs(kappa[0])
            scale_ks = abs(kappa_s[i]) + kappa[0] ** 2 + kappa[i] ** 2
            e = ((k - kappa[i]) / scale_k) ** 2 + ((ks - kappa_s[i]) / scale_ks) ** 2
            if e < best:
                best, best_t = e, t
        t_out[i], err[i] = best_t, best
    return t_out, err


def spline_candidates(
    kappa: np.ndarray, kappa_s: np.ndarray, phi: np.ndarray, pair: tuple[int, int]
) -> SplineCandidates:
    """Every spline (3.35) through the contacts ``pair``, a polynomial cubic (3.25) whose
    kappa and kappa_s (thesis Eqs. (3.1)-(3.2)) and tangent turn match theirs (module
    docstring), with every contact placed on it, best agreement of the others first.

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative in the order of traversal.
    phi : (m,) float
        Tangent angle of each contact (radians), relative to any fixed direction.
    pair : (int, int)
        The two contacts that fix the candidates.
    """
    i, j = pair
    scale = abs(kappa[i])
    m = kappa.size
    empty = SplineCandidates(
        np.zeros((0, 3)), np.zeros((0, m)), np.zeros(0), np.zeros(0), np.zeros(0)
    )
    if scale == 0:
        return empty
    k1, ks1 = kappa[i] / scale, kappa_s[i] / scale**2
    k2, ks2 = kappa[j] / scale, kappa_s[j] / scale**2
    d = float(phi[j] - phi[i])
    with np.errstate(all="ignore"):
        roots = _second_contact_roots(k1, ks1, k2, ks2, d)
    order = np.r_[i, np.delete(np.arange(m), i)]
    rows = []
    for u, v, _ in roots:
        coefficients = np.array([[0.0, 0.0], [1.0, 0.0], [u, 0.5 * k1], [v, ks1 / 6.0 + k1 * u]])
        with np.errstate(all="ignore"):
            t_local, err = _place_contacts(
                coefficients,
                kappa[order] / scale,
                kappa_s[order] / scale**2,
                phi[order] - phi[i],
            )
        if not np.all(np.isfinite(t_local)):
            continue
        P = coefficients / scale  # back to the data's length unit, same t
        try:
            red = reduce_cubic_spline(
                P[3, 0], P[2, 0], P[1, 0], 0.0, P[3, 1], P[2, 1], P[1, 1], 0.0
            )
        except DegenerateGeometry:
            continue
        if len(red.params) != 3:
            continue
        t = np.empty(m)
        t[order] = red.canonical_parameter(t_local)
        # canonical angle = angle in this frame - theta; this frame = data angles - phi[i]
        psi = -red.theta - phi[i]
        rows.append((red.params, t, psi, np.sign(red.u_scale), float(np.sqrt(np.mean(err)))))
    if not rows:
        return empty
    rows.sort(key=lambda r: r[4])
    return SplineCandidates(
        np.array([r[0] for r in rows]),
        np.array([r[1] for r in rows]),
        np.array([r[2] for r in rows]),
        np.array([r[3] for r in rows], dtype=float),
        np.array([r[4] for r in rows]),
    )
