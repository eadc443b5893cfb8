"""The recorder's frame clock, and when its fast streams need to be read at all (plain
Python: the clock and the wait are injected, so it is tested without ROS).

Frames are made at ticks ``start + k * period``, each from the newest value of every
stream. A stream at 100 Hz sampled at 10 Hz needs only the messages just before a tick, yet
rospy wakes the subscriber's thread for every message (~10 wake-ups a frame a topic, most
of recording's CPU). ``hold()``, called from a subscriber's callback (which runs in that
topic's own receive thread), sleeps until ``window`` s before the next tick: meanwhile the
messages wait in the socket, and the first read after the hold takes them all at once
(rospy keeps the last ``queue_size``). From then until the tick the thread reads every
message as usual, so the value at the tick is as fresh as without the hold; right after the
tick it holds again. A thread woken late (a loaded machine) would leave the tick a whole
frame behind, so the tick first waits (``caught_up``, a few ms at most) for every stream
still holding for this tick's window. About 2-3 wake-ups a frame remain.
"""

import math
import threading
import time

__all__ = ["FramePacer"]


class FramePacer:
    """Ticks every ``period`` s from ``start``; streams read ``window`` s before each tick."""

    def __init__(
        self,
        period: float,
        window: float,
        clock=time.monotonic,
        start: float | None = None,
        event=None,
        catch_up: int = 0,
    ):
        if period <= 0 or window < 0:
            raise ValueError(f"frame period {period} s and read window {window} s: period > 0, window >= 0")
        self.period = float(period)
        self.window = float(window)
        self.clock = clock
        self.start = clock() if start is None else float(start)
        self._stopped = event if event is not None else threading.Event()
        self._next = self.start + self.period
        self.catch_up = int(catch_up)  # missed ticks made up, at most, after a late call
        self.made_up = 0  # ticks returned late by a period or more (made up)
        self.skipped = 0  # ticks never returned (the caller was later than catch_up ticks)
        self._held = {}  # window opening time -> streams holding for it
        self._changed = threading.Condition()

    def next_tick(self, now: float) -> float:
        """The first tick strictly after ``now``."""
        return self.start + (math.floor((now - self.start) / self.period) + 1) * self.period

    def hold_s(self, now: float) -> float:
        """How long a stream can stay unread from ``now`` (0 inside a tick's window)."""
        return max(0.0, self.next_tick(now) - self.window - now)

    def hold(self, stamp: float | None = None) -> None:
        """Sleep (in a subscriber's thread) until the next tick's window opens, or stop.
        With the message's ``stamp`` (this clock), a message from before the last tick does
        not hold: the thread is reading what waited in its socket since then (it woke late,
        or the message came late), and the messages after it are wanted too."""
        now = self.clock()
        wait = self.hold_s(now)
        if wait <= 0 or (stamp is not None and stamp < self.next_tick(now) - self.period):
            return
        opens = now + wait
        with self._changed:
            self._held[opens] = self._held.get(opens, 0) + 1
        try:
            self._stopped.wait(wait)
        finally:
            with self._changed:
                self._held[opens] -= 1
                if not self._held[opens]:
                    del self._held[opens]
                self._changed.notify_all()

    def late(self, tick: float) -> int:
        """Streams still holding although ``tick``'s window has opened (woken late)."""
        with self._changed:
            return self._late(tick)

    def caught_up(self, tick: float, timeout: float) -> bool:
        """Wait up to ``timeout`` s until no stream is late for ``tick`` (True) or give up."""
        with self._changed:
            return self._changed.wait_for(lambda: self._stopped.is_set() or not self._late(tick), timeout)

    def _late(self, tick: float) -> int:
        return sum(n for opens, n in self._held.items() if opens <= tick - self.window + 1e-6)

    def wait_tick(self) -> float | None:
        """Sleep until the next tick; its time, or None once stopped. Of the ticks missed
        while the caller was late, the last ``catch_up`` are returned at once, one a call
        (made up: a recorder whose streams keep their history makes their frames at their
        own instants, instead of leaving a gap in time that the frames' fixed rate hides),
        the older ones skipped."""
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
        """Wake every holding stream and the ticking thread, for good."""
        self._stopped.set()
        with self._changed:
            self._changed.notify_all()
