"""The tip's contact with the object's own mesh: a box kept tangent to it under the tip.

MuJoCo collides a mesh geom as its convex hull, so an object is a set of convex parts
(CoACD), and their union stands up to a few tenths of a millimetre proud of the object's
surface in concave places. The probe's tip, a sphere of radius r, meets the surface where
the surface is nearest its centre c: the sphere-mesh contact is the contact with the
tangent plane at that nearest point q, at distance |c - q| - r along (c - q) / |c - q|.
:class:`TipContact` keeps a mocap box (:func:`tactile_sim.scene.add_tip_contact`, the only
geom the tip collides with besides the table) with its top face on that plane, the nearest
point found on the exact mesh (:class:`~recognition.surfaces.distance.MeshDistance`) before
each step. The convex parts still
collide with the probe's housing and shaft.

The nearest point is looked up again only when the tip may be in contact (within
``reach_m`` of the surface it last measured) and has moved sideways by more than
``lateral_m`` (or by more than ``travel_m`` in all) since; moving along the plane's
normal keeps the plane exact, and a sideways move of d off a plane at distance r changes
the contact by about d^2 / (2 r) (0.2 um for 20 um).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from tactile_sim import scene
from tactile_sim.probing.probe_scene import ProbeScene

__all__ = ["TipContact", "TipContactConfig"]

Step = Callable[..., None]
"""Steps a simulation: ``step(model, data)`` or ``step(model, data, nstep)``."""


@dataclass(frozen=True)
class TipContactConfig:
    """When the tip's contact box follows the tip.

    Attributes
    ----------
    lateral_m : float, metres
        Sideways move of the tip centre (across the contact normal) that triggers a new
        nearest-point query.
    travel_m : float, metres
        Any move of the tip centre longer than this triggers a query.
    reach_m : float, metres
        No query while the tip centre is farther than this from the surface it last
        measured (minus its move since): the tip cannot touch it.
    """

    lateral_m: float = 20e-6
    travel_m: float = 0.2e-3
    reach_m: float = 2.5e-3


class TipContact:
    """Keeps the tip's contact box tangent to the object's mesh under the tip.

    Parameters
    ----------
    probe_scene : ProbeScene
        A scene built with the tip's contact box (``build_probe_scene(...,
        tip_contact=True)``).
    config : TipContactConfig
    """

    def __init__(self, probe_scene: ProbeScene, config: TipContactConfig | None = None) -> None:
        physics = probe_scene.physics
        self.config = config or TipContactConfig()
        self._mesh = probe_scene.mesh_distance
        T = probe_scene.T_world_from_object
        self._R, self._t = T[:3, :3].copy(), T[:3, 3].copy()
        self._site = int(physics.model.name2id(scene.PROBE_TIP_SITE, "site"))
        body = int(physics.model.name2id(scene.TIP_CONTACT_BODY, "body"))
        self._mocap = int(physics.model.body_mocapid[body])
        self._half_thickness = scene.TIP_CONTACT_HALF_SIZE_M[2]
        self.queries = 0
        self.reset()

    def reset(self) -> None:
        """Forgets the last query (after a reset of the physics)."""
        self._centre = np.full(3, np.inf)
        self._normal = np.zeros(3)
        self._distance = 0.0

    def update(self, data: mujoco.MjData) -> None:
        """Places the contact box under the tip centre of the last step, if it may touch."""
        c = data.site_xpos[self._site]
        delta = c - self._centre
        moved2 = float(delta @ delta)
        if math.isfinite(moved2):
            moved = math.sqrt(moved2)
            if self._distance - moved > self.config.reach_m:
                return
            along = float(delta @ self._normal)
            if moved < self.config.travel_m and moved2 - along * along < self.config.lateral_m**2:
                return
        self._query(data, c)

    def _query(self, data: mujoco.MjData, c: NDArray[np.float64]) -> None:
        self.queries += 1
        R = self._R
        c_object = (c - self._t) @ R
        distance, qx, qy, qz, face = self._mesh.closest_to(*c_object)
        q = np.array((qx, qy, qz))
        face_normal = self._mesh.face_normals[face]
        n = (c_object - q) / distance if distance > 1e-12 else face_normal
        if n @ face_normal < 0:  # the centre is under the surface: push it out
            n = face_normal
        n_world = R @ n
        nx, ny, nz = n_world
        # the box's x axis: the world's x (or y, when the normal is near x) across the normal
        ax, ay, az = (0.0, -nz, ny) if abs(nx) < 0.9 else (nz, 0.0, -nx)
        length = math.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / length, ay / length, az / length
        frame = np.array(  # columns x, n x x, n
            (
                (ax, ny * az - nz * ay, nx),
                (ay, nz * ax - nx * az, ny),
                (az, nx * ay - ny * ax, nz),
            )
        )
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, frame.reshape(9))
        data.mocap_pos[self._mocap] = R @ q + self._t - self._half_thickness * n_world
        data.mocap_quat[self._mocap] = quat
        self._centre = c.copy()
        self._normal = n_world
        self._distance = distance

    def stepping(self, step: Step) -> Step:
        """``step`` with the contact box placed before each call (the tip barely moves
        within one call of several steps: a settle)."""

        def contact_step(model: mujoco.MjModel, data: mujoco.MjData, nstep: int = 1) -> None:
            self.update(data)
            if nstep == 1:
                step(model, data)
            else:
                step(model, data, nstep)

        return contact_step
