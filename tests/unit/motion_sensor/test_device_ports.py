"""The three devices ported onto HandDevice (replay, SpaceMouse, Leap), run by the
DeviceRunner on a fake clock wherever timing matters (no real sleeping)."""

import os
import socket
import struct

import numpy as np
import pytest

from motion_common.errors import ParameterError
from motion_sensor.devices.device import Backoff, DeviceRunner
from motion_sensor.devices.leap_client import LeapDevice
from motion_sensor.devices.leap_server import Faults, LeapReplayServer
from motion_sensor.devices.leap_v6 import read_recording
from motion_sensor.devices.replay import ReplayDevice
from motion_sensor.devices.spacemouse import SpaceMouseDevice
from motion_sensor.errors import MotionSensorError

from ..conftest import DATA, ROOT
from .test_device import FakeClock

WAVE = os.path.join(DATA, "wave.jsonl.gz")
HIDLOG = os.path.join(DATA, "spacemouse_push_forward.hidlog")


def config(device_cls, **values):
    return device_cls.params.validate(values, "test")


def run(device, clock, stopped=lambda published: False):
    published, bools = [], []
    runner = DeviceRunner(
        device,
        published.append,
        lambda: stopped(published),
        clock=clock,
        sleep=clock.sleep,
        publish_bool=lambda key, value: bools.append((key, value)),
    )
    return runner.run(), published, bools


def test_replay_plays_at_recorded_timing_stamped_when_published():
    clock = FakeClock(1000.0)
    device = ReplayDevice(config(ReplayDevice, recording=WAVE), clock=clock, sleep=clock.sleep)
    finished, published, _ = run(device, clock)
    frames = read_recording(WAVE).frames
    assert finished and len(published) == len(frames) and device.counters["frames"] == len(frames)
    stamps = np.array([s.stamp for s in published])
    np.testing.assert_allclose(stamps - stamps[0], [f.timestamp - frames[0].timestamp for f in frames], atol=1e-9)
    assert stamps[0] == 1000.0 and published[0].frame_id == "leap"


def test_replay_rate_offset_and_loop():
    clock = FakeClock(0.0)
    frames = read_recording(WAVE).frames
    duration = frames[-1].timestamp - frames[0].timestamp
    fast = ReplayDevice(
        config(ReplayDevice, recording=WAVE, rate=2.0, start_offset=0.5), clock=clock, sleep=clock.sleep
    )
    _, published, _ = run(fast, clock)
    assert len(published) < len(frames)
    assert published[-1].stamp - published[0].stamp == pytest.approx((duration - 0.5) / 2, abs=0.02)
    looped = ReplayDevice(config(ReplayDevice, recording=WAVE, loop=True, rate=0.0), clock=clock, sleep=clock.sleep)
    finished, published, _ = run(looped, clock, lambda p: len(p) >= 2 * len(frames) + 5)
    assert not finished and looped.counters["loops"] == 2


def test_replay_csv_and_unusable_files(tmp_path):
    path = tmp_path / "hand.csv"
    path.write_text(
        "stamp,x,y,z,qx,qy,qz,qw,hand_type\n1.0,0,0,0.2,0,0,0,1,right\n1.1,0,0,0.21,0,0,0,1,\n1.2,x,0,0,0,0,0,1,right\n"
    )
    clock = FakeClock()
    device = ReplayDevice(config(ReplayDevice, recording=str(path)), clock=clock, sleep=clock.sleep)
    _, published, _ = run(device, clock)
    assert [s.hands_num for s in published] == [1, 0] and device.counters["rejected"] == 1
    with pytest.raises(MotionSensorError, match="recording"):
        ReplayDevice(config(ReplayDevice))
    with pytest.raises(MotionSensorError, match="missing"):
        ReplayDevice(config(ReplayDevice, recording=str(tmp_path / "missing.jsonl.gz")))
    with pytest.raises(ParameterError, match="rate"):
        config(ReplayDevice, recording=WAVE, rate=-1.0)


def test_spacemouse_report_log_drives_the_virtual_hand_and_the_clutch():
    clock = FakeClock(50.0)
    device = SpaceMouseDevice(config(SpaceMouseDevice, report_log=HIDLOG), clock=clock, sleep=clock.sleep)
    _, published, bools = run(device, clock, lambda p: clock.now > 50.0 + 6.0)
    assert bools == [("engage", False), ("engage", True), ("engage", False)]
    assert device.counters["rejected"] == 1 and device.counters["ignored"] == 1
    assert 550 < len(published) < 650  # 100 Hz over the log's 5.5 s and a bit
    moved = published[-1].position - published[0].position
    # pushed fully away for 1.5 s at 0.15 m/s, minus the one dropped report's repeat
    assert moved[0] == pytest.approx(0.225, abs=0.01) and abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-9
    assert published[0].frame_id == "spacemouse" and published[0].hand_types == ("right",)


def report(kind, *values):
    return [kind] + list(struct.pack(f"<{len(values)}h", *values))


class FakeHid:
    """hidapi: one SpaceMouse Compact whose reads come from a queue; an exception = unplug."""

    def __init__(self, queue):
        self.queue, self.opened, self.closed = queue, 0, 0

    def enumerate(self):
        return [{"vendor_id": 0x256F, "product_id": 0xC635, "product_string": "x"}]

    def device(self):
        hid = self

        class Device:
            def open(self, vendor, product):
                hid.opened += 1

            def read(self, size, timeout_ms):
                item = hid.queue.pop(0) if hid.queue else []
                if isinstance(item, Exception):
                    raise item
                return item

            def close(self):
                hid.closed += 1

        return Device()


def test_spacemouse_hid_unplug_reconnects_with_backoff():
    clock = FakeClock()
    hid = FakeHid([report(1, 0, -350, 0), [3, 1], [], OSError("unplugged"), report(1, 0, 0, 0)])
    device = SpaceMouseDevice(config(SpaceMouseDevice), hid_module=hid, clock=clock, sleep=clock.sleep)
    _, published, bools = run(device, clock, lambda p: len(p) >= 10)
    assert hid.opened == 2 and hid.closed == 2  # closed at the unplug and at the stop
    assert device.counters["connections"] == 2 and device.counters["connection_errors"] == 1
    # state at the first report, the press, and released again by the re-plugged device
    assert bools == [("engage", False), ("engage", True), ("engage", False)]
    assert device.describe() == "SpaceMouse Compact"


def test_spacemouse_parameters_are_checked():
    with pytest.raises(MotionSensorError, match="axis_signs"):
        SpaceMouseDevice(config(SpaceMouseDevice, report_log=HIDLOG, axis_signs=[1, 1, 0, 1, 1, 1]))
    with pytest.raises(ParameterError, match="hid_backend"):
        config(SpaceMouseDevice, hid_backend="usb")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_leap_device_streams_a_service_and_counts_bad_messages():
    port = free_port()
    server = LeapReplayServer(WAVE, port=port, rate=0, faults=Faults(malformed=[5], nan=[20])).start()
    try:
        device = LeapDevice(config(LeapDevice, port=port))
        published = []
        runner = DeviceRunner(
            device, published.append, lambda: len(published) >= len(server.frames) - 2, backoff=Backoff(0.01, 2.0, 0.05)
        )
        runner.run()
    finally:
        device.stop()
        server.shutdown()
    assert len(published) == len(server.frames) - 2 and device.counters["rejected"] == 2
    assert device.counters["connections"] == 1 and all(s.frame_id == "leap" for s in published)
    assert np.all(np.diff([s.stamp for s in published]) >= 0)
    with pytest.raises(ParameterError, match="port"):
        config(LeapDevice, port=70000)


def test_device_executables_are_three_lines():
    for node in ("leap_driver", "spacemouse_driver", "hand_replay"):
        with open(os.path.join(ROOT, "src", "motion_sensor", "nodes", node), encoding="utf-8") as fh:
            code = [line for line in fh.read().split('"""')[-1].splitlines() if line.strip()]
        assert len(code) <= 5 and any("run_device_node" in line for line in code), node


def test_replay_repeat_plays_passes_with_a_hand_absent_pause_then_finishes():
    clock = FakeClock(1000.0)
    frames = read_recording(WAVE).frames
    duration = frames[-1].timestamp - frames[0].timestamp
    device = ReplayDevice(
        config(ReplayDevice, recording=WAVE, repeat=3, repeat_pause=0.5), clock=clock, sleep=clock.sleep
    )
    finished, published, _ = run(device, clock)
    assert finished and len(published) == 3 * len(frames) and device.counters["passes"] == 2
    stamps = np.array([s.stamp for s in published])
    # Each new pass starts after the pause, with no frame in between: the sequencer sees the
    # hand leave (a gap longer than its hand_lost_s) and enter again.
    gaps = np.diff(stamps)
    starts = np.flatnonzero(gaps > 0.4)
    assert list(starts) == [len(frames) - 1, 2 * len(frames) - 1]
    assert gaps[starts] == pytest.approx([0.5, 0.5], abs=0.02)
    assert stamps[-1] - stamps[0] == pytest.approx(3 * duration + 1.0, abs=0.05)


def test_replay_is_stamped_on_publish_and_live_devices_are_not():
    # A recording has no reception time: the node stamps it as it publishes it. A live
    # device keeps the stamp of the moment its frame arrived.
    assert ReplayDevice.stamp_on_publish is True
    assert LeapDevice.stamp_on_publish is False and SpaceMouseDevice.stamp_on_publish is False
