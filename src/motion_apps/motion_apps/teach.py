"""Teach mode: gesture events in, waypoints and operator feedback out (plain Python).

A teach node (the ROS edge) feeds ``TeachSession.on_gesture(name, stamp)`` with every
recognised gesture (fist, open_palm, hold_still, swipe_left, circle, ...); the gesture is
mapped to a teach command by ``config/gesture_commands.yaml`` (``load_gesture_config``)
and handled by ``TeachSession.handle_command(command, stamp)``:

  mark_waypoint  record the current tool pose and joints as a waypoint (action none)
  grip           record a waypoint at the current pose whose action closes the gripper
  release        record a waypoint at the current pose whose action opens the gripper
  undo           remove the last waypoint (and the gripper state it set)
  save           write the program atomically to ``<programs_dir>/<program_name>.yaml``
  stop           end teaching: save what is unsaved, then take no further gesture
                 (the skeleton gestures' "shake", ``config/skeleton_gesture_commands.yaml``)

The robot state comes from a callback ``robot_state() -> (position [m], quaternion
x, y, z, w, joints [rad])`` (e.g. the latest /motion_controller/tool_pose and
/joint_states); it may return None while nothing has been received yet. Every event
returns a ``Feedback``: ``understood`` and a sentence for the operator saying what was
done, or why the event was ignored.

Programs go to ``output/programs/`` by default (relative to the current directory: a ROS
node should pass an absolute ``programs_dir``).
"""

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

from motion_commander.program import Program, ProgramError, Waypoint, program_path, save_program
from motion_common.atomic_file import remove_stale_temp_files
from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema, read_yaml_file
from motion_common.rotations import is_unit_quaternion, quaternion_norm

COMMANDS = ("mark_waypoint", "grip", "release", "undo", "save", "stop")
DEFAULT_PROGRAMS_DIR = os.path.join("output", "programs")
DEFAULT_GESTURES = {
    "hold_still": "mark_waypoint",
    "fist": "grip",
    "open_palm": "release",
    "swipe_left": "undo",
    "circle": "save",
}

GESTURE_SCHEMA = ParamSchema(
    [
        Param("commands", dict(DEFAULT_GESTURES), doc="recognised gesture name -> teach command " + "|".join(COMMANDS)),
        Param(
            "repeat_guard_s",
            1.0,
            "s",
            "a gesture repeated within this time is the same one held: ignored",
            low=0.0,
            high=10.0,
        ),
        Param("speed", 0.5, "1", "speed fraction stored in each taught waypoint", low=0.0, high=1.0, low_open=True),
        Param(
            "min_waypoint_distance",
            0.005,
            "m",
            "a mark this close to the last waypoint is ignored ...",
            low=0.0,
            high=1.0,
        ),
        Param(
            "min_waypoint_angle", 0.05, "rad", "... unless the tool turned at least this much", low=0.0, high=math.pi
        ),
    ],
    ignore=("config_file",),
)


def check_gesture_config(values: dict | None, source: str) -> dict:
    """Checked gesture configuration (defaults filled in); ParameterError names ``source``."""
    config = GESTURE_SCHEMA.validate(values, source)
    for gesture, command in config["commands"].items():
        if not isinstance(gesture, str) or not gesture:
            raise ParameterError(f"{source}: parameter 'commands': gesture names are strings, got {gesture!r}")
        if command not in COMMANDS:
            raise ParameterError(
                f"{source}: parameter 'commands': gesture {gesture!r} maps to unknown command "
                f"{command!r}; commands are {list(COMMANDS)}"
            )
    return config


def load_gesture_config(path: str) -> dict:
    """Read and check a gesture_commands.yaml; ParameterError names the file."""
    return check_gesture_config(read_yaml_file(path), path)


@dataclass
class Feedback:
    """The answer to one event: whether it did something, and what to tell the operator."""

    understood: bool
    command: str
    text: str

    def __str__(self) -> str:
        return self.text


class TeachSession:
    """The teach-mode state machine of one program.

    ``robot_state`` returns (position, orientation, joints) or None; ``clock`` gives
    seconds (event stamps default to it). Thread-unsafe by design: a node calls it from
    one callback queue (or under its own lock).
    """

    def __init__(
        self,
        robot: str,
        robot_state: Callable[[], tuple | None],
        tool_frame: str = "tool0",
        programs_dir: str = DEFAULT_PROGRAMS_DIR,
        program_name: str | None = None,
        config: dict | None = None,
        clock: Callable[[], float] = time.time,
    ):
        if not robot:
            raise ValueError("robot: name the robot being taught (GET_ROBOTS name)")
        self.robot = robot
        self.tool_frame = tool_frame
        self.robot_state = robot_state
        self.programs_dir = programs_dir
        self.clock = clock
        self.program_name = program_name or time.strftime("teach_%Y%m%d_%H%M%S", time.localtime(clock()))
        program_path(programs_dir, self.program_name)  # ValueError now, not at the first save
        # Temporary files of saves that were killed go at start, not only at the next save.
        remove_stale_temp_files(programs_dir)
        # Checking an already checked config is harmless: pass load_gesture_config's result.
        self.config = check_gesture_config(config, "teach config")
        self.waypoints: list[Waypoint] = []
        self.gripping = False
        self.saved_path: str | None = None
        self.dirty = False
        self._last_gesture: dict[str, float] = {}
        self._counter = 0
        self.stopped = False

    # -- events ----------------------------------------------------------------------------
    def on_gesture(self, gesture: str, stamp: float | None = None) -> Feedback:
        """A recognised gesture: map it to its command (ignore unmapped or held ones)."""
        stamp = self.clock() if stamp is None else float(stamp)
        command = self.config["commands"].get(gesture)
        if command is None:
            mapped = ", ".join(f"{g}={c}" for g, c in sorted(self.config["commands"].items()))
            return Feedback(False, "", f"ignored: gesture {gesture!r} has no teach command ({mapped})")
        last = self._last_gesture.get(gesture)
        self._last_gesture[gesture] = stamp
        if last is not None and 0.0 <= stamp - last < self.config["repeat_guard_s"]:
            return Feedback(
                False,
                command,
                f"ignored: {gesture} repeated within {self.config['repeat_guard_s']:g} s (still the same gesture)",
            )
        return self.handle_command(command, stamp)

    def handle_command(self, command: str, stamp: float | None = None) -> Feedback:
        """A teach command (from a gesture, a button or a service)."""
        if command not in COMMANDS:
            return Feedback(False, command, f"ignored: unknown command {command!r}; commands are {list(COMMANDS)}")
        if self.stopped:
            return Feedback(False, command, "ignored: teaching was stopped")
        return getattr(self, "_do_" + command)()

    # -- commands --------------------------------------------------------------------------
    def _state(self):
        try:
            state = self.robot_state()
        except Exception as exc:  # the source's problem is the operator's information
            return None, f"no robot pose: {exc}"
        if state is None:
            return None, "no robot pose yet (is the robot state being received?)"
        position, orientation, joints = (list(map(float, v)) for v in state)
        values = position + orientation + joints
        if len(position) != 3 or len(orientation) != 4 or not joints or not all(map(math.isfinite, values)):
            return None, "the robot pose is invalid (non-finite or wrong length)"
        norm = quaternion_norm(orientation)
        if not is_unit_quaternion(orientation):
            return None, f"the robot orientation is not a unit quaternion (norm {norm:.4f})"
        return (position, [v / norm for v in orientation], joints), ""

    def _record(self, command: str, action: str) -> Feedback:
        state, why = self._state()
        if state is None:
            return Feedback(False, command, f"ignored: {why}")
        position, orientation, joints = state
        if action == "none" and self.waypoints:
            last = self.waypoints[-1]
            distance = math.dist(position, last.position)
            dot = min(1.0, abs(sum(a * b for a, b in zip(orientation, last.orientation))))
            angle = 2.0 * math.acos(dot)
            if distance < self.config["min_waypoint_distance"] and angle < self.config["min_waypoint_angle"]:
                return Feedback(
                    False,
                    command,
                    f"ignored: the tool is still at waypoint {len(self.waypoints)} "
                    f"{last.name!r} ({distance * 1000:.1f} mm away); move first",
                )
        self._counter += 1
        name = f"wp{self._counter}" if action == "none" else f"{action}{self._counter}"
        self.waypoints.append(
            Waypoint(
                name=name,
                position=position,
                orientation=orientation,
                joints=joints,
                action=action,
                speed=self.config["speed"],
            )
        )
        self.dirty = True
        where = "(" + ", ".join(f"{v:.3f}" for v in position) + ") m"
        what = {"none": "waypoint", "grip": "grip", "release": "release"}[action]
        return Feedback(True, command, f"{what} {len(self.waypoints)} {name!r} recorded at {where}")

    def _do_mark_waypoint(self) -> Feedback:
        return self._record("mark_waypoint", "none")

    def _do_grip(self) -> Feedback:
        if self.gripping:
            return Feedback(False, "grip", "ignored: already gripping (release first)")
        feedback = self._record("grip", "grip")
        if feedback.understood:
            self.gripping = True
        return feedback

    def _do_release(self) -> Feedback:
        if not self.gripping:
            return Feedback(False, "release", "ignored: nothing is gripped (grip first)")
        feedback = self._record("release", "release")
        if feedback.understood:
            self.gripping = False
        return feedback

    def _do_undo(self) -> Feedback:
        if not self.waypoints:
            return Feedback(False, "undo", "ignored: no waypoint to undo")
        removed = self.waypoints.pop()
        if removed.action == "grip":
            self.gripping = False
        elif removed.action == "release":
            self.gripping = True
        self.dirty = True
        return Feedback(
            True, "undo", f"removed waypoint {len(self.waypoints) + 1} {removed.name!r}; {len(self.waypoints)} left"
        )

    def _do_save(self) -> Feedback:
        if not self.waypoints:
            return Feedback(False, "save", "ignored: nothing to save (no waypoints yet)")
        path = program_path(self.programs_dir, self.program_name)
        try:
            self.saved_path = save_program(self.program(), path)
        except (OSError, ProgramError) as exc:
            return Feedback(False, "save", f"NOT saved: {exc}")
        self.dirty = False
        note = " (still gripping: the program ends holding the part)" if self.gripping else ""
        return Feedback(True, "save", f"saved {len(self.waypoints)} waypoints to {self.saved_path}{note}")

    def _do_stop(self) -> Feedback:
        saved = self._do_save() if self.dirty and self.waypoints else None
        if saved is not None and not saved.understood:
            return Feedback(False, "stop", f"not stopped: {saved.text}")
        self.stopped = True
        return Feedback(True, "stop", "teaching stopped" + (f"; {saved.text}" if saved else ""))

    # -- result ----------------------------------------------------------------------------
    def program(self) -> Program:
        """The program taught so far."""
        return Program(robot=self.robot, tool_frame=self.tool_frame, waypoints=list(self.waypoints))
