"""The hand-device base class and the device-independent streaming logic, without ROS.

A device (a Leap service, a SpaceMouse, a recording) is ONE class derived from
``HandDevice``, as robosuite's ``Device`` is for its input devices. It declares:

- ``name``: its hardware id in /diagnostics (``leap``, ``spacemouse``, ``replay``);
- ``params``: a ``ParamSchema`` of its own parameters (units, ranges); the node wrapper
  (``motion_sensor.devices.device_node``) merges it with the wrapper's (topic, frame_id, readiness,
  backoff) and validates the node's private parameters against the union;
- ``rate_hz``: None when ``read`` blocks until the next sample arrives (event-driven), or
  a rate at which the wrapper polls ``read`` (a rate device such as the SpaceMouse);
- ``open()``, ``read(now)``, ``close()``: connect, return the next ``HandSample`` (or None
  when there is nothing to publish), disconnect. ``open``/``read`` raise
  ``DeviceUnavailable`` (or ``OSError``) for anything a reconnect may cure, then the
  wrapper closes, waits with exponential backoff and opens again; a finite source raises
  ``EndOfStream`` when it is done; any other ``MotionSensorError`` stops the node;
- ``counters``: what it saw, by name, published on /diagnostics as they are.

``DeviceRunner`` drives a device: readiness is waited for by the wrapper beforehand, then
it opens, reads (at ``rate_hz`` or as samples come), checks each sample (``sample_problem``)
and publishes it, and reconnects with backoff. Its clock and sleep are injected, so unit
tests run it on a fake clock without sleeping.
"""

import abc
import logging
import math
import time
from collections import Counter
from collections.abc import Callable, Iterable

import numpy as np

from motion_common.params import Param, ParamSchema
from motion_common.rotations import is_unit_quaternion
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError
from motion_sensor.hand_sample import HandSample

_LOG = logging.getLogger("motion_sensor.devices.device")


#: A device that sees both hands follows only this one when set: the two devices of a
#: bimanual session each take one hand of the same stream, and neither ever falls over
#: to the other hand when its own leaves the view.
HAND_TYPE_PARAM = Param(
    "hand_type",
    "",
    choices=("", "left", "right"),
    doc="follow only this hand (empty: primary_hand picks, falling back to the other)",
)


def hand_preference(config: dict) -> tuple[str, bool]:
    """(preferred hand type, strict) of a device config with ``primary_hand`` and
    ``hand_type``: a set ``hand_type`` wins and is strict."""
    if config.get("hand_type"):
        return config["hand_type"], True
    return config["primary_hand"], False


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


RETRYABLE = (OSError, DeviceUnavailable)


def reconnect_loop(
    session: Callable[[], None],
    stopped: Callable[[], bool],
    backoff: Backoff,
    wait: Callable[[float], object],
    on_error: Callable[[BaseException, float], None],
    retry: tuple[type, ...] = RETRYABLE,
) -> None:
    """Run ``session()`` until ``stopped()``; after a retryable error call
    ``on_error(exc, delay)`` and ``wait(delay)`` with the next backoff delay. The session
    resets the backoff itself once it is connected. A session that returns ends the loop."""
    while not stopped():
        try:
            session()
            return
        except retry as exc:
            if stopped():
                return
            delay = backoff.next()
            on_error(exc, delay)
            wait(delay)


def sample_problem(sample: HandSample) -> str | None:
    """Why a sample must not be published, or None when it is good.

    A frame without a hand (hands_num 0) is good whatever its pose: it tells the sequencer
    the hand left. A hand needs a finite position and a unit quaternion, and hands_num must
    match hand_types.
    """
    if sample.hands_num != len(sample.hand_types):
        return f"hands_num {sample.hands_num} but {len(sample.hand_types)} hand types"
    if not math.isfinite(sample.stamp):
        return f"stamp {sample.stamp!r} is not finite"
    if sample.hands_num == 0:
        return None
    position = np.asarray(sample.position, dtype=float)
    orientation = np.asarray(sample.orientation, dtype=float)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        return f"position {position.tolist()} is not 3 finite numbers"
    if orientation.shape != (4,) or not np.all(np.isfinite(orientation)):
        return f"orientation {orientation.tolist()} is not 4 finite numbers"
    if not is_unit_quaternion(orientation.tolist()):
        return f"orientation {orientation.tolist()} is not a unit quaternion"
    return None


def empty_sample(stamp: float, frame_id: str, device: str = "") -> HandSample:
    """A frame without a hand (hands_num 0): the hand left or none is in view."""
    return HandSample(
        stamp=stamp,
        position=np.zeros(3),
        orientation=np.zeros(4),
        hands_num=0,
        hand_types=(),
        frame_id=frame_id,
        device=device,
    )


class HandDevice(abc.ABC):
    """A source of hand frames. Subclasses set ``name``, ``params`` and ``rate_hz`` and
    implement ``open``, ``read`` and ``close``; see the module docstring.

    ``config`` is the validated dict of the device's ``params`` (plus the wrapper's, which a
    device may read, e.g. ``frame_id``). ``clock`` and ``sleep`` are the wrapper's (ROS time
    in a node, a fake in tests); ``info``/``warn`` log through the wrapper.
    """

    name: str = "device"
    params: ParamSchema = ParamSchema([])
    rate_hz: float | None = None
    finite: bool = False  # True: a recording that ends (the node then reports ~finished and exits)
    # True: the wrapper stamps each message as it publishes it. A recording has no moment of
    # reception, so its frames are stamped where a live driver's would start their way
    # through the framework: at the publish (the same point the transport floor starts at).
    stamp_on_publish: bool = False
    default_frame_id: str = "device"
    wrapper_defaults: dict[str, object] = {}  # the device's defaults for wrapper parameters
    # Extra latched std_msgs/Bool outputs: key -> topic; the device calls emit(key, value).
    bool_outputs: dict[str, str] = {}
    subscribes: tuple = ()  # motion_common.interface.Topic entries the node feeds the device from
    # True: its samples carry whole-hand skeletons (HandSample.skeletons), which the node
    # publishes on motion_sensor/raw_hand_skeleton.
    publishes_skeletons: bool = False

    def __init__(
        self, config: dict, clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep
    ):
        self.config = dict(config)
        self.frame_id = self.config.get("frame_id") or self.default_frame_id
        self.clock = clock
        self.sleep = sleep
        self.counters: Counter = Counter()
        self.connected = False
        self.info: Callable[[str], None] = _LOG.info
        self.warn: Callable[[str], None] = _LOG.warning
        self.emitted = []  # (key, bool) events not yet published, drained by the wrapper

    @abc.abstractmethod
    def open(self) -> None:
        """Connect to the device (or load the recording)."""

    @abc.abstractmethod
    def read(self, now: float) -> HandSample | None:
        """The next sample, or None when there is nothing to publish now."""

    @abc.abstractmethod
    def close(self) -> None:
        """Disconnect; ``open`` may be called again afterwards."""

    def stop(self) -> None:
        """Wake a blocked ``read`` at shutdown (optional)."""

    def shutdown(self) -> None:
        """Release what lives across reconnects (files), once at exit (optional)."""

    def describe(self) -> str:
        """One line for the /diagnostics message: what the device is connected to."""
        return self.name

    def emit(self, key: str, value: bool) -> None:
        """Queue a value for the ``bool_outputs[key]`` topic."""
        self.emitted.append((key, bool(value)))


class DeviceRunner:
    """Opens, reads, checks and publishes a device's samples, reconnecting with backoff.

    ``publish(sample)`` gets every good sample; ``publish_bool(key, value)`` every emitted
    value; ``stopped()`` says when to return. ``run()`` returns True when a finite device
    reached its end, False when stopped.
    """

    def __init__(
        self,
        device: HandDevice,
        publish: Callable[[HandSample], None],
        stopped: Callable[[], bool],
        backoff: Backoff = None,
        clock: Callable[[], float] = None,
        sleep: Callable[[float], object] = None,
        publish_bool: Callable[[str, bool], None] = None,
    ):
        self.device = device
        self.publish = publish
        self.publish_bool = publish_bool or (lambda key, value: None)
        self.stopped = stopped
        self.backoff = backoff or Backoff()
        self.clock = clock or device.clock
        self.sleep = sleep or device.sleep
        self.counters = device.counters
        self.finished = False
        self.last_problem = ""

    def run(self) -> bool:
        """Stream until stopped or, for a finite device, to its end."""
        try:
            reconnect_loop(
                self._session, lambda: self.stopped() or self.finished, self.backoff, self.sleep, self._on_error
            )
        finally:
            self.device.connected = False
        return self.finished

    def _on_error(self, exc: BaseException, delay: float) -> None:
        self.counters["connection_errors"] += 1
        self.last_problem = f"{exc}"
        self.device.warn(f"{self.device.name}: {exc}; retrying in {delay:.2f} s")

    def _session(self) -> None:
        self.device.open()
        self.device.connected = True
        self.counters["connections"] += 1
        self.backoff.reset()
        try:
            self._stream()
        except EndOfStream:
            self.step(None)  # what the device emitted as it ended (e.g. the clutch released)
            self.finished = True
        finally:
            self.device.connected = False
            self.device.close()

    def _stream(self) -> None:
        period = 1.0 / self.device.rate_hz if self.device.rate_hz else None
        tick = self.clock()
        while not self.stopped():
            if period is not None:
                tick += period
                delay = tick - self.clock()
                if delay > 0:
                    self.sleep(delay)
                elif delay < -period:  # fell behind (a stall): do not burst to catch up
                    tick = self.clock()
                if self.stopped():
                    return
            self.step(self.device.read(self.clock()))

    def step(self, sample: HandSample | None) -> bool:
        """Check and publish one sample (and the device's emitted values); True if published."""
        while self.device.emitted:
            self.publish_bool(*self.device.emitted.pop(0))
        if sample is None:
            return False
        problem = sample_problem(sample)
        if problem is not None:
            self.counters["invalid_samples"] += 1
            self.device.warn(f"{self.device.name}: sample dropped: {problem}")
            return False
        self.publish(sample)
        self.counters["published"] += 1
        return True


def wait_until_ready(
    conditions: Iterable[tuple[str, Callable[[], bool]]],
    stopped: Callable[[], bool],
    clock: Callable[[], float],
    sleep: Callable[[float], object],
    log: Callable[[str], None],
    poll_s: float = 0.05,
    log_every_s: float = 5.0,
) -> bool:
    """Wait until every ``(description, predicate)`` holds; log what is awaited at the start
    and every ``log_every_s``. True when ready, False if ``stopped()`` first."""
    conditions = list(conditions)
    start = clock()
    next_log = start
    while not stopped():
        waiting = [text for text, ready in conditions if not ready()]
        if not waiting:
            return True
        now = clock()
        if now >= next_log:
            log(f"waiting {now - start:.1f} s for " + " and ".join(waiting))
            next_log = now + log_every_s
        sleep(poll_s)
    return False
