"""The last few messages of a stamped stream, and its value at a given time (plain Python:
the recorder node feeds it, tests feed it directly).

A recorded frame stands for one instant, yet the newest message of a 100 Hz stream is
anywhere from 0 to 10 ms old when a frame is made, and the newest command 0-9 ms: at the
tool's 0.6 m/s in the teach demo, up to 6 mm between the recorded state and the recorded
action of one frame, which a replay cannot reproduce. So the recorder makes each frame a
little after its instant (``delay``) and takes the measured joints, the tool and the
core's command and target at that instant, linearly between the two messages stamped
around it (the stamps are the driver's sample time and the hand frame's time; quaternions
normalised after the blend). A stream with nothing after the instant (idle, or late) gives
its newest value before it; one with nothing before gives its oldest.
"""

from collections import deque

import numpy as np

__all__ = ["StampedHistory", "blend", "rate_between"]


def blend(before: np.ndarray, after: np.ndarray, u: float, quaternion: slice | None = None) -> np.ndarray:
    """``before`` + u (``after`` - ``before``); the ``quaternion`` part normalised, with
    ``after`` flipped to ``before``'s hemisphere first."""
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    if quaternion is not None and float(np.dot(before[quaternion], after[quaternion])) < 0:
        after = after.copy()
        after[quaternion] = -after[quaternion]
    out = before + (after - before) * u
    if quaternion is not None:
        norm = np.linalg.norm(out[quaternion])
        if norm > 0:
            out[quaternion] = out[quaternion] / norm
    return out


def rate_between(before: np.ndarray, after: np.ndarray, stamp_before: float, stamp_after: float) -> np.ndarray:
    """(``after`` - ``before``) per second between two stamped samples: the velocity a
    stream without one (a driver's joint_states carry positions only) had between them;
    zeros when both are the same sample (an end of the history)."""
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    dt = float(stamp_after) - float(stamp_before)
    return (after - before) / dt if dt > 0 else np.zeros_like(after)


class StampedHistory:
    """(stamp, item) in stamp order, the last ``maxlen``."""

    def __init__(self, maxlen: int = 12):
        self._items = deque(maxlen=maxlen)

    def __len__(self) -> int:
        return len(self._items)

    def add(self, stamp: float, item) -> bool:
        """Keep ``item``; False (dropped) when stamped before the newest kept."""
        if self._items and stamp < self._items[-1][0]:
            return False
        self._items.append((float(stamp), item))
        return True

    def newest(self):
        return self._items[-1] if self._items else None

    def around(self, moment: float):
        """((stamp, item) before or at ``moment``, (stamp, item) after it, u in [0, 1]);
        at either end of the history, both are the same message. None when empty."""
        if not self._items:
            return None
        previous = None
        for entry in self._items:
            if entry[0] > moment:
                if previous is None:
                    return entry, entry, 0.0
                span = entry[0] - previous[0]
                return previous, entry, (moment - previous[0]) / span if span > 0 else 1.0
            previous = entry
        return previous, previous, 0.0
