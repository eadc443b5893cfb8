"""motion_apps.program_runner with a fake controller: the client's methods, HwInterfaceError
with .result on refusal. Stops mid-program (INTERRUPTED, LATCHED_STOP), refusals, dry run."""

import os
import subprocess
import sys

import pytest

from ..conftest import HOME, ROOT, UR5E

APPS = os.path.join(ROOT, "src", "motion_apps")
if APPS not in sys.path:
    sys.path.insert(0, APPS)

from hw_interface.errors import HwInterfaceError  # noqa: E402
from hw_interface.protocol import Result  # noqa: E402
from motion_apps.program_check import ProgramChecker  # noqa: E402
from motion_apps.program_runner import EXIT_OK, EXIT_REFUSED, EXIT_STOPPED, ProgramRunner  # noqa: E402

from .test_program_check import taught  # noqa: E402


class FakeController:
    """Records every call; ``fail_at`` = (call number, Result) makes that call fail."""

    def __init__(self, robot="ur5e", fail_at=None):
        self.robot = robot
        self.calls = []
        self.fail_at = fail_at
        self.motions = 0

    def _maybe_fail(self, what):
        self.calls.append(what)
        if what[0] in ("move_j", "move_l"):
            self.motions += 1
            if self.fail_at and self.motions == self.fail_at[0]:
                raise HwInterfaceError(f"{what[0].upper()} refused: {self.fail_at[1].name}: test", self.fail_at[1])

    def get_robots(self):
        return [(self.robot, 6)]

    def get_joints(self):
        return list(HOME)

    def get_pose(self):
        return [-0.49, -0.13, 0.49], [0.7071, 0.7071, 0.0, 0.0]

    def move_j(self, joints):
        self._maybe_fail(("move_j", tuple(round(v, 6) for v in joints)))

    def move_l(self, position, orientation):
        self._maybe_fail(("move_l", tuple(position)))

    def set_gripper(self, closed):
        self._maybe_fail(("set_gripper", closed))

    def stop(self):
        self.calls.append(("stop",))


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        self.now += 0.5
        return self.now


@pytest.fixture(scope="module")
def checker():
    checker = ProgramChecker(UR5E, "ur5e")
    yield checker
    checker.close()


def run(controller, checker=None, program=None, dry_run=False, **kwargs):
    lines = []
    runner = ProgramRunner(controller, checker, out=lines.append, clock=Clock(), **kwargs)
    return runner.run(program or taught(), dry_run=dry_run), lines


def test_a_whole_program_runs_in_order(checker):
    controller = FakeController()
    outcome, lines = run(controller, checker)
    assert outcome.ok and outcome.exit_code == EXIT_OK and outcome.done == 6
    kinds = [c[0] for c in controller.calls]
    assert kinds == ["move_j", "move_l", "set_gripper", "move_l", "move_l", "move_l", "set_gripper", "move_l"]
    assert [c[1] for c in controller.calls if c[0] == "set_gripper"] == [True, False]
    assert controller.calls[1][1] == (-0.45, -0.20, 0.045)
    assert lines[0].startswith("check passed: 6 waypoints")
    assert lines[1].startswith("1/6 start_above MoveJ (speed 0.50) ... ok")
    assert lines[2].startswith("2/6 pick MoveL + grip")
    assert "6/6 waypoints done" in lines[-1] and "result SUCCESS" in lines[-1]


@pytest.mark.parametrize("result", [Result.INTERRUPTED, Result.LATCHED_STOP, Result.DRIVER_FAULT])
def test_a_stop_mid_program_ends_the_run_at_that_waypoint(checker, result):
    controller = FakeController(fail_at=(4, result))  # the 4th motion: MoveL to place_above
    outcome, lines = run(controller, checker)
    assert not outcome.ok and outcome.exit_code == EXIT_STOPPED
    assert outcome.result == result
    assert (outcome.stopped_index, outcome.stopped_name, outcome.done) == (3, "place_above", 3)
    assert controller.calls[-1][0] == "move_l" and controller.motions == 4  # nothing after the stop
    assert [c for c in controller.calls if c == ("set_gripper", False)] == []  # the part is not dropped
    assert f"4/6 place_above MoveL (speed 0.50) ... {result.name}" in lines[-3]
    assert "stopped at waypoint 4/6 'place_above' (index 3)" == lines[-2]
    assert "3/6 waypoints done" in lines[-1] and f"result {result.name}" in lines[-1]


def test_a_latched_stop_before_the_start_refuses_the_first_move(checker):
    controller = FakeController(fail_at=(1, Result.LATCHED_STOP))
    outcome, _ = run(controller, checker)
    assert outcome.result == Result.LATCHED_STOP and outcome.stopped_index == 0 and outcome.done == 0


def test_a_gripper_failure_ends_the_run_too(checker):
    class GripFails(FakeController):
        def set_gripper(self, closed):
            raise HwInterfaceError("SET_GRIPPER refused: NOT_CONNECTED", Result.NOT_CONNECTED)

    outcome, _ = run(GripFails(), checker)
    assert (outcome.result, outcome.stopped_name, outcome.done) == (Result.NOT_CONNECTED, "pick", 1)


def test_another_robot_is_refused_before_anything_moves(checker):
    controller = FakeController(robot="ur10e")
    outcome, lines = run(controller, checker)
    assert outcome.refused and outcome.exit_code == EXIT_REFUSED
    assert "taught on robot 'ur5e', this robot is 'ur10e'" in lines[0]
    assert [c for c in controller.calls if c[0] != "get_robots"] == []


def test_a_failed_check_refuses_with_reasons(checker):
    program = taught()
    program.waypoints[2].position = [-1.6, 0.0, 0.2]
    controller = FakeController()
    outcome, lines = run(controller, checker, program)
    assert outcome.refused and outcome.exit_code == EXIT_REFUSED and controller.calls == []
    assert "waypoint 2 'lift': unreachable" in lines[0]
    assert "result REFUSED" in lines[-1]


def test_dry_run_checks_only(checker):
    controller = FakeController()
    outcome, lines = run(controller, checker, dry_run=True)
    assert outcome.ok and controller.calls == []
    assert "dry run" in lines[-1]
    offline, _ = run(None, checker, dry_run=True)
    assert offline.ok


def test_the_movej_goes_to_the_checked_joints(checker):
    controller = FakeController()
    outcome, _ = run(controller, checker)
    program = taught()
    assert controller.calls[0][1] == pytest.approx(program.waypoints[0].joints, abs=1e-3)


def test_speed_is_validated_and_reported(checker):
    with pytest.raises(ValueError):
        ProgramRunner(FakeController(), speed=0.0)
    outcome, lines = run(FakeController(), checker, speed=0.5)
    assert "(speed 0.25)" in lines[1]
    assert "speed fraction 0.5 (not sent: commander.srv has no speed field)" in lines[-1]


def test_run_program_help_is_honest_about_speed():
    node = os.path.join(APPS, "nodes", "run_program")
    out = subprocess.run([sys.executable, node, "--help"], capture_output=True, text=True, timeout=30)
    assert out.returncode == 0, out.stderr
    for text in (
        "--dry-run",
        "--speed",
        "--robot",
        "--urdf",
        "--scene",
        "NOT sent to the robot",
        "INTERRUPTED",
        "LATCHED_STOP",
    ):
        assert text in out.stdout
    bad = subprocess.run([sys.executable, node, "x.yaml", "--speed", "1.5"], capture_output=True, text=True, timeout=30)
    assert bad.returncode == 2 and "--speed must be in (0, 1]" in bad.stderr
