"""Placing an object: resolving names, random poses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_sim.errors import UnknownObject
from tactile_sim.probing import probe_object, random_pose


def test_random_pose_is_upright_and_near_the_mount() -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        T = random_pose(rng)
        np.testing.assert_allclose(T[:3, 2], [0.0, 0.0, 1.0], atol=1e-12)
        assert T[2, 3] == 0.0
        assert np.hypot(T[0, 3] - 0.40, T[1, 3]) <= 0.02 + 1e-12


def test_random_pose_turns_by_the_drawn_yaw_exactly() -> None:
    for seed in range(50):
        T = random_pose(np.random.default_rng(seed))
        yaw = np.random.default_rng(seed).uniform(-math.pi, math.pi)
        c, s = math.cos(yaw), math.sin(yaw)
        assert np.array_equal(T[:3, :3], [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_unknown_object_lists_catalog_and_solids() -> None:
    with pytest.raises(UnknownObject, match=r"known objects: pear.*elephant.*sphere"):
        probe_object("teapot", seed=0)
