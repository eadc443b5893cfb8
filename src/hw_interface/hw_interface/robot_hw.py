"""The robot driver template: the paper's API plus what real controllers need.

A driver implements these few methods; motion_controller_server and every tool above it
only ever talk to this interface (as ros_control's RobotHW does for C++ controllers).
Poses are (position [m], quaternion x, y, z, w) of the tool in the robot base frame;
joints are radians in the driver's ``joint_names`` order.
"""

import abc
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import HwInterfaceError
from .protocol import Result


@dataclass
class DriverStatus:
    """What a driver reports about its controller."""

    connected: bool = False
    moving: bool = False
    fault: str = ""
    protective_stop: bool = False
    safety_mode: str = ""
    gripper: str = ""  # "" released; else what holds: the gripped body (sim) or "on" (IO gripper)


class RobotDriver(abc.ABC):
    """Base class of every robot driver. Methods raise HwInterfaceError on failure."""

    #: Registry name of the driver (e.g. "pybullet", "ur_rtde").
    name = ""

    #: The driver's ``driver_params`` (a motion_common.params.ParamSchema, units and ranges);
    #: None: the server passes them unchecked.
    PARAMETERS = None

    #: The name of the driver parameter (s) by which the arm trails a streamed (SET_JOINTS)
    #: target beyond the simulation's follower, which has no smoothing (UR: servoJ's
    #: lookahead_time); None: no more than it. A replay of an episode recorded in the
    #: simulation sends its stream that much earlier (``registry.stream_lag_s``).
    STREAM_LAG_PARAM = None

    @property
    @abc.abstractmethod
    def joint_names(self) -> list[str]:
        """Joint names in command order."""

    @property
    @abc.abstractmethod
    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) joint limits."""

    @abc.abstractmethod
    def get_robots(self) -> list[tuple[str, int]]:
        """GetRobots: (name, DOF) of every robot this driver can drive."""

    @abc.abstractmethod
    def login(self, url: str, user: str = "", password: str = "") -> None:
        """Login: connect to the controller at ``url``."""

    @abc.abstractmethod
    def disconnect(self) -> None:
        """Stop the robot and close the connection; safe to call twice."""

    @abc.abstractmethod
    def get_robot_joints(self) -> np.ndarray:
        """GetRobotJoints: measured joint positions."""

    @abc.abstractmethod
    def get_robot_cartesian_position(self) -> tuple[np.ndarray, np.ndarray]:
        """GetRobotCartesianPosition: measured tool pose."""

    def joint_sample(self) -> tuple[float, np.ndarray]:
        """(wall-clock time in s, measured joints) of one and the same sample: what
        /joint_states publishes, so that speeds computed from its stamps are true speeds.
        This default stamps the read; a driver that knows when its controller sampled the
        joints (a physics step, an RTDE packet) overrides it."""
        joints = self.get_robot_joints()
        return time.time(), joints

    @abc.abstractmethod
    def set_joints(self, joints: Sequence[float]) -> None:
        """SetJoints: stream a servo target; returns at once."""

    @abc.abstractmethod
    def move_j(self, joints: Sequence[float], timeout: float = 30.0) -> None:
        """MoveJ: joint-interpolated motion to ``joints``; blocks until the MEASURED joints
        are within the driver's goal tolerance. Raises HwInterfaceError with INTERRUPTED
        when stop(), a fault or a protective stop cuts it short, TIMEOUT (robot stopped)
        after ``timeout`` seconds."""

    @abc.abstractmethod
    def move_l(self, position: Sequence[float], orientation: Sequence[float], timeout: float = 30.0) -> None:
        """MoveL: straight-line tool motion with slerped orientation; blocks and answers as
        move_j does."""

    def path_limits(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(joint speed limits rad/s, joint acceleration limits rad/s^2) a FOLLOW_PATH is
        checked against before it is sent: the limits the driver's streaming enforces.
        None (this default): the driver cannot follow a timed path (NOT_SUPPORTED)."""
        return None

    def follow_path(self, path, timeout: float = 30.0) -> float:
        """FOLLOW_PATH: follow ``path`` (a checked hw_interface.timed_path.TimedPath),
        sampling it by the driver's own clock in its control loop; block until the MEASURED
        joints are within the goal tolerance of its end; return when it started (wall-clock
        s, as joint_sample()'s stamps). Raises as move_j does. This default refuses with
        NOT_SUPPORTED: a driver that overrides it also overrides path_limits()."""
        raise HwInterfaceError(
            f"the {self.name or type(self).__name__} driver cannot follow a timed path (FOLLOW_PATH); "
            "stream it with SET_JOINTS instead",
            Result.NOT_SUPPORTED,
        )

    @abc.abstractmethod
    def stop(self, reason: str = "STOP") -> None:
        """Stop any motion and streaming at once, from any thread; the robot holds where it
        is and a blocking move in progress raises INTERRUPTED (naming ``reason``)."""

    @abc.abstractmethod
    def set_gripper(self, closed: bool) -> None:
        """Grip (True) or release (False) with the tool's gripper."""

    @abc.abstractmethod
    def set_digital_output(self, output: int, value: bool) -> None:
        """Set one of the controller's digital outputs."""

    @abc.abstractmethod
    def status(self) -> DriverStatus:
        """Connection, motion and fault state."""


class UrdfModelMixin:
    """Joint names, limits and the robot list of a driver that holds a pinocchio model
    (``self.kinematics``) and a ``self.robot_name``: shared by the shipped drivers."""

    @property
    def joint_names(self) -> list[str]:
        """Joint names in command order (the URDF's)."""
        return list(self.kinematics.joint_names)

    @property
    def joint_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) joint limits from the URDF."""
        return self.kinematics.lower.copy(), self.kinematics.upper.copy()

    def get_robots(self) -> list[tuple[str, int]]:
        """GetRobots: the one robot this driver drives, with its DOF."""
        return [(self.robot_name, self.kinematics.dof)]


class SimulatedScene(abc.ABC):
    """What a *simulated* driver offers on top of RobotDriver: the true poses of its scene
    bodies (for demos, benchmarks and tests to measure against) and a reset to the scene's
    start. A real robot has no such thing; the server exposes these only for drivers that
    derive from this class."""

    @abc.abstractmethod
    def scene_poses(self) -> dict:
        """{body name: (position [m], quaternion x, y, z, w)} in the robot base frame."""

    @abc.abstractmethod
    def reset_scene(self) -> None:
        """Release the gripper, put every scene body back at its start pose and the arm at its
        start joints; any running motion ends INTERRUPTED."""
