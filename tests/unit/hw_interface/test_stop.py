"""STOP interrupts everything: the pybullet driver and the UR driver on its real-time fake,
MoveJ and MoveL, a STOP command and the latched stop of the dispatcher, sent from another
thread during a ~3 s move. Bounds are generous (0.2 s) for a loaded 2-core machine."""

import time

import numpy as np
import pytest

from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import CommandIndex, Result
from hw_interface.registry import create_driver
from hw_interface.sim_driver import PybulletSimDriver

from ..conftest import HOME, UR5E
from ..stop_helpers import stop_during, wait_for

LONG_J = HOME + [2.8, 0.0, 0.0, 0.0, 0.0, 0.0]


def sim_driver():
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=True)
    driver.login()
    return driver


def fake_driver():
    driver = create_driver("ur_rtde_fake", urdf_path=UR5E, initial_joints=list(HOME), linear_speed=0.1)
    driver.login()
    return driver


@pytest.fixture(params=["pybullet", "ur_rtde_fake"])
def driver(request):
    driver = sim_driver() if request.param == "pybullet" else fake_driver()
    yield driver
    driver.disconnect()


def assert_still(driver):
    """Still once the stop is over: sim from 0.3 s after the STOP, the fake once stopJ's
    deceleration ends; then the measured joints do not change."""
    if isinstance(driver, PybulletSimDriver):
        target = driver.sim_time + 0.3
        assert wait_for(lambda: driver.sim_time >= target)
        rest = driver.get_robot_joints()
        target = driver.sim_time + 0.2
        assert wait_for(lambda: driver.sim_time >= target)
        np.testing.assert_allclose(driver.get_robot_joints(), rest, atol=2e-4)
        assert np.max(np.abs(driver.get_joint_velocities())) < 0.01
    else:
        assert wait_for(lambda: not driver.fake.is_moving(), 2.0)
        rest = driver.get_robot_joints()
        time.sleep(0.1)
        np.testing.assert_array_equal(driver.get_robot_joints(), rest)


def moved(driver, start, amount=0.05):
    return lambda: np.max(np.abs(driver.get_robot_joints() - start)) > amount


@pytest.mark.parametrize("kind", ["move_j", "move_l"])
def test_stop_command_interrupts_a_blocking_move(driver, kind):
    dispatcher = CommandDispatcher(driver)
    start = driver.get_robot_joints()
    if kind == "move_j":
        request = dict(command_index=CommandIndex.MOVE_J, joints=list(LONG_J))
    else:
        position, orientation = driver.get_robot_cartesian_position()
        request = dict(
            command_index=CommandIndex.MOVE_L, position=list(position + [0.0, 0.0, -0.3]), orientation=list(orientation)
        )
    answers = {}
    runner, stop_at, stop_took = stop_during(
        lambda: answers.update(move=dispatcher.handle(**request)),
        moved(driver, start),
        lambda: answers.update(stop=dispatcher.handle(CommandIndex.STOP)),
    )
    stop_answer, move_answer = answers["stop"], answers["move"]
    assert stop_answer.result == Result.SUCCESS and stop_took < 0.2
    assert move_answer.result == Result.INTERRUPTED, move_answer.reason
    assert "STOP" in move_answer.reason
    assert runner.returned_at - stop_at < 0.2
    assert_still(driver)
    if kind == "move_j":
        assert driver.get_robot_joints()[0] < LONG_J[0] - 1.0


def test_latched_stop_interrupts_refuses_and_releases(driver):
    dispatcher = CommandDispatcher(driver)
    start = driver.get_robot_joints()
    answers = []
    runner, stop_at, stop_took = stop_during(
        lambda: answers.append(dispatcher.handle(CommandIndex.MOVE_J, joints=list(LONG_J))),
        moved(driver, start),
        lambda: dispatcher.latch_stop("test"),
    )
    assert answers[0].result == Result.INTERRUPTED and "latch_stop" in answers[0].reason
    assert stop_took < 0.2 and runner.returned_at - stop_at < 0.2
    assert dispatcher.latched and dispatcher.latch_source == "test"
    assert_still(driver)
    here = driver.get_robot_joints()
    position, orientation = driver.get_robot_cartesian_position()
    for request in (
        dict(command_index=CommandIndex.SET_JOINTS, joints=list(here + 0.01)),
        dict(command_index=CommandIndex.MOVE_J, joints=list(HOME)),
        dict(command_index=CommandIndex.MOVE_L, position=list(position + [0, 0, 0.01]), orientation=list(orientation)),
    ):
        answer = dispatcher.handle(**request)
        assert answer.result == Result.LATCHED_STOP and "latch_stop" in answer.reason and "false" in answer.reason
    np.testing.assert_allclose(driver.get_robot_joints(), here, atol=2e-4)  # nothing moved
    # Reading and IO still work while latched.
    assert dispatcher.handle(CommandIndex.GET_ROBOT_JOINTS).result == Result.SUCCESS
    assert "released" in dispatcher.release_stop("test")
    assert not dispatcher.latched
    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(here + [0.05, 0, 0, 0, 0, 0]))
    assert answer.result == Result.SUCCESS, answer.reason
    np.testing.assert_allclose(driver.get_robot_joints(), here + [0.05, 0, 0, 0, 0, 0], atol=2e-3)


def test_move_timeout_stops_and_answers_timeout(driver):
    dispatcher = CommandDispatcher(driver, move_timeout=0.4)
    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(LONG_J))
    assert answer.result == Result.TIMEOUT, answer.reason
    assert_still(driver)
    assert driver.get_robot_joints()[0] < LONG_J[0] - 1.0


def test_sim_move_that_cannot_arrive_is_not_a_success():
    # Joint efforts far too low to hold the arm up: the path ends, the arm never gets there.
    sim = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False, settle_timeout=0.3)
    sim.login()
    try:
        sim._efforts = sim._efforts * 0.001
        with pytest.raises(HwInterfaceError, match="did not settle") as err:
            sim.move_j(HOME + [0.0, 0.3, 0.0, 0.0, 0.0, 0.0])
        assert err.value.result == Result.DRIVER_FAULT
    finally:
        sim.disconnect()
