"""Which poses are the same answer, and which the data cannot tell apart.

Near-duplicates are poses that put p at nearly the same place, turned nearly alike. Two
distinct poses are *equivalent* when the data's noise cannot tell them apart (a
symmetric part, a sphere, a flat face reached at two places); a pose has *free motions*
when the data leave it free to move along some directions (a plane: two slides and a
turn; a cylinder: a slide along its axis; a sphere or a surface of revolution: turns
about its centre or axis), the classic degeneracy of point-to-plane registration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from recognition.rigid import point_to_plane_jacobian
from recognition.surfaces.registration.config import FastConfig
from recognition.surfaces.registration.data import effective_noise_m

__all__ = ["DISTINCT_ANGLE_RAD", "DISTINCT_RADIUS_M", "Resolution", "distinct_poses"]

Array = NDArray[np.float64]

#: Poses closer than this (p's image, metres) and ...
DISTINCT_RADIUS_M = 0.5e-3
#: ... turned less than this from a better pose are near-duplicates.
DISTINCT_ANGLE_RAD = float(np.deg2rad(3.0))


def distinct_poses(
    R: Array,
    t: Array,
    errors: Array,
    point: Array,
    n_keep: int,
    radius: float = DISTINCT_RADIUS_M,
    angle: float = DISTINCT_ANGLE_RAD,
) -> NDArray[np.int64]:
    """Indices of the ``n_keep`` best poses R (k, 3, 3), t (k, 3) (least ``errors``),
    skipping any pose that puts ``point`` (3,) within ``radius`` of a better kept pose
    while rotated less than ``angle`` from it; best first."""
    from recognition.surfaces import field_kernels  # numba: imported when first needed

    order = np.argsort(errors, kind="stable")
    R = np.ascontiguousarray(R[order], dtype=np.float64)
    location = np.ascontiguousarray(R @ point + t[order], dtype=np.float64)
    kept = field_kernels.distinct_in_order(
        R, location, float(radius), float(1 + 2 * np.cos(angle)), int(n_keep)
    )
    return order[kept]


@dataclass(frozen=True)
class Resolution:
    """What n data points with Gaussian errors of standard deviation ``sigma_m`` resolve.

    The data are exp(D / (2 sigma^2)) times likelier at one pose than at another whose
    sum of squared distances is larger by D; the data cannot tell two poses apart while
    that ratio is at most exp(``log_ratio``).

    Attributes
    ----------
    sigma_m : float
        The effective noise (sensor and model mismatch), metres.
    n_points : int
    log_ratio : float
    floor_m : float
        Errors within this of each other are equivalent whatever the noise (noise-free
        data), metres.
    motion_m : float
        A pose is free along a direction when moving it by this much along it (a turn
        moving the data's farthest point this far) is not resolved, metres.
    """

    sigma_m: float
    n_points: int
    log_ratio: float = 3.0
    floor_m: float = 1.0e-6
    motion_m: float = 1.0e-3

    @classmethod
    def of(cls, noise_m: float, n_points: int, config: FastConfig = FastConfig()) -> Resolution:
        """The resolution of fast-mode data with noise ``noise_m`` across the surface."""
        return cls(
            effective_noise_m(noise_m, config),
            n_points,
            config.equivalent_log_ratio,
            config.equivalent_floor_m,
            config.free_motion_m,
        )

    def equivalent_error_m(self, best_m: float) -> float:
        """Largest mean error (4.8) of a pose equivalent to one of error ``best_m``.

        n points at mean distance e have a sum of squared distances of about
        (pi / 2) n e^2 (half-normal distances), so a pose of error e is equivalent while
        pi n (e^2 - best^2) / (4 sigma^2) <= ``log_ratio``, or e <= best + ``floor_m``.
        """
        gap = 4 * self.sigma_m**2 * self.log_ratio / (np.pi * max(self.n_points, 1))
        return float(max(np.sqrt(best_m**2 + gap), best_m + self.floor_m))

    def free_motions(self, points: Array, normals: Array) -> int:
        """Degrees of freedom (0-6) that the data leave free at a pose.

        ``points`` (n, 3): the data at the pose; ``normals`` (n, 3): the model's normals
        at their closest points. The point-to-plane residuals change at first order by
        J dx under a motion dx (a turn about the data's centroid scaled by its reach,
        and a shift, both in metres); a direction v of J^T J with eigenvalue lambda adds
        lambda m^2 to the sum of squares when moved by m, which is unresolved while
        lambda m^2 / (2 sigma^2) <= ``log_ratio`` at m = ``motion_m``.
        """
        centred = points - points.mean(axis=0)
        reach = max(float(np.max(np.linalg.norm(centred, axis=1))), 1e-12)
        J = point_to_plane_jacobian(points, normals, points.mean(axis=0))
        J[:, :3] /= reach
        eigenvalues = np.linalg.eigvalsh(J.T @ J)
        limit = 2 * self.sigma_m**2 * self.log_ratio / self.motion_m**2
        return int(np.sum(eigenvalues <= limit))
