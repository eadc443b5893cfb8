"""motion_apps.program_check: robot, limits, IK, fence and static-scene collisions, with reasons."""

import copy
import os
import sys

import numpy as np
import pytest

from ..conftest import HOME, ROOT, UR5E

APPS = os.path.join(ROOT, "src", "motion_apps")
if APPS not in sys.path:
    sys.path.insert(0, APPS)

from motion_apps.program_check import ProgramChecker, check_params, load_check_params, load_scene_file  # noqa: E402
from motion_commander.program import Program, Waypoint  # noqa: E402
from motion_common.errors import ParameterError  # noqa: E402
from motion_common.kinematics import RobotKinematics, pose_to_se3  # noqa: E402

SCENE = os.path.join(ROOT, "src", "hw_interface", "config", "scenes", "table_parts.yaml")
CONFIG = os.path.join(APPS, "config", "program_check.yaml")
DOWN = [1.0, 0.0, 0.0, 0.0]
PICK_PLACE = [
    ("start_above", (-0.45, -0.20, 0.20), "none"),
    ("pick", (-0.45, -0.20, 0.045), "grip"),
    ("lift", (-0.45, -0.20, 0.20), "none"),
    ("place_above", (-0.30, -0.25, 0.20), "none"),
    ("place", (-0.30, -0.25, 0.045), "release"),
    ("retreat", (-0.30, -0.25, 0.20), "none"),
]


def taught(points=PICK_PLACE, robot="ur5e"):
    """A program as teach mode records it: poses and the joints IK gives from home."""
    kin = RobotKinematics(UR5E)
    seed, waypoints = HOME, []
    for name, position, action in points:
        solution = kin.solve_ik(pose_to_se3(position, DOWN), seed, max_iterations=200)
        assert solution.success
        seed = solution.joints
        waypoints.append(Waypoint(name, list(position), list(DOWN), solution.joints.tolist(), action, 0.5))
    return Program(robot=robot, waypoints=waypoints)


@pytest.fixture(scope="module")
def checker():
    checker = ProgramChecker(UR5E, "ur5e", scene=load_scene_file(SCENE), params=load_check_params(CONFIG))
    yield checker
    checker.close()


def test_a_pick_and_place_above_the_table_passes(checker):
    report = checker.check(taught(), HOME)
    assert report.ok, report.text()
    assert report.start_checked and report.samples > 50
    assert len(report.joints) == 6
    np.testing.assert_allclose(report.joints[1], taught().waypoints[1].joints, atol=1e-3)


def test_another_robot_is_refused(checker):
    report = checker.check(taught(robot="ur10e"))
    assert not report.ok
    assert "taught on robot 'ur10e', this robot is 'ur5e'" in report.text()


def test_an_unreachable_waypoint_names_index_and_name(checker):
    program = taught()
    program.waypoints[3].position = [-1.5, -0.25, 0.2]
    report = checker.check(program, HOME)
    assert [(i.index, i.name) for i in report.issues] == [(3, "place_above")]
    assert "unreachable" in report.text()


def test_joints_outside_the_limits(checker):
    program = taught()
    program.waypoints[2].joints[0] = 7.0
    report = checker.check(program, HOME)
    assert "waypoint 2 'lift': recorded joints ['shoulder_pan_joint'] outside their limits" in report.text()


def test_the_workspace_fence(checker):
    fenced = ProgramChecker(UR5E, "ur5e", params={"fence_min": [-1.0, -0.22, 0.01], "fence_max": [1.0, 1.0, 1.2]})
    report = fenced.check(taught(), HOME)
    assert [i.index for i in report.issues] == [3, 4, 5]
    assert "outside the workspace fence" in str(report.issues[0])
    fenced.close()


def test_a_waypoint_below_the_floor_collides(checker):
    low = dict(fence_min=[-1.0, -1.0, -0.5], fence_max=[1.0, 1.0, 1.2])
    checker_low = ProgramChecker(UR5E, "ur5e", scene=load_scene_file(SCENE), params=low)
    program = taught()
    program.waypoints[1].position = [-0.45, -0.20, -0.02]
    report = checker_low.check(program, HOME)
    assert not report.ok
    assert "waypoint 1 'pick': in collision: link wrist_3_link touches floor" in report.text()
    checker_low.close()


def test_a_segment_through_an_obstacle_collides(checker):
    """A static block above the middle of a MoveL: both ends are clear, the line is not."""
    block = [{"name": "block", "box": [0.02, 0.02, 0.02], "position": [-0.40, -0.20, 0.13], "mass": 0.0}]
    blocked = ProgramChecker(UR5E, "ur5e", scene=load_scene_file(SCENE) + block)
    points = [("a", (-0.50, -0.20, 0.10), "none"), ("b", (-0.30, -0.20, 0.10), "none")]
    report = blocked.check(taught(points), None)
    assert not report.start_checked
    assert [(i.index, i.name) for i in report.issues] == [(1, "b")]
    assert "MoveL from 'a': at " in report.text() and "touches block" in report.text()
    blocked.close()


def test_movable_parts_are_not_obstacles(checker):
    """The parts of table_parts.yaml (mass > 0) are what the gripper picks: the pick
    waypoint sits on bolt_yellow and still passes."""
    program = taught()
    program.waypoints[1].position = [-0.45, -0.20, 0.041]
    assert checker.check(program, HOME).ok


def test_the_movej_from_the_current_pose_is_checked(checker):
    """A post where the tool passes halfway through the joint-space move to waypoint 0."""
    program, kin = taught(), RobotKinematics(UR5E)
    start = copy.copy(HOME)
    start[0] = 1.2
    middle, _ = kin.forward_pose((start + np.array(program.waypoints[0].joints)) / 2)
    post = [{"name": "post", "box": [0.03, 0.03, 0.03], "position": middle.tolist(), "mass": 0.0}]
    posted = ProgramChecker(UR5E, "ur5e", scene=post)
    assert posted.check(program, None).ok
    report = posted.check(program, start)
    assert [(i.index, i.name) for i in report.issues] == [(0, "start_above")]
    assert "MoveJ from the current pose, at " in report.text() and "touches post" in report.text()
    posted.close()


def test_check_parameters_are_validated():
    with pytest.raises(ParameterError, match="unknown parameter 'fence'"):
        check_params({"fence": 1}, "c.yaml")
    with pytest.raises(ParameterError, match="fence_min .* must be below fence_max"):
        check_params({"fence_min": [0, 0, 0], "fence_max": [1, 1, 0]}, "c.yaml")
    assert load_check_params(CONFIG)["collision_margin"] == 0.005


def test_the_arm_through_the_teach_table_is_a_collision_even_at_the_zero_pose():
    """Moving links are always checked: at the URDF's zero pose the stretched UR5e passes
    through the teach cell's table, and the check must say so (only the base's own
    contacts, e.g. standing on the floor, are ignored)."""
    scene = load_scene_file(os.path.join(ROOT, "src", "motion_apps", "config", "teach_scene.yaml"))
    checker = ProgramChecker(UR5E, "ur5e", scene=scene)
    try:
        kin = RobotKinematics(UR5E)
        position, orientation = kin.forward_pose(np.zeros(6))
        program = Program(
            robot="ur5e", waypoints=[Waypoint("stretched", list(position), list(orientation), [0.0] * 6, "none", 0.5)]
        )
        report = checker.check(program)
        assert not report.ok and "table" in report.text(), report.text()
        home_position, home_orientation = kin.forward_pose(HOME)
        fine = Program(
            robot="ur5e",
            waypoints=[Waypoint("home", list(home_position), list(home_orientation), list(HOME), "none", 0.5)],
        )
        assert checker.check(fine).ok, checker.check(fine).text()
    finally:
        checker.close()
