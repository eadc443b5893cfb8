"""When the core does its between-frames work: shortly before the next frame is due.

TeleopCore.prepare_next() computes what the next frame needs that does not depend on its
hand pose (the IK's first step at its seed, the command's condition number and tool pose).
Done right after a command, that work is ~9 ms old when the next frame of a 110 Hz stream
arrives, and on a machine whose caches and clocks have gone cold meanwhile the frame pays
again for bringing the interpreter, numpy, pinocchio and LAPACK back in. Done ``lead_s``
before the frame is due, the same work leaves them warm for it (bench/e2e_latency
--breakdown: the core's per-frame cost after a 110 Hz gap, both ways).

The next arrival is predicted from the median of recent inter-arrival intervals, so a
device's own rate (Leap 110 Hz, SpaceMouse, a camera) is learnt, and one late or early
frame does not move the prediction. Plain Python (no ROS): the node owns the thread.
"""

from collections import deque

from .errors import MotionCommanderError


class PrepareTiming:
    """Predicts when to prepare the next frame's work from the frames' arrival times (s, any
    monotonic clock).

    ``lead_s``: how long before the predicted arrival to prepare (0: never scheduled, the
    caller prepares right after each command). ``window``: intervals in the median.
    Intervals longer than ``max_interval_s`` (the hand left, the stream paused) are not
    a frame period and are ignored.
    """

    def __init__(self, lead_s: float, window: int = 15, max_interval_s: float = 0.1):
        if not lead_s >= 0:
            raise MotionCommanderError(f"prepare lead must be >= 0 s, got {lead_s!r}")
        if window < 1 or not max_interval_s > 0:
            raise MotionCommanderError("prepare timing needs window >= 1 and max_interval_s > 0")
        self.lead_s = float(lead_s)
        self.max_interval_s = float(max_interval_s)
        self._intervals = deque(maxlen=window)
        self._last_arrival: float | None = None

    def on_frame(self, arrival: float) -> None:
        """Record that a frame arrived at ``arrival``."""
        if self._last_arrival is not None:
            interval = arrival - self._last_arrival
            if 0.0 < interval <= self.max_interval_s:
                self._intervals.append(interval)
        self._last_arrival = arrival

    @property
    def period(self) -> float | None:
        """The median recent frame interval (s); None until three intervals are known."""
        if len(self._intervals) < 3:
            return None
        ordered = sorted(self._intervals)
        return ordered[len(ordered) // 2]

    def prepare_at(self) -> float | None:
        """When to prepare for the next frame: ``lead_s`` before it is due, on the arrival
        clock. None: prepare at once (no lead configured, the rate not known yet, or the
        period too short for the lead)."""
        period = self.period
        if not self.lead_s or period is None or period <= 2.0 * self.lead_s:
            return None
        return self._last_arrival + period - self.lead_s
