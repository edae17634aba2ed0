"""Trajectory capture during a session: off by default, sampled every few steps."""

from __future__ import annotations

import numpy as np
import pytest

from tactile_sim.probing import ProbeSession, probe_object


@pytest.fixture(scope="module")
def session() -> ProbeSession:
    return probe_object("sphere", seed=3, n_points=7, trajectory_hz=200.0, progress=False)


def test_capture_is_off_by_default_and_does_not_change_the_session(session: ProbeSession) -> None:
    plain = probe_object("sphere", seed=3, n_points=7, progress=False)
    assert plain.trajectory is None
    assert plain.sim_seconds == session.sim_seconds
    for a, b in zip(plain.curves.curves, session.curves.curves, strict=True):
        np.testing.assert_array_equal(a, b)


def test_trajectory_samples_every_few_steps_and_passes_through_the_readings(
    session: ProbeSession,
) -> None:
    trajectory = session.trajectory
    every = 5  # 200 Hz at the 1 ms timestep
    total_steps = round(session.sim_seconds / trajectory.timestep_s)
    assert len(trajectory) == total_steps // every + 1
    np.testing.assert_array_equal(trajectory.steps, every * np.arange(len(trajectory)))
    b = len(trajectory.body_names)
    assert {"inner_link", "joystick_probe/tip"} <= set(trajectory.body_names)
    assert trajectory.body_positions_in_world.shape == (len(trajectory), b, 3)
    norms = np.linalg.norm(trajectory.body_quats_wxyz_in_world, axis=-1)
    np.testing.assert_allclose(norms, 1.0, atol=1e-9)
    assert "base" in trajectory.static_body_names
    # The tip passes (within the distance covered between two samples) through every
    # true tip centre at a reading.
    for sweep in session.sweeps:
        gaps = np.linalg.norm(
            sweep.true_tip_centres_in_world[:, None] - trajectory.tip_centres_in_world[None],
            axis=-1,
        ).min(axis=1)
        assert gaps.max() < 0.2e-3
        assert np.all(np.diff(np.sort(sweep.reading_times_s)) > 0)
    assert trajectory.deflection_magnitude_rad.max() > 1e-3  # the presses tilt the stylus
    assert trajectory.tip_force_n[:, 2].max() > 0.01  # and load it axially
