"""Fixtures of the probing tests: a sphere on the object mount."""

from __future__ import annotations

import numpy as np
import pytest

from recognition.rigid import pose_matrix
from tactile_sim.probing import ProbeScene, build_probe_scene
from tactile_sim.probing.placement import MOUNT_IN_WORLD

AT_MOUNT = pose_matrix(np.eye(3), MOUNT_IN_WORLD)
"""T_world_from_object: upright on the object mount, axes parallel to the world's."""


@pytest.fixture(scope="package")
def sphere_scene() -> ProbeScene:
    return build_probe_scene("sphere", AT_MOUNT, progress=False)
