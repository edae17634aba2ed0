"""Uncertainty of the recognition tree's inputs and the chi-square consistency test.

A class hypothesis is consistent with the data when the standardised residuals of its
least-squares fit (each residual divided by the standard uncertainty of the datum) are no
larger than the data's errors explain: the sum of their squares, the test statistic, is
below the ``1 - significance`` quantile of its distribution. With independent Gaussian
errors that distribution is chi-square with (residuals - unknowns) degrees of freedom.
With correlated errors (the estimates of
:func:`~recognition.curves.estimation.local_fit_geometry` share input points) the
statistic of the linearised fit is a weighted sum of chi-square variables, approximated
by ``g chi2(nu)`` with matching mean and variance (Satterthwaite): with R the
covariance of the fitted residuals, ``g = tr(R^2) / tr(R)`` and ``nu = tr(R)^2 / tr(R^2)``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import chdtrc

from recognition.errors import InvalidCurveData

__all__ = [
    "DEFAULT_SIGNIFICANCE",
    "EXACT_PRECISION",
    "InputUncertainty",
    "consistency_test",
    "magnitude_scales",
]

#: Default significance of the consistency test: the probability that data of a class,
#: with errors of the stated size, are found inconsistent with it.
DEFAULT_SIGNIFICANCE = 1e-3
#: Relative uncertainty assumed when none is given: values exact to rounding (the fits
#: resolve relative residuals of 1e-13 to 1e-11 on exact data).
EXACT_PRECISION = 1e-9


def magnitude_scales(kappa: np.ndarray, kappa_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The magnitudes a relative uncertainty refers to, per contact.

    ``|kappa_i| + median |kappa|`` and ``|kappa_s,i| + median |kappa_s| + median(|kappa|)^2``:
    relative where the values are large and relative to their typical size where they
    pass through zero (an inflection, a vertex), so that no contact is taken as exact.
    """
    kappa_ref = float(np.median(np.abs(kappa)))
    kappa_s_ref = float(np.median(np.abs(kappa_s)))
    return np.abs(kappa) + kappa_ref, np.abs(kappa_s) + kappa_s_ref + kappa_ref * kappa_ref


def _per_contact(value: ArrayLike, m: int, name: str) -> np.ndarray:
    """A scalar or (m,) array of non-negative finite uncertainties, as (m,)."""
    v = np.asarray(value, dtype=float)
    if v.ndim > 1 or (v.ndim == 1 and v.size != m):
        raise InvalidCurveData(
            f"the uncertainty of {name} must be a number or hold one value per contact "
            f"({m}), got shape {v.shape}"
        )
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise InvalidCurveData(
            f"the uncertainty of {name} must be finite and non-negative, got {value!r}"
        )
    return np.broadcast_to(v, (m,)).astype(float)


@dataclass(frozen=True)
class InputUncertainty:
    """Standard uncertainty of kappa, kappa_s and the tangent angles at each contact.

    Each datum's standard deviation is the root sum of squares of its absolute and its
    relative part; the relative part refers to :func:`magnitude_scales`. The tangent
    angles are those the rotations ``dphi`` are measured between: their common rotation
    is an unknown of every fit, so an error shared by all of them does not count.

    Attributes
    ----------
    kappa, kappa_s : float or (m,) float
        Absolute uncertainty of the curvature (1/length) and of its arc-length
        derivative (1/length^2).
    phi : float or (m,) float
        Absolute uncertainty of each tangent angle, radians.
    kappa_relative, kappa_s_relative : float
        Relative uncertainty of the curvature and of its derivative.
    correlation : (3m, 3m) float, optional
        Correlation of the errors, ordered kappa (m), kappa_s (m), phi (m); independent
        when omitted.
    """

    kappa: float | np.ndarray = 0.0
    kappa_s: float | np.ndarray = 0.0
    phi: float | np.ndarray = 0.0
    kappa_relative: float = 0.0
    kappa_s_relative: float = 0.0
    correlation: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("kappa_relative", "kappa_s_relative"):
            value = getattr(self, name)
            ok = isinstance(value, numbers.Real) and math.isfinite(value) and float(value) >= 0
            if not ok:
                raise InvalidCurveData(
                    f"{name} must be a finite non-negative number, got {value!r}"
                )

    @classmethod
    def relative(cls, precision: float, phi: float | None = None) -> InputUncertainty:
        """The same relative uncertainty for kappa and kappa_s, and ``phi`` (radians,
        default ``precision``) for the tangent angles."""
        return cls(
            phi=precision if phi is None else phi,
            kappa_relative=precision,
            kappa_s_relative=precision,
        )

    @classmethod
    def from_covariance(cls, covariance: ArrayLike) -> InputUncertainty:
        """Absolute uncertainties and their correlation from a covariance (3m, 3m) of the
        errors of kappa (m), kappa_s (m) and phi (m)."""
        cov = np.asarray(covariance, dtype=float)
        if cov.ndim != 2 or cov.shape[0] != cov.shape[1] or cov.shape[0] % 3:
            raise InvalidCurveData(
                f"expected a covariance of shape (3m, 3m) (kappa, kappa_s, phi), got {cov.shape}"
            )
        std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        if not np.all(np.isfinite(cov)) or not np.all(std > 0):
            raise InvalidCurveData("the covariance must be finite with a positive diagonal")
        m = cov.shape[0] // 3
        corr = cov / np.outer(std, std)
        return cls(std[:m], std[m : 2 * m], std[2 * m :], correlation=corr)

    def standard_deviations(
        self, kappa: np.ndarray, kappa_s: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Standard deviations (m,) of kappa, kappa_s and phi at the given contacts.

        Raises :class:`InvalidCurveData` when one of them is zero (a datum taken as exact)
        or the correlation does not fit the contacts.
        """
        m = kappa.size
        scale_k, scale_ks = magnitude_scales(kappa, kappa_s)
        sk = np.hypot(_per_contact(self.kappa, m, "kappa"), self.kappa_relative * scale_k)
        sks = np.hypot(_per_contact(self.kappa_s, m, "kappa_s"), self.kappa_s_relative * scale_ks)
        sphi = _per_contact(self.phi, m, "phi")
        for name, s in (("kappa", sk), ("kappa_s", sks), ("phi", sphi)):
            if not np.all(s > 0) or not np.all(np.isfinite(s)):
                raise InvalidCurveData(
                    f"the uncertainty of {name} is zero or not finite at some contact; "
                    f"expected a positive absolute or relative uncertainty"
                )
        if self.correlation is not None:
            c = np.asarray(self.correlation, dtype=float)
            if c.shape != (3 * m, 3 * m) or not np.all(np.isfinite(c)):
                raise InvalidCurveData(
                    f"the correlation must be a finite ({3 * m}, {3 * m}) matrix for {m} "
                    f"contacts, got shape {c.shape}"
                )
        return sk, sks, sphi


def consistency_test(
    z: np.ndarray,
    jacobian: np.ndarray,
    correlation: np.ndarray | None = None,
    rank_tol: float = 1e-10,
) -> tuple[float, float, float, float]:
    """Chi-square statistic of standardised fit residuals and its p-value.

    Parameters
    ----------
    z : (n,) float
        Residuals divided by the standard deviations of the data, at the fit.
    jacobian : (n, k) float
        Their derivatives with respect to the fit's unknowns.
    correlation : (n, n) float, optional
        Correlation of the data errors (module docstring); independent when omitted.
    rank_tol : float
        Singular values of the Jacobian below this fraction of the largest are taken as
        zero (unknowns the data do not fix).

    Returns
    -------
    statistic : float
        ``sum(z^2)``.
    scale, dof : float
        The statistic is distributed as ``scale * chi2(dof)`` for consistent data.
    p_value : float
        Probability of a statistic at least as large for consistent data; NaN when no
        degree of freedom is left.
    """
    statistic = float(np.sum(z * z))
    n = z.size
    J = np.where(np.isfinite(jacobian), jacobian, 0.0)
    U, s, _ = np.linalg.svd(J, full_matrices=False)
    rank = int(np.sum(s > rank_tol * max(s.max(initial=0.0), 1e-300)))
    if correlation is None:
        scale, dof = 1.0, float(n - rank)
    else:
        Uk = U[:, :rank]
        P = np.eye(n) - Uk @ Uk.T
        R = P @ correlation @ P
        trace, trace2 = float(np.trace(R)), float(np.sum(R * R))
        scale, dof = (trace2 / trace, trace * trace / trace2) if trace > 0 else (1.0, 0.0)
    if not dof > 0 or not np.isfinite(statistic):
        return statistic, scale, dof, float("nan") if dof <= 0 else 0.0
    return statistic, scale, dof, float(chdtrc(dof, statistic / scale))
