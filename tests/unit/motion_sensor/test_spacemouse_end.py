"""A SpaceMouse report log ends the stream like any recording, with the clutch released; a
missing device stops the node after device_wait_s with the udev rule in the message."""

import pytest

from motion_sensor.devices.spacemouse import LOG_TAIL_S, SpaceMouseDevice
from motion_sensor.errors import MotionSensorError

from .test_device import FakeClock
from .test_device_ports import HIDLOG, config, run


def test_a_report_log_ends_the_stream_with_the_clutch_open():
    clock = FakeClock(10.0)
    device = SpaceMouseDevice(config(SpaceMouseDevice, report_log=HIDLOG), clock=clock, sleep=clock.sleep)
    finished, published, bools = run(device, clock, lambda p: clock.now > 10.0 + 60.0)
    assert finished and clock.now < 10.0 + 10.0
    assert bools[-1] == ("engage", False)
    last_report = 10.0 + device._rows[-1][0] - device._rows[0][0]
    assert published[-1].stamp - last_report == pytest.approx(0.25 + LOG_TAIL_S, abs=0.02)


class NoHid:
    def enumerate(self):
        return []


def test_no_device_stops_after_the_wait_with_the_udev_hint():
    clock = FakeClock(0.0)
    device = SpaceMouseDevice(
        config(SpaceMouseDevice, device_wait_s=10.0), hid_module=NoHid(), clock=clock, sleep=clock.sleep
    )
    with pytest.raises(MotionSensorError, match=r"no SpaceMouse found in 1\d s .*udev rule.*device_wait_s:=0"):
        run(device, clock)
    assert clock.now < 20.0


def test_device_wait_zero_waits_for_ever():
    clock = FakeClock(0.0)
    device = SpaceMouseDevice(
        config(SpaceMouseDevice, device_wait_s=0.0), hid_module=NoHid(), clock=clock, sleep=clock.sleep
    )
    finished, published, _ = run(device, clock, lambda p: clock.now > 120.0)
    assert not finished and not published and device.counters["connection_errors"] > 20
