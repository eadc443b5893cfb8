"""A FOLLOW_PATH call its caller can leave early without leaving the arm moving for nobody.

The call blocks until the arm reaches the path's end, so it runs on a thread of its own
and the caller waits on ``finished``, an Event: Python 3.11.2's ``Thread.join``,
interrupted by Ctrl-C, marks the thread stopped while it still waits for the path
(``is_alive()`` then lies), and an Event does not.

A caller that leaves early (Ctrl-C, an error of its own) calls ``stop_until_answered``.
One STOP is not enough: a long path takes tens of milliseconds on the wire, and a STOP
that arrives before the server has the path finds nothing to stop; the path then runs to
its end (one that arrives while the server checks the path keeps it from starting). So
STOP goes out again every ``every_s`` until the path's call answers, and never after it
answered: a STOP stops all motion on the server, whoever sent it, so one sent then could
stop another client's move (as one sent while the path is still on the wire can).
``most_s`` bounds the wait for a server that does not answer; a STOP call that hangs is
not bounded by it.

Plain Python: the service call and the STOP are callables (``MotionControllerClient``'s
``follow_path`` and ``stop`` in the nodes, stand-ins in the tests).
"""

import threading
import time

__all__ = ["PathCall"]


class PathCall:
    """``follow_path(times, joints)`` on its own thread (``start``); ``finished`` is set
    when it answered, ``result()`` is what it returned or raises what it raised."""

    def __init__(self, follow_path, times, joints, clock=time.monotonic):
        self._follow_path = follow_path
        self._times = times
        self._joints = joints
        self._clock = clock
        self._outcome = {}
        self.finished = threading.Event()
        self.started = False
        self._thread = threading.Thread(target=self._run, name="follow-path", daemon=True)

    def _run(self):
        try:
            self._outcome["started"] = self._follow_path(self._times, self._joints)
        except Exception as exc:  # noqa: BLE001 - handed to the caller's thread by result()
            self._outcome["error"] = exc
        finally:
            self.finished.set()

    def start(self) -> None:
        # Marked before the thread starts: a Ctrl-C between the two must still STOP.
        self.started = True
        self._thread.start()

    @property
    def failed(self) -> bool:
        """The call answered with an error (refused, interrupted, no server)."""
        return "error" in self._outcome

    def result(self) -> float:
        """What ``follow_path`` returned (when the path started); raises what it raised.
        Only once ``finished`` is set."""
        if not self.finished.is_set():
            raise RuntimeError("the path's call has not answered yet")
        if "error" in self._outcome:
            raise self._outcome["error"]
        return self._outcome["started"]

    def stop_until_answered(self, stop, log, every_s: float = 0.2, most_s: float = 5.0) -> int:
        """STOP the path (``stop()``) every ``every_s`` until its call answered, for at
        most ``most_s``; the number of STOPs that went out. A STOP that fails is logged
        (``log``) and ends the attempt. A further Ctrl-C meanwhile does not end it: the
        user pressing it again is the user who wants the arm stopped. What became of the
        path is ``describe()``'s."""
        if not self.started:
            return 0
        sent = 0
        deadline = self._clock() + most_s
        while not self.finished.is_set() and self._clock() <= deadline:
            try:
                stop()
                sent += 1
                self.finished.wait(every_s)
            except KeyboardInterrupt:
                log(f"still stopping the path (at most {most_s:g} s)")
            except Exception as exc:  # noqa: BLE001 - the caller's own reason to leave is the one it raises
                log(f"could not STOP the path ({exc})")
                break
        return sent

    def describe(self) -> str:
        """What became of the path, for the user of a call left early."""
        if not self.started:
            return "no path was sent"
        if not self.finished.is_set():
            return "the path did not answer: the server may follow it to its end"
        if "error" in self._outcome:
            return f"the path answered: {self._outcome['error']}"
        return "the path had already ended"
