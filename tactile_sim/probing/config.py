"""The sweep controller's set points, speeds and limits."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "ProbingConfig",
]


@dataclass(frozen=True)
class ProbingConfig:
    """The sweep controller's set points, speeds and limits.

    Attributes
    ----------
    approach_speed_m_s : float, m/s
        Speed of the guarded approach towards the surface, until the first touch.
    press_speed_m_s : float, m/s
        Speed of the press after the first touch, until the set point.
    move_speed_m_s : float, m/s
        Peak speed of the short moves between points.
    travel_speed_m_s : float, m/s
        Peak speed of the travel moves between sweep sides and sweeps.
    standoff_m : float, metres
        The approach starts this far outside the predicted surface.
    search_m : float, metres
        The approach gives up (lost contact) this far beyond the predicted surface.
    first_clearance_m, first_search_m : float, metres
        The same for the first point of a sweep, where the surface is known only from
        the experimenter's plan (p on the model).
    clearance_m : float, metres
        Height above the highest point touched so far for travel moves.
    touch_deflection_rad, touch_axial_force_n : float, radians, newtons
        First-touch thresholds of the approach (well above the noise).
    touch_settle_s : float, seconds
        Pause between the first touch and the press.
    backoff_m : float, metres
        The arm backs off this far from the touch (where its momentum carried it) before
        the press.
    press_travel_m : float, metres
        Longest press beyond the first touch.
    press_persist_steps : int
        The set point must hold for this many consecutive timesteps (an impact spike
        of the axial force on a slope does not count).
    press_retries : int
        Presses that still end below the sensor's ``min_normal_force_n`` continue this
        many times, each at a lower speed.
    deflection_trigger_rad : float, radians
        Deflection set point of the press: the stylus tilts this much (0.002 rad moves
        the tip 0.24 mm; a lateral force of 5 mN).
    axial_force_trigger_n : float, newtons
        Axial force set point of the press (a level surface does not tilt the stylus;
        0.1 N sinks the tip about 1 um into the surface).
    settle_s : float, seconds
        Wait after a move before an approach (the stylus swings when the arm accelerates).
    dwell_s : float, seconds
        Wait between the trigger and the reading.
    reading_average_s : float, seconds
        A reading is the mean of the sensor's samples (one per timestep) over this time.
    axial_average_steps : int
        The axial-force thresholds apply to the mean of this many samples (the stiff tip
        contact may switch on and off from one timestep to the next).
    ramp_s : float, seconds
        The approach reaches its speed over this time (a jerk tilts the stylus).
    max_tilt_deg : float, degrees
        A side of a vertical sweep ends where the in-plane normal tilts more than this
        from vertical (the stylus would touch with its shaft).
    extend_on_loss : bool
        When one side of p is truncated, sample the missing points on the other side.
    max_replans : int
        When p was chosen automatically and a sweep still ends with fewer than five
        points, choose another p, at most this many times.
    tool_yaw_rad : float, radians
        Yaw of the flange (and of the deflection axes) during probing.
    """

    approach_speed_m_s: float = 0.006
    press_speed_m_s: float = 0.002
    move_speed_m_s: float = 0.04
    travel_speed_m_s: float = 0.05
    standoff_m: float = 0.3e-3
    search_m: float = 1.5e-3
    first_clearance_m: float = 1.5e-3
    first_search_m: float = 3.0e-3
    clearance_m: float = 3.0e-3
    touch_deflection_rad: float = 5e-4
    touch_axial_force_n: float = 0.01
    touch_settle_s: float = 0.03
    backoff_m: float = 20e-6
    press_travel_m: float = 0.6e-3
    press_persist_steps: int = 4
    press_retries: int = 2
    deflection_trigger_rad: float = 2e-3
    axial_force_trigger_n: float = 0.1
    settle_s: float = 0.03
    dwell_s: float = 0.03
    reading_average_s: float = 0.01
    axial_average_steps: int = 8
    ramp_s: float = 0.01
    max_tilt_deg: float = 75.0
    extend_on_loss: bool = True
    max_replans: int = 3
    tool_yaw_rad: float = 0.0
