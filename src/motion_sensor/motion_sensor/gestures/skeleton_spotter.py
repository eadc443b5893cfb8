"""Online spotting of skeleton gestures in a live stream of one hand's canonical skeletons.

``SkeletonSpotter.update(stamp, joints)`` takes one frame (``joints`` (22, 3), metres,
REP 103) and returns the gestures it completes, each a ``GestureEvent`` whose ``info``
has ``start``, ``end`` (stamps, s), the 28-class label and the motion extent.

Every ``hop_s`` the frames of the last ``max(window_s)`` seconds are cut into windows
ending now, one per length in ``window_s``; each is resampled in time to the network's
frame count and classified (one onnxruntime run for all of them). A window is a
candidate when

- its motion extent (the largest RMS excursion of a joint about its mean place in the
  window: fingers relative to the palm, the palm itself as it is; metres, independent of
  the frame rate and of tremor-sized noise) is at least ``min_extent_m`` (an idle or
  still hand is no gesture; whole SHREC'17 gestures measure 2.3 cm and more), and
- the best gesture's probability is at least ``min_confidence`` and its label is one
  of ``labels`` (all 14 when empty).

Non-maximum suppression: overlapping candidates compete and the most confident wins;
the winner is emitted once no overlapping candidate has beaten it for ``settle_s``.
After an emitted gesture nothing starting before its end + ``refractory_s`` is taken.
A gap longer than ``max_gap_s`` (hand lost) clears the history. Memory is bounded: the
frame history is a deque of at most ``max(window_s)`` seconds at ``max_rate_hz``.
"""

from collections import deque
from dataclasses import dataclass

import numpy as np

from motion_common.params import Param, ParamSchema
from motion_sensor.gestures.gesture_frame import GestureEvent
from motion_sensor.gestures.skeleton_dataset import CLASSES_14
from motion_sensor.gestures.skeleton_features import FRAMES
from motion_sensor.skeleton_joints import N_JOINTS

__all__ = ["SKELETON_SPOTTER_PARAMS", "SkeletonSpotter", "motion_extent"]

SKELETON_SPOTTER_PARAMS = ParamSchema(
    [
        Param("window_s", [1.0, 1.5, 2.0, 2.5], "s", "window lengths tried at each hop", item_kind=float),
        Param("hop_s", 0.2, "s", "time between two evaluations", low=0.01),
        Param("min_extent_m", 0.015, "m", "windows whose motion extent is smaller are idle", low=0.0),
        Param("min_confidence", 0.85, "", "a candidate's best gesture probability", low=0.0, high=1.0),
        Param("settle_s", 0.4, "s", "a candidate unbeaten this long is emitted", low=0.0),
        Param("refractory_s", 0.5, "s", "after a gesture, no new one starts before its end plus this", low=0.0),
        Param("max_gap_s", 0.3, "s", "a longer frame gap clears the history", low=0.0, low_open=True),
        Param("max_rate_hz", 200.0, "Hz", "bounds the frame history", low=1.0),
        Param("labels", [], "", "gestures that may fire (empty: all 14)", item_kind=str),
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


@dataclass
class _Candidate:
    label: str
    label28: str
    confidence: float
    start: float
    end: float
    energy: float
    seen: float  # when it became the best candidate


class SkeletonSpotter:
    """Sliding-window spotting with a ``SkeletonClassifier`` (see the module doc)."""

    def __init__(self, classifier, params=None):
        self.classifier = classifier
        self.params = SKELETON_SPOTTER_PARAMS.validate(dict(params or {}), "skeleton spotter")
        unknown = sorted(set(self.params["labels"]) - set(CLASSES_14))
        if unknown:
            raise ValueError(f"skeleton spotter: unknown labels {unknown} (known: {', '.join(CLASSES_14)})")
        self.windows = sorted(float(w) for w in self.params["window_s"])
        self.allowed = set(self.params["labels"]) or set(CLASSES_14)
        longest = self.windows[-1]
        self._frames = deque(maxlen=int(longest * self.params["max_rate_hz"]) + 2)
        self._next_eval = None
        self._pending = None
        self._blocked_until = -np.inf
        self.counters = {
            "frames": 0,
            "evaluations": 0,
            "idle": 0,
            "candidates": 0,
            "gestures": 0,
            "gaps": 0,
            "out_of_order": 0,
        }

    def reset(self):
        """Forget the history (the hand left)."""
        self._frames.clear()
        self._next_eval = None
        self._pending = None

    def update(self, stamp, joints):
        """Take one frame; return the list of gestures completed now (usually empty)."""
        stamp = float(stamp)
        events = []
        if self._frames:
            last = self._frames[-1][0]
            if stamp <= last:
                self.counters["out_of_order"] += 1
                return []
            if stamp - last > self.params["max_gap_s"]:
                self.counters["gaps"] += 1
                events = self._flush(stamp, force=True)
                self.reset()
        self._frames.append((stamp, np.asarray(joints, dtype=np.float64).reshape(N_JOINTS, 3)))
        self.counters["frames"] += 1
        if self._next_eval is None:
            self._next_eval = stamp + self.windows[0]
        if stamp >= self._next_eval:
            self._next_eval = stamp + self.params["hop_s"]
            self._evaluate(stamp)
        return events + self._flush(stamp)

    def finish(self):
        """The gesture still pending at the end of a stream, if any."""
        return self._flush(np.inf, force=True)

    def _windows(self, now):
        stamps = np.fromiter((f[0] for f in self._frames), dtype=float, count=len(self._frames))
        cut = []
        for length in self.windows:
            start = now - length
            if stamps[0] > start + 0.05 * length or start < self._blocked_until:
                continue
            first = int(np.searchsorted(stamps, start))
            if len(stamps) - first < 4:
                continue
            cut.append((start, first))
        return stamps, cut

    def _evaluate(self, now):
        self.counters["evaluations"] += 1
        stamps, cut = self._windows(now)
        if not cut:
            return
        joints = np.stack([f[1] for f in self._frames])
        sequences, spans, energies = [], [], []
        for _start, first in cut:
            times = np.linspace(stamps[first], now, FRAMES)
            window = joints[first:]
            energy = motion_extent(window)
            if energy < self.params["min_extent_m"]:
                self.counters["idle"] += 1
                continue
            positions = np.interp(times, stamps[first:], np.arange(len(window), dtype=float))
            low = np.minimum(np.floor(positions).astype(int), len(window) - 2)
            frac = (positions - low)[:, None, None]
            sequences.append(window[low] * (1.0 - frac) + window[low + 1] * frac)
            spans.append((stamps[first], now))
            energies.append(energy)
        if not sequences:
            return
        results = self.classifier.classify_batch(sequences)
        best = None
        for result, span, energy in zip(results, spans, energies, strict=True):
            if result.label14 not in self.allowed or result.confidence < self.params["min_confidence"]:
                continue
            if best is None or result.confidence > best.confidence:
                best = _Candidate(result.label14, result.label28, result.confidence, *span, energy, now)
        if best is None:
            return
        self.counters["candidates"] += 1
        pending = self._pending
        if pending is None or best.start >= pending.end or best.confidence > pending.confidence:
            if pending is not None and best.start >= pending.end:
                return  # a later, separate candidate waits until the pending one is out
            self._pending = best

    def _flush(self, now, force=False):
        pending = self._pending
        if pending is None or (not force and now - pending.seen < self.params["settle_s"]):
            return []
        self._pending = None
        self._blocked_until = pending.end + self.params["refractory_s"]
        self.counters["gestures"] += 1
        info = {
            "start": pending.start,
            "end": pending.end,
            "label28": pending.label28,
            "extent_m": round(pending.energy, 4),
        }
        return [GestureEvent(pending.label, pending.confidence, pending.end, info)]
