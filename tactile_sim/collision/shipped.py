"""The hulls shipped with the repository, rebuilt by maintainers after a catalog mesh changes."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from tactile_sim.collision.config import DecompositionConfig
from tactile_sim.collision.decomposition import object_parts
from tactile_sim.collision.parts import ConvexParts, safe_name, shipped_hulls_dir, write_parts

__all__ = [
    "build_shipped_hulls",
    "write_shipped_parts",
]


def write_shipped_parts(parts: ConvexParts, name: str, config: DecompositionConfig) -> Path:
    """Writes parts into the shipped-hulls directory, replacing older files of ``name``.

    For maintainers: after the catalog meshes change, rebuild the parts (e.g.
    ``object_parts(load_object(n))``) and ship them with this.

    Returns
    -------
    Path
        The written file.
    """
    directory = shipped_hulls_dir()
    directory.mkdir(parents=True, exist_ok=True)
    stem = f"{safe_name(name)}-{parts.key[:16]}"
    path = directory / f"{stem}.npz"
    write_parts(path, parts, name, config)
    for stale in directory.glob(f"{safe_name(name)}-*.npz"):
        if stale != path:
            stale.unlink(missing_ok=True)
    return path


def build_shipped_hulls(
    names: Sequence[str] | None = None,
    config: DecompositionConfig | None = None,
    *,
    progress: bool = True,
) -> dict[str, Path]:
    """Builds (or reads from the cache) the catalog objects' parts and ships them.

    For maintainers, after a catalog mesh changes: the shipped files are keyed by the
    mesh, so stale ones are simply not used (and replaced here).

    Parameters
    ----------
    names : sequence of str or None
        Catalog names; None: all of them.
    config : DecompositionConfig or None
        None: the defaults.
    progress : bool
        Announce each build with a progress bar.

    Returns
    -------
    dict of str to Path
        The shipped file of each object (convex objects ship nothing).
    """
    from tactile_sim.objects import load_object, object_names

    config = config or DecompositionConfig()
    shipped = {}
    for name in names if names is not None else object_names():
        parts = object_parts(load_object(name), config, progress=progress)
        if parts.source != "convex":
            shipped[name] = write_shipped_parts(parts, name, config)
    return shipped
