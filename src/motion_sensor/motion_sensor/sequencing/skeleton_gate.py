"""The sequencer's drop rules applied to skeletons: a skeleton goes on only with its palm.

A device publishes each frame twice: the palm (``motion_sensor/raw_hand``) and the whole
skeleton of each hand seen (``motion_sensor/raw_hand_skeleton``), with the same stamp.
The sequencer decides on the palm frame (validation, device binding, timing, hand
identity, entry and exit trims, jumps); ``SkeletonGate`` passes a skeleton on exactly
when the palm frame of its stamp was passed on, whichever of the two arrives first, and
drops it when a later palm frame passes without it (its own frame was dropped). A
skeleton that is malformed itself is dropped too (``skeleton_joints.check_skeleton``).
Both waiting lists are bounded.
"""

from collections import Counter, deque

__all__ = ["SkeletonGate"]


class SkeletonGate:
    """Pairs skeletons with the palm frames the sequencer emitted (see the module doc)."""

    def __init__(self, max_pending: int = 64, max_released: int = 64):
        self._pending = deque(maxlen=max_pending)  # skeletons waiting for their palm frame
        self._released = deque(maxlen=max_released)  # stamps of palm frames passed on
        self.counters = Counter()

    def on_skeleton(self, skeleton) -> list:
        """A skeleton arrived; returns it (in a list) when its palm frame already passed."""
        problem = skeleton.problem()
        if problem is not None:
            self.counters["dropped_invalid"] += 1
            return []
        if skeleton.stamp in self._released:
            self.counters["passed"] += 1
            return [skeleton]
        if self._released and skeleton.stamp < self._released[-1]:
            self.counters["dropped_with_palm"] += 1  # an older frame that was not passed on
            return []
        if len(self._pending) == self._pending.maxlen:
            self.counters["dropped_overflow"] += 1
        self._pending.append(skeleton)
        return []

    def on_palm(self, stamp: float) -> list:
        """The sequencer passed on the palm frame stamped ``stamp``: the skeletons of that
        frame (older waiting ones are dropped: their frames were not passed on)."""
        self._released.append(stamp)
        out, keep = [], []
        for skeleton in self._pending:
            if skeleton.stamp == stamp:
                out.append(skeleton)
            elif skeleton.stamp < stamp:
                self.counters["dropped_with_palm"] += 1
            else:
                keep.append(skeleton)
        self._pending.clear()
        self._pending.extend(keep)
        self.counters["passed"] += len(out)
        return out
