"""The simulated arm's queue of streamed targets (TimedTargets inside the pybullet driver):
nothing queued in one session moves the next, and a step of the wall clock does not delay
the stream (arrivals and the steps' schedule share the monotonic clock)."""

import time

import numpy as np
import pytest

from hw_interface.sim_driver import PybulletSimDriver

from ..conftest import HOME, UR5E
from ..stop_helpers import wait_for


@pytest.fixture
def driver():
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=True)
    driver.login()
    yield driver
    driver.disconnect()


def test_a_target_queued_in_an_earlier_session_never_moves_the_next(driver):
    driver.disconnect()
    # A target that arrived after the last step of that session ran (queued, not applied).
    driver._timed_targets.add(time.perf_counter(), HOME + np.array([1.0, 0, 0, 0, 0, 0]))
    driver.login()
    steps = driver.steps
    assert wait_for(lambda: driver.steps > steps + 100, 10.0), "the physics thread did not run"
    np.testing.assert_allclose(driver.get_robot_joints(), HOME, atol=1e-3)
    assert driver.stream_timeouts == 0


def test_a_step_of_the_wall_clock_does_not_delay_the_stream(driver, monkeypatch):
    wall = time.time
    monkeypatch.setattr(time, "time", lambda: wall() + 1000.0)  # NTP steps the clock forward
    goal = HOME + np.array([0.05, 0, 0, 0, 0, 0])
    # A stream's last target, sent until the arm is there (each target within the follower's
    # reach); with arrivals on the wall clock they would wait 1000 s in the queue.
    assert wait_for(lambda: driver.set_joints(goal) or np.max(np.abs(driver.get_robot_joints() - goal)) < 2e-3, 10.0), (
        f"the arm never followed the stream: {driver.get_robot_joints() - goal}"
    )
