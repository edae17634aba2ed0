"""Verification touches by the robot after the three sweeps (active touch).

:func:`touch_until_sure` recognises the session's curves, then runs
:func:`recognition.verify` with the rig itself as the touch: for each planned touch the
arm retreats to its travel height, moves over the approach's start, comes down to it and
makes one guarded approach along the planned direction
(:meth:`tactile_sim.probing.rig.Rig.approach`); the sensed contact point (or nothing
within the travel) updates every hypothesis. Touches are planned on the object's free
surface within the stylus's tilt limit, clear of the table, and where the arm reaches
both ends of the approach. A reading whose force runs far more across the stylus than any
surface allowed to a touch would press it is the shaft's, not the tip's: it is not used
(:class:`recognition.NoReading`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from recognition import (
    BeliefConfig,
    Contact,
    ModelDatabase,
    NoiseModel,
    NoReading,
    Recognition,
    RegistrationConfig,
    TouchLimits,
    TouchPlan,
    Verification,
    verify,
)
from tactile_sim.errors import SimulationError, UnreachablePoint
from tactile_sim.kinematics import COBRA600, inverse_kinematics
from tactile_sim.probing.session import ProbeSession
from tactile_sim.trajectory import Trajectory

__all__ = [
    "RobotToucher",
    "TouchRecord",
    "TouchSession",
    "shaft_reading",
    "touch_limits",
    "touch_until_sure",
]

Array = NDArray[np.float64]

#: Touches stay this far above the table top (world z = 0), metres.
TABLE_CLEARANCE_M = 5.0e-3
#: Largest tilt of a touched surface from vertical, degrees (within the sweeps' limit).
TOUCH_TILT_DEG = 60.0
#: A reading whose sensed normal tilts this much more than that from vertical is the
#: shaft's: the tip pressed on a surface within the limit pushes the stylus along its axis
#: too, the shaft is pushed across it (over 30 sessions with 0.1 mm model error, 69 tip
#: readings tilted at most 77 degrees, the readings without the tip's contact 83-90; a tip
#: reading refused is a touch lost, a shaft's used a point up to millimetres off).
SHAFT_READING_MARGIN_DEG = 20.0
#: The stylus shaft's collision radius (``scenes/joystick_probe.xml``), metres ...
STYLUS_RADIUS_M = 0.8e-3
#: ... checked for clearance this far above the tip (the housing sits higher than any
#: catalog object), metres.
STYLUS_CHECK_LENGTH_M = 0.1


@dataclass(frozen=True)
class TouchRecord:
    """One verification touch of the robot (world frame, metres).

    Attributes
    ----------
    plan : TouchPlan
    point_in_world : (3,) float or None
        Sensed contact point (None: nothing met within the travel).
    normal_in_world : (3,) float or None
        Sensed outward normal.
    true_contact_in_world : (3,) float or None
        Ground truth: where MuJoCo's contact met the object (None without a contact).
    no_reading : str or None
        Why the reading was not used (the shaft touched); None: it was, or nothing met.
    confidence : float
        Confidence after the update.
    best_model : str or None
    recognition_time_s : float
        Planning and updating, seconds.
    robot_time_s : float
        Wall time of the motion and the approach, seconds.
    sim_time_s : float
        Simulated time at the reading (or when the approach gave up), seconds.
    """

    plan: TouchPlan
    point_in_world: Array | None
    normal_in_world: Array | None
    true_contact_in_world: Array | None
    confidence: float
    best_model: str | None
    recognition_time_s: float
    robot_time_s: float
    sim_time_s: float
    no_reading: str | None = None


@dataclass(frozen=True)
class TouchSession:
    """The recognition after the sweeps and the verification touches that followed.

    Attributes
    ----------
    recognition : Recognition
        From the three curves alone.
    verification : Verification
        The belief after the touches (``verification.belief``) and why they stopped.
    touches : tuple of TouchRecord
    wall_seconds : float
        Recognition, planning, updates and robot motion, seconds.
    trajectory : Trajectory or None
        The rig's state sampled through the sweeps and the touches (when the session
        recorded one).
    """

    recognition: Recognition
    verification: Verification
    touches: tuple[TouchRecord, ...]
    wall_seconds: float
    trajectory: Trajectory | None = None


def shaft_reading(normal_in_world: Array) -> str | None:
    """Why a reading whose sensed outward normal (world frame, unit) is ``normal_in_world``
    is the shaft's, not the tip's (it tilts more than ``SHAFT_READING_MARGIN_DEG`` beyond
    the touches' tilt limit from vertical); None: it may be the tip's."""
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, float(normal_in_world[2])))))
    if tilt <= TOUCH_TILT_DEG + SHAFT_READING_MARGIN_DEG:
        return None
    return f"the force ran {tilt:.0f} deg from the stylus's axis: the shaft touched"


def touch_limits(session: ProbeSession) -> TouchLimits:
    """The touches the session's robot can make: world frame (the curves' frame), the
    stylus's tilt limit, clear of the table, both ends of the approach reachable."""
    robot = session.runner.rig.sensor.robot if session.runner is not None else COBRA600
    limits = TouchLimits(
        up=np.array([0.0, 0.0, 1.0]),
        max_tilt_rad=math.radians(TOUCH_TILT_DEG),
        min_height_m=TABLE_CLEARANCE_M,
        tip_radius_m=robot.probe.tip_radius_m,
        tool_radius_m=STYLUS_RADIUS_M,
        tool_length_m=STYLUS_CHECK_LENGTH_M,
    )

    def reachable(starts: Array, directions: Array) -> NDArray[np.bool_]:
        ok = np.ones(len(starts), bool)
        for k, (start, direction) in enumerate(zip(starts, directions, strict=True)):
            try:
                for point in (start, start + limits.depth_m * direction):
                    inverse_kinematics(point, robot=robot)
            except UnreachablePoint:
                ok[k] = False
        return ok

    return replace(limits, reachable=reachable)


def touch_until_sure(
    session: ProbeSession,
    database: ModelDatabase,
    *,
    max_touches: int = 5,
    confidence: float = 0.99,
    registration: RegistrationConfig | None = None,
    noise: NoiseModel | None = None,
    belief: BeliefConfig | None = None,
    recognition: Recognition | None = None,
) -> TouchSession:
    """Recognise the session's curves, then touch until sure (module docstring).

    Parameters
    ----------
    session : ProbeSession
        Fresh from :func:`probe_object` (its rig continues).
    database : ModelDatabase
    max_touches : int
        At most this many touches (0: the thesis's three curves alone).
    confidence : float
        Stop once the belief's confidence (:attr:`Belief.confidence`) reaches this.
    registration, noise, belief
        Passed to :meth:`ModelDatabase.recognize`.
    recognition : Recognition, optional
        The curves' recognition when already made.

    Raises
    ------
    SimulationError
        The session's rig is gone (a session rebuilt from files), or MuJoCo became
        unstable.
    """
    start = time.perf_counter()
    runner = session.runner
    toucher = RobotToucher(session)
    if recognition is None:
        recognition = database.recognize(session.curves, registration, noise=noise, belief=belief)
    assert recognition.belief is not None  # mesh databases give a belief
    verification = verify(
        database,
        recognition.belief,
        toucher,
        toucher.limits,
        max_touches=max_touches,
        confidence=confidence,
        seed=session.seed,
    )
    if runner is not None and toucher.made:
        runner.retreat()
    records = tuple(
        TouchRecord(
            step.plan,
            point,
            normal,
            truth,
            step.confidence,
            step.best_model,
            step.recognition_time_s,
            seconds,
            sim_time,
            no_reading,
        )
        for step, (point, normal, truth, seconds, sim_time, no_reading) in zip(
            verification.steps, toucher.made, strict=True
        )
    )
    recorder = toucher.runner.rig.recorder
    return TouchSession(
        recognition,
        verification,
        records,
        time.perf_counter() - start,
        None if recorder is None else recorder.trajectory(),
    )


class RobotToucher:
    """The rig of a fresh session as the touch of :func:`recognition.verify`: retreat to
    the travel height, over the approach's start, down to it, one guarded approach along
    the planned direction. ``made`` keeps each touch's sensed point and normal, MuJoCo's
    contact (None without one), the wall and simulated time taken, and why the reading
    was not used (None: it was).

    Raises
    ------
    SimulationError
        The session's rig is gone (a session rebuilt from files).
    """

    def __init__(self, session: ProbeSession) -> None:
        if session.runner is None:
            raise SimulationError("the session's rig is gone: touches need a fresh probe_object")
        self.runner = session.runner
        self.limits = touch_limits(session)
        self.made: list[
            tuple[Array | None, Array | None, Array | None, float, float, str | None]
        ] = []

    def __call__(self, plan: TouchPlan) -> Contact | NoReading | None:
        """The sensed contact of the planned touch (None: nothing within its travel); its
        normal when the reading's force gave one; :class:`NoReading` when that force ran
        across the stylus (``SHAFT_READING_MARGIN_DEG`` beyond the touches' tilt limit)."""
        runner = self.runner
        began = time.perf_counter()
        runner.retreat()
        runner.travel_to(plan.start)
        estimate = runner.rig.approach(plan.start, plan.direction, plan.travel_m)
        if estimate is None:
            sim_time = float(runner.rig.data.time)
            self.made.append((None, None, None, time.perf_counter() - began, sim_time, None))
            return None
        sample = runner.sample(estimate)
        touched = sample.touched if np.all(np.isfinite(sample.touched)) else None
        # The sensed contact: a tip radius from the sensed centre against the sensed
        # normal (the reading's force direction; the approach's when the force gave none).
        # The approach runs along the normal the hypotheses predict, often 5-15 degrees
        # off the true one: a point a radius ahead along it lay up to 0.19 mm off the
        # surface (p90 0.075 mm), the sensed one within 0.003 mm (median 0.0005).
        point = estimate.point_in_world
        no_reading = shaft_reading(estimate.normal_in_world) if estimate.normal_from_force else None
        self.made.append(
            (
                point,
                estimate.normal_in_world,
                touched,
                time.perf_counter() - began,
                estimate.reading.time_s,
                no_reading,
            )
        )
        if no_reading is not None:
            return NoReading(no_reading)
        return Contact(point, estimate.normal_in_world if estimate.normal_from_force else None)
