"""A simulated simple_message controller at the byte level: the two TCP server programs of
a ROS-Industrial controller (motion and state), speaking the real framing, with an arm
that moves in real time. It is what hw_interface.industrial_driver is tested and dry-run
against (registry name ``simple_message_fake``).

- Motion port: every JOINT_TRAJ_PT / JOINT_TRAJ_PT_FULL request is answered. Points are
  queued and executed in order, each joint segment at the commanded fraction of the URDF
  speed limits (or the point's duration, if longer). A sequence out of order (not the
  previous + 1, nor 0 which starts a new trajectory) aborts the motion and is answered
  FAILURE, as is a point outside the joint limits or one sent during an e-stop or error.
  STOP_TRAJECTORY (-4) aborts: the arm brakes at ``stop_deceleration`` and stays still.
  START_TRAJECTORY_STREAMING/DOWNLOAD and END_TRAJECTORY are acknowledged. PING is echoed;
  any other request is answered FAILURE (REP).
- State port: JOINT_POSITION (or JOINT_FEEDBACK with ``joint_feedback=True``) and STATUS
  every ``state_period``.
- Injection: ``trigger_estop()`` / ``clear_estop()``, ``set_error(code)`` /
  ``clear_error()``, ``drop_connections(refuse=...)`` (and ``accept_connections()``),
  ``send_raw_state(bytes)`` and ``reply_raw_next(bytes)`` (malformed frames),
  ``silent = True`` (points get no reply), ``pause_state = True`` (no state published).

A dropped motion connection aborts the motion (the server program's own safety).
``clock`` (seconds, monotonic) can be injected. Memory is bounded: the point queue
(``queue_limit``) and the request log.
"""

import collections
import socket
import threading
import time

import numpy as np

from motion_common.kinematics import RobotKinematics

from .. import simple_message as sm
from ..driver_params import positive_param
from ..industrial_driver import SimpleMessageDriver
from ..tcp import close_socket
from .fake_parameters import fake_driver_parameters
from .fault_injection import FaultInjection

__all__ = ["FakeSimpleMessageController", "fake_simple_message_driver"]


class _Server:
    """One listening port with at most one client at a time (a new client replaces the old)."""

    def __init__(self, host, port, on_client):
        self.host, self.port = host, port
        self.on_client = on_client
        self.listener = None
        self.client = None
        self.lock = threading.Lock()  # serialises writes to the client
        self.open()

    def open(self):
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind((self.host, self.port))
        listener.listen(1)
        self.port = listener.getsockname()[1]
        self.listener = listener
        threading.Thread(target=self._accept, args=(listener,), name=f"fake-sm-accept-{self.port}", daemon=True).start()

    def _accept(self, listener):
        while True:
            try:
                client, _ = listener.accept()
            except OSError:
                return  # listener closed
            client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.drop_client()
            with self.lock:
                self.client = client
            self.on_client(client)

    def send(self, data, client=None):
        """Write to the client (or ``client``); False when there is none or it failed."""
        with self.lock:
            target = client or self.client
            if target is None or (client is not None and client is not self.client):
                return False
            try:
                target.sendall(data)
                return True
            except OSError:
                return False

    def drop_client(self):
        with self.lock:
            client, self.client = self.client, None
        close_socket(client)

    def close_listener(self):
        close_socket(self.listener)
        self.listener = None


class FakeSimpleMessageController(FaultInjection):
    """The simulated controller; ``start()`` opens both ports (``motion_port`` and
    ``state_port``: 0 picks free ones, read back after start), ``close()`` ends it."""

    def __init__(
        self,
        urdf_path: str,
        initial_joints=None,
        host: str = "127.0.0.1",
        motion_port: int = 0,
        state_port: int = 0,
        byte_order: str = "little",
        joint_slots=(),
        state_period: float = 0.01,
        period: float = 0.004,
        stop_deceleration: float = 20.0,
        joint_feedback: bool = False,
        queue_limit: int = 2000,
        tool_frame: str = "tool0",
        clock=time.monotonic,
    ):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        dof = self.kinematics.dof
        self.q = np.zeros(dof) if initial_joints is None else np.array(initial_joints, dtype=float)
        if self.q.shape != (dof,):
            raise ValueError(f"initial_joints has {self.q.size} values; the robot has {dof} joints")
        self.slots = np.array(list(joint_slots) or list(range(dof)), dtype=int)
        self.v = np.zeros(dof)
        self.host, self.byte_order = host, byte_order
        self.motion_port, self.state_port = int(motion_port), int(state_port)
        self.state_period, self.period = float(state_period), float(period)
        self.stop_deceleration = float(stop_deceleration)
        self.joint_feedback = bool(joint_feedback)
        self.clock = clock
        self.lock = threading.RLock()
        self._queue = collections.deque()  # (goal, fraction, duration) waiting
        self.queue_limit = int(queue_limit)
        self._segment = None  # (goal, velocity vector) of the point being executed
        self._braking = False
        self._expected = 0  # the next sequence number in order
        self._last_time = 0.0  # the previous JOINT_TRAJ_PT_FULL time
        self.estop = False
        self.error_code = 0
        self.silent = False
        self.pause_state = False
        self._raw_reply = None
        # Bounded logs of what arrived, for tests to read.
        self.requests = collections.deque(maxlen=20000)  # (msg_type, sequence)
        self.stops = 0
        self.aborts = 0
        self.refused = 0
        self.connections = 0
        self._running = False
        self._motion = self._state = None

    # -- life cycle ------------------------------------------------------------------------
    def start(self):
        self._motion = _Server(self.host, self.motion_port, self._serve_motion)
        self._state = _Server(self.host, self.state_port, lambda client: self._count())
        self.motion_port, self.state_port = self._motion.port, self._state.port
        self._running = True
        threading.Thread(target=self._run, name="fake-sm-controller", daemon=True).start()
        return self

    def close(self):
        self._running = False
        for server in (self._motion, self._state):
            if server is not None:
                server.close_listener()
                server.drop_client()

    def _count(self):
        with self.lock:
            self.connections += 1

    # -- injection -------------------------------------------------------------------------
    def trigger_estop(self):
        """Emergency stop: the arm halts at once; points are refused until cleared."""
        self._inject_fault(estop=True)

    def clear_estop(self):
        self._clear_fault(estop=False)

    def set_error(self, code: int):
        """The controller goes into error ``code``: the arm halts, points are refused."""
        self._inject_fault(error_code=int(code))

    def clear_error(self):
        self._clear_fault(error_code=0)

    def drop_connections(self, refuse: bool = False, ports=("motion", "state")):
        """Close the client connections of ``ports`` (both: a pulled cable); with ``refuse``
        the ports stay closed until accept_connections()."""
        servers = {"motion": self._motion, "state": self._state}
        for server in (servers[name] for name in ports):
            if refuse:
                server.close_listener()
            server.drop_client()

    def accept_connections(self):
        for server in (self._motion, self._state):
            if server.listener is None:
                server.open()

    def send_raw_state(self, data: bytes):
        """Write ``data`` on the state connection as it is (a malformed frame)."""
        return self._state.send(data)

    def reply_raw_next(self, data: bytes):
        """Answer the next motion request with ``data`` instead of its reply."""
        with self.lock:
            self._raw_reply = data

    def is_moving(self) -> bool:
        with self.lock:
            return bool(np.any(self.v != 0.0)) or self._segment is not None or bool(self._queue)

    def sequences(self, msg_type=sm.JOINT_TRAJ_PT):
        """Sequence numbers of the point requests so far, in order."""
        with self.lock:
            return [seq for kind, seq in self.requests if kind == msg_type]

    # -- motion server ---------------------------------------------------------------------
    def _serve_motion(self, client):
        self._count()
        threading.Thread(target=self._motion_client, args=(client,), name="fake-sm-motion", daemon=True).start()

    def _motion_client(self, client):
        reader = sm.FrameReader(self.byte_order)
        try:
            while True:
                data = client.recv(4096)
                if not data:
                    break
                for frame in reader.feed(data):
                    reply = self._handle(frame)
                    if reply is not None:
                        self._motion.send(reply, client)
        except (OSError, sm.SimpleMessageError):
            pass  # a broken client: drop it
        with self.lock:
            if self._motion.client is client or self._motion.client is None:
                self._abort()  # the motion client is gone: do not keep moving for it
        try:
            client.close()
        except OSError:
            pass

    def _reply(self, msg_type, code):
        with self.lock:
            raw, self._raw_reply = self._raw_reply, None
            if self.silent:
                return None
        if raw is not None:
            return raw
        return sm.encode_frame(sm.Header(msg_type, sm.SERVICE_REPLY, code), b"", self.byte_order)

    def _handle(self, frame):
        header = frame.header
        if header.comm_type != sm.SERVICE_REQUEST:
            return None  # topics to the motion server are ignored
        try:
            message = sm.decode_message(frame, self.byte_order)
        except sm.SimpleMessageError:
            with self.lock:
                self.refused += 1
            return self._reply(header.msg_type, sm.FAILURE)
        if isinstance(message, sm.Ping):
            return self._reply(sm.PING, sm.SUCCESS)
        if isinstance(message, sm.JointTrajPt):
            joints = np.asarray(message.joints)[self.slots]
            ok = self._point(message.sequence, joints, message.velocity, message.duration, sm.JOINT_TRAJ_PT)
            return self._reply(sm.JOINT_TRAJ_PT, sm.SUCCESS if ok else sm.FAILURE)
        if isinstance(message, sm.JointTrajPtFull):
            joints = np.asarray(message.positions)[self.slots]
            with self.lock:
                duration = message.time - self._last_time if message.sequence > 0 else message.time
                if message.sequence >= 0:
                    self._last_time = message.time
            ok = self._point(message.sequence, joints, 1.0, max(duration, 0.0), sm.JOINT_TRAJ_PT_FULL)
            return self._reply(sm.JOINT_TRAJ_PT_FULL, sm.SUCCESS if ok else sm.FAILURE)
        return self._reply(header.msg_type, sm.FAILURE)  # a service this server does not offer

    def _point(self, sequence, joints, fraction, duration, msg_type):
        """Queue one point or act on a special sequence number; False: refused."""
        with self.lock:
            self.requests.append((msg_type, sequence))
            if sequence == sm.STOP_TRAJECTORY:
                self.stops += 1
                self._abort()
                return True
            if sequence in (sm.START_TRAJECTORY_STREAMING, sm.START_TRAJECTORY_DOWNLOAD):
                self._expected = 0
                return True
            if sequence == sm.END_TRAJECTORY:
                return True
            if sequence < 0 or (sequence != 0 and sequence != self._expected):
                self._abort()  # out of order: abort what runs, refuse the point
                self.refused += 1
                return False
            lower, upper = self.kinematics.lower, self.kinematics.upper
            valid = (
                not self.estop
                and not self.error_code
                and 0.0 < fraction <= 1.0
                and np.all(np.isfinite(joints))
                and np.all(joints >= lower - 1e-6)
                and np.all(joints <= upper + 1e-6)
                and len(self._queue) < self.queue_limit
            )
            if not valid:
                self._abort()
                self.refused += 1
                return False
            if sequence == 0:
                self._queue.clear()  # a new trajectory replaces the rest of the old one
                self._braking = False
            self._queue.append((np.array(joints, dtype=float), float(fraction), float(duration)))
            self._expected = sequence + 1
            return True

    def _abort(self):
        """Abort the trajectory: drop the queue, brake to rest (caller holds the lock)."""
        self._queue.clear()
        self._segment = None
        self._expected = 0
        if np.any(self.v != 0.0):
            self._braking = True
            self.aborts += 1

    def _halt(self):
        """Stop at once (e-stop, error): no braking ramp (caller holds the lock)."""
        self._queue.clear()
        self._segment = None
        self._braking = False
        self._expected = 0
        self.v[:] = 0.0

    # -- the controller loop ---------------------------------------------------------------
    def _run(self):
        last = self.clock()
        next_state = last
        while self._running:
            time.sleep(self.period)
            now = self.clock()
            dt, last = now - last, now
            with self.lock:
                self._tick(dt)
            if now >= next_state:
                next_state = now + self.state_period
                if not self.pause_state:
                    self._state.send(self._state_frames())

    def _tick(self, dt):
        if dt <= 0:
            return
        if self._braking:
            speed = float(np.max(np.abs(self.v)))
            scale = max(0.0, speed - self.stop_deceleration * dt) / speed if speed > 0 else 0.0
            self.v = self.v * scale
            self.q = np.clip(self.q + self.v * dt, self.kinematics.lower, self.kinematics.upper)
            if scale == 0.0:
                self._braking = False
            return
        remaining = dt
        while remaining > 0:
            if self._segment is None:
                if not self._queue:
                    self.v[:] = 0.0
                    return
                goal, fraction, duration = self._queue.popleft()
                delta = goal - self.q
                needed = float(np.max(np.abs(delta) / (fraction * self.kinematics.velocity_limits)))
                time_s = max(needed, duration)
                if time_s <= 0:
                    self.q = goal.copy()
                    continue
                self._segment = (goal, delta / time_s)
            goal, velocity = self._segment
            left = goal - self.q
            time_left = float(np.max(np.abs(left) / np.maximum(np.abs(velocity), 1e-12)))
            if time_left <= remaining:
                self.q = goal.copy()
                self._segment = None
                remaining -= time_left
                self.v = velocity
            else:
                self.q = self.q + velocity * remaining
                self.v = velocity
                remaining = 0.0
        if self._segment is None and not self._queue:
            self.v[:] = 0.0

    def _state_frames(self) -> bytes:
        with self.lock:
            slots = np.zeros(sm.MAX_JOINTS)
            slots[self.slots] = self.q
            moving = bool(np.any(self.v != 0.0)) or self._segment is not None or bool(self._queue)
            fault = self.estop or bool(self.error_code)
            status = sm.RobotStatus(
                drives_powered=sm.OFF if self.estop else sm.ON,
                e_stopped=sm.ON if self.estop else sm.OFF,
                error_code=self.error_code,
                in_error=sm.ON if self.error_code else sm.OFF,
                in_motion=sm.ON if moving else sm.OFF,
                mode=2,  # AUTO
                motion_possible=sm.OFF if fault else sm.ON,
            )
        if self.joint_feedback:
            joints = sm.JointFeedback(0, 0x02, 0.0, tuple(slots))
        else:
            joints = sm.JointPosition(0, tuple(slots))
        return sm.encode(joints, byte_order=self.byte_order) + sm.encode(status, byte_order=self.byte_order)


def fake_simple_message_driver(
    urdf_path: str,
    tool_frame: str = "tool0",
    initial_joints=None,
    robot_ip: str = "",
    armed: bool = False,
    robot_name=None,
    motion_port: int = 0,
    state_port: int = 0,
    fake_stop_deceleration: float = 20.0,
    **params,
) -> SimpleMessageDriver:
    """The ``simple_message_fake`` driver: SimpleMessageDriver on a
    FakeSimpleMessageController started on free local ports (the ports given are ignored),
    whose arm starts at ``initial_joints`` (the robot's start pose). ``robot_ip`` and
    ``armed`` are accepted and ignored: nothing real is reached. The controller is
    ``driver.fake``; any LOGIN url reaches it."""
    fake = FakeSimpleMessageController(
        urdf_path,
        initial_joints,
        byte_order=params.get("byte_order", "little"),
        joint_slots=params.get("joint_slots", ()),
        stop_deceleration=fake_stop_deceleration,
        tool_frame=tool_frame,
    ).start()
    driver = _FakeControllerDriver(
        urdf_path,
        tool_frame,
        robot_ip="127.0.0.1",
        armed=True,
        motion_port=fake.motion_port,
        state_port=fake.state_port,
        robot_name=robot_name,
        **params,
    )
    driver.fake = fake
    return driver


class _FakeControllerDriver(SimpleMessageDriver):
    """The driver of a fake controller: every LOGIN url means the fake."""

    def login(self, url: str = "", user: str = "", password: str = "") -> None:
        super().login("", user, password)


fake_simple_message_driver.PARAMETERS = fake_driver_parameters(
    SimpleMessageDriver.PARAMETERS,
    positive_param(
        "fake_stop_deceleration", 20.0, "rad/s^2", "how hard the simulated controller brakes on STOP_TRAJECTORY", 1000.0
    ),
)
