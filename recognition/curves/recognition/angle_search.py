"""Starting shapes of the parabola and the two-parameter classes from kappa and phi alone.

On noisy estimates kappa_s is the least reliable input, and the thesis's invariants
that use it (I_p (3.10), I_c1/I_c2 (3.19)-(3.20), the slope quartics (3.31), (3.34))
start the fits far from the data. These starts use the curvature and the tangent angle
only. For a rotation psi of the data into the canonical frame, each contact's tangent
angle fixes its parameter t up to the shape's one scale-free parameter (none for the
parabola: all parabolas are similar), thesis Eqs. (3.5), (3.11), (3.21), (3.26) and the
semi-cubical slope; its curvature then gives the shape's size. The shape is consistent
where every contact gives the same size; a grid of (shape parameter, psi) is scored by
the spread of the log sizes and its best cells are the starts.

Conventions follow :mod:`recognition.curves.families`: the canonical curve traversed
with increasing t; a datum's direction in the canonical frame is ``phi + psi`` and
``sigma = +1`` when it agrees with increasing t.
"""

from __future__ import annotations

import numpy as np

from recognition.curves.families import CurveKind

__all__ = [
    "ANGLE_STEPS",
    "SHAPE_STEPS",
    "SPREAD_CAP",
    "angle_starts",
    "local_minima",
]

#: Rotations psi tried, uniform over a full turn.
ANGLE_STEPS = 256
#: Values of the scale-free shape parameter tried.
SHAPE_STEPS = 48
#: A contact that contradicts a cell (wrong sign, impossible slope) counts as a squared
#: log-size deviation of this much; so does any larger deviation.
SPREAD_CAP = 1.0


def _shape_grid(kind: CurveKind) -> np.ndarray:
    """The scale-free shape parameter values tried for ``kind``."""
    if kind is CurveKind.ELLIPSE:  # b / a
        return np.asarray(np.geomspace(0.05, 1.0, SHAPE_STEPS))
    if kind is CurveKind.HYPERBOLA:  # b / a
        return np.asarray(np.geomspace(0.05, 20.0, SHAPE_STEPS))
    if kind in (CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA):  # b
        u = (np.arange(SHAPE_STEPS) + 0.5) / SHAPE_STEPS * np.pi - np.pi / 2
        return np.asarray(np.tan(u))
    return np.zeros(1)  # the parabola: one shape up to scale


def _cells(
    kind: CurveKind, shape: np.ndarray, theta: np.ndarray, kappa: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per cell (shape, psi) and contact: log size, validity, parameter t and sigma.

    ``shape`` (S, 1, 1), ``theta`` (1, P, m) data directions in the canonical frame,
    ``kappa`` (m,). The size is a for the parabola (3.5), ellipse (3.11) and hyperbola
    (3.21) (b = shape * a), |a| of the cubical parabola (3.26) (signed through t) and a
    of the semi-cubical parabola.
    """
    c, s = np.cos(theta), np.sin(theta)
    k = np.abs(kappa)
    if kind is CurveKind.PARABOLA:
        # direction of increasing t is (t, 1): t = cot theta, sigma = sign(sin theta)
        sigma = np.sign(s)
        valid = np.sign(kappa) == -sigma  # canonical kappa < 0
        log_size = np.log(np.abs(s) ** 3 / (2.0 * k))
        t = c / s
    elif kind is CurveKind.ELLIPSE:
        sigma = np.broadcast_to(np.sign(kappa), theta.shape)  # canonical kappa > 0
        c1, s1 = sigma * c, sigma * s  # the canonical direction (-a sin t, b cos t)
        t = np.arctan2(s1 / shape, -c1)
        st, ct = np.sin(t), np.cos(t)
        log_size = np.log(shape / (k * (st * st + (shape * ct) ** 2) ** 1.5))
        valid = np.ones(theta.shape, dtype=bool)
    elif kind is CurveKind.HYPERBOLA:
        sigma = np.broadcast_to(-np.sign(kappa), theta.shape)  # canonical kappa < 0
        c1, s1 = sigma * c, sigma * s  # the canonical direction (a sinh t, b cosh t)
        ratio = shape * c1 / s1
        valid = (s1 > 0) & (np.abs(ratio) < 1.0)
        t = np.arctanh(np.clip(ratio, -0.999999, 0.999999))
        sh, ch = np.sinh(t), np.cosh(t)
        log_size = np.log(shape / (k * (sh * sh + (shape * ch) ** 2) ** 1.5))
    elif kind is CurveKind.CUBICAL_PARABOLA:
        # increasing t goes towards +x; a t^2 = (lam - b) / 3, a t = sigma kappa cos^-3 / 6
        sigma = np.sign(c)
        lam = s / c
        at = sigma * kappa / (6.0 * np.abs(c) ** 3)
        at2 = (lam - shape) / 3.0
        a = at * at / at2
        log_size = np.log(np.abs(a))
        t = at / a
        valid = np.isfinite(log_size)
    else:  # semi-cubical: lam = 3 a t / 2 + b, |kappa| = 9 a^2 |cos|^3 / (8 |lam - b|)
        lam = s / c
        a = np.sqrt(8.0 * k * np.abs(lam - shape) / (9.0 * np.abs(c) ** 3))
        t = 2.0 * (lam - shape) / (3.0 * a)
        sigma = np.sign(c) * np.sign(t)
        valid = sigma == np.sign(kappa)  # canonical kappa > 0 for a > 0
        log_size = np.log(a)
    return log_size, valid & np.isfinite(log_size), t, sigma


def local_minima(
    score: np.ndarray, periodic_columns: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the finite cells of a 2-D score no larger than their eight
    neighbours; with ``periodic_columns`` the last column neighbours the first (an
    angle)."""
    if periodic_columns:
        padded = np.pad(score, ((1, 1), (0, 0)), constant_values=np.inf)
        padded = np.concatenate([padded[:, -1:], padded, padded[:, :1]], axis=1)
    else:
        padded = np.pad(score, 1, constant_values=np.inf)
    centre = padded[1:-1, 1:-1]
    is_min = np.isfinite(centre)
    n0, n1 = score.shape
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                is_min &= centre <= padded[1 + di : 1 + di + n0, 1 + dj : 1 + dj + n1]
    i, j = np.nonzero(is_min)
    return i, j


def angle_starts(
    kind: CurveKind,
    kappa: np.ndarray,
    phi: np.ndarray,
    weight: np.ndarray,
    n_starts: int,
) -> list[tuple[tuple[float, ...], np.ndarray, float, float]]:
    """The best ``n_starts`` starting hypotheses of ``kind`` from kappa and phi.

    Parameters
    ----------
    kind : CurveKind
        The parabola, ellipse, hyperbola, cubical or semi-cubical parabola.
    kappa, phi : (m,) float
        Curvature and tangent angle (relative to the first) at m >= 3 contacts.
    weight : (m,) float
        Weight of each contact's log size (e.g. its inverse relative variance).
    n_starts : int

    Returns
    -------
    list of (params, t, psi, sigma)
        Shape parameters, contact parameters (m,), rotation and orientation.
    """
    shape = _shape_grid(kind)[:, None, None]
    psi = np.linspace(0.0, 2.0 * np.pi, ANGLE_STEPS, endpoint=False)
    theta = (phi[None, :] + psi[:, None])[None]  # (1, P, m)
    with np.errstate(all="ignore"):
        log_size, valid, t, sigma = _cells(kind, shape, theta, kappa)
        w = np.broadcast_to(weight, valid.shape) * valid
        total = np.sum(w, axis=-1)
        mean = np.sum(np.where(valid, w * log_size, 0.0), axis=-1) / total
        dev = np.minimum((log_size - mean[..., None]) ** 2, SPREAD_CAP)
        dev = np.where(valid, dev, SPREAD_CAP)
        # one orientation along the whole curve
        same = np.abs(np.sum(np.where(valid, sigma, 0.0), axis=-1)) == np.sum(valid, axis=-1)
        score = np.sum(weight * dev, axis=-1) / np.sum(weight)
        score = np.where(np.isfinite(mean) & same, score, np.inf)
    i_shape, i_psi = local_minima(score, periodic_columns=True)
    order = np.argsort(score[i_shape, i_psi], kind="stable")[:n_starts]
    starts: list[tuple[tuple[float, ...], np.ndarray, float, float]] = []
    for i, j in zip(i_shape[order], i_psi[order], strict=True):
        size = float(np.exp(mean[i, j]))
        t_ij = t[i if t.shape[0] > 1 else 0, j]
        ok = valid[i, j]
        sig = float(np.sign(np.sum(np.where(ok, sigma[i if sigma.shape[0] > 1 else 0, j], 0))))
        p = float(shape[i, 0, 0])
        params: tuple[float, ...]
        if kind is CurveKind.PARABOLA:
            params = (size,)
        elif kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
            params = (size, p * size)
        elif kind is CurveKind.CUBICAL_PARABOLA:
            # a t^2 = (lam - b) / 3: a has the sign of lam - b
            lam = np.tan(theta[0, j])
            a = size * float(np.sign(np.nanmedian(np.where(ok, lam - p, np.nan))))
            params = (a, p)
        else:
            params = (size, p)
        t_ij = np.where(ok, t_ij, np.nan)
        if np.all(np.isnan(t_ij)):
            continue
        idx = np.arange(t_ij.size)
        t_ij = np.interp(idx, idx[~np.isnan(t_ij)], t_ij[~np.isnan(t_ij)])
        starts.append((params, t_ij, float(psi[j]), sig or 1.0))
    return starts
