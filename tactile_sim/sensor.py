"""The joystick probe's sensor model: encoder, deflection and axial-force readings -> contact.

What the robot measures (:class:`SensorReading`): the four arm joint encoders, the two
pivot deflection encoders of the stylus and an axial force cell in the stylus, each with
seeded Gaussian noise (:class:`NoiseModel`). From these alone :func:`estimate_contact`
computes

1. the tip sphere's centre, by forward kinematics of the arm and the deflected stylus
   (:func:`tactile_sim.kinematics.probe_tip_pose`);
2. the contact force on the tip: its two lateral components from the pivot spring
   torques (stiffness times deflection, less the stylus's own weight), its axial
   component from the force cell;
3. the outward surface normal, along that force. Friction tilts the force by up to the
   friction angle along the way the tip slid; the component along the measured slide
   (tip centre before and after) is removed, and :func:`sweep_contacts` removes what is
   left along the path of a whole sweep. What friction leaves moves the compensated
   point along the surface, not off it;
4. the contact point, the tip centre moved by the tip radius against the normal.

The simulator's true state (true tip centre, MuJoCo's contacts) is read only by
:func:`ground_truth_contact`, kept apart for evaluation and never used by the estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tactile_sim.kinematics import COBRA600, Cobra600Geometry, probe_tip_pose

if TYPE_CHECKING:
    import mujoco
    from dm_control import mjcf

__all__ = [
    "ContactEstimate",
    "GroundTruthContact",
    "GroundTruthReader",
    "NoiseModel",
    "SensorConfig",
    "SensorReader",
    "SensorReading",
    "contact_force_in_tip_frame",
    "estimate_contact",
    "ground_truth_contact",
    "path_tangents",
    "sweep_contacts",
]

_GRAVITY_M_S2 = 9.81
_NOISE_BLOCK = 4096


@dataclass(frozen=True)
class NoiseModel:
    """Standard deviations of the sensor readings' zero-mean Gaussian noise.

    Every reading draws fresh, independent noise from the caller's generator. The
    magnitudes are those of 20-bit-class encoders and a milli-newton force cell; their
    effect on a sensed point is a few micrometres (shoulder and elbow: 5 urad at up to
    0.6 m reach is 3 um at the tip; deflection: 10 urad on the 0.12 m stylus is 1.2 um).

    Attributes
    ----------
    shoulder_rad, elbow_rad : float, radians
        Arm encoder noise.
    quill_m : float, metres
        Quill (vertical axis) encoder noise.
    roll_rad : float, radians
        Roll encoder noise.
    deflection_rad : float, radians
        Noise of each of the two stylus deflection encoders.
    axial_force_n : float, newtons
        Noise of the axial force cell.
    """

    shoulder_rad: float = 5e-6
    elbow_rad: float = 5e-6
    quill_m: float = 1e-6
    roll_rad: float = 1e-5
    deflection_rad: float = 1e-5
    axial_force_n: float = 5e-4

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            if not (value >= 0.0 and math.isfinite(value)):
                raise ValueError(f"NoiseModel.{name} must be finite and >= 0, got {value}")

    @classmethod
    def noiseless(cls) -> NoiseModel:
        """Returns a noise model with every standard deviation zero."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def sigmas(self) -> NDArray[np.float64]:
        """Returns the standard deviations in reading order: 4 joints, 2 deflections, force."""
        return np.array(
            [
                self.shoulder_rad,
                self.elbow_rad,
                self.quill_m,
                self.roll_rad,
                self.deflection_rad,
                self.deflection_rad,
                self.axial_force_n,
            ]
        )


@dataclass(frozen=True)
class SensorConfig:
    """The probe's sensor model: noise and the calibration constants it computes with.

    Attributes
    ----------
    noise : NoiseModel
        Reading noise.
    robot : Cobra600Geometry
        Kinematics of the arm and the probe (tip radius, stylus length).
    pivot_stiffness_n_m_per_rad : float, N m/rad
        Spring stiffness of each pivot axis (``joystick_probe.xml``: 0.3).
    stylus_first_moment_kg_m : float, kg m
        Mass times pivot-to-centre-of-mass distance of everything below the pivot
        (stylus 3 g at 60 mm, tip 0.033 g at 120 mm): its weight's torque is removed
        from the spring torque.
    tip_weight_n : float, newtons
        Weight of the tip sphere, which the axial force cell also carries.
    min_normal_force_n : float, newtons
        Below this estimated contact force the force direction is too noisy to give the
        normal; :func:`estimate_contact` then uses the caller's fallback normal.
    min_slide_m : float, metres
        Shortest slide whose direction :func:`estimate_contact` trusts (encoder noise
        moves the tip centre by a few micrometres).
    normals_across_path : bool
        Refine a sweep's normals with its path (:func:`sweep_contacts`): remove from each
        the component along the tip centres' path, which friction puts there.
    max_path_correction : float
        Largest component along the slide or the path that is removed (the sine of the
        largest tilt blamed on friction; the probe's friction angle is atan(0.1) =
        5.7 deg). Larger components mean the tip did not slide along a face (an edge) and
        are kept.
    """

    noise: NoiseModel = field(default_factory=NoiseModel)
    robot: Cobra600Geometry = COBRA600
    pivot_stiffness_n_m_per_rad: float = 0.3
    stylus_first_moment_kg_m: float = 0.003 * 0.06 + 3.3e-5 * 0.12
    tip_weight_n: float = 3.3e-5 * _GRAVITY_M_S2
    min_normal_force_n: float = 2e-3
    min_slide_m: float = 20e-6
    normals_across_path: bool = True
    max_path_correction: float = 0.2


@dataclass(frozen=True)
class SensorReading:
    """One reading of the probe's sensors, noise included: all the controller sees.

    Attributes
    ----------
    time_s : float, seconds
        Simulation time of the reading.
    joints : (4,) float
        Encoders (shoulder rad, elbow rad, quill m, roll rad).
    deflection_rad : (2,) float, radians
        Pivot angles (deflection_x, deflection_y).
    axial_force_n : float, newtons
        Force along the stylus on the tip, positive when the stylus presses the tip
        against something (the ``tip_force`` sensor's z component).
    """

    time_s: float
    joints: NDArray[np.float64]
    deflection_rad: NDArray[np.float64]
    axial_force_n: float

    @property
    def deflection_magnitude_rad(self) -> float:
        """Returns the stylus tilt, sqrt(dx^2 + dy^2), radians."""
        return float(math.hypot(self.deflection_rad[0], self.deflection_rad[1]))


@dataclass(frozen=True)
class ContactEstimate:
    """A contact sensed from one reading (world frame, metres).

    Attributes
    ----------
    point_in_world : (3,) float, metres
        Estimated contact point on the surface: tip centre minus tip radius times normal.
    tip_centre_in_world : (3,) float, metres
        Tip sphere centre from forward kinematics of the readings.
    normal_in_world : (3,) float
        Estimated outward unit surface normal.
    force_in_world : (3,) float, newtons
        Estimated contact force on the tip.
    normal_from_force : bool
        False when the force was below ``min_normal_force_n`` and the fallback normal was
        used.
    reading : SensorReading
        The reading it was computed from.
    """

    point_in_world: NDArray[np.float64]
    tip_centre_in_world: NDArray[np.float64]
    normal_in_world: NDArray[np.float64]
    force_in_world: NDArray[np.float64]
    normal_from_force: bool
    reading: SensorReading


class SensorReader:
    """Reads the probe's sensors from a simulation, adding seeded noise.

    Parameters
    ----------
    physics : dm_control.mjcf.Physics
        The probing scene (:mod:`tactile_sim.scene`).
    noise : NoiseModel
        Reading noise.
    rng : numpy.random.Generator
        Source of the noise; the same generator state gives the same readings.
    """

    def __init__(self, physics: mjcf.Physics, noise: NoiseModel, rng: np.random.Generator) -> None:
        from tactile_sim import scene

        model = physics.model
        names = (
            "shoulder_pos",
            "elbow_pos",
            "quill_pos",
            "roll_pos",
            "joystick_probe/deflection_x",
            "joystick_probe/deflection_y",
        )
        adr = [int(model.sensor_adr[model.name2id(n, "sensor")]) for n in names]
        force = int(model.sensor_adr[model.name2id(scene.TIP_FORCE_SENSOR, "sensor")])
        self._index = np.array([*adr, force + 2])
        self._data = physics.data.ptr
        self._sigmas = noise.sigmas
        self._noisy = bool(np.any(self._sigmas > 0))
        self._rng = rng
        # Noise is drawn in blocks (fast in control loops); the sequence of readings is
        # the same for the same generator state.
        self._block = np.empty((0, 7))
        self._next = 0

    def raw(self) -> NDArray[np.float64]:
        """Returns the 7 noisy values (4 joints, 2 deflections, axial force) of the last
        sensor evaluation, without building a SensorReading (for control loops)."""
        values = self._data.sensordata[self._index]
        if self._noisy:
            if self._next == len(self._block):
                self._block = self._sigmas * self._rng.standard_normal((_NOISE_BLOCK, 7))
                self._next = 0
            values += self._block[self._next]
            self._next += 1
        return values

    def read(self) -> SensorReading:
        """Returns a noisy reading of the current sensor values."""
        values = self.raw()
        return SensorReading(
            time_s=float(self._data.time),
            joints=values[:4].copy(),
            deflection_rad=values[4:6].copy(),
            axial_force_n=float(values[6]),
        )


def contact_force_in_tip_frame(
    reading: SensorReading, config: SensorConfig | None = None
) -> NDArray[np.float64]:
    """Returns the contact force on the tip in the tip (stylus) frame, (3,) newtons.

    At rest the pivot springs balance the torque of the contact force about the pivot
    (lever: the stylus length L along the stylus z axis) and the stylus's weight. With
    the deflection_x hinge about the gimbal x axis and deflection_y about the tilted y
    axis, the two hinge balances and the axial force cell give three linear equations in
    the three force components.

    Parameters
    ----------
    reading : SensorReading
    config : SensorConfig or None
        None: the defaults.
    """
    config = config or SensorConfig()
    theta_x, theta_y = (float(a) for a in reading.deflection_rad)
    T_world_from_tip = probe_tip_pose(reading.joints, config.robot, reading.deflection_rad)
    R_world_from_tip = T_world_from_tip[:3, :3]
    # Hinge axes in the tip frame: deflection_y is the tip frame's y axis; deflection_x is
    # the gimbal x axis, R_y(theta_y)^T x.
    axis_y = np.array([0.0, 1.0, 0.0])
    axis_x = np.array([math.cos(theta_y), 0.0, math.sin(theta_y)])
    z = np.array([0.0, 0.0, 1.0])
    length = config.robot.probe.stylus_length_m
    k = config.pivot_stiffness_n_m_per_rad
    gravity_in_tip = R_world_from_tip.T @ np.array([0.0, 0.0, -_GRAVITY_M_S2])
    weight_torque = config.stylus_first_moment_kg_m * np.cross(z, gravity_in_tip)
    # Contact torque about the pivot: (L z) x F; the springs push back with -k theta:
    # axis . ((L z) x F + weight_torque) = k theta  <=>  L (axis x z) . F = k theta - ...
    rows = np.array([length * np.cross(axis_x, z), length * np.cross(axis_y, z), z])
    rhs = np.array(
        [
            k * theta_x - axis_x @ weight_torque,
            k * theta_y - axis_y @ weight_torque,
            # The force cell reads the stylus's push on the tip (+z: pressing); the contact
            # force balances it and the tip's weight.
            -reading.axial_force_n - config.tip_weight_n * gravity_in_tip[2] / _GRAVITY_M_S2,
        ]
    )
    return np.linalg.solve(rows, rhs)


def estimate_contact(
    reading: SensorReading,
    config: SensorConfig | None = None,
    fallback_normal: ArrayLike | None = None,
    slid_from_in_world: ArrayLike | None = None,
) -> ContactEstimate:
    """Returns the contact point sensed from one reading (see the module docstring).

    Parameters
    ----------
    reading : SensorReading
        Taken at rest while the tip touches the surface.
    config : SensorConfig or None
        None: the defaults.
    fallback_normal : (3,) float or None
        Outward normal to use when the estimated contact force is below
        ``config.min_normal_force_n`` (e.g. against the approach direction); None means
        straight up.
    slid_from_in_world : (3,) float or None, metres
        Where the tip centre was (from an earlier reading) when the tip started sliding to
        where it is now. Friction acts along the slide, tangent to the surface: the
        normal's component along the slide is removed (slides shorter than
        ``config.min_slide_m`` are ignored).
    """
    config = config or SensorConfig()
    T_world_from_tip = probe_tip_pose(reading.joints, config.robot, reading.deflection_rad)
    centre = T_world_from_tip[:3, 3]
    force = T_world_from_tip[:3, :3] @ contact_force_in_tip_frame(reading, config)
    magnitude = float(np.linalg.norm(force))
    from_force = magnitude >= config.min_normal_force_n
    if from_force:
        normal = force / magnitude
        if slid_from_in_world is not None:
            # The tip slid on the surface: the chord is tangent to it (to within the
            # curvature times half the slide).
            slide = centre - np.asarray(slid_from_in_world, dtype=np.float64)
            length = float(np.linalg.norm(slide))
            if length >= config.min_slide_m:
                slide /= length
                along = float(normal @ slide)
                # More than friction can tilt: the slide was not along a face (an edge).
                if abs(along) <= config.max_path_correction:
                    normal = normal - along * slide
                    normal /= np.linalg.norm(normal)
    else:
        fallback = np.array([0.0, 0.0, 1.0] if fallback_normal is None else fallback_normal)
        normal = fallback / np.linalg.norm(fallback)
    radius = config.robot.probe.tip_radius_m
    return ContactEstimate(
        point_in_world=centre - radius * normal,
        tip_centre_in_world=centre,
        normal_in_world=normal,
        force_in_world=force,
        normal_from_force=from_force,
        reading=reading,
    )


def path_tangents(points: ArrayLike) -> NDArray[np.float64]:
    """Returns unit tangents of a polyline, (n, 3): central differences inside, second-order
    one-sided differences at the ends (n >= 3; fewer points give the chord direction)."""
    c = np.asarray(points, dtype=np.float64)
    if len(c) < 2:
        raise ValueError("a path needs at least two points")
    if len(c) == 2:
        t = np.tile(c[1] - c[0], (2, 1))
    else:
        t = np.empty_like(c)
        t[1:-1] = c[2:] - c[:-2]
        t[0] = -3.0 * c[0] + 4.0 * c[1] - c[2]
        t[-1] = 3.0 * c[-1] - 4.0 * c[-2] + c[-3]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def sweep_contacts(
    tip_centres_in_world: ArrayLike,
    normals_in_world: ArrayLike,
    config: SensorConfig | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Returns the contact points and normals of a sweep, refined with its path.

    The tip centres lie on the surface offset by the tip radius, whose normal at each
    centre is the surface's normal at the contact: it is perpendicular to the path of the
    centres. Friction tilts the force direction along the way the tip slid, i.e. along
    that path, so the component of each sensed normal along the path's tangent is
    friction (to first order) and is removed (``config.normals_across_path``).

    Parameters
    ----------
    tip_centres_in_world : (n, 3) float, metres
        Sensed tip centres, ordered along the sweep.
    normals_in_world : (n, 3) float
        Sensed unit normals.
    config : SensorConfig or None
        None: the defaults.

    Returns
    -------
    points : (n, 3) float, metres
        Contact points, tip centres minus the tip radius along the normals.
    normals : (n, 3) float
        Unit normals.
    """
    config = config or SensorConfig()
    centres = np.asarray(tip_centres_in_world, dtype=np.float64)
    normals = np.array(normals_in_world, dtype=np.float64)
    if config.normals_across_path and len(centres) >= 3:
        tangents = path_tangents(centres)
        along = np.einsum("ij,ij->i", normals, tangents)
        # Friction tilts by at most the friction angle; a larger component means the path's
        # tangent is not the surface's there (an edge, a kink): keep that normal.
        along[np.abs(along) > config.max_path_correction] = 0.0
        normals -= along[:, None] * tangents
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return centres - config.robot.probe.tip_radius_m * normals, normals


@dataclass(frozen=True)
class GroundTruthContact:
    """The simulator's true contact state (evaluation only; the sensor model never reads it).

    Attributes
    ----------
    tip_centre_in_world : (3,) float, metres
        True tip sphere centre (site ``probe_tip``).
    contact_points_in_world : (k, 3) float, metres
        MuJoCo's contact points of the tip geom (midway between the surfaces).
    contact_normals_in_world : (k, 3) float
        Their unit normals, pointing from the other geom towards the tip.
    surface_points_in_world : (k, 3) float, metres
        Where each contact meets the surface of the other geom (the collider the tip
        touches): the contact point moved out by half the penetration.
    penetrations_m : (k,) float, metres
        Depth of each contact (positive: the tip is inside the other geom).
    other_geoms : (k,) int
        Ids of the geoms the tip touches.
    stylus_contacts : int
        Contacts of the probe's other geoms (shaft, housing): a sensed point is suspect.
    """

    tip_centre_in_world: NDArray[np.float64]
    contact_points_in_world: NDArray[np.float64]
    contact_normals_in_world: NDArray[np.float64]
    surface_points_in_world: NDArray[np.float64]
    penetrations_m: NDArray[np.float64]
    other_geoms: NDArray[np.int64]
    stylus_contacts: int

    @property
    def touched_point_in_world(self) -> NDArray[np.float64]:
        """Returns the surface point of the deepest contact, (3,) metres (NaN: none)."""
        if len(self.penetrations_m) == 0:
            return np.full(3, np.nan)
        return self.surface_points_in_world[int(np.argmax(self.penetrations_m))]


class GroundTruthReader:
    """Reads the probe's true contact state from a simulation (evaluation only).

    The probe's ids in the model (tip geom, tip site, the other probe geoms) are looked
    up once, here.

    Parameters
    ----------
    physics : dm_control.mjcf.Physics
        The probing scene (:mod:`tactile_sim.scene`).
    """

    def __init__(self, physics: mjcf.Physics) -> None:
        from tactile_sim import scene

        model = physics.model.ptr
        self._data = physics.data.ptr
        self._tip_geom = int(physics.model.name2id(scene.PROBE_TIP_GEOM, "geom"))
        self._tip_site = int(physics.model.name2id(scene.PROBE_TIP_SITE, "site"))
        probe_body = physics.model.name2id("joystick_probe/probe_housing", "body")
        self._stylus_geoms = frozenset(
            g
            for g in range(model.ngeom)
            if _is_descendant(model, int(model.geom_bodyid[g]), probe_body) and g != self._tip_geom
        )

    def read(self) -> GroundTruthContact:
        """Returns the true contact state of the probe now."""
        data, tip_geom, site = self._data, self._tip_geom, self._tip_site
        points, normals, others, depths = [], [], [], []
        stylus = 0
        for i in range(data.ncon):
            contact = data.contact[i]
            g1, g2 = int(contact.geom1), int(contact.geom2)
            if tip_geom in (g1, g2):
                other = g2 if g1 == tip_geom else g1
                normal = np.array(contact.frame[:3])
                # Orient the normal from the surface towards the tip centre.
                if normal @ (data.site_xpos[site] - contact.pos) < 0:
                    normal = -normal
                points.append(np.array(contact.pos))
                normals.append(normal)
                others.append(other)
                depths.append(-float(contact.dist))
            elif g1 in self._stylus_geoms or g2 in self._stylus_geoms:
                stylus += 1
        points_array = np.array(points).reshape(-1, 3)
        normals_array = np.array(normals).reshape(-1, 3)
        penetrations = np.array(depths)
        return GroundTruthContact(
            tip_centre_in_world=np.array(data.site_xpos[site]),
            contact_points_in_world=points_array,
            contact_normals_in_world=normals_array,
            surface_points_in_world=points_array + 0.5 * penetrations[:, None] * normals_array,
            penetrations_m=penetrations,
            other_geoms=np.array(others, dtype=np.int64),
            stylus_contacts=stylus,
        )


def ground_truth_contact(physics: mjcf.Physics) -> GroundTruthContact:
    """Returns the true contact state of the probe from the simulator (evaluation only);
    code that reads it often keeps a :class:`GroundTruthReader`."""
    return GroundTruthReader(physics).read()


def _is_descendant(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """True if ``body`` is ``ancestor`` or below it in the kinematic tree."""
    while True:
        if body == ancestor:
            return True
        if body == 0:
            return False
        body = int(model.body_parentid[body])
