"""tests/nodes/check_helpers.py: the one wait of the rostest check scripts (polled, or woken
by a condition variable the subscribers notify), checked here without a ROS master."""

import os
import sys
import threading
import time

import pytest

from ..conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "nodes"))
from check_helpers import wait_until  # noqa: E402


def test_polling_returns_the_value_or_false_or_fails_with_what():
    start = time.monotonic()
    assert wait_until(lambda: time.monotonic() - start > 0.05 and "done", 2.0, period=0.01) == "done"
    assert wait_until(lambda: [], 0.05, period=0.01) is False
    with pytest.raises(AssertionError, match="timed out after 0.05 s waiting for the moon"):
        wait_until(lambda: None, 0.05, "the moon", period=0.01)


def test_a_notified_wait_wakes_when_the_data_changes():
    cond, box = threading.Condition(), {"value": None}

    def publish():
        time.sleep(0.05)
        with cond:
            box["value"] = 42
            cond.notify_all()

    threading.Thread(target=publish, daemon=True).start()
    start = time.monotonic()
    assert wait_until(lambda: box["value"], 5.0, "the value", notified=cond) == 42
    assert time.monotonic() - start < 1.0
    with pytest.raises(AssertionError, match="waiting for nothing"):
        wait_until(lambda: False, 0.05, "nothing", notified=cond)
