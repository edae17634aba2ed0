"""Three concurrent data curves on a surface (thesis Section 4.1.1): the seam of the project."""

from __future__ import annotations

import os
import zipfile
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from recognition.errors import DegenerateGeometry, InvalidCurveData
from recognition.files import array_checksum, write_atomic

__all__ = ["DataCurves", "closest_points_between_polylines"]

Array = NDArray[np.float64]

#: Default largest gap (metres) between the curves at their common point.
MEET_TOLERANCE_M = 1.0e-3
#: Smallest angle between two curve tangents at the common point (radians).
MIN_TANGENT_ANGLE = np.deg2rad(5.0)
#: Each curve needs at least this many points.
MIN_POINTS = 5
#: Coordinates beyond this (metres) are not tactile data in metres.
MAX_COORDINATE_M = 1.0e3
#: A curve more than this fraction of whose points lie nearest a point more than two
#: places away along it is not in order (noise and a few outliers leave most points next
#: to their neighbours, a third of them at worst on the robot's 0.05 mm sweeps; shuffled
#: points are next to strangers).
MAX_UNORDERED = 0.5


def _real_array(value: ArrayLike, label: str) -> Array:
    """``value`` as a float array, or an :class:`InvalidCurveData` saying what it is."""
    if value is None:
        raise InvalidCurveData(f"{label} is None; expected an array of real numbers")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidCurveData(
            f"{label} is ragged or holds non-numbers; expected an array of real numbers"
        ) from exc
    if raw.dtype == object:
        raise InvalidCurveData(
            f"{label} is ragged or holds non-numbers; expected an array of real numbers"
        )
    if raw.dtype.kind not in "iuf":
        kind = {"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes"}
        raise InvalidCurveData(
            f"{label} holds {kind.get(raw.dtype.kind, raw.dtype.name)}; expected real numbers"
        )
    return np.array(raw, dtype=float)


def closest_points_between_polylines(a: Array, b: Array) -> tuple[Array, Array, float]:
    """Closest pair of points between two polylines.

    Parameters
    ----------
    a, b : (n, 3), (k, 3) float
        Ordered points of each polyline.

    Returns
    -------
    point_a, point_b : (3,) float
        The closest points, on a segment of ``a`` and of ``b``.
    distance : float
        Their distance, in the units of the points.
    """
    p0, d0 = a[:-1], np.diff(a, axis=0)  # (n-1, 3)
    q0, d1 = b[:-1], np.diff(b, axis=0)  # (k-1, 3)
    r = p0[:, None, :] - q0[None, :, :]
    A = np.einsum("ik,ik->i", d0, d0)[:, None]
    E = np.einsum("jk,jk->j", d1, d1)[None, :]
    B = np.einsum("ik,jk->ij", d0, d1)
    C = np.einsum("ik,ijk->ij", d0, r)
    F = np.einsum("jk,ijk->ij", d1, r)
    denom = A * E - B * B
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-30, (B * F - C * E) / denom, 0.0)
    s = np.clip(s, 0.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip((B * s + F) / E, 0.0, 1.0)
        s = np.clip((B * t - C) / A, 0.0, 1.0)
    pa = p0[:, None, :] + s[..., None] * d0[:, None, :]
    pb = q0[None, :, :] + t[..., None] * d1[None, :, :]
    dist = np.linalg.norm(pa - pb, axis=-1)
    i, j = np.unravel_index(np.argmin(dist), dist.shape)
    return pa[i, j], pb[i, j], float(dist[i, j])


@dataclass(frozen=True)
class DataCurves:
    """Three (or more) data curves sampled on a surface, all passing through one point p.

    Attributes
    ----------
    curves : tuple of (n_i, 3) float arrays
        Points in metres, ordered along each curve (thesis: alpha, beta, gamma).
    meet_tolerance_m : float
        Largest allowed gap between the curves at their common point.
    approach : (3,) float or None
        Unit direction in which the sensor approached the surface (pointing into the
        object), same frame as the curves. It orients the surface normal outward; when
        None, registration tries both orientations.
    normals : tuple of (n_i, 3) float arrays or None
        The sensor's estimate of the outward surface normal at every point (unit
        vectors, same frame), when it gives one; the normal at p takes them into account
        (:func:`~recognition.surfaces.local_geometry.local_surface_geometry`).

    The common point :attr:`intersection` is the mean of the pairwise closest points of
    the curves. Construction validates the data and raises
    :class:`~recognition.errors.InvalidCurveData` (malformed input, curves that do not
    meet) or :class:`~recognition.errors.DegenerateGeometry` (tangents at p that do not
    span a plane, two identical sampling planes).
    """

    curves: tuple[Array, ...]
    meet_tolerance_m: float = MEET_TOLERANCE_M
    approach: Array | None = None
    normals: tuple[Array, ...] | None = None
    intersection: Array = field(init=False, repr=False, compare=False)
    gap_m: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if isinstance(self.curves, str | bytes) or not isinstance(
            self.curves, Sequence | np.ndarray
        ):
            kind = type(self.curves).__name__
            raise InvalidCurveData(f"curves must be a sequence of (n, 3) point arrays, got {kind}")
        curves = tuple(self._validated(c, i) for i, c in enumerate(self.curves))
        if len(curves) < 3:
            raise InvalidCurveData(f"expected three data curves (or more), got {len(curves)}")
        object.__setattr__(self, "curves", curves)
        tolerance = self.meet_tolerance_m
        if isinstance(tolerance, bool) or not isinstance(tolerance, int | float | np.floating):
            raise InvalidCurveData(f"meet_tolerance_m must be a number, got {tolerance!r}")
        if not (np.isfinite(tolerance) and tolerance > 0):
            raise InvalidCurveData(f"meet_tolerance_m must be positive and finite, got {tolerance}")
        if self.approach is not None:
            v = _real_array(self.approach, "approach").reshape(-1)
            if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.linalg.norm(v) > 0:
                raise InvalidCurveData(f"approach must be a finite non-zero 3-vector, got {v}")
            object.__setattr__(self, "approach", v / np.linalg.norm(v))
        if self.normals is not None:
            object.__setattr__(self, "normals", self._validated_normals(self.normals, curves))
        pairs = []
        gap = 0.0
        for i in range(len(curves)):
            for j in range(i + 1, len(curves)):
                pa, pb, d = closest_points_between_polylines(curves[i], curves[j])
                pairs += [pa, pb]
                gap = max(gap, d)
        if not gap <= self.meet_tolerance_m:
            extent = float(np.ptp(np.concatenate(curves), axis=0).max())
            hint = (
                f"; the points span {extent:.3g} m: they look like millimetres, and "
                "DataCurves expects metres"
                if extent > 1.0
                else ""
            )
            raise InvalidCurveData(
                f"the curves do not meet at one point: they pass {gap * 1e3:.3g} mm apart, "
                f"expected at most {self.meet_tolerance_m * 1e3:.3g} mm{hint}"
            )
        object.__setattr__(self, "intersection", np.mean(pairs, axis=0))
        object.__setattr__(self, "gap_m", float(gap))
        self._check_tangents()

    @staticmethod
    def _validated(curve: ArrayLike, index: int) -> Array:
        c = _real_array(curve, f"curve {index}")
        if c.ndim != 2 or c.shape[1] != 3:
            raise InvalidCurveData(f"curve {index} must be an (n, 3) array, got shape {c.shape}")
        if c.shape[0] < MIN_POINTS:
            raise InvalidCurveData(
                f"curve {index} has {c.shape[0]} points; expected at least {MIN_POINTS}"
            )
        if not np.all(np.isfinite(c)):
            raise InvalidCurveData(f"curve {index} has NaN or infinite coordinates")
        if np.abs(c).max() > MAX_COORDINATE_M:
            raise InvalidCurveData(
                f"curve {index} has a coordinate of {np.abs(c).max():.3g} m; expected points "
                f"within {MAX_COORDINATE_M:g} m of the origin, in metres"
            )
        step = np.linalg.norm(np.diff(c, axis=0), axis=1)
        gap, nearest = cKDTree(c).query(c, k=2)
        # any two points at one place, next to each other or not (a curve stepping back)
        if np.any(gap[:, 1] <= 1e-9 * max(float(np.median(step)), 1e-300)):
            raise InvalidCurveData(
                f"curve {index} repeats a point; expected distinct points in order"
            )
        far = np.abs(nearest[:, 1] - np.arange(len(c))) > 2
        if np.mean(far) > MAX_UNORDERED:
            raise InvalidCurveData(
                f"curve {index} is not in order along the curve: {np.count_nonzero(far)} of its "
                f"{len(c)} points lie nearest a point more than two places away; expected the "
                "points ordered along the curve"
            )
        c.setflags(write=False)
        return c

    @staticmethod
    def _validated_normals(
        normals: Sequence[ArrayLike], curves: tuple[Array, ...]
    ) -> tuple[Array, ...]:
        if isinstance(normals, str | bytes) or not isinstance(normals, Sequence | np.ndarray):
            raise InvalidCurveData("normals must be one (n_i, 3) array per curve")
        arrays = tuple(_real_array(n, f"normals of curve {i}") for i, n in enumerate(normals))
        if len(arrays) != len(curves):
            raise InvalidCurveData(
                f"expected one normal array per curve ({len(curves)}), got {len(arrays)}"
            )
        out = []
        for i, (n, c) in enumerate(zip(arrays, curves, strict=True)):
            if n.shape != c.shape:
                raise InvalidCurveData(
                    f"normals of curve {i} must have the curve's shape {c.shape}, got {n.shape}"
                )
            length = np.linalg.norm(n, axis=1)
            if not np.all(np.isfinite(n)) or not np.all(length > 0):
                raise InvalidCurveData(f"normals of curve {i} must be finite non-zero vectors")
            unit = n / length[:, None]
            unit.setflags(write=False)
            out.append(unit)
        return tuple(out)

    def _check_tangents(self) -> None:
        """Tangents at p must not be parallel; the sampling planes must differ."""
        tangents = [self.chord_direction(i) for i in range(len(self.curves))]
        normals = [self.plane_normal(i) for i in range(len(self.curves))]
        for i in range(len(tangents)):
            for j in range(i + 1, len(tangents)):
                sin_t = np.linalg.norm(np.cross(tangents[i], tangents[j]))
                if sin_t < np.sin(MIN_TANGENT_ANGLE):
                    same_plane = np.linalg.norm(np.cross(normals[i], normals[j])) < np.sin(
                        MIN_TANGENT_ANGLE
                    )
                    what = (
                        "lie in the same sampling plane"
                        if same_plane
                        else "have parallel tangents at the common point"
                    )
                    raise DegenerateGeometry(
                        f"curves {i} and {j} {what}; expected sampling planes at least "
                        f"{np.rad2deg(MIN_TANGENT_ANGLE):.0f} deg apart about the normal"
                    )

    def chord_direction(self, index: int) -> Array:
        """(3,) unit chord direction of curve ``index`` across the two samples either side of p."""
        c = self.curves[index]
        i0 = int(np.argmin(np.linalg.norm(c - self.intersection, axis=1)))
        lo, hi = max(i0 - 2, 0), min(i0 + 2, c.shape[0] - 1)
        u = c[hi] - c[lo]
        return u / np.linalg.norm(u)

    def plane_normal(self, index: int) -> Array:
        """(3,) unit normal of the best-fit plane of curve ``index`` (sign arbitrary)."""
        c = self.curves[index]
        return np.linalg.svd(c - c.mean(axis=0), full_matrices=False)[2][-1]

    @property
    def points(self) -> Array:
        """All data points stacked, (sum n_i, 3)."""
        return np.concatenate(self.curves)

    @property
    def n_points(self) -> int:
        """Number of data points, all curves together."""
        return sum(c.shape[0] for c in self.curves)

    def transformed(self, T: ArrayLike) -> DataCurves:
        """The curves moved by a (4, 4) rigid transform ``T`` (translation in metres)."""
        T = np.asarray(T, dtype=float)
        approach = None if self.approach is None else T[:3, :3] @ self.approach
        normals = None if self.normals is None else tuple(n @ T[:3, :3].T for n in self.normals)
        return DataCurves(
            tuple(c @ T[:3, :3].T + T[:3, 3] for c in self.curves),
            self.meet_tolerance_m,
            approach,
            normals,
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the curves to ``path`` (.npz, no pickle), atomically."""
        path = Path(path)
        arrays = {f"curve_{i}": c for i, c in enumerate(self.curves)}
        arrays["meet_tolerance_m"] = np.array(self.meet_tolerance_m)
        if self.approach is not None:
            arrays["approach"] = self.approach
        for i, n in enumerate(self.normals or ()):
            arrays[f"normals_{i}"] = n
        arrays["digest"] = np.array(array_checksum(arrays))
        return write_atomic(path, lambda f: np.savez(f, allow_pickle=False, **arrays))

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> DataCurves:
        """Read curves written by :meth:`save` (or any .npz of ``curve_0``, ``curve_1``, ...
        arrays, with optional ``approach``, ``meet_tolerance_m`` and ``normals_i``).

        Raises
        ------
        InvalidCurveData
            The file cannot be read, is damaged (its arrays do not match the digest
            :meth:`save` stored with them), or holds no valid data curves.
        """
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise InvalidCurveData(f"cannot read data curves from {path}: {exc}") from exc
        digest = arrays.pop("digest", None)
        if digest is not None and str(digest) != array_checksum(arrays):
            raise InvalidCurveData(
                f"{path} is damaged: its arrays do not match the digest saved with them"
            )
        keys: list[str] = []
        while f"curve_{len(keys)}" in arrays:
            keys.append(f"curve_{len(keys)}")
        if len(keys) < 3:
            raise InvalidCurveData(
                f"{path} holds {len(keys)} data curves (arrays curve_0, curve_1, ...); "
                "expected three or more"
            )
        try:
            tol = float(arrays.get("meet_tolerance_m", MEET_TOLERANCE_M))
        except (TypeError, ValueError) as exc:
            raise InvalidCurveData(f"{path}: meet_tolerance_m is not a number") from exc
        normal_keys = [f"normals_{i}" for i in range(len(keys))]
        normals = (
            tuple(arrays[k] for k in normal_keys) if all(k in arrays for k in normal_keys) else None
        )
        curves = tuple(arrays[k] for k in keys)
        return cls(curves, tol, arrays.get("approach"), normals)
