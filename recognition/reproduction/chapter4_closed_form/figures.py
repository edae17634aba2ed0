"""Figs. 4.3, 4.5 and 4.7 of the thesis (closed forms), drawn as PNGs (imports matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from recognition.reproduction.chapter4_closed_form.experiments import (
    SurfaceExperiment,
    fig_4_5_data,
    seeded_rng,
    surface_instances,
)
from recognition.reproduction.tables import save_figure
from recognition.surfaces import closed_form as cf
from recognition.surfaces.registration import data_geometry, register

__all__ = ["figures"]


def figures(
    out_dir: Path,
    experiment: SurfaceExperiment = SurfaceExperiment(),
    workers: int | None = None,
) -> list[Path]:
    """Figs. 4.3 (E against phi), 4.5 (worked example) and 4.7 (true vs estimated p)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []

    # Fig. 4.3: curves from the ellipsoid at (1.02, 0.69), placed at (0.31, 0.63)
    ellipsoid = cf.ellipsoid(1.0, 0.8, 0.5)
    rng = seeded_rng(experiment.seed, 43)
    curves, *_ = experiment.data_curves(ellipsoid, 1.02, 0.69, rng)
    geometry = data_geometry(curves, experiment.config().geometry)
    X = cf.local_coordinates(geometry, curves.points)
    phi = np.linspace(0, 2 * np.pi, 721)
    fig, ax = plt.subplots(figsize=(7, 4))
    for (u, v), label in (((0.31, 0.63), "placed at (0.31, 0.63)"), ((1.02, 0.69), "at p")):
        ax.plot(phi, cf.superposition_error(ellipsoid, X, u, v, phi), label=label)
        best, e = cf.initial_phi(ellipsoid, X, u, v)
        ax.plot([best], [e], "o", color="k", ms=4)
    ax.set(xlabel="phi (rad)", ylabel="E (4.11)", title="Fig. 4.3: E against phi (ellipsoid)")
    ax.legend()
    paths.append(save_figure(fig, out_dir / "fig4_3_error_vs_phi.png"))

    # Fig. 4.5: data curves at their true place and as registered
    surface, curves, _, T_true, _ = fig_4_5_data(experiment)
    model = cf.ClosedFormModel.build(surface, *experiment.grid)
    registration = register(model, curves, experiment.config())
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    uu, vv = np.meshgrid(np.linspace(0, 2 * np.pi, 60), np.linspace(0, 1, 30))
    P = surface.sigma(uu, vv)
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="0.8", alpha=0.5, linewidth=0)
    for c in curves.curves:
        true = c @ T_true[:3, :3].T + T_true[:3, 3]
        reg = c @ registration.T_model_from_data[:3, :3].T + registration.T_model_from_data[:3, 3]
        ax.plot(*true.T, "k-", lw=3)
        ax.plot(*reg.T, "--", color="tab:red", lw=1.5)
    ax.set(title="Fig. 4.5: data curves at p (black) and registered (red, dashed)")
    paths.append(save_figure(fig, out_dir / "fig4_5_worked_example.png"))

    # Fig. 4.7: true p (dots) and estimates p* (crosses), symmetric copy nearest p
    records = surface_instances(experiment, workers)
    fig = plt.figure(figsize=(11, 10))
    for i, s in enumerate(cf.table_4_1_surfaces()):
        ax = fig.add_subplot(2, 2, i + 1, projection="3d")
        (u0, u1), (v0, v1) = s.domain
        uu, vv = np.meshgrid(np.linspace(u0, u1, 50), np.linspace(v0, v1, 40))
        P = s.sigma(uu, vv)
        ax.plot_wireframe(P[..., 0], P[..., 1], P[..., 2], color="0.7", lw=0.3)
        for r in (r for r in records if r["surface"] == s.name):
            p, est = np.array(r["point"]), np.array(r["location"])
            est = s.symmetric_image(p, est)
            ax.plot(*p, "o", color="tab:blue", ms=5)
            ax.plot(*est, "x", color="tab:red", ms=7)
        ax.set(title=f"({'abcd'[i]}) {s.name.replace('_', ' ')}")
    fig.suptitle("Fig. 4.7: true p (dots) and estimated p* (crosses)")
    paths.append(save_figure(fig, out_dir / "fig4_7_registration_instances.png"))
    return paths
