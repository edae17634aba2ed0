"""Random curves of each class, placed by a rigid motion and sampled as a tactile sensor would."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.errors import InvalidCurveData
from recognition.rigid import apply_pose

__all__ = [
    "SampledCurve",
    "random_curve",
    "sample_by_arc_length",
]


@dataclass(frozen=True)
class SampledCurve:
    """Tactile samples of a canonical curve, with the ground truth kept apart.

    Attributes
    ----------
    points : (n, 2) float
        Measured points in the data frame, ordered along the curve, noise included.
    t : (n,) float
        True curve parameter of each sample.
    curve : CanonicalCurve
        The sampled curve in its canonical frame.
    T_data_from_canonical : (3, 3) float
        Homogeneous rigid motion that placed the canonical curve in the data frame.
    noise_std : float
        Standard deviation of the isotropic Gaussian noise added to each coordinate.
    """

    points: np.ndarray
    t: np.ndarray
    curve: CanonicalCurve
    T_data_from_canonical: np.ndarray
    noise_std: float

    @property
    def true_points(self) -> np.ndarray:
        """(n, 2) noise-free points in the data frame."""
        return apply_pose(self.T_data_from_canonical, self.curve.points(self.t))


def sample_by_arc_length(
    curve: CanonicalCurve,
    t_start: float,
    t_end: float,
    spacing: float,
    *,
    rng: np.random.Generator | None = None,
    noise_std: float = 0.0,
    T_data_from_canonical: np.ndarray | None = None,
) -> SampledCurve:
    """Points at equal arc-length ``spacing`` from ``t_start`` towards ``t_end``.

    Parameters
    ----------
    curve : CanonicalCurve
    t_start, t_end : float
        Parameter interval; the traversal runs from ``t_start`` to ``t_end`` (either order).
    spacing : float
        Arc length between consecutive samples (same unit as the curve).
    rng : numpy.random.Generator, optional
        Needed when ``noise_std > 0``.
    noise_std : float
        Isotropic Gaussian noise added to each coordinate.
    T_data_from_canonical : (3, 3) float, optional
        Rigid motion into the data frame (identity if omitted).
    """
    if not spacing > 0:
        raise InvalidCurveData(f"spacing must be positive, got {spacing}")
    if noise_std > 0 and rng is None:
        raise InvalidCurveData("noise_std > 0 needs an explicit numpy.random.Generator")
    t_fine = np.linspace(t_start, t_end, 20001)
    s_fine = cumulative_trapezoid(curve.speed(t_fine), t_fine, initial=0.0)
    s_fine = np.abs(s_fine)
    s = np.arange(0.0, s_fine[-1] + 1e-12 * spacing, spacing)
    if s.size < 2:
        raise InvalidCurveData(
            f"arc of length {s_fine[-1]:.3g} is shorter than the spacing {spacing:.3g}"
        )
    t = np.interp(s, s_fine, t_fine)
    T = np.eye(3) if T_data_from_canonical is None else np.asarray(T_data_from_canonical, float)
    points = apply_pose(T, curve.points(t))
    if noise_std > 0 and rng is not None:  # rng is not None: checked above
        points = points + rng.normal(scale=noise_std, size=points.shape)
    return SampledCurve(points, t, curve, T, float(noise_std))


def _signed(rng: np.random.Generator, low: float, high: float) -> float:
    """A magnitude uniform in [low, high) with a random sign."""
    return rng.choice([-1.0, 1.0]) * rng.uniform(low, high)


def random_curve(
    kind: CurveKind | str, rng: np.random.Generator
) -> tuple[CanonicalCurve, float, float]:
    """A random curve of class ``kind`` and a parameter interval to sample it on.

    The shapes are drawn from fixed, documented ranges (unit-free; think centimetres),
    away from the degenerate members of each class (circles, straight lines, vanishing
    parameters, which also keep the relative parameter error of Table 3.3 meaningful)
    so that the class is identifiable from a short arc:

    ======================  ======================================  ======================
    class                   shape parameters                        parameter interval
    ======================  ======================================  ======================
    parabola                a in [0.5, 3]                           width 2 in [-2, 2]
    ellipse                 a in [1, 4], b/a in [0.35, 0.85]        width 2.5 rad
    hyperbola               a, b in [0.5, 3]                        width 1.5 in [-1.5, 1.5]
    cubical parabola        |a| in [0.5, 3], |b| in [0.3, 2]        t0 + [0, 1.2], t0 >= 0.15
    semi-cubical parabola   a in [0.5, 3], |b| in [0.3, 2]          t0 + [0, 1.2], t0 >= 0.2
    cubic spline            a in [0.5, 2], |b|, |c| in [0.3, 2]     t0 + [0, 1.4], t0 >= 0.1
    quartic (no class)      a in [0.5, 2], b, c in [-1, 1]          t0 + [0, 1.5], t0 >= 0.2
    ======================  ======================================  ======================

    (t0 is drawn up to 0.6, 0.6, 0.5 and 0.6 respectively.)
    The cubic classes traverse ``t > 0``; the mirror images and reversed traversals come
    from the random rigid motion, a random reversal and the random signs of ``a`` and
    ``c``. Returns ``(CanonicalCurve, t_start, t_end)``.
    """
    kind = CurveKind(kind)
    params: tuple[float, ...]
    if kind is CurveKind.PARABOLA:
        params = (rng.uniform(0.5, 3.0),)
        t0 = rng.uniform(-2.0, 0.0)
        interval = (t0, t0 + 2.0)
    elif kind is CurveKind.ELLIPSE:
        a = rng.uniform(1.0, 4.0)
        params = (a, a * rng.uniform(0.35, 0.85))
        t0 = rng.uniform(-np.pi, np.pi)
        interval = (t0, t0 + 2.5)
    elif kind is CurveKind.HYPERBOLA:
        params = (rng.uniform(0.5, 3.0), rng.uniform(0.5, 3.0))
        t0 = rng.uniform(-1.5, 0.0)
        interval = (t0, t0 + 1.5)
    elif kind is CurveKind.CUBICAL_PARABOLA:
        params = (_signed(rng, 0.5, 3.0), _signed(rng, 0.3, 2.0))
        t0 = rng.uniform(0.15, 0.6)
        interval = (t0, t0 + 1.2)
    elif kind is CurveKind.SEMICUBICAL_PARABOLA:
        params = (rng.uniform(0.5, 3.0), _signed(rng, 0.3, 2.0))
        t0 = rng.uniform(0.2, 0.6)
        interval = (t0, t0 + 1.2)
    elif kind is CurveKind.CUBIC_SPLINE:
        params = (rng.uniform(0.5, 2.0), _signed(rng, 0.3, 2.0), _signed(rng, 0.3, 2.0))
        t0 = rng.uniform(0.1, 0.5)
        interval = (t0, t0 + 1.4)
    elif kind is CurveKind.QUARTIC:
        params = (rng.uniform(0.5, 2.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0))
        t0 = rng.uniform(0.2, 0.6)
        interval = (t0, t0 + 1.5)
    else:
        raise InvalidCurveData(f"no random generator for {kind}")
    if rng.random() < 0.5:
        interval = interval[::-1]
    return CanonicalCurve(kind, params), *interval
