"""Cobra 600 SCARA kinematics with the joystick probe: forward, inverse and workspace checks."""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import rotation_about
from tactile_sim.errors import UnreachablePoint, WorkspaceLimit

__all__ = [
    "COBRA600",
    "Cobra600Geometry",
    "ElbowBranch",
    "JointLimits",
    "ProbeGeometry",
    "UnreachablePoint",
    "WorkspaceLimit",
    "flange_pose",
    "inverse_kinematics",
    "joint_limit_violation",
    "probe_tip_pose",
    "probe_tip_position",
    "reach_radii",
]


class ElbowBranch(enum.Enum):
    """The two inverse-kinematics solutions of the planar arm, as Adept names them.

    ``RIGHTY``: elbow angle >= 0 (seen from above the elbow lies to the right of the
    shoulder-to-quill line, like a right arm). ``LEFTY``: elbow angle < 0.
    """

    RIGHTY = "righty"
    LEFTY = "lefty"


@dataclass(frozen=True)
class JointLimits:
    """Joint ranges of the Cobra 600 (data sheet), the same as in ``scenes/cobra600.xml``.

    Attributes
    ----------
    shoulder_rad, elbow_rad, roll_rad : (2,) float, radians
        Lower and upper limits of the revolute joints.
    quill_m : (2,) float, metres
        Quill stroke, 0 = retracted (top), positive downwards.
    """

    shoulder_rad: tuple[float, float] = (-math.radians(105.0), math.radians(105.0))
    elbow_rad: tuple[float, float] = (-math.radians(150.0), math.radians(150.0))
    quill_m: tuple[float, float] = (0.0, 0.21)
    roll_rad: tuple[float, float] = (-2.0 * math.pi, 2.0 * math.pi)


@dataclass(frozen=True)
class ProbeGeometry:
    """Joystick probe dimensions, the same as in ``scenes/joystick_probe.xml``.

    Attributes
    ----------
    pivot_offset_m : float, metres
        Flange face to the pivot (the two deflection hinges), along the tool z axis.
    stylus_length_m : float, metres
        Pivot to the tip sphere's centre.
    tip_radius_m : float, metres
        Radius of the spherical tip.
    """

    pivot_offset_m: float = 0.06
    stylus_length_m: float = 0.12
    tip_radius_m: float = 0.001

    @property
    def tip_offset_m(self) -> float:
        """Returns the flange face to tip centre distance with the stylus undeflected, metres."""
        return self.pivot_offset_m + self.stylus_length_m


@dataclass(frozen=True)
class Cobra600Geometry:
    """Kinematic parameters of the SCARA arm (standard DH of the Cobra 600) and its probe.

    Joint vectors are ``(shoulder, elbow, quill, roll)`` in radians, radians, metres,
    radians: the revolute joints turn about +z (counter-clockwise seen from above), the
    quill moves down. The flange frame has its origin on the quill's lower end, z pointing
    down (tool approach direction) and x at yaw ``base_yaw + shoulder + elbow + roll``.

    Attributes
    ----------
    d1_m : float, metres
        Flange height above the base mounting plane with the quill retracted.
    a1_m, a2_m : float, metres
        Shoulder-to-elbow and elbow-to-quill link lengths.
    limits : JointLimits
        Joint ranges.
    probe : ProbeGeometry
        The joystick probe mounted on the flange.
    base_position_in_world : (3,) float, metres
        Base frame origin (shoulder axis on the mounting plane) in the world frame.
    base_yaw_rad : float, radians
        Rotation of the base frame about the world z axis.
    """

    d1_m: float = 0.387
    a1_m: float = 0.325
    a2_m: float = 0.275
    limits: JointLimits = field(default_factory=JointLimits)
    probe: ProbeGeometry = field(default_factory=ProbeGeometry)
    base_position_in_world: tuple[float, float, float] = (0.0, 0.0, 0.0)
    base_yaw_rad: float = 0.0


COBRA600 = Cobra600Geometry()
"""The robot of ``scenes/scene.xml``: base at the world origin, probe on the flange."""


def _joint_array(joints: ArrayLike) -> NDArray[np.float64]:
    """Checks a joint vector (or a stack of them) of shape (..., 4)."""
    q = np.asarray(joints, dtype=np.float64)
    if q.ndim == 0 or q.shape[-1] != 4:
        raise ValueError(
            f"joints must have shape (..., 4) (shoulder, elbow, quill, roll), got {q.shape}"
        )
    return q


_HALF_TURN_ABOUT_X = np.diag([1.0, -1.0, -1.0])
"""Rotation by pi about x, exact (``rotation_about(0, pi)`` leaves sin(pi) = 1.2e-16)."""


def flange_pose(joints: ArrayLike, robot: Cobra600Geometry = COBRA600) -> NDArray[np.float64]:
    """Returns T_world_from_flange, the flange pose for joint vectors.

    Parameters
    ----------
    joints : (..., 4) float
        ``(shoulder rad, elbow rad, quill m, roll rad)``.
    robot : Cobra600Geometry
        Kinematic parameters.

    Returns
    -------
    (..., 4, 4) float
        Homogeneous transforms, metres; the flange z axis points down.
    """
    q = _joint_array(joints)
    shoulder, elbow, quill, roll = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    x_in_base = robot.a1_m * np.cos(shoulder) + robot.a2_m * np.cos(shoulder + elbow)
    y_in_base = robot.a1_m * np.sin(shoulder) + robot.a2_m * np.sin(shoulder + elbow)
    c, s = math.cos(robot.base_yaw_rad), math.sin(robot.base_yaw_rad)
    base = robot.base_position_in_world
    yaw = robot.base_yaw_rad + shoulder + elbow + roll
    T = np.zeros((*q.shape[:-1], 4, 4))
    # Rotation about z by the yaw, then half a turn about x (the flange z axis points down).
    T[..., :3, :3] = rotation_about(2, yaw) @ _HALF_TURN_ABOUT_X
    T[..., 0, 3] = c * x_in_base - s * y_in_base + base[0]
    T[..., 1, 3] = s * x_in_base + c * y_in_base + base[1]
    T[..., 2, 3] = robot.d1_m - quill + base[2]
    T[..., 3, 3] = 1.0
    return T


def probe_tip_pose(
    joints: ArrayLike,
    robot: Cobra600Geometry = COBRA600,
    deflection: ArrayLike = (0.0, 0.0),
) -> NDArray[np.float64]:
    """Returns T_world_from_tip, the pose of the probe tip centre (site ``probe_tip``).

    Parameters
    ----------
    joints : (..., 4) float
        ``(shoulder rad, elbow rad, quill m, roll rad)``.
    robot : Cobra600Geometry
        Kinematic parameters, including the probe's.
    deflection : (..., 2) float, radians
        Pivot angles ``(deflection_x, deflection_y)``: a rotation about the flange x axis,
        then about the tilted y axis. Zero is a stylus along the flange z axis.

    Returns
    -------
    (..., 4, 4) float
        Homogeneous transforms, metres; the tip frame's z axis runs along the stylus.
    """
    T_world_from_flange = flange_pose(joints, robot)
    angles = np.asarray(deflection, dtype=np.float64)
    if angles.ndim == 0 or angles.shape[-1] != 2:
        raise ValueError(f"deflection must have shape (..., 2), got {angles.shape}")
    R_flange_from_tip = rotation_about(0, angles[..., 0]) @ rotation_about(1, angles[..., 1])
    probe = robot.probe
    tip_in_flange = np.array([0.0, 0.0, probe.pivot_offset_m]) + (
        R_flange_from_tip[..., :, 2] * probe.stylus_length_m
    )
    shape = np.broadcast_shapes(T_world_from_flange.shape[:-2], angles.shape[:-1])
    T_flange_from_tip = np.zeros((*shape, 4, 4))
    T_flange_from_tip[..., :3, :3] = R_flange_from_tip
    T_flange_from_tip[..., :3, 3] = tip_in_flange
    T_flange_from_tip[..., 3, 3] = 1.0
    return T_world_from_flange @ T_flange_from_tip


def probe_tip_position(
    joints: ArrayLike,
    robot: Cobra600Geometry = COBRA600,
    deflection: ArrayLike = (0.0, 0.0),
) -> NDArray[np.float64]:
    """Returns the probe tip centre in the world frame, (..., 3) metres (see probe_tip_pose)."""
    return probe_tip_pose(joints, robot, deflection)[..., :3, 3]


def reach_radii(robot: Cobra600Geometry = COBRA600) -> tuple[float, float]:
    """Returns the smallest and largest quill-axis distance from the shoulder axis, metres.

    The smallest radius is set by the elbow limit, the largest by the stretched arm.
    """
    elbow_max = max(abs(robot.limits.elbow_rad[0]), abs(robot.limits.elbow_rad[1]))
    elbow_max = min(elbow_max, math.pi)
    a1, a2 = robot.a1_m, robot.a2_m
    r_min = math.sqrt(max(a1 * a1 + a2 * a2 + 2.0 * a1 * a2 * math.cos(elbow_max), 0.0))
    return r_min, a1 + a2


def _limit_message(name: str, value: float, limits: tuple[float, float], unit: str) -> str:
    """Formats 'name = value outside [lo, hi]' in degrees (angles) or metres."""
    scale = math.degrees(1.0) if unit == "deg" else 1.0
    digits = 1 if unit == "deg" else 4
    return (
        f"{name} = {value * scale:.{digits}f} {unit}, outside the {name} limit "
        f"[{limits[0] * scale:.{digits}f}, {limits[1] * scale:.{digits}f}] {unit}"
    )


def joint_limit_violation(
    joints: ArrayLike, robot: Cobra600Geometry = COBRA600
) -> UnreachablePoint | None:
    """Returns the error for the first joint outside its limit, or None if all are inside.

    Parameters
    ----------
    joints : (4,) float
        ``(shoulder rad, elbow rad, quill m, roll rad)``.
    robot : Cobra600Geometry
        Kinematic parameters and joint limits.
    """
    q = _joint_array(joints)
    if q.shape != (4,):
        raise ValueError(f"joints must have shape (4,), got {q.shape}")
    lim = robot.limits
    checks = (
        (WorkspaceLimit.SHOULDER, q[0], lim.shoulder_rad, "deg"),
        (WorkspaceLimit.ELBOW, q[1], lim.elbow_rad, "deg"),
        (WorkspaceLimit.QUILL, q[2], lim.quill_m, "m"),
        (WorkspaceLimit.ROLL, q[3], lim.roll_rad, "deg"),
    )
    tolerance = 1e-12
    for limit, value, (lo, hi), unit in checks:
        if not lo - tolerance <= value <= hi + tolerance:
            return UnreachablePoint(_limit_message(limit.value, value, (lo, hi), unit), limit)
    return None


def _branch_solution(
    x: float,
    y: float,
    quill: float,
    yaw_in_base: float,
    branch: ElbowBranch,
    robot: Cobra600Geometry,
    roll_reference: float | None,
) -> NDArray[np.float64] | UnreachablePoint:
    """Joint vector of one elbow branch (radius and quill already checked), or its error."""
    a1, a2 = robot.a1_m, robot.a2_m
    cos_elbow = (x * x + y * y - a1 * a1 - a2 * a2) / (2.0 * a1 * a2)
    elbow = math.acos(min(max(cos_elbow, -1.0), 1.0))
    if branch is ElbowBranch.LEFTY:
        elbow = -elbow
    shoulder = math.atan2(y, x) - math.atan2(a2 * math.sin(elbow), a1 + a2 * math.cos(elbow))
    shoulder = math.remainder(shoulder, 2.0 * math.pi)
    roll = math.remainder(yaw_in_base - shoulder - elbow, 2.0 * math.pi)
    lo, hi = robot.limits.roll_rad
    candidates = [roll + k * 2.0 * math.pi for k in range(-2, 3)]
    candidates = [c for c in candidates if lo <= c <= hi] or [roll]
    reference = 0.0 if roll_reference is None else roll_reference
    roll = min(candidates, key=lambda c: abs(c - reference))
    q = np.array([shoulder, elbow, quill, roll])
    violation = joint_limit_violation(q, robot)
    if violation is not None:
        return UnreachablePoint(f"{branch.value} elbow branch needs {violation}", violation.limit)
    return q


def inverse_kinematics(
    tip_position_in_world: ArrayLike,
    tool_yaw_rad: float = 0.0,
    robot: Cobra600Geometry = COBRA600,
    branch: ElbowBranch | None = None,
    joints_reference: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Returns the joint vector that puts the undeflected probe tip centre at a point.

    Closed form: the quill sets the height, the planar two-link arm the horizontal position
    (two elbow branches), the roll the tool yaw.

    Parameters
    ----------
    tip_position_in_world : (3,) float, metres
        Target for the tip centre, stylus along the flange z axis (no deflection).
    tool_yaw_rad : float, radians
        Yaw of the flange x axis about the world z axis.
    robot : Cobra600Geometry
        Kinematic parameters and joint limits.
    branch : ElbowBranch or None
        Elbow branch to use; None picks a branch within the joint limits, the one closest
        to ``joints_reference`` if given, else RIGHTY before LEFTY.
    joints_reference : (4,) float or None
        Current joints: picks the branch (when ``branch`` is None) and the roll turn closest
        to them.

    Returns
    -------
    (4,) float
        ``(shoulder rad, elbow rad, quill m, roll rad)``.

    Raises
    ------
    UnreachablePoint
        The point is too far from or too close to the shoulder axis, needs a quill position
        outside the stroke, or (for the requested branch, or for both when ``branch`` is
        None) a joint outside its limit. The message names the limit.
    """
    target = np.asarray(tip_position_in_world, dtype=np.float64)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise ValueError(f"tip_position_in_world must be a finite (3,) array, got {target}")
    flange_in_world = target + np.array([0.0, 0.0, robot.probe.tip_offset_m])
    offset = flange_in_world - np.asarray(robot.base_position_in_world)
    c, s = math.cos(robot.base_yaw_rad), math.sin(robot.base_yaw_rad)
    x, y = c * offset[0] + s * offset[1], -s * offset[0] + c * offset[1]
    radius = math.hypot(x, y)
    r_min, r_max = reach_radii(robot)
    tolerance = 1e-12
    if radius > r_max + tolerance:
        raise UnreachablePoint(
            f"point {target.round(4).tolist()} m is {radius:.4f} m from the shoulder axis, "
            f"beyond the reach a1 + a2 = {r_max:.4f} m (radius too large)",
            WorkspaceLimit.RADIUS_TOO_LARGE,
        )
    if radius < r_min - tolerance:
        raise UnreachablePoint(
            f"point {target.round(4).tolist()} m is {radius:.4f} m from the shoulder axis, "
            f"inside the minimum radius {r_min:.4f} m set by the elbow limit "
            f"{math.degrees(max(map(abs, robot.limits.elbow_rad))):.1f} deg (radius too small)",
            WorkspaceLimit.RADIUS_TOO_SMALL,
        )
    quill = robot.d1_m - offset[2]
    lo, hi = robot.limits.quill_m
    if not lo - tolerance <= quill <= hi + tolerance:
        tip_lo = robot.base_position_in_world[2] + robot.d1_m - hi - robot.probe.tip_offset_m
        tip_hi = robot.base_position_in_world[2] + robot.d1_m - lo - robot.probe.tip_offset_m
        raise UnreachablePoint(
            f"point {target.round(4).tolist()} m needs quill = {quill:.4f} m, outside the "
            f"quill stroke [{lo:.4f}, {hi:.4f}] m (tip height range "
            f"[{tip_lo:.4f}, {tip_hi:.4f}] m)",
            WorkspaceLimit.QUILL,
        )
    quill = min(max(quill, lo), hi)
    reference = None if joints_reference is None else _joint_array(joints_reference)
    roll_reference = None if reference is None else float(reference[3])
    yaw_in_base = tool_yaw_rad - robot.base_yaw_rad
    branches: Sequence[ElbowBranch] = (
        (branch,) if branch is not None else (ElbowBranch.RIGHTY, ElbowBranch.LEFTY)
    )
    solutions = [
        _branch_solution(x, y, quill, yaw_in_base, b, robot, roll_reference) for b in branches
    ]
    feasible = [q for q in solutions if not isinstance(q, UnreachablePoint)]
    if not feasible:
        errors = [e for e in solutions if isinstance(e, UnreachablePoint)]
        message = "; ".join(str(e) for e in errors)
        raise UnreachablePoint(f"point {target.round(4).tolist()} m: {message}", errors[0].limit)
    if reference is None:
        return feasible[0]
    return min(feasible, key=lambda q: float(np.linalg.norm(q[:2] - reference[:2])))
