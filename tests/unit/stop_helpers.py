"""Shared by the STOP tests: run a blocking move in a thread and stop it from another."""
import threading
import time


def wait_for(predicate, timeout=3.0, period=0.002):
    """Poll ``predicate`` until true or ``timeout`` s; return whether it became true."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(period)
    return False


class MoveInThread:
    """``move()`` in a background thread; records its exception and when it returned."""

    def __init__(self, move):
        self.error = None
        self.returned_at = None
        self._thread = threading.Thread(target=self._run, args=(move,), daemon=True)
        self._thread.start()

    def _run(self, move):
        try:
            move()
        except Exception as exc:  # the tests inspect it
            self.error = exc
        self.returned_at = time.monotonic()

    def join(self, timeout=10.0):
        self._thread.join(timeout)
        assert not self._thread.is_alive(), "the move never returned"
        return self


def stop_during(move, started, stop, timeout=10.0):
    """Start ``move`` in a thread, wait until ``started()``, call ``stop()``; return
    (the finished MoveInThread, time of the stop call, seconds stop() itself took)."""
    runner = MoveInThread(move)
    assert wait_for(started, 5.0), "the move never started"
    stop_at = time.monotonic()
    stop()
    stop_took = time.monotonic() - stop_at
    runner.join(timeout)
    return runner, stop_at, stop_took
