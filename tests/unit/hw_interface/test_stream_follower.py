"""The simulated servo's stream follower: joint speed AND acceleration within the limits
whatever the client sends, no overshoot beyond rounding, and a stop when the stream stops."""

import numpy as np
import pytest

from hw_interface.stream_follower import StreamFollower

DT = 0.002
LIMITS = np.array([3.0, 3.0, 3.0])


def run(follower, steps):
    path = [follower.setpoint.copy()]
    for _ in range(steps):
        path.append(follower.step(DT).copy())
    return np.array(path)


def derivatives(path):
    velocity = np.diff(path, axis=0) / DT
    acceleration = np.diff(velocity, axis=0) / DT
    return velocity, acceleration


def test_a_jump_target_is_reached_within_speed_and_acceleration_and_never_passed():
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    follower.set_goal([0.17, -0.05, 0.0])  # a stale target from before a restart
    path = run(follower, 400)
    velocity, acceleration = derivatives(path)
    assert np.all(np.abs(velocity) <= LIMITS + 1e-9)
    assert np.max(np.abs(acceleration)) <= 200.0 + 1e-6
    np.testing.assert_allclose(path[-1], [0.17, -0.05, 0.0], atol=1e-9)
    # Past a fixed goal by at most the last steps' rounding (0.1 mrad: 0.1 mm at 1 m reach).
    assert np.all(path[:, 0] <= 0.17 + 1e-4) and np.all(path[:, 1] >= -0.05 - 1e-4)
    assert follower.at_rest


def test_without_an_acceleration_limit_the_old_speed_only_servo_is_kept():
    follower = StreamFollower(LIMITS, np.zeros(3))
    follower.set_goal([0.01, 0.0, 0.0])
    np.testing.assert_allclose(follower.step(DT), [0.006, 0.0, 0.0])


def test_a_fuzzed_stream_never_exceeds_either_limit(rng):
    """Random jumps, reversals and stops: the servo setpoint's speed and acceleration stay
    within the limits at every step, and it always comes to rest on its last goal."""
    limits = np.array([3.14, 3.14, 3.14, 6.28, 6.28, 6.28])
    for trial in range(60):
        follower = StreamFollower(limits, np.zeros(6), acceleration=200.0)
        path = [follower.setpoint.copy()]
        for k in range(1300):
            if k % 5 == 0 and k < 200:
                follower.set_goal(follower.goal + rng.normal(0, 0.03 if trial % 2 else 0.2, 6))
            if k == 150 and trial % 3 == 0:
                follower.brake()
            path.append(follower.step(DT).copy())
        velocity, acceleration = derivatives(np.array(path))
        assert np.max(np.abs(velocity) / limits) <= 1 + 1e-9
        assert np.max(np.abs(acceleration)) <= 200.0 * (1 + 1e-9)
        assert follower.at_rest


def test_a_smooth_stream_is_followed_closely(rng):
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    t = np.arange(0, 1.0, 0.009)
    lag = []
    for k, now in enumerate(t):
        goal = 0.2 * np.sin(2 * np.pi * 0.8 * now) * np.array([1.0, 0.5, -0.3])
        follower.set_goal(goal + rng.normal(0, 1e-5, 3))
        for _ in range(4 if k % 2 else 5):  # 110 Hz frames on a 500 Hz servo
            follower.step(DT)
        lag.append(np.max(np.abs(follower.setpoint - goal)))
    assert max(lag[20:]) < 0.02  # rad: the servo keeps up with a hand-speed stream


def test_brake_stops_at_rest_within_the_acceleration_limit():
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    follower.set_goal([1.0, 0.0, 0.0])
    run(follower, 20)
    moving = follower.velocity.copy()
    assert moving[0] > 1.0
    follower.brake()
    path = run(follower, 200)
    _, acceleration = derivatives(path)
    assert np.max(np.abs(acceleration)) <= 200.0 + 1e-6
    assert follower.at_rest
    assert path[-1][0] - path[0][0] <= moving[0] ** 2 / (2 * 200.0) + 1e-6


def test_a_joint_that_must_stop_is_not_held_back_by_a_wrist_turning_hard():
    # Joint 0 moves at 1 rad/s with 5.5 mrad left to its goal: at 100 rad/s^2 it can just
    # stop there (5 mrad). The wrist, at 3 rad/s, is sent back hard at the same time. One
    # factor for every joint's change of velocity let joint 0 brake only as hard as the
    # wrist's share allowed, and it ran past its goal.
    follower = StreamFollower([10.0, 10.0], [0.0, 0.0], acceleration=100.0)
    follower.velocity = np.array([1.0, 3.0])
    follower.set_goal([0.0055, -0.5])
    furthest = max(float(follower.step(0.002)[0]) for _ in range(200))
    assert furthest <= 0.0055 + 1e-4, f"joint 0 ran {1e3 * (furthest - 0.0055):.2f} mrad past its goal"
    assert follower.setpoint[0] == pytest.approx(0.0055, abs=1e-4)
