"""TeleopCore: from a filtered hand pose to a safe joint command (no ROS here).

The node feeds it hand poses and the robot's measured joints; it answers with the joint
target to stream, or with the status that explains why nothing is sent.
"""
import enum
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .kinematics import RobotKinematics, pose_to_se3
from .safety import JointStepLimiter
from .teleop import AutoClutch, TeleopMapper


class TeleopStatus(enum.IntEnum):
    """Status codes published on /motion_commander/status (data field)."""

    WAITING_FOR_ROBOT = 0   # no /joint_states yet
    DISENGAGED = 1          # clutch open: the robot holds still
    ENGAGED = 2             # commands are streaming
    JOINT_SPEED_LIMITED = 3  # engaged, this command was slowed to the joint speed limit
    IK_FAILED = 4           # the target is unreachable: the robot holds its last command
    BAD_INPUT = 5           # the hand pose was not finite / not a unit quaternion


@dataclass
class TeleopCommand:
    """A joint target for the driver, with the sensor stamp it came from."""

    stamp: float
    joints: np.ndarray
    target_position: np.ndarray
    target_orientation: np.ndarray


class TeleopCore:
    """Clutch, mapping, IK and joint-step limiting for one robot."""

    def __init__(self, kinematics: RobotKinematics, mapper: TeleopMapper, clutch: AutoClutch,
                 limiter: JointStepLimiter):
        self.kinematics = kinematics
        self.mapper = mapper
        self.clutch = clutch
        self.limiter = limiter
        self.status = TeleopStatus.WAITING_FOR_ROBOT
        self.measured_joints: Optional[np.ndarray] = None
        self._command: Optional[np.ndarray] = None
        self._command_stamp: Optional[float] = None

    def on_joint_state(self, joints) -> None:
        """Record the robot's measured joints (used as the reference at engage)."""
        self.measured_joints = np.asarray(joints, dtype=float)
        if self.status == TeleopStatus.WAITING_FOR_ROBOT:
            self.status = TeleopStatus.DISENGAGED

    def on_hand_lost(self, now: float) -> bool:
        """Disengage when the clutch reports the hand lost; return True if it did."""
        if self.mapper.engaged and self.clutch.hand_lost(now):
            self.disengage()
            return True
        return False

    def disengage(self) -> None:
        """Open the clutch: no more commands until the next engage; the robot holds."""
        self.mapper.disengage()
        self._command = None
        if self.status != TeleopStatus.WAITING_FOR_ROBOT:
            self.status = TeleopStatus.DISENGAGED

    def on_hand_pose(self, stamp: float, position, orientation) -> Optional[TeleopCommand]:
        """Process one filtered hand pose; return the command to send, if any."""
        position = np.asarray(position, dtype=float)
        orientation = np.asarray(orientation, dtype=float)
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(orientation))
                and abs(np.linalg.norm(orientation) - 1.0) < 1e-3):
            self.status = TeleopStatus.BAD_INPUT
            return None
        if self.measured_joints is None:
            return None
        engaged_now = self.clutch.on_frame(stamp)
        if not engaged_now:
            return None
        if not self.mapper.engaged:
            # Engage on the measured robot pose so the first target is where the robot is.
            tool_position, tool_orientation = self.kinematics.forward_pose(self.measured_joints)
            self.mapper.engage(position, orientation, tool_position, tool_orientation)
            self._command = self.measured_joints.copy()
            self._command_stamp = stamp
        target_position, target_orientation = self.mapper.target(position, orientation)
        result = self.kinematics.solve_ik(pose_to_se3(target_position, target_orientation), self._command)
        if not result.success:
            self.status = TeleopStatus.IK_FAILED
            return None
        joints, limited = self.limiter.limit(self._command, result.joints, stamp - self._command_stamp)
        self._command = joints
        self._command_stamp = stamp
        self.status = TeleopStatus.JOINT_SPEED_LIMITED if limited else TeleopStatus.ENGAGED
        return TeleopCommand(stamp, joints, target_position, target_orientation)
