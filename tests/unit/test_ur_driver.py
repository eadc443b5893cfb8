"""The Universal Robots driver against a fake of ur_rtde: arming, motions, streaming,
IO, and fault injection (protective stop, dropped connection, driver exceptions)."""
import time

import numpy as np
import pytest

from conftest import HOME, UR5E
from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.fake_rtde import FakeUR
from hw_interface.protocol import CommandIndex, Result
from hw_interface.registry import create_driver
from hw_interface.ur_driver import URRtdeDriver, pose_to_ur, ur_to_pose


@pytest.fixture
def fake():
    return FakeUR(UR5E, initial_joints=HOME)


def make(fake, **kw):
    params = dict(robot_ip="192.0.2.10", armed=True, rtde_classes=fake.classes(), reconnect_backoff=0.001)
    params.update(kw)
    return URRtdeDriver(UR5E, **params)


def wait_for(predicate, timeout=2.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.002)
    return False


def test_refuses_to_connect_unless_armed_with_an_ip(fake):
    with pytest.raises(HwInterfaceError, match="not armed") as err:
        make(fake, armed=False).login()
    assert err.value.result == Result.LOGIN_FAILED
    with pytest.raises(HwInterfaceError, match="robot_ip"):
        make(fake, robot_ip="").login()
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


def test_move_j_and_move_l_blocking_and_async(fake):
    driver = make(fake)
    driver.login()
    goal = HOME + 0.1
    driver.move_j(goal)
    assert fake.calls[-1] == ("moveJ", (list(goal), 1.0, 1.4, False))
    driver.move_j(HOME, asynchronous=True)
    assert fake.calls[-1][1][-1] is True
    position, orientation = driver.get_robot_cartesian_position()
    driver.move_l(position + [0.0, 0.05, 0.0], orientation)
    name, args = [c for c in fake.calls if c[0] == "moveL"][-1]
    np.testing.assert_allclose(args[0][:3], position + [0.0, 0.05, 0.0])
    np.testing.assert_allclose(driver.get_robot_cartesian_position()[0], position + [0.0, 0.05, 0.0], atol=1e-4)


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
    assert fake.outputs == {3: True}
    driver.set_digital_output(5, False)
    assert fake.outputs[5] is False
    driver.disconnect()
    names = fake.names()
    assert "stopJ" in names and "stopScript" in names and names.count("disconnect") == 3


def test_connect_retries_with_backoff_then_fails():
    attempts = []

    class Refusing:
        def __init__(self, ip):
            attempts.append(time.monotonic())
            raise RuntimeError("connection refused")

    driver = URRtdeDriver(UR5E, robot_ip="192.0.2.10", armed=True, rtde_classes=(Refusing, Refusing, Refusing),
                          reconnect_attempts=3, reconnect_backoff=0.01)
    with pytest.raises(HwInterfaceError, match="connection refused") as err:
        driver.login()
    assert err.value.result == Result.LOGIN_FAILED and len(attempts) == 3
    assert attempts[2] - attempts[1] >= attempts[1] - attempts[0]  # backoff grows


def test_registry_builds_the_ur_driver_and_checks_servo_ranges(fake):
    driver = create_driver("ur_rtde", urdf_path=UR5E, robot_ip="x", armed=False)
    assert isinstance(driver, URRtdeDriver)
    with pytest.raises(HwInterfaceError, match="lookahead"):
        URRtdeDriver(UR5E, lookahead_time=1.0)
    with pytest.raises(HwInterfaceError, match="gain"):
        URRtdeDriver(UR5E, gain=5)
