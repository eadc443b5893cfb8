"""Universal Robots driver over RTDE (ur_rtde): RTDEControlInterface for motion,
RTDEReceiveInterface for state, RTDEIOInterface for the gripper output.

Safety rules, as in the Universal Robots ROS driver:
- it connects to a real controller only when a robot_ip is given *and* ``armed`` is set;
- streaming uses servoJ at the controller rate (500 Hz e-Series, 125 Hz CB3) and is
  stopped with servoStop before any other motion, and when targets stop arriving;
- every exit path stops the robot (``finally``).
It has been tested against a fake of the ur_rtde classes only (hw_interface.testing.fake_rtde),
never against a controller.
"""

import threading
import time

import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.kinematics import RobotKinematics
from motion_common.params import Param, ParamSchema

from .driver_params import ARMING_PARAMS, GOAL_TOLERANCE_PARAMS, RECONNECT_PARAMS, positive_param
from .errors import HwInterfaceError
from .protocol import Result
from .real_controller import RealControllerMixin
from .robot_hw import DriverStatus, RobotDriver, UrdfModelMixin
from .stream_follower import STREAM_ACCELERATION_PARAM, StreamFollower

# UR safety modes as RTDEReceiveInterface.getSafetyMode() numbers them.
SAFETY_MODES = {
    1: "normal",
    2: "reduced",
    3: "protective_stop",
    4: "recovery",
    5: "safeguard_stop",
    6: "system_emergency_stop",
    7: "robot_emergency_stop",
    8: "violation",
    9: "fault",
    10: "validate_joint_id",
    11: "undefined",
    12: "automatic_mode_safeguard_stop",
    13: "system_three_position_enabling_stop",
}


def _rtde_classes():
    """The real ur_rtde classes, imported only when a real connection is made."""
    import rtde_control
    import rtde_io
    import rtde_receive

    return rtde_control.RTDEControlInterface, rtde_receive.RTDEReceiveInterface, rtde_io.RTDEIOInterface


def pose_to_ur(position, orientation):
    """UR pose [x, y, z, rx, ry, rz] (rotation vector) from position + quaternion."""
    return list(np.asarray(position, dtype=float)) + list(Rotation.from_quat(orientation).as_rotvec())


def ur_to_pose(pose):
    """(position, quaternion x, y, z, w) from a UR pose."""
    pose = np.asarray(pose, dtype=float)
    return pose[:3], Rotation.from_rotvec(pose[3:6]).as_quat()


def _stop_call(method, deceleration):
    """stopJ/stopL asynchronously where ur_rtde supports it (1.5.6+), else blocking."""
    try:
        method(deceleration, True)
    except TypeError:
        method(deceleration)


class URRtdeDriver(RealControllerMixin, UrdfModelMixin, RobotDriver):
    """A Universal Robots arm over RTDE.

    Parameters (``PARAMETERS``, with units and ranges): ``urdf_path`` (the arm's model: joint
    names and limits), ``robot_ip``, ``armed`` (must be True to connect), ``frequency`` (Hz:
    500 e-Series, 125 CB3), ``lookahead_time`` (s, 0.03-0.2) and ``gain`` (100-2000) of
    servoJ, ``joint_speed`` / ``joint_acceleration`` of MoveJ, ``linear_speed`` /
    ``linear_acceleration`` of MoveL, the decelerations STOP uses (stopJ, stopL, servoStop),
    ``stream_timeout``, ``gripper_output``, ``reconnect_attempts`` / ``reconnect_backoff``,
    ``goal_tolerance`` (rad) / ``goal_position_tolerance`` (m): how close the MEASURED arm
    must be for a move to succeed. Injected: ``rtde_classes`` (control, receive, io classes;
    tests and the ``ur_rtde_fake`` driver pass hw_interface.testing.fake_rtde's),
    ``clock`` and ``sleep`` (the reconnect backoff uses them; tests need no real sleeping).

    Blocking MoveJ/MoveL are issued as asynchronous ur_rtde moves and watched without
    holding the driver lock, so stop() from another thread acts within one controller
    period: stopJ for MoveJ, stopL for MoveL, servoStop for streaming.
    """

    name = "ur_rtde"

    #: servoJ smooths the stream over its lookahead and the arm trails by about as much.
    STREAM_LAG_PARAM = "lookahead_time"

    PARAMETERS = ParamSchema(
        [
            *ARMING_PARAMS,
            Param("frequency", 500.0, "Hz", "servoJ rate: 500 e-Series, 125 CB3", low=10.0, high=1000.0),
            Param(
                "lookahead_time",
                0.03,
                "s",
                "servoJ lookahead (ur_rtde range): the controller smooths the stream over it and the arm trails by "
                "about as much; the follower already limits the stream's speed and acceleration, so the shortest "
                "(bench/hand_to_tool: hand to tool 61 ms at 0.03 s, 75 at 0.05, 112 at 0.1)",
                low=0.03,
                high=0.2,
            ),
            Param(
                "gain",
                300.0,
                "1",
                "servoJ proportional gain (ur_rtde range): higher follows the smoothed target more tightly, too high "
                "makes a real arm vibrate (not modelled by the simulated controller)",
                low=100.0,
                high=2000.0,
            ),
            positive_param("joint_speed", 1.0, "rad/s", "MoveJ speed of the leading joint", 3.14),
            positive_param("joint_acceleration", 1.4, "rad/s^2", "MoveJ acceleration", 40.0),
            positive_param("linear_speed", 0.25, "m/s", "MoveL tool speed", 3.0),
            positive_param("linear_acceleration", 1.2, "m/s^2", "MoveL tool acceleration", 150.0),
            positive_param("joint_stop_deceleration", 2.0, "rad/s^2", "stopJ deceleration (STOP of a MoveJ)", 40.0),
            positive_param("linear_stop_deceleration", 10.0, "m/s^2", "stopL deceleration (STOP of a MoveL)", 150.0),
            positive_param(
                "servo_stop_deceleration", 10.0, "rad/s^2", "servoStop deceleration (STOP of streaming)", 40.0
            ),
            STREAM_ACCELERATION_PARAM,
            positive_param("stream_timeout", 0.1, "s", "without a new SET_JOINTS before streaming stops", 5.0),
            Param("gripper_output", 0, "", "standard digital output driving the gripper", low=0, high=7),
            *RECONNECT_PARAMS,
            *GOAL_TOLERANCE_PARAMS,
            Param(
                "settle_time", 0.5, "s", "how long a finished move may take to come within tolerance", low=0.0, high=5.0
            ),
        ]
    )

    def __init__(
        self,
        urdf_path: str,
        tool_frame: str = "tool0",
        robot_ip: str = "",
        armed: bool = False,
        frequency: float = 500.0,
        lookahead_time: float = 0.03,
        gain: float = 300.0,
        joint_speed: float = 1.0,
        joint_acceleration: float = 1.4,
        linear_speed: float = 0.25,
        linear_acceleration: float = 1.2,
        joint_stop_deceleration: float = 2.0,
        linear_stop_deceleration: float = 10.0,
        servo_stop_deceleration: float = 10.0,
        stream_timeout: float = 0.1,
        stream_acceleration: float = 200.0,
        gripper_output: int = 0,
        reconnect_attempts: int = 3,
        reconnect_backoff: float = 0.5,
        goal_tolerance: float = 0.002,
        goal_position_tolerance: float = 0.002,
        settle_time: float = 0.5,
        robot_name: str | None = None,
        rtde_classes=None,
        clock=time.monotonic,
        sleep=time.sleep,
    ):
        if not 0.03 <= lookahead_time <= 0.2:
            raise HwInterfaceError(f"lookahead_time must be 0.03-0.2 s (ur_rtde range), got {lookahead_time}")
        if not 100 <= gain <= 2000:
            raise HwInterfaceError(f"gain must be 100-2000 (ur_rtde range), got {gain}")
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        self.robot_ip = robot_ip
        self.armed = bool(armed)
        self.period = 1.0 / float(frequency)
        self.lookahead_time, self.gain = float(lookahead_time), float(gain)
        self.joint_speed, self.joint_acceleration = float(joint_speed), float(joint_acceleration)
        self.linear_speed, self.linear_acceleration = float(linear_speed), float(linear_acceleration)
        self.joint_stop_deceleration = float(joint_stop_deceleration)
        self.linear_stop_deceleration = float(linear_stop_deceleration)
        self.servo_stop_deceleration = float(servo_stop_deceleration)
        self.stream_timeout = float(stream_timeout)
        self.stream_acceleration = float(stream_acceleration)
        # The servo setpoint sent each period: it chases the latest target within the speed
        # and acceleration limits, so no client (a stale stream, a burst) can make a lurch.
        self._follower: StreamFollower | None = None
        self.gripper_output = int(gripper_output)
        self._init_controller(reconnect_attempts, reconnect_backoff, goal_tolerance, goal_position_tolerance, sleep)
        self.settle_time = float(settle_time)
        self.robot_name = robot_name or self.kinematics.model.name
        self._classes = rtde_classes
        self._clock = clock
        self._control = self._receive = self._io = None
        # _lock guards the RTDE objects and the motion/streaming state. It is only ever held
        # for single controller calls: never across a motion, a sleep or a backoff.
        self._lock = threading.RLock()
        self._connect_lock = threading.Lock()  # serialises login attempts (may back off)
        self._target: np.ndarray | None = None
        self._target_time = 0.0
        self._stream_thread: threading.Thread | None = None
        self._streaming = threading.Event()
        # Each stream thread serves one generation: a stop followed at once by a new
        # target starts a new generation, and the old thread (perhaps still waiting out its
        # period outside the lock) sees the change and exits: never two servoJ loops.
        self._stream_generation = 0
        self._fault = ""
        self._gripper_on = False
        self.servo_periods = 0
        self.missed_periods = 0

    # -- connection ------------------------------------------------------------------------
    def login(self, url: str = "", user: str = "", password: str = "") -> None:
        ip = url.replace("ur://", "").strip("/") if url and not url.startswith("sim") else self.robot_ip
        self._check_armed(ip, self.armed, "a UR")
        with self._connect_lock:
            with self._lock:
                if self._control is not None:
                    return
            control_cls, receive_cls, io_cls = self._classes or _rtde_classes()
            for attempt in self._backoff_attempts():
                try:
                    receive = receive_cls(ip)
                    control = control_cls(ip)
                    io = io_cls(ip)
                    with self._lock:
                        self._receive, self._control, self._io = receive, control, io
                        self.robot_ip = ip
                        self._fault = ""
                    return
                except Exception as exc:  # ur_rtde raises RuntimeError; anything else is as fatal
                    with self._lock:
                        self._fault = f"connect to {ip} failed (attempt {attempt}): {exc}"
            raise HwInterfaceError(f"cannot connect to the UR controller at {ip}: {self._fault}", Result.LOGIN_FAILED)

    def disconnect(self) -> None:
        try:
            self.stop()
        finally:
            self._streaming.clear()
            with self._lock:
                for interface in (self._control, self._receive, self._io):
                    if interface is not None:
                        try:
                            interface.disconnect()
                        except Exception:  # already gone: nothing more to close
                            pass
                if self._control is not None:
                    try:
                        self._control.stopScript()
                    except Exception:
                        pass
                self._control = self._receive = self._io = None

    def _ensure_connected(self):
        """Raise NOT_CONNECTED unless connected; reconnect with backoff after a drop.

        Called WITHOUT the lock: each attempt takes it briefly, the backoff sleeps outside.
        """
        delay = self.reconnect_backoff
        for attempt in range(self.reconnect_attempts + 1):
            with self._lock:
                if self._control is None:
                    raise HwInterfaceError("not connected to the UR controller: call LOGIN first", Result.NOT_CONNECTED)
                try:
                    if self._control.isConnected() and self._receive.isConnected():
                        if attempt:
                            self._fault = ""
                        return
                    if attempt and self._receive.reconnect() and self._control.reconnect():
                        self._io.reconnect()
                        self._fault = ""
                        return
                except Exception as exc:
                    self._fault = f"reconnect failed: {exc}"
            if attempt == self.reconnect_attempts:
                break
            if attempt:
                self._sleep(delay)
                delay *= 2
        with self._lock:
            self._fault = "disconnected from the controller"
        raise HwInterfaceError("lost the connection to the UR controller and could not reconnect", Result.NOT_CONNECTED)

    def _ensure_can_move(self):
        self._ensure_connected()
        with self._lock:
            if self._receive.isProtectiveStopped() or self._receive.isEmergencyStopped():
                raise HwInterfaceError(
                    "the robot is in a protective or emergency stop: clear it on the pendant", Result.PROTECTIVE_STOP
                )

    # -- state -----------------------------------------------------------------------------
    def get_robot_joints(self) -> np.ndarray:
        self._ensure_connected()
        with self._lock:
            return np.array(self._receive.getActualQ(), dtype=float)

    def get_robot_cartesian_position(self):
        self._ensure_connected()
        with self._lock:
            return ur_to_pose(self._receive.getActualTCPPose())

    def status(self) -> DriverStatus:
        with self._lock:
            if self._control is None:
                return DriverStatus(connected=False, fault=self._fault)
            try:
                connected = self._control.isConnected() and self._receive.isConnected()
                stopped = connected and (self._receive.isProtectiveStopped() or self._receive.isEmergencyStopped())
                moving = connected and not self._control.isSteady()
                safety = SAFETY_MODES.get(self._receive.getSafetyMode(), "unknown") if connected else ""
            except Exception as exc:
                return DriverStatus(connected=False, fault=f"status read failed: {exc}")
            return DriverStatus(
                connected=connected,
                moving=moving,
                fault=self._fault,
                protective_stop=stopped,
                safety_mode=safety,
                gripper="on" if self._gripper_on else "",
            )

    # -- motion ----------------------------------------------------------------------------
    def set_joints(self, joints) -> None:
        self._ensure_can_move()
        with self._lock:
            self._set_stream_target(joints, time.monotonic())
            if not self._streaming.is_set():
                # A new stream starts where the arm is, at rest.
                self._follower = StreamFollower(
                    self.kinematics.velocity_limits,
                    np.asarray(self._receive.getActualQ(), dtype=float),
                    self.stream_acceleration,
                )
                self._streaming.set()
                self._stream_generation += 1
                self._stream_thread = threading.Thread(
                    target=self._stream_loop, args=(self._stream_generation,), name="ur-servoj", daemon=True
                )
                self._stream_thread.start()

    def move_j(self, joints, timeout: float = 30.0, asynchronous: bool = False) -> None:
        goal = np.asarray(joints, dtype=float)
        token, before = self._start_move(
            "moveJ",
            lambda control: control.moveJ(list(map(float, goal)), self.joint_speed, self.joint_acceleration, True),
        )
        if not asynchronous:
            self._watch("moveJ", token, before, timeout, lambda q: self._joint_error(q, goal))

    def move_l(self, position, orientation, timeout: float = 30.0, asynchronous: bool = False) -> None:
        pose = pose_to_ur(position, orientation)
        token, before = self._start_move(
            "moveL", lambda control: control.moveL(pose, self.linear_speed, self.linear_acceleration, True)
        )
        if not asynchronous:
            self._watch("moveL", token, before, timeout, lambda q: self._pose_error(q, position, orientation))

    def path_limits(self):
        """The streamed motion's limits: the URDF joint speeds and stream_acceleration."""
        velocity = self.kinematics.velocity_limits
        return velocity, np.full(velocity.shape, self.stream_acceleration)

    def follow_path(self, path, timeout: float = 30.0) -> float:
        """servoJ the timed path sampled by the driver's clock once per controller period
        (a late period samples the path at its own time: a stall never bends the path), then
        its end until the measured joints are within goal_tolerance (settle_time); STOP,
        a protective stop or a lost connection answer INTERRUPTED within a period."""
        self._ensure_can_move()
        with self._lock:
            if self._active_move is not None:
                raise HwInterfaceError(f"a {self._active_move} is running; wait or STOP it", Result.BUSY)
            self._stop_streaming()
            self._move_token += 1
            token = self._move_token
            self._active_move = "path"
            self._wake.clear()
            control = self._control
        start = self._clock()
        started = time.time()
        ended_at = None
        while True:
            period = control.initPeriod()
            with self._lock:
                self._raise_if_stopped("path", token)
                if self._control is None:
                    raise self._interrupted("path", token, "the driver disconnected")
                try:
                    if self._receive.isProtectiveStopped() or self._receive.isEmergencyStopped():
                        self._fault = "protective stop during a path"
                        raise self._interrupted("path", token, "protective or emergency stop")
                    now = self._clock()
                    target = path.sample(now - start)
                    ok = control.servoJ(list(map(float, target)), 0.0, 0.0, self.period, self.lookahead_time, self.gain)
                    self.servo_periods += 1
                    if not ok:
                        self.missed_periods += 1
                    q = np.array(self._receive.getActualQ(), dtype=float)
                except HwInterfaceError:
                    raise
                except Exception as exc:  # connection lost mid-path: the controller halts the arm
                    self._fault = f"path lost the controller: {exc}"
                    raise self._interrupted("path", token, f"connection lost ({exc})") from None
                if ended_at is None and now - start >= path.duration:
                    ended_at = now
                if ended_at is not None:
                    error = float(np.max(np.abs(q - path.end)))
                    if error <= self.goal_tolerance:
                        self._stop_call_servo()
                        self._end_move(token)
                        return started
                    if now - ended_at > self.settle_time:
                        self._stop_call_servo()
                        raise self._interrupted(
                            "path",
                            token,
                            f"the arm ended {error:.4f} rad from the path's end (tolerance {self.goal_tolerance:g})",
                        )
                elif now - start > timeout:
                    raise self._timed_out("path", timeout)
            control.waitPeriod(period)

    def _stop_call_servo(self):
        """servoStop at a path's end or failure (caller holds the lock)."""
        try:
            self._control.servoStop(self.servo_stop_deceleration)
        except Exception as exc:  # the connection may be gone; nothing moves then
            self._fault = f"servoStop failed: {exc}"

    def stop(self, reason: str = "STOP") -> None:
        """Stop now, from any thread: stopL for a MoveL, servoStop for streaming and a
        timed path, stopJ otherwise; a blocking move being watched answers INTERRUPTED
        within one period."""
        with self._lock:
            if self._control is None:
                return
            self._stopped_token = self._move_token
            self._stop_reason = reason
            active, self._active_move = self._active_move, None
            self._wake.set()
            try:
                self._stop_streaming()
            finally:
                try:
                    if active == "moveL":
                        _stop_call(self._control.stopL, self.linear_stop_deceleration)
                    elif active == "path":  # servoJ motion: servoStop, as for a stream
                        self._control.servoStop(self.servo_stop_deceleration)
                    else:
                        _stop_call(self._control.stopJ, self.joint_stop_deceleration)
                except Exception as exc:  # the connection may be gone; nothing moves then
                    self._fault = f"stop failed: {exc}"

    def set_gripper(self, closed: bool) -> None:
        self.set_digital_output(self.gripper_output, closed)
        self._gripper_on = bool(closed)

    def set_digital_output(self, output: int, value: bool) -> None:
        self._ensure_connected()
        with self._lock:
            if not self._io.setStandardDigitalOut(int(output), bool(value)):
                raise HwInterfaceError(f"controller refused digital output {output}", Result.DRIVER_FAULT)

    # -- internals -------------------------------------------------------------------------
    def _start_move(self, kind, issue):
        """Issue an asynchronous move under the lock (briefly); return its token and the
        async progress value before it, to detect its end."""
        self._ensure_can_move()
        with self._lock:
            self._stop_streaming()
            self._move_token += 1
            token = self._move_token
            self._wake.clear()
            before = self._control.getAsyncOperationProgress()
            ok = issue(self._control)
            if ok:
                self._active_move = kind
            stopped = not ok and self._receive.isProtectiveStopped()
        if ok:
            return token, before
        if stopped:
            raise HwInterfaceError(f"{kind} refused: the robot is in a protective stop", Result.PROTECTIVE_STOP)
        raise HwInterfaceError(
            f"{kind} refused by the controller (unreachable or outside its limits)", Result.DRIVER_FAULT
        )

    def _watch(self, kind, token, before, timeout, error_of):
        """Follow an asynchronous move to its end at the controller period, taking the lock
        only for each poll; raise INTERRUPTED, TIMEOUT, or return once arrived."""
        deadline = self._clock() + max(float(timeout), 0.0)
        seen_running = False
        ended_at = None
        while True:
            with self._lock:
                self._raise_if_stopped(kind, token)
                if self._control is None:
                    raise self._interrupted(kind, token, "the driver disconnected")
                try:
                    if self._receive.isProtectiveStopped() or self._receive.isEmergencyStopped():
                        self._fault = f"protective stop during {kind}"
                        raise self._interrupted(kind, token, "protective or emergency stop")
                    progress = self._control.getAsyncOperationProgress() if ended_at is None else -1
                    q = np.array(self._receive.getActualQ(), dtype=float)
                except HwInterfaceError:
                    raise
                except Exception as exc:  # connection lost mid-move: the controller halts the arm
                    self._fault = f"{kind} lost the controller: {exc}"
                    raise self._interrupted(kind, token, f"connection lost ({exc})") from None
                now = self._clock()
                if ended_at is None:
                    if progress >= 0:
                        seen_running = True
                    elif seen_running or progress != before:
                        ended_at = now
                        self._end_move(token)
                if ended_at is not None:
                    error, tolerance, unit = error_of(q)
                    if error <= tolerance:
                        return
                    if now - ended_at > self.settle_time:
                        raise HwInterfaceError(
                            f"{kind} ended {error:.4f} {unit} from the goal (tolerance "
                            f"{tolerance:g}): the controller stopped short",
                            Result.INTERRUPTED,
                        )
                elif now >= deadline:
                    pass  # handled below, outside the poll
            if ended_at is None and self._clock() >= deadline:
                raise self._timed_out(kind, timeout)
            self._wake.wait(self.period)

    def _stop_streaming(self):
        """servoStop before anything else moves the arm (caller holds the lock)."""
        if not self._streaming.is_set():
            return
        self._streaming.clear()
        self._target = None
        try:
            self._control.servoStop(self.servo_stop_deceleration)
        except Exception as exc:
            self._fault = f"servoStop failed: {exc}"

    def _stream_loop(self, generation):
        """servoJ the latest target once per controller period until told to stop (or a
        newer stream generation took over)."""
        control = self._control
        try:
            while self._streaming.is_set() and generation == self._stream_generation:
                start = control.initPeriod()
                with self._lock:
                    if not self._streaming.is_set() or generation != self._stream_generation:
                        break
                    if time.monotonic() - self._target_time > self.stream_timeout:
                        # Targets stopped coming (stale teleop): halt rather than hold a servo.
                        self._stop_streaming()
                        break
                    if self._receive.isProtectiveStopped():
                        self._fault = "protective stop while streaming"
                        self._stop_streaming()
                        break
                    self._follower.set_goal(self._target)
                    target = list(map(float, self._follower.step(self.period)))
                    ok = control.servoJ(target, 0.0, 0.0, self.period, self.lookahead_time, self.gain)
                    self.servo_periods += 1
                    if not ok:
                        self.missed_periods += 1
                control.waitPeriod(start)
        except Exception as exc:  # disconnect mid-stream: stop streaming, report, recover on the next command
            with self._lock:
                if generation == self._stream_generation:
                    self._fault = f"streaming stopped: {exc}"
                    self._streaming.clear()
                    self._target = None
