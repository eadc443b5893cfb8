"""CommandDispatcher: checks every commander.srv request, then calls the driver.

A refused request never reaches the driver; the answer always carries a Result code and
a reason the server logs. This is the logic of motion_controller_server, kept out of the
node so it is testable without ROS.

A LATCHED STOP (``latch_stop`` / ``release_stop``) reaches every client at once: the
robot stops, a blocking move in progress answers INTERRUPTED, and every motion command
(SET_JOINTS, MOVE_J, MOVE_L, FOLLOW_PATH) is refused with LATCHED_STOP until it is released.

FOLLOW_PATH (a timed joint path, hw_interface.timed_path) is checked whole before the
driver sees it; it blocks as MOVE_J does and shares its BUSY.
"""

import math
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from motion_common.float_list import float_list
from motion_common.rotations import is_unit_quaternion

from .errors import HwInterfaceError
from .protocol import CommandIndex, Result
from .robot_hw import RobotDriver
from .timed_path import TimedPath, check_path_start, check_timed_path


@dataclass
class Workspace:
    """Axis-aligned box (m, robot base frame) the tool must stay inside."""

    lower: np.ndarray = field(default_factory=lambda: np.array([-2.0, -2.0, 0.0]))
    upper: np.ndarray = field(default_factory=lambda: np.array([2.0, 2.0, 2.0]))

    def contains(self, position) -> bool:
        """True when ``position`` lies inside the box."""
        p = np.asarray(position, dtype=float)
        return bool(np.all(p >= self.lower) and np.all(p <= self.upper))


@dataclass
class CommandResult:
    """What the server answers: result code, reason, and the robot's current state."""

    result: Result
    reason: str = ""
    joints: Sequence[float] = ()
    position: Sequence[float] = ()
    orientation: Sequence[float] = ()
    robots: Sequence = ()
    started: float | None = None  # FOLLOW_PATH: when the path started (wall-clock s, the robot's stamps)


# s: a streamed target arriving later than this after the previous one starts a new stream,
# compared with the measured joints (teleop streams at 30-500 Hz; a pause means a new start).
STREAM_REFERENCE_TIMEOUT = 0.25
MOTION_COMMANDS = (CommandIndex.SET_JOINTS, CommandIndex.MOVE_J, CommandIndex.MOVE_L, CommandIndex.FOLLOW_PATH)

#: How to release a latched stop, for refusal messages.
RELEASE_HINT = (
    'release it with `rosservice call /motion_controller/latch_stop "data: false"` '
    "(or publish False on /motion_commander/estop)"
)


def stop_driver(driver: RobotDriver, reason: str) -> None:
    """driver.stop(reason), for drivers whose stop() takes no reason too (plugins)."""
    try:
        driver.stop(reason=reason)
    except TypeError:
        driver.stop()


class CommandDispatcher:
    """Validates and executes commander.srv requests on one driver (thread-safe)."""

    def __init__(
        self,
        driver: RobotDriver,
        workspace: Workspace | None = None,
        max_stream_step: float = 0.2,
        user: str = "",
        password: str = "",
        move_timeout: float = 30.0,
        max_stream_lag: float = 0.6,
        clock=time.monotonic,
        stream_start_tolerance: float = 0.05,
    ):
        self.driver = driver
        self.workspace = workspace or Workspace()
        # Largest joint change (rad) one streamed SetJoints may ask for: teleop streams
        # small steps, so a bigger one is a jump the robot must never execute.
        self.max_stream_step = float(max_stream_step)
        # A servo follows its stream with a delay (ur_rtde servoJ: about lookahead_time), so
        # while streaming each target is compared with the previous accepted one, not with
        # the lagging measured joints; the lag itself is bounded separately, so a stream
        # can never run away from a robot that does not follow.
        self.max_stream_lag = float(max_stream_lag)
        # A stream starts where the robot is: its first target (after a (re)start, a STOP, a
        # move or a pause) must lie within this of the measured joints. A client that kept
        # streaming through a server restart sends targets from before it, and those are
        # refused until it engages afresh from the measured joints.
        self.stream_start_tolerance = min(float(stream_start_tolerance), self.max_stream_step)
        self._clock = clock
        self._stream_lock = threading.Lock()  # service threads stream concurrently
        self._stream_reference: np.ndarray | None = None
        self._stream_time = float("-inf")
        # The driver's joint limits as float lists, read once (every streamed command is
        # checked against them) and again after each LOGIN, which may load another model.
        self._limit_lists = None
        self._user = user
        self._password = password
        self._blocking_motion = threading.Lock()
        # Longest a MOVE_J/MOVE_L may run (s) before the robot is stopped and TIMEOUT answered.
        self.move_timeout = float(move_timeout)
        # _gate orders the latch against motion commands: a command checks the latch and
        # registers as in flight under it, so a latch never misses a motion starting.
        self._gate = threading.Lock()
        self._latched = False
        self._latch_source = ""
        self._in_flight = 0  # motion commands past the latch check, not yet returned
        self._stop_epoch = 0  # increases with every STOP / latch

    # -- latched stop ----------------------------------------------------------------------
    @property
    def latched(self) -> bool:
        """True while a latched stop is active."""
        return self._latched

    @property
    def latch_source(self) -> str:
        """Who engaged the active latched stop ("" when released)."""
        return self._latch_source

    def latch_stop(self, source: str = "latch_stop") -> str:
        """Engage the latched stop: stop the robot now, refuse motion until released."""
        with self._gate:
            already = self._latched
            self._latched = True
            if not already:
                self._latch_source = source
        self._stop(f"latched stop ({source})")
        return (
            f"stop already latched (by {self._latch_source}); robot stopped again"
            if already
            else f"stop latched by {source}: robot stopped, motion refused until released"
        )

    def release_stop(self, source: str = "latch_stop") -> str:
        """Release the latched stop; motion commands are accepted again.

        Only the channel that latched it may release it: a button that keeps publishing
        False on the e-stop topic must not lift a stop an operator latched by service."""
        with self._gate:
            was, by = self._latched, self._latch_source
            if was and by != source:
                return (
                    f"stop NOT released: it was latched by {by}, release it there "
                    f"(a release from {source} cannot lift it)"
                )
            self._latched, self._latch_source = False, ""
        return f"stop released by {source}" if was else "no stop was latched"

    def _stop(self, reason: str) -> None:
        """Stop the driver; while a motion command that passed the latch check is still
        starting, stop again each few ms (bounded) so a move issued just after the first
        stop is cut short too."""
        with self._gate:
            self._stop_epoch += 1
            epoch, in_flight = self._stop_epoch, self._in_flight
        self._note_stream(None)  # after a stop, a stream restarts from where the robot is
        stop_driver(self.driver, reason)
        if in_flight:
            threading.Thread(target=self._restop, args=(epoch, reason), name="restop", daemon=True).start()

    def _restop(self, epoch, reason, period=0.01):
        # Until every motion command that passed the latch check has returned (a move may
        # start late: a reconnect backoff, a busy machine), bounded by the move timeout.
        deadline = time.monotonic() + self.move_timeout
        while time.monotonic() < deadline:
            time.sleep(period)
            with self._gate:
                if self._in_flight == 0 or self._stop_epoch != epoch:
                    return
            try:
                stop_driver(self.driver, reason)
            except Exception:  # the first stop already reported; keep the server alive
                return

    def handle(
        self, command_index: int, position=(), orientation=(), joints=(), url: str = "", times=()
    ) -> CommandResult:
        """Run one request; never raises, every failure becomes a Result code. ``times``:
        FOLLOW_PATH's sample times (s), ``joints`` then its samples one after another."""
        try:
            command = CommandIndex(command_index)
        except ValueError:
            known = ", ".join(f"{c.name}={c.value}" for c in CommandIndex)
            return CommandResult(Result.UNKNOWN_COMMAND, f"unknown command_index {command_index}; known: {known}")
        motion = command in MOTION_COMMANDS
        try:
            refusal = self._validate(command, position, orientation, joints)
            if refusal is not None:
                return self._answer(refusal[0], refusal[1])
            if motion:
                with self._gate:
                    if self._latched:
                        return self._answer(
                            Result.LATCHED_STOP,
                            (
                                f"{command.name} refused: a latched stop is active (set by {self._latch_source}); "
                                + RELEASE_HINT
                            ),
                        )
                    self._in_flight += 1
                    epoch = self._stop_epoch
            try:
                # A path is checked once in flight (60000 samples take ~0.1 s): a STOP that
                # comes meanwhile is repeated until it returns, and cuts the path it starts.
                path = None
                if command == CommandIndex.FOLLOW_PATH:
                    path = self._check_path(times, joints)
                    with self._gate:
                        if self._stop_epoch != epoch:  # a STOP came during the check: never start
                            raise HwInterfaceError(
                                "FOLLOW_PATH interrupted by a STOP before it started", Result.INTERRUPTED
                            )
                robots, started = self._execute(command, position, orientation, joints, url, path)
            finally:
                if motion:
                    with self._gate:
                        self._in_flight -= 1
                        stopped_meanwhile = self._stop_epoch != epoch
            if motion and stopped_meanwhile:
                # A STOP or latch came while this command was under way: whatever the
                # driver said, it did not complete as asked. Stop again, never SUCCESS.
                stop_driver(self.driver, "a STOP during the command")
                raise HwInterfaceError(f"{command.name} interrupted by a STOP while it ran", Result.INTERRUPTED)
            answer = self._answer(Result.SUCCESS, "", robots)
            answer.started = started
            return answer
        except HwInterfaceError as exc:
            reason = str(exc)
            if exc.result == Result.INTERRUPTED and self._latched:
                reason += f"; a latched stop is active (set by {self._latch_source}): " + RELEASE_HINT
            return self._answer(Result(exc.result), reason)
        except Exception as exc:  # a driver bug must not kill the server; report it
            return self._answer(Result.DRIVER_FAULT, f"driver error: {type(exc).__name__}: {exc}")

    # -- validation ------------------------------------------------------------------------
    def _validate(self, command, position, orientation, joints):
        dof = len(self.driver.joint_names)
        if command in (CommandIndex.SET_JOINTS, CommandIndex.MOVE_J):
            return self._check_joints(command, joints, dof)
        if command == CommandIndex.MOVE_L:
            return self._check_pose(position, orientation)
        if command == CommandIndex.SET_GRIPPER:
            if len(joints) != 1 or joints[0] not in (0.0, 1.0):
                return Result.WRONG_LENGTH, "SET_GRIPPER needs joints = [1] to grip or [0] to release"
        if command == CommandIndex.SET_DIGITAL_OUTPUT:
            if len(joints) == 2 and not np.all(np.isfinite(np.asarray(joints, dtype=float))):
                return Result.NOT_FINITE, "SET_DIGITAL_OUTPUT: joints contains NaN or inf"
            if len(joints) != 2 or joints[1] not in (0.0, 1.0) or joints[0] != int(joints[0]) or joints[0] < 0:
                return Result.WRONG_LENGTH, "SET_DIGITAL_OUTPUT needs joints = [output number, 0 or 1]"
        return None

    def _check_joints(self, command, joints, dof):
        if len(joints) != dof:
            return Result.WRONG_LENGTH, f"joints needs {dof} values for this robot, got {len(joints)}"
        # Every streamed command passes here, on its latency: plain floats, since a numpy
        # call on a 6-vector costs several times this arithmetic when the caches are cold
        # between two commands (bench/e2e_latency).
        q = [float(v) for v in joints]
        if not all(map(math.isfinite, q)):
            return Result.NOT_FINITE, f"joints contains NaN or inf: {q}"
        lower, upper = self._joint_limit_lists()
        outside = [i for i, (v, low, high) in enumerate(zip(q, lower, upper)) if v < low or v > high]
        if outside:
            names = [self.driver.joint_names[i] for i in outside]
            return Result.JOINT_LIMIT, f"joints {names} outside their limits"
        if command == CommandIndex.SET_JOINTS:
            current = float_list(self.driver.get_robot_joints())
            with self._stream_lock:
                fresh = self._clock() - self._stream_time <= STREAM_REFERENCE_TIMEOUT
                reference = self._stream_reference if fresh and self._stream_reference is not None else None
            base = current if reference is None else float_list(reference)
            step = max(abs(v - b) for v, b in zip(q, base))
            if reference is None and step > self.stream_start_tolerance:
                return Result.TOO_FAR, (
                    f"SET_JOINTS starts a stream {step:.3f} rad from the measured joints (limit "
                    f"{self.stream_start_tolerance:.3f}): a stream must start where the robot is; engage afresh "
                    "from the measured joints (use MOVE_J for large motions)"
                )
            against = "the last streamed target" if reference is not None else "the robot"
            if step > self.max_stream_step:
                return Result.TOO_FAR, (
                    f"SET_JOINTS target is {step:.3f} rad from {against} (limit "
                    f"{self.max_stream_step:.3f}); use MOVE_J for large motions"
                )
            lag = max(abs(v - c) for v, c in zip(q, current))
            if lag > self.max_stream_lag:
                return Result.TOO_FAR, (
                    f"SET_JOINTS target is {lag:.3f} rad ahead of the robot (limit "
                    f"{self.max_stream_lag:.3f}): the robot is not following the stream; "
                    "slow the stream down or check the robot"
                )
        return None

    def _joint_limit_lists(self):
        """The driver's (lower, upper) joint limits as lists, read once per login."""
        if self._limit_lists is None:
            self._limit_lists = tuple(float_list(limits) for limits in self.driver.joint_limits)
        return self._limit_lists

    def _check_path(self, times, joints) -> TimedPath:
        """The request's timed path, checked against the driver's limits (raises the refusal)."""
        limits = self.driver.path_limits()
        if limits is None:
            name = self.driver.name or type(self.driver).__name__
            raise HwInterfaceError(
                f"FOLLOW_PATH refused: the {name} driver cannot follow a timed path (it declares no path_limits); "
                "stream the path with SET_JOINTS instead",
                Result.NOT_SUPPORTED,
            )
        return check_timed_path(times, joints, self.driver.joint_names, self._joint_limit_lists(), limits[0], limits[1])

    def _note_stream(self, target: np.ndarray | None) -> None:
        """Remember the last accepted streamed target (None: the stream was broken off)."""
        with self._stream_lock:
            self._stream_reference = target
            self._stream_time = self._clock() if target is not None else float("-inf")

    def _check_pose(self, position, orientation):
        if len(position) != 3 or len(orientation) != 4:
            return Result.WRONG_LENGTH, (
                f"MOVE_L needs 3 position and 4 orientation values, got {len(position)} and {len(orientation)}"
            )
        p = np.asarray(position, dtype=float)
        o = np.asarray(orientation, dtype=float)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(o))):
            return Result.NOT_FINITE, "position or orientation contains NaN or inf"
        # float32 on the wire: allow its rounding, nothing more.
        if not is_unit_quaternion(o):
            return Result.BAD_ORIENTATION, f"orientation norm is {np.linalg.norm(o):.4f}, not 1 (x, y, z, w)"
        if not self.workspace.contains(p):
            return Result.OUT_OF_WORKSPACE, (
                f"position {p.round(3).tolist()} is outside the workspace box "
                f"{self.workspace.lower.tolist()}..{self.workspace.upper.tolist()}"
            )
        return None

    # -- execution -------------------------------------------------------------------------
    def _execute(self, command, position, orientation, joints, url, path=None):
        """Run a checked request: (robots for GET_ROBOTS, when a FOLLOW_PATH started)."""
        driver = self.driver
        if command == CommandIndex.GET_ROBOTS:
            return driver.get_robots(), None
        if command == CommandIndex.LOGIN:
            try:
                driver.login(url, self._user, self._password)
            except HwInterfaceError:
                raise
            except Exception as exc:
                raise HwInterfaceError(f"login to {url!r} failed: {exc}", Result.LOGIN_FAILED) from None
            finally:
                self._limit_lists = None  # after the login: it may have loaded another model
        elif command == CommandIndex.GET_ROBOT_JOINTS:
            driver.get_robot_joints()  # raises NOT_CONNECTED when there is no controller
        elif command == CommandIndex.GET_ROBOT_CARTESIAN_POSITION:
            driver.get_robot_cartesian_position()
        elif command in MOTION_COMMANDS and driver.status().protective_stop:
            raise HwInterfaceError(
                "the robot is in a protective stop; clear it, then command again", Result.PROTECTIVE_STOP
            )
        elif command == CommandIndex.SET_JOINTS:
            target = np.asarray(joints, dtype=float)
            driver.set_joints(target)
            self._note_stream(target)
        elif command == CommandIndex.STOP:
            self._stop("STOP")
        elif command == CommandIndex.SET_GRIPPER:
            driver.set_gripper(bool(joints[0]))
        elif command == CommandIndex.SET_DIGITAL_OUTPUT:
            driver.set_digital_output(int(joints[0]), bool(joints[1]))
        elif command in (CommandIndex.MOVE_J, CommandIndex.MOVE_L):
            if not self._blocking_motion.acquire(blocking=False):
                raise HwInterfaceError("another MOVE_J/MOVE_L/FOLLOW_PATH is running; wait or send STOP", Result.BUSY)
            self._note_stream(None)  # a new stream after this move starts from the measured joints
            try:
                if command == CommandIndex.MOVE_J:
                    driver.move_j(np.asarray(joints, dtype=float), timeout=self.move_timeout)
                else:
                    driver.move_l(
                        np.asarray(position, dtype=float),
                        np.asarray(orientation, dtype=float),
                        timeout=self.move_timeout,
                    )
            finally:
                self._blocking_motion.release()
        elif command == CommandIndex.FOLLOW_PATH:
            if not self._blocking_motion.acquire(blocking=False):
                raise HwInterfaceError("another MOVE_J/MOVE_L/FOLLOW_PATH is running; wait or send STOP", Result.BUSY)
            try:
                with self._stream_lock:
                    streaming = self._clock() - self._stream_time <= STREAM_REFERENCE_TIMEOUT
                if streaming:  # the easing onto the path starts from rest, not from a moving arm
                    raise HwInterfaceError(
                        "FOLLOW_PATH refused: a SET_JOINTS stream moved the arm in the last "
                        f"{STREAM_REFERENCE_TIMEOUT:g} s; a path starts from an arm at rest: "
                        "let the stream end, or STOP, first",
                        Result.BUSY,
                    )
                self._note_stream(None)
                current = np.asarray(driver.get_robot_joints(), dtype=float)
                gap = np.abs(path.start - current)
                if gap.max() > self.stream_start_tolerance:
                    name = driver.joint_names[int(np.argmax(gap))]
                    raise HwInterfaceError(
                        f"FOLLOW_PATH refused: its first sample is {gap.max():.3f} rad from the measured joints "
                        f"({name}; limit {self.stream_start_tolerance:.3f}, the server's stream_start_tolerance): "
                        "a path starts where the robot is (MOVE_J there first)",
                        Result.TOO_FAR,
                    )
                # The first command is where the arm is: the path eases onto its first sample.
                check_path_start(path, current, driver.joint_names, self._joint_limit_lists(), *driver.path_limits())
                # The move timeout counts from the path's end: a path may be longer than it.
                return (), driver.follow_path(path, timeout=path.duration + self.move_timeout)
            finally:
                self._blocking_motion.release()
        return (), None

    def _answer(self, result: Result, reason: str, robots=()) -> CommandResult:
        answer = CommandResult(result, reason, robots=robots)
        try:
            if self.driver.status().connected:
                answer.joints = self.driver.get_robot_joints().tolist()
                position, orientation = self.driver.get_robot_cartesian_position()
                answer.position, answer.orientation = position.tolist(), orientation.tolist()
        except Exception:  # the state is a courtesy; the result code already says it all
            pass
        return answer
