"""Pictures of the catalog objects: each one shaded, and a contact sheet of them all.

Each object is decimated, back-face culled and flat-shaded (Lambert plus ambient) in
an orthographic matplotlib 3D view (matplotlib is imported when drawing).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tactile_sim.errors import UnknownObject
from tactile_sim.objects.catalog import ObjectModel, load_object, object_names

__all__ = ["COLOURS", "DOCS_OBJECTS_DIR", "VIEWS", "RenderConfig", "draw_object", "render_objects"]

#: Where the committed pictures are.
DOCS_OBJECTS_DIR = Path(__file__).resolve().parents[2] / "docs" / "objects"

#: Body colour of each object (others: grey).
COLOURS = {
    "pear": "#c9c24a",
    "stone": "#9a9690",
    "monkey": "#9a6b46",
    "bird": "#5b8fc7",
    "dog": "#c8a172",
    "frog": "#6fae4f",
    "cat": "#e08d3c",
    "snail": "#b98a5a",
    "fish": "#e8a33d",
    "elephant": "#8f98a6",
}

#: (elevation, azimuth) in degrees of views that differ from the default front-left one.
VIEWS = (
    ("cat", 18.0, -40.0),
    ("snail", 15.0, -65.0),
    ("fish", 15.0, -60.0),
    ("stone", 35.0, 35.0),
)


@dataclass(frozen=True)
class RenderConfig:
    """What to render and where.

    Attributes
    ----------
    objects : tuple of str
        Object names; empty for the whole catalog.
    out_dir : Path
        Output directory for ``<name>.png`` and ``contact_sheet.png``.
    faces : int
        Triangle count of the decimated copy that is drawn.
    image_size_in : float, inches
        Side of each single-object image.
    dpi : int
        Dots per inch.
    default_view_deg : (2,) float, degrees
        (elevation, azimuth) for objects without an entry in ``views``.
    views : tuple of (str, float, float)
        Per-object (name, elevation, azimuth) in degrees.
    contact_sheet : bool
        Also write ``contact_sheet.png``.
    """

    objects: tuple[str, ...] = ()
    out_dir: Path = DOCS_OBJECTS_DIR
    faces: int = 14000
    image_size_in: float = 4.0
    dpi: int = 110
    default_view_deg: tuple[float, float] = (18.0, 35.0)
    contact_sheet: bool = True
    views: tuple[tuple[str, float, float], ...] = VIEWS


def _decimated(model: ObjectModel, faces: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (mm) and faces of a decimated copy of the model's mesh."""
    import fast_simplification

    vertices = np.asarray(model.mesh.vertices) * 1e3
    triangles = np.asarray(model.mesh.faces)
    reduction = max(0.0, 1.0 - faces / len(triangles))
    return fast_simplification.simplify(vertices, triangles, target_reduction=reduction)


def draw_object(ax: Any, model: ObjectModel, config: RenderConfig) -> None:
    """Draw one object, shaded, on a matplotlib 3D axis (orthographic, no axes)."""
    from matplotlib.colors import to_rgb
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    vertices, faces = _decimated(model, config.faces)
    views = {name: (elev, azim) for name, elev, azim in config.views}
    elev, azim = views.get(model.name, config.default_view_deg)
    e, a = np.radians(elev), np.radians(azim)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.cross(eye, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, eye)
    light = eye + 0.9 * up - 0.6 * right
    light /= np.linalg.norm(light)

    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-12
    visible = normals @ eye > 0
    tri, normals = tri[visible], normals[visible]
    diffuse = np.clip(normals @ light, 0.0, 1.0)
    half = (light + eye) / np.linalg.norm(light + eye)
    specular = np.clip(normals @ half, 0.0, 1.0) ** 40
    base = np.array(to_rgb(COLOURS.get(model.name, "#999999")))
    rgb = base[None, :] * (0.28 + 0.72 * diffuse[:, None]) + 0.25 * specular[:, None]
    colours = np.clip(rgb, 0.0, 1.0)
    # Edges in the face colour hide the anti-aliasing seams between faces.
    ax.add_collection3d(
        Poly3DCollection(tri, facecolors=colours, edgecolors=colours, linewidths=0.3)
    )
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, radius = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(centre[0] - radius, centre[0] + radius)
    ax.set_ylim(centre[1] - radius, centre[1] + radius)
    ax.set_zlim(centre[2] - radius, centre[2] + radius)
    ax.set_box_aspect((1, 1, 1))
    ax.set_proj_type("ortho")
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()


def _title(model: ObjectModel) -> str:
    dims = np.ptp(np.asarray(model.mesh.vertices), axis=0) * 1e3
    return f"{model.name}  {dims[0]:.1f} x {dims[1]:.1f} x {dims[2]:.1f} mm"


def render_objects(config: RenderConfig) -> list[Path]:
    """Render the configured objects; return the written PNG paths.

    Raises
    ------
    UnknownObject
        A name is not a catalog object (checked before any object is built).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = config.objects or object_names()
    for name in names:  # all of them before building any
        if name not in object_names():
            raise UnknownObject(name, object_names())
    models = [load_object(name) for name in names]
    config.out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for model in models:
        fig = plt.figure(figsize=(config.image_size_in, config.image_size_in))
        ax = fig.add_axes((0, 0, 1, 0.93), projection="3d")
        draw_object(ax, model, config)
        fig.suptitle(_title(model), fontsize=9, y=0.97)
        path = config.out_dir / f"{model.name}.png"
        fig.savefig(path, dpi=config.dpi)
        plt.close(fig)
        written.append(path)
    if config.contact_sheet and len(models) > 1:
        cols = min(5, len(models))
        rows = -(-len(models) // cols)
        fig = plt.figure(figsize=(3.0 * cols, 3.2 * rows))
        for i, model in enumerate(models):
            ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
            draw_object(ax, model, config)
            ax.set_title(model.name, fontsize=11, y=0.95)
        fig.subplots_adjust(left=0, right=1, bottom=0, top=0.95, wspace=0, hspace=0.05)
        path = config.out_dir / "contact_sheet.png"
        fig.savefig(path, dpi=config.dpi)
        plt.close(fig)
        written.append(path)
    return written
