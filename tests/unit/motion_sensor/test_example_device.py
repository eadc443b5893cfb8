"""The worked device example (examples/circle_device.py) streams through the shared device
runner: still, then circles of the stated radius, then out of view, then the end; and the
generic device_node loads it by module:Class."""

import os
import sys

import numpy as np
import pytest

from motion_sensor.devices.device import DeviceRunner
from motion_sensor.devices.device_loader import device_class
from motion_sensor.errors import MotionSensorError

from ..conftest import ROOT
from .test_device import FakeClock

sys.path.insert(0, os.path.join(ROOT, "examples"))
from circle_device import CircleDevice  # noqa: E402


def test_circles_then_leaves_then_ends():
    clock = FakeClock(0.0)
    config = CircleDevice.params.validate({"radius_m": 0.05, "period_s": 1.0, "turns": 2, "hold_s": 0.5}, "test")
    device = CircleDevice(config, clock=clock, sleep=clock.sleep)
    published = []
    finished = DeviceRunner(device, published.append, lambda: False, clock=clock, sleep=clock.sleep).run()
    assert finished
    hands = [s for s in published if s.hands_num]
    assert 240 <= len(hands) <= 260 and published[-1].hands_num == 0  # 2.5 s at 100 Hz, then gone
    positions = np.array([s.position for s in hands])
    centre = np.array([-0.05, 0.0, 0.2])
    moving = positions[60:]
    assert np.allclose(np.linalg.norm(moving - centre, axis=1), 0.05, atol=1e-9)
    assert np.ptp(positions[:45], axis=0).max() == 0.0  # still while the clutch engages


def test_device_node_loads_a_class_by_name_and_refuses_others():
    assert device_class("circle_device:CircleDevice") is CircleDevice
    for spec, reason in [("circle_device", "module:Class"), ("nope:X", "PYTHONPATH"), ("numpy:ndarray", "HandDevice")]:
        with pytest.raises(MotionSensorError, match=reason):
            device_class(spec)
