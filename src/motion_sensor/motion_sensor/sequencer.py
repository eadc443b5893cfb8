"""The sequencer: turns irregular, noisy device frames into a clean pose stream.

It validates each frame, drops stale and out-of-order ones (the latest frame wins, so no
queue builds up between the asynchronous reading and commanding), re-seeds the filter when
a different hand appears, and filters the pose. Every rejected frame is counted by reason.
"""
from collections import Counter
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .errors import MotionSensorError
from .filters import make_filter
from .hand_sample import HandSample

# Quaternions from drivers are normalised in float64; messages carry float64 too, so
# anything further than this from unit norm was not produced as a rotation.
UNIT_QUATERNION_TOLERANCE = 1e-3


@dataclass
class SequencerConfig:
    """Sequencer parameters (units in the names)."""

    filter_name: str = "mean"
    filter_params: dict = None
    max_age_s: float = 0.25
    max_future_s: float = 0.05

    def __post_init__(self):
        if self.filter_params is None:
            self.filter_params = {"queue_size": 10}
        if not (self.max_age_s > 0):
            raise MotionSensorError(f"max_age_s must be > 0 seconds, got {self.max_age_s!r}")
        if not (self.max_future_s >= 0):
            raise MotionSensorError(f"max_future_s must be >= 0 seconds, got {self.max_future_s!r}")


@dataclass
class SequencedPose:
    """A filtered pose ready for /motion_states, with the stamp of its sensor frame."""

    stamp: float
    position: np.ndarray
    orientation: np.ndarray
    frame_id: str
    hand_type: str
    hands_num: int


def validate_sample(sample: HandSample) -> Optional[str]:
    """Return why ``sample`` is unusable, or None when it is fine."""
    position = np.asarray(sample.position, dtype=float)
    orientation = np.asarray(sample.orientation, dtype=float)
    if position.shape != (3,) or orientation.shape != (4,):
        return "malformed"
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(orientation)) and np.isfinite(sample.stamp)):
        return "non_finite"
    if abs(np.linalg.norm(orientation) - 1.0) > UNIT_QUATERNION_TOLERANCE:
        return "non_unit_quaternion"
    if sample.hands_num != len(sample.hand_types):
        return "hands_num_mismatch"
    if sample.stamp <= 0:
        return "bad_stamp"
    return None


class Sequencer:
    """Validates, de-stales and filters hand samples. Not thread-safe: one caller."""

    def __init__(self, config: SequencerConfig = None):
        self.config = config or SequencerConfig()
        self.filter = make_filter(self.config.filter_name, **self.config.filter_params)
        self.counters = Counter()
        self._last_stamp = None
        self._hand_key = None

    def reset(self) -> None:
        """Forget the filter history and the last stamp (e.g. on a device switch)."""
        self.filter.reset()
        self._last_stamp = None
        self._hand_key = None

    def process(self, sample: HandSample, now: float) -> Optional[SequencedPose]:
        """Take one sample at wall time ``now`` (s); return the filtered pose or None.

        None means the frame was dropped; ``counters`` says why.
        """
        self.counters["frames_in"] += 1
        # A frame without a hand is normal (the hand left the sensor), not malformed.
        reason = "no_hand" if sample.hands_num == 0 and not sample.hand_types else validate_sample(sample)
        if reason is None:
            reason = self._timing_problem(sample.stamp, now)
        if reason is not None:
            self.counters["dropped_" + reason] += 1
            return None
        key = (sample.hand_id, sample.primary_type)
        if key != self._hand_key:
            if self._hand_key is not None:
                self.counters["filter_reseeds"] += 1
            # Two hands are never blended: a new hand starts a fresh filter.
            self.filter.reset()
            self._hand_key = key
        self._last_stamp = sample.stamp
        position, orientation = self.filter.update(sample.stamp, sample.position, sample.orientation)
        self.counters["frames_out"] += 1
        return SequencedPose(sample.stamp, position, orientation, sample.frame_id,
                             sample.primary_type, sample.hands_num)

    def _timing_problem(self, stamp: float, now: float) -> Optional[str]:
        if self._last_stamp is not None and stamp == self._last_stamp:
            return "duplicate"
        if self._last_stamp is not None and stamp < self._last_stamp:
            return "out_of_order"
        if stamp > now + self.config.max_future_s:
            return "future_stamp"
        if now - stamp > self.config.max_age_s:
            return "stale"
        return None

    @property
    def dropped(self) -> int:
        """Total frames dropped for any reason."""
        return sum(v for k, v in self.counters.items() if k.startswith("dropped_"))
