"""A worked example of a robot driver: an ideal arm that moves its joints at a set speed.

Copy this file to start the driver of your own robot. Every driver derives from
``hw_interface.robot_hw.RobotDriver`` and answers the paper's API (get_robots, login,
get_robot_joints, get_robot_cartesian_position, set_joints, move_j, move_l) plus stop,
the gripper, digital outputs and a status. motion_controller_server checks every request
(lengths, finite values, joint limits, workspace, jumps) before your driver sees it, so a
driver only has to talk to its controller.

Run a session with it (from the project root):

    PYTHONPATH=$PWD/examples scripts/teleop_sim driver:=kinematic_driver:KinematicDriver

The server creates the driver with ``urdf_path``, ``tool_frame``, ``robot_name`` and the
``driver_params`` (here: PARAMETERS below; ``driver_params:=FILE`` loads a YAML of them,
``robot_config:=FILE`` the start pose ``initial_joints``). A real driver would open its
connection in ``login`` and read the joints from the controller; this one integrates its
commands in time instead, so it needs no thread: the joints at any moment follow from the
last command and the clock.
"""

import threading
import time

import numpy as np

from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import Result
from hw_interface.robot_hw import DriverStatus, RobotDriver, UrdfModelMixin
from motion_common.kinematics import RobotKinematics
from motion_common.params import Param, ParamSchema

__all__ = ["KinematicDriver"]


class KinematicDriver(UrdfModelMixin, RobotDriver):
    """Joints move straight to their target at ``joint_speed``; MoveL follows the IK of a
    straight tool line; STOP freezes the joints where they are, from any thread."""

    name = "kinematic_example"

    # The driver_params, checked by the server at start-up (units and ranges; an unknown
    # key stops the node naming the file).
    PARAMETERS = ParamSchema(
        [
            Param("initial_joints", None, "rad", "start pose (robot_config)", kind=list, nullable=True),
            Param("joint_speed", 1.0, "rad/s", "speed of every joint toward its target", low=0.0, low_open=True),
            Param("goal_tolerance", 0.001, "rad", "largest joint error for a move's SUCCESS", low=0.0, low_open=True),
        ]
    )

    def __init__(
        self,
        urdf_path: str,
        tool_frame: str = "tool0",
        robot_name: str | None = None,
        initial_joints=None,
        joint_speed: float = 1.0,
        goal_tolerance: float = 0.001,
    ):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        self.robot_name = robot_name or "kinematic_arm"
        dof = self.kinematics.dof
        start = np.zeros(dof) if initial_joints is None else np.asarray(initial_joints, dtype=float)
        if start.shape != (dof,):
            raise HwInterfaceError(f"initial_joints needs {dof} values, got {len(start)}", Result.WRONG_LENGTH)
        self.joint_speed = float(joint_speed)
        self.goal_tolerance = float(goal_tolerance)
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        # The motion in progress: joints `_origin` at time `_since`, heading for `_target`.
        self._origin = start
        self._target = start.copy()
        self._since = time.monotonic()
        self._connected = False
        self._gripper = False

    # -- the joints as a function of time ---------------------------------------------
    def _joints_at(self, now: float) -> np.ndarray:
        step = self.joint_speed * max(0.0, now - self._since)
        delta = self._target - self._origin
        return self._origin + np.clip(delta, -step, step)

    def _head_for(self, target) -> None:
        with self._lock:
            now = time.monotonic()
            self._origin = self._joints_at(now)
            self._target = np.asarray(target, dtype=float).copy()
            self._since = now

    def _require_connection(self) -> None:
        if not self._connected:
            raise HwInterfaceError("not logged in", Result.NOT_CONNECTED)

    # -- RobotDriver ------------------------------------------------------------------
    def login(self, url: str, user: str = "", password: str = "") -> None:
        self._connected = True

    def disconnect(self) -> None:
        self.stop("disconnect")
        self._connected = False

    def get_robot_joints(self) -> np.ndarray:
        with self._lock:
            return self._joints_at(time.monotonic())

    def get_robot_cartesian_position(self):
        return self.kinematics.forward_pose(self.get_robot_joints())

    def set_joints(self, joints) -> None:
        self._require_connection()
        self._stopped.clear()
        self._head_for(joints)

    def _wait_until_at(self, goal, timeout: float) -> None:
        """Block until the joints are within goal_tolerance of ``goal``; STOP raises
        INTERRUPTED and a move longer than ``timeout`` stops and raises TIMEOUT."""
        deadline = time.monotonic() + timeout
        while np.max(np.abs(self.get_robot_joints() - goal)) > self.goal_tolerance:
            if self._stopped.wait(0.002):
                raise HwInterfaceError("move interrupted by STOP", Result.INTERRUPTED)
            if time.monotonic() > deadline:
                self.stop("timeout")
                raise HwInterfaceError(f"move did not arrive within {timeout} s", Result.TIMEOUT)

    def move_j(self, joints, timeout: float = 30.0) -> None:
        self._require_connection()
        self._stopped.clear()
        goal = np.asarray(joints, dtype=float)
        self._head_for(goal)
        self._wait_until_at(goal, timeout)

    def move_l(self, position, orientation, timeout: float = 30.0) -> None:
        self._require_connection()
        self._stopped.clear()
        path = self.kinematics.line_path(self.get_robot_joints(), position, orientation)
        if not path.reachable:
            raise HwInterfaceError(f"line unreachable at {path.failed_at:.0%} of its length", Result.UNREACHABLE)
        deadline = time.monotonic() + timeout
        for waypoint in path.joints[1:]:
            self._head_for(waypoint)
            self._wait_until_at(waypoint, max(0.0, deadline - time.monotonic()))

    def stop(self, reason: str = "STOP") -> None:
        self._stopped.set()
        with self._lock:
            now = time.monotonic()
            self._origin = self._joints_at(now)
            self._target = self._origin.copy()
            self._since = now

    def set_gripper(self, closed: bool) -> None:
        self._require_connection()
        self._gripper = bool(closed)

    def set_digital_output(self, output: int, value: bool) -> None:
        self._require_connection()

    def status(self) -> DriverStatus:
        with self._lock:
            moving = bool(np.any(self._joints_at(time.monotonic()) != self._target))
        return DriverStatus(connected=self._connected, moving=moving, gripper="on" if self._gripper else "")
