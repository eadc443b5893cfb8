"""Replays a taught program through the manipulation API (plain Python, no rospy).

``ProgramRunner(controller, checker).run(program)``: the controller is anything with the
methods of hw_interface's MotionControllerClient (get_robots, get_joints, move_j, move_l,
set_gripper), raising an exception with a ``result`` code (HwInterfaceError) on refusal.

1. Check first (program_check.ProgramChecker, from the robot's current joints): any issue
   refuses the whole program before anything moves.
2. MoveJ to the first waypoint (to the IK solution the check found, seeded with the
   recorded joints), MoveL to each following one; at a waypoint whose action is grip or
   release the gripper is switched once the pose is reached.
3. Any refusal or failure ends the run at once, reporting the waypoint (index and name):
   INTERRUPTED (a move cut short by STOP, a latched stop, a fault), LATCHED_STOP (the
   server's latched stop is on), or any other result. The gripper is left as it is (a
   held part is not dropped in mid-air).

One progress line per waypoint ("3/7 place_above MoveL ... ok (1.2 s)") and a summary.

Speed: commander.srv has no speed field, so the speed fraction (each waypoint's recorded
``speed`` times ``speed``) is validated, shown per waypoint and in the summary, but the
robot moves at its driver's configured speed (pybullet: ``speed_scale`` and
``cartesian_speed`` in hw_interface/config/sim_driver.yaml; UR: ``joint_speed`` and
``linear_speed`` in ur_driver.yaml).
"""

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from hw_interface.protocol import Result
from motion_commander.manipulation import ManipulationAPI

#: Exit codes of run_program.
EXIT_OK, EXIT_STOPPED, EXIT_REFUSED = 0, 1, 2


@dataclass
class RunOutcome:
    """How a run ended."""

    ok: bool
    result: int | None  # commander.srv Result of the failing answer (None: refused / success)
    done: int  # waypoints completed (pose reached and action done)
    total: int
    elapsed: float  # s
    stopped_index: int | None = None
    stopped_name: str = ""
    reason: str = ""
    refused: bool = False
    lines: list[str] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        return EXIT_OK if self.ok else (EXIT_REFUSED if self.refused else EXIT_STOPPED)

    @property
    def result_name(self) -> str:
        if self.ok:
            return "SUCCESS"
        if self.refused:
            return "REFUSED"
        try:
            return Result(self.result).name
        except (ValueError, TypeError):
            return f"ERROR {self.result}"


class ProgramRunner:
    """Checks and runs programs on one controller; ``out`` receives each line printed."""

    def __init__(
        self,
        controller,
        checker=None,
        speed: float = 1.0,
        robot_name: str | None = None,
        out: Callable[[str], None] = print,
        clock: Callable[[], float] = time.monotonic,
        on_waypoint: Callable[[int, object], None] | None = None,
    ):
        if not 0.0 < float(speed) <= 1.0:
            raise ValueError(f"speed must be a fraction in (0, 1], got {speed!r}")
        self.controller = controller
        self.api = ManipulationAPI(controller)
        self.checker = checker
        self.speed = float(speed)
        self.robot_name = robot_name
        self.out = out
        self.clock = clock
        self.on_waypoint = on_waypoint  # called (index, waypoint) as each waypoint starts

    def robot(self) -> str:
        """The robot's name: ``robot_name`` if given, else the server's (GET_ROBOTS)."""
        if self.robot_name:
            return self.robot_name
        robots = self.controller.get_robots()
        return robots[0][0] if robots else ""

    def check(self, program, start_joints=None):
        """The checker's report (robot name mismatch included); None without a checker."""
        if self.checker is None:
            return None
        return self.checker.check(program, start_joints)

    def run(self, program, dry_run: bool = False) -> RunOutcome:
        """Check, then (unless ``dry_run``) run the whole program; never raises on a refusal."""
        start = self.clock()
        total = len(program.waypoints)
        outcome = RunOutcome(ok=False, result=None, done=0, total=total, elapsed=0.0)

        def say(line):
            outcome.lines.append(line)
            self.out(line)

        try:
            if self.controller is None:  # an offline dry run: no server to ask
                if not dry_run:
                    raise ValueError("running a program needs a controller")
                robot, start_joints = self.robot_name or "", None
            else:
                robot, start_joints = self.robot(), self.api.info_get_joints()
        except Exception as exc:
            if not hasattr(exc, "result"):
                raise
            outcome.result, outcome.reason = int(exc.result), f"cannot read the robot: {exc}"
            say(f"cannot read the robot: {exc}")
            return self._finish(outcome, start, say)
        if robot and program.robot != robot:
            outcome.refused = True
            outcome.reason = (
                f"program taught on robot {program.robot!r}, this robot is {robot!r}: "
                "refusing to replay it on another robot"
            )
            say("check REFUSED the program:\n  - " + outcome.reason)
            return self._finish(outcome, start, say)
        report = self.check(program, start_joints)
        targets = [w.joints for w in program.waypoints]
        if report is not None:
            say(report.text())
            if not report.ok:
                outcome.refused = True
                outcome.reason = "; ".join(str(issue) for issue in report.issues)
                return self._finish(outcome, start, say)
            targets = report.joints
        else:
            say("no check configured: running unchecked")
        if dry_run:
            outcome.ok = True
            outcome.reason = "dry run: checked only, nothing moved"
            return self._finish(outcome, start, say)
        for index, wp in enumerate(program.waypoints):
            if self.on_waypoint is not None:
                self.on_waypoint(index, wp)
            motion = "MoveJ" if index == 0 else "MoveL"
            action = "" if wp.action == "none" else f" + {wp.action}"
            head = f"{index + 1}/{total} {wp.name} {motion}{action} (speed {wp.speed * self.speed:.2f})"
            t0 = self.clock()
            try:
                if index == 0:
                    self.api.move_j(targets[0])
                else:
                    self.controller.move_l(list(wp.position), list(wp.orientation))
                if wp.action != "none":
                    self.controller.set_gripper(wp.action == "grip")
            except Exception as exc:
                if not hasattr(exc, "result"):
                    raise
                outcome.result = int(exc.result)
                outcome.stopped_index, outcome.stopped_name = index, wp.name
                outcome.reason = str(exc)
                say(f"{head} ... {outcome.result_name}: {exc}")
                say(f"stopped at waypoint {index + 1}/{total} {wp.name!r} (index {index})")
                return self._finish(outcome, start, say)
            outcome.done = index + 1
            say(f"{head} ... ok ({self.clock() - t0:.1f} s)")
        outcome.ok = True
        return self._finish(outcome, start, say)

    def _finish(self, outcome: RunOutcome, start: float, say) -> RunOutcome:
        outcome.elapsed = self.clock() - start
        say(
            f"=== program summary: {outcome.done}/{outcome.total} waypoints done in {outcome.elapsed:.1f} s, "
            f"result {outcome.result_name}"
            + (f" ({outcome.reason})" if outcome.reason and not outcome.ok else "")
            + (f"; {outcome.reason}" if outcome.ok and outcome.reason else "")
            + f"; speed fraction {self.speed:g} (not sent: commander.srv has no speed field) ==="
        )
        return outcome
