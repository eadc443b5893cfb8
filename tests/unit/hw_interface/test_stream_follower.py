"""The simulated servo's stream follower: joint speed AND acceleration within the limits
whatever the client sends, no overshoot beyond rounding, and a stop when the stream stops."""

import numpy as np

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


def stream(follower, goal_at, seconds, period=0.009):
    """Step the follower at DT while goals ``goal_at(t)`` arrive every ``period`` (a 110 Hz
    teleop stream); return (goal rows (t, q...), setpoint rows (t, q...))."""
    goals, setpoints, t, due = [], [], 0.0, 0.0
    while t < seconds:
        if t >= due - 1e-12:
            goal = np.array(goal_at(t), dtype=float)
            follower.set_goal(goal)
            goals.append((t, *goal))
            due += period
        setpoints.append((t + DT, *follower.step(DT)))
        t += DT
    return np.array(goals), np.array(setpoints)


def test_a_moving_stream_is_followed_without_falling_a_command_period_behind():
    from motion_commander.lag_estimate import best_lag

    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    goals, setpoints = stream(follower, lambda t: 0.3 * np.sin(2 * np.pi * 1.0 * t) * np.array([1.0, -0.5, 0.2]), 3.0)
    lag, _ = best_lag(goals[:, :2], setpoints[:, :2], np.arange(0.0, 0.03, 0.0005))
    # Braking to stop at every goal, as if each were the last, trailed by 10.5 ms here.
    assert lag <= 0.002, f"{lag * 1000:.1f} ms behind the goals"
    velocity, acceleration = derivatives(setpoints[:, 1:])
    assert np.all(np.abs(velocity) <= LIMITS + 1e-9)
    assert np.max(np.abs(acceleration)) <= 200.0 + 1e-6
    # Past the goal's turning points by no more than the lead's prediction error there:
    # about a T^2 with the goal's 12 rad/s^2 at its peaks and T = 9 ms, 1 mrad (0.5 mm at
    # 0.5 m reach).
    assert np.max(setpoints[:, 1]) <= np.max(goals[:, 1]) + 1e-3
    assert np.min(setpoints[:, 1]) >= np.min(goals[:, 1]) - 1e-3


def test_a_stream_that_ends_at_speed_settles_on_its_last_goal():
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    goals, setpoints = stream(follower, lambda t: np.array([1.0, 0.0, 0.0]) * min(t, 0.3), 0.31)
    last = goals[-1, 1:]
    tail = run(follower, 200)
    np.testing.assert_allclose(tail[-1], last, atol=1e-9)
    # Led past it by at most one command interval at the stream's speed (1 rad/s x 9 ms).
    assert np.max(tail[:, 0]) <= last[0] + 1.0 * 0.009 + 1e-9


def test_a_repeated_goal_means_stopped_but_the_same_goal_object_each_period_does_not():
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    for k in range(1, 6):
        follower.set_goal(np.array([0.01 * k, 0.0, 0.0]))
        run(follower, 5)  # 10 ms between goals: 1 rad/s
    np.testing.assert_allclose(follower.goal_velocity, [1.0, 0.0, 0.0])
    same = np.array([0.06, 0.0, 0.0])
    follower.set_goal(same)
    for _ in range(4):  # a fixed-rate servo loop passes the latest goal every period
        follower.set_goal(same)
        follower.step(DT)
    np.testing.assert_allclose(follower.goal_velocity, [1.0, 0.0, 0.0])
    follower.set_goal(np.array([0.06, 0.0, 0.0]))  # a new goal, the same values: stopped
    np.testing.assert_array_equal(follower.goal_velocity, [0.0, 0.0, 0.0])
    tail = run(follower, 300)
    np.testing.assert_allclose(tail[-1], [0.06, 0.0, 0.0], atol=1e-9)


def test_brake_and_reset_drop_the_lead():
    follower = StreamFollower(LIMITS, np.zeros(3), acceleration=200.0)
    for k in range(1, 4):
        follower.set_goal(np.array([0.01 * k, 0.0, 0.0]))
        run(follower, 5)
    follower.brake()
    np.testing.assert_array_equal(follower.goal_velocity, 0.0)
    follower.reset(np.zeros(3))
    np.testing.assert_array_equal(follower.goal_velocity, 0.0)
