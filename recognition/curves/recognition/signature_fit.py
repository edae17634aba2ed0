"""Least-squares fit of the exact canonical signature to the estimates of one class.

Unknowns are the shape parameters, the rotation psi between data and canonical frame
(when tangent rotations are given) and each contact's parameter t_i; residuals are
``kappa_i - sigma kappa(t_i)`` and ``kappa_s,i - kappa_s(t_i)`` (divided by the measured
magnitude plus its median over the points) and ``sin(phi_i + psi - theta(t_i))``, with
kappa and kappa_s of the canonical form by thesis Eqs. (3.1)-(3.2). The reduced RMS
residual (divided by the degrees of freedom left) is the class's consistency measure,
comparable across classes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

from recognition.curves.families import (
    CurveKind,
    canonical_derivatives,
    curvature,
    curvature_derivative,
    tangent_angle,
)
from recognition.curves.recognition.results import ClassFit
from recognition.errors import DegenerateGeometry, InvalidCurveData

__all__ = [
    "N_REFINED",
    "ContactData",
    "Guess",
    "best_fit",
    "canonical_form",
    "canonical_parameters",
    "contact_data",
    "initial_guess",
    "psi_guess",
    "reduced_rms",
    "refine",
    "refine_best",
    "rejected",
    "signature_residuals",
]


@dataclass(frozen=True)
class ContactData:
    """Checked estimates at m contacts and the scales of their residuals.

    Attributes
    ----------
    kappa, kappa_s : (m,) float
        Curvature (1/length) and its arc-length derivative (1/length^2).
    phi : (m,) float or None
        Tangent angles (radians) relative to the first estimate, when measured.
    kappa_scale, kappa_s_scale : (m,) float
        Per-point scales of the kappa and kappa_s residuals.
    """

    kappa: np.ndarray
    kappa_s: np.ndarray
    phi: np.ndarray | None
    kappa_scale: np.ndarray
    kappa_s_scale: np.ndarray

    @property
    def m(self) -> int:
        """Number of contacts."""
        return self.kappa.size

    @property
    def measured_phi(self) -> np.ndarray:
        """The tangent angles; :class:`InvalidCurveData` when they were not given."""
        if self.phi is None:
            raise InvalidCurveData("this hypothesis needs the tangent rotations dphi")
        return self.phi

    def subset(self, keep: np.ndarray) -> ContactData:
        """The points ``keep``, tangent angles again relative to the first of them."""
        return ContactData(
            self.kappa[keep],
            self.kappa_s[keep],
            None if self.phi is None else self.phi[keep] - self.phi[keep][0],
            self.kappa_scale[keep],
            self.kappa_s_scale[keep],
        )


def contact_data(kappa: ArrayLike, kappa_s: ArrayLike, dphi: ArrayLike | None) -> ContactData:
    """Check kappa, kappa_s (and the tangent rotations ``dphi``) at m >= 3 contacts.

    Raises :class:`InvalidCurveData` for mismatched, too few or non-finite values and
    :class:`DegenerateGeometry` when kappa is zero everywhere.
    """
    kappa = np.asarray(kappa, dtype=float).ravel()
    kappa_s = np.asarray(kappa_s, dtype=float).ravel()
    if kappa.shape != kappa_s.shape:
        raise InvalidCurveData(
            f"kappa and kappa_s must have the same length, got {kappa.size} and {kappa_s.size}"
        )
    if kappa.size < 3:
        raise InvalidCurveData(f"expected kappa, kappa_s at three or more points, got {kappa.size}")
    if not (np.all(np.isfinite(kappa)) and np.all(np.isfinite(kappa_s))):
        raise InvalidCurveData("kappa and kappa_s must be finite; got NaN or infinity")
    phi: np.ndarray | None = None
    if dphi is not None:
        phi = np.asarray(dphi, dtype=float).ravel()
        if phi.shape != kappa.shape or not np.all(np.isfinite(phi)):
            raise InvalidCurveData(
                f"dphi must hold {kappa.size} finite tangent rotations (radians), "
                f"got shape {phi.shape}"
            )
        phi = phi - phi[0]
    kappa_ref = float(np.median(np.abs(kappa)))
    if not np.any(kappa != 0):
        raise DegenerateGeometry(
            "kappa is zero at every point: a straight segment has no curvature invariants"
        )
    # residuals are relative where the values are large and relative to the typical
    # magnitude where they are small: estimation errors grow with |kappa| and |kappa_s|
    kappa_scale = np.abs(kappa) + max(kappa_ref, 1e-300)
    kappa_s_scale = np.abs(kappa_s) + float(np.median(np.abs(kappa_s))) + kappa_ref**2
    return ContactData(kappa, kappa_s, phi, kappa_scale, kappa_s_scale)


def signature_residuals(
    kind: CurveKind,
    params: tuple[np.ndarray, ...],
    t: np.ndarray,
    psi: np.ndarray,
    sigma: np.ndarray,
    data: ContactData,
) -> np.ndarray:
    """Relative residuals of a batch of hypotheses against the canonical signature,
    thesis Eqs. (3.1)-(3.2).

    ``params`` is a tuple of (B,) arrays, ``t`` (B, m), ``psi`` and ``sigma`` (B,).
    Returns (B, 2m) or (B, 3m): kappa, kappa_s and (with tangent angles) slope blocks.
    """
    with np.errstate(all="ignore"):
        d = canonical_derivatives(kind, params, t)
        k, ks = curvature(d), curvature_derivative(d)
        parts = [
            (sigma[:, None] * k - data.kappa) / data.kappa_scale,
            (ks - data.kappa_s) / data.kappa_s_scale,
        ]
        if data.phi is not None:
            parts.append(np.sin(data.phi + psi[:, None] - tangent_angle(d)))
        r = np.concatenate(parts, axis=1)
    return np.where(np.isfinite(r), r, 1e6)


@dataclass(frozen=True)
class Guess:
    """An initial hypothesis: shape, contact parameters, rotation and orientation."""

    params: tuple[float, ...]
    t: np.ndarray
    psi: float
    sigma: float
    invariants: dict[str, np.ndarray]


def reduced_rms(r: np.ndarray, n_unknowns: int) -> np.ndarray:
    """RMS residual per degree of freedom left, (B, n_res) -> (B,)."""
    return np.sqrt(np.sum(r**2, axis=-1) / max(r.shape[-1] - n_unknowns, 1))


def _least_squares(
    kind: CurveKind, n_p: int, x0: np.ndarray, sigma: float, data: ContactData
) -> tuple[np.ndarray, np.ndarray]:
    """Minimise the residuals over x = (params, [psi], t_1..t_m); returns (x, residuals).

    The Jacobian is a central difference, taken for all columns in one batched
    evaluation: column by column for the shape parameters and psi, and for all t_i at
    once (residual i depends on t_i only).
    """
    use_psi = data.phi is not None
    head = n_p + (1 if use_psi else 0)
    m = data.m
    n_blocks = 3 if use_psi else 2
    sigma_1 = np.array([sigma])

    def batch(X: np.ndarray) -> np.ndarray:
        B = X.shape[0]
        params = tuple(X[:, j] for j in range(n_p))
        psi = X[:, n_p] if use_psi else np.zeros(B)
        return signature_residuals(kind, params, X[:, head:], psi, np.repeat(sigma_1, B), data)

    def fun(x: np.ndarray) -> np.ndarray:
        return batch(x[None])[0]

    def jac(x: np.ndarray) -> np.ndarray:
        h = 1e-6 * np.maximum(1.0, np.abs(x))
        X = np.repeat(x[None], 2 * head + 2, axis=0)
        for j in range(head):
            X[2 * j, j] += h[j]
            X[2 * j + 1, j] -= h[j]
        X[-2, head:] += h[head:]
        X[-1, head:] -= h[head:]
        F = batch(X)
        J = np.zeros((n_blocks * m, x.size))
        J[:, :head] = ((F[0 : 2 * head : 2] - F[1 : 2 * head : 2]) / (2 * h[:head, None])).T
        diag = (F[-2] - F[-1]) / np.tile(2 * h[head:], n_blocks)
        J[np.arange(n_blocks * m), head + np.tile(np.arange(m), n_blocks)] = diag
        return J

    with np.errstate(all="ignore"):
        sol = least_squares(fun, x0, jac=jac, method="lm", x_scale="jac", max_nfev=100)
    return sol.x, sol.fun


def refine(kind: CurveKind, guess: Guess, data: ContactData) -> ClassFit:
    """Least-squares refinement of (params, psi, t_i) from an initial guess."""
    n_p = len(guess.params)
    use_psi = data.phi is not None
    head = n_p + (1 if use_psi else 0)
    x0 = np.concatenate([guess.params, [guess.psi] if use_psi else [], guess.t])
    x, r = _least_squares(kind, n_p, x0, guess.sigma, data)
    params, t, sigma = canonical_form(kind, tuple(float(v) for v in x[:n_p]), x[head:], guess.sigma)
    return ClassFit(
        kind,
        params,
        float(reduced_rms(r, x0.size)),
        t.copy(),
        float(np.mod(x[n_p], 2 * np.pi)) if use_psi else None,
        int(sigma),
        guess.invariants,
        per_point=np.sqrt(np.sum(r.reshape(-1, data.m) ** 2, axis=0)),
    )


#: Number of best-scoring initial guesses of a class that are refined.
N_REFINED = 2


def refine_best(
    kind: CurveKind,
    guesses: list[Guess],
    data: ContactData,
    message: str,
    n_refined: int = N_REFINED,
) -> ClassFit:
    """Score every initial guess in one batch and refine the best ``n_refined``."""
    guesses = [g for g in guesses if all(np.isfinite(g.params)) and np.all(np.isfinite(g.t))]
    if not guesses:
        return rejected(kind, message)
    params = tuple(np.array([g.params[j] for g in guesses]) for j in range(len(guesses[0].params)))
    r = signature_residuals(
        kind,
        params,
        np.stack([g.t for g in guesses]),
        np.array([g.psi for g in guesses]),
        np.array([g.sigma for g in guesses]),
        data,
    )
    order = np.argsort(reduced_rms(r, 0))[:n_refined]
    return best_fit([refine(kind, guesses[i], data) for i in order])


def canonical_form(
    kind: CurveKind, params: tuple[float, ...], t: np.ndarray, sigma: float
) -> tuple[tuple[float, ...], np.ndarray, float]:
    """Report equivalent shapes one way: (a, b) positive for conics, a > 0 for x = t^2 classes.

    ``x = t^2, y = a t^3 + b t^2 + c t`` with ``t -> -t`` is the same curve with
    (-a, b, -c), traversed the other way; for the semi-cubical parabola (-a, b).
    """
    p = list(params)
    if kind in (CurveKind.PARABOLA, CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        p = [abs(v) for v in p]
    elif kind in (CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE) and p[0] < 0:
        p[0] = -p[0]
        if kind is CurveKind.CUBIC_SPLINE:
            p[2] = -p[2]
        t, sigma = -t, -sigma
    return tuple(p), t, sigma


def canonical_parameters(kind: CurveKind | str, params: Sequence[float]) -> tuple[float, ...]:
    """The representative of a shape's equivalent parameter sets that the tree reports."""
    kind = CurveKind(kind)
    return canonical_form(kind, tuple(float(v) for v in params), np.zeros(0), 1.0)[0]


def rejected(kind: CurveKind, message: str) -> ClassFit:
    """A hypothesis rejected outright: no parameters, infinite residual, ``message`` why."""
    return ClassFit(kind, (), float("inf"), np.array([]), None, 1, {}, message)


def psi_guess(data: ContactData, kind: CurveKind, params: tuple[float, ...], t: ArrayLike) -> float:
    """Rotation (radians, modulo pi) taking the data's tangent angles to those of the
    canonical curve at ``t``; 0 without tangent angles."""
    if data.phi is None:
        return 0.0
    theta = tangent_angle(canonical_derivatives(kind, params, t))
    z = np.exp(2j * (theta - data.phi))  # mod pi: orientation is carried by sigma
    return float(np.angle(z.mean()) / 2.0)


def best_fit(fits: Sequence[ClassFit]) -> ClassFit:
    """The hypothesis of smallest residual."""
    return min(fits, key=lambda f: f.residual)


def initial_guess(
    data: ContactData,
    kind: CurveKind,
    params: Sequence[float],
    t: ArrayLike,
    sigma: float,
    invariants: dict[str, np.ndarray],
) -> Guess:
    """A :class:`Guess` of shape ``params``, contacts ``t`` and orientation ``sigma``, its
    rotation from the tangent angles (:func:`psi_guess`)."""
    shape = tuple(float(v) for v in params)
    return Guess(
        shape, np.asarray(t, float), psi_guess(data, kind, shape, t), float(sigma), invariants
    )
