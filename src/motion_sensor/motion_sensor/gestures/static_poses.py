"""Static hand poses with hysteresis and a dwell time, from what a hand message carries.

``StaticPoseDetector.update(frame)`` takes one ``GestureFrame`` (stamp s, palm m, grab and
pinch strength 0-1 or -1 = unknown, hands_num) and returns the events it completes:

========================  =========================================================
event                     when
========================  =========================================================
``fist``                  grab >= grab_on for fist_dwell_s (ends when grab < grab_off)
``pinch``                 pinch >= pinch_on and grab < pinch_max_grab for pinch_dwell_s
                          (ends when pinch < pinch_off); a fist is not a pinch
``open_palm``             grab <= open_on and pinch <= open_on for open_dwell_s
                          (ends when either rises above open_off)
``second_hand``           hands_num >= 2 for second_hand_dwell_s (ends below 2)
``hold_still``            palm speed < still_speed for still_time_s (ends when the speed
                          exceeds still_release_speed): the one gesture a palm-only
                          device (no grab/pinch) can make
``<name>_end``            the pose above was active and is released
========================  =========================================================

Each pose fires once per entry: holding a fist gives one ``fist`` event, releasing it one
``fist_end``. The band between the on and off thresholds is the hysteresis: a strength
hovering at the threshold does not chatter. An unknown strength (-1) is no evidence: the
pose keeps its state and its dwell timer restarts. A gap between frames longer than
``max_gap_s`` (hand lost) or a frame without a hand ends every active pose and restarts
every timer. Stamps are injected (no clock is read), so tests replay time exactly.

Palm speed is the displacement over the last ``speed_window_s`` divided by its duration,
which averages the tracker's sub-millimetre jitter away. The defaults come from the real
Leap recordings in tests/data: a hand "held still" there drifts at 15-45 mm/s (0.3 s
windows), hence still_speed 0.05 m/s; deliberate motion is 0.2 m/s and more.
"""

from collections import deque

import numpy as np

from motion_common.params import Param, ParamSchema, check_ordered
from motion_sensor.gestures.gesture_frame import GestureEvent, GestureFrame

STATIC_PARAMS = ParamSchema(
    [
        Param("grab_on", 0.8, "", "grab strength that starts a fist", low=0.0, high=1.0),
        Param("grab_off", 0.5, "", "grab strength under which a fist ends (hysteresis)", low=0.0, high=1.0),
        Param("fist_dwell_s", 0.25, "s", "time the fist must be held", low=0.0),
        Param("pinch_on", 0.85, "", "pinch strength that starts a pinch", low=0.0, high=1.0),
        Param("pinch_off", 0.6, "", "pinch strength under which a pinch ends", low=0.0, high=1.0),
        Param("pinch_max_grab", 0.6, "", "a pinch needs grab below this (else it is a fist)", low=0.0, high=1.0),
        Param("pinch_dwell_s", 0.2, "s", "time the pinch must be held", low=0.0),
        Param("open_on", 0.1, "", "grab and pinch at most this for an open palm", low=0.0, high=1.0),
        Param("open_off", 0.3, "", "open palm ends when grab or pinch exceeds this", low=0.0, high=1.0),
        Param("open_dwell_s", 0.5, "s", "time the open palm must be held", low=0.0),
        Param("second_hand_dwell_s", 0.3, "s", "time a second hand must be seen", low=0.0),
        Param("still_speed", 0.05, "m/s", "palm speed under which the hand counts as still", low=0.0, low_open=True),
        Param(
            "still_release_speed", 0.1, "m/s", "palm speed that ends hold_still (hysteresis)", low=0.0, low_open=True
        ),
        Param("still_time_s", 1.0, "s", "time the palm must stay still for hold_still", low=0.0, low_open=True),
        Param("speed_window_s", 0.25, "s", "window over which the palm speed is measured", low=0.0, low_open=True),
        Param("max_gap_s", 0.25, "s", "a longer gap between frames means the hand was lost", low=0.0, low_open=True),
    ]
)

POSES = ("fist", "pinch", "open_palm", "second_hand", "hold_still")


class _Pose:
    """One on/off pose: enters after ``dwell`` s of its on-condition, leaves on its
    off-condition; tracks the mean confidence over the dwell."""

    def __init__(self, name: str, dwell: float):
        self.name, self.dwell = name, dwell
        self.active = False
        self.since: float | None = None
        self.scores: list[float] = []

    def reset(self, stamp: float, events: list[GestureEvent]) -> None:
        if self.active:
            events.append(GestureEvent(self.name + "_end", 1.0, stamp))
        self.active, self.since, self.scores = False, None, []

    def update(self, on: bool | None, off: bool | None, score: float, stamp: float, events: list[GestureEvent]) -> None:
        """``on``/``off`` None = unknown (state kept, dwell restarted)."""
        if on is None or off is None:
            self.since, self.scores = None, []
            return
        if self.active:
            if off:
                self.active, self.since, self.scores = False, None, []
                events.append(GestureEvent(self.name + "_end", 1.0, stamp))
            return
        if not on:
            self.since, self.scores = None, []
            return
        if self.since is None:
            self.since = stamp
        self.scores.append(score)
        if stamp - self.since >= self.dwell - 1e-9:  # stamps are sums of float steps
            self.active = True
            confidence = float(np.clip(np.mean(self.scores), 0.0, 1.0))
            events.append(GestureEvent(self.name, confidence, stamp, {"held_s": stamp - self.since}))


class StaticPoseDetector:
    """Static poses and hold-still from a stream of GestureFrames (see module docstring)."""

    def __init__(self, params: dict | None = None, source: str = "static_poses"):
        p = STATIC_PARAMS.validate(params or {}, source)
        check_ordered(
            p,
            [
                ("grab_off", "grab_on"),
                ("pinch_off", "pinch_on"),
                ("open_on", "open_off"),
                ("still_speed", "still_release_speed"),
            ],
            source,
        )
        self.params = p
        self._poses = {
            name: _Pose(name, p[key])
            for name, key in (
                ("fist", "fist_dwell_s"),
                ("pinch", "pinch_dwell_s"),
                ("open_palm", "open_dwell_s"),
                ("second_hand", "second_hand_dwell_s"),
                ("hold_still", "still_time_s"),
            )
        }
        self._history: deque[tuple[float, np.ndarray]] = deque()
        self._last_stamp: float | None = None
        self.speed = float("nan")

    def active(self) -> list[str]:
        """Names of the poses active now."""
        return [name for name, pose in self._poses.items() if pose.active]

    def reset(self, stamp: float) -> list[GestureEvent]:
        """Hand lost at ``stamp``: end every active pose (their ``_end`` events)."""
        events: list[GestureEvent] = []
        for pose in self._poses.values():
            pose.reset(stamp, events)
        self._history.clear()
        self._last_stamp = None
        self.speed = float("nan")
        return events

    def _palm_speed(self, stamp: float, palm: np.ndarray) -> float | None:
        self._history.append((stamp, palm))
        window = self.params["speed_window_s"]
        while len(self._history) > 2 and stamp - self._history[1][0] >= window:
            self._history.popleft()
        first_stamp, first_palm = self._history[0]
        if stamp - first_stamp < 0.5 * window:
            return None  # not enough history yet
        return float(np.linalg.norm(palm - first_palm) / (stamp - first_stamp))

    def update(self, frame: GestureFrame) -> list[GestureEvent]:
        """Feed one frame; return the events it completes (often none)."""
        p = self.params
        events: list[GestureEvent] = []
        stamp = float(frame.stamp)
        if self._last_stamp is not None and (stamp - self._last_stamp > p["max_gap_s"] or stamp < self._last_stamp):
            events.extend(self.reset(stamp))
        if frame.hands_num < 1:
            events.extend(self.reset(stamp))
            return events
        self._last_stamp = stamp
        grab = frame.grab if frame.grab >= 0 else None
        pinch = frame.pinch if frame.pinch >= 0 else None

        fist = self._poses["fist"]
        if grab is None:
            fist.update(None, None, 0.0, stamp, events)
        else:
            fist.update(grab >= p["grab_on"], grab < p["grab_off"], grab, stamp, events)

        pinch_pose = self._poses["pinch"]
        if pinch is None or grab is None:
            pinch_pose.update(None, None, 0.0, stamp, events)
        else:
            on = pinch >= p["pinch_on"] and grab < p["pinch_max_grab"] and not fist.active
            pinch_pose.update(on, pinch < p["pinch_off"] or fist.active, pinch, stamp, events)

        open_palm = self._poses["open_palm"]
        if pinch is None or grab is None:
            open_palm.update(None, None, 0.0, stamp, events)
        else:
            strength = max(grab, pinch)
            open_palm.update(strength <= p["open_on"], strength > p["open_off"], 1.0 - strength, stamp, events)

        self._poses["second_hand"].update(frame.hands_num >= 2, frame.hands_num < 2, 1.0, stamp, events)

        speed = self._palm_speed(stamp, np.asarray(frame.palm, dtype=float))
        still = self._poses["hold_still"]
        if speed is None:
            still.update(None, None, 0.0, stamp, events)
        else:
            self.speed = speed
            still.update(
                speed < p["still_speed"],
                speed > p["still_release_speed"],
                1.0 - speed / p["still_speed"],
                stamp,
                events,
            )
        return events
