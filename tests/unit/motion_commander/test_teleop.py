"""Teleop mapping, auto clutch, joint-step limiting and the TeleopCore pipeline."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_commander.errors import MotionCommanderError
from motion_commander.safety import JointStepLimiter
from motion_commander.teleop import AutoClutch, TeleopMapper
from motion_commander.teleop_core import Action, SafetyConfig, TeleopCore, TeleopStatus
from motion_common.kinematics import RobotKinematics

from ..conftest import HOME, UR5E

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def test_target_at_engage_is_the_tool_pose():
    mapper = TeleopMapper(speed_ratio=0.5)
    tool_q = Rotation.from_euler("x", np.pi).as_quat()
    mapper.engage([0.1, 0.2, 0.3], IDENTITY, [-0.5, -0.1, 0.4], tool_q)
    position, orientation = mapper.target([0.1, 0.2, 0.3], IDENTITY)
    np.testing.assert_allclose(position, [-0.5, -0.1, 0.4])
    assert (Rotation.from_quat(orientation) * Rotation.from_quat(tool_q).inv()).magnitude() < 1e-9


def test_displacement_is_scaled_and_rotated_into_robot_frame():
    # Device rotated +90 deg about z in the robot frame: hand +x is robot +y.
    mapper = TeleopMapper(speed_ratio=0.5, hand_to_robot=Rotation.from_euler("z", np.pi / 2).as_matrix())
    mapper.engage([0, 0, 0], IDENTITY, [1.0, 0.0, 0.0], IDENTITY)
    position, _ = mapper.target([0.2, 0.0, 0.04], IDENTITY)
    np.testing.assert_allclose(position, [1.0, 0.1, 0.02], atol=1e-12)


def test_rotation_mapping_with_a_rotated_device_matches_the_definition():
    # Target = H (R_hand R_hand0^-1) H^-1 R_tool0, with H the device's rotation in the
    # robot frame: checked against scipy on random poses (the mapper uses plain floats).
    rng = np.random.default_rng(11)
    for _ in range(20):
        device, hand0, tool0, hand = (Rotation.from_quat(q) for q in rng.normal(size=(4, 4)))
        mapper = TeleopMapper(speed_ratio=0.7, hand_to_robot=device.as_matrix())
        hand0_p, tool0_p, hand_p = rng.normal(size=(3, 3))
        mapper.engage(hand0_p, hand0.as_quat(), tool0_p, tool0.as_quat())
        position, orientation = mapper.target(hand_p, hand.as_quat())
        expected = device * hand * hand0.inv() * device.inv() * tool0
        assert (Rotation.from_quat(orientation) * expected.inv()).magnitude() < 1e-9
        np.testing.assert_allclose(position, tool0_p + 0.7 * device.apply(hand_p - hand0_p), atol=1e-12)


def test_hand_rotation_turns_the_tool_the_same_way():
    mapper = TeleopMapper()
    tool_r = Rotation.from_euler("x", np.pi)
    mapper.engage([0, 0, 0], IDENTITY, [0, 0, 0], tool_r.as_quat())
    turn = Rotation.from_euler("z", 0.3)
    _, orientation = mapper.target([0, 0, 0], turn.as_quat())
    assert (Rotation.from_quat(orientation) * (turn * tool_r).inv()).magnitude() < 1e-9
    fixed = TeleopMapper(follow_orientation=False)
    fixed.engage([0, 0, 0], IDENTITY, [0, 0, 0], tool_r.as_quat())
    _, orientation = fixed.target([0, 0, 0], turn.as_quat())
    assert (Rotation.from_quat(orientation) * tool_r.inv()).magnitude() < 1e-9


def test_mapper_refuses_bad_settings_and_unengaged_use():
    with pytest.raises(MotionCommanderError):
        TeleopMapper(speed_ratio=0)
    with pytest.raises(MotionCommanderError):
        TeleopMapper(hand_to_robot=np.ones((3, 3)))
    with pytest.raises(MotionCommanderError, match="not engaged"):
        TeleopMapper().target([0, 0, 0], IDENTITY)


def test_auto_clutch_needs_steady_frames_and_drops_on_loss():
    clutch = AutoClutch(steady_frames=3, lost_after_s=0.2)
    assert [clutch.on_frame(t) for t in (0.0, 0.01, 0.02)] == [False, False, True]
    assert not clutch.hand_lost(0.1)
    assert clutch.hand_lost(0.5)
    assert not clutch.on_frame(0.6)  # steady count starts again


def test_limiter_scales_the_whole_step_uniformly():
    limiter = JointStepLimiter([1.0, 1.0], scale=1.0)
    command, limited = limiter.limit([0.0, 0.0], [0.1, 0.05], dt=0.01)
    np.testing.assert_allclose(command, [0.01, 0.005])  # same direction, fastest joint at 1 rad/s
    assert limited
    command, limited = limiter.limit([0.0, 0.0], [0.005, 0.0], dt=0.01)
    assert not limited and command[0] == 0.005
    # A long gap is clamped to max_dt: no big jump after the hand comes back.
    command, _ = limiter.limit([0.0, 0.0], [1.0, 0.0], dt=5.0)
    assert command[0] == pytest.approx(limiter.max_dt)


def make_core(steady=3, ratio=1.0, **safety):
    kin = RobotKinematics(UR5E)
    config = SafetyConfig(**{"joint_speed_scale": 1.0, "engage_ramp_s": 0.0, **safety})
    return TeleopCore(kin, TeleopMapper(ratio), AutoClutch(steady, 0.2), config)


def test_core_engages_without_a_jump_then_follows():
    core = make_core()
    assert core.on_hand_pose(0.0, [0, 0, 0.2], IDENTITY) is None  # no robot state yet
    core.on_joint_state(HOME)
    hand = np.array([0.0, 0.0, 0.2])
    commands = [core.on_hand_pose(0.01 * i, hand, IDENTITY) for i in range(1, 4)]
    assert commands[:2] == [None, None]
    np.testing.assert_allclose(commands[2].joints, HOME, atol=1e-6)  # engage: no jump
    tool0, _ = core.kinematics.forward_pose(HOME)
    stamp = 0.03
    for _ in range(50):
        stamp += 0.01
        command = core.on_hand_pose(stamp, hand + [0.0, 0.05, 0.0], IDENTITY)
    reached, _ = core.kinematics.forward_pose(command.joints)
    np.testing.assert_allclose(reached, tool0 + [0.0, 0.05, 0.0], atol=1e-4)
    assert core.status == TeleopStatus.ENGAGED


def test_core_rejects_bad_input_and_holds_on_unreachable_target():
    core = make_core(steady=1, ratio=10.0)
    core.on_joint_state(HOME)
    assert core.on_hand_pose(0.0, [np.nan, 0, 0], IDENTITY) is None
    assert core.status == TeleopStatus.BAD_INPUT
    assert core.on_hand_pose(0.01, [0, 0, 0.2], IDENTITY) is not None
    assert core.on_hand_pose(0.02, [0.5, 0, 0.2], IDENTITY) is None  # 5 m away at ratio 10
    assert core.status == TeleopStatus.IK_FAILED


def test_core_disengages_when_the_hand_is_lost():
    core = make_core(steady=1, stale_timeout_s=1.0)
    core.on_joint_state(HOME)
    core.on_hand_pose(1.0, [0, 0, 0.2], IDENTITY)
    assert core.mapper.engaged
    assert core.tick(1.5) == Action.DISENGAGE and not core.mapper.engaged
    assert core.status == TeleopStatus.DISENGAGED
