"""Shared fixtures of the pure-Python suite (no roscore needed), for every folder below, and
the paths its test modules import (``from ..conftest import DATA``)."""

import os
import sys

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
# The pure-Python packages import straight from the source tree, so the unit tests need
# neither a built workspace nor ROS environment variables.
for package in (
    "motion_common",
    "motion_sensor",
    "motion_commander",
    "hw_interface",
    "motion_apps",
    "kitting",
    "dashboard",
):
    path = os.path.join(ROOT, "src", package)
    if path not in sys.path:
        sys.path.insert(0, path)

DATA = os.path.join(ROOT, "tests", "data")
UR5E = os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf")
UR10E = os.path.join(ROOT, "src", "motion_common", "urdf", "ur10e.urdf")
HOME = np.array([0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0])


@pytest.fixture
def rng():
    """Seeded random generator: every run sees the same numbers."""
    return np.random.default_rng(12345)
