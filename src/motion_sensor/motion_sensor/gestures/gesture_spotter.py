"""Online spotting of dynamic gestures in a live hand stream, then classification with
rejection.

``GestureSpotter.update(frame)`` takes one ``GestureFrame`` and returns the events it
completes. Segmentation (``mode``):

* ``"speed"`` (default): the tracked point (``source``: palm or index tip) must first
  rest, speed under ``stop_speed`` for ``pause_s`` (armed); a segment starts when it then
  moves faster than ``start_speed`` (the slow lead-in since the pause is kept) and ends
  at the next pause (speed under ``stop_speed`` for ``pause_s``; the resting tail is cut
  off). A segment longer than ``max_duration_s`` is abandoned (continuous motion is not
  a gesture) and the spotter waits for a pause again.
* ``"clutch"``: a segment is the path while the clutch pose is held (``clutch`` pinch or
  grab strength >= ``clutch_on``, released under ``clutch_off``).

A finished segment shorter than ``min_duration_s`` or smaller than ``min_extent_m``
(bounding-box diagonal) is ignored. Otherwise the classifier (a ``DTWClassifier``, open
set: its ``reject_distance`` must be set, e.g. by ``calibrate_rejection``) labels it;
with ``min_confidence`` > 0, a label whose margin to the next class is smaller is
rejected too. An accepted segment gives ``GestureEvent(label, confidence, end stamp,
info={"distance", "start", "duration_s", ...})``; every segment, accepted or not, is kept
in ``last_segment`` (the teach mode and ``record_gesture`` cut templates with it).

Speed is the displacement over ``speed_window_s`` divided by its duration. A gap longer
than ``max_gap_s`` (hand lost) drops the current segment.
"""

from collections import deque
from dataclasses import dataclass

import numpy as np

from motion_common.params import Param, ParamSchema, check_ordered
from motion_sensor.gestures.dtw_classifier import Classification, DTWClassifier
from motion_sensor.gestures.gesture_frame import GestureEvent, GestureFrame

MAX_KEPT_SEGMENTS = 200  # the newest segments kept for inspection; a node runs for hours

SPOTTER_PARAMS = ParamSchema(
    [
        Param("mode", "speed", "", "segmentation: speed/pause or a held clutch pose", choices=("speed", "clutch")),
        Param("source", "palm", "", "tracked point", choices=("palm", "index")),
        Param("start_speed", 0.25, "m/s", "speed that starts a segment after a pause", low=0.0, low_open=True),
        Param("stop_speed", 0.08, "m/s", "speed under which the point rests", low=0.0, low_open=True),
        Param("pause_s", 0.2, "s", "rest that arms the spotter and ends a segment", low=0.0, low_open=True),
        Param("min_duration_s", 0.2, "s", "shorter segments are ignored", low=0.0),
        Param("max_duration_s", 2.5, "s", "longer motion is abandoned (not a gesture)", low=0.0, low_open=True),
        Param("min_extent_m", 0.06, "m", "segments with a smaller bounding-box diagonal are ignored", low=0.0),
        Param("clutch", "pinch", "", "clutch pose in clutch mode", choices=("pinch", "grab")),
        Param("clutch_on", 0.8, "", "strength that engages the clutch", low=0.0, high=1.0),
        Param("clutch_off", 0.6, "", "strength under which the clutch releases", low=0.0, high=1.0),
        Param(
            "clutch_max_grab",
            0.6,
            "",
            "pinch clutch: a grab this strong is a fist, not a pinch (Leap reports a fist as pinched too)",
            low=0.0,
            high=1.0,
        ),
        Param("speed_window_s", 0.05, "s", "window of the speed estimate", low=0.0, low_open=True),
        Param("max_gap_s", 0.25, "s", "a longer frame gap drops the segment", low=0.0, low_open=True),
        Param("min_confidence", 0.0, "", "reject labels with a smaller margin to the next class", low=0.0, high=1.0),
    ]
)


@dataclass
class Segment:
    """One spotted segment: stamps (s), points (m), its classification (None when it was
    too short or small to classify) and whether an event was emitted."""

    stamps: np.ndarray
    points: np.ndarray
    classification: Classification | None
    accepted: bool
    reason: str = ""

    @property
    def duration(self) -> float:
        return float(self.stamps[-1] - self.stamps[0]) if len(self.stamps) else 0.0


class GestureSpotter:
    """Segments a hand stream and classifies the segments (see the module docstring)."""

    def __init__(
        self, classifier: DTWClassifier | None = None, params: dict | None = None, source: str = "gesture_spotter"
    ):
        self.params = SPOTTER_PARAMS.validate(params or {}, source)
        check_ordered(self.params, [("clutch_off", "clutch_on"), ("stop_speed", "start_speed")], source)
        self.classifier = classifier
        self.last_segment: Segment | None = None
        # The latest segments (bounded: a node runs for hours), for record_gesture and tests.
        self.segments: deque[Segment] = deque(maxlen=MAX_KEPT_SEGMENTS)
        self.speed = float("nan")
        self._reset_state()

    def _reset_state(self):
        self._history: deque = deque()  # (stamp, point) for the speed estimate
        self._recent: deque = deque()  # (stamp, point, speed) since the last rest
        self._rest_since: float | None = None
        self._armed = False
        self._recording: list = []
        self._clutched = False
        self._last_stamp: float | None = None

    @property
    def recording(self) -> bool:
        """True while a segment is being recorded."""
        return bool(self._recording)

    def reset(self) -> None:
        """Drop any segment in progress (hand lost)."""
        self._reset_state()

    def _speed(self, stamp, point) -> float:
        self._history.append((stamp, point))
        window = self.params["speed_window_s"]
        while len(self._history) > 2 and stamp - self._history[1][0] >= window:
            self._history.popleft()
        first_stamp, first_point = self._history[0]
        if stamp <= first_stamp:
            return 0.0
        return float(np.linalg.norm(point - first_point) / (stamp - first_stamp))

    def update(self, frame: GestureFrame) -> list[GestureEvent]:
        """Feed one frame; return the gesture events it completes."""
        stamp = float(frame.stamp)
        if self._last_stamp is not None and (
            stamp - self._last_stamp > self.params["max_gap_s"] or stamp < self._last_stamp
        ):
            self._reset_state()
        if frame.hands_num < 1:
            self._reset_state()
            return []
        self._last_stamp = stamp
        point = np.asarray(frame.point(self.params["source"]), dtype=float)
        speed = self._speed(stamp, point)
        self.speed = speed
        if self.params["mode"] == "clutch":
            return self._update_clutch(frame, stamp, point)
        return self._update_speed(stamp, point, speed)

    def _update_speed(self, stamp, point, speed) -> list[GestureEvent]:
        p = self.params
        resting = speed < p["stop_speed"]
        if resting:
            if self._rest_since is None:
                self._rest_since = stamp
        else:
            self._rest_since = None
        rested = self._rest_since is not None and stamp - self._rest_since >= p["pause_s"]
        if self._recording:
            self._recording.append((stamp, point))
            if rested:
                # Cut the resting tail: keep points up to where the rest began.
                kept = [item for item in self._recording if item[0] <= self._rest_since]
                self._recording = []
                self._armed = True
                self._recent.clear()
                return self._finish(kept, stamp)
            if stamp - self._recording[0][0] > p["max_duration_s"]:
                self._recording = []
                self._armed = False
                self.last_segment = Segment(np.array([]), np.zeros((0, 3)), None, False, "too long")
            return []
        if rested:
            self._armed = True
            self._recent.clear()
        if not resting:
            self._recent.append((stamp, point))
        else:
            self._recent.clear()
            self._recent.append((stamp, point))
        if self._armed and speed > p["start_speed"]:
            self._recording = list(self._recent)
            self._armed = False
        return []

    def _update_clutch(self, frame, stamp, point) -> list[GestureEvent]:
        p = self.params
        strength = frame.pinch if p["clutch"] == "pinch" else frame.grab
        if p["clutch"] == "pinch" and frame.grab >= p["clutch_max_grab"]:
            # A closed hand also reads as pinched: carrying a part with a fist must not
            # draw gestures. Whatever was recorded is dropped, not classified.
            if self._clutched:
                self._clutched, self._recording = False, []
                self.last_segment = Segment(np.array([]), np.zeros((0, 3)), None, False, "a fist, not a pinch")
                self.segments.append(self.last_segment)
            return []
        if strength < 0:  # unknown: keep the state
            if self._clutched:
                self._recording.append((stamp, point))
            return []
        if not self._clutched and strength >= p["clutch_on"]:
            self._clutched = True
            self._recording = [(stamp, point)]
            return []
        if self._clutched:
            if strength < p["clutch_off"]:
                self._clutched = False
                kept, self._recording = self._recording, []
                return self._finish(kept, stamp)
            self._recording.append((stamp, point))
            if stamp - self._recording[0][0] > p["max_duration_s"]:
                self._recording = []
                self._clutched = False
                self.last_segment = Segment(np.array([]), np.zeros((0, 3)), None, False, "too long")
        return []

    def _finish(self, items, stamp) -> list[GestureEvent]:
        p = self.params
        stamps = np.array([s for s, _ in items], dtype=float)
        points = np.array([q for _, q in items], dtype=float).reshape(-1, 3)
        segment = Segment(stamps, points, None, False)
        self.last_segment = segment
        self.segments.append(segment)
        if len(stamps) < 3 or stamps[-1] - stamps[0] < p["min_duration_s"]:
            segment.reason = "too short"
            return []
        if np.linalg.norm(np.ptp(points, axis=0)) < p["min_extent_m"]:
            segment.reason = "too small"
            return []
        if self.classifier is None or not len(self.classifier):
            segment.reason = "no classifier"
            return []
        result = self.classifier.classify(points, stamps, open_set=True)
        segment.classification = result
        if result.rejected:
            segment.reason = "rejected: too far from every template"
            return []
        if result.confidence < p["min_confidence"]:
            segment.reason = f"rejected: ambiguous ({result.candidate} vs {result.runner_up})"
            return []
        segment.accepted = True
        return [
            GestureEvent(
                result.label,
                result.confidence,
                stamp,
                {
                    "distance": result.distance,
                    "start": float(stamps[0]),
                    "duration_s": segment.duration,
                    "runner_up": result.runner_up,
                },
            )
        ]
