"""Figs. 3.1-3.3 and 3.7: curves, their signature curves, invariants and estimates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves import invariants as inv
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.reproduction.chapter3.experiments import (
    DEFAULT_JOYSTICK_EXPERIMENT,
    JoystickExperiment,
    joystick_ellipse_estimates,
)
from recognition.reproduction.tables import save_figure

__all__ = [
    "figures",
]


def _signature(curve: CanonicalCurve, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The signature curve (kappa, kappa_s) of ``curve`` at ``t``, thesis Eqs. (3.1)-(3.2)."""
    return curve.kappa(t), curve.kappa_s(t)


def figures(
    out_dir: Path, joystick: JoystickExperiment = DEFAULT_JOYSTICK_EXPERIMENT
) -> list[Path]:
    """Figs. 3.1-3.3 (curves and signature curves) and 3.7 (estimates vs signature).

    Fig. 3.2 shows I_p (thesis Eq. (3.10)) along each parabola, Fig. 3.3 the pairs
    (I_c1, I_c2) of Eqs. (3.19)-(3.20). matplotlib is imported here, not with the package.
    Returns the paths of the PNGs written to ``out_dir``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []

    # Fig. 3.1: y = 0.6 x^3 + 0.4 x and its signature curve
    curve = CanonicalCurve(CurveKind.CUBICAL_PARABOLA, (0.6, 0.4))
    t = np.linspace(-1.5, 1.5, 600)
    fig, ax = plt.subplots(1, 2, figsize=(9, 4))
    p = curve.points(t)
    ax[0].plot(p[:, 0], p[:, 1])
    ax[0].set(title="(a) y = 0.6 x^3 + 0.4 x", xlabel="x", ylabel="y", aspect="equal")
    ax[1].plot(*_signature(curve, t))
    ax[1].set(title="(b) signature curve", xlabel="kappa", ylabel="kappa_s")
    paths.append(save_figure(fig, out_dir / "fig3_1_cubical_parabola_signature.png"))

    # Fig. 3.2: three parabolas, signatures, I_p along each
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    t = np.linspace(-2.0, 2.0, 400)
    for a in (0.5, 1.0, 2.0):
        c = CanonicalCurve(CurveKind.PARABOLA, (a,))
        p = c.points(t)
        k, ks = _signature(c, t)
        ax[0].plot(p[:, 0], p[:, 1], label=f"a = {a}")
        ax[1].plot(k, ks)
        ax[2].plot(
            t, inv.parabola_invariant(k, ks), label=f"(2a)^(-2/3) = {(2 * a) ** (-2 / 3):.3f}"
        )
    ax[0].set(title="(a) y^2 = 4 a x", xlabel="x", ylabel="y")
    ax[0].legend()
    ax[1].set(title="(b) signature curves", xlabel="kappa", ylabel="kappa_s")
    ax[2].set(title="(c) I_p along each curve", xlabel="t", ylabel="I_p")
    ax[2].legend()
    paths.append(save_figure(fig, out_dir / "fig3_2_parabolas.png"))

    # Fig. 3.3: two ellipses and a circle, signatures, (I_c1, I_c2)
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    t = np.linspace(0, 2 * np.pi, 500)
    for a, b in ((2.0, 1.0), (1.6, 1.25), (1.1, 1.1)):
        c = CanonicalCurve(CurveKind.ELLIPSE, (a, b))
        p = c.points(t)
        k, ks = _signature(c, t)
        ax[0].plot(p[:, 0], p[:, 1], label=f"a = {a}, b = {b}")
        ax[1].plot(k, ks, "o" if a == b else "-", ms=4)
        ic1, ic2 = (a * b) ** (-2 / 3), (a * a + b * b) / (a * b) ** (4 / 3)
        if a != b:  # evaluated at random pairs: one point in the (I_c1, I_c2) plane
            i, j = np.random.default_rng(0).integers(0, t.size, (2, 30))
            keep = np.abs(np.abs(k[i]) - np.abs(k[j])) > 1e-3
            i, j = i[keep], j[keep]
            args = (k[i], ks[i], k[j], ks[j])
            ax[2].plot(inv.conic_invariant_1(*args), inv.conic_invariant_2(*args), "x")
        else:
            ax[2].plot([ic1], [ic2], "o")
    ax[0].set(title="(a) ellipses x^2/a^2 + y^2/b^2 = 1", aspect="equal")
    ax[0].legend(fontsize=8)
    ax[1].set(title="(b) signature curves", xlabel="kappa", ylabel="kappa_s")
    ax[2].set(title="(c) (I_c1, I_c2) from pairs of points", xlabel="I_c1", ylabel="I_c2")
    paths.append(save_figure(fig, out_dir / "fig3_3_ellipses.png"))

    # Fig. 3.7: estimates from joystick-like samples against the signature curve
    g = joystick_ellipse_estimates(joystick, 0)
    c = CanonicalCurve(CurveKind.ELLIPSE, (joystick.a, joystick.b))
    k, ks = _signature(c, t)
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    p = c.points(t)
    ax[0].plot(p[:, 0], p[:, 1])
    ax[0].set(title=f"(a) ellipse a = {joystick.a}, b = {joystick.b}", aspect="equal")
    ax[1].plot(k, ks, label="signature curve")
    ax[1].plot(g.kappa, g.kappa_s, "o", ms=4, label="estimates from noisy samples")
    ax[1].set(title="(b) estimates vs signature", xlabel="kappa", ylabel="kappa_s")
    ax[1].legend()
    paths.append(save_figure(fig, out_dir / "fig3_7_estimates_vs_signature.png"))
    return paths
