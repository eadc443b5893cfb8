"""The worked driver example (examples/kinematic_driver.py) keeps the RobotDriver contract:
created by the registry as module:Class with its checked parameters, moves arrive, STOP from
another thread interrupts a move, MoveL follows the line, and its status tells the truth."""

import os
import sys
import threading

import numpy as np
import pytest

from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import Result
from hw_interface.registry import available_drivers, create_driver, driver_parameters

from ..conftest import HOME, ROOT, UR5E

sys.path.insert(0, os.path.join(ROOT, "examples"))
NAME = "kinematic_driver:KinematicDriver"


def driver(**params):
    params = driver_parameters(NAME).validate({"initial_joints": list(HOME), **params}, "test")
    robot = create_driver(NAME, urdf_path=UR5E, tool_frame="tool0", robot_name="arm", **params)
    robot.login("sim://")
    return robot


def test_found_by_module_and_class_with_its_parameters():
    assert "ur_rtde" in available_drivers()
    assert set(driver_parameters(NAME).params) == {"initial_joints", "joint_speed", "goal_tolerance"}
    with pytest.raises(HwInterfaceError, match="no 'Missing'"):
        create_driver("kinematic_driver:Missing")
    with pytest.raises(HwInterfaceError, match="PYTHONPATH"):
        create_driver("no_such_module:Driver")


def test_move_j_arrives_and_move_l_follows_a_line():
    robot = driver(joint_speed=3.0)
    goal = HOME + 0.2
    robot.move_j(goal, timeout=5.0)
    assert np.max(np.abs(robot.get_robot_joints() - goal)) <= 0.001
    position, orientation = robot.get_robot_cartesian_position()
    robot.move_l(position + [0.05, 0.0, 0.0], orientation, timeout=5.0)
    reached, _ = robot.get_robot_cartesian_position()
    assert np.linalg.norm(reached - position - [0.05, 0.0, 0.0]) < 0.002
    assert robot.get_robots() == [("arm", 6)] and not robot.status().moving


def test_stop_from_another_thread_interrupts_a_move():
    robot = driver(joint_speed=0.1)
    threading.Timer(0.05, robot.stop).start()
    with pytest.raises(HwInterfaceError) as raised:
        robot.move_j(HOME + 1.0, timeout=20.0)
    assert raised.value.result == Result.INTERRUPTED
    held = robot.get_robot_joints()
    assert np.max(np.abs(held - HOME)) < 0.05 and not robot.status().moving


def test_not_logged_in_and_wrong_start_pose_are_refused():
    with pytest.raises(HwInterfaceError, match="6 values"):
        create_driver(NAME, urdf_path=UR5E, initial_joints=[0.0, 0.0])
    robot = create_driver(NAME, urdf_path=UR5E)
    with pytest.raises(HwInterfaceError) as raised:
        robot.set_joints(HOME)
    assert raised.value.result == Result.NOT_CONNECTED
