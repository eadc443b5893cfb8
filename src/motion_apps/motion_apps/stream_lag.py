"""How long an arm trails the stream of joint targets it is being sent, measured while the
stream runs from the arm's own stamped joint samples (plain Python: the replay feeds it
what it sends, the replay node what the server publishes; tests feed it directly).

A replay of the recorded joint path must run ahead by the lag of the arm that REPLAYS it:
the recorded episode's own lag (its actions against its states) is the recording
machine's, and it moved with that machine's load (10.5 ms for one episode of the demo,
12.1-12.4 for the two others, all recorded on the same simulation), while the replaying
arm trailed its stream by 12.0-12.5 ms (11.5 at under 0.8 rad/s, 13.0 above 1.2) on a
loaded machine. Two milliseconds short at the save circle's 0.5-0.6 m/s put the tool
1-1.5 mm behind at every fast frame and over 2 mm with the timing's jitter on top.

Estimate: with the targets sent, linear between their send moments, and each measured
sample's joints and velocity (from the sample before), each moving sample's own lag (those
with a joint faster than ``min_speed``) is the least-squares ``lag`` in ``target - joints
= velocity * lag``, and the arm's is their median over the last ``window`` samples,
weighted by the squared speed: the recorded lag's estimate, on the live arm. A median, not
one least squares over the window: on a busy machine the client or the server stalls for
20-80 ms now and then, the arm falls that far behind its stream for a few samples, and a
least squares over the window took them in (a lead of 18.9 ms at the end of one replay
against the arm's 12-13, 2.3-4 mm ahead at every fast frame after).
"""

import threading
from collections import deque

import numpy as np

from .stamped_history import StampedHistory

__all__ = ["StreamLag"]


class StreamLag:
    """``start_s``: the lag assumed until enough motion was measured (``min_power``: the
    sum of squared joint speeds, (rad/s)^2, over the samples used); at most ``most_s``.
    ``sent`` and ``measured`` take moments on one clock; safe to call from two threads."""

    def __init__(
        self,
        start_s: float,
        window: int = 200,
        min_speed: float = 0.3,
        min_power: float = 5.0,
        most_s: float = 0.1,
    ):
        self.start_s = float(start_s)
        self.min_speed = float(min_speed)
        self.min_power = float(min_power)
        self.most_s = float(most_s)
        self._sent = StampedHistory(maxlen=400)  # 4 s at the replay's 100 Hz
        self._terms = deque(maxlen=window)  # (the sample's own lag, velocity . velocity) per moving sample
        self._previous = None  # (moment, joints) of the last sample taken in
        # Samples not taken in yet: each waits for a target sent after it. The server's
        # samples and the replay's sends are both 100 Hz; at some phases every sample came
        # just before the next send, and a sample judged on arrival was never used.
        self._waiting = deque(maxlen=50)
        self._lock = threading.Lock()

    def sent(self, moment: float, target) -> None:
        """A target the stream sent at ``moment``."""
        with self._lock:
            self._sent.add(moment, np.asarray(target, dtype=np.float64))
            self._take_in()

    def measured(self, moment: float, joints) -> bool:
        """The arm's joints measured at ``moment`` (the state's own stamp); False (and not
        used) for a sample that is empty or not finite, whose velocity would be no number."""
        joints = np.asarray(joints, dtype=np.float64)
        if joints.size == 0 or not np.all(np.isfinite(joints)) or not np.isfinite(moment):
            return False
        with self._lock:
            self._waiting.append((float(moment), joints))
            self._take_in()
        return True

    def _take_in(self) -> None:
        """Each waiting sample with a target sent after it, in order (caller holds the lock)."""
        newest = self._sent.newest()
        while self._waiting:
            moment, joints = self._waiting[0]
            previous = self._previous
            if previous is None or moment <= previous[0] or previous[1].shape != joints.shape:
                self._previous = self._waiting.popleft()
                continue
            middle = previous[0] + 0.5 * (moment - previous[0])  # the velocity is the one between the two
            if newest is None or newest[0] <= middle:
                return  # no target after it yet
            self._previous = self._waiting.popleft()
            self._add_term(previous, moment, joints, middle)

    def _add_term(self, previous, moment: float, joints, middle: float) -> None:
        velocity = (joints - previous[1]) / (moment - previous[0])
        if float(np.max(np.abs(velocity))) < self.min_speed:
            return
        found = self._sent.around(middle)
        if found is None or found[0][0] > middle:
            return  # no target sent before the sample: not in the stream
        (_, before), (_, after), u = found
        if before.shape != joints.shape:
            return
        behind = before + (after - before) * u - 0.5 * (joints + previous[1])
        power = float(np.dot(velocity, velocity))
        self._terms.append((float(np.dot(behind, velocity)) / power, power))

    def lag_s(self) -> float:
        """The measured lag (s), or ``start_s`` while too little motion was measured."""
        with self._lock:
            terms = np.asarray(self._terms) if self._terms else np.zeros((0, 2))
        terms = terms[np.all(np.isfinite(terms), axis=1)]
        if terms[:, 1].sum() < self.min_power:
            return self.start_s
        terms = terms[np.argsort(terms[:, 0])]
        half = np.searchsorted(np.cumsum(terms[:, 1]), 0.5 * terms[:, 1].sum())
        return min(max(float(terms[half, 0]), 0.0), self.most_s)

    @property
    def measuring(self) -> bool:
        """True once the lag comes from the arm (enough motion measured)."""
        with self._lock:
            power = sum(term[1] for term in self._terms)
        return power >= self.min_power
