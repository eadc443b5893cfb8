"""commander.srv tables, request validation and the pybullet driver behind the dispatcher."""

import os
import re
import time

import numpy as np
import pytest

from hw_interface.dispatcher import CommandDispatcher, Workspace
from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import CommandIndex, Result
from hw_interface.registry import available_drivers, create_driver, register_driver
from hw_interface.robot_hw import DriverStatus, RobotDriver
from hw_interface.sim_driver import PybulletSimDriver

from ..conftest import HOME, ROOT, UR5E

SRV = os.path.join(ROOT, "src", "motion_commander", "srv", "commander.srv")


def srv_constants(part):
    text = open(SRV, encoding="utf-8").read().split("---")[part]
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"^uint8 ([A-Z_]+) = (\d+)", text, re.M)}


def test_python_tables_match_the_srv_file():
    assert srv_constants(0) == {c.name: c.value for c in CommandIndex}
    assert srv_constants(1) == {r.name: r.value for r in Result}


def test_srv_fields_are_table_2():
    request, response = (part.strip().splitlines() for part in open(SRV, encoding="utf-8").read().split("---"))

    def fields(lines):
        return [
            line.split("#")[0].strip()
            for line in lines
            if line.strip() and not line.startswith("#") and "=" not in line
        ]

    assert fields(request) == [
        "uint8 command_index",
        "std_msgs/Header header",
        "float32[] position",
        "float32[] orientation",
        "float32[] joints",
        "float64[] times",  # FOLLOW_PATH's sample times, beyond Table 2
    ]
    assert fields(response) == [
        "uint8 result",
        "std_msgs/Header header",
        "float32[] position",
        "float32[] orientation",
        "float32[] joints",
    ]


@pytest.fixture(scope="module")
def sim():
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False)
    yield driver
    driver.disconnect()


@pytest.fixture(scope="module")
def dispatcher(sim):
    return CommandDispatcher(sim, Workspace(np.array([-1.0, -1.0, 0.05]), np.array([1.0, 1.0, 1.2])))


def wait_sim(sim, seconds):
    """Block until the simulation has advanced ``seconds`` of simulated time."""
    deadline = sim.sim_time + seconds
    while sim.sim_time < deadline:
        time.sleep(0.0005)


def test_after_disconnect_the_last_step_is_not_served_as_the_robot_state():
    # The step loop caches each step's joints; once the simulation is gone, a read must say
    # NOT_CONNECTED instead of returning the last step's joints.
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False)
    driver.login("sim://")
    deadline = time.monotonic() + 30.0
    while driver.steps < 3 and time.monotonic() < deadline:
        time.sleep(0.001)
    np.testing.assert_allclose(driver.get_robot_joints(), HOME, atol=0.05)
    driver.disconnect()
    with pytest.raises(HwInterfaceError) as refused:
        driver.get_robot_joints()
    assert refused.value.result == Result.NOT_CONNECTED


def test_commands_before_login_say_not_connected():
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False)
    answer = CommandDispatcher(driver).handle(CommandIndex.GET_ROBOT_JOINTS)
    assert answer.result == Result.NOT_CONNECTED and "LOGIN" in answer.reason


def test_login_and_state(dispatcher):
    assert dispatcher.handle(CommandIndex.LOGIN, url="sim://").result == Result.SUCCESS
    answer = dispatcher.handle(CommandIndex.GET_ROBOTS)
    assert answer.result == Result.SUCCESS and answer.robots == [("ur5e", 6)]
    answer = dispatcher.handle(CommandIndex.GET_ROBOT_CARTESIAN_POSITION)
    np.testing.assert_allclose(answer.joints, HOME, atol=1e-3)
    np.testing.assert_allclose(answer.position, [-0.4919, -0.1333, 0.4879], atol=2e-3)
    assert dispatcher.handle(CommandIndex.LOGIN, url="tcp://10.0.0.1").result == Result.SUCCESS  # already up


@pytest.mark.parametrize(
    "kwargs, code",
    [
        (dict(command_index=99), Result.UNKNOWN_COMMAND),
        (dict(command_index=CommandIndex.SET_JOINTS, joints=[0.0] * 5), Result.WRONG_LENGTH),
        (dict(command_index=CommandIndex.SET_JOINTS, joints=list(HOME[:5]) + [float("nan")]), Result.NOT_FINITE),
        (dict(command_index=CommandIndex.MOVE_J, joints=list(HOME[:2]) + [4.0] + list(HOME[3:])), Result.JOINT_LIMIT),
        (dict(command_index=CommandIndex.SET_JOINTS, joints=list(HOME + [0.5, 0, 0, 0, 0, 0])), Result.TOO_FAR),
        (dict(command_index=CommandIndex.MOVE_L, position=[0.1, 0.2], orientation=[0, 0, 0, 1]), Result.WRONG_LENGTH),
        (
            dict(command_index=CommandIndex.MOVE_L, position=[0.1, 0.2, float("inf")], orientation=[0, 0, 0, 1]),
            Result.NOT_FINITE,
        ),
        (
            dict(command_index=CommandIndex.MOVE_L, position=[0.3, 0.2, 0.3], orientation=[0, 0, 0, 2]),
            Result.BAD_ORIENTATION,
        ),
        (
            dict(command_index=CommandIndex.MOVE_L, position=[0.3, 0.2, -0.3], orientation=[0, 0, 0, 1]),
            Result.OUT_OF_WORKSPACE,
        ),
        (
            dict(command_index=CommandIndex.MOVE_L, position=[0.9, 0.9, 0.9], orientation=[0, 0, 0, 1]),
            Result.UNREACHABLE,
        ),
    ],
)
def test_bad_requests_are_refused_and_the_robot_does_not_move(dispatcher, sim, kwargs, code):
    dispatcher.handle(CommandIndex.LOGIN, url="sim://")
    before = sim.get_robot_joints()
    answer = dispatcher.handle(**kwargs)
    assert answer.result == code, answer.reason
    assert answer.reason
    np.testing.assert_allclose(sim.get_robot_joints(), before, atol=1e-3)


def test_move_j_move_l_and_streaming_reach_their_targets(dispatcher, sim):
    dispatcher.handle(CommandIndex.LOGIN, url="sim://")
    goal = HOME + [0.2, -0.1, 0.15, 0.1, -0.2, 0.3]
    assert dispatcher.handle(CommandIndex.MOVE_J, joints=goal).result == Result.SUCCESS
    np.testing.assert_allclose(sim.get_robot_joints(), goal, atol=2e-3)
    position, orientation = sim.get_robot_cartesian_position()
    answer = dispatcher.handle(CommandIndex.MOVE_L, position=position + [0.05, -0.05, 0.05], orientation=orientation)
    assert answer.result == Result.SUCCESS, answer.reason
    np.testing.assert_allclose(answer.position, position + [0.05, -0.05, 0.05], atol=2e-3)
    q = sim.get_robot_joints()
    for _ in range(100):
        q = q + 0.002  # 1 rad/s at the 2 ms pace below
        assert dispatcher.handle(CommandIndex.SET_JOINTS, joints=q).result == Result.SUCCESS
        wait_sim(sim, 0.002)
    wait_sim(sim, 1.0)
    np.testing.assert_allclose(sim.get_robot_joints(), q, atol=2e-3)
    assert dispatcher.handle(CommandIndex.STOP).result == Result.SUCCESS
    dispatcher.handle(CommandIndex.MOVE_J, joints=HOME)


def test_driver_exceptions_become_driver_fault():
    class Broken(PybulletSimDriver):
        def get_robots(self):
            raise RuntimeError("controller on fire")

    answer = CommandDispatcher(Broken(UR5E, real_time=False)).handle(CommandIndex.GET_ROBOTS)
    assert answer.result == Result.DRIVER_FAULT and "controller on fire" in answer.reason


def test_registry_finds_builtin_and_registered_drivers():
    assert "pybullet" in available_drivers()
    driver = create_driver("pybullet", urdf_path=UR5E, real_time=False)
    assert isinstance(driver, RobotDriver) and driver.get_robots() == [("ur5e", 6)]
    register_driver("mine", lambda **kw: "custom")
    assert create_driver("mine") == "custom" and "mine" in available_drivers()
    with pytest.raises(HwInterfaceError, match="available"):
        create_driver("kuka_magic")
    with pytest.raises(HwInterfaceError, match="bad parameters"):
        create_driver("pybullet", urdf=UR5E)


class LaggingServo(RobotDriver):
    """A robot whose measured joints stay where they are (a servo that lags its stream)."""

    name = "lagging"
    joint_names = [f"j{i}" for i in range(6)]
    joint_limits = (np.full(6, -6.0), np.full(6, 6.0))

    def __init__(self):
        self.q = np.zeros(6)
        self.targets = []

    def get_robots(self):
        return [("lagging", 6)]

    def login(self, url, user="", password=""):
        pass

    def disconnect(self):
        pass

    def get_robot_joints(self):
        return self.q.copy()

    def get_robot_cartesian_position(self):
        return np.zeros(3), np.array([0, 0, 0, 1.0])

    def set_joints(self, joints):
        self.targets.append(np.array(joints))

    def move_j(self, joints, timeout=30.0):
        self.q = np.array(joints, float)

    def move_l(self, position, orientation, timeout=30.0):
        pass

    def stop(self):
        pass

    def set_gripper(self, closed):
        pass

    def set_digital_output(self, output, value):
        pass

    def status(self):
        return DriverStatus(connected=True)


def test_a_stream_is_checked_step_by_step_and_bounded_ahead_of_a_lagging_robot():
    now = [0.0]
    robot = LaggingServo()
    dispatcher = CommandDispatcher(
        robot, max_stream_step=0.2, max_stream_lag=0.6, clock=lambda: now[0], stream_start_tolerance=0.2
    )

    def stream(q):
        return dispatcher.handle(CommandIndex.SET_JOINTS, joints=[q, 0, 0, 0, 0, 0]).result

    # Steps of 0.15 rad from the previous target are accepted although the robot lags behind...
    results = []
    for i in range(1, 5):
        now[0] += 0.01
        results.append(stream(0.15 * i))
    assert results == [Result.SUCCESS] * 4 and len(robot.targets) == 4
    # ... until the stream runs more than max_stream_lag ahead of the measured joints.
    now[0] += 0.01
    assert stream(0.75) == Result.TOO_FAR and len(robot.targets) == 4
    # A jump back from the last target (0.6) is refused even though it is close to the robot.
    now[0] += 0.01
    assert stream(0.05) == Result.TOO_FAR
    assert robot.targets[-1][0] == pytest.approx(0.6)
    # After a STOP the next target is compared with the robot again.
    dispatcher.handle(CommandIndex.STOP)
    now[0] += 0.01
    assert stream(0.5) == Result.TOO_FAR
    assert stream(0.1) == Result.SUCCESS
    # A pause longer than the stream timeout restarts from the measured joints too.
    now[0] += 1.0
    assert stream(0.25) == Result.TOO_FAR


def test_a_stale_stream_after_a_restart_is_refused_until_it_starts_at_the_robot():
    """A client that streamed through a server restart sends targets from before it: 0.17 rad
    from the arm was accepted (within max_stream_step) and the arm lurched. A stream now
    starts within stream_start_tolerance of the measured joints, and only then continues
    step by step."""
    now = [0.0]
    robot = LaggingServo()
    dispatcher = CommandDispatcher(robot, max_stream_step=0.2, max_stream_lag=0.6, clock=lambda: now[0])

    def stream(q):
        now[0] += 0.009
        return dispatcher.handle(CommandIndex.SET_JOINTS, joints=[q, 0, 0, 0, 0, 0])

    stale = stream(0.17)
    assert stale.result == Result.TOO_FAR and "starts a stream" in stale.reason and robot.targets == []
    assert stream(0.01).result == Result.SUCCESS
    assert stream(0.1).result == Result.SUCCESS  # continuing: checked against the last target
    now[0] += 1.0  # a pause: the next target starts a stream again
    assert stream(0.25).result == Result.TOO_FAR


def test_sim_scene_reset_puts_part_arm_and_gripper_back():
    scene = [
        {"name": "table", "box": [0.2, 0.32, 0.1], "position": [-0.5, -0.04, 0.1], "mass": 0.0},
        {"name": "part", "box": [0.015, 0.015, 0.015], "position": [-0.5, -0.2, 0.215], "mass": 0.05},
    ]
    driver = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False, scene=scene)
    driver.login("sim://")
    try:
        down = [0.70710678, 0.70710678, 0.0, 0.0]
        driver.move_l([-0.5, -0.2, 0.33], down)
        driver.move_l([-0.5, -0.2, 0.238], down)
        driver.set_gripper(True)
        driver.move_l([-0.45, 0.1, 0.33], down)
        carried = driver.scene_poses()["part"][0]
        np.testing.assert_allclose(carried[:2], [-0.45, 0.1], atol=0.003)
        driver.reset_scene()
        wait_sim(driver, 0.3)
        assert driver.gripped_body is None and not driver.status().gripper
        np.testing.assert_allclose(driver.scene_poses()["part"][0], [-0.5, -0.2, 0.215], atol=0.002)
        np.testing.assert_allclose(driver.get_robot_joints(), HOME, atol=1e-3)
    finally:
        driver.disconnect()


def test_a_move_that_started_late_after_a_latch_never_answers_success():
    """A MOVE_J past the latch check whose driver call only starts moving later (a
    reconnect backoff, a busy machine) is stopped again and answered INTERRUPTED."""
    import threading

    class LateMover(LaggingServo):
        def __init__(self):
            super().__init__()
            self.entered, self.proceed, self.stops = threading.Event(), threading.Event(), 0

        def move_j(self, joints, timeout=30.0):
            self.entered.set()
            self.proceed.wait(5.0)  # the driver is still connecting when the latch comes
            self.q = np.array(joints, float)

        def stop(self):
            self.stops += 1

    robot = LateMover()
    dispatcher = CommandDispatcher(robot, move_timeout=5.0)
    answers = []
    worker = threading.Thread(target=lambda: answers.append(dispatcher.handle(CommandIndex.MOVE_J, joints=[0.5] * 6)))
    worker.start()
    assert robot.entered.wait(5.0)
    dispatcher.latch_stop("test")
    robot.proceed.set()
    worker.join(5.0)
    assert answers[0].result == Result.INTERRUPTED, answers[0].reason
    assert robot.stops >= 2, "stopped at the latch and again when the late move returned"


def test_a_latch_is_released_only_by_the_channel_that_set_it():
    dispatcher = CommandDispatcher(LaggingServo())
    dispatcher.latch_stop("latch_stop service")
    assert "NOT released" in dispatcher.release_stop("/motion_commander/estop") and dispatcher.latched
    assert "released by latch_stop service" in dispatcher.release_stop("latch_stop service")
    assert not dispatcher.latched
