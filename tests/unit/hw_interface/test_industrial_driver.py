"""The simple_message driver against the byte-level simulated controller
(hw_interface.testing.fake_simple_message) over real TCP on free local ports, with the
Stäubli TX90's model: arming, the login checks, MoveJ/MoveL arriving on measured joints,
STOP during MoveJ and MoveL (answered within one state period, INTERRUPTED, the arm then
still), streaming, e-stop and error mapping, reconnect with backoff outside the lock, a
controller that does not reply, and every malformed input answered DRIVER_FAULT without a
crash and without motion."""

import os
import socket
import struct
import time
import types

import numpy as np
import pytest

from hw_interface import industrial_driver
from hw_interface import simple_message as sm
from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.industrial_driver import SimpleMessageDriver, parse_controller_url
from hw_interface.protocol import CommandIndex, Result
from hw_interface.registry import create_driver, driver_parameters
from hw_interface.testing.fake_simple_message import FakeSimpleMessageController

from ..conftest import ROOT
from ..stop_helpers import stop_during, wait_for
from .driver_helpers import LockProbingSleep, assert_imports_no_fake, assert_refuses_unless_armed, assert_still

TX90 = os.path.join(ROOT, "src", "motion_common", "urdf", "tx90.urdf")
START = np.array([0.0, 0.4, 1.6, 0.0, 1.14, 0.0])  # motion_common/config/robots/tx90.yaml
LONG = START + [2.8, 0.0, 0.0, 0.0, 0.0, 0.0]  # 4 s at 0.1 of the 7 rad/s limit
STATE_PERIOD = 0.05  # the simulated controller's state period in the STOP tests


@pytest.fixture
def fake():
    controller = FakeSimpleMessageController(TX90, START, state_period=0.01).start()
    yield controller
    controller.close()


def make(fake, **kw):
    params = dict(
        robot_ip="127.0.0.1",
        armed=True,
        motion_port=fake.motion_port,
        state_port=fake.state_port,
        byte_order=fake.byte_order,
        reconnect_backoff=0.001,
        connect_timeout=1.0,
        sleep=lambda s: None,
    )
    params.update(kw)
    return SimpleMessageDriver(TX90, **params)


@pytest.fixture
def driver(fake):
    drivers = []

    def build(**kw):
        d = make(fake, **kw)
        drivers.append(d)
        d.login()
        return d

    yield build
    for d in drivers:
        d.disconnect()


def test_refuses_to_connect_unless_armed_with_an_address(fake):
    assert_refuses_unless_armed(lambda **kw: make(fake, **kw))
    assert fake.connections == 0  # nothing was even opened
    assert parse_controller_url("simple_message://10.0.0.5/", "x") == "10.0.0.5"
    assert parse_controller_url("sim://", "10.0.0.7") == "10.0.0.7"


def test_state_is_stamped_on_receipt_and_mapped_from_the_slots(driver, fake):
    d = driver()
    np.testing.assert_allclose(d.get_robot_joints(), START, atol=1e-6)  # float32 on the wire
    stamp, joints = d.joint_sample()
    assert abs(stamp - time.time()) < 0.5 and joints.shape == (6,)
    status = d.status()
    assert status.connected and not status.moving and not status.protective_stop and status.safety_mode == "normal"


def test_login_checks_the_controllers_joints_against_the_robot():
    # A controller that fills a seventh slot: more joints than the TX90 has.
    seven = FakeSimpleMessageController(TX90, START + 0.1, joint_slots=(0, 1, 2, 3, 4, 6)).start()
    try:
        with pytest.raises(HwInterfaceError, match="slots") as err:
            make(seven).login()
        assert err.value.result == Result.LOGIN_FAILED
    finally:
        seven.close()
    # A joint outside the URDF limits: another robot, another joint order or degrees.
    wrong = FakeSimpleMessageController(TX90, [0.0, 0.4, 1.6, 0.0, 2.9, 0.0]).start()
    try:
        with pytest.raises(HwInterfaceError, match="outside the URDF limits") as err:
            make(wrong).login()
        assert err.value.result == Result.LOGIN_FAILED
        assert not wrong.requests  # no point was ever sent
    finally:
        wrong.close()
    with pytest.raises(HwInterfaceError, match="joint_slots"):
        SimpleMessageDriver(TX90, joint_slots=[0, 1, 2])


def test_move_j_and_move_l_succeed_on_the_measured_arrival(driver, fake):
    d = driver()
    goal = START + 0.2
    d.move_j(goal)
    assert fake.sequences() == [0]  # one point: the controller interpolates the joints
    np.testing.assert_allclose(fake.q, goal, atol=d.goal_tolerance)
    position, orientation = d.get_robot_cartesian_position()
    target = position + [0.0, 0.05, -0.05]
    d.move_l(target, orientation)
    sequences = fake.sequences()[1:]
    assert sequences == list(range(len(sequences))) and len(sequences) > 5  # the line's joint path
    np.testing.assert_allclose(d.get_robot_cartesian_position()[0], target, atol=d.goal_position_tolerance)
    assert d.status().connected and not d.status().moving


def test_full_points_carry_time_and_positions(driver, fake):
    d = driver(point_type="joint_traj_pt_full")
    d.move_j(START - 0.1)
    assert fake.sequences(sm.JOINT_TRAJ_PT_FULL) == [0]
    np.testing.assert_allclose(fake.q, START - 0.1, atol=d.goal_tolerance)


def test_success_only_when_the_measured_arm_arrived(driver, fake, monkeypatch):
    d = driver(settle_time=0.1)
    real_point = fake._point
    # A controller that acknowledges the point but stops 0.05 rad short of it.
    monkeypatch.setattr(fake, "_point", lambda seq, q, *a: real_point(seq, np.asarray(q) - 0.05, *a))
    with pytest.raises(HwInterfaceError, match="from the goal") as err:
        d.move_j(START + 0.1)
    assert err.value.result == Result.INTERRUPTED


@pytest.mark.parametrize("kind", ["move_j", "move_l"])
def test_stop_during_a_move_is_answered_within_one_state_period(kind):
    fake = FakeSimpleMessageController(TX90, START, state_period=STATE_PERIOD).start()
    d = make(fake, move_velocity=0.1, linear_speed=0.1)
    try:
        d.login()
        if kind == "move_j":
            move = lambda: d.move_j(LONG)  # noqa: E731
        else:
            position, orientation = d.get_robot_cartesian_position()
            move = lambda: d.move_l(position + [0.0, 0.0, -0.3], orientation)  # noqa: E731  ~3 s at 0.1 m/s
        runner, stop_at, stop_took = stop_during(move, lambda: np.max(np.abs(fake.q - START)) > 0.05, d.stop)
        assert stop_took < STATE_PERIOD and runner.returned_at - stop_at < STATE_PERIOD
        assert runner.error is not None and runner.error.result == Result.INTERRUPTED, runner.error
        assert wait_for(lambda: fake.stops == 1) and fake.sequences()[-1] == sm.STOP_TRAJECTORY
        assert_still(fake)
        assert np.max(np.abs(fake.q - START)) < 1.0  # cut short, far from the goal
        assert d.status().connected and not d.status().moving
        d.move_j(START)  # and the next move runs
        np.testing.assert_allclose(fake.q, START, atol=d.goal_tolerance)
    finally:
        d.disconnect()
        fake.close()


def test_move_past_its_timeout_stops_the_robot(driver, fake):
    d = driver(move_velocity=0.1)
    with pytest.raises(HwInterfaceError) as err:
        d.move_j(LONG, timeout=0.3)
    assert err.value.result == Result.TIMEOUT
    assert wait_for(lambda: fake.stops == 1)
    assert_still(fake)


def test_streaming_sends_consecutive_points_then_brakes_when_targets_stop(driver, fake):
    d = driver(stream_timeout=0.05)
    for i in range(30):
        d.set_joints(START + 0.002 * i)
        time.sleep(0.01)
    assert wait_for(lambda: not fake.is_moving() and not d._streaming, 3.0)
    sequences = fake.sequences()
    assert sequences == list(range(len(sequences))) and len(sequences) > 10
    np.testing.assert_allclose(fake.q, START + 0.058, atol=0.01)
    assert d.status().fault == ""
    d.set_joints(d.get_robot_joints())  # a new stream starts at sequence 0
    assert wait_for(lambda: fake.sequences()[-1] == 0 and len(fake.sequences()) > len(sequences))


def test_stop_while_streaming_sends_stop_trajectory_and_the_arm_halts(driver, fake):
    d = driver(stream_timeout=5.0)
    for i in range(20):
        d.set_joints(START + 0.01 * i)
        time.sleep(0.01)
    d.stop()
    assert wait_for(lambda: fake.stops == 1)
    count = len(fake.sequences())
    assert_still(fake)
    assert len(fake.sequences()) == count  # nothing sent after STOP_TRAJECTORY


def test_emergency_stop_maps_to_protective_stop_and_interrupts(driver, fake):
    d = driver(move_velocity=0.1)
    dispatcher = CommandDispatcher(d)
    runner, stop_at, _ = stop_during(lambda: d.move_j(LONG), lambda: fake.q[0] > START[0] + 0.1, fake.trigger_estop)
    assert runner.error.result == Result.INTERRUPTED and "emergency stop" in str(runner.error)
    assert runner.returned_at - stop_at < 0.2
    assert wait_for(lambda: d.status().protective_stop)
    assert d.status().safety_mode == "emergency_stop"
    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(START))
    assert answer.result == Result.PROTECTIVE_STOP
    fake.clear_estop()
    assert wait_for(lambda: not d.status().protective_stop)
    assert dispatcher.handle(CommandIndex.MOVE_J, joints=list(START)).result == Result.SUCCESS


def test_controller_error_maps_to_driver_fault_with_its_code(driver, fake):
    d = driver()
    dispatcher = CommandDispatcher(d)
    fake.set_error(4242)
    assert wait_for(lambda: d.status().fault == "controller error 4242")
    assert d.status().safety_mode == "fault"
    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(START + 0.1))
    assert answer.result == Result.DRIVER_FAULT and "4242" in answer.reason
    assert dispatcher.handle(CommandIndex.SET_JOINTS, joints=list(START)).result == Result.DRIVER_FAULT
    assert not fake.requests
    fake.clear_error()
    assert wait_for(lambda: d.status().fault == "")
    assert dispatcher.handle(CommandIndex.MOVE_J, joints=list(START + 0.1)).result == Result.SUCCESS


def test_dropped_connections_interrupt_a_move_and_are_reconnected(driver, fake):
    d = driver(move_velocity=0.1)
    runner, _, _ = stop_during(lambda: d.move_j(LONG), fake.is_moving, fake.drop_connections)
    assert runner.error.result == Result.INTERRUPTED and "connection lost" in str(runner.error)
    assert_still(fake)  # the controller aborts when its motion client is gone
    d.move_j(START)  # reconnects, then arrives
    np.testing.assert_allclose(fake.q, START, atol=d.goal_tolerance)
    assert fake.connections >= 4  # two ports, twice


def test_a_connection_dropped_before_a_points_reply_interrupts_the_move(driver, fake):
    # The point reached the controller, whose reply never comes before the drop: the move was
    # cut short (INTERRUPTED, as one whose connection drops while it is watched).
    d = driver(reply_timeout=5.0)
    fake.silent = True
    runner, _, _ = stop_during(lambda: d.move_j(LONG), lambda: len(fake.requests) > 0, fake.drop_connections)
    assert runner.error.result == Result.INTERRUPTED and "connection lost" in str(runner.error), runner.error
    fake.silent = False
    d.move_j(START)  # reconnects, then arrives
    np.testing.assert_allclose(fake.q, START, atol=d.goal_tolerance)


def test_reconnect_backs_off_outside_the_driver_lock(fake):
    sleep = LockProbingSleep()
    d = sleep.driver = make(fake, reconnect_attempts=3, reconnect_backoff=0.25, sleep=sleep, connect_timeout=0.3)
    d.login()
    fake.drop_connections(refuse=True)
    assert wait_for(lambda: not d.status().connected)
    with pytest.raises(HwInterfaceError) as err:
        d.get_robot_joints()
    assert err.value.result == Result.NOT_CONNECTED
    assert sleep.sleeps == [0.25, 0.5] and sleep.lock_free == [True, True]
    fake.accept_connections()  # cable back in
    np.testing.assert_allclose(d.get_robot_joints(), START, atol=1e-6)
    d.disconnect()


def test_a_controller_that_does_not_reply_is_a_fault_and_the_arm_is_stopped(driver, fake):
    d = driver(reply_timeout=0.2)
    fake.silent = True
    began = time.monotonic()
    with pytest.raises(HwInterfaceError, match="did not answer") as err:
        d.move_j(START + 0.5)
    assert err.value.result == Result.DRIVER_FAULT and time.monotonic() - began < 1.0
    assert wait_for(lambda: fake.stops == 1)  # STOP_TRAJECTORY went out after the missing reply
    assert_still(fake)


def frame(*ints_then_floats, floats=()):
    body = struct.pack(f"<{len(ints_then_floats)}i", *ints_then_floats) + struct.pack(f"<{len(floats)}f", *floats)
    return struct.pack("<i", len(body)) + body


# What a broken or foreign controller may send on the state port.
MALFORMED_STATE = {
    "unknown message type": frame(99, 1, 0),
    "JOINT_POSITION one joint short": frame(10, 1, 0, 0, floats=[0.0] * 9),
    "STATUS with an extra word": frame(13, 1, 0, 1, 0, 0, 0, 0, 2, 1, 0),
    "NaN joint": frame(10, 1, 0, 0, floats=[0.0, float("nan")] + [0.0] * 8),
    "infinite joint": frame(10, 1, 0, 0, floats=[float("inf")] + [0.0] * 9),
    "wrong byte order": struct.pack(">4i", 12, 13, 1, 0),
    "garbage length prefix": b"\xff\xff\xff\x7f" + b"\0" * 12,
    "invalid comm_type": frame(13, 9, 0, 1, 0, 0, 0, 0, 2, 1),
    "a reply on the state port": frame(13, 3, 1, 1, 0, 0, 0, 0, 2, 1),
    "tri-state out of range": frame(13, 1, 0, 7, 0, 0, 0, 0, 2, 1),
    "a joint in a slot the TX90 lacks": frame(10, 1, 0, 0, floats=[0.0] * 8 + [0.3, 0.0]),
    "JOINT_TRAJ_PT on the state port": frame(11, 1, 0, 0, floats=[0.0] * 12),
}


@pytest.mark.parametrize("name", sorted(MALFORMED_STATE))
def test_malformed_state_is_a_driver_fault_never_a_crash_never_motion(driver, fake, name):
    d = driver(stream_timeout=5.0)
    dispatcher = CommandDispatcher(d)
    for i in range(5):  # streaming when the bad data arrives
        d.set_joints(START + 0.01 * i)
        time.sleep(0.01)
    fake.send_raw_state(MALFORMED_STATE[name])
    assert wait_for(lambda: "bad data" in d.status().fault), d.status()
    assert_still(fake)
    count = len(fake.requests)
    for command, kw in (
        (CommandIndex.MOVE_J, {"joints": list(START)}),
        (CommandIndex.SET_JOINTS, {"joints": list(START)}),
        (CommandIndex.GET_ROBOT_JOINTS, {}),
    ):
        answer = dispatcher.handle(command, **kw)
        assert answer.result == Result.DRIVER_FAULT and "bad data" in answer.reason, answer
    time.sleep(0.05)
    assert len(fake.requests) == count and not fake.is_moving()  # nothing more was sent
    d.login()  # checked and logged in again: the fault clears
    d.move_j(START)
    np.testing.assert_allclose(fake.q, START, atol=d.goal_tolerance)


def test_a_frame_cut_by_a_closed_connection_is_a_truncated_frame(driver, fake):
    d = driver(state_timeout=5.0)
    fake.pause_state = True  # so that nothing follows the cut frame
    time.sleep(0.05)
    fake.send_raw_state(frame(10, 1, 0, 0, floats=[0.0] * 10)[:20])
    time.sleep(0.05)
    fake.drop_connections(ports=("state",))
    assert wait_for(lambda: "truncated" in d.status().fault), d.status()
    with pytest.raises(HwInterfaceError) as err:
        d.move_j(START)
    assert err.value.result == Result.DRIVER_FAULT


MALFORMED_REPLIES = {
    "reply of another type": frame(10, 3, 1),
    "reply code out of range": frame(11, 3, 7),
    "reply of an odd size": frame(11, 3, 1, 0, 0, 0),
    "a request from the controller": frame(11, 2, 0, 0, floats=[0.0] * 12),
    "wrong byte order": struct.pack(">4i", 12, 11, 3, 1),
}


@pytest.mark.parametrize("name", sorted(MALFORMED_REPLIES))
def test_malformed_replies_are_a_driver_fault_and_the_arm_stops(driver, fake, name):
    d = driver(move_velocity=0.1)
    fake.reply_raw_next(MALFORMED_REPLIES[name])
    with pytest.raises(HwInterfaceError) as err:
        d.move_j(LONG)
    assert err.value.result == Result.DRIVER_FAULT and "bad data" in str(err.value), err.value
    assert_still(fake)
    assert "bad data" in d.status().fault


def test_a_refused_point_is_a_driver_fault(driver, fake, monkeypatch):
    d = driver()
    monkeypatch.setattr(fake, "_point", lambda *a: False)
    with pytest.raises(HwInterfaceError, match="refused") as err:
        d.move_j(START + 0.1)
    assert err.value.result == Result.DRIVER_FAULT


def test_a_controller_in_the_other_byte_order_never_logs_in():
    swapped = FakeSimpleMessageController(TX90, START, byte_order="big").start()
    try:
        with pytest.raises(HwInterfaceError, match="byte order") as err:
            make(swapped, byte_order="little").login()
        assert err.value.result == Result.LOGIN_FAILED and not swapped.requests
        d = make(swapped, byte_order="big")  # Fanuc-style: swapped bytes both ways
        d.login()
        d.move_j(START + 0.1)
        np.testing.assert_allclose(swapped.q, START + 0.1, atol=d.goal_tolerance)
        d.disconnect()
    finally:
        swapped.close()


def test_the_simulated_controller_aborts_on_an_out_of_order_sequence(fake):
    client = socket.create_connection(("127.0.0.1", fake.motion_port), timeout=2.0)
    reader = sm.FrameReader()

    def ask(message):
        client.sendall(sm.encode(message, sm.SERVICE_REQUEST))
        frames = []
        while not frames:
            frames = reader.feed(client.recv(4096))
        return frames[0].header

    def point(sequence, joints):
        return ask(sm.JointTrajPt(sequence, tuple(joints), 0.1, 0.0))

    try:
        assert point(0, START + 0.3).reply_code == sm.SUCCESS
        assert point(1, START + 0.6).reply_code == sm.SUCCESS
        assert wait_for(fake.is_moving)
        reply = point(3, START)  # 2 is missing
        assert reply == sm.Header(sm.JOINT_TRAJ_PT, sm.SERVICE_REPLY, sm.FAILURE)
        assert_still(fake)
        assert np.max(np.abs(fake.q - START)) < 0.3  # aborted before the first point
        assert point(sm.STOP_TRAJECTORY, []).reply_code == sm.SUCCESS  # acknowledged too
        assert ask(sm.Ping()) == sm.Header(sm.PING, sm.SERVICE_REPLY, sm.SUCCESS)
    finally:
        client.close()


def test_registry_builds_both_and_the_driver_imports_no_fake():
    d = create_driver("simple_message", urdf_path=TX90, robot_ip="192.0.2.10", armed=False)
    assert isinstance(d, SimpleMessageDriver) and d.motion_port == 11000 and d.state_port == 11002
    fake_driver = create_driver("simple_message_fake", urdf_path=TX90, initial_joints=list(START), armed=False)
    try:
        fake_driver.login("192.0.2.10")  # any url: the simulated controller
        np.testing.assert_allclose(fake_driver.get_robot_joints(), START, atol=1e-6)
    finally:
        fake_driver.disconnect()
        fake_driver.fake.close()
    schema = driver_parameters("simple_message_fake")
    assert "initial_joints" in schema.params and "initial_joints" not in driver_parameters("simple_message").params
    assert schema.params["byte_order"].choices == ("little", "big")
    import hw_interface.industrial_driver as production

    assert_imports_no_fake(production)


def test_no_gripper_or_io_in_the_standard_set(driver):
    d = driver()
    for call in (lambda: d.set_gripper(True), lambda: d.set_digital_output(1, True)):
        with pytest.raises(HwInterfaceError) as err:
            call()
        assert err.value.result == Result.DRIVER_FAULT


def test_states_a_late_reader_took_together_are_stamped_as_sampled_not_as_received(fake, monkeypatch):
    # The driver's clock and the wall clock are the test's: a state's stamp is then exact.
    clock = [100.0]
    monkeypatch.setattr(
        industrial_driver, "time", types.SimpleNamespace(time=lambda: clock[0] + 1000.0, sleep=time.sleep)
    )
    d = make(fake, clock=lambda: clock[0], state_timeout=60.0)
    d.login()
    try:
        fake.pause_state = True
        time.sleep(0.05)  # a state already on its way arrives (stamped 1100, like login's)

        def state(i):
            slots = np.zeros(sm.MAX_JOINTS)
            slots[:6] = START + 0.001 * (i + 1)  # none is the state the controller had
            return sm.encode(sm.JointPosition(0, tuple(slots)), byte_order=fake.byte_order)

        def arrives(data, at, last):
            clock[0] = at
            fake.send_raw_state(data)
            assert wait_for(lambda: abs(d.get_robot_joints()[0] - (START[0] + 0.001 * (last + 1))) < 1e-6)
            return d.joint_sample()[0] - 1000.0

        stamps = [arrives(state(i), 101.0 + 0.01 * i, i) for i in range(20)]  # on time
        np.testing.assert_allclose(stamps, 101.0 + 0.01 * np.arange(20), atol=1e-9)
        # The reader was busy: the states sampled at 101.20, 101.21 and 101.22 are read
        # together at 101.227, then the next one on time.
        burst = arrives(state(20) + state(21) + state(22), 101.227, 22)
        after = arrives(state(23), 101.23, 23)
        # Stamped on receipt, 101.227 then 101.23: a speed 3.3 times the true one.
        assert burst == pytest.approx(101.22, abs=0.001) and after == pytest.approx(101.23, abs=1e-9)
    finally:
        d.disconnect()
