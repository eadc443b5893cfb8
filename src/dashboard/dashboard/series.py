"""Time series for the page's charts: bounded windows of (t, value), thinned in time, and
the session's three curves (teleop status, latency, tracking error). Plain Python.

Every window is a deque with a maxlen: a session running for days keeps the same memory.
"""

import math
from collections import deque

__all__ = ["SeriesWindow", "Telemetry", "tracking_error_m"]


class SeriesWindow:
    """The last ``max_points`` samples of one quantity, at most one per ``min_interval_s``
    (a 500 Hz stream costs the chart what a 10 Hz one does)."""

    def __init__(self, max_points: int = 600, min_interval_s: float = 0.1):
        if max_points < 2 or min_interval_s < 0:
            raise ValueError("SeriesWindow needs max_points >= 2 and min_interval_s >= 0")
        self.min_interval_s = float(min_interval_s)
        self._points = deque(maxlen=int(max_points))

    def add(self, t: float, value: float, force: bool = False) -> bool:
        """Keep (t, value) unless it is not finite or too close in time to the last kept
        sample (``force``: keep it anyway, e.g. a status change must show); True if kept."""
        value = float(value)
        if not math.isfinite(value):
            return False
        if self._points and not force and t - self._points[-1][0] < self.min_interval_s:
            return False
        self._points.append((float(t), value))
        return True

    def __len__(self) -> int:
        return len(self._points)

    def last(self):
        """The newest (t, value), or None."""
        return self._points[-1] if self._points else None

    def relative(self, now: float) -> list[list[float]]:
        """[[t - now (s, <= 0), value], ...], oldest first: the chart's x axis ends at now."""
        return [[round(t - now, 3), v] for t, v in self._points]

    def clear(self) -> None:
        """Forget every sample."""
        self._points.clear()


def tracking_error_m(target, tool) -> float:
    """Distance (m) between the commanded hand target and the measured tool position."""
    return math.dist(tuple(float(v) for v in target), tuple(float(v) for v in tool))


class Telemetry:
    """The three curves of the time-series chart.

    - ``status``: the teleop status code, one sample per change (and a repeat at most
      every ``min_interval_s`` so the step line reaches now);
    - ``latency_ms``: sensor-to-driver latency per command, thinned;
    - ``tracking_mm``: distance from the last target to the tool, taken when a tool pose
      arrives and the target is at most ``target_max_age_s`` older (a stale target while
      disengaged is no tracking error).
    """

    NAMES = ("status", "latency_ms", "tracking_mm")

    def __init__(self, max_points: int = 600, min_interval_s: float = 0.1, target_max_age_s: float = 0.5):
        self.series = {name: SeriesWindow(max_points, min_interval_s) for name in self.NAMES}
        self.target_max_age_s = float(target_max_age_s)
        self._target = None  # (t, xyz)

    def add_status(self, t: float, code: int) -> None:
        """One status message (kept when it changes, else thinned)."""
        last = self.series["status"].last()
        self.series["status"].add(t, int(code), force=last is None or last[1] != int(code))

    def add_latency(self, t: float, seconds: float) -> None:
        """One command's latency in seconds (negative values are not latencies)."""
        if seconds >= 0.0:
            self.series["latency_ms"].add(t, 1000.0 * seconds)

    def add_target(self, t: float, xyz) -> None:
        """The hand target (m, base frame)."""
        self._target = (float(t), tuple(float(v) for v in xyz))

    def add_tool(self, t: float, xyz) -> None:
        """The measured tool position (m, base frame): one tracking-error sample."""
        if self._target is None or t - self._target[0] > self.target_max_age_s:
            return
        self.series["tracking_mm"].add(t, 1000.0 * tracking_error_m(self._target[1], xyz))

    def relative(self, now: float) -> dict[str, list[list[float]]]:
        """name -> [[t - now, value], ...]."""
        return {name: window.relative(now) for name, window in self.series.items()}
