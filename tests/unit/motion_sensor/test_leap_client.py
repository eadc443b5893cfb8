"""The Leap WebSocket client against a local Leap v6 replay server on loopback."""

import os
import socket
import threading
import time

import numpy as np
import pytest

from motion_sensor.devices.leap_client import FOCUSED, Backoff, ClockMapper, LeapClient
from motion_sensor.devices.leap_server import Faults, LeapReplayServer
from motion_sensor.errors import MotionSensorError

from ..conftest import DATA

RECORDING = os.path.join(DATA, "wave.jsonl.gz")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def collect(port, until, timeout=15.0, **kw):
    frames, problems = [], []
    client = LeapClient(
        "127.0.0.1",
        port,
        on_frame=lambda f, t: frames.append((f, t)),
        on_problem=problems.append,
        backoff=Backoff(0.05, 2.0, 0.2),
        **kw,
    )
    thread = threading.Thread(target=client.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout
    while not until(frames, client) and time.monotonic() < deadline:
        time.sleep(0.01)
    client.stop()
    thread.join(timeout=5)
    return client, frames, problems


def test_backoff_and_clock_mapping():
    backoff = Backoff(0.1, 2.0, 0.5)
    assert [backoff.next() for _ in range(5)] == [0.1, 0.2, 0.4, 0.5, 0.5]
    backoff.reset()
    assert backoff.next() == 0.1
    clock = ClockMapper()
    assert clock.to_local(1.0, 101.02) == pytest.approx(101.02)
    assert clock.to_local(1.01, 101.011) == pytest.approx(101.011)  # a faster frame tightens the offset
    assert clock.to_local(1.02, 101.05) == pytest.approx(101.021)
    with pytest.raises(MotionSensorError):
        LeapClient(port=70000)


def test_handshake_and_frames_at_recorded_timing():
    port = free_port()
    server = LeapReplayServer(RECORDING, port=port).start()
    try:
        client, frames, problems = collect(port, lambda f, c: len(f) >= len(server.frames))
    finally:
        server.shutdown()
    assert server.received[:1] == [FOCUSED]  # the exact string, no spaces
    assert len(frames) == len(server.frames) and client.counters["rejected"] == 0
    device = np.array([f.timestamp for f, _ in frames])
    received = np.array([t for _, t in frames])
    # Recorded timing: arrival spacing follows the device clock (within scheduling noise).
    assert abs((received[-1] - received[0]) - (device[-1] - device[0])) < 0.15


def test_bad_messages_are_counted_and_the_stream_goes_on():
    port = free_port()
    faults = Faults(malformed=[5], truncated=[10], oversized=[15], nan=[20])
    server = LeapReplayServer(RECORDING, port=port, rate=0, faults=faults).start()
    try:
        client, frames, problems = collect(port, lambda f, c: server.done.is_set() and len(f) >= len(server.frames) - 4)
    finally:
        server.shutdown()
    assert client.counters["rejected"] == 4 and len(frames) == len(server.frames) - 4
    assert any("exceeds" in p for p in problems) and any("not finite" in p for p in problems)


def wait_for(condition, timeout=10.0):
    """Poll ``condition`` until it holds or ``timeout`` s pass (a deadline, not a measurement)."""
    deadline = time.monotonic() + timeout
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.01)
    return condition()


def test_reconnects_with_backoff_after_a_drop():
    port = free_port()
    problems, frames, waits = [], [], []
    allowed = threading.Semaphore(0)  # the injected wait: returns at once, as often as the test allows

    def wait(seconds):
        waits.append(seconds)
        allowed.acquire(timeout=10)

    client = LeapClient(
        "127.0.0.1",
        port,
        on_frame=lambda f, t: frames.append(f),
        on_problem=problems.append,
        backoff=Backoff(0.05, 2.0, 0.2),
        wait=wait,
    )
    thread = threading.Thread(target=client.run, daemon=True)
    thread.start()
    for attempt in range(3):  # nobody listening yet: refused, retried with growing delays
        assert wait_for(lambda attempt=attempt: len(waits) > attempt)
        allowed.release()
    assert wait_for(lambda: len(waits) == 4)
    assert waits == [0.05, 0.1, 0.2, 0.2] and client.counters["disconnects"] == 4
    server = LeapReplayServer(RECORDING, port=port, rate=0).start()  # serves one pass, then closes
    allowed.release()
    assert wait_for(lambda: client.counters["connections"] >= 1 and len(waits) >= 5)
    assert waits[4] == 0.05  # a good connection reset the backoff
    allowed.release()
    assert wait_for(lambda: client.counters["connections"] >= 2)  # came back after the server closed the socket
    client.stop()
    for _ in range(3):
        allowed.release()
    thread.join(timeout=5)
    server.shutdown()
    assert not thread.is_alive() and len(frames) >= len(server.frames)
    assert all("retrying" in p for p in problems[:4])


def test_clock_mapper_restarts_with_the_device_clock():
    clock = ClockMapper()
    clock.to_local(50.0, 1000.0)
    assert clock.to_local(1.0, 1001.0) == pytest.approx(1001.0)  # device clock went back: re-synced


def test_dropout_loses_frames_like_a_real_link():
    server = LeapReplayServer(RECORDING, port=free_port(), faults=Faults(dropout_at=20, dropout_s=0.1))
    lost = [i for i in range(len(server.frames)) if server._lost(i)]
    assert lost[0] == 20 and 8 <= len(lost) <= 13  # about 0.1 s of frames at ~110 fps
