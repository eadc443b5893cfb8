"""The last few messages of a stamped stream, and where a given time lies among them (plain
Python: the recorder node and the replay feed it, tests feed it directly).

A recorded frame stands for one instant, yet the newest message of a 100 Hz stream is
anywhere from 0 to 10 ms old when a frame is made: at the tool's 0.6 m/s in the teach demo,
up to 6 mm between the recorded state and the recorded action of one frame, which a replay
cannot reproduce. So the producers send their value at each frame's instant, blended
between their two samples stamped around it (``motion_common.frame_blend``), and the
recorder keeps those messages by stamp and takes the one for its instant; the replay blends
the server's stamped tool poses at the moment each frame's targets go out. A stream with
nothing after the instant (idle, or late) gives its newest value before it; one with
nothing before gives its oldest.
"""

from collections import deque

__all__ = ["StampedHistory"]


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
