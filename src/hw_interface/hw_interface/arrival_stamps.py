"""When a controller sampled its joint states, estimated from when they arrived (plain
Python: the simple_message driver feeds it arrival times, tests feed it their own).

A ROS-Industrial controller sends JOINT_POSITION states at a steady rate with no time of
its own. Stamped on receipt, a state that waited for a busy reader thread carries a late
stamp, and the next one, on time, a stamp a fraction of a period after it: speeds taken
from consecutive /joint_states (position difference over stamp difference) then read
several times the arm's true speed. A steady sender's sample times are the lower envelope
of the arrivals: each state is stamped no later than the previous stamp plus a period (the
median of recent arrival spacings, each read's spacing shared among the states it
brought), and never earlier than its arrival less ``max_delay_periods`` periods (a real
pause of the sender, or a change of its rate, costs at most that). The period is taken
with a little slack, so that stamps left behind by a pause catch up with the arrivals
(1 % of a period a state); the same slack is what a reader's stall may still add to the
next state's apparent speed, 1 % for each state the stall delayed.
"""

from collections import deque

import numpy as np

__all__ = ["ArrivalStamps"]


class ArrivalStamps:
    """Sample times (s) of a periodic sender's messages from their arrival times (s, one
    monotonic clock). Memory is bounded by ``window`` spacings."""

    def __init__(self, window: int = 50, slack: float = 1.01, max_delay_periods: float = 3.0, min_spacings: int = 10):
        if window < 3 or slack < 1.0 or max_delay_periods <= 0 or not 1 <= min_spacings <= window:
            raise ValueError(
                f"ArrivalStamps: window {window} (>= 3), slack {slack} (>= 1), max_delay_periods "
                f"{max_delay_periods} (> 0) and min_spacings {min_spacings} (1..window) are out of range"
            )
        self.slack = float(slack)
        self.max_delay_periods = float(max_delay_periods)
        self.min_spacings = int(min_spacings)
        self._spacings = deque(maxlen=int(window))
        self._arrival = None
        self._stamp = None

    def reset(self) -> None:
        """Forget the sender (a new connection)."""
        self._spacings.clear()
        self._arrival = self._stamp = None

    @property
    def period(self) -> float:
        """The sender's period (s) as estimated, 0 while unknown."""
        if len(self._spacings) < self.min_spacings:
            return 0.0
        return float(np.median(self._spacings))

    def stamps(self, arrival: float, count: int = 1) -> list[float]:
        """The estimated sample times of ``count`` messages read together at ``arrival``,
        oldest first."""
        if count < 1:
            return []
        arrival = float(arrival)
        if self._arrival is not None:
            arrival = max(arrival, self._arrival)  # arrival order wins
            self._spacings.append((arrival - self._arrival) / count)
        self._arrival = arrival
        period = self.period
        out = []
        for _ in range(count):
            stamp = arrival
            if self._stamp is not None and period > 0.0:
                stamp = min(arrival, self._stamp + period * self.slack)
                stamp = max(stamp, arrival - period * self.max_delay_periods, self._stamp)
            self._stamp = stamp
            out.append(stamp)
        return out
