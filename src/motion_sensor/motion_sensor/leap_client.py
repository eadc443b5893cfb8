"""Leap Motion WebSocket client (protocol v6), without ROS.

The Leap service listens on ws://127.0.0.1:6437/v6.json, sends {"version":6} on connect,
then one JSON message per tracking frame. The client answers the handshake with the exact
string {"focused":true} (Ultraleap's bridge matches control messages as exact strings),
parses every frame, and reconnects with exponential backoff when the socket drops.
"""
import threading
import time
from collections import Counter, deque
from typing import Callable, Optional

from websockets.exceptions import ConnectionClosed, InvalidHandshake, InvalidURI
from websockets.sync.client import connect

from .errors import MotionSensorError
from .leap_v6 import LeapFrame, parse_message

FOCUSED = '{"focused":true}'


class Backoff:
    """Exponential backoff delays: ``initial`` s, times ``factor``, capped at ``maximum``."""

    def __init__(self, initial: float = 0.25, factor: float = 2.0, maximum: float = 5.0):
        if not (initial > 0 and factor >= 1 and maximum >= initial):
            raise MotionSensorError("backoff needs initial > 0, factor >= 1, maximum >= initial")
        self.initial, self.factor, self.maximum = initial, factor, maximum
        self._next = initial

    def next(self) -> float:
        """The delay to wait now; the following one grows."""
        delay = self._next
        self._next = min(self._next * self.factor, self.maximum)
        return delay

    def reset(self) -> None:
        """Back to the initial delay (after a good connection)."""
        self._next = self.initial


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


class LeapClient:
    """Connects to a Leap v6 service and hands every parsed frame to ``on_frame``.

    ``on_frame(frame, received_time)`` is called for each tracking frame; bad messages are
    counted in ``counters`` (by reason) and reported through ``on_problem(text)``.
    ``run()`` blocks until ``stop()``; it reconnects with backoff on any drop.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 6437, on_frame: Callable = None,
                 on_problem: Callable = None, backoff: Optional[Backoff] = None, clock=time.time,
                 open_timeout: float = 2.0, frame_timeout: float = 2.0):
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
        self._socket = None

    def stop(self) -> None:
        """Ask run() to return; closes the socket so a blocked receive wakes up."""
        self._stop.set()
        socket = self._socket
        if socket is not None:
            socket.close()

    def run(self) -> None:
        """Connect, read frames, reconnect on drops, until stop()."""
        while not self._stop.is_set():
            try:
                self._session()
            except (OSError, ConnectionClosed, InvalidHandshake, InvalidURI, TimeoutError, MotionSensorError) as exc:
                if self._stop.is_set():
                    break
                self.counters["disconnects"] += 1
                delay = self.backoff.next()
                self.on_problem(f"leap connection to {self.uri} lost or refused ({type(exc).__name__}: {exc}); "
                                f"retrying in {delay:.2f} s")
                self._stop.wait(delay)

    def _session(self) -> None:
        # close_timeout is short: on stop() nobody should wait 10 s for a closing handshake.
        with connect(self.uri, open_timeout=self.open_timeout, max_size=4 * 1024 * 1024,
                     compression=None, close_timeout=0.5) as socket:
            self._socket = socket
            try:
                first = socket.recv(timeout=self.open_timeout)
                if parse_message(first) is not None or '"version"' not in str(first):
                    raise MotionSensorError(f"expected the {{\"version\":6}} handshake, got {str(first)[:60]!r}")
                socket.send(FOCUSED)
                self.counters["connections"] += 1
                self.backoff.reset()
                while not self._stop.is_set():
                    message = socket.recv(timeout=self.frame_timeout)
                    received = self.clock()
                    self._handle(message, received)
            finally:
                self._socket = None

    def _handle(self, message, received: float) -> None:
        self.counters["messages"] += 1
        try:
            frame: Optional[LeapFrame] = parse_message(message)
        except MotionSensorError as exc:
            self.counters["rejected"] += 1
            self.on_problem(f"rejected Leap message: {exc}")
            return
        if frame is None:
            self.counters["control_messages"] += 1
            return
        self.counters["frames"] += 1
        self.on_frame(frame, received)
