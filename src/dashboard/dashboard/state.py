"""The dashboard's state: ROS callbacks write it from their threads, the page reads
snapshots from the web server's thread. One lock; a snapshot is a plain dict copy."""

import copy
import threading
import time
from collections.abc import Callable

from .path_buffer import PathBuffer
from .readings import LatencyWindow


class DashboardState:
    """Thread-safe store of everything the page shows.

    ``set(key, value)`` records a value and when it arrived (``clock``, injectable for
    tests); ``snapshot()`` returns every value, its age in seconds, the latency
    percentiles and the plot's path series.
    """

    def __init__(
        self,
        clock: Callable[[], float] = time.monotonic,
        path_points: int = 400,
        path_interval_s: float = 0.05,
        latency_window: int = 500,
    ):
        self._clock = clock
        self._lock = threading.Lock()
        self._values = {}
        self._stamps = {}
        self._paths = PathBuffer(path_points, path_interval_s)
        self._latency = LatencyWindow(latency_window)

    def set(self, key: str, value) -> None:
        """Record ``value`` under ``key`` now."""
        with self._lock:
            self._values[key] = value
            self._stamps[key] = self._clock()

    def update(self, **values) -> None:
        """Record several values at once."""
        with self._lock:
            now = self._clock()
            for key, value in values.items():
                self._values[key] = value
                self._stamps[key] = now

    def get(self, key: str, default=None):
        """One value (a copy-free read: callers must not mutate it)."""
        with self._lock:
            return self._values.get(key, default)

    def age(self, key: str) -> float | None:
        """Seconds since ``key`` was last set, or None if never."""
        with self._lock:
            stamp = self._stamps.get(key)
            return None if stamp is None else self._clock() - stamp

    def add_path_point(self, name: str, t: float, position) -> None:
        """A point of the hand ('hand') or tool ('tool') path."""
        with self._lock:
            self._paths.add(name, t, position)

    def clear_paths(self) -> None:
        """Empty the plot."""
        with self._lock:
            self._paths.clear()

    def add_latency(self, seconds: float) -> None:
        """One command's sensor-to-driver latency."""
        with self._lock:
            self._latency.add(seconds)

    def snapshot(self) -> dict:
        """Everything, copied: {'values', 'ages', 'latency_ms', 'paths'}."""
        with self._lock:
            now = self._clock()
            return {
                "values": copy.deepcopy(self._values),
                "ages": {key: now - stamp for key, stamp in self._stamps.items()},
                "latency_ms": self._latency.percentiles_ms(),
                "paths": self._paths.series(),
            }
