"""PathCall: a FOLLOW_PATH call on its own thread, STOPped until it answers when left early."""

import threading

import pytest

from hw_interface.errors import HwInterfaceError
from hw_interface.path_call import PathCall
from hw_interface.protocol import Result


class OnTheWire:
    """A server whose path arrives only after ``late`` STOPs: the STOPs before it find
    nothing to stop; the first one after it cuts the path (INTERRUPTED) and answers once
    the path's call has (so the count of STOPs does not depend on the threads' timing)."""

    def __init__(self, late: int):
        self.late = late
        self.stops = 0
        self.cut = threading.Event()
        self.call = None

    def follow_path(self, times, joints):
        self.cut.wait(10.0)
        raise HwInterfaceError("FOLLOW_PATH interrupted by a STOP", Result.INTERRUPTED)

    def stop(self):
        self.stops += 1
        if self.stops > self.late:
            self.cut.set()
            assert self.call.finished.wait(10.0)


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
    call = server.call = PathCall(server.follow_path, [0.0, 1.0], [[0.0], [1.0]])
    call.start()
    sent = call.stop_until_answered(server.stop, log=pytest.fail, every_s=0.01)
    assert sent == server.stops == late + 1
    assert call.finished.is_set()
    with pytest.raises(HwInterfaceError, match="interrupted"):
        call.result()
    assert call.describe() == "the path answered: FOLLOW_PATH interrupted by a STOP"


def test_a_second_ctrl_c_does_not_end_the_stopping():
    server = OnTheWire(late=0)
    call = server.call = PathCall(server.follow_path, [0.0, 1.0], [[0.0], [1.0]])
    call.start()
    pressed = []

    def stop():
        if not pressed:  # Ctrl-C again, inside the first STOP's call
            pressed.append(1)
            raise KeyboardInterrupt
        server.stop()

    logged = []
    assert call.stop_until_answered(stop, log=logged.append, every_s=0.01) == 1
    assert call.finished.is_set() and server.stops == 1
    assert logged == ["still stopping the path (at most 5 s)"]


def test_no_stop_after_the_path_answered():
    # A STOP then could stop another client's motion.
    call = PathCall(lambda times, joints: 1.0, [0.0], [[0.0]])
    call.start()
    assert call.finished.wait(10.0)
    stops = []
    assert call.stop_until_answered(lambda: stops.append(1), log=pytest.fail) == 0
    assert stops == []
    assert call.describe() == "the path had already ended"


def test_no_stop_for_a_call_never_started():
    stops = []
    call = PathCall(lambda times, joints: 1.0, [0.0], [[0.0]])
    assert call.stop_until_answered(lambda: stops.append(1), log=pytest.fail) == 0
    assert stops == []
    assert call.describe() == "no path was sent"


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
    # Each look at the clock is 0.5 s on, and a STOP goes out at most every look: about
    # most_s / 0.5 STOPs, whatever the loop's exact shape.
    assert 8 <= sent == len(stops) <= 11
    assert call.describe() == "the path did not answer: the server may follow it to its end"
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
    assert logged == ["could not STOP the path (no server)"]
    release.set()
    assert call.finished.wait(10.0)
