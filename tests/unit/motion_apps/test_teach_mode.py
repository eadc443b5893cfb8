"""motion_apps.teach: gesture events and robot poses in, waypoints and operator feedback out."""

import os
import sys

import pytest

from ..conftest import ROOT

APPS = os.path.join(ROOT, "src", "motion_apps")
if APPS not in sys.path:
    sys.path.insert(0, APPS)

from motion_apps.teach import DEFAULT_GESTURES, TeachSession, check_gesture_config, load_gesture_config  # noqa: E402
from motion_commander.program import load_program  # noqa: E402
from motion_common.errors import ParameterError  # noqa: E402

CONFIG = os.path.join(APPS, "config", "gesture_commands.yaml")
DOWN = [1.0, 0.0, 0.0, 0.0]
JOINTS = [0.1, -1.4, 1.6, -1.8, -1.57, 0.1]


class Robot:
    """The pose callback: the test moves the tool by setting ``position``."""

    def __init__(self):
        self.position = [-0.4, -0.2, 0.2]
        self.state = True

    def __call__(self):
        if not self.state:
            return None
        return list(self.position), list(DOWN), list(JOINTS)


@pytest.fixture
def robot():
    return Robot()


@pytest.fixture
def session(robot, tmp_path):
    clock = iter(range(1000, 100000, 10)).__next__  # 10 s between events: no repeat guard
    return TeachSession(
        "ur5e",
        robot,
        programs_dir=str(tmp_path / "programs"),
        program_name="demo",
        config=load_gesture_config(CONFIG),
        clock=clock,
    )


def test_the_shipped_config_maps_the_issue_gestures():
    config = load_gesture_config(CONFIG)
    assert config["commands"] == DEFAULT_GESTURES
    assert config["repeat_guard_s"] == 1.0


def test_bad_configs_name_the_file_and_key(tmp_path):
    bad = tmp_path / "g.yaml"
    bad.write_text("commands: {fist: grab}\n")
    with pytest.raises(ParameterError, match=r"g\.yaml.*'fist' maps to unknown command 'grab'"):
        load_gesture_config(str(bad))
    bad.write_text("repeat_guard: 1.0\n")
    with pytest.raises(ParameterError, match=r"g\.yaml: unknown parameter 'repeat_guard'; valid keys"):
        load_gesture_config(str(bad))
    with pytest.raises(ParameterError, match="speed"):
        check_gesture_config({"speed": 0.0}, "x.yaml")


def test_teach_a_pick_and_place_and_save(session, robot, tmp_path):
    said = [session.on_gesture("hold_still")]
    robot.position = [-0.4, -0.2, 0.05]
    said.append(session.on_gesture("fist"))
    robot.position = [-0.3, -0.2, 0.2]
    said.append(session.on_gesture("hold_still"))
    robot.position = [-0.3, -0.2, 0.05]
    said.append(session.on_gesture("open_palm"))
    said.append(session.on_gesture("circle"))
    assert all(f.understood for f in said), [str(f) for f in said]
    assert [f.command for f in said] == ["mark_waypoint", "grip", "mark_waypoint", "release", "save"]
    assert "grip 2" in str(said[1]) and "(-0.400, -0.200, 0.050) m" in str(said[1])
    path = str(tmp_path / "programs" / "demo.yaml")
    assert str(said[-1]) == f"saved 4 waypoints to {path}"
    program = load_program(path)
    assert program.robot == "ur5e"
    assert [w.action for w in program.waypoints] == ["none", "grip", "none", "release"]
    assert program.waypoints[1].position == [-0.4, -0.2, 0.05]
    assert program.waypoints[1].joints == JOINTS
    assert all(w.speed == 0.5 for w in program.waypoints)


def test_every_ignored_event_says_why(session, robot):
    first = session.on_gesture("wave")
    assert not first.understood and "gesture 'wave' has no teach command" in str(first)
    assert "nothing is gripped" in str(session.on_gesture("open_palm"))
    assert "no waypoint to undo" in str(session.on_gesture("swipe_left"))
    assert "nothing to save" in str(session.on_gesture("circle"))
    robot.state = False
    assert "no robot pose yet" in str(session.on_gesture("hold_still"))
    robot.state = True
    assert session.on_gesture("hold_still").understood
    same = session.on_gesture("hold_still")
    assert not same.understood and "still at waypoint 1" in str(same)
    assert session.on_gesture("fist").understood
    again = session.on_gesture("fist")
    assert not again.understood and "already gripping" in str(again)
    assert "unknown command" in str(session.handle_command("jump"))
    assert len(session.waypoints) == 2


def test_a_held_gesture_counts_once(robot, tmp_path):
    session = TeachSession("ur5e", robot, programs_dir=str(tmp_path), config={"repeat_guard_s": 1.0})
    assert session.on_gesture("hold_still", stamp=10.0).understood
    robot.position = [0.0, 0.4, 0.3]
    held = session.on_gesture("hold_still", stamp=10.5)
    assert not held.understood and "repeated within 1 s" in str(held)
    assert session.on_gesture("hold_still", stamp=12.0).understood


def test_undo_removes_the_last_waypoint_and_its_gripper_state(session, robot):
    session.on_gesture("hold_still")
    robot.position = [-0.4, -0.2, 0.05]
    session.on_gesture("fist")
    assert session.gripping
    undo = session.on_gesture("swipe_left")
    assert undo.understood and "removed waypoint 2 'grip2'; 1 left" == str(undo)
    assert not session.gripping
    assert session.on_gesture("fist").understood  # can grip again


def test_invalid_poses_are_not_recorded(session, robot):
    robot.position = [float("nan"), 0.0, 0.2]
    assert "invalid" in str(session.on_gesture("hold_still"))

    def broken():
        raise RuntimeError("tf timeout")

    session.robot_state = broken
    assert "tf timeout" in str(session.on_gesture("hold_still"))
    assert session.waypoints == []


def test_saving_again_rewrites_the_same_file(session, robot, tmp_path):
    session.on_gesture("hold_still")
    first = session.on_gesture("circle")
    robot.position = [-0.3, -0.1, 0.2]
    session.on_gesture("hold_still")
    second = session.on_gesture("circle")
    assert first.understood and second.understood and session.saved_path
    assert len(load_program(session.saved_path).waypoints) == 2
    assert os.listdir(tmp_path / "programs") == ["demo.yaml"]


def test_default_programs_folder_and_name(robot):
    session = TeachSession("ur5e", robot, clock=lambda: 0.0)
    assert session.programs_dir == os.path.join("output", "programs")
    assert session.program_name.startswith("teach_")


@pytest.mark.parametrize("name", ["../escaped", "a/b", ".hidden", "..", "x\0y"])
def test_program_name_is_a_plain_name(tmp_path, name):
    """The same rule as the dashboard's: a name can never reach outside the programs folder."""
    with pytest.raises(ValueError, match="not a program name"):
        TeachSession("ur5e", lambda: None, programs_dir=str(tmp_path), program_name=name)
    assert list(tmp_path.iterdir()) == []
