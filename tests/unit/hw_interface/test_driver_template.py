"""Every driver honours the template the same way; the sim's gripper and scene; plugins."""

import sys
import time

import numpy as np
import pybullet
import pytest

from hw_interface.registry import available_drivers, create_driver
from hw_interface.robot_hw import RobotDriver
from hw_interface.sim_driver import PybulletSimDriver
from hw_interface.testing.fake_rtde import FakeUR
from hw_interface.ur_driver import URRtdeDriver

from ..conftest import HOME, UR5E


def sim_driver():
    return PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False)


def ur_driver():
    return URRtdeDriver(UR5E, robot_ip="192.0.2.1", armed=True, rtde_classes=FakeUR(UR5E, HOME).classes())


@pytest.mark.parametrize("factory", [sim_driver, ur_driver], ids=["pybullet", "ur_rtde"])
def test_driver_follows_the_template(factory):
    driver = factory()
    assert isinstance(driver, RobotDriver)
    assert not driver.status().connected
    driver.login("")
    try:
        assert driver.status().connected
        assert driver.get_robots()[0][1] == 6 and len(driver.joint_names) == 6
        lower, upper = driver.joint_limits
        assert np.all(lower < HOME) and np.all(HOME < upper)
        goal = HOME + [0.1, -0.1, 0.1, 0.0, 0.1, -0.1]
        driver.move_j(goal)
        np.testing.assert_allclose(driver.get_robot_joints(), goal, atol=2e-3)
        position, orientation = driver.get_robot_cartesian_position()
        driver.move_l(position + [0.02, 0.0, -0.02], orientation)
        np.testing.assert_allclose(driver.get_robot_cartesian_position()[0], position + [0.02, 0.0, -0.02], atol=2e-3)
        driver.set_joints(driver.get_robot_joints())
        driver.stop()
        driver.set_gripper(True)
        driver.set_gripper(False)
        driver.set_digital_output(4, True)
    finally:
        driver.disconnect()
        driver.disconnect()  # twice is harmless
    assert not driver.status().connected


def test_suction_gripper_picks_and_places_a_scene_box():
    scene = [
        {"name": "floor", "urdf": "plane.urdf", "fixed": True},
        {"name": "part", "box": [0.02, 0.02, 0.02], "mass": 0.1, "position": [-0.49, -0.13, 0.02]},
    ]
    sim = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False, scene=scene)
    sim.login()
    try:
        position, orientation = sim.get_robot_cartesian_position()
        sim.set_gripper(True)
        assert sim.gripped_body is None  # nothing within reach 45 cm above the part
        sim.set_gripper(False)
        part, _ = sim.body_pose("part")
        sim.move_l([part[0], part[1], part[2] + 0.02 + 0.005], orientation)  # cup 5 mm above the top face
        sim.set_gripper(True)
        assert sim.gripped_body == "part" and sim.outputs[0] is True
        sim.move_l([part[0], part[1] + 0.1, 0.3], orientation)
        lifted, _ = sim.body_pose("part")
        assert lifted[2] > 0.2 and abs(lifted[1] - (part[1] + 0.1)) < 0.01
        sim.set_gripper(False)
        deadline = sim.sim_time + 1.0
        while sim.sim_time < deadline:
            time.sleep(0.001)
        dropped, _ = sim.body_pose("part")
        assert sim.gripped_body is None and dropped[2] < 0.05  # released: back on the floor
    finally:
        sim.disconnect()


def test_plugin_driver_is_found_through_its_entry_point(tmp_path, monkeypatch):
    (tmp_path / "my_robot_driver.py").write_text(
        "from hw_interface.sim_driver import PybulletSimDriver\n"
        "class MyDriver(PybulletSimDriver):\n    name = 'my_robot'\n"
    )
    dist = tmp_path / "my_robot_driver-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: my-robot-driver\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[hw_interface.drivers]\nmy_robot = my_robot_driver:MyDriver\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "my_robot" in available_drivers()
    driver = create_driver("my_robot", urdf_path=UR5E, real_time=False)
    assert type(driver).__name__ == "MyDriver"
    sys.modules.pop("my_robot_driver", None)


@pytest.mark.parametrize("robot, home", [("ur10e", HOME), ("tx90", [0.0, 0.4, 1.6, 0.0, 1.14, 0.0])])
def test_sim_runs_every_shipped_robot(robot, home):
    sim = PybulletSimDriver(UR5E.replace("ur5e", robot), initial_joints=home, real_time=False)
    sim.login()
    try:
        assert sim.get_robots() == [(robot, 6)]
        position, orientation = sim.get_robot_cartesian_position()
        expected, _ = sim.kinematics.forward_pose(home)
        np.testing.assert_allclose(position, expected, atol=2e-3)  # pybullet and pinocchio agree
        sim.move_l(position + [0.05, 0.05, -0.05], orientation)
        np.testing.assert_allclose(sim.get_robot_cartesian_position()[0], position + [0.05, 0.05, -0.05], atol=2e-3)
    finally:
        sim.disconnect()


def test_sim_state_is_read_once_per_physics_step_and_never_stale():
    sim = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False)
    sim.login()
    try:
        sim.move_j(np.asarray(HOME) + 0.3)
        # Hold the physics still (the step thread ends), so the cache is tested step by step.
        sim._running.clear()
        sim._thread.join(timeout=5.0)

        def pybullet_joints():
            return np.array([s[0] for s in sim._client.getJointStates(sim._body, sim._joint_indices)])

        stamp, joints = sim.joint_sample()
        np.testing.assert_array_equal(joints, pybullet_joints())
        joints[:] = 99.0  # a caller changing its copy must not change the cache
        assert sim.joint_sample() == (stamp, pytest.approx(pybullet_joints()))
        position, orientation = sim.get_robot_cartesian_position()
        # A new step invalidates both caches.
        sim._client.setJointMotorControlArray(
            sim._body, sim._joint_indices, pybullet.VELOCITY_CONTROL, targetVelocities=[1.0] * 6, forces=[500.0] * 6
        )
        sim._client.stepSimulation()
        with sim._lock:
            sim.steps += 1
        assert np.max(np.abs(sim.joint_sample()[1] - joints)) > 0
        np.testing.assert_array_equal(sim.joint_sample()[1], pybullet_joints())
        assert np.linalg.norm(sim.get_robot_cartesian_position()[0] - position) > 0
        # A scene reset moves the arm without a step: the next read is the reset pose.
        sim.reset_scene()
        np.testing.assert_allclose(sim.joint_sample()[1], HOME, atol=1e-12)
        start_position, _ = PybulletSimDriver(UR5E, initial_joints=HOME).kinematics.forward_pose(HOME)
        np.testing.assert_allclose(sim.get_robot_cartesian_position()[0], start_position, atol=1e-4)
    finally:
        sim.disconnect()
