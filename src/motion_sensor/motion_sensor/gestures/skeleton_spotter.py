"""Online spotting of skeleton gestures in a live stream of one hand's canonical skeletons.

``SkeletonSpotter.update(stamp, joints)`` takes one frame (``joints`` (22, 3), metres,
REP 103) and returns the gestures it completes, each a ``GestureEvent`` (stamp = the
gesture's end) whose ``info`` has ``start``, ``end`` (stamps, s), the 28-class label and
the motion extent.

A gesture is motion between two rests, as the SHREC online tracks' streams and an
operator's deliberate commands are. The hand is at rest while the motion extent of the
last ``rest_window_s`` (the largest RMS excursion of a joint about its mean place: fingers
relative to the palm, the palm itself; metres, independent of the frame rate) is under
``rest_extent_m``. A segment starts when the hand leaves a rest of at least ``pause_s``
(a command starts from rest: the hand that moves on from teleop motion starts none) and
ends once it has rested ``pause_s`` again. The segment usually holds more than the
gesture: the hand's way from the last rest to where the gesture begins. So several windows
of it are classified in one batch (the shipped network through ``classifier``), each from a
fraction ``window_starts`` of the segment to its end, and the most confident window wins;
a gesture is reported when

- it lasted ``min_duration_s`` to ``max_duration_s`` (longer motion is not a command: the
  spotter then waits for the next rest),
- its motion extent is at least ``min_extent_m`` (whole SHREC'17 gestures measure 2.3 cm
  and more), and
- the best gesture's probability is at least ``min_confidence`` and its label is one of
  ``labels`` (all 14 when empty). The shipped network was trained to answer with no
  confident class on motion that is no gesture (``skeleton_negatives``), so the gate can
  stay low;
- with ``labels`` set, a window counts only when no gesture outside them has a probability
  of ``max_other_probability`` or more. The gestures that are no command are the ones a
  command gets confused with (a pinch read as a grab, a swipe down as a tap): such a window
  still gives the other gesture some weight, a real command almost none; and a window on
  which the network is unsure (near uniform: 1/14 each) counts neither. 1 turns it off.

After a gesture, a segment that starts before its end + ``refractory_s`` is ignored. A
frame gap longer than ``max_gap_s`` (hand lost) drops the segment. Memory is bounded: the
history is a deque of at most ``max_duration_s`` plus the rest windows at ``max_rate_hz``.
"""

from collections import deque

import numpy as np

from motion_common.params import Param, ParamSchema
from motion_sensor.gestures.gesture_frame import GestureEvent
from motion_sensor.gestures.skeleton_dataset import CLASSES_14
from motion_sensor.skeleton_joints import N_JOINTS

__all__ = ["SKELETON_SPOTTER_PARAMS", "SkeletonSpotter", "motion_extent"]

SKELETON_SPOTTER_PARAMS = ParamSchema(
    [
        Param("rest_window_s", 0.3, "s", "window of the rest test", low=0.05),
        Param("rest_extent_m", 0.006, "m", "motion extent under which the hand rests", low=0.0, low_open=True),
        Param("pause_s", 0.3, "s", "rest that ends a segment", low=0.0),
        Param("min_duration_s", 0.4, "s", "shorter segments are ignored", low=0.0),
        Param("max_duration_s", 6.0, "s", "longer motion is not a gesture", low=0.0, low_open=True),
        Param("min_extent_m", 0.015, "m", "segments whose motion extent is smaller are ignored", low=0.0),
        Param("min_confidence", 0.6, "", "a segment's best gesture probability", low=0.0, high=1.0),
        Param("refractory_s", 0.3, "s", "after a gesture, no new one starts before its end plus this", low=0.0),
        Param("max_gap_s", 0.3, "s", "a longer frame gap drops the segment", low=0.0, low_open=True),
        Param("max_rate_hz", 200.0, "Hz", "bounds the frame history", low=1.0),
        Param("labels", [], "", "gestures that may fire (empty: all 14)", item_kind=str),
        Param(
            "max_other_probability",
            1.0,
            "",
            "with labels set, a window counts only if every gesture outside them is less probable (1: off)",
            low=0.0,
            low_open=True,
            high=1.0,
        ),
        Param(
            "window_starts",
            [0.0, 0.2],
            "",
            "fractions of a segment where its classified windows start (each runs to the end)",
            low=0.0,
            high=0.9,
        ),
    ]
)


def motion_extent(joints):
    """Largest RMS excursion (m) of a joint about its mean in ``joints`` (n, 22, 3):
    fingers and wrist relative to the palm, the palm as it is."""
    joints = np.asarray(joints, dtype=float)
    if len(joints) < 2:
        return 0.0
    relative = joints - joints[:, 1:2]
    relative[:, 1] = joints[:, 1]
    spread = np.sqrt(np.mean(np.sum((relative - relative.mean(axis=0)) ** 2, axis=2), axis=0))
    return float(spread.max())


class SkeletonSpotter:
    """Rest-bounded segmentation and classification with a ``SkeletonClassifier``
    (``classify_batch``); see the module doc."""

    def __init__(self, classifier, params=None):
        self.classifier = classifier
        self.params = SKELETON_SPOTTER_PARAMS.validate(dict(params or {}), "skeleton spotter")
        unknown = sorted(set(self.params["labels"]) - set(CLASSES_14))
        if unknown:
            raise ValueError(f"skeleton spotter: unknown labels {unknown} (known: {', '.join(CLASSES_14)})")
        self.allowed = set(self.params["labels"]) or set(CLASSES_14)
        p = self.params
        span = p["max_duration_s"] + p["pause_s"] + 2.0 * p["rest_window_s"]
        self._frames = deque(maxlen=int(span * p["max_rate_hz"]) + 2)
        self._start = None  # stamp where the current segment started
        self._rest_since = None  # stamp where the hand came to rest within a segment
        self._wait_for_rest = False  # after overlong motion
        self._calm_since = None  # stamp since which the hand rests outside a segment
        self._blocked_until = -np.inf
        self.counters = dict.fromkeys(
            ("frames", "segments", "short", "long", "small", "unsure", "other", "gestures", "gaps", "out_of_order"), 0
        )
        # Indices of the 14 classes outside ``labels``, weighed by max_other_probability.
        self._others = np.array([k for k, name in enumerate(CLASSES_14) if name not in self.allowed], dtype=int)

    def reset(self):
        """Forget the history (the hand left)."""
        self._frames.clear()
        self._start = None
        self._rest_since = None
        self._wait_for_rest = False
        self._calm_since = None

    def finish(self):
        """The gesture of a segment still open at the end of a stream, if any."""
        if self._start is None or not self._frames:
            return []
        end = self._frames[-1][0]
        self._start, start = None, self._start
        return self._decide(start, end)

    def update(self, stamp, joints):
        """Take one frame; return the list of gestures completed now (usually empty)."""
        stamp = float(stamp)
        if self._frames:
            last = self._frames[-1][0]
            if stamp <= last:
                self.counters["out_of_order"] += 1
                return []
            if stamp - last > self.params["max_gap_s"]:
                self.counters["gaps"] += 1
                self.reset()
        self._frames.append((stamp, np.asarray(joints, dtype=np.float64).reshape(N_JOINTS, 3)))
        self.counters["frames"] += 1
        p = self.params
        if stamp - self._frames[0][0] < p["rest_window_s"]:
            return []
        resting = motion_extent(self._recent(stamp - p["rest_window_s"])) < p["rest_extent_m"]
        if self._start is None:
            if resting:
                self._wait_for_rest = False
                self._calm_since = stamp if self._calm_since is None else self._calm_since
            elif self._calm_since is not None and stamp - self._calm_since >= p["pause_s"]:
                self._start = stamp - p["rest_window_s"]  # a command starts from rest
                self._rest_since = self._calm_since = None
            else:
                self._calm_since = None
            return []
        if not resting:
            self._rest_since = None
            if stamp - self._start > p["max_duration_s"] + p["rest_window_s"]:
                self.counters["long"] += 1
                self._start, self._wait_for_rest = None, True
            return []
        if self._rest_since is None:
            self._rest_since = stamp
        if stamp - self._rest_since < p["pause_s"]:
            return []
        start, end = self._start, self._rest_since - 0.5 * p["rest_window_s"]
        self._calm_since = self._rest_since  # already resting: the next command may follow
        self._start = self._rest_since = None
        return self._decide(start, end)

    def _recent(self, since):
        return np.stack([f[1] for f in self._frames if f[0] >= since])

    def _segment(self, start, end):
        stamps = np.fromiter((f[0] for f in self._frames), dtype=float, count=len(self._frames))
        first, last = int(np.searchsorted(stamps, start)), int(np.searchsorted(stamps, end, side="right"))
        return stamps[first:last], np.stack([f[1] for f in list(self._frames)[first:last]]) if last > first else None

    def _windows(self, stamps):
        """First frame of each window: at the ``window_starts`` fractions of the segment,
        keeping at least 4 frames and ``min_duration_s`` (duplicates once)."""
        duration = stamps[-1] - stamps[0]
        keep = min(self.params["min_duration_s"], duration)
        firsts = []
        for fraction in self.params["window_starts"] or [0.0]:
            first = int(np.searchsorted(stamps, stamps[0] + fraction * duration))
            if len(stamps) - first >= 4 and stamps[-1] - stamps[first] >= keep and first not in firsts:
                firsts.append(first)
        return firsts or [0]

    def _decide(self, start, end):
        p = self.params
        self.counters["segments"] += 1
        if start < self._blocked_until:
            return []
        if end - start < p["min_duration_s"]:
            self.counters["short"] += 1
            return []
        stamps, joints = self._segment(start, end)
        if joints is None or len(joints) < 4:
            self.counters["short"] += 1
            return []
        extent = motion_extent(joints)
        if extent < p["min_extent_m"]:
            self.counters["small"] += 1
            return []
        windows = self._windows(stamps)
        results = self.classifier.classify_batch([joints[first:] for first in windows])
        counted = [k for k, result in enumerate(results) if not self._other_likely(result)]
        if not counted:
            self.counters["other"] += 1
            return []
        pick = max(counted, key=lambda k: results[k].confidence)
        best = results[pick]
        if best.label14 not in self.allowed or best.confidence < p["min_confidence"]:
            self.counters["unsure"] += 1
            return []
        self._blocked_until = float(stamps[-1]) + p["refractory_s"]
        self.counters["gestures"] += 1
        info = {
            "start": float(stamps[windows[pick]]),
            "end": float(stamps[-1]),
            "label28": best.label28,
            "extent_m": round(extent, 4),
        }
        return [GestureEvent(best.label14, best.confidence, float(stamps[-1]), info)]

    def _other_likely(self, result) -> bool:
        """A gesture outside ``labels`` is too probable in this window's result."""
        limit = self.params["max_other_probability"]
        if limit >= 1.0 or not len(self._others):
            return False
        return float(np.max(np.asarray(result.prob14)[self._others])) >= limit
