"""The Universal Robots driver against a fake of ur_rtde (hw_interface.testing.fake_rtde,
which moves the arm in real time): arming, motions, STOP from another thread, timeouts,
arrival checks, streaming, IO, backoff with an injected sleep, and fault injection
(protective stop, dropped connection, driver exceptions)."""

import threading
import time

import numpy as np
import pytest

from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import CommandIndex, Result
from hw_interface.registry import create_driver, driver_parameters, stream_lag_s
from hw_interface.testing.fake_rtde import FakeUR
from hw_interface.ur_driver import URRtdeDriver, pose_to_ur, ur_to_pose

from ..conftest import HOME, UR5E
from ..stop_helpers import stop_during, wait_for
from .driver_helpers import LockProbingSleep, assert_imports_no_fake, assert_refuses_unless_armed, assert_still


@pytest.fixture
def fake():
    return FakeUR(UR5E, initial_joints=HOME)


def make(fake, **kw):
    params = dict(
        robot_ip="192.0.2.10", armed=True, rtde_classes=fake.classes(), reconnect_backoff=0.001, sleep=lambda s: None
    )
    params.update(kw)
    return URRtdeDriver(UR5E, **params)


def test_refuses_to_connect_unless_armed_with_an_ip(fake):
    assert_refuses_unless_armed(lambda **kw: make(fake, **kw))
    assert fake.connections == 0  # nothing was even opened


def test_state_and_pose_conversion(fake):
    driver = make(fake)
    driver.login()
    np.testing.assert_allclose(driver.get_robot_joints(), HOME)
    position, orientation = driver.get_robot_cartesian_position()
    expected_p, expected_q = driver.kinematics.forward_pose(HOME)
    np.testing.assert_allclose(position, expected_p, atol=1e-9)
    assert abs(np.dot(orientation, expected_q)) == pytest.approx(1.0)
    p, q = ur_to_pose(pose_to_ur([0.1, 0.2, 0.3], [0.0, 0.0, np.sin(0.5), np.cos(0.5)]))
    np.testing.assert_allclose(q, [0.0, 0.0, np.sin(0.5), np.cos(0.5)], atol=1e-12)


def test_move_j_and_move_l_are_async_on_the_controller_and_succeed_on_arrival(fake):
    driver = make(fake)
    driver.login()
    goal = HOME + 0.1
    driver.move_j(goal)
    assert [c for c in fake.calls if c[0] == "moveJ"][-1] == ("moveJ", (list(goal), 1.0, 1.4, True))
    np.testing.assert_allclose(fake.q, goal, atol=driver.goal_tolerance)  # measured, not assumed
    driver.move_j(HOME, asynchronous=True)
    assert fake.is_moving()  # returned at once, the arm is on its way
    assert wait_for(lambda: not fake.is_moving())
    np.testing.assert_allclose(fake.q, HOME, atol=1e-6)
    position, orientation = driver.get_robot_cartesian_position()
    driver.move_l(position + [0.0, 0.05, 0.0], orientation)
    name, args = [c for c in fake.calls if c[0] == "moveL"][-1]
    np.testing.assert_allclose(args[0][:3], position + [0.0, 0.05, 0.0])
    assert args[-1] is True
    np.testing.assert_allclose(driver.get_robot_cartesian_position()[0], position + [0.0, 0.05, 0.0], atol=1e-4)


LONG_J = HOME + [2.8, 0.0, 0.0, 0.0, 0.0, 0.0]  # ~3.5 s at 1 rad/s, 1.4 rad/s^2


def test_stop_from_another_thread_interrupts_move_j_promptly(fake):
    driver = make(fake)
    driver.login()
    runner, stop_at, stop_took = stop_during(
        lambda: driver.move_j(LONG_J), lambda: fake.q[0] > HOME[0] + 0.3, driver.stop
    )
    assert stop_took < 0.2 and runner.returned_at - stop_at < 0.2
    assert runner.error is not None and runner.error.result == Result.INTERRUPTED, runner.error
    assert "stopJ" in fake.names() and "stopL" not in fake.names()
    assert_still(fake)
    assert fake.q[0] < LONG_J[0] - 1.0  # cut short, far from the goal
    assert driver.status().connected and not driver.status().moving


def test_stop_from_another_thread_interrupts_move_l_with_stop_l(fake):
    driver = make(fake, linear_speed=0.1)
    driver.login()
    position, orientation = driver.get_robot_cartesian_position()
    goal = position + [0.0, 0.0, -0.3]  # ~3 s at 0.1 m/s
    start = fake.q.copy()
    runner, stop_at, _ = stop_during(
        lambda: driver.move_l(goal, orientation), lambda: np.max(np.abs(fake.q - start)) > 0.05, driver.stop
    )
    assert runner.returned_at - stop_at < 0.2
    assert runner.error.result == Result.INTERRUPTED
    assert [c for c in fake.calls if c[0] == "stopL"][-1][1] == (10.0, True)
    assert_still(fake)
    assert np.linalg.norm(driver.get_robot_cartesian_position()[0] - goal) > 0.1


def test_move_past_timeout_stops_the_robot_and_answers_timeout(fake):
    driver = make(fake)
    driver.login()
    with pytest.raises(HwInterfaceError) as err:
        driver.move_j(LONG_J, timeout=0.3)
    assert err.value.result == Result.TIMEOUT
    assert "stopJ" in fake.names()
    assert_still(fake)
    assert fake.q[0] < LONG_J[0] - 1.0


def test_success_only_when_the_measured_arm_arrived(fake, monkeypatch):
    driver = make(fake, settle_time=0.05)
    driver.login()
    control_cls = driver._control.__class__
    real_move = control_cls.moveJ
    # A controller that reports the move done 0.05 rad short of the goal.
    monkeypatch.setattr(control_cls, "moveJ", lambda self, q, *a: real_move(self, np.asarray(q) - 0.05, *a))
    with pytest.raises(HwInterfaceError, match="from the goal") as err:
        driver.move_j(HOME + 0.1)
    assert err.value.result == Result.INTERRUPTED


def test_protective_stop_or_lost_connection_during_a_move_interrupts_it(fake):
    driver = make(fake)
    driver.login()
    runner, stop_at, _ = stop_during(
        lambda: driver.move_j(LONG_J), lambda: fake.q[0] > HOME[0] + 0.2, fake.trigger_protective_stop
    )
    assert runner.error.result == Result.INTERRUPTED and "protective" in str(runner.error)
    assert runner.returned_at - stop_at < 0.2
    fake.clear_protective_stop()
    runner, _, _ = stop_during(
        lambda: driver.move_j(HOME), fake.is_moving, lambda: fake.drop_connection(allow_reconnect=True)
    )
    assert runner.error.result == Result.INTERRUPTED and "connection" in str(runner.error)
    driver.move_j(HOME)  # reconnects, then arrives
    np.testing.assert_allclose(fake.q, HOME, atol=driver.goal_tolerance)


def test_streaming_stop_uses_servo_stop_and_the_arm_halts(fake):
    driver = make(fake, stream_timeout=5.0)
    driver.login()
    for _ in range(5):
        driver.set_joints(HOME + 0.02)
        time.sleep(0.01)
    assert wait_for(lambda: np.max(np.abs(fake.q - HOME)) > 0.005)
    driver.stop()
    assert [c for c in fake.calls if c[0] == "servoStop"][-1][1] == (10.0,)
    assert_still(fake)


def test_streaming_uses_servoj_and_servo_stop_precedes_other_moves(fake):
    driver = make(fake, frequency=500.0, lookahead_time=0.05, gain=500)
    driver.login()
    for i in range(20):
        driver.set_joints(HOME + 0.001 * i)
        time.sleep(0.002)
    assert wait_for(lambda: "servoJ" in fake.names())
    servo = [args for name, args in fake.calls if name == "servoJ"][-1]
    assert servo[3:] == (0.002, 0.05, 500)  # period, lookahead, gain
    driver.move_j(HOME)
    names = fake.names()
    assert names.index("servoStop") < names.index("moveJ")
    np.testing.assert_allclose(fake.q, HOME, atol=driver.goal_tolerance)
    assert driver.servo_periods > 0 and driver.missed_periods == 0


def test_streaming_stops_when_targets_go_stale(fake):
    driver = make(fake, stream_timeout=0.05)
    driver.login()
    driver.set_joints(HOME)
    assert wait_for(lambda: "servoStop" in fake.names())


def test_protective_stop_refuses_motion_reports_and_recovers(fake):
    driver = make(fake)
    driver.login()
    dispatcher = CommandDispatcher(driver)
    driver.set_joints(HOME)
    fake.protective_stopped = True
    assert wait_for(lambda: "servoStop" in fake.names())  # streaming halted
    assert driver.status().protective_stop and driver.status().safety_mode == "protective_stop"
    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(HOME))
    assert answer.result == Result.PROTECTIVE_STOP
    fake.protective_stopped = False  # cleared on the pendant
    assert dispatcher.handle(CommandIndex.MOVE_J, joints=list(HOME + 0.05)).result == Result.SUCCESS


def test_disconnect_mid_stream_is_reported_then_reconnects(fake):
    driver = make(fake)
    driver.login()
    driver.set_joints(HOME)
    assert wait_for(lambda: "servoJ" in fake.names())
    fake.drop_connection(allow_reconnect=False)
    assert wait_for(lambda: "streaming stopped" in driver.status().fault or not driver.status().connected)
    dispatcher = CommandDispatcher(driver)
    assert dispatcher.handle(CommandIndex.GET_ROBOT_JOINTS).result == Result.NOT_CONNECTED
    fake.allow_reconnect = True  # cable back in
    assert dispatcher.handle(CommandIndex.GET_ROBOT_JOINTS).result == Result.SUCCESS
    assert dispatcher.handle(CommandIndex.SET_JOINTS, joints=list(HOME)).result == Result.SUCCESS
    assert "reconnect" in fake.names()


def test_controller_exception_becomes_driver_fault(fake):
    driver = make(fake)
    driver.login()
    driver._control.moveJ = lambda *a: (_ for _ in ()).throw(RuntimeError("script crashed"))
    answer = CommandDispatcher(driver).handle(CommandIndex.MOVE_J, joints=list(HOME))
    assert answer.result == Result.DRIVER_FAULT and "script crashed" in answer.reason


def test_gripper_is_a_digital_output_and_exit_stops_the_robot(fake):
    driver = make(fake, gripper_output=3)
    driver.login()
    driver.set_gripper(True)
    assert fake.outputs == {3: True} and driver.status().gripper == "on"
    driver.set_gripper(False)
    assert fake.outputs == {3: False} and driver.status().gripper == ""
    driver.set_digital_output(5, True)
    assert fake.outputs[5] is True
    driver.disconnect()
    names = fake.names()
    assert "stopJ" in names and "stopScript" in names and names.count("disconnect") == 3


def test_connect_retries_with_backoff_then_fails():
    attempts, sleeps = [], []

    class Refusing:
        def __init__(self, ip):
            attempts.append(ip)
            raise RuntimeError("connection refused")

    driver = URRtdeDriver(
        UR5E,
        robot_ip="192.0.2.10",
        armed=True,
        rtde_classes=(Refusing, Refusing, Refusing),
        reconnect_attempts=3,
        reconnect_backoff=0.5,
        sleep=sleeps.append,
    )
    with pytest.raises(HwInterfaceError, match="connection refused") as err:
        driver.login()
    assert err.value.result == Result.LOGIN_FAILED and len(attempts) == 3
    assert sleeps == [0.5, 1.0]  # doubled between attempts, none after the last


def test_reconnect_backoff_sleeps_outside_the_driver_lock(fake):
    sleep = LockProbingSleep()
    driver = sleep.driver = make(fake, reconnect_attempts=3, reconnect_backoff=0.25, sleep=sleep)
    driver.login()
    fake.drop_connection(allow_reconnect=False)
    with pytest.raises(HwInterfaceError) as err:
        driver.get_robot_joints()
    assert err.value.result == Result.NOT_CONNECTED
    assert sleep.sleeps == [0.25, 0.5] and sleep.lock_free == [True, True]
    assert fake.names().count("reconnect") == 3


def test_registry_builds_the_ur_driver_and_checks_servo_ranges(fake):
    driver = create_driver("ur_rtde", urdf_path=UR5E, robot_ip="x", armed=False)
    assert isinstance(driver, URRtdeDriver)
    with pytest.raises(HwInterfaceError, match="bad parameters"):
        create_driver("ur_rtde", urdf_path=UR5E, fake_controller=True)  # no flag: the fake is injected
    import hw_interface.ur_driver as production

    assert_imports_no_fake(production)
    with pytest.raises(HwInterfaceError, match="lookahead"):
        URRtdeDriver(UR5E, lookahead_time=1.0)
    with pytest.raises(HwInterfaceError, match="gain"):
        URRtdeDriver(UR5E, gain=5)


def test_ur_rtde_fake_driver_starts_at_the_start_pose_and_checks_its_parameters():
    driver = create_driver("ur_rtde_fake", urdf_path=UR5E, initial_joints=list(HOME), robot_ip="", armed=False)
    assert isinstance(driver, URRtdeDriver)
    driver.login()
    try:
        np.testing.assert_allclose(driver.get_robot_joints(), HOME)
    finally:
        driver.disconnect()
    schema = driver_parameters("ur_rtde_fake")
    assert "initial_joints" in schema.params and "initial_joints" not in driver_parameters("ur_rtde").params
    assert schema.params["joint_stop_deceleration"].unit == "rad/s^2"


def test_the_ur_drivers_declare_how_long_their_arm_trails_a_stream():
    # servoJ's lookahead: a replay of an episode recorded in the simulation sends its
    # stream that much earlier; the simulation's own driver declares none.
    assert stream_lag_s("ur_rtde") == URRtdeDriver.PARAMETERS.params["lookahead_time"].default == 0.03
    assert stream_lag_s("ur_rtde_fake", {"lookahead_time": 0.05, "gain": 600.0}) == 0.05
    assert stream_lag_s("pybullet", {"gui": False}) == 0.0


def test_a_stop_then_a_new_target_never_leaves_two_servoj_loops(fake):

    driver = make(fake, stream_timeout=5.0)
    driver.login()
    for _ in range(20):  # stop and restart at once, many times: the old loop may be mid-period
        driver.set_joints(HOME + 0.01)
        driver.stop()
        driver.set_joints(HOME + 0.01)
    loops = lambda: [t for t in threading.enumerate() if t.name == "ur-servoj" and t.is_alive()]  # noqa: E731
    assert wait_for(lambda: len(loops()) == 1), f"{len(loops())} servoJ loops alive"
    driver.stop()
    assert wait_for(lambda: not loops())
