"""How a mesh is split into convex parts: CoACD's parameters, and the library versions."""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass

__all__ = [
    "DecompositionConfig",
    "library_versions",
]


@dataclass(frozen=True)
class DecompositionConfig:
    """How a mesh is split into convex parts (CoACD after decimation).

    The defaults were chosen from measured accuracy on the catalog objects (see the package
    docstring and ``hull_surface_deviation``): on 20k-face copies threshold 0.02 keeps the
    union of the parts within a few hundredths of a millimetre of the original surface.

    Attributes
    ----------
    target_faces : int
        The mesh is decimated (quadric edge collapse) to at most this many faces first;
        meshes with fewer faces are used as they are.
    threshold : float
        CoACD concavity threshold, a fraction of the bounding-box diagonal (dimensionless);
        smaller means more, tighter parts and a longer run.
    preprocess_mode : str
        CoACD's manifold pre-processing: ``"auto"`` (only for non-manifold input), ``"on"``
        or ``"off"``.
    preprocess_resolution : int
        Voxel resolution of that pre-processing.
    resolution : int
        CoACD's sampling resolution for the concavity metric.
    mcts_nodes, mcts_iterations, mcts_max_depth : int
        CoACD's Monte-Carlo tree search budget.
    max_convex_hull : int
        Cap on the number of parts (-1: none).
    seed : int
        CoACD's random seed: the same mesh and config give the same parts.
    """

    target_faces: int = 20_000
    threshold: float = 0.015
    preprocess_mode: str = "auto"
    preprocess_resolution: int = 50
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 150
    mcts_max_depth: int = 3
    max_convex_hull: int = -1
    seed: int = 0

    def __post_init__(self) -> None:
        if self.target_faces < 100:
            raise ValueError(f"target_faces must be >= 100, got {self.target_faces}")
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"threshold must lie in (0, 1), got {self.threshold}")
        if self.preprocess_mode not in ("auto", "on", "off"):
            raise ValueError(
                f"preprocess_mode must be 'auto', 'on' or 'off', got {self.preprocess_mode!r}"
            )


def library_versions() -> dict[str, str]:
    """Returns the versions of the libraries whose output the parts depend on."""
    versions = {}
    for package in ("coacd", "fast_simplification"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = "missing"
    return versions
