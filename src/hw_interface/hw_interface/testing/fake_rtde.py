"""A fake of ur_rtde's RTDEControlInterface / RTDEReceiveInterface / RTDEIOInterface.

It records every call and simulates the arm in real time, so the UR driver can be tested
and a UR session dry-run without a controller:

- moveJ / moveL (blocking or ``asynchronous=True``) move the arm along a joint line / a
  Cartesian line at the commanded speed and acceleration (trapezoid profile of the path
  parameter: rad of the leading joint for moveJ, m of the tool for moveL), in a background
  thread at the controller period;
- getAsyncOperationProgress is 0 while an asynchronous move runs and negative once it has
  ended, toggling between -1 and -2 from one operation to the next, as ur_rtde does;
  getAsyncOperationProgressEx gives the same as an object;
- stopJ / stopL / servoStop (from any thread) decelerate the arm at the given rate and halt
  it; a blocking move then returns False;
- servoJ moves toward its target (first-order, ``lookahead_time``, within joint speed);
- ``trigger_protective_stop()`` halts the arm at once and refuses motion until
  ``clear_protective_stop()``; ``drop_connection()`` makes every call raise RuntimeError
  (the arm halts, as the controller's script does when RTDE goes away).

Usage: ``FakeUR(urdf, initial_joints).classes()`` gives the three classes for
URRtdeDriver. ``clock`` (seconds, monotonic) can be injected.
"""

import collections
import threading
import time

import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.kinematics import RobotKinematics

from ..ur_driver import URRtdeDriver, pose_to_ur
from .fake_parameters import fake_driver_parameters
from .fault_injection import FaultInjection

# Joint speed (rad/s) servoJ may use, and the speed under which the arm counts as steady.
SERVO_MAX_SPEED = 3.14
STEADY_SPEED = 1e-4


class _PathMotion:
    """A rest-to-rest motion along a path parametrised by s in [0, length]."""

    def __init__(self, kind, q_of_s, length, speed, acceleration, blocking):
        self.kind = kind  # "moveJ" or "moveL"
        self.q_of_s = q_of_s
        self.length = float(length)
        self.speed = float(speed)
        self.acceleration = float(acceleration)
        self.s = 0.0
        self.v = 0.0
        self.stop_deceleration = None  # set by stopJ/stopL
        self.done = threading.Event()
        self.arrived = False
        self.blocking = blocking

    def step(self, dt):
        """Advance dt seconds; return the joint position."""
        if self.stop_deceleration is not None:
            self.v = max(0.0, self.v - self.stop_deceleration * dt)
        else:
            remaining = self.length - self.s
            braking = self.v * self.v / (2.0 * self.acceleration)
            if remaining <= braking + self.v * dt:
                self.v = max(0.0, self.v - self.acceleration * dt)
                if self.v == 0.0 or remaining <= 1e-9:
                    self.s = self.length  # rest at the goal (discretisation remainder)
            else:
                self.v = min(self.speed, self.v + self.acceleration * dt)
        self.s = min(self.length, self.s + self.v * dt)
        return self.q_of_s(self.s)

    @property
    def finished(self):
        return self.s >= self.length or (self.stop_deceleration is not None and self.v <= 0.0)


class FakeUR(FaultInjection):
    """The simulated controller shared by the three fake interfaces."""

    def __init__(
        self,
        urdf_path: str,
        initial_joints=None,
        frequency: float = 500.0,
        clock=time.monotonic,
        tool_frame: str = "tool0",
    ):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        self.q = np.zeros(self.kinematics.dof) if initial_joints is None else np.array(initial_joints, float)
        self.qd = np.zeros_like(self.q)
        self.period = 1.0 / frequency
        self.clock = clock
        # Bounded: a dry-run session polls the state at 100 Hz for hours.
        self.calls = collections.deque(maxlen=20000)
        self.outputs = {}
        self.connected = True
        self.allow_reconnect = True
        self._protective_stopped = False
        self.connections = 0
        self.lock = threading.RLock()
        self._motion = None  # a _PathMotion
        self._servo_target = None  # np.ndarray while servoing
        self._servo_lookahead = 0.1
        self._servo_stop_deceleration = None
        self._progress = -1  # ur_rtde: <0 when no async operation runs
        self._thread = None
        self.servo_targets = 0

    # -- bookkeeping -------------------------------------------------------------------
    def record(self, name, *args):
        """Log a call; raise like ur_rtde does when the connection is down."""
        with self.lock:
            self.calls.append((name, args))
        if not self.connected and name not in ("isConnected", "reconnect", "disconnect"):
            raise RuntimeError("RTDE connection lost")

    def names(self):
        """Names of the calls so far, in order."""
        with self.lock:
            return [name for name, _ in self.calls]

    # -- fault injection ---------------------------------------------------------------
    @property
    def protective_stopped(self):
        return self._protective_stopped

    @protective_stopped.setter
    def protective_stopped(self, value):
        if value:
            self.trigger_protective_stop()
        else:
            self.clear_protective_stop()

    def trigger_protective_stop(self):
        """A protective stop: the arm halts at once, motion is refused until cleared."""
        self._inject_fault(_protective_stopped=True)

    def clear_protective_stop(self):
        """Cleared on the pendant."""
        self._clear_fault(_protective_stopped=False)

    def drop_connection(self, allow_reconnect: bool = True):
        """Simulate a dropped cable; reconnect() succeeds only if ``allow_reconnect``."""
        self._inject_fault(connected=False, allow_reconnect=allow_reconnect)

    def is_moving(self):
        """True while the simulated arm moves (any joint faster than STEADY_SPEED)."""
        with self.lock:
            return bool(np.max(np.abs(self.qd)) > STEADY_SPEED) or self._motion is not None

    # -- motion ------------------------------------------------------------------------
    def _halt(self):
        """Stop everything now (caller holds the lock)."""
        if self._motion is not None:
            self._finish(arrived=False)
        self._servo_target = None
        self._servo_stop_deceleration = None
        self.qd[:] = 0.0

    def _finish(self, arrived):
        motion = self._motion
        self._motion = None
        motion.arrived = arrived
        if not motion.blocking:
            self._progress = -2 if self._progress == -1 else -1
        motion.done.set()

    def start_path(self, kind, q_of_s, length, speed, acceleration, blocking):
        """Begin a path motion (replacing any other); return it."""
        with self.lock:
            if self._motion is not None:
                self._finish(arrived=False)
            self._servo_target = None
            motion = _PathMotion(kind, q_of_s, length, speed, acceleration, blocking)
            self._motion = motion
            if not blocking:
                self._progress = 0
            self._ensure_thread()
            return motion

    def stop_motion(self, deceleration):
        """Decelerate a path motion or servoing at ``deceleration`` and halt."""
        with self.lock:
            if self._motion is not None:
                self._motion.stop_deceleration = max(float(deceleration), 1e-6)
            if self._servo_target is not None:
                self._servo_target = None
                self._servo_stop_deceleration = max(float(deceleration), 1e-6)
                self._ensure_thread()

    def servo(self, target, lookahead_time):
        with self.lock:
            if self._motion is not None:
                return False
            self._servo_target = np.array(target, dtype=float)
            self._servo_lookahead = float(lookahead_time)
            self._servo_stop_deceleration = None
            self.servo_targets += 1
            self._ensure_thread()
            return True

    def _ensure_thread(self):
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._run, name="fake-ur-arm", daemon=True)
            self._thread.start()

    def _run(self):
        """The controller loop: integrate the active motion every period until idle."""
        last = self.clock()
        while True:
            time.sleep(self.period)
            now = self.clock()
            dt, last = now - last, now
            with self.lock:
                if not self._tick(dt):
                    self._thread = None
                    return

    def _tick(self, dt):
        """One controller step; False once nothing moves."""
        if dt <= 0:
            return True
        previous = self.q.copy()
        motion = self._motion
        if motion is not None:
            self.q = np.asarray(motion.step(dt), dtype=float)
            if motion.finished:
                self._finish(arrived=motion.s >= motion.length and motion.stop_deceleration is None)
        elif self._servo_target is not None:
            gain = min(1.0, dt / max(self._servo_lookahead, dt))
            step = np.clip((self._servo_target - self.q) * gain, -SERVO_MAX_SPEED * dt, SERVO_MAX_SPEED * dt)
            self.q = self.q + step
        elif self._servo_stop_deceleration is not None:
            speed = np.abs(self.qd)
            new_speed = np.maximum(0.0, speed - self._servo_stop_deceleration * dt)
            self.q = self.q + np.sign(self.qd) * new_speed * dt
            if not np.any(new_speed > 0):
                self._servo_stop_deceleration = None
        self.qd = (self.q - previous) / dt
        return (
            self._motion is not None
            or self._servo_target is not None
            or self._servo_stop_deceleration is not None
            or bool(np.any(self.qd != 0.0))
        )

    def classes(self):
        """(control, receive, io) classes bound to this fake controller."""
        robot = self

        class Control(_FakeControl):
            fake = robot

        class Receive(_FakeReceive):
            fake = robot

        class IO(_FakeIO):
            fake = robot

        return Control, Receive, IO


class _FakeInterface:
    fake: FakeUR = None

    def __init__(self, hostname, *args, **kwargs):
        self.hostname = hostname
        self.fake.record(type(self).__name__ + ".__init__", hostname)
        self.fake.connections += 1

    def isConnected(self):
        self.fake.record("isConnected")
        return self.fake.connected

    def reconnect(self):
        self.fake.record("reconnect")
        if self.fake.allow_reconnect:
            self.fake.connected = True
        return self.fake.connected

    def disconnect(self):
        self.fake.record("disconnect")


class AsyncOperationStatus:
    """What getAsyncOperationProgressEx returns (the subset the driver reads)."""

    def __init__(self, progress):
        self._progress = progress

    def isAsyncOperationRunning(self):
        return self._progress >= 0

    def progress(self):
        return self._progress


class _FakeControl(_FakeInterface):
    def _run_path(self, kind, q_of_s, length, speed, acceleration, asynchronous):
        fake = self.fake
        if fake.protective_stopped:
            return False
        motion = fake.start_path(kind, q_of_s, length, speed, acceleration, blocking=not asynchronous)
        if asynchronous:
            return True
        motion.done.wait()
        return motion.arrived

    def moveJ(self, q, speed=1.05, acceleration=1.4, asynchronous=False):
        self.fake.record("moveJ", list(q), speed, acceleration, asynchronous)
        start, goal = self.fake.q.copy(), np.array(q, dtype=float)
        length = float(np.max(np.abs(goal - start)))
        q_of_s = (lambda s: goal.copy()) if length == 0 else (lambda s: start + (goal - start) * (s / length))
        return self._run_path("moveJ", q_of_s, length, speed, acceleration, asynchronous)

    def moveL(self, pose, speed=0.25, acceleration=1.2, asynchronous=False):
        self.fake.record("moveL", list(pose), speed, acceleration, asynchronous)
        fake = self.fake
        line = fake.kinematics.line_path(fake.q.copy(), pose[:3], Rotation.from_rotvec(pose[3:6]).as_quat())
        if not line.reachable:
            return False  # the controller refuses an unreachable line
        waypoints, distance, angle, count = line.joints, line.distance, line.angle, len(line.joints)
        # Path length in metres; a pure rotation counts 0.1 m per radian.
        length = max(distance, 0.1 * angle)

        def q_of_s(s):
            if length == 0:
                return waypoints[-1].copy()
            x = s / length * (count - 1)
            i = min(int(x), count - 2)
            return waypoints[i] + (x - i) * (waypoints[i + 1] - waypoints[i])

        return self._run_path("moveL", q_of_s, length, speed, acceleration, asynchronous)

    def getAsyncOperationProgress(self):
        self.fake.record("getAsyncOperationProgress")
        with self.fake.lock:
            return self.fake._progress

    def getAsyncOperationProgressEx(self):
        return AsyncOperationStatus(self.getAsyncOperationProgress())

    def servoJ(self, q, speed, acceleration, time_s, lookahead_time, gain):
        self.fake.record("servoJ", list(q), speed, acceleration, time_s, lookahead_time, gain)
        if self.fake.protective_stopped:
            return False
        return self.fake.servo(q, lookahead_time)

    def servoStop(self, a=10.0):
        self.fake.record("servoStop", a)
        self.fake.stop_motion(a)
        return True

    def stopJ(self, a=2.0, asynchronous=False):
        self.fake.record("stopJ", a, asynchronous)
        self.fake.stop_motion(a)

    def stopL(self, a=10.0, asynchronous=False):
        self.fake.record("stopL", a, asynchronous)
        self.fake.stop_motion(a)

    def stopScript(self):
        self.fake.record("stopScript")
        with self.fake.lock:
            self.fake._halt()

    def isSteady(self):
        self.fake.record("isSteady")
        return not self.fake.is_moving()

    def isProtectiveStopped(self):
        self.fake.record("isProtectiveStopped")
        return self.fake.protective_stopped

    def initPeriod(self):
        return time.perf_counter()

    def waitPeriod(self, start):
        remaining = start + self.fake.period - time.perf_counter()
        if remaining > 0:
            time.sleep(remaining)


class _FakeReceive(_FakeInterface):
    def getActualQ(self):
        self.fake.record("getActualQ")
        with self.fake.lock:
            return self.fake.q.tolist()

    def getActualQd(self):
        self.fake.record("getActualQd")
        with self.fake.lock:
            return self.fake.qd.tolist()

    def getActualTCPPose(self):
        self.fake.record("getActualTCPPose")
        with self.fake.lock:
            q = self.fake.q.copy()
        position, orientation = self.fake.kinematics.forward_pose(q)
        return pose_to_ur(position, orientation)

    def isProtectiveStopped(self):
        self.fake.record("isProtectiveStopped")
        return self.fake.protective_stopped

    def getSafetyMode(self):
        self.fake.record("getSafetyMode")
        return 3 if self.fake.protective_stopped else 1

    def isEmergencyStopped(self):
        self.fake.record("isEmergencyStopped")
        return False


class _FakeIO(_FakeInterface):
    def setStandardDigitalOut(self, output, value):
        self.fake.record("setStandardDigitalOut", output, value)
        self.fake.outputs[output] = value
        return True


def fake_ur_driver(
    urdf_path: str,
    tool_frame: str = "tool0",
    initial_joints=None,
    robot_ip: str = "",
    armed: bool = False,
    robot_name=None,
    **params,
) -> URRtdeDriver:
    """The ``ur_rtde_fake`` driver: URRtdeDriver on a FakeUR arm that starts at
    ``initial_joints`` (the robot's start pose), for dry runs of the UR path without a
    robot. ``robot_ip`` and ``armed`` are accepted and ignored: nothing real is reached.
    The fake is ``driver.fake``."""
    fake = FakeUR(urdf_path, initial_joints, params.get("frequency", 500.0), tool_frame=tool_frame)
    driver = URRtdeDriver(
        urdf_path,
        tool_frame,
        robot_ip="fake-ur",
        armed=True,
        robot_name=robot_name,
        rtde_classes=fake.classes(),
        **params,
    )
    driver.fake = fake
    return driver


fake_ur_driver.PARAMETERS = fake_driver_parameters(URRtdeDriver.PARAMETERS)
fake_ur_driver.STREAM_LAG_PARAM = URRtdeDriver.STREAM_LAG_PARAM
