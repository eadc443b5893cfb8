"""FOLLOW_PATH, the timed joint path: every check refuses before the driver sees the path
(each Result named, the sample named); the simulated arm samples it at its physics steps'
simulated times, so a stalled physics thread catches up on the path's own times; STOP
cuts it at the next step and answers INTERRUPTED; a path the arm did not arrive at never
answers SUCCESS; the UR driver samples it by its own clock; a driver without timed paths
answers NOT_SUPPORTED. The simulated arm runs on a fake clock here (no sleeps)."""

import re
import threading
import time

import numpy as np
import pytest

import hw_interface.sim_driver as sim_module
from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.industrial_driver import SimpleMessageDriver
from hw_interface.protocol import CommandIndex, Result
from hw_interface.robot_hw import RobotDriver
from hw_interface.sim_driver import PybulletSimDriver
from hw_interface.testing.fake_rtde import FakeUR
from hw_interface.timed_path import (
    MAX_PATH_DURATION,
    MAX_PATH_SAMPLES,
    START_BLEND,
    TimedPath,
    check_path_start,
    check_timed_path,
)
from hw_interface.ur_driver import URRtdeDriver

from ..conftest import HOME, UR5E
from ..stop_helpers import wait_for

AMPLITUDE = np.array([0.2, 0.1, 0.1, 0.2, 0.2, 0.2])


def swing(duration=0.4, rate=100.0, amplitude=AMPLITUDE):
    """(times, joints): from HOME out and back, at rest at both ends."""
    times = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    return times, HOME + np.outer(np.sin(np.pi * times / duration) ** 2, amplitude)


class FakeTime:
    """The sim driver's ``time`` module on a fake clock: each sleep of the physics thread
        advances it by what was asked; each step is logged when the thread reads the clock
    after it. Counted in steps of a running path: ``stall_at``
        {path step: s} holds the thread up that much after it, ``hooks`` {path step: fn} run in
        the thread after it (outside the driver's lock). ``targets``: (the target each step
        applied, a path was running)."""

    def __init__(self):
        self.now = 1000.0
        self.driver = None
        self.stall_at = {}
        self.hooks = {}
        self.targets = []
        self.path_steps = 0
        self.seen = 0

    def perf_counter(self):
        # The physics thread reads the clock once after each step (outside its lock).
        driver = self.driver
        if driver is not None and threading.current_thread().name == "pybullet-step" and driver.steps > self.seen:
            self.seen = driver.steps
            running = driver._path is not None
            self.targets.append((driver._target.copy(), running))
            if running:
                self.path_steps += 1
                self.now += self.stall_at.pop(self.path_steps, 0.0)
                hook = self.hooks.pop(self.path_steps, None)
                if hook is not None:
                    hook()
        return self.now

    def time(self):
        return self.now + 5.0e8

    def sleep(self, seconds):
        self.now += max(seconds, 0.0)
        time.sleep(0)


@pytest.fixture
def fake_time(monkeypatch):
    """(FakeTime, make(**params) -> a logged-in simulated arm on it)."""
    clock = FakeTime()
    monkeypatch.setattr(sim_module, "time", clock)
    drivers = []

    def make(**params):
        clock.driver = None
        clock.targets, clock.path_steps, clock.seen = [], 0, 0
        driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=True, **params)
        drivers.append(driver)
        driver.login()
        clock.driver = driver
        return driver

    yield clock, make
    for driver in drivers:
        driver.disconnect()


def sim_dispatcher(**params):
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False, **params)
    driver.login()
    return driver, CommandDispatcher(driver)


def send(dispatcher, times, joints):
    return dispatcher.handle(
        CommandIndex.FOLLOW_PATH, joints=np.asarray(joints).ravel().tolist(), times=np.asarray(times).tolist()
    )


def test_every_check_refuses_before_the_driver_sees_the_path():
    driver, dispatcher = sim_dispatcher()
    followed = []
    driver.follow_path = lambda path, timeout=30.0: followed.append(path)
    times, joints = swing()
    lower, upper = driver.joint_limits
    too_high = joints.copy()
    too_high[5, 1] = upper[1] + 0.01
    nan = joints.copy()
    nan[3, 2] = np.nan
    fast_times = times * 0.2  # five times faster: over the motors' speed
    jerk = joints.copy()
    jerk[20, 5] += 0.005  # a 5 mrad spike for 10 ms: over the acceleration limit, not the speed
    cases = [
        (times[:1], joints[:1], Result.WRONG_LENGTH, "at least 2 samples"),
        (times, joints[:-1], Result.WRONG_LENGTH, "joints needs"),
        (times + 0.1, joints, Result.WRONG_LENGTH, "times\\[0\\]"),
        (np.r_[times[:10], times[9], times[11:]], joints, Result.WRONG_LENGTH, "sample 10"),
        (np.r_[times[:4], np.inf, times[5:]], joints, Result.NOT_FINITE, "times\\[4\\]"),
        (times, nan, Result.NOT_FINITE, "sample 3"),
        (times, too_high, Result.JOINT_LIMIT, "sample 5 .*shoulder_lift_joint"),
        (fast_times, joints, Result.TOO_FAR, "speed"),
        (times, jerk, Result.TOO_FAR, "between samples 19 and 20 .*acceleration"),
        (times, joints + 0.06, Result.TOO_FAR, "first sample is 0.060 rad"),
    ]
    for case_times, case_joints, result, reason in cases:
        answer = send(dispatcher, case_times, case_joints)
        assert answer.result == result, (reason, answer.reason)
        assert re.search(reason, answer.reason), answer.reason
    too_many = np.arange(MAX_PATH_SAMPLES + 1) * 0.01
    answer = send(dispatcher, too_many, np.tile(HOME, (len(too_many), 1)))
    assert answer.result == Result.WRONG_LENGTH and f"at most {MAX_PATH_SAMPLES}" in answer.reason
    dispatcher.latch_stop("test")
    assert send(dispatcher, times, joints).result == Result.LATCHED_STOP
    dispatcher.release_stop("test")
    assert not followed, "a refused path reached the driver"
    assert dispatcher._blocking_motion.acquire(blocking=False)  # a MOVE_J is running
    answer = send(dispatcher, times, joints)
    dispatcher._blocking_motion.release()
    assert answer.result == Result.BUSY and not followed
    assert send(dispatcher, times, joints).result == Result.SUCCESS and len(followed) == 1
    driver.disconnect()


def test_a_driver_without_timed_paths_answers_not_supported():
    driver, dispatcher = sim_dispatcher()
    driver.path_limits = lambda: None
    answer = send(dispatcher, *swing())
    assert answer.result == Result.NOT_SUPPORTED and "cannot follow a timed path" in answer.reason
    with pytest.raises(HwInterfaceError) as err:
        super(PybulletSimDriver, driver).follow_path(None)  # RobotDriver's default
    assert err.value.result == Result.NOT_SUPPORTED
    driver.disconnect()
    # The ROS-Industrial driver keeps the defaults (docs/drivers.md says so).
    assert SimpleMessageDriver.path_limits is RobotDriver.path_limits
    assert SimpleMessageDriver.follow_path is RobotDriver.follow_path


def test_the_curve_never_overshoots_a_sample_and_rests_at_both_ends():
    times = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    joints = np.array([[0.0], [1.0], [1.0], [0.2], [0.2]])
    path = TimedPath(times, joints)
    dense = np.array([path.sample(t)[0] for t in np.linspace(0, 0.4, 2001)])
    assert dense.min() >= 0.0 and dense.max() <= 1.0
    assert np.all(path.velocity(0.0) == 0) and np.all(path.velocity(0.4) == 0)
    np.testing.assert_allclose(path.sample(-1.0), joints[0])
    np.testing.assert_allclose(path.sample(9.0), joints[-1])
    speeds, accelerations = path.peaks()
    fine = np.linspace(0, 0.4, 40001)
    numeric = np.abs(np.array([path.velocity(t)[0] for t in fine[1:-1]]))
    assert speeds.max() == pytest.approx(numeric.max(), rel=1e-3)
    assert accelerations.max() == pytest.approx(
        np.abs(np.diff([path.velocity(t)[0] for t in fine]) / (fine[1] - fine[0])).max(), rel=1e-2
    )
    with pytest.raises(HwInterfaceError, match="speed reaches"):
        check_timed_path(times, joints, ["j"], ([-5.0], [5.0]), max_speed=10.0, max_acceleration=1e6)


def test_the_simulated_arm_follows_a_path_exactly_under_a_stall_of_its_thread(fake_time):
    clock, make = fake_time
    times, joints = swing()
    runs = []
    for stall in (0.0, 0.08):  # 80 ms: 40 steps owed, run back to back
        driver = make()
        clock.stall_at[50] = stall
        answer = send(CommandDispatcher(driver), times, joints)
        driver.disconnect()
        runs.append((driver, answer, [target for target, running in clock.targets if running]))
    (calm, calm_answer, calm_steps), (stalled, stalled_answer, stalled_steps) = runs
    assert calm_answer.result == stalled_answer.result == Result.SUCCESS
    assert calm_answer.started == pytest.approx(stalled_answer.started)
    # Step for step the same targets: the path's, at each step's simulated time.
    assert len(calm_steps) == len(stalled_steps) > len(times)
    for steps in (calm_steps, stalled_steps):
        path = TimedPath(times, joints)
        path.start_from(steps[0])  # each starts where its arm was: the first command
        for k, target in enumerate(steps):
            np.testing.assert_allclose(target, path.sample(k * calm.time_step), atol=1e-12)
    assert stalled.overruns == calm.overruns == 0


def test_stop_cuts_a_path_at_the_next_step_and_answers_interrupted(fake_time):
    clock, make = fake_time
    driver = make()
    dispatcher = CommandDispatcher(driver)
    stopped, done = {}, threading.Event()

    def stop():
        stopped.update(at=len(clock.targets), answer=dispatcher.handle(CommandIndex.STOP))
        done.set()

    clock.hooks[100] = stop
    answer = send(dispatcher, *swing(duration=1.0))
    assert done.wait(30.0), "the STOP never returned"
    assert stopped["answer"].result == Result.SUCCESS
    assert answer.result == Result.INTERRUPTED and "STOP" in answer.reason
    assert wait_for(lambda: len(clock.targets) > stopped["at"] + 5, 30.0), "the physics thread stopped stepping"
    after = clock.targets[stopped["at"] :]
    assert after and not any(running for _, running in after), "a path step ran after the STOP"
    hold = after[0][0]
    assert all(np.array_equal(target, hold) for target, _ in after[:5]), "the arm did not hold where it stopped"


def test_a_path_the_arm_did_not_arrive_at_never_answers_success():
    driver, dispatcher = sim_dispatcher(settle_timeout=0.2)
    driver._efforts = driver._efforts * 0.0  # motors without torque: the arm falls, never arrives
    answer = send(dispatcher, *swing())
    assert answer.result != Result.SUCCESS and "did not settle" in answer.reason
    driver.disconnect()


class StepClock:
    """The UR driver's clock; each controller period advances it 2 ms, one period 50 ms."""

    def __init__(self):
        self.now = 0.0
        self.periods = 0

    def __call__(self):
        return self.now

    def wait_period(self, start):
        self.periods += 1
        self.now += 0.05 if self.periods == 30 else 0.002
        time.sleep(0)


def test_the_ur_driver_samples_the_path_by_its_clock():
    fake = FakeUR(UR5E, initial_joints=HOME)
    clock = StepClock()
    driver = URRtdeDriver(
        UR5E, robot_ip="192.0.2.10", armed=True, rtde_classes=fake.classes(), clock=clock, settle_time=0.02
    )
    driver.login()
    driver._control.waitPeriod = clock.wait_period
    times, joints = swing(duration=0.2)
    path = TimedPath(times, joints)
    moments = []
    servo = driver._control.servoJ
    driver._control.servoJ = lambda q, *rest: moments.append((clock.now, np.array(q))) or servo(q, *rest)
    try:
        driver.follow_path(path, timeout=5.0)
    except HwInterfaceError as exc:  # the fake arm moves in real time: it may not have arrived
        assert exc.result == Result.INTERRUPTED and "from the path's end" in str(exc)
    assert any(b - a == pytest.approx(0.05) for (a, _), (b, _) in zip(moments, moments[1:]))
    for now, target in moments:
        np.testing.assert_allclose(target, path.sample(now), atol=1e-12)
    assert moments[-1][0] >= path.duration
    assert driver._active_move is None
    driver.disconnect()


def test_a_path_starts_where_the_arm_is_and_eases_onto_its_first_sample():
    times, joints = swing()
    path = TimedPath(times, joints)
    measured = HOME + np.array([0.03, -0.02, 0.0, 0.0, 0.0, 0.01])
    extra_speed, extra_acceleration = path.start_from(measured)
    np.testing.assert_allclose(path.sample(0.0), measured)  # the first command: no step
    np.testing.assert_allclose(path.velocity(1e-9), TimedPath(times, joints).velocity(1e-9), atol=1e-6)
    plain = TimedPath(times, joints)
    fine = np.linspace(0.0, path.duration, 8001)
    eased = np.array([path.sample(t) for t in fine])
    for t in (START_BLEND, START_BLEND + 0.05, path.duration):  # on the path from the blend's end
        np.testing.assert_allclose(path.sample(t), plain.sample(t), atol=1e-12)
    # velocity() is the derivative of sample(), and the easing adds no more than it says.
    numeric = np.diff(eased, axis=0) / np.diff(fine)[:, None]
    analytic = np.array([path.velocity(t) for t in (fine[1:] + fine[:-1]) / 2])
    np.testing.assert_allclose(numeric, analytic, atol=2e-3)
    added = np.abs(numeric - np.diff([plain.sample(t) for t in fine], axis=0) / np.diff(fine)[:, None])
    assert np.all(added.max(axis=0) <= extra_speed + 1e-6)
    assert extra_acceleration[0] == pytest.approx(0.03 * 6.0 / START_BLEND**2)
    # A gap the driver's limits cannot ease within 0.25 s is refused.
    names = [f"j{i}" for i in range(6)]
    wide = (np.full(6, -6.0), np.full(6, 6.0))
    with pytest.raises(HwInterfaceError, match="easing from the measured joints .*j0's speed") as err:
        check_path_start(TimedPath(times, joints), measured, names, wide, max_speed=0.5, max_acceleration=1e3)
    assert err.value.result == Result.TOO_FAR
    check_path_start(TimedPath(times, joints), measured, names, wide, max_speed=3.0, max_acceleration=1e3)
    # Samples within the limits, an arm beyond the first one: the easing could pass a limit.
    tight = (np.full(6, -6.0), np.r_[joints[:, 0].max() + 0.01, np.full(5, 6.0)])
    with pytest.raises(HwInterfaceError, match="could take j0 .*outside its limits") as err:
        check_path_start(TimedPath(times, joints), measured, names, tight, max_speed=3.0, max_acceleration=1e3)
    assert err.value.result == Result.JOINT_LIMIT


def test_the_server_starts_a_path_from_the_measured_joints_and_not_under_a_stream():
    driver, dispatcher = sim_dispatcher()
    followed = []
    driver.follow_path = lambda path, timeout=30.0: followed.append(path)
    here = np.asarray(driver.get_robot_joints())
    times, joints = swing()
    joints = joints + np.array([0.03, 0.0, 0.0, 0.0, 0.0, 0.0])  # the first sample 30 mrad off
    assert send(dispatcher, times, joints).result == Result.SUCCESS
    np.testing.assert_allclose(followed[0].sample(0.0), here, atol=1e-9)  # the first command: the arm
    np.testing.assert_allclose(followed[0].sample(START_BLEND), TimedPath(times, joints).sample(START_BLEND))
    # Under a live SET_JOINTS stream the arm may be moving: the easing assumes rest.
    assert dispatcher.handle(CommandIndex.SET_JOINTS, joints=here.tolist()).result == Result.SUCCESS
    answer = send(dispatcher, times, joints)
    assert answer.result == Result.BUSY and "stream" in answer.reason and len(followed) == 1
    driver.disconnect()


def test_a_path_in_milliseconds_is_refused_for_its_length():
    driver, dispatcher = sim_dispatcher()
    followed = []
    driver.follow_path = lambda path, timeout=30.0: followed.append(path)
    times, joints = swing()
    answer = send(dispatcher, times * (MAX_PATH_DURATION + 1.0) / times[-1], joints)
    assert answer.result == Result.WRONG_LENGTH and "times are in seconds" in answer.reason
    assert not followed
    driver.disconnect()


def test_a_disconnect_ends_a_running_path_it_never_goes_on_in_the_next_session(fake_time):
    clock, make = fake_time
    driver = make()
    dispatcher = CommandDispatcher(driver)
    clock.hooks[50] = lambda: threading.Thread(target=driver.disconnect).start()
    answer = send(dispatcher, *swing(duration=1.0))
    assert answer.result == Result.INTERRUPTED and "disconnected" in answer.reason
    assert wait_for(lambda: driver._client is None, 30.0)
    driver.login()
    assert driver._path is None
    driver.disconnect()


def test_stop_during_a_ur_path_stops_the_servo_and_answers_interrupted():
    fake = FakeUR(UR5E, initial_joints=HOME)
    clock = StepClock()
    driver = URRtdeDriver(UR5E, robot_ip="192.0.2.10", armed=True, rtde_classes=fake.classes(), clock=clock)
    driver.login()
    driver._control.waitPeriod = clock.wait_period
    outcome = {}

    def follow():
        try:
            driver.follow_path(TimedPath(*swing(duration=5.0)), timeout=10.0)
        except HwInterfaceError as exc:
            outcome["error"] = exc

    runner = threading.Thread(target=follow)
    runner.start()
    assert wait_for(lambda: clock.periods > 20, 30.0)
    driver.stop("STOP")
    runner.join(30.0)
    assert outcome["error"].result == Result.INTERRUPTED
    names = fake.call_names() if hasattr(fake, "call_names") else [name for name, _ in fake.calls]
    after = names[max(i for i, n in enumerate(names) if n == "servoJ") + 1 :]
    assert "servoStop" in after, names[-5:]
    driver.disconnect()


def test_a_stop_while_the_server_checks_a_path_cuts_it(monkeypatch):
    """60000 samples take ~0.1 s to check: a STOP in that time must not be lost."""
    import hw_interface.dispatcher as dispatcher_module  # noqa: PLC0415

    driver, dispatcher = sim_dispatcher()
    followed = []
    driver.follow_path = lambda path, timeout=30.0: followed.append(path) or 0.0
    check = dispatcher_module.check_timed_path

    def slow_check(*args, **kwargs):
        assert dispatcher.handle(CommandIndex.STOP).result == Result.SUCCESS  # arrives meanwhile
        return check(*args, **kwargs)

    monkeypatch.setattr(dispatcher_module, "check_timed_path", slow_check)
    answer = send(dispatcher, *swing())
    assert answer.result == Result.INTERRUPTED and "STOP before it started" in answer.reason, answer
    assert not followed, "the path started after a STOP"
    driver.disconnect()
