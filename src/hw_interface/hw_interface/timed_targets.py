"""Streamed targets applied at the simulated moment they arrived, not when the physics
thread next gets the CPU (plain Python: the simulation driver feeds it, tests feed it with
their own times).

The simulated arm is stepped in real time by a thread of its own; on a busy machine the
thread wakes late and runs the steps it owes back to back, each stamped with its scheduled
time. Applying the newest streamed target to every step of such a burst gave the steps
scheduled before that target arrived a target from their future, and a stream of a fast
motion moved the arm early by the thread's delay (on a 2-core machine with one core kept
busy, steps ran up to 25 ms late). Each target is kept with its arrival time instead, and a
step applies the newest one that had arrived by the step's scheduled start: a late thread
then moves the arm exactly as an on-time one would have.
"""

from collections import deque

__all__ = ["TimedTargets"]


class TimedTargets:
    """Targets by arrival time, the last ``maxlen`` (a bounded queue: a thread that is
    more than ``maxlen`` targets behind applies the newest ones)."""

    def __init__(self, maxlen: int = 256):
        self._queue = deque(maxlen=maxlen)

    def __len__(self) -> int:
        return len(self._queue)

    def add(self, arrival: float, target) -> None:
        """A target that arrived at ``arrival`` (s, the clock of the steps' schedule); one
        stamped before the newest kept is kept at the newest's time (arrival order wins)."""
        if self._queue and arrival < self._queue[-1][0]:
            arrival = self._queue[-1][0]
        self._queue.append((float(arrival), target))

    def due(self, moment: float):
        """The newest target that had arrived by ``moment`` (None: none since the last
        call); it and every older one leave the queue."""
        found = None
        while self._queue and self._queue[0][0] <= moment:
            found = self._queue.popleft()[1]
        return found

    def clear(self) -> None:
        """Forget every queued target (a STOP, a move, a reset: none may be applied after it)."""
        self._queue.clear()
