"""The probing rig: joint-space moves and guarded approaches of the arm, sensor readings.

An approach runs in two phases: at ``approach_speed_m_s`` until the first touch (a small
deflection or axial force), then, after backing off ``backoff_m`` from the impact, a press
at ``press_speed_m_s`` until the set point: a deflection of ``deflection_trigger_rad`` (a
sloped surface tilts the stylus) or an axial force of ``axial_force_trigger_n`` (a level
one loads it along its rigid axis), steadily for a few timesteps so that an impact spike
does not count. The arm then holds, the stylus settles for ``dwell_s`` and the sensors are
read, averaged over ``reading_average_s`` (:mod:`tactile_sim.sensor` turns the reading and
the slide of the press into the sensed contact point and normal).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import NDArray

from tactile_sim import scene
from tactile_sim.kinematics import inverse_kinematics, probe_tip_position
from tactile_sim.probing.config import ProbingConfig
from tactile_sim.probing.probe_scene import ProbeScene
from tactile_sim.probing.tip_contact import TipContact
from tactile_sim.sensor import (
    ContactEstimate,
    SensorConfig,
    SensorReader,
    SensorReading,
    estimate_contact,
)
from tactile_sim.trajectory import TrajectoryRecorder

__all__ = [
    "Rig",
]


class Rig:
    """Drives the arm through joint-space moves and guarded approaches; reads the sensor.

    Parameters
    ----------
    probe_scene : ProbeScene
        The scene to drive, its physics just reset.
    config : ProbingConfig
        Speeds, set points and thresholds of the moves and approaches.
    sensor : SensorConfig
        The sensor model: noise, the robot's kinematics, the calibration.
    rng : numpy.random.Generator
        Source of the reading noise.
    recorder : TrajectoryRecorder or None
        Steps the simulation and samples the rig's state on the way; None steps plainly.
    """

    def __init__(
        self,
        probe_scene: ProbeScene,
        config: ProbingConfig,
        sensor: SensorConfig,
        rng: np.random.Generator,
        recorder: TrajectoryRecorder | None = None,
    ) -> None:
        physics = probe_scene.physics
        self.physics = physics
        self.model, self.data = physics.model.ptr, physics.data.ptr
        # Steps like mujoco.mj_step(model, data[, nstep]); the recorder samples on the way,
        # the tip's contact box follows the tip.
        step = mujoco.mj_step if recorder is None else recorder.step
        self.recorder = recorder
        self.tip_contact = TipContact(probe_scene) if probe_scene.tip_contact else None
        self._step = step if self.tip_contact is None else self.tip_contact.stepping(step)
        self.config = config
        self.sensor = sensor
        self.reader = SensorReader(physics, sensor.noise, rng)
        self.dt = float(self.model.opt.timestep)
        actuators = [physics.model.name2id(j, "actuator") for j in scene.ARM_JOINTS]
        first = actuators[0]
        # A slice is faster than an index array in the per-step loops.
        self.actuators = (
            slice(first, first + 4) if actuators == list(range(first, first + 4)) else actuators
        )
        self.q_command = scene.arm_joints(physics)
        self.last_touch_centre = np.zeros(3)
        self.first_contact: NDArray[np.float64] | None = None

    def _set_ctrl(self, q: NDArray[np.float64]) -> None:
        """Commands the joints ``q`` (4,) from the next step on."""
        self.data.ctrl[self.actuators] = q
        self.q_command = q

    def _check(self) -> None:
        """Raises SimulationUnstable if MuJoCo warned or the state is not finite."""
        scene.raise_on_warnings(self.physics)

    def ik(self, tip_in_world: NDArray[np.float64]) -> NDArray[np.float64]:
        """Returns the joints (4,) that put the undeflected tip centre at a point, the branch
        and roll turn nearest the commanded joints."""
        return inverse_kinematics(
            tip_in_world,
            tool_yaw_rad=self.config.tool_yaw_rad,
            robot=self.sensor.robot,
            joints_reference=self.q_command,
        )

    def teleport(self, tip_in_world: NDArray[np.float64]) -> None:
        """Puts the arm at rest with the undeflected tip at a point (no contact there)."""
        q = self.ik(tip_in_world)
        scene.set_arm_joints(self.physics, q)
        self.q_command = q

    def settle(self, seconds: float) -> None:
        """Holds the command for ``seconds`` of simulated time (at least one step)."""
        n = max(1, round(seconds / self.dt))
        self._step(self.model, self.data, n)
        self._check()

    def move(self, tip_in_world: NDArray[np.float64], speed: float) -> None:
        """Minimum-jerk joint-space move of the undeflected tip to a point."""
        distance = float(np.linalg.norm(np.asarray(tip_in_world) - self.commanded_tip()))
        self._smooth_to(self.ik(tip_in_world), max(1.875 * distance / speed, 0.01))

    def _smooth_to(self, q1: NDArray[np.float64], duration: float) -> None:
        """Minimum-jerk joint-space move of the command to ``q1`` in ``duration`` seconds."""
        q0 = self.q_command.copy()
        n = max(1, round(duration / self.dt))
        tau = np.arange(1, n + 1) / n
        profile = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
        path = q0 + profile[:, None] * (q1 - q0)
        model, data, actuators, step = self.model, self.data, self.actuators, self._step
        for q in path:
            data.ctrl[actuators] = q
            step(model, data)
        self.q_command = np.array(q1, dtype=np.float64)
        self._check()

    def commanded_tip(self) -> NDArray[np.float64]:
        """Returns where the commanded joints put the undeflected tip centre, world."""
        return probe_tip_position(self.q_command, self.sensor.robot)

    def _guarded_line(
        self,
        target: NDArray[np.float64],
        travel: float,
        speed: float,
        deflection_rad: float,
        axial_force_n: float,
        persist_steps: int,
        lead: bool,
    ) -> NDArray[np.float64] | None:
        """Moves the command in a straight joint-space line towards the undeflected tip
        position ``target`` (``travel`` metres away) at ``speed`` after a ramp, until the
        deflection or the axial force reaches its threshold for ``persist_steps`` steps in
        a row. Then holds the arm where the encoders put it when the streak began (they lag
        the state by one step; ``lead`` adds the command increment, holding the arm where
        it was then rather than one step before); returns the triggering reading (7
        values, see SensorReader.raw), or None after the whole travel. The first reading
        with evidence of contact (the touch thresholds) is kept in ``first_contact``."""
        q0 = self.q_command.copy()
        q1 = self.ik(target)
        # Distance covered after each step: a linear speed ramp, then constant speed.
        n_ramp = max(1, round(self.config.ramp_s / self.dt))
        n_total = n_ramp // 2 + math.ceil(travel / (speed * self.dt))
        steps = np.arange(1, n_total + 1)
        covered = np.where(
            steps <= n_ramp,
            0.5 * speed * self.dt * steps**2 / n_ramp,
            speed * self.dt * (steps - 0.5 * n_ramp),
        )
        path = q0 + np.minimum(covered / travel, 1.0)[:, None] * (q1 - q0)
        model, data, actuators, raw = self.model, self.data, self.actuators, self.reader.raw
        step = self._step
        count = 0
        streak_start = q0
        previous = q0
        # The stiff tip contact can chatter (on and off every step) while the stylus, with
        # its inertia, does not: the axial force is judged on a short running mean.
        recent_axial = [0.0] * self.config.axial_average_steps
        touch_deflection, touch_force = (
            self.config.touch_deflection_rad,
            self.config.touch_axial_force_n,
        )
        self.first_contact = None
        for i, q in enumerate(path):
            data.ctrl[actuators] = q
            step(model, data)
            values = raw()
            recent_axial[i % len(recent_axial)] = values[6]
            axial = sum(recent_axial) / len(recent_axial)
            deflection = math.hypot(values[4], values[5])
            if self.first_contact is None and (
                deflection >= touch_deflection or values[6] >= touch_force
            ):
                self.first_contact = values
            if deflection >= deflection_rad or axial >= axial_force_n:
                if count == 0:
                    streak_start = values[:4] + (q - previous) if lead else values[:4].copy()
                count += 1
                if count >= persist_steps:
                    # Hold where the condition first held (a stiff contact would otherwise
                    # build force while the streak is confirmed).
                    self._set_ctrl(streak_start)
                    self._check()
                    return values
            else:
                count = 0
            previous = q
        self.q_command = q1
        self._check()
        return None

    def approach(
        self, start: NDArray[np.float64], direction: NDArray[np.float64], travel: float
    ) -> ContactEstimate | None:
        """Guarded approach from ``start`` along ``direction``; returns the sensed contact,
        or None when nothing was touched within ``travel`` metres.

        Two phases: at ``approach_speed_m_s`` until the first touch, then, from where the
        arm stopped, a press at ``press_speed_m_s`` until the deflection or the axial
        force reaches its set point (steadily, not in an impact spike). The arm holds
        there, the stylus settles for ``dwell_s``, the sensors are read.
        """
        config = self.config
        touched = self._guarded_line(
            start + travel * direction,
            travel,
            config.approach_speed_m_s,
            config.touch_deflection_rad,
            config.touch_axial_force_n,
            1,
            lead=False,
        )
        if touched is None:
            return None
        # Back off from the impact (the arm overshoots the touch point), then press slowly.
        touch_tip = self.commanded_tip()
        here = touch_tip - config.backoff_m * direction
        self._smooth_to(self.ik(here), 2.0 * config.ramp_s)
        self.settle(config.touch_settle_s)
        touch_centre = probe_tip_position(touched[:4], self.sensor.robot, touched[4:6])
        travel = config.backoff_m + config.press_travel_m
        for attempt in range(1 + config.press_retries):
            start_tip = self.commanded_tip()
            pressed = self._guarded_line(
                start_tip + travel * direction,
                travel,
                config.press_speed_m_s / (1 + attempt),
                config.deflection_trigger_rad,
                config.axial_force_trigger_n,
                config.press_persist_steps,
                lead=False,
            )
            if pressed is None:
                self._set_ctrl(self.q_command)
            if attempt == 0 and self.first_contact is not None:
                # The slide starts where the slow press met the surface again.
                values = self.first_contact
                touch_centre = probe_tip_position(values[:4], self.sensor.robot, values[4:6])
            self.last_touch_centre = touch_centre
            self.settle(config.dwell_s)
            estimate = estimate_contact(
                self._averaged_reading(),
                self.sensor,
                fallback_normal=-direction,
                slid_from_in_world=touch_centre,
            )
            # An impact spike can stop the press before the set point: press on, slower.
            if estimate.normal_from_force or pressed is None:
                break
            travel = config.press_travel_m
        return estimate

    def _averaged_reading(self) -> SensorReading:
        """Returns the mean of the readings over the next ``reading_average_s`` (the sensor
        samples every timestep; the mean smooths contact chatter and noise)."""
        n = max(1, round(self.config.reading_average_s / self.dt))
        total = np.zeros(7)
        for _ in range(n):
            self._step(self.model, self.data)
            total += self.reader.raw()
        self._check()
        mean = total / n
        return SensorReading(
            time_s=float(self.data.time),
            joints=mean[:4],
            deflection_rad=mean[4:6],
            axial_force_n=float(mean[6]),
        )
