"""The recorder's frame clock (plain Python: the clock and the wait are injected, so it is
tested without ROS).

Frames are made at ticks ``start + k * period``. A caller held up past a tick (a loaded
machine) gets the ticks it missed at once, one a call, up to the last ``catch_up`` of them,
so that a recorder whose streams keep their last messages makes each missed frame at its
own instant (``motion_apps.stamped_history``) instead of leaving a gap in time that the
episode's fixed rate would hide: a frame skipped puts the next one a period earlier than its
instant, and a replay lags there by the arm's travel in a period. Older missed ticks are
skipped. Both are counted (``made_up``, ``skipped``).
"""

import math
import threading
import time

__all__ = ["FramePacer"]


class FramePacer:
    """Ticks every ``period`` s from ``start``; up to ``catch_up`` missed ticks made up."""

    def __init__(self, period: float, clock=time.monotonic, start: float | None = None, event=None, catch_up: int = 0):
        if period <= 0 or catch_up < 0:
            raise ValueError(f"frame period {period} s and catch_up {catch_up}: period > 0, catch_up >= 0")
        self.period = float(period)
        self.clock = clock
        self.start = clock() if start is None else float(start)
        self._stopped = event if event is not None else threading.Event()
        self._next = self.start + self.period
        self.catch_up = int(catch_up)
        self.made_up = 0  # ticks returned late by a period or more
        self.skipped = 0  # ticks never returned (the caller was later than catch_up ticks)

    def next_tick(self, now: float) -> float:
        """The first tick strictly after ``now``."""
        return self.start + (math.floor((now - self.start) / self.period) + 1) * self.period

    def wait_tick(self) -> float | None:
        """Sleep until the next tick; its time, or None once stopped. Of the ticks missed
        while the caller was late, the last ``catch_up`` are returned at once, one a call;
        the older ones are skipped."""
        now = self.clock()
        if self._next <= now - self.period:
            oldest = self.next_tick(now) - self.catch_up * self.period
            if self._next < oldest - 1e-9:
                self.skipped += int(round((oldest - self._next) / self.period))
                self._next = oldest
            if self._next <= now - self.period:
                self.made_up += 1
        tick, wait = self._next, self._next - now
        if wait > 0 and self._stopped.wait(wait):
            return None
        self._next += self.period
        return None if self._stopped.is_set() else tick

    def stop(self) -> None:
        """Wake the ticking thread, for good."""
        self._stopped.set()
