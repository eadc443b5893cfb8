"""A driver for ROS-Industrial controllers that speak simple_message (Stäubli's VAL3 server,
ABB's RAPID server, Fanuc's Karel server, Motoman's MotoROS): two TCP connections to the
controller's server programs, the motion port (trajectory points, 11000 by default) and
the state port (joint positions and STATUS, 11002).

Safety rules, as in the UR driver:
- it connects to a real controller only when a robot_ip is given *and* ``armed`` is set;
- every trajectory point needs the controller's reply within ``reply_timeout``, or the
  driver reports a fault (and stops) rather than waiting forever;
- STOP sends STOP_TRAJECTORY at once from any thread (sends are serialised by a lock held
  only for one ``sendall``); a blocking move then answers INTERRUPTED;
- controller data that is not valid simple_message (a truncated frame, an unknown type, a
  wrong length, the wrong byte order, a non-finite joint, a joint in a slot the robot does
  not have) latches a DRIVER_FAULT until the next LOGIN: the driver stops the arm and
  sends nothing more;
- no sleep and no socket wait under the driver lock.
It has been tested against the byte-level simulated controller of
hw_interface.testing.fake_simple_message only, never against a real controller.
"""

import collections
import socket
import threading
import time

import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.kinematics import RobotKinematics
from motion_common.params import Param, ParamSchema

from . import simple_message as sm
from .arrival_stamps import ArrivalStamps
from .driver_params import ARMING_PARAMS, GOAL_TOLERANCE_PARAMS, RECONNECT_PARAMS, positive_param
from .errors import HwInterfaceError
from .protocol import Result
from .real_controller import RealControllerMixin
from .robot_hw import DriverStatus, RobotDriver, UrdfModelMixin
from .stream_follower import STREAM_ACCELERATION_PARAM, StreamFollower
from .tcp import close_socket

__all__ = ["SimpleMessageDriver", "parse_controller_url"]


def parse_controller_url(url: str, default_host: str) -> str:
    """The controller host of a LOGIN url: ``simple_message://HOST``, ``tcp://HOST`` or a
    bare HOST; empty or ``sim://``: ``default_host`` (the robot_ip parameter)."""
    url = (url or "").strip()
    if not url or url.startswith("sim://"):
        return default_host
    for scheme in ("simple_message://", "tcp://"):
        if url.startswith(scheme):
            url = url[len(scheme) :]
    return url.strip("/")


class _Pending:
    """A request waiting for its SERVICE_REPLY (replies come in request order)."""

    __slots__ = ("msg_type", "what", "event", "reply_code", "error")

    def __init__(self, msg_type, what):
        self.msg_type, self.what = msg_type, what
        self.event = threading.Event()
        self.reply_code = None
        self.error = None  # an HwInterfaceError when the connection failed first


class SimpleMessageDriver(RealControllerMixin, UrdfModelMixin, RobotDriver):
    """An industrial arm behind a simple_message server.

    Parameters (``PARAMETERS``): the address (``robot_ip``, ``motion_port``,
    ``state_port``), ``armed``, ``byte_order``, ``joint_slots`` (which of the 10 slots
    carries each URDF joint), the point message (``point_type``, ``robot_id``), motion
    speeds, streaming, timeouts, reconnection and arrival tolerances. Injected: ``clock``
    and ``sleep`` (the reconnect backoff uses them; tests need no real sleeping).
    """

    name = "simple_message"

    PARAMETERS = ParamSchema(
        [
            *ARMING_PARAMS,
            Param(
                "motion_port", 11000, "", "TCP port of the controller's motion (trajectory) server", low=1, high=65535
            ),
            Param("state_port", 11002, "", "TCP port of the controller's state server", low=1, high=65535),
            Param(
                "byte_order",
                "little",
                doc="byte order of the controller's server: little (Stäubli, ABB, Motoman) or big (swapped, Fanuc)",
                choices=("little", "big"),
            ),
            Param(
                "joint_slots",
                [],
                "",
                "slot (0-9) of the 10-slot joint arrays carrying each URDF joint, in URDF order; empty: 0, 1, 2...",
                item_kind=int,
                low=0,
                high=9,
            ),
            Param(
                "point_type",
                "joint_traj_pt",
                doc="message of a trajectory point: joint_traj_pt (every server) or joint_traj_pt_full",
                choices=("joint_traj_pt", "joint_traj_pt_full"),
            ),
            Param("robot_id", 0, "", "motion group of JOINT_TRAJ_PT_FULL points", low=0, high=15),
            positive_param(
                "move_velocity", 0.25, "1", "MOVE_J speed as a fraction of the URDF joint speed limits", 1.0
            ),
            positive_param("linear_speed", 0.25, "m/s", "MOVE_L tool speed", 3.0),
            positive_param("angular_speed", 1.0, "rad/s", "MOVE_L tool turn rate", 6.3),
            Param(
                "stream_period",
                0.02,
                "s",
                "interval of the streamed (SET_JOINTS) points; each waits for its reply",
                low=0.004,
                high=0.2,
            ),
            STREAM_ACCELERATION_PARAM,
            positive_param(
                "stream_timeout", 0.1, "s", "without a new SET_JOINTS before the stream brakes to rest and ends", 5.0
            ),
            positive_param(
                "reply_timeout", 1.0, "s", "longest wait for the reply to a point; none: DRIVER_FAULT", 30.0
            ),
            positive_param(
                "state_timeout", 0.5, "s", "joint state older than this counts as lost (NOT_CONNECTED)", 10.0
            ),
            positive_param("connect_timeout", 2.0, "s", "TCP connect and first state wait", 30.0),
            *RECONNECT_PARAMS,
            *GOAL_TOLERANCE_PARAMS,
            Param(
                "settle_time",
                1.0,
                "s",
                "a move whose arm stays still this long away from the goal ends INTERRUPTED",
                low=0.05,
                high=10.0,
            ),
            Param("max_points", 500, "", "most points of one MOVE_L (its line is resampled to fit)", low=2, high=5000),
        ]
    )

    def __init__(
        self,
        urdf_path: str,
        tool_frame: str = "tool0",
        robot_ip: str = "",
        armed: bool = False,
        motion_port: int = 11000,
        state_port: int = 11002,
        byte_order: str = "little",
        joint_slots=(),
        point_type: str = "joint_traj_pt",
        robot_id: int = 0,
        move_velocity: float = 0.25,
        linear_speed: float = 0.25,
        angular_speed: float = 1.0,
        stream_period: float = 0.02,
        stream_acceleration: float = 200.0,
        stream_timeout: float = 0.1,
        reply_timeout: float = 1.0,
        state_timeout: float = 0.5,
        connect_timeout: float = 2.0,
        reconnect_attempts: int = 3,
        reconnect_backoff: float = 0.5,
        goal_tolerance: float = 0.002,
        goal_position_tolerance: float = 0.002,
        settle_time: float = 1.0,
        max_points: int = 500,
        robot_name: str | None = None,
        clock=time.monotonic,
        sleep=time.sleep,
    ):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        dof = self.kinematics.dof
        slots = list(joint_slots) or list(range(dof))
        if len(slots) != dof or len(set(slots)) != dof or not all(0 <= s < sm.MAX_JOINTS for s in slots):
            raise HwInterfaceError(
                f"joint_slots {slots} must name {dof} different slots 0-9, one per joint of the URDF "
                f"({', '.join(self.kinematics.joint_names)})"
            )
        if byte_order not in ("little", "big"):
            raise HwInterfaceError(f"byte_order must be little or big, got {byte_order!r}")
        if point_type not in ("joint_traj_pt", "joint_traj_pt_full"):
            raise HwInterfaceError(f"point_type must be joint_traj_pt or joint_traj_pt_full, got {point_type!r}")
        self.slots = np.array(slots, dtype=int)
        self.robot_ip = robot_ip
        self.armed = bool(armed)
        self.motion_port, self.state_port = int(motion_port), int(state_port)
        self.byte_order = byte_order
        self.point_type, self.robot_id = point_type, int(robot_id)
        self.move_velocity = float(move_velocity)
        self.linear_speed, self.angular_speed = float(linear_speed), float(angular_speed)
        self.stream_period = float(stream_period)
        self.stream_acceleration = float(stream_acceleration)
        self.stream_timeout = float(stream_timeout)
        self.reply_timeout = float(reply_timeout)
        self.state_timeout = float(state_timeout)
        self.connect_timeout = float(connect_timeout)
        self._init_controller(reconnect_attempts, reconnect_backoff, goal_tolerance, goal_position_tolerance, sleep)
        self.settle_time = float(settle_time)
        self.max_points = int(max_points)
        self.robot_name = robot_name or self.kinematics.model.name
        self._clock = clock
        # _lock guards every field below; it is held for bookkeeping only, never across a
        # socket wait, a sleep or a backoff. _send_lock serialises writes to the motion
        # socket (one sendall each), so STOP goes out at once even while a point waits.
        self._lock = threading.RLock()
        self._send_lock = threading.Lock()
        self._connect_lock = threading.Lock()
        self._motion_sock = self._state_sock = None
        self._generation = 0  # increases with every connect and close: old reader threads exit
        self._logged_in = False
        self._pending = collections.deque()
        self._joints = None  # latest measured joints (URDF order)
        self._joints_wall = 0.0  # time.time() when they were sampled (estimated, ArrivalStamps)
        self._joints_mono = 0.0  # clock() of their arrival
        self._status = sm.RobotStatus()
        self._state_event = threading.Condition(self._lock)
        self._fault = ""
        self._protocol_fault = ""  # latched until LOGIN: the controller sent bad data
        self._target = None
        self._target_time = 0.0
        self._streaming = False
        self._stream_generation = 0
        self._follower: StreamFollower | None = None
        self.ignored_messages = 0  # vendor-specific topics skipped
        self.points_sent = 0
        self.stops_sent = 0

    # -- connection ------------------------------------------------------------------------
    def login(self, url: str = "", user: str = "", password: str = "") -> None:
        host = parse_controller_url(url, self.robot_ip)
        self._check_armed(host, self.armed, "the controller")
        with self._connect_lock:
            with self._lock:
                if self._logged_in and self._motion_sock is not None and not self._protocol_fault:
                    return
                self._protocol_fault = ""
                self.robot_ip = host
            self._close("login")
            error = self._connect_with_backoff(Result.LOGIN_FAILED)
            if error is not None:
                raise HwInterfaceError(str(error), Result.LOGIN_FAILED)
            try:
                self._check_controller()
            except HwInterfaceError:
                self._close("login check failed")
                raise
            with self._lock:
                self._logged_in = True

    def disconnect(self) -> None:
        try:
            self.stop("disconnect")
        finally:
            with self._lock:
                self._logged_in = False
            self._close("disconnect")

    def _connect_with_backoff(self, result):
        """Up to ``reconnect_attempts`` connections, the backoff slept outside every lock;
        None on success, else the HwInterfaceError to raise."""
        for attempt in self._backoff_attempts():
            try:
                self._connect_once()
                return None
            except HwInterfaceError as exc:
                if exc.result == Result.DRIVER_FAULT:
                    return exc  # bad data is not fixed by trying again
                with self._lock:
                    self._fault = f"connect to {self.robot_ip} failed (attempt {attempt}): {exc}"
        with self._lock:
            fault = self._fault
        return HwInterfaceError(f"cannot connect to the controller at {self.robot_ip}: {fault}", result)

    def _connect_once(self):
        """Open both connections, start their readers and wait for the first joint state."""
        host = self.robot_ip
        try:
            state = socket.create_connection((host, self.state_port), timeout=self.connect_timeout)
        except OSError as exc:
            raise HwInterfaceError(f"state port {host}:{self.state_port}: {exc}", Result.NOT_CONNECTED) from None
        try:
            motion = socket.create_connection((host, self.motion_port), timeout=self.connect_timeout)
        except OSError as exc:
            state.close()
            raise HwInterfaceError(f"motion port {host}:{self.motion_port}: {exc}", Result.NOT_CONNECTED) from None
        for sock in (state, motion):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            sock.settimeout(None)  # readers block; sends are bounded by the socket buffer
        with self._lock:
            self._generation += 1
            generation = self._generation
            self._state_sock, self._motion_sock = state, motion
            self._joints = None
            self._status = sm.RobotStatus()
            self._fault = ""
        for sock, reader, label in ((state, self._state_reader, "state"), (motion, self._motion_reader, "motion")):
            threading.Thread(
                target=reader, args=(sock, generation), name=f"simple-message-{label}", daemon=True
            ).start()
        deadline = self._clock() + self.connect_timeout
        with self._lock:
            while self._joints is None and self._generation == generation and not self._protocol_fault:
                remaining = deadline - self._clock()
                if remaining <= 0:
                    break
                self._state_event.wait(min(remaining, 0.05))  # releases the lock while waiting
            joints, fault, protocol = self._joints, self._fault, self._protocol_fault
        if protocol:
            raise HwInterfaceError(f"the controller sent bad data: {protocol}", Result.DRIVER_FAULT)
        if joints is None:
            self._close("no joint state")
            raise HwInterfaceError(
                fault or f"no joint state on port {self.state_port} within {self.connect_timeout:g} s",
                Result.NOT_CONNECTED,
            )

    def _check_controller(self):
        """The controller's joints fit the robot: they lie within the URDF limits (a wrong
        joint order or unit shows here). The slot check runs on every state message."""
        with self._lock:
            joints = self._joints.copy()
        lower, upper = self.joint_limits
        outside = np.flatnonzero((joints < lower - 0.01) | (joints > upper + 0.01))
        if outside.size:
            names = [self.joint_names[i] for i in outside]
            raise HwInterfaceError(
                f"the controller reports {names} at {np.round(joints[outside], 3).tolist()} rad, outside the "
                f"URDF limits of {self.robot_name}: wrong robot, joint order (joint_slots) or units?",
                Result.LOGIN_FAILED,
            )

    def _close(self, why, result=Result.NOT_CONNECTED):
        """Close both connections; fail the pending requests (with ``result``); wake a
        watching move."""
        with self._lock:
            self._generation += 1
            socks = (self._motion_sock, self._state_sock)
            self._motion_sock = self._state_sock = None
            self._streaming = False
            self._stream_generation += 1
            pending, self._pending = list(self._pending), collections.deque()
            self._state_event.notify_all()
        for request in pending:
            text = (
                f"the controller sent bad data ({why})"
                if result == Result.DRIVER_FAULT
                else f"connection closed ({why})"
            )
            request.error = HwInterfaceError(f"{text} before the reply to {request.what}", result)
            request.event.set()
        for sock in socks:
            close_socket(sock)
        self._wake.set()

    def _lost(self, generation, why, protocol=False):
        """A reader's connection failed: a protocol error latches a fault and stops the arm
        first (its joints are unknown); a drop is reported and repaired on the next command."""
        with self._lock:
            if generation != self._generation:
                return
            if protocol:
                self._protocol_fault = why
                self._fault = f"controller sent bad data: {why}"
            else:
                self._fault = f"connection lost: {why}"
        if protocol:
            self._send_stop_trajectory()
        self._close(why, Result.DRIVER_FAULT if protocol else Result.NOT_CONNECTED)

    def _ensure_connected(self):
        """Raise unless connected with fresh state; reconnect with backoff after a drop."""
        with self._lock:
            if self._protocol_fault:
                raise HwInterfaceError(
                    f"the controller sent bad data ({self._protocol_fault}); check the controller and its "
                    "byte_order, then LOGIN again",
                    Result.DRIVER_FAULT,
                )
            if not self._logged_in:
                raise HwInterfaceError("not connected to the controller: call LOGIN first", Result.NOT_CONNECTED)
            up = self._motion_sock is not None and self._state_sock is not None
            fresh = up and self._joints is not None and self._clock() - self._joints_mono <= self.state_timeout
            if fresh:
                return
        if up:
            self._close("joint state stale")
        with self._connect_lock:
            with self._lock:
                if self._motion_sock is not None and self._joints is not None:
                    return
            error = self._connect_with_backoff(Result.NOT_CONNECTED)
        if error is not None:
            raise HwInterfaceError(
                f"lost the connection to the controller and could not reconnect: {error}", error.result
            )

    def _ensure_can_move(self):
        self._ensure_connected()
        with self._lock:
            status = self._status
        if status.e_stopped == sm.ON:
            raise HwInterfaceError(
                "the controller reports an emergency stop: clear it on the pendant", Result.PROTECTIVE_STOP
            )
        if status.in_error == sm.ON:
            raise HwInterfaceError(
                f"the controller is in error (code {status.error_code}): clear it on the pendant", Result.DRIVER_FAULT
            )
        if status.motion_possible == sm.OFF or status.drives_powered == sm.OFF:
            raise HwInterfaceError(
                "the controller says motion is not possible (drives off, or the server program not running)",
                Result.DRIVER_FAULT,
            )

    # -- readers (one thread per connection) -----------------------------------------------
    def _frames(self, sock, generation):
        """Yield the frames of ``sock`` until it closes; a close mid-frame is a truncated frame."""
        for chunk in self._chunks(sock, generation):
            yield from chunk

    def _chunks(self, sock, generation):
        """Yield the frames of ``sock`` as lists, one per read: the frames that arrived
        together. A close mid-frame is a truncated frame."""
        reader = sm.FrameReader(self.byte_order)
        while True:
            with self._lock:
                if generation != self._generation:
                    return
            try:
                data = sock.recv(4096)
            except OSError as exc:
                self._lost(generation, f"{exc}")
                return
            if not data:
                if reader.pending:
                    raise sm.SimpleMessageError(
                        f"truncated frame: the connection closed {reader.pending} bytes into it"
                    )
                self._lost(generation, "the controller closed the connection")
                return
            yield list(reader.feed(data))

    def _state_reader(self, sock, generation):
        # States carry no time of their own: each is stamped with its estimated sample time
        # (ArrivalStamps), not its receipt, so that states a busy reader thread read late
        # do not show speeds many times the arm's. Of the joint states read together only
        # the newest is taken (each is checked): the older ones were superseded before
        # anyone could have read them.
        stamps = ArrivalStamps()
        try:
            for chunk in self._chunks(sock, generation):
                arrival = self._clock()
                states = [joints for joints in map(self._state_frame, chunk) if joints is not None]
                if states:
                    self._joint_state(states[-1], stamps.stamps(arrival, len(states))[-1], generation)
        except sm.SimpleMessageError as exc:
            self._lost(generation, f"state port: {exc}", protocol=True)

    def _state_frame(self, frame):
        """Handle one state-port frame; return the joints (URDF order) of a joint state,
        checked but not yet taken, else None."""
        if frame.header.comm_type != sm.TOPIC and frame.header.msg_type not in (sm.PING,):
            raise sm.SimpleMessageError(
                f"message type {frame.header.msg_type} with comm_type {frame.header.comm_type} on the state port"
            )
        if sm.is_vendor_specific(frame.header.msg_type):
            self.ignored_messages += 1
            return None
        message = sm.decode_message(frame, self.byte_order)
        if isinstance(message, sm.RobotStatus):
            with self._lock:
                self._status = message
            if message.e_stopped == sm.ON or message.in_error == sm.ON:
                self._wake.set()
        elif isinstance(message, (sm.JointPosition, sm.JointFeedback)):
            values = message.joints if isinstance(message, sm.JointPosition) else message.positions
            return self._robot_joints(np.asarray(values, dtype=float))
        elif not isinstance(message, sm.Ping):
            raise sm.SimpleMessageError(f"unexpected {type(message).__name__} on the state port")
        return None

    def _robot_joints(self, slots):
        """The robot's joints (URDF order) from a state's slots; a filled slot the robot
        does not have is bad data."""
        extra = [i for i in range(sm.MAX_JOINTS) if i not in self.slots and slots[i] != 0.0]
        if extra:
            raise sm.SimpleMessageError(
                f"the controller reports joint slots {extra} that the robot ({self.kinematics.dof} joints, "
                f"slots {self.slots.tolist()}) does not have: check joint_slots and the robot model"
            )
        return slots[self.slots]

    def _joint_state(self, joints, sampled, generation):
        """Take ``joints``, sampled at ``sampled`` (the driver's clock)."""
        with self._lock:
            if generation != self._generation:
                return
            now = self._clock()
            self._joints = joints
            self._joints_wall = time.time() - (now - sampled)
            self._joints_mono = now
            self._state_event.notify_all()

    def _motion_reader(self, sock, generation):
        try:
            for frame in self._frames(sock, generation):
                header = frame.header
                if header.comm_type == sm.TOPIC and sm.is_vendor_specific(header.msg_type):
                    self.ignored_messages += 1
                    continue
                if header.comm_type != sm.SERVICE_REPLY:
                    raise sm.SimpleMessageError(
                        f"message type {header.msg_type} with comm_type {header.comm_type} on the motion port"
                    )
                sm.decode_message(frame, self.byte_order)  # checks the type and body length
                with self._lock:
                    request = self._pending.popleft() if self._pending else None
                if request is None:
                    continue  # a reply to nothing outstanding is ignored (REP)
                if request.msg_type != header.msg_type:
                    raise sm.SimpleMessageError(
                        f"reply of type {header.msg_type} to a request of type {request.msg_type} ({request.what})"
                    )
                request.reply_code = header.reply_code
                request.event.set()
        except sm.SimpleMessageError as exc:
            self._lost(generation, f"motion port: {exc}", protocol=True)

    # -- requests ----------------------------------------------------------------------------
    def _send(self, frame: bytes, request: _Pending | None, wanted=None):
        """Send ``frame`` on the motion socket (with ``request`` queued for its reply).
        ``wanted`` (called under the lock, with the send lock held) says whether the move
        or stream it belongs to still runs: once stop() has cut it, nothing more is sent
        after STOP_TRAJECTORY, and False is returned."""
        with self._send_lock:
            with self._lock:
                if wanted is not None and not wanted():
                    return False
                sock = self._motion_sock
                generation = self._generation
                if sock is None:
                    raise HwInterfaceError("not connected to the controller's motion port", Result.NOT_CONNECTED)
                if request is not None:
                    self._pending.append(request)
            try:
                sock.sendall(frame)
            except OSError as exc:
                self._lost(generation, f"send failed: {exc}")
                raise HwInterfaceError(f"lost the motion connection: {exc}", Result.NOT_CONNECTED) from None
        return True

    def _request(self, message, what, wanted=None):
        """Send a point (or PING) and wait for its reply; raise DRIVER_FAULT on FAILURE or
        no reply within reply_timeout. Returns False when a stop cut the move first."""
        request = _Pending(message.MSG_TYPE, what)
        frame = sm.encode(message, sm.SERVICE_REQUEST, byte_order=self.byte_order)
        if not self._send(frame, request, wanted):
            return False
        if not request.event.wait(self.reply_timeout):
            with self._lock:
                self._fault = f"no reply to {what} within {self.reply_timeout:g} s"
            self._send_stop_trajectory()
            self._close("reply timeout")
            raise HwInterfaceError(
                f"the controller did not answer {what} within {self.reply_timeout:g} s; robot stopped",
                Result.DRIVER_FAULT,
            )
        if request.error is not None:
            raise request.error
        if request.reply_code != sm.SUCCESS:
            with self._lock:
                self._fault = f"the controller refused {what} (reply code {request.reply_code})"
                status = self._status
            stopped = status.e_stopped == sm.ON
            raise HwInterfaceError(
                f"the controller refused {what} (reply code {request.reply_code}"
                + (", emergency stop)" if stopped else ")"),
                Result.PROTECTIVE_STOP if stopped else Result.DRIVER_FAULT,
            )
        self.points_sent += 1
        return True

    def _send_stop_trajectory(self):
        """STOP_TRAJECTORY now, its reply checked by the motion reader (not waited for)."""
        frame = sm.encode(sm.JointTrajPt(sm.STOP_TRAJECTORY), sm.SERVICE_REQUEST, byte_order=self.byte_order)
        try:
            sent = self._send(frame, _Pending(sm.JOINT_TRAJ_PT, "STOP_TRAJECTORY"))
        except HwInterfaceError:
            return False  # no motion connection: the controller has nothing to stop for us
        if sent:
            self.stops_sent += 1
        return sent

    def _point(self, sequence, joints, velocity, duration, elapsed):
        """The point message: JOINT_TRAJ_PT, or JOINT_TRAJ_PT_FULL with time and positions."""
        slots = np.zeros(sm.MAX_JOINTS)
        slots[self.slots] = joints
        if self.point_type == "joint_traj_pt_full":
            return sm.JointTrajPtFull(self.robot_id, sequence, 0x01 | 0x02, float(elapsed), tuple(slots))
        return sm.JointTrajPt(sequence, tuple(slots), float(velocity), float(duration))

    def _segment(self, start, goal, fraction):
        """(velocity fraction, duration) of a joint segment at ``fraction`` of the limits."""
        reach = np.abs(np.asarray(goal) - np.asarray(start)) / self.kinematics.velocity_limits
        duration = float(np.max(reach)) / fraction
        return fraction, duration

    # -- state -----------------------------------------------------------------------------
    def get_robot_joints(self) -> np.ndarray:
        self._ensure_connected()
        with self._lock:
            return self._joints.copy()

    def joint_sample(self):
        self._ensure_connected()
        with self._lock:
            return self._joints_wall, self._joints.copy()

    def get_robot_cartesian_position(self):
        return self.kinematics.forward_pose(self.get_robot_joints())

    def status(self) -> DriverStatus:
        with self._lock:
            connected = (
                self._motion_sock is not None
                and self._joints is not None
                and self._clock() - self._joints_mono <= self.state_timeout
            )
            status = self._status
            fault = self._fault
            if connected and status.in_error == sm.ON:
                fault = f"controller error {status.error_code}"
            if status.e_stopped == sm.ON:
                mode = "emergency_stop"
            elif status.in_error == sm.ON:
                mode = "fault"
            elif status.drives_powered == sm.OFF:
                mode = "drives_off"
            else:
                mode = "normal" if connected else ""
            return DriverStatus(
                connected=connected,
                moving=connected and (status.in_motion == sm.ON or self._active_move is not None),
                fault=fault,
                protective_stop=connected and status.e_stopped == sm.ON,
                safety_mode=mode,
            )

    # -- motion ----------------------------------------------------------------------------
    def set_joints(self, joints) -> None:
        self._ensure_can_move()
        with self._lock:
            self._set_stream_target(joints, self._clock())
            if not self._streaming:
                # A new stream starts where the arm is, at rest, with sequence 0.
                self._follower = StreamFollower(
                    self.kinematics.velocity_limits, self._joints.copy(), self.stream_acceleration
                )
                self._streaming = True
                self._stream_generation += 1
                threading.Thread(
                    target=self._stream_loop, args=(self._stream_generation,), name="simple-message-stream", daemon=True
                ).start()

    def _stream_loop(self, generation):
        """One point per stream_period: the follower's setpoint toward the latest target,
        each waiting for its reply; brakes to rest when targets stop coming."""
        sequence = 0
        elapsed = 0.0
        next_at = self._clock()

        def streaming():
            return self._streaming and generation == self._stream_generation

        try:
            while True:
                with self._lock:
                    if not self._streaming or generation != self._stream_generation:
                        return
                    if self._status.e_stopped == sm.ON or self._status.in_error == sm.ON:
                        self._fault = "emergency stop or controller error while streaming"
                        self._streaming = False
                        return
                    if self._target is not None and self._clock() - self._target_time > self.stream_timeout:
                        self._target = None
                        self._follower.brake()  # stale teleop: come to rest within the limits
                    elif self._target is not None:
                        self._follower.set_goal(self._target)
                    previous = self._follower.setpoint.copy()
                    setpoint = self._follower.step(self.stream_period).copy()
                    done = self._target is None and self._follower.at_rest
                if done:
                    with self._lock:
                        if generation == self._stream_generation:
                            self._streaming = False
                    return
                if sequence == 0 or np.any(setpoint != previous):
                    elapsed += self.stream_period
                    _, duration = self._segment(previous, setpoint, 1.0)
                    point = self._point(sequence, setpoint, 1.0, max(duration, self.stream_period), elapsed)
                    if not self._request(point, f"streamed point {sequence}", streaming):
                        return
                    sequence += 1
                next_at += self.stream_period
                delay = next_at - self._clock()
                if delay > 0:
                    time.sleep(delay)  # the stream's pace (real time); no lock held
                else:
                    next_at = self._clock()
        except HwInterfaceError as exc:
            with self._lock:
                if generation == self._stream_generation:
                    self._fault = f"streaming stopped: {exc}"
                    self._streaming = False

    def move_j(self, joints, timeout: float = 30.0) -> None:
        goal = np.asarray(joints, dtype=float)
        self._run_move("moveJ", lambda start: [goal], timeout, lambda q: self._joint_error(q, goal))

    def move_l(self, position, orientation, timeout: float = 30.0) -> None:
        position = np.asarray(position, dtype=float)
        orientation = np.asarray(orientation, dtype=float)

        def waypoints(start):
            line = self.kinematics.line_path(start, position, orientation)
            if not line.reachable:
                raise HwInterfaceError(
                    f"MOVE_L line unreachable from {100 * line.failed_at:.0f}% on (IK error {line.ik_error:.4f} m)",
                    Result.UNREACHABLE,
                )
            points = np.asarray(line.joints)[1:]
            if len(points) > self.max_points:  # bounded: resample to max_points, the goal kept
                index = np.unique(np.linspace(0, len(points) - 1, self.max_points).round().astype(int))
                points = points[index]
            return list(points)

        self._run_move("moveL", waypoints, timeout, lambda q: self._pose_error(q, position, orientation))

    def stop(self, reason: str = "STOP") -> None:
        """STOP_TRAJECTORY now, from any thread; streaming ends, a move being watched
        answers INTERRUPTED at once."""
        with self._lock:
            self._stopped_token = self._move_token
            self._stop_reason = reason
            self._active_move = None
            self._streaming = False
            self._stream_generation += 1
            self._target = None
            connected = self._motion_sock is not None
        self._wake.set()
        if connected:
            self._send_stop_trajectory()

    def set_gripper(self, closed: bool) -> None:
        raise HwInterfaceError(
            "simple_message's standard set has no gripper or IO message: wire the gripper to a controller program",
            Result.DRIVER_FAULT,
        )

    def set_digital_output(self, output: int, value: bool) -> None:
        raise HwInterfaceError(
            "simple_message's standard set has no digital output message (WRITE_OUTPUT is deprecated)",
            Result.DRIVER_FAULT,
        )

    # -- internals -------------------------------------------------------------------------
    def _run_move(self, kind, plan, timeout, error_of):
        """Send the move's points (each with its reply), then watch the measured joints:
        SUCCESS on arrival; INTERRUPTED on stop, e-stop, error, lost connection or an arm
        that stays still short of the goal; TIMEOUT (robot stopped) after ``timeout``."""
        self._ensure_can_move()
        with self._lock:
            if self._streaming:
                self._streaming = False
                self._stream_generation += 1
                stream_was_on = True
            else:
                stream_was_on = False
            self._move_token += 1
            token = self._move_token
            self._wake.clear()
            start = self._joints.copy()
        if stream_was_on:
            self._send_stop_trajectory()  # end the stream's trajectory before a new one
        points = plan(start)
        if not points:
            return
        with self._lock:
            if self._stopped_token >= token:
                raise self._interrupted(kind, token, self._stop_reason)
            self._active_move = kind
        deadline = self._clock() + max(float(timeout), 0.0)
        try:
            previous, elapsed = start, 0.0
            for sequence, point in enumerate(points):
                if kind == "moveJ":
                    velocity, duration = self._segment(previous, point, self.move_velocity)
                else:
                    velocity, duration = self._line_segment(previous, point)
                elapsed += duration
                message = self._point(sequence, point, velocity, duration, elapsed)
                if not self._request(message, f"{kind} point {sequence}", lambda: self._stopped_token < token):
                    raise self._interrupted(kind, token, self._stop_reason)
                previous = point
        except HwInterfaceError as exc:
            if exc.result == Result.INTERRUPTED:
                raise
            with self._lock:
                stopped = self._stopped_token >= token
            if stopped:
                raise self._interrupted(kind, token, self._stop_reason) from None
            self.stop(reason=f"{kind} failed")
            if exc.result == Result.NOT_CONNECTED:
                # The connection dropped while the points went out (before a reply came): the
                # move is cut short, as one whose connection drops while it is watched.
                raise self._interrupted(kind, token, f"connection lost ({exc})") from None
            raise
        self._watch(kind, token, deadline, timeout, error_of)

    def _line_segment(self, previous, point):
        """(velocity fraction, duration) of one MOVE_L chord: the tool's speed and turn rate,
        never faster than the joint limits allow."""
        p0, q0 = self.kinematics.forward_pose(previous)
        p1, q1 = self.kinematics.forward_pose(point)
        distance = float(np.linalg.norm(p1 - p0))
        angle = float((Rotation.from_quat(q0).inv() * Rotation.from_quat(q1)).magnitude())
        _, joint_time = self._segment(previous, point, 1.0)
        duration = max(distance / self.linear_speed, angle / self.angular_speed, joint_time, 1e-3)
        return min(1.0, max(joint_time / duration, 1e-3)), duration

    def _watch(self, kind, token, deadline, timeout, error_of):
        still_since = None
        last_q = None
        while True:
            with self._lock:
                self._raise_if_stopped(kind, token)
                if self._protocol_fault:
                    raise self._interrupted(kind, token, f"bad controller data ({self._protocol_fault})")
                if self._motion_sock is None or self._joints is None:
                    raise self._interrupted(kind, token, f"connection lost ({self._fault})")
                status, q = self._status, self._joints.copy()
            if status.e_stopped == sm.ON or status.in_error == sm.ON:
                why = "emergency stop" if status.e_stopped == sm.ON else f"controller error {status.error_code}"
                with self._lock:
                    self._fault = f"{why} during {kind}"
                raise self._interrupted(kind, token, why)
            now = self._clock()
            error, tolerance, unit = error_of(q)
            moving = status.in_motion == sm.ON or last_q is None or np.max(np.abs(q - last_q)) > 1e-6
            last_q = q
            if error <= tolerance and status.in_motion != sm.ON:
                with self._lock:
                    self._end_move(token)
                return
            if moving:
                still_since = None
            else:
                still_since = still_since or now
                if now - still_since > self.settle_time:
                    raise self._interrupted(
                        kind, token, f"the arm stopped {error:.4f} {unit} from the goal (tolerance {tolerance:g})"
                    )
            if now >= deadline:
                raise self._timed_out(kind, timeout)
            self._wake.wait(0.01)
