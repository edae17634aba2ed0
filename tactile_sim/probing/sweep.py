"""Sweeps: the touch-probe cycle along one sampling plane, point by point, and its result.

For every point the cycle

1. predicts where the next contact lies: one spacing on from where the last approach met
   the surface, along the in-plane tangent that the last sensed normal gives (turned by
   half the turn of the normal between the last two points);
2. moves the undeflected tip to a start point ``standoff_m`` outside that prediction,
   aimed off the plane by what the last point drifted (so that the contact lands in it);
3. approaches along the in-plane normal, presses to the set point, dwells and reads the
   sensors (:meth:`tactile_sim.probing.rig.Rig.approach`).

The first point of the first sweep is touched twice: the second approach line is moved
by the horizontal miss of the first, so that the three curves meet at the planned p.

No contact within ``search_m`` beyond the prediction means the surface fell away (an
edge): that side of the sweep is truncated, reported, and the other side of p is
extended instead when it can be. A surface turning steeper than ``max_tilt_deg`` ends a
side the same way, as does a point the arm cannot reach (the reason names the limit).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from tactile_sim.errors import SimulationError, UnreachablePoint
from tactile_sim.probing.config import ProbingConfig
from tactile_sim.probing.plan import SamplingPlane
from tactile_sim.probing.probe_scene import ProbeScene
from tactile_sim.probing.rig import Rig
from tactile_sim.sensor import ContactEstimate, GroundTruthReader, SensorConfig, sweep_contacts

__all__ = [
    "Sample",
    "StopReason",
    "SweepResult",
    "SweepRunner",
    "SweepSide",
    "run_sweep",
    "sweep_result",
]


class StopReason(enum.Enum):
    """Why one side of a sweep ended."""

    COMPLETE = "complete"
    LOST_CONTACT = "lost_contact"
    TOO_STEEP = "too_steep"
    UNREACHABLE = "unreachable"
    BLOCKED = "blocked"


@dataclass(frozen=True)
class SweepSide:
    """One side of a sweep, from p outward.

    Attributes
    ----------
    direction : int
        +1 (along ``forward_in_world``) or -1.
    requested : int
        Points asked for on this side (p excluded).
    acquired : int
        Points sensed.
    stop : StopReason
    message : str
        What stopped it, in words ("" when complete).
    """

    direction: int
    requested: int
    acquired: int
    stop: StopReason
    message: str = ""


@dataclass(frozen=True)
class SweepResult:
    """One sweep: the sensed curve through p in one sampling plane.

    Attributes
    ----------
    plane : SamplingPlane
    points_in_world : (n, 3) float, metres
        Sensed contact points, ordered along ``forward_in_world``.
    normals_in_world : (n, 3) float
        Sensed outward normals.
    tip_centres_in_world : (n, 3) float, metres
        Tip centres from the readings.
    p_index : int
        Index of the point sensed at p.
    sides : tuple of SweepSide
        What happened on each side of p, in the order they ran.
    true_tip_centres_in_world : (n, 3) float, metres
        Ground truth: the simulator's tip centres at the readings.
    true_contact_points_in_world : (n, 3) float, metres
        Ground truth: where MuJoCo's contact met the surface the tip touched (the
        collider) at each reading (the nearest mesh point where a reading caught the
        stiff contact off for a timestep).
    mesh_points_in_world : (n, 3) float, metres
        Ground truth: the points of the object's mesh nearest the true tip centres.
    stylus_contacts : (n,) int
        Ground truth: contacts of the shaft or housing at each reading (should be 0).
    contact_found : (n,) bool
        Ground truth: whether MuJoCo reported the tip's contact at the reading (else
        ``true_contact_points_in_world`` holds the nearest mesh point).
    reading_times_s : (n,) float, seconds
        Simulated time of each point's reading.
    """

    plane: SamplingPlane
    points_in_world: NDArray[np.float64]
    normals_in_world: NDArray[np.float64]
    tip_centres_in_world: NDArray[np.float64]
    p_index: int
    sides: tuple[SweepSide, ...]
    true_tip_centres_in_world: NDArray[np.float64]
    true_contact_points_in_world: NDArray[np.float64]
    mesh_points_in_world: NDArray[np.float64]
    stylus_contacts: NDArray[np.int64]
    reading_times_s: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
    contact_found: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def truncated(self) -> bool:
        """Returns True if a side stopped early."""
        return any(side.stop is not StopReason.COMPLETE for side in self.sides)

    @property
    def n_points(self) -> int:
        """Returns the number of sensed points."""
        return len(self.points_in_world)


@dataclass
class Sample:
    """One sensed point: the estimate, the press's slide (sensed), and the ground truth."""

    estimate: ContactEstimate
    slide: NDArray[np.float64]
    true_tip: NDArray[np.float64]
    touched: NDArray[np.float64]
    stylus_contacts: int


def _in_plane(vector: NDArray[np.float64], plane: SamplingPlane) -> NDArray[np.float64] | None:
    """Unit projection of a vector into the plane, None if it is (nearly) normal to it."""
    projected = vector - (vector @ plane.normal_in_world) * plane.normal_in_world
    norm = float(np.linalg.norm(projected))
    return None if norm < 1e-6 else projected / norm


def _rotate_in_plane(
    vector: NDArray[np.float64], plane: SamplingPlane, angle: float
) -> NDArray[np.float64]:
    """Rotates an in-plane vector about the plane normal by ``angle`` radians."""
    n = plane.normal_in_world
    return vector * math.cos(angle) + np.cross(n, vector) * math.sin(angle)


def _signed_angle(a: NDArray[np.float64], b: NDArray[np.float64], plane: SamplingPlane) -> float:
    """Signed angle from in-plane vector a to b about the plane normal."""
    return math.atan2(float(np.cross(a, b) @ plane.normal_in_world), float(a @ b))


class SweepRunner:
    """Runs the touch-probe cycle along sampling planes, one side of p at a time.

    Parameters
    ----------
    rig : Rig
        The arm and its sensor.
    config : ProbingConfig
    spacing_m : float, metres
        Distance between neighbouring points along the curve.
    max_tilt_deg : float or None, degrees
        A side ends where the in-plane normal tilts more than this from the plane's up
        direction; None: no limit (outline traces).
    """

    def __init__(
        self, rig: Rig, config: ProbingConfig, spacing_m: float, max_tilt_deg: float | None
    ) -> None:
        self.rig = rig
        self.config = config
        self.spacing = spacing_m
        self.max_tilt = None if max_tilt_deg is None else math.radians(max_tilt_deg)
        self.highest_z = -math.inf
        self.truth = GroundTruthReader(rig.physics)

    def sample(self, estimate: ContactEstimate) -> Sample:
        """The sample of an estimate just sensed, with the slide of its press and the truth."""
        truth = self.truth.read()
        self.highest_z = max(self.highest_z, float(estimate.tip_centre_in_world[2]))
        slide = estimate.tip_centre_in_world - self.rig.last_touch_centre
        return Sample(
            estimate,
            slide,
            truth.tip_centre_in_world,
            truth.touched_point_in_world,
            truth.stylus_contacts,
        )

    def first(
        self,
        plane: SamplingPlane,
        line_point: NDArray[np.float64],
        clearance: float,
        search: float,
        from_current: bool = False,
    ) -> Sample:
        """Approaches along -up the line through ``line_point`` (where the tip centre
        should touch), from ``clearance`` outside it."""
        start = line_point + clearance * plane.up_in_world
        self.highest_z = max(self.highest_z, float(start[2]))
        if from_current:
            self.travel_to(start)
        else:
            self.rig.teleport(start)
            self.rig.settle(self.config.settle_s)
        estimate = self.rig.approach(start, -plane.up_in_world, clearance + search)
        if estimate is None:
            raise SimulationError(
                f"no surface found within {(clearance + search) * 1e3:.1f} mm of the planned "
                f"point {np.round(plane.origin_in_world, 4).tolist()} m (the tip centre was "
                f"to touch at {np.round(line_point, 4).tolist()} m)"
            )
        return self.sample(estimate)

    def side(
        self, plane: SamplingPlane, history: list[Sample], direction: int, count: int
    ) -> tuple[list[Sample], SweepSide]:
        """Samples up to ``count`` points from the last of ``history`` in ``direction``."""
        config, rig = self.config, self.rig
        samples: list[Sample] = []
        last = history[-1]
        up = _in_plane(last.estimate.normal_in_world, plane)
        if up is None:
            up = plane.up_in_world
        tangent = direction * np.cross(plane.normal_in_world, up)
        turn = 0.0  # change of the normal's direction per point, radians
        if len(history) >= 2:
            previous = _in_plane(history[-2].estimate.normal_in_world, plane)
            if previous is not None:
                turn = _signed_angle(previous, up, plane)
        e = plane.normal_in_world
        radius = rig.sensor.robot.probe.tip_radius_m
        for _ in range(count):
            # Where the last approach line met the surface: the sensed tip centre less the
            # slide of the press (readings before and after it).
            line = last.estimate.tip_centre_in_world - last.slide
            # Predict along the chord: half the expected turn of the tangent.
            chord = _rotate_in_plane(tangent, plane, 0.5 * turn)
            predicted = line + self.spacing * chord
            predicted_up = _rotate_in_plane(up, plane, turn)
            start = predicted + config.standoff_m * predicted_up
            # Aim the approach line off the plane so that the contact lands in it: the tip
            # will slide about as it did last time, and the contact lies a tip radius from
            # the centre along the normal.
            aim = radius * float(last.estimate.normal_in_world @ e) - float(last.slide @ e)
            start = start + (aim - plane.distance(start)) * e
            try:
                rig.move(start, config.move_speed_m_s)
                rig.settle(config.settle_s)
                estimate = rig.approach(start, -predicted_up, config.standoff_m + config.search_m)
            except UnreachablePoint as error:
                return samples, SweepSide(
                    direction, count, len(samples), StopReason.UNREACHABLE, str(error)
                )
            if estimate is None:
                return samples, SweepSide(
                    direction,
                    count,
                    len(samples),
                    StopReason.LOST_CONTACT,
                    f"lost contact after {len(samples)} of {count} points on the "
                    f"{'+' if direction > 0 else '-'} side: no surface within "
                    f"{config.search_m * 1e3:.1f} mm beyond the predicted point (an edge)",
                )
            sample = self.sample(estimate)
            new_up = _in_plane(estimate.normal_in_world, plane)
            if new_up is None:
                new_up = predicted_up
            tilt = _signed_angle(plane.up_in_world, new_up, plane)
            if self.max_tilt is not None and abs(tilt) > self.max_tilt:
                return samples, SweepSide(
                    direction,
                    count,
                    len(samples),
                    StopReason.TOO_STEEP,
                    f"surface too steep after {len(samples)} of {count} points on the "
                    f"{'+' if direction > 0 else '-'} side: normal {math.degrees(tilt):.0f} deg"
                    f" from vertical, limit {math.degrees(self.max_tilt):.0f} deg",
                )
            turn = _signed_angle(up, new_up, plane)
            tangent = _rotate_in_plane(tangent, plane, turn)
            up = new_up
            samples.append(sample)
            last = sample
        return samples, SweepSide(direction, count, len(samples), StopReason.COMPLETE)

    def _travel_height(self) -> float:
        """Height of travel moves: the clearance above the highest point touched so far."""
        return self.highest_z + self.config.clearance_m

    def retreat(self) -> None:
        """Moves straight up from the current point to the travel height."""
        here = self.rig.commanded_tip()
        up = here.copy()
        up[2] = max(self._travel_height(), here[2] + self.config.clearance_m)
        self.rig.move(up, self.config.travel_speed_m_s)

    def travel_to(self, target: NDArray[np.float64]) -> None:
        """Moves at the travel height over ``target``, then down to it, and settles."""
        here = self.rig.commanded_tip()
        height = max(self._travel_height(), here[2], target[2])
        if here[2] < height - 1e-6:
            self.rig.move(np.array([here[0], here[1], height]), self.config.travel_speed_m_s)
        self.rig.move(np.array([target[0], target[1], height]), self.config.travel_speed_m_s)
        self.rig.move(target, self.config.travel_speed_m_s)
        self.rig.settle(self.config.settle_s)


def _touched_or_nearest(
    samples: list[Sample], nearest: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Where MuJoCo's contact met the touched surface at each reading, and whether it did;
    at a reading that caught the stiff contact off for a timestep, the mesh point nearest
    the tip centre."""
    touched = np.array([s.touched for s in samples]).reshape(-1, 3)
    found = np.all(np.isfinite(touched), axis=1)
    touched[~found] = nearest[~found]
    return touched, found


def sweep_result(
    probe_scene: ProbeScene,
    plane: SamplingPlane,
    samples: list[Sample],
    p_index: int,
    sides: Sequence[SweepSide],
    sensor: SensorConfig,
) -> SweepResult:
    """Returns a sweep's result from its samples: the points refined with the sweep's path
    (:func:`tactile_sim.sensor.sweep_contacts`) and the ground truth."""
    centres = np.array([s.estimate.tip_centre_in_world for s in samples])
    points, normals = sweep_contacts(
        centres, np.array([s.estimate.normal_in_world for s in samples]), sensor
    )
    true_tips = np.array([s.true_tip for s in samples])
    nearest, _ = probe_scene.closest_points_in_world(true_tips)
    contacts, found = _touched_or_nearest(samples, nearest)
    return SweepResult(
        plane=plane,
        points_in_world=points,
        normals_in_world=normals,
        tip_centres_in_world=centres,
        p_index=p_index,
        sides=tuple(sides),
        true_tip_centres_in_world=true_tips,
        true_contact_points_in_world=contacts,
        mesh_points_in_world=nearest,
        contact_found=found,
        stylus_contacts=np.array([s.stylus_contacts for s in samples], dtype=np.int64),
        reading_times_s=np.array([s.estimate.reading.time_s for s in samples]),
    )


def run_sweep(
    runner: SweepRunner,
    probe_scene: ProbeScene,
    plane: SamplingPlane,
    line_point: NDArray[np.float64],
    n_points: int,
    first: bool,
) -> SweepResult:
    """Returns one full sweep through p (the plane origin) with p in the middle; the first
    approach comes down the line through ``line_point`` (corrected in place by the first
    sweep)."""
    config = runner.config
    p_sample = runner.first(
        plane,
        line_point,
        config.first_clearance_m,
        config.first_search_m,
        from_current=not first,
    )
    if first:
        # The press slides the tip off the planned point: touch again, the approach line
        # moved by the horizontal miss, so the sensed p lands on the planned one (the
        # later sweeps come down the corrected line directly).
        miss = plane.origin_in_world - p_sample.estimate.point_in_world
        miss[2] = 0.0
        line_point += miss
        runner.retreat()
        p_sample = runner.first(
            plane,
            line_point,
            config.first_clearance_m,
            config.first_search_m,
            from_current=True,
        )
    n_plus = (n_points - 1) // 2
    n_minus = n_points - 1 - n_plus
    plus, plus_side = runner.side(plane, [p_sample], +1, n_plus)
    missing = n_plus - len(plus)
    sides = [plus_side]
    minus: list[Sample] = []
    if n_minus + (missing if config.extend_on_loss else 0) > 0:
        runner.retreat()
        # Back over p, then down to p's approach start for the other side.
        start = p_sample.estimate.tip_centre_in_world + config.standoff_m * plane.up_in_world
        runner.travel_to(start)
        count = n_minus + (missing if config.extend_on_loss else 0)
        minus, minus_side = runner.side(plane, [*plus[:1], p_sample], -1, count)
        sides.append(minus_side)
    samples = [*minus[::-1], p_sample, *plus]
    runner.retreat()
    return sweep_result(probe_scene, plane, samples, len(minus), sides, runner.rig.sensor)
