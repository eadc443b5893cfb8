"""The 3-D view's robot model: link segments from the URDF's forward kinematics, joints
reordered from a joint_states message, and joint readings against the URDF limits."""

import numpy as np
import pytest

from dashboard.robot_view import RobotView, joint_readings, segment_pose
from motion_common.kinematics import RobotKinematics

from ..conftest import HOME, UR5E


@pytest.fixture(scope="module")
def view():
    return RobotView(UR5E)


def test_a_segment_puts_the_cylinder_axis_along_it_centred_between_its_ends():
    segment = segment_pose((0.1, 0.2, 0.3), (0.1, 0.2, 0.8))
    assert segment.length == pytest.approx(0.5)
    assert segment.center == pytest.approx((0.1, 0.2, 0.55))
    rotation = np.array(segment.rotation)
    assert rotation @ [0, 1, 0] == pytest.approx([0, 0, 1])  # the cylinder's y axis maps onto the link
    assert rotation.T @ rotation == pytest.approx(np.eye(3))
    assert np.linalg.det(rotation) == pytest.approx(1.0)


@pytest.mark.parametrize("direction", [(1, 0, 0), (-1, 0, 0), (0, -1, 0), (0.3, -0.4, 0.5)])
def test_any_direction_gives_a_proper_rotation(direction):
    segment = segment_pose((0, 0, 0), direction)
    rotation = np.array(segment.rotation)
    unit = np.asarray(direction) / np.linalg.norm(direction)
    assert rotation @ [0, 1, 0] == pytest.approx(unit)
    assert np.linalg.det(rotation) == pytest.approx(1.0)


def test_a_zero_length_segment_has_no_length_and_no_nan():
    segment = segment_pose((0.5, 0, 0), (0.5, 0, 0))
    assert segment.length == 0.0 and np.isfinite(segment.rotation).all()


def test_frame_points_come_from_the_kinematics_and_end_at_the_tool(view):
    points = view.frame_points(HOME)
    assert len(points) == view.dof + 2  # base, each joint, tool
    assert points[0] == (0.0, 0.0, 0.0)
    tool = RobotKinematics(UR5E).forward(HOME).translation
    assert points[-1] == pytest.approx(tuple(tool))
    assert len(view.segments(HOME)) == view.dof + 1


def test_the_links_move_when_the_joints_do(view):
    before = view.segments(HOME)
    moved = HOME.copy()
    moved[0] += 0.5
    after = view.segments(moved)
    assert not np.allclose(before[-1].center, after[-1].center)


def test_joint_states_are_reordered_by_name_and_incomplete_ones_refused(view):
    names = list(reversed(view.joint_names))
    positions = list(reversed(HOME.tolist()))
    assert view.model_order(names, positions) == pytest.approx(HOME)
    assert view.model_order(names[:-1], positions[:-1]) is None
    assert view.model_order([], HOME.tolist()) == pytest.approx(HOME)  # no names: the model's order
    assert view.model_order([], [0.0]) is None


def test_joint_readings_in_degrees_with_their_place_between_the_limits():
    rows = joint_readings(["a", "b", "c"], [0.0, 1.5, -1.0], [-2.0, -1.0, -1.0], [2.0, 1.6, 1.0])
    assert [r.name for r in rows] == ["a", "b", "c"]
    assert rows[0].degrees == pytest.approx(0.0) and rows[0].fraction == pytest.approx(0.5)
    assert not rows[0].near_limit
    assert rows[1].near_limit and rows[2].near_limit and rows[2].fraction == 0.0
    assert rows[0].lower_deg == pytest.approx(np.degrees(-2.0))


def test_view_readings_use_the_urdf_limits(view):
    rows = view.readings(HOME)
    assert [r.name for r in rows] == view.joint_names
    assert rows[2].upper_deg == pytest.approx(np.degrees(view.upper[2]))
