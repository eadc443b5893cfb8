"""A blocking move stopped from another thread, the experiment every STOP test runs: the
rostest check (hw_stop_check, through ROS), the unit tests (tests/unit/stop_helpers, in
process) and the STOP benchmark (bench/stop_bench.py, timing it). Plain Python, no ROS:
importable wherever this folder is on ``sys.path``.
"""

import threading
import time

import numpy as np

__all__ = ["HOME", "LONG", "wait_for", "MoveInThread", "stop_during"]

HOME = np.array([0.0, -1.5707963, 1.5707963, -1.5707963, -1.5707963, 0.0])
LONG = HOME + [2.8, 0.0, 0.0, 0.0, 0.0, 0.0]  # ~3 s of MoveJ on either driver


def wait_for(predicate, timeout=3.0, period=0.002):
    """Poll ``predicate`` until true or ``timeout`` s; return whether it became true."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(period)
    return False


class MoveInThread:
    """``move()`` in a background thread; records what it returned (``result``) or raised
    (``error``) and when it returned (``returned_at``, time.monotonic)."""

    def __init__(self, move):
        self.result = None
        self.error = None
        self.returned_at = None
        self._thread = threading.Thread(target=self._run, args=(move,), daemon=True)
        self._thread.start()

    def _run(self, move):
        try:
            self.result = move()
        except Exception as exc:  # the caller inspects it
            self.error = exc
        self.returned_at = time.monotonic()

    def join(self, timeout=10.0):
        self._thread.join(timeout)
        assert not self._thread.is_alive(), "the move never returned"
        return self


def stop_during(move, started, stop, timeout=10.0, start_timeout=5.0):
    """Start ``move`` in a thread, wait (up to ``start_timeout`` s) until ``started()``, call
    ``stop()``; return (the finished MoveInThread, time.monotonic of the stop call, seconds
    stop() itself took). The move must return within ``timeout`` s of the stop."""
    runner = MoveInThread(move)
    assert wait_for(started, start_timeout), "the move never started"
    stop_at = time.monotonic()
    stop()
    stop_took = time.monotonic() - stop_at
    runner.join(timeout)
    return runner, stop_at, stop_took
