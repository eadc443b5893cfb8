"""Leap Motion WebSocket client (protocol v6), without ROS.

The Leap service listens on ws://127.0.0.1:6437/v6.json, sends {"version":6} on connect,
then one JSON message per tracking frame. The client answers the handshake with the exact
string {"focused":true} (Ultraleap's bridge matches control messages as exact strings),
parses every frame, and reconnects with exponential backoff when the socket drops.
``LeapDevice`` is the Leap as a HandDevice (nodes/leap_driver).
"""

import threading
import time
from collections import Counter, deque
from collections.abc import Callable

from websockets.exceptions import ConnectionClosed, InvalidHandshake, InvalidURI
from websockets.sync.client import connect

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import (
    HAND_TYPE_PARAM,
    Backoff,
    HandDevice,
    empty_sample,
    hand_preference,
    reconnect_loop,
)
from motion_sensor.devices.leap_v6 import LeapFrame, frame_to_sample, parse_message
from motion_sensor.errors import DeviceUnavailable, MotionSensorError

FOCUSED = '{"focused":true}'


class ClockMapper:
    """Maps device timestamps (s) to the local clock: local = device + offset.

    The offset is the smallest (receive time - device time) seen over the last ``window``
    frames: the frame that travelled fastest bounds the true offset best, and the window
    follows slow drift between the two clocks.
    """

    def __init__(self, window: int = 500):
        self._offsets = deque(maxlen=window)
        self._last_device_time = None

    def reset(self) -> None:
        """Forget the offset (a new connection may mean a restarted device clock)."""
        self._offsets.clear()
        self._last_device_time = None

    def to_local(self, device_time: float, received: float) -> float:
        """Local time at which the device took the frame."""
        if self._last_device_time is not None and device_time < self._last_device_time:
            self.reset()  # the device clock restarted (service restart, replay loop)
        self._last_device_time = device_time
        self._offsets.append(received - device_time)
        return device_time + min(self._offsets)


# What websockets raises when the service is absent, drops or misbehaves: a reconnect may cure it.
_SOCKET_ERRORS = (OSError, ConnectionClosed, InvalidHandshake, InvalidURI, TimeoutError)


class LeapClient:
    """Connects to a Leap v6 service and hands every parsed frame to ``on_frame``.

    ``on_frame(frame, received_time)`` is called for each tracking frame; bad messages are
    counted in ``counters`` (by reason) and reported through ``on_problem(text)``.
    ``connect``/``receive``/``close`` are one connection (LeapDevice uses them);
    ``run()`` loops over connections with backoff until ``stop()``, waiting through
    ``wait(seconds)`` (injectable: tests need no real sleeping).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 6437,
        on_frame: Callable = None,
        on_problem: Callable = None,
        backoff: Backoff | None = None,
        clock=time.time,
        open_timeout: float = 2.0,
        frame_timeout: float = 2.0,
        wait: Callable[[float], object] = None,
    ):
        if not 0 < int(port) < 65536:
            raise MotionSensorError(f"leap port must be 1-65535, got {port!r}")
        self.uri = f"ws://{host}:{int(port)}/v6.json"
        self.on_frame = on_frame or (lambda frame, received: None)
        self.on_problem = on_problem or (lambda text: None)
        self.backoff = backoff or Backoff()
        self.clock = clock
        self.open_timeout = open_timeout
        self.frame_timeout = frame_timeout
        self.counters = Counter()
        self._stop = threading.Event()
        self.wait = wait or self._stop.wait
        self._socket = None

    def stop(self) -> None:
        """Ask run() to return; closes the socket so a blocked receive wakes up."""
        self._stop.set()
        socket = self._socket
        if socket is not None:
            socket.close()

    def connect(self) -> None:
        """Open the socket and do the v6 handshake; DeviceUnavailable when that fails."""
        try:
            # close_timeout is short: on stop() nobody should wait 10 s for a closing handshake.
            socket = connect(
                self.uri, open_timeout=self.open_timeout, max_size=4 * 1024 * 1024, compression=None, close_timeout=0.5
            ).__enter__()  # as `with` would
        except _SOCKET_ERRORS as exc:
            raise DeviceUnavailable(f"leap connection to {self.uri} refused ({type(exc).__name__}: {exc})") from None
        self._socket = socket
        try:
            first = socket.recv(timeout=self.open_timeout)
            if parse_message(first) is not None or '"version"' not in str(first):
                raise DeviceUnavailable(f'expected the {{"version":6}} handshake, got {str(first)[:60]!r}')
            socket.send(FOCUSED)
        except (MotionSensorError, *_SOCKET_ERRORS) as exc:
            self.close()
            if isinstance(exc, DeviceUnavailable):
                raise
            raise DeviceUnavailable(f"leap handshake with {self.uri} failed ({type(exc).__name__}: {exc})") from None

    def receive(self):
        """(frame, received time) of the next tracking frame, or None for a control or
        rejected message; DeviceUnavailable when the connection is lost."""
        socket = self._socket
        if socket is None or self._stop.is_set():
            raise DeviceUnavailable(f"leap connection to {self.uri} closed")
        try:
            message = socket.recv(timeout=self.frame_timeout)
        except _SOCKET_ERRORS as exc:
            raise DeviceUnavailable(f"leap connection to {self.uri} lost ({type(exc).__name__}: {exc})") from None
        received = self.clock()
        frame = self._handle(message)
        return None if frame is None else (frame, received)

    def close(self) -> None:
        """Close the socket (if open)."""
        socket, self._socket = self._socket, None
        if socket is not None:
            socket.close()

    def run(self) -> None:
        """Connect, read frames, reconnect on drops, until stop()."""
        reconnect_loop(self._session, self._stop.is_set, self.backoff, self.wait, self._on_error)

    def _on_error(self, exc, delay) -> None:
        self.counters["disconnects"] += 1
        self.on_problem(f"{exc}; retrying in {delay:.2f} s")

    def _session(self) -> None:
        self.connect()
        self.counters["connections"] += 1
        self.backoff.reset()
        try:
            while not self._stop.is_set():
                got = self.receive()
                if got is not None:
                    self.on_frame(*got)
        finally:
            self.close()

    def _handle(self, message) -> LeapFrame | None:
        self.counters["messages"] += 1
        try:
            frame: LeapFrame | None = parse_message(message)
        except MotionSensorError as exc:
            self.counters["rejected"] += 1
            self.on_problem(f"rejected Leap message: {exc}")
            return None
        if frame is None:
            self.counters["control_messages"] += 1
            return None
        self.counters["frames"] += 1
        return frame


class LeapDevice(HandDevice):
    """A live Leap service over WebSocket v6 as a HandDevice: every frame is published, also
    those without a hand (hands_num 0, so the sequencer knows the hand left), stamped with
    the device's capture time mapped onto the local clock."""

    name = "leap"
    publishes_skeletons = True  # whole-hand skeletons on motion_sensor/raw_hand_skeleton
    default_frame_id = "leap"
    params = ParamSchema(
        [
            Param("host", "127.0.0.1", doc="Leap service host"),
            Param("port", 6437, low=1, high=65535, doc="Leap service port"),
            Param(
                "primary_hand", "right", choices=("right", "left", "first"), doc="hand that steers when two are seen"
            ),
            HAND_TYPE_PARAM,
            Param("open_timeout_s", 2.0, unit="s", low=0, low_open=True, doc="connect and handshake timeout"),
            Param(
                "frame_timeout_s", 2.0, unit="s", low=0, low_open=True, doc="silence that counts as a lost connection"
            ),
        ]
    )

    def __init__(self, config, **kw):
        super().__init__(config, **kw)
        self.primary, self.strict = hand_preference(self.config)
        self.client = LeapClient(
            self.config["host"],
            self.config["port"],
            on_problem=lambda text: self.warn(text),
            clock=self.clock,
            open_timeout=self.config["open_timeout_s"],
            frame_timeout=self.config["frame_timeout_s"],
        )
        self.counters = self.client.counters  # one set of counters: rejected messages, frames, ...
        self.mapper = ClockMapper()

    def describe(self) -> str:
        return self.client.uri

    def open(self) -> None:
        self.client.connect()

    def read(self, now):
        got = self.client.receive()
        if got is None:
            return None
        frame, received = got
        stamp = self.mapper.to_local(frame.timestamp, received)
        sample = frame_to_sample(frame, stamp, self.primary, self.frame_id, self.strict)
        return empty_sample(stamp, self.frame_id, "leap") if sample is None else sample

    def close(self) -> None:
        self.client.close()

    def stop(self) -> None:
        self.client.stop()
