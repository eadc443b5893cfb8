"""PathCall: a FOLLOW_PATH call on its own thread, STOPped until it answers when left early."""

import threading

import pytest

from hw_interface.errors import HwInterfaceError
from hw_interface.path_call import PathCall
from hw_interface.protocol import Result


class OnTheWire:
    """A server whose path arrives only after ``late`` STOPs: the STOPs before it find
    nothing to stop; the first one after it cuts the path (INTERRUPTED)."""

    def __init__(self, late: int):
        self.late = late
        self.stops = 0
        self.arrived = threading.Event()
        self.cut = threading.Event()

    def follow_path(self, times, joints):
        self.cut.wait(10.0)
        raise HwInterfaceError("FOLLOW_PATH interrupted by a STOP", Result.INTERRUPTED)

    def stop(self):
        self.stops += 1
        if self.stops > self.late:
            self.cut.set()


def test_the_result_is_the_calls_answer():
    call = PathCall(lambda times, joints: 12.5, [0.0, 1.0], [[0.0], [1.0]])
    call.start()
    assert call.finished.wait(10.0)
    assert not call.failed
    assert call.result() == 12.5


def test_a_refusal_is_raised_in_the_callers_thread():
    def refuse(times, joints):
        raise HwInterfaceError("FOLLOW_PATH refused: too far", Result.TOO_FAR)

    call = PathCall(refuse, [0.0], [[0.0]])
    call.start()
    assert call.finished.wait(10.0)
    assert call.failed
    with pytest.raises(HwInterfaceError, match="too far"):
        call.result()


def test_no_result_before_the_call_answered():
    release = threading.Event()
    call = PathCall(lambda times, joints: release.wait(10.0), [0.0], [[0.0]])
    call.start()
    with pytest.raises(RuntimeError, match="not answered"):
        call.result()
    release.set()
    assert call.finished.wait(10.0)


@pytest.mark.parametrize("late", [0, 1, 3])
def test_stop_is_repeated_until_the_path_answers(late):
    # A single STOP (late > 0) found no path yet, and the path then ran to its end.
    server = OnTheWire(late)
    call = PathCall(server.follow_path, [0.0, 1.0], [[0.0], [1.0]])
    call.start()
    sent = call.stop_until_answered(server.stop, log=pytest.fail, every_s=0.01)
    assert sent == late + 1
    assert call.finished.is_set()
    with pytest.raises(HwInterfaceError, match="interrupted"):
        call.result()


def test_no_stop_after_the_path_answered():
    # A STOP then could stop another client's motion.
    call = PathCall(lambda times, joints: 1.0, [0.0], [[0.0]])
    call.start()
    assert call.finished.wait(10.0)
    stops = []
    assert call.stop_until_answered(lambda: stops.append(1), log=pytest.fail) == 0
    assert stops == []


def test_no_stop_for_a_call_never_started():
    stops = []
    call = PathCall(lambda times, joints: 1.0, [0.0], [[0.0]])
    assert call.stop_until_answered(lambda: stops.append(1), log=pytest.fail) == 0
    assert stops == []


def test_stopping_a_server_that_never_answers_is_bounded():
    now = [0.0]

    def clock():
        now[0] += 0.5  # each look at the clock half a second on
        return now[0]

    silent = threading.Event()
    call = PathCall(lambda times, joints: silent.wait(10.0), [0.0], [[0.0]], clock=clock)
    call.start()
    stops = []
    sent = call.stop_until_answered(lambda: stops.append(1), log=pytest.fail, every_s=0.0, most_s=5.0)
    # The deadline is 5.5 s (taken at 0.5 s); after the STOPs the clock reads 1.0, 1.5, ..,
    # and the STOP after which it reads 6.0, past the deadline, is the last: 11.
    assert sent == len(stops) == 11
    silent.set()
    assert call.finished.wait(10.0)


def test_a_stop_that_fails_is_logged_and_ends_the_attempt():
    release = threading.Event()
    call = PathCall(lambda times, joints: release.wait(10.0), [0.0], [[0.0]])
    call.start()
    logged = []

    def broken_stop():
        raise HwInterfaceError("no server", Result.NOT_CONNECTED)

    assert call.stop_until_answered(broken_stop, log=logged.append, every_s=0.01) == 0
    assert logged == ["could not STOP the path (no server); the server follows it to its end"]
    release.set()
    assert call.finished.wait(10.0)
