"""Universal Robots driver over RTDE (ur_rtde): RTDEControlInterface for motion,
RTDEReceiveInterface for state, RTDEIOInterface for the gripper output.

Safety rules, as in the Universal Robots ROS driver:
- it connects to a real controller only when a robot_ip is given *and* ``armed`` is set;
- streaming uses servoJ at the controller rate (500 Hz e-Series, 125 Hz CB3) and is
  stopped with servoStop before any other motion, and when targets stop arriving;
- every exit path stops the robot (``finally``).
It has been tested against a fake of the ur_rtde classes only (tests/unit), never against a
controller.
"""
import threading
import time
from typing import Optional

import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.kinematics import RobotKinematics

from .errors import HwInterfaceError
from .protocol import Result
from .robot_hw import DriverStatus, RobotDriver, UrdfModelMixin


# UR safety modes as RTDEReceiveInterface.getSafetyMode() numbers them.
SAFETY_MODES = {1: "normal", 2: "reduced", 3: "protective_stop", 4: "recovery", 5: "safeguard_stop",
                6: "system_emergency_stop", 7: "robot_emergency_stop", 8: "violation", 9: "fault",
                10: "validate_joint_id", 11: "undefined", 12: "automatic_mode_safeguard_stop",
                13: "system_three_position_enabling_stop"}


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


class URRtdeDriver(UrdfModelMixin, RobotDriver):
    """A Universal Robots arm over RTDE.

    Parameters: ``urdf_path`` (the arm's model: joint names and limits), ``robot_ip``,
    ``armed`` (must be True to connect), ``frequency`` (Hz: 500 e-Series, 125 CB3),
    ``lookahead_time`` (s, 0.03-0.2) and ``gain`` (100-2000) of servoJ,
    ``joint_speed`` (rad/s) / ``joint_acceleration`` (rad/s^2) of MoveJ,
    ``linear_speed`` (m/s) / ``linear_acceleration`` (m/s^2) of MoveL,
    ``stream_timeout`` (s without a new target before streaming stops),
    ``gripper_output`` (standard digital output driving the gripper),
    ``reconnect_attempts`` and ``reconnect_backoff`` (s, doubled each attempt),
    ``rtde_classes`` (control, receive, io classes; tests pass fakes),
    ``fake_controller`` (True: talk to hw_interface.fake_rtde instead of a controller, for
    dry runs of a UR session without a robot; ``initial_joints`` sets its start pose).
    """

    name = "ur_rtde"

    def __init__(self, urdf_path: str, tool_frame: str = "tool0", robot_ip: str = "", armed: bool = False,
                 frequency: float = 500.0, lookahead_time: float = 0.1, gain: float = 300.0,
                 joint_speed: float = 1.0, joint_acceleration: float = 1.4, linear_speed: float = 0.25,
                 linear_acceleration: float = 1.2, stream_timeout: float = 0.1, gripper_output: int = 0,
                 reconnect_attempts: int = 3, reconnect_backoff: float = 0.5, robot_name: Optional[str] = None,
                 rtde_classes=None, fake_controller: bool = False, initial_joints=None):
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
        self.stream_timeout = float(stream_timeout)
        self.gripper_output = int(gripper_output)
        self.reconnect_attempts = int(reconnect_attempts)
        self.reconnect_backoff = float(reconnect_backoff)
        self.robot_name = robot_name or self.kinematics.model.name
        self._classes = rtde_classes
        if fake_controller and rtde_classes is None:
            from .fake_rtde import FakeUR
            self._classes = FakeUR(urdf_path, initial_joints, frequency).classes()
        self._control = self._receive = self._io = None
        # _lock guards the RTDE objects and the streaming state across the server's
        # service threads and the streaming thread.
        self._lock = threading.RLock()
        self._target: Optional[np.ndarray] = None
        self._target_time = 0.0
        self._stream_thread: Optional[threading.Thread] = None
        self._streaming = threading.Event()
        self._fault = ""
        self._gripper_on = False
        self.servo_periods = 0
        self.missed_periods = 0

    # -- connection ------------------------------------------------------------------------
    def login(self, url: str = "", user: str = "", password: str = "") -> None:
        ip = url.replace("ur://", "").strip("/") if url and not url.startswith("sim") else self.robot_ip
        if not ip:
            raise HwInterfaceError("no robot_ip: pass robot_ip:=<controller address> to connect to a UR",
                                   Result.LOGIN_FAILED)
        if not self.armed:
            raise HwInterfaceError(f"refusing to connect to the real robot at {ip}: the driver is not armed; "
                                   "check the cell is clear, then start with armed:=true", Result.LOGIN_FAILED)
        with self._lock:
            if self._control is not None:
                return
            control_cls, receive_cls, io_cls = self._classes or _rtde_classes()
            delay = self.reconnect_backoff
            for attempt in range(1, self.reconnect_attempts + 1):
                try:
                    self._receive = receive_cls(ip)
                    self._control = control_cls(ip)
                    self._io = io_cls(ip)
                    self.robot_ip = ip
                    self._fault = ""
                    return
                except Exception as exc:  # ur_rtde raises RuntimeError; anything else is as fatal
                    self._control = self._receive = self._io = None
                    self._fault = f"connect to {ip} failed (attempt {attempt}): {exc}"
                    if attempt < self.reconnect_attempts:
                        time.sleep(delay)
                        delay *= 2
            raise HwInterfaceError(f"cannot connect to the UR controller at {ip}: {self._fault}", Result.LOGIN_FAILED)

    def disconnect(self) -> None:
        try:
            self.stop()
        finally:
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
        """Raise NOT_CONNECTED unless connected; reconnect with backoff after a drop."""
        if self._control is None:
            raise HwInterfaceError("not connected to the UR controller: call LOGIN first", Result.NOT_CONNECTED)
        if self._control.isConnected() and self._receive.isConnected():
            return
        delay = self.reconnect_backoff
        for _ in range(self.reconnect_attempts):
            try:
                if self._receive.reconnect() and self._control.reconnect():
                    self._io.reconnect()
                    self._fault = ""
                    return
            except Exception as exc:
                self._fault = f"reconnect failed: {exc}"
            time.sleep(delay)
            delay *= 2
        self._fault = "disconnected from the controller"
        raise HwInterfaceError("lost the connection to the UR controller and could not reconnect",
                               Result.NOT_CONNECTED)

    def _ensure_can_move(self):
        self._ensure_connected()
        if self._receive.isProtectiveStopped() or self._receive.isEmergencyStopped():
            raise HwInterfaceError("the robot is in a protective or emergency stop: clear it on the pendant",
                                   Result.PROTECTIVE_STOP)

    # -- state -----------------------------------------------------------------------------
    def get_robot_joints(self) -> np.ndarray:
        with self._lock:
            self._ensure_connected()
            return np.array(self._receive.getActualQ(), dtype=float)

    def get_robot_cartesian_position(self):
        with self._lock:
            self._ensure_connected()
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
            return DriverStatus(connected=connected, moving=moving, fault=self._fault, protective_stop=stopped,
                                safety_mode=safety, gripper="on" if self._gripper_on else "")

    # -- motion ----------------------------------------------------------------------------
    def set_joints(self, joints) -> None:
        with self._lock:
            self._ensure_can_move()
            self._target = np.asarray(joints, dtype=float)
            self._target_time = time.monotonic()
            if not self._streaming.is_set():
                self._streaming.set()
                self._stream_thread = threading.Thread(target=self._stream_loop, name="ur-servoj", daemon=True)
                self._stream_thread.start()

    def move_j(self, joints, timeout: float = 30.0, asynchronous: bool = False) -> None:
        with self._lock:
            self._ensure_can_move()
            self._stop_streaming()
            ok = self._control.moveJ(list(map(float, joints)), self.joint_speed, self.joint_acceleration, asynchronous)
        self._check_motion(ok, "moveJ")

    def move_l(self, position, orientation, timeout: float = 30.0, asynchronous: bool = False) -> None:
        with self._lock:
            self._ensure_can_move()
            self._stop_streaming()
            ok = self._control.moveL(pose_to_ur(position, orientation), self.linear_speed,
                                     self.linear_acceleration, asynchronous)
        self._check_motion(ok, "moveL")

    def stop(self) -> None:
        with self._lock:
            if self._control is None:
                return
            try:
                self._stop_streaming()
            finally:
                try:
                    self._control.stopJ(2.0)
                except Exception as exc:  # the connection may be gone; nothing moves then
                    self._fault = f"stopJ failed: {exc}"

    def set_gripper(self, closed: bool) -> None:
        self.set_digital_output(self.gripper_output, closed)
        self._gripper_on = bool(closed)

    def set_digital_output(self, output: int, value: bool) -> None:
        with self._lock:
            self._ensure_connected()
            if not self._io.setStandardDigitalOut(int(output), bool(value)):
                raise HwInterfaceError(f"controller refused digital output {output}", Result.DRIVER_FAULT)

    # -- internals -------------------------------------------------------------------------
    def _check_motion(self, ok, what):
        if ok:
            return
        with self._lock:
            stopped = self._receive is not None and self._receive.isProtectiveStopped()
        if stopped:
            raise HwInterfaceError(f"{what} interrupted by a protective stop", Result.PROTECTIVE_STOP)
        raise HwInterfaceError(f"{what} failed on the controller", Result.DRIVER_FAULT)

    def _stop_streaming(self):
        """servoStop before anything else moves the arm (caller holds the lock)."""
        if not self._streaming.is_set():
            return
        self._streaming.clear()
        self._target = None
        try:
            self._control.servoStop()
        except Exception as exc:
            self._fault = f"servoStop failed: {exc}"

    def _stream_loop(self):
        """servoJ the latest target once per controller period until told to stop."""
        control = self._control
        try:
            while self._streaming.is_set():
                start = control.initPeriod()
                with self._lock:
                    if not self._streaming.is_set():
                        break
                    if time.monotonic() - self._target_time > self.stream_timeout:
                        # Targets stopped coming (stale teleop): halt rather than hold a servo.
                        self._stop_streaming()
                        break
                    if self._receive.isProtectiveStopped():
                        self._fault = "protective stop while streaming"
                        self._stop_streaming()
                        break
                    target = list(map(float, self._target))
                    ok = control.servoJ(target, 0.0, 0.0, self.period, self.lookahead_time, self.gain)
                    self.servo_periods += 1
                    if not ok:
                        self.missed_periods += 1
                control.waitPeriod(start)
        except Exception as exc:  # disconnect mid-stream: stop streaming, report, recover on the next command
            with self._lock:
                self._fault = f"streaming stopped: {exc}"
                self._streaming.clear()
                self._target = None
