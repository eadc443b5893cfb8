"""Every teleop safety rule on its own, then inside TeleopCore."""

import numpy as np
import pytest

from motion_commander.errors import MotionCommanderError
from motion_commander.safety import (
    EngageRamp,
    JointLimitMargin,
    JointStepLimiter,
    SingularityGuard,
    StaleCommandWatchdog,
    WorkspaceFence,
    condition_number,
)
from motion_commander.teleop import ButtonClutch, GestureClutch, TeleopMapper, make_clutch
from motion_commander.teleop_core import Action, SafetyConfig, TeleopCore, TeleopStatus
from motion_common.kinematics import RobotKinematics, pose_to_se3

from ..conftest import HOME, ROOT, UR5E

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def test_acceleration_limit_ramps_velocity():
    limiter = JointStepLimiter([10.0], scale=1.0, acceleration_limit=2.0)
    velocities, q = [], np.zeros(1)
    for _ in range(5):
        new, limited = limiter.limit(q, [1.0], dt=0.01)
        velocities.append((new - q)[0] / 0.01)
        q = new
    np.testing.assert_allclose(velocities, [0.02, 0.04, 0.06, 0.08, 0.10], atol=1e-9)  # 2 rad/s^2
    assert limited


def test_speed_fraction_zero_means_no_motion():
    limiter = JointStepLimiter([1.0, 1.0], scale=1.0)
    command, limited = limiter.limit([0.0, 0.0], [0.1, 0.1], dt=0.01, speed_fraction=0.0)
    np.testing.assert_allclose(command, [0.0, 0.0])
    assert limited


def test_joint_limit_margin_clips():
    margin = JointLimitMargin([-1.0, -1.0], [1.0, 1.0], margin=0.1)
    clipped, flag = margin.apply([0.95, -0.2])
    np.testing.assert_allclose(clipped, [0.9, -0.2])
    assert flag
    with pytest.raises(MotionCommanderError):
        JointLimitMargin([0.0], [0.1], margin=0.1)


def test_singularity_guard_slows_then_halts_only_toward_it():
    guard = SingularityGuard(10.0, 20.0)
    assert guard.speed_fraction(5.0, 6.0) == 1.0
    assert guard.speed_fraction(14.0, 15.0) == pytest.approx(0.5)
    assert guard.speed_fraction(19.0, 25.0) == 0.0
    assert guard.speed_fraction(25.0, 22.0) == 1.0  # backing out is never slowed


def test_condition_number_rises_at_the_stretched_out_singularity():
    kin = RobotKinematics(UR5E)
    assert condition_number(kin.jacobian(HOME)) < 10  # 8.3
    stretched = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, -np.pi / 2, 0.0])  # elbow straight
    assert condition_number(kin.jacobian(stretched)) > 1e3
    wrist_straight = HOME * [1, 1, 1, 1, 0, 1]
    assert condition_number(kin.jacobian(wrist_straight)) > 1e3


def test_workspace_fence_and_floor():
    fence = WorkspaceFence([-1, -1, -1], [1, 1, 1], floor_z=0.05)
    assert fence.clamp([0.5, 0.5, 0.5])[1] is False
    clamped, outside = fence.clamp([2.0, 0.0, -0.2])
    np.testing.assert_allclose(clamped, [1.0, 0.0, 0.05])
    assert outside


def test_engage_ramp_and_watchdog():
    ramp = EngageRamp(0.5)
    ramp.start(10.0)
    assert ramp.fraction(10.25) == pytest.approx(0.5) and ramp.fraction(11.0) == 1.0
    assert ramp.fraction(10.0) > 0
    watchdog = StaleCommandWatchdog(0.1)
    assert not watchdog.expired(5.0)
    watchdog.commanded(5.0)
    assert not watchdog.expired(5.09) and watchdog.expired(5.11)


def test_gesture_and_button_clutches():
    gesture = GestureClutch(steady_frames=2)
    assert [gesture.on_frame(t, n) for t, n in [(0, 1), (0.01, 2), (0.02, 2), (0.03, 1)]] == [False, False, True, False]
    button = ButtonClutch()
    assert not button.on_frame(0.0)
    button.set_pressed(True)
    assert button.on_frame(0.01)
    button.set_pressed(False)
    assert not button.on_frame(0.02)
    with pytest.raises(MotionCommanderError):
        make_clutch("telepathy")


def make_core(**safety):
    kin = RobotKinematics(UR5E)
    config = SafetyConfig(**{"joint_speed_scale": 1.0, "engage_ramp_s": 0.0, **safety})
    core = TeleopCore(kin, TeleopMapper(1.0), make_clutch("auto", 1), config)
    core.on_joint_state(HOME)
    return core


def test_core_halts_on_stale_input_and_resumes_without_a_jump():
    core = make_core(stale_timeout_s=0.1, engage_ramp_s=0.2)
    hand = np.array([0.0, 0.0, 0.2])
    for i in range(10):
        core.on_hand_pose(0.01 * i, hand + [0.002 * i, 0, 0], IDENTITY)
    assert core.tick(0.15) == Action.NONE  # last command at 0.09: 60 ms old
    assert core.tick(0.2) == Action.HALT and core.status == TeleopStatus.STALE_INPUT_HALT
    assert core.tick(0.21) == Action.NONE  # halts once
    moved = HOME + 0.01  # where the robot actually stopped
    core.on_joint_state(moved)
    command = core.on_hand_pose(0.22, hand + [0.05, 0, 0], IDENTITY)  # hand moved meanwhile
    assert np.max(np.abs(command.joints - moved)) < 0.01  # starts from where it stopped, ramping
    assert command.status == TeleopStatus.RAMPING


def test_core_fences_the_target():
    core = make_core(workspace_lower=[-1, -1, 0.4], workspace_upper=[1, 1, 1])
    tool, _ = core.kinematics.forward_pose(HOME)  # z = 0.488
    for i in range(60):
        command = core.on_hand_pose(0.01 * i, [0, 0, 0.2 - 0.005 * i], IDENTITY)
    assert command.target_position[2] == pytest.approx(0.4)
    assert core.status == TeleopStatus.WORKSPACE_LIMIT
    reached, _ = core.kinematics.forward_pose(command.joints)
    assert reached[2] >= 0.4 - 1e-3


def test_core_estop_halts_and_needs_a_fresh_engage():
    core = make_core()
    core.on_hand_pose(0.0, [0, 0, 0.2], IDENTITY)
    assert core.set_estop(True) and core.status == TeleopStatus.ESTOP
    assert core.on_hand_pose(0.01, [0, 0, 0.2], IDENTITY) is None
    assert not core.set_estop(True)  # already active: no second halt
    core.set_estop(False)
    assert core.status == TeleopStatus.DISENGAGED
    assert core.on_hand_pose(0.02, [0, 0, 0.2], IDENTITY) is not None


def test_no_joint_step_above_the_limits_at_engage():
    core = make_core(joint_speed_scale=0.5, engage_ramp_s=0.3)
    max_step = core.limiter.max_velocity
    previous = HOME
    commands = 0
    for i in range(40):  # a hand already moving fast when teleop engages
        command = core.on_hand_pose(0.01 * i, [0.01 * i, 0.0, 0.2], IDENTITY)
        if command is None:  # the frames before the clutch engages
            continue
        commands += 1
        assert np.all(np.abs(command.joints - previous) <= max_step * 0.01 + 1e-9)
        previous = command.joints
    # The check must have seen the engage and the streaming after it, not nothing.
    assert commands >= 25, f"only {commands} commands: teleop never engaged"
    assert np.max(np.abs(previous - HOME)) > np.max(max_step) * 0.01, "the arm never moved"


def test_teleop_config_is_checked_with_the_file_named():
    from motion_commander.config import load_teleop_config
    from motion_common.errors import ParameterError

    config = load_teleop_config(
        {
            "speed_ratio": 0.5,
            "engage": "gesture",
            "joint_acceleration": 30.0,
            "workspace_lower": [-1, -1, 0],
            "input": "pose",
        },
        "my.yaml",
    )
    assert config.speed_ratio == 0.5 and config.safety.joint_acceleration == 30.0
    for bad, fragment in [
        ({"speed_ratio": -1}, "speed_ratio"),
        ({"engage": "psychic"}, "engage"),
        ({"joint_speed_scale": 1.5}, "joint_speed_scale"),
        ({"stale_timout_s": 0.1}, "unknown"),
        ({"workspace_lower": [0, 0]}, "workspace_lower"),
        ({"input": "udp"}, "input"),
        ({"singularity_slowdown": 90.0}, "singularity"),
    ]:
        with pytest.raises(ParameterError, match=fragment) as err:
            load_teleop_config(bad, "my.yaml")
        assert "my.yaml" in str(err.value)


def test_teleop_config_unknown_key_lists_the_valid_keys():
    from motion_commander.config import load_teleop_config
    from motion_common.errors import ParameterError

    with pytest.raises(ParameterError) as err:
        load_teleop_config({"stale_timout_s": 0.1}, "teleop.yaml")
    text = str(err.value)
    assert "teleop.yaml" in text and "'stale_timout_s'" in text and "stale_timeout_s" in text


def test_shipped_teleop_yaml_validates():
    import os

    import yaml

    from motion_commander.config import load_teleop_config

    path = os.path.join(ROOT, "src", "motion_commander", "config", "teleop.yaml")
    with open(path, encoding="utf-8") as stream:
        config = load_teleop_config(yaml.safe_load(stream), path)
    assert config.safety.stale_timeout_s == 0.1 and config.safety.joint_acceleration == 200.0


def test_limiter_brakes_in_time_to_stop_at_a_reversing_target():
    # Regression: a command catching up at speed used to run past the point where the hand
    # turned back (acceleration-limited braking that never planned its stop distance).
    limiter = JointStepLimiter([3.0], scale=1.0, acceleration_limit=80.0)
    dt, command, commands = 0.009, 0.0, []
    for k in range(80):
        target = 0.4 * np.sin(2 * np.pi * 1.5 * k * dt)  # peaks at 0.4 rad, moving up to 3.8 rad/s
        limiter.observe_target([target], dt)
        command = float(limiter.limit([command], [target], dt)[0][0])
        commands.append(command)
    # Before the fix the command ran 32 mrad past the peak (0.432 rad).
    assert max(commands) <= 0.4 + 0.002, f"command ran past the 0.4 rad peak to {max(commands):.4f}"


def test_limiter_keeps_pace_with_a_target_moving_at_constant_speed():
    limiter = JointStepLimiter([3.0], scale=1.0, acceleration_limit=80.0)
    dt, command = 0.009, 0.0
    for k in range(1, 60):
        target = 1.0 * k * dt  # 1 rad/s
        limiter.observe_target([target], dt)
        command = float(limiter.limit([command], [target], dt)[0][0])
    assert target - command < 0.01, f"lags {target - command:.4f} rad behind a 1 rad/s target"


def test_carried_and_prepared_command_figures_give_the_same_commands_as_recomputing_them():
    # The core carries the Jacobian condition number of an unlimited command to the next
    # frame instead of recomputing it; the commands must be exactly those of recomputing.
    import os

    from motion_sensor.devices.leap_v6 import frame_to_sample, read_recording
    from motion_sensor.sequencing.sequencer import Sequencer

    from ..conftest import DATA

    frames = read_recording(os.path.join(DATA, "test-paddle-rightwards.jsonl.gz")).frames
    runs = []
    for recompute, prepare in ((False, False), (True, False), (False, True)):
        core = make_core(joint_speed_scale=1.0, joint_acceleration=200.0)
        sequencer, commands, carried, seeded = Sequencer(), [], 0, 0
        for frame in frames:
            sample = frame_to_sample(frame, frame.timestamp)
            pose = None if sample is None else sequencer.process(sample, now=frame.timestamp)
            if pose is None:
                continue
            seeded += core._prepared_seed is not None
            if recompute:
                core._command_condition = None
            elif core._command_condition is not None:
                carried += 1
            command = core.on_hand_pose(pose.stamp, pose.position, pose.orientation)
            if command is not None:
                commands.append(command.joints)
                core.on_joint_state(command.joints)
                if prepare:  # as the node does once the command is out
                    core.prepare_next()
                    assert core._command_condition is not None and core._command_pose is not None
        runs.append((np.array(commands), carried, seeded))
    (carried_run, carried_frames, _), (recomputed_run, _, _), (prepared_run, _, seeded_frames) = runs
    assert len(carried_run) > 300 and carried_frames > 100, "the cache was never used: the test shows nothing"
    assert seeded_frames > 300, "the IK's prepared seed step was never used: the test shows nothing"
    np.testing.assert_allclose(carried_run, recomputed_run, rtol=0, atol=1e-9)
    # Computing the command's condition number and pose and the IK's first step at its seed
    # between frames changes nothing either.
    np.testing.assert_allclose(prepared_run, recomputed_run, rtol=0, atol=1e-9)


def test_condition_bound_never_claims_below_when_it_is_not():
    # Weyl's bound from a nearby reference: whenever it says "below", the exact condition
    # number is below; along a path into the wrist singularity it must stop saying so.
    from motion_commander.safety import condition_certainly_below, extreme_singular_values

    core = make_core()
    kin, rng = core.kinematics, np.random.default_rng(5)
    decided = undecided = 0
    for _ in range(300):
        reference_q = HOME + rng.uniform(-1.0, 1.0, 6)
        q = reference_q + rng.normal(0.0, 0.01, 6)
        reference = kin.local_jacobian(reference_q)
        below = condition_certainly_below(kin.local_jacobian(q), reference, extreme_singular_values(reference), 40.0)
        exact = condition_number(kin.jacobian(q))
        if below:
            decided += 1
            assert exact < 40.0
        else:
            undecided += 1
    assert decided > 150 and undecided > 0, (decided, undecided)
    # The wrist straightening (q5 -> 0): the condition number grows without bound.
    q = HOME.copy()
    for wrist in np.linspace(-0.5, -1e-4, 60):
        previous = q.copy()
        q[4] = wrist
        reference = kin.local_jacobian(previous)
        if condition_certainly_below(kin.local_jacobian(q), reference, extreme_singular_values(reference), 40.0):
            assert condition_number(kin.jacobian(q)) < 40.0
    assert not condition_certainly_below(kin.local_jacobian(q), reference, extreme_singular_values(reference), 40.0)


def test_the_bound_gives_the_guards_own_decisions_where_it_acts():
    # With a slowdown threshold the paddle recording crosses (its condition numbers are 7.7-9.1),
    # the core with its between-frames work (where the bound replaces the SVD) must slow
    # down exactly where the core without it does: same statuses, same commands.
    import os

    from motion_sensor.devices.leap_v6 import frame_to_sample, read_recording
    from motion_sensor.sequencing.sequencer import Sequencer

    from ..conftest import DATA

    frames = read_recording(os.path.join(DATA, "test-paddle-rightwards.jsonl.gz")).frames
    runs = []
    for prepare in (False, True):
        core = make_core(
            joint_speed_scale=1.0, joint_acceleration=200.0, singularity_slowdown=8.5, singularity_halt=12.0
        )
        sequencer, commands, statuses = Sequencer(), [], []
        for frame in frames:
            sample = frame_to_sample(frame, frame.timestamp)
            pose = None if sample is None else sequencer.process(sample, now=frame.timestamp)
            if pose is None:
                continue
            command = core.on_hand_pose(pose.stamp, pose.position, pose.orientation)
            if command is not None:
                commands.append(command.joints)
                statuses.append(command.status)
                core.on_joint_state(command.joints)
                if prepare:
                    core.prepare_next()
        runs.append((np.array(commands), statuses))
    (plain, plain_statuses), (prepared, prepared_statuses) = runs
    slowed = sum(s in (TeleopStatus.SINGULARITY_SLOWDOWN, TeleopStatus.SINGULARITY_HALT) for s in plain_statuses)
    assert 20 < slowed < len(plain_statuses) - 20, f"{slowed} of {len(plain_statuses)}: pick another threshold"
    assert prepared_statuses == plain_statuses
    np.testing.assert_allclose(prepared, plain, rtol=0, atol=1e-9)


def test_ik_seeded_with_the_last_goal_stays_on_the_commanded_branch():
    # A fast hand with the joints speed-limited: the command lags the IK goal. Seeding each
    # IK with the previous goal must give the solution of the same branch as seeding with
    # the command would (the joints the arm is heading for), frame after frame.
    core = make_core(joint_speed_scale=0.2, joint_acceleration=200.0)
    limited = 0
    for i in range(120):
        hand = [0.15 * np.sin(i / 15.0), 0.1 * np.sin(i / 9.0), 0.2]
        command = core.on_hand_pose(0.009 * i, hand, IDENTITY)
        if command is None:
            continue
        limited += command.status == TeleopStatus.JOINT_SPEED_LIMITED
        goal = core._last_goal
        reference = core.kinematics.solve_ik(
            pose_to_se3(command.target_position, command.target_orientation), core._command
        )
        assert reference.success
        np.testing.assert_allclose(goal, core.margin.apply(reference.joints)[0], atol=1e-3)
        core.on_joint_state(command.joints)
    assert limited > 20, "the command never lagged: the test shows nothing"


@pytest.mark.parametrize("speed_fraction", [0.0, 0.3, 1.0])
def test_the_tool_closest_step_keeps_every_joint_within_its_limits(rng, speed_fraction):
    # Where the acceleration limit binds and a Jacobian is given, the step is solved, not
    # scaled: whatever the Jacobian and the velocities, each joint's change of velocity stays
    # within the acceleration limit, and its speed within the (scaled) speed limit wherever
    # it can get there this step; a halt (speed 0) stops every joint that can stop.
    dt, acceleration, limits = 0.009, 200.0, np.full(6, 3.14)
    for _ in range(200):
        limiter = JointStepLimiter(limits, scale=1.0, acceleration_limit=acceleration)
        start, wanted = rng.uniform(-1.0, 1.0, 6), rng.uniform(-3.0, 3.0, 6)
        for _ in range(2):  # two steps toward a target moving at up to 3 rad/s
            previous = start
            start, _ = limiter.limit(previous, previous + wanted * dt, dt)
        velocity = (start - previous) / dt
        target = start + rng.uniform(-0.05, 0.05, 6)
        jacobian = rng.normal(size=(6, 6))
        command, _ = limiter.limit(start, target, dt, speed_fraction, jacobian=lambda j=jacobian: j)
        new_velocity = (command - start) / dt
        assert np.all(np.isfinite(command))
        assert np.all(np.abs(new_velocity - velocity) <= acceleration * dt * (1 + 1e-9) + 1e-9)
        reachable = np.abs(velocity) - acceleration * dt <= limits * speed_fraction
        assert np.all(np.abs(new_velocity[reachable]) <= limits[reachable] * speed_fraction * (1 + 1e-9) + 1e-9)
