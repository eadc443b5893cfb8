"""The page's event log: what happened in the session, newest first, bounded.

Callers note events (a gesture, a stop, a status change, a refused input, a pick); an
event identical to the last one of its kind within ``repeat_s`` is counted on that entry
instead of added (a held gesture reported at frame rate is one line, "x12").
``changed(key, value)`` tells whether a watched value differs from the last one seen, so
that only changes of a status are logged. Plain Python.
"""

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["Event", "EventLog"]


@dataclass
class Event:
    """One line of the log: when (wall clock, s), what kind, what, how often in a row."""

    t: float
    kind: str
    text: str
    count: int = 1

    def line(self) -> str:
        """The line as the page shows it (local time of day)."""
        stamp = time.strftime("%H:%M:%S", time.localtime(self.t))
        repeat = f" (x{self.count})" if self.count > 1 else ""
        return f"{stamp}  {self.kind:<8} {self.text}{repeat}"


class EventLog:
    """At most ``max_events`` events; ``clock`` (wall time) is injectable for tests."""

    def __init__(self, max_events: int = 200, repeat_s: float = 2.0, clock: Callable[[], float] = time.time):
        if max_events < 1:
            raise ValueError("EventLog needs max_events >= 1")
        self._events = deque(maxlen=int(max_events))
        self._last_by_kind = {}
        self._watched = {}
        self.repeat_s = float(repeat_s)
        self._clock = clock
        self.version = 0  # bumped on every change, so a page redraws only when needed

    def add(self, kind: str, text: str) -> None:
        """Record an event now (or count it on the same event of the same kind just before)."""
        now = self._clock()
        last = self._last_by_kind.get(kind)
        if last is not None and last.text == text and now - last.t <= self.repeat_s and last in self._events:
            last.count += 1
            last.t = now
        else:
            event = Event(now, kind, text)
            self._events.append(event)
            self._last_by_kind[kind] = event
        self.version += 1

    def changed(self, key: str, value) -> bool:
        """True when ``value`` differs from the last one seen under ``key`` (the first value
        counts as a change); remembers it."""
        missing = object()
        if self._watched.get(key, missing) == value:
            return False
        self._watched[key] = value
        return True

    def newest_first(self, limit: int | None = None) -> list[Event]:
        """The events, newest first (at most ``limit``)."""
        events = list(reversed(self._events))
        return events if limit is None else events[:limit]

    def __len__(self) -> int:
        return len(self._events)
