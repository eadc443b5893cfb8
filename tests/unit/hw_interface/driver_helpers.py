"""Checks shared by the tests of the drivers of real controllers (test_ur_driver against
fake_rtde, test_industrial_driver against fake_simple_message): the arming gate, a
simulated arm that has come to rest, a reconnect backoff that sleeps outside the driver
lock, and a production module that imports no test double."""

import inspect
import threading
import time

import numpy as np
import pytest

from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import Result

from ..stop_helpers import wait_for

__all__ = ["assert_refuses_unless_armed", "assert_still", "LockProbingSleep", "assert_imports_no_fake"]


def assert_refuses_unless_armed(make):
    """``make(**params)`` builds a driver; it must refuse LOGIN unarmed, or without an address."""
    with pytest.raises(HwInterfaceError, match="not armed") as err:
        make(armed=False).login()
    assert err.value.result == Result.LOGIN_FAILED
    with pytest.raises(HwInterfaceError, match="robot_ip"):
        make(robot_ip="").login()


def assert_still(fake, bound=2.0):
    """The simulated arm comes to rest (a stop's deceleration over) and stays exactly there."""
    assert wait_for(lambda: not fake.is_moving(), bound), "the arm never came to rest"
    rest = fake.q.copy()
    time.sleep(0.1)
    np.testing.assert_array_equal(fake.q, rest)


class LockProbingSleep:
    """An injected ``sleep`` that records each wait and meanwhile takes the driver's lock
    from another thread, as a STOP or a status read would: ``lock_free`` says whether it
    could. Set ``driver`` once the driver is built."""

    def __init__(self):
        self.driver = None
        self.sleeps = []
        self.lock_free = []

    def __call__(self, seconds):
        self.sleeps.append(seconds)
        thread = threading.Thread(target=self._probe)
        thread.start()
        thread.join()

    def _probe(self):
        got = self.driver._lock.acquire(timeout=1.0)
        if got:
            self.driver._lock.release()
        self.lock_free.append(got)


def assert_imports_no_fake(module):
    """Production ``module`` imports nothing from the test doubles (they are injected)."""
    imports = [line for line in inspect.getsource(module).splitlines() if line.lstrip().startswith(("import", "from"))]
    assert not [line for line in imports if "fake" in line or "testing" in line]
