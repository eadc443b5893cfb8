"""A fake of ur_rtde's RTDEControlInterface / RTDEReceiveInterface / RTDEIOInterface.

It records every call and simulates a robot well enough to test the UR driver and dry-run
a UR session without a controller: joints jump to moveJ/servoJ targets, the TCP pose
follows by forward kinematics, and faults (protective stop, dropped connection) can be
injected. Usage: ``FakeUR(urdf).classes()`` gives the three classes for URRtdeDriver.
"""
import threading
import time

import numpy as np

from motion_common.kinematics import RobotKinematics

from .ur_driver import pose_to_ur


class FakeUR:
    """The simulated controller shared by the three fake interfaces."""

    def __init__(self, urdf_path: str, initial_joints=None, frequency: float = 500.0):
        self.kinematics = RobotKinematics(urdf_path)
        self.q = np.zeros(self.kinematics.dof) if initial_joints is None else np.array(initial_joints, float)
        self.period = 1.0 / frequency
        self.calls = []
        self.outputs = {}
        self.connected = True
        self.allow_reconnect = True
        self.protective_stopped = False
        self.connections = 0
        self.lock = threading.Lock()

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

    def drop_connection(self, allow_reconnect: bool = True):
        """Simulate a dropped cable; reconnect() succeeds only if ``allow_reconnect``."""
        self.connected = False
        self.allow_reconnect = allow_reconnect

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


class _FakeControl(_FakeInterface):
    def _move(self, name, q, *args):
        self.fake.record(name, list(q), *args)
        if self.fake.protective_stopped:
            return False
        self.fake.q = np.array(q, dtype=float)
        return True

    def moveJ(self, q, speed=1.05, acceleration=1.4, asynchronous=False):
        return self._move("moveJ", q, speed, acceleration, asynchronous)

    def moveL(self, pose, speed=0.25, acceleration=1.2, asynchronous=False):
        self.fake.record("moveL", list(pose), speed, acceleration, asynchronous)
        if self.fake.protective_stopped:
            return False
        from motion_common.kinematics import pose_to_se3
        from scipy.spatial.transform import Rotation
        target = pose_to_se3(pose[:3], Rotation.from_rotvec(pose[3:]).as_quat())
        result = self.fake.kinematics.solve_ik(target, self.fake.q)
        if result.success:
            self.fake.q = result.joints
        return result.success

    def servoJ(self, q, speed, acceleration, time_s, lookahead_time, gain):
        return self._move("servoJ", q, speed, acceleration, time_s, lookahead_time, gain)

    def servoStop(self, a=10.0):
        self.fake.record("servoStop", a)
        return True

    def stopJ(self, a=2.0, asynchronous=False):
        self.fake.record("stopJ", a)

    def stopScript(self):
        self.fake.record("stopScript")

    def isSteady(self):
        self.fake.record("isSteady")
        return True

    def initPeriod(self):
        return time.perf_counter()

    def waitPeriod(self, start):
        remaining = start + self.fake.period - time.perf_counter()
        if remaining > 0:
            time.sleep(remaining)


class _FakeReceive(_FakeInterface):
    def getActualQ(self):
        self.fake.record("getActualQ")
        return self.fake.q.tolist()

    def getActualTCPPose(self):
        self.fake.record("getActualTCPPose")
        position, orientation = self.fake.kinematics.forward_pose(self.fake.q)
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
