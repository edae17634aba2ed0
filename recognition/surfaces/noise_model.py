"""How far contact data lie from the true model at the true pose: the belief's noise model.

    residual r_i = signed distance of contact point i from the model at the pose,
    r ~ N(0, Sigma),  Sigma_ij = s^2 [i = j] + m^2 k(|x_i - x_j| / l),
    k(u) = (1 + sqrt(3) u) exp(-sqrt(3) u)   (Matern 3/2),

sensor noise s independent per point, the object's mismatch from its model m a field of
correlation length l along the surface (:mod:`recognition.surfaces.belief` explains the
choice); residuals are counted by Huber's loss. A sensed contact normal differs from the
model's by the sensor's error and by the mismatch's slope, each component across the
normal with standard deviation

    sqrt(s_n^2 + 3 m^2 / l^2)   (the Matern 3/2 field's slope: -k''(0) = 3 / l^2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from recognition.errors import InvalidArgument

__all__ = ["NoiseModel", "huber"]

Array = NDArray[np.float64]


def huber(z: Array, k: float) -> Array:
    """Huber's loss of each z: z^2 / 2 for |z| <= k, k |z| - k^2 / 2 beyond."""
    a = np.abs(z)
    return np.where(a <= k, 0.5 * a * a, k * a - 0.5 * k * k)


@dataclass(frozen=True)
class NoiseModel:
    """How far contact data lie from the true model at the true pose.

    Attributes
    ----------
    sensor_noise_m : float or None
        Standard deviation of a contact point across the surface, metres; None: the
        curves' own scatter (:func:`~recognition.surfaces.registration.data.data_noise_m`),
        at least ``sensor_floor_m``.
    sensor_floor_m : float
        Least sensor noise assumed, metres (a fit never resolves below it: the models'
        own discretisation).
    model_mismatch_m : float
        RMS of the object's difference from its model along the normals, metres.
    correlation_m : float
        Correlation length of that difference, metres (Matern 3/2).
    outlier_sigmas : float
        A residual beyond this many effective noise levels sqrt(s^2 + m^2) counts at that
        level and makes the point an outlier of the hypothesis.
    outlier_floor_m : float
        The outlier level is at least this, metres.
    huber_k : float
        The whitened residuals z count z^2 / 2 up to this size and linearly beyond
        (Huber): a few points that neither sensor noise nor a smooth mismatch explain (a
        sharp feature, a slip of the stylus) do not decide the posterior alone.
    normal_sd_rad : float
        Standard deviation of each component of a sensed contact normal across the true
        normal, radians. The default is the simulated robot's: over 23 verification
        touches of 20 catalog sessions its sensed normals lay 1.3 deg (median), 2.5 deg
        (RMS) and at most 6.6 deg from the mesh's face normal at MuJoCo's contact, i.e.
        about 1.8 deg per component.
    """

    sensor_noise_m: float | None = None
    sensor_floor_m: float = 2.0e-6
    model_mismatch_m: float = 5.0e-6
    correlation_m: float = 5.0e-3
    outlier_sigmas: float = 5.0
    outlier_floor_m: float = 0.1e-3
    huber_k: float = 3.0
    normal_sd_rad: float = float(np.deg2rad(2.0))

    def __post_init__(self) -> None:
        values = {
            "sensor_floor_m": self.sensor_floor_m,
            "model_mismatch_m": self.model_mismatch_m,
            "correlation_m": self.correlation_m,
            "outlier_sigmas": self.outlier_sigmas,
            "outlier_floor_m": self.outlier_floor_m,
            "normal_sd_rad": self.normal_sd_rad,
        }
        if self.sensor_noise_m is not None:
            values["sensor_noise_m"] = self.sensor_noise_m
        for name, value in values.items():
            if not (np.isfinite(value) and value >= 0):
                raise InvalidArgument(f"NoiseModel.{name} must be finite and >= 0, got {value}")
        if self.correlation_m <= 0 or self.outlier_sigmas <= 0 or self.normal_sd_rad <= 0:
            raise InvalidArgument(
                "NoiseModel: correlation_m, outlier_sigmas and normal_sd_rad must be > 0"
            )

    def sensor_m(self, estimated_m: float) -> float:
        """The sensor noise to use when the data's own scatter is ``estimated_m``."""
        own = estimated_m if self.sensor_noise_m is None else self.sensor_noise_m
        return max(float(own), self.sensor_floor_m)

    def covariance(self, points: Array, sensor_m: float) -> Array:
        """Sigma (n, n) of the residuals at ``points`` (n, 3), metres^2 (module docstring)."""
        u = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=-1)
        u *= np.sqrt(3.0) / self.correlation_m
        K = self.model_mismatch_m**2 * (1.0 + u) * np.exp(-u)
        return K + sensor_m**2 * np.eye(len(points))

    def point_sigma_m(self, sensor_m: float) -> float:
        """One contact point's effective noise sqrt(s^2 + m^2), metres."""
        return float(np.hypot(sensor_m, self.model_mismatch_m))

    def outlier_level_m(self, sensor_m: float) -> float:
        """Residual level beyond which a point is an outlier, metres."""
        return max(self.outlier_sigmas * self.point_sigma_m(sensor_m), self.outlier_floor_m)

    def normal_sigma_rad(self) -> float:
        """Standard deviation of each component of a sensed normal across the model's at
        the true pose, radians: the sensor's and the mismatch's slope (module docstring)."""
        slope = np.sqrt(3.0) * self.model_mismatch_m / self.correlation_m
        return float(np.hypot(self.normal_sd_rad, slope))
