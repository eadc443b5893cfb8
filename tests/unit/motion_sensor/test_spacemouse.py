"""SpaceMouse: HID report decoding, rate integration, the reconnecting reader, report logs."""

import struct
import threading

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_sensor.devices.leap_client import Backoff
from motion_sensor.devices.spacemouse import (
    RateConfig,
    RateIntegrator,
    SpaceMouseDecoder,
    SpaceMouseReader,
    SpaceMouseState,
    find_device,
    format_report_line,
    read_report_log,
)
from motion_sensor.errors import MotionSensorError

from ..conftest import ROOT


def report(kind, *values):
    return [kind] + list(struct.pack(f"<{len(values)}h", *values))


def test_decoder_reads_translation_rotation_buttons_and_combined_reports():
    decoder = SpaceMouseDecoder()
    assert decoder.feed(report(1, 10, -20, 350))
    assert decoder.feed(report(2, -1, 2, -300))
    np.testing.assert_array_equal(decoder.state.translation, [10, -20, 350])
    np.testing.assert_array_equal(decoder.state.rotation, [-1, 2, -300])
    assert decoder.feed([3, 0b10, 0])
    assert decoder.state.button(1) and not decoder.state.button(0)
    assert decoder.feed(report(1, 1, 2, 3, 4, 5, 6))  # receivers: one 13-byte report
    np.testing.assert_array_equal(decoder.state.rotation, [4, 5, 6])
    assert not decoder.feed([0x17, 100])  # battery level: not motion


@pytest.mark.parametrize("bad", [[], [1, 0, 0, 0], [2] + [0] * 8, [3], [1] + [0] * 9])
def test_malformed_reports_are_rejected_and_change_nothing(bad):
    decoder = SpaceMouseDecoder()
    decoder.feed(report(1, 5, 6, 7))
    with pytest.raises(MotionSensorError):
        decoder.feed(bad)
    np.testing.assert_array_equal(decoder.state.translation, [5, 6, 7])


def integrate(integrator, state, seconds, rate=100.0, age=0.0):
    t = 0.0
    integrator.update(t, state, age)
    for _ in range(int(seconds * rate)):
        t += 1.0 / rate
        position, orientation = integrator.update(t, state, age)
    return position, orientation


def test_full_push_away_moves_the_virtual_hand_forward_at_max_speed():
    integrator = RateIntegrator()
    start = integrator.position.copy()
    # HID y points toward the user: pushing the cap away reads negative y.
    position, orientation = integrate(integrator, SpaceMouseState(translation=np.array([0.0, -350.0, 0.0])), 1.0)
    np.testing.assert_allclose(position - start, [0.15, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(orientation, [0, 0, 0, 1], atol=1e-12)


def test_dead_zone_and_response_curve():
    integrator = RateIntegrator(RateConfig(deadzone=0.1, response_exponent=2.0, max_speed_mps=0.2))
    small, _ = integrator.rates(SpaceMouseState(translation=np.array([30.0, 0.0, 0.0])), 0.0)
    assert np.all(small == 0)  # 30/350 = 0.086 < 0.1
    half, _ = integrator.rates(SpaceMouseState(translation=np.array([0.0, 0.0, -175.0])), 0.0)  # lift: HID z is down
    np.testing.assert_allclose(half, [0.0, 0.0, 0.2 * ((0.5 - 0.1) / 0.9) ** 2])


def test_a_deflection_the_device_stops_repeating_is_released():
    integrator = RateIntegrator()
    held = SpaceMouseState(translation=np.array([350.0, 0.0, 0.0]))
    start = integrator.position.copy()
    position, _ = integrate(integrator, held, 1.0, age=0.3)  # > hold_timeout_s 0.25
    np.testing.assert_array_equal(position, start)
    assert np.all(integrator.rates(held, float("nan"))[0] == 0)


def test_twist_turns_about_up_and_the_hand_stays_in_its_box():
    integrator = RateIntegrator(RateConfig(max_angular_speed_rps=0.5, workspace_half_size_m=0.1))
    # Twisting the cap counter-clockwise seen from above reads negative HID rz (z points down).
    state = SpaceMouseState(translation=np.array([-350.0, 0.0, 0.0]), rotation=np.array([0.0, 0.0, -350.0]))
    position, orientation = integrate(integrator, state, 2.0)
    yaw = Rotation.from_quat(orientation).as_euler("xyz")[2]
    assert yaw == pytest.approx(1.0, abs=1e-6)
    # Pushing right-to-left (HID -x) is +y in REP 103; the box stops it 0.1 m from start.
    assert position[1] == pytest.approx(0.1)
    assert np.linalg.norm(orientation) == pytest.approx(1.0)


def test_a_long_gap_is_integrated_as_max_step_only():
    integrator = RateIntegrator(RateConfig(max_step_s=0.05))
    state = SpaceMouseState(translation=np.array([0.0, -350.0, 0.0]))
    integrator.update(0.0, state, 0.0)
    position, _ = integrator.update(2.0, state, 0.0)  # the timer stalled for 2 s
    assert position[0] - 0.0 == pytest.approx(0.15 * 0.05)


@pytest.mark.parametrize(
    "field,value",
    [
        ("deadzone", 1.0),
        ("max_speed_mps", 0.0),
        ("hold_timeout_s", float("nan")),
        ("axis_signs", (1, 1, 1, 1, 1, 2)),
        ("start_position_m", (0, 0)),
    ],
)
def test_bad_rate_parameters_are_named(field, value):
    with pytest.raises(MotionSensorError, match=field):
        RateIntegrator(RateConfig(**{field: value}))


class FakeHidDevice:
    """hidapi's device: replays queued reports, then raises OSError like an unplug."""

    def __init__(self, owner):
        self.owner = owner

    def open(self, vendor, product):
        self.owner.opened.append((vendor, product))

    def read(self, size, timeout_ms):
        if self.owner.queue:
            item = self.owner.queue.pop(0)
            if isinstance(item, Exception):
                raise item
            return item
        self.owner.reader.stop()
        return []

    def close(self):
        self.owner.closed += 1


class FakeHid:
    def __init__(self, devices, queue):
        self.devices, self.queue, self.opened, self.closed, self.reader = devices, queue, [], 0, None

    def enumerate(self):
        return self.devices

    def device(self):
        return FakeHidDevice(self)


def test_reader_reconnects_after_an_unplug_and_closes_the_device():
    hid = FakeHid(
        [{"vendor_id": 0x256F, "product_id": 0xC635, "product_string": "x"}],
        [report(1, 1, 2, 3), OSError("read error"), report(1, 4, 5, 6)],
    )
    got, problems, connects = [], [], []
    reader = SpaceMouseReader(
        lambda r, t: got.append(r),
        problems.append,
        hid_module=hid,
        backoff=Backoff(initial=0.001, maximum=0.001),
        clock=lambda: 1.0,
        on_connect=connects.append,
    )
    hid.reader = reader
    thread = threading.Thread(target=reader.run)
    thread.start()
    thread.join(5.0)
    assert not thread.is_alive()
    assert got == [report(1, 1, 2, 3), report(1, 4, 5, 6)]
    assert len(problems) == 1 and "read error" in problems[0]
    assert connects == ["SpaceMouse Compact"] * 2 and hid.closed == 2
    assert reader.counters["connections"] == 2 and reader.counters["connection_errors"] == 1


def test_find_device_knows_models_and_honours_explicit_ids():
    devices = [
        {"vendor_id": 0x1234, "product_id": 0x1, "product_string": "keyboard"},
        {"vendor_id": 0x046D, "product_id": 0xC626, "product_string": "3Dconnexion SpaceNavigator"},
    ]
    hid = FakeHid(devices, [])
    assert find_device(hid) == (0x046D, 0xC626, "SpaceNavigator")
    assert find_device(hid, 0x1234, 0x1) == (0x1234, 0x1, "keyboard")
    assert find_device(FakeHid(devices[:1], [])) is None


def test_report_log_round_trip_and_errors(tmp_path):
    path = tmp_path / "log.txt"
    path.write_text("# a comment\n" + format_report_line(0.0, report(1, 1, 2, 3)) + format_report_line(0.01, [3, 1, 0]))
    rows = read_report_log(str(path))
    assert rows == [(0.0, bytes(report(1, 1, 2, 3))), (0.01, bytes([3, 1, 0]))]
    path.write_text("0.0 0102\n0.1 zz\n")
    with pytest.raises(MotionSensorError, match=":2:"):
        read_report_log(str(path))
    path.write_text("0.2 0102\n0.1 0102\n")
    with pytest.raises(MotionSensorError, match="backwards"):
        read_report_log(str(path))


def test_unknown_hid_backend_is_named():
    with pytest.raises(MotionSensorError, match="bluetooth"):
        SpaceMouseReader(lambda r, t: None, backend="bluetooth")


def test_committed_report_log_is_what_its_generator_writes(tmp_path):
    """tests/data/spacemouse_push_forward.hidlog is synthetic; keep it reproducible."""
    import os
    import subprocess
    import sys

    tests = os.path.join(ROOT, "tests")
    fresh = tmp_path / "log.hidlog"
    subprocess.run(
        [sys.executable, os.path.join(tests, "tools", "make_spacemouse_log.py"), str(fresh)],
        check=True,
        capture_output=True,
    )
    with open(os.path.join(tests, "data", "spacemouse_push_forward.hidlog"), encoding="utf-8") as fh:
        assert fh.read() == fresh.read_text()
    rows = read_report_log(str(fresh))
    assert rows[0][0] == 0.0 and rows[-1][0] == pytest.approx(5.5)
