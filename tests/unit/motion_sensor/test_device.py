"""The hand-device base class and its ROS-free runner, on a fake clock (no real sleeping)."""

import numpy as np
import pytest

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import (
    Backoff,
    DeviceRunner,
    HandDevice,
    empty_sample,
    reconnect_loop,
    sample_problem,
    wait_until_ready,
)
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError
from motion_sensor.hand_sample import HandSample


class FakeClock:
    """time and sleep in one: sleeping advances the time, instantly."""

    def __init__(self, start=100.0):
        self.now = start
        self.sleeps = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now += seconds


def good(stamp):
    return HandSample(stamp=stamp, position=np.array([0.1, 0.2, 0.3]), orientation=np.array([0.0, 0.0, 0.0, 1.0]))


class FakeDevice(HandDevice):
    """Scripted: ``opens`` says what each open does (None = works, an exception = raised),
    ``script`` what each read returns or raises."""

    name = "fake"
    params = ParamSchema([Param("gain", 1.0, low=0)])

    def __init__(self, opens=(), script=(), **kw):
        super().__init__({}, **kw)
        self.opens, self.script = list(opens), list(script)
        self.closed = 0

    def open(self):
        outcome = self.opens.pop(0) if self.opens else None
        if outcome is not None:
            raise outcome

    def read(self, now):
        item = self.script.pop(0) if self.script else EndOfStream()
        if isinstance(item, BaseException):
            raise item
        return item(now) if callable(item) else item

    def close(self):
        self.closed += 1


def run(device, clock, **kw):
    published, bools = [], []
    runner = DeviceRunner(
        device,
        published.append,
        lambda: False,
        clock=clock,
        sleep=clock.sleep,
        publish_bool=lambda k, v: bools.append((k, v)),
        **kw,
    )
    return runner, runner.run(), published, bools


def test_reconnects_with_exponential_backoff_on_the_injected_clock():
    clock = FakeClock()
    refused = DeviceUnavailable("refused")
    device = FakeDevice(
        opens=[refused, OSError("unplugged"), refused, None, None],
        script=[good, DeviceUnavailable("dropped"), good, good],
        clock=clock,
        sleep=clock.sleep,
    )
    runner, finished, published, _ = run(device, clock, backoff=Backoff(0.5, 2.0, 1.5))
    assert finished and len(published) == 3
    # three refusals: 0.5, 1, 1.5 (capped); the drop after a good connection starts again at 0.5
    assert clock.sleeps == [0.5, 1.0, 1.5, 0.5]
    assert device.counters["connections"] == 2 and device.counters["connection_errors"] == 4
    assert device.closed == 2 and not device.connected
    assert "dropped" in runner.last_problem


def test_bad_samples_are_dropped_and_counted_empty_frames_pass():
    clock = FakeClock()
    nan = good(1.0)
    nan.position = np.array([np.nan, 0, 0])
    scaled = good(1.0)
    scaled.orientation = np.array([0, 0, 0, 2.0])
    mismatch = good(1.0)
    mismatch.hands_num = 2
    device = FakeDevice(
        script=[good, nan, scaled, mismatch, None, empty_sample(5.0, "f")], clock=clock, sleep=clock.sleep
    )
    warnings = []
    device.warn = warnings.append
    _, _, published, _ = run(device, clock)
    assert len(published) == 2 and published[1].hands_num == 0
    assert device.counters["invalid_samples"] == 3 and device.counters["published"] == 2
    assert any("unit quaternion" in w for w in warnings) and any("finite" in w for w in warnings)


def test_sample_problem_names_the_fault():
    assert sample_problem(good(1.0)) is None
    assert "hands_num" in sample_problem(HandSample(1.0, np.zeros(3), np.zeros(4), hands_num=1, hand_types=()))
    assert sample_problem(empty_sample(1.0, "leap")) is None


def test_polled_device_is_read_at_its_rate():
    clock = FakeClock(0.0)
    device = FakeDevice(script=[good] * 5, clock=clock, sleep=clock.sleep)
    device.rate_hz = 50.0
    times = []
    device.read = (lambda read: lambda now: times.append(now) or read(now))(device.read)
    run(device, clock)
    np.testing.assert_allclose(np.diff(times), 0.02)


def test_emitted_values_reach_their_topic_and_fatal_errors_propagate():
    clock = FakeClock()
    device = FakeDevice(script=[lambda now: device.emit("engage", True) or good(now)], clock=clock, sleep=clock.sleep)
    _, _, published, bools = run(device, clock)
    assert bools == [("engage", True)] and len(published) == 1
    broken = FakeDevice(opens=[MotionSensorError("unusable file")], clock=clock, sleep=clock.sleep)
    with pytest.raises(MotionSensorError, match="unusable"):
        run(broken, clock)


def test_stop_ends_the_run_without_finishing():
    clock = FakeClock()
    device = FakeDevice(script=[good] * 100, clock=clock, sleep=clock.sleep)
    published = []
    runner = DeviceRunner(device, published.append, lambda: len(published) >= 3, clock=clock, sleep=clock.sleep)
    assert runner.run() is False and len(published) == 3 and device.closed == 1


def test_reconnect_loop_returns_when_stopped():
    calls, waits = [], []
    stop = []

    def session():
        calls.append(1)
        if len(calls) == 3:
            stop.append(1)
        raise OSError("no")

    reconnect_loop(session, lambda: bool(stop), Backoff(0.1, 3.0, 1.0), waits.append, lambda exc, d: None)
    assert len(calls) == 3 and waits == pytest.approx([0.1, 0.3])


def test_wait_until_ready_logs_what_it_waits_for():
    clock = FakeClock(0.0)
    state = {"ready": False, "subscribers": 0}
    logs = []

    def sleep(seconds):
        clock.sleep(seconds)
        if clock.now > 3.0:
            state["subscribers"] = 1
        if clock.now > 12.0:
            state["ready"] = True

    ok = wait_until_ready(
        [("True on /ready", lambda: state["ready"]), ("1 subscriber(s)", lambda: state["subscribers"] >= 1)],
        lambda: False,
        clock,
        sleep,
        logs.append,
        poll_s=0.1,
        log_every_s=5.0,
    )
    assert ok and 12.0 < clock.now < 12.2
    assert len(logs) == 3 and "/ready" in logs[0] and "subscriber" in logs[0] and "subscriber" not in logs[-1]
    assert wait_until_ready([("never", lambda: False)], lambda: True, clock, sleep, logs.append) is False
