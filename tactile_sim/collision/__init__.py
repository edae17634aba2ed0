"""Convex collision geometry for MuJoCo: cached CoACD decompositions and closed-form solids.

MuJoCo collides every mesh geom as its convex hull, so a non-convex object is a body of
convex parts. :func:`convex_decomposition` (:mod:`~tactile_sim.collision.decomposition`)
decimates a mesh (``fast_simplification``) and splits it with CoACD; the parts
(:mod:`~tactile_sim.collision.parts`) are cached as ``.npz`` files keyed by a hash of the
mesh and every parameter (:mod:`~tactile_sim.collision.config`), written atomically.
Lookup order: the hulls shipped with the repository (``assets/hulls/``, rebuilt with
:mod:`~tactile_sim.collision.shipped`), then the generated-assets cache
(``assets/generated/hulls/`` or ``$TACTILE_ASSETS_DIR/hulls/``, see
:mod:`tactile_sim.objects.cache`). A warm start reads a file; only a cold start runs CoACD
(tens of seconds per object), announced on stderr with a progress bar. How close the
parts lie to the mesh: :mod:`~tactile_sim.collision.deviation`.

The closed-form solids of thesis Fig. 4.15 (two circular cylinders, an elliptic cylinder,
a sphere) and the extruded outlines of the planar experiments of thesis Section 3.4.2
(an ellipse a = 25 mm, b = 17.5 mm and a closed cubic spline of five segments) are
generated as meshes (:func:`load_solid`, :mod:`~tactile_sim.collision.solids`, from the
outlines of :mod:`~tactile_sim.collision.outlines`); they are convex and collide as one
hull.
"""

from tactile_sim.collision.config import DecompositionConfig
from tactile_sim.collision.decomposition import (
    DECOMPOSITION_VERSION,
    convex_decomposition,
    decimate,
    decomposition_key,
    object_parts,
)
from tactile_sim.collision.deviation import HullAccuracy, hull_surface_deviation
from tactile_sim.collision.hulls import convex_hull_part
from tactile_sim.collision.outlines import (
    DEFAULT_SPLINE_KNOTS_M,
    closed_spline_coefficients,
    closed_spline_outline,
    ellipse_outline,
    extrude_outline,
)
from tactile_sim.collision.parts import ConvexParts, shipped_hulls_dir
from tactile_sim.collision.shipped import build_shipped_hulls, write_shipped_parts
from tactile_sim.collision.solids import (
    CYLINDER_LENGTH_M,
    PRISM_HEIGHT_M,
    SOLID_NAMES,
    Solid,
    load_solid,
    solid_names,
    sphere_mesh,
)

__all__ = [
    "CYLINDER_LENGTH_M",
    "DECOMPOSITION_VERSION",
    "DEFAULT_SPLINE_KNOTS_M",
    "PRISM_HEIGHT_M",
    "SOLID_NAMES",
    "ConvexParts",
    "DecompositionConfig",
    "HullAccuracy",
    "Solid",
    "build_shipped_hulls",
    "closed_spline_coefficients",
    "closed_spline_outline",
    "convex_decomposition",
    "convex_hull_part",
    "decimate",
    "decomposition_key",
    "ellipse_outline",
    "extrude_outline",
    "hull_surface_deviation",
    "load_solid",
    "object_parts",
    "shipped_hulls_dir",
    "solid_names",
    "sphere_mesh",
    "write_shipped_parts",
]
