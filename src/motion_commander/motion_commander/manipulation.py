"""The paper's manipulation control API, plus pick-and-place and the motion vocabulary of
"Towards Robot Software Abstraction" (MoveJ, MoveR, MoveL, MoveROT, MoveRP).

``ManipulationAPI`` drives any controller object with the methods of
hw_interface's MotionControllerClient (get_joints, get_pose, move_j, move_l, set_gripper),
each raising an exception with a ``result`` code on refusal. It holds no ROS code, so
scripts and tests can give it a client, a driver adapter or a fake.
"""

from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import MotionCommanderError


class ManipulationAPI:
    """High-level robot commands; every motion blocks until done.

    ``approach_height`` (m) is how far above a pick/place pose the tool approaches and
    retreats, along the base z axis.
    """

    def __init__(self, controller, approach_height: float = 0.10):
        if not approach_height > 0:
            raise MotionCommanderError("approach_height must be > 0 m")
        self.controller = controller
        self.approach_height = float(approach_height)
        self.last_error = ""
        self.last_result = 0

    # -- the paper's three calls -------------------------------------------------------------
    def motion_setPose(self, pose) -> bool:  # noqa: N802 - the paper's name
        """Move the tool to ``pose`` = (position [m], quaternion x, y, z, w) in a straight
        line; return True on success, False (reason in ``last_error``) on refusal."""
        position, orientation = pose
        try:
            self.controller.move_l(list(position), list(orientation))
        except Exception as exc:  # a refusal is an answer here, not a crash
            if not hasattr(exc, "result"):
                raise
            self.last_error = str(exc)
            self.last_result = int(exc.result)
            return False
        self.last_error = ""
        self.last_result = 0
        return True

    def info_getPose(self):  # noqa: N802 - the paper's name
        """Tool (position, quaternion x, y, z, w) in the base frame."""
        position, orientation = self.controller.get_pose()
        return np.array(position), np.array(orientation)

    def info_get_joints(self) -> list:  # noqa: N802 - the paper's name
        """Joint positions (rad), in the robot's joint order."""
        return list(self.controller.get_joints())

    # -- motion vocabulary -------------------------------------------------------------------
    def move_j(self, joints: Sequence[float]) -> None:
        """MoveJ: joint-interpolated move to absolute joint values (rad)."""
        self.controller.move_j(list(joints))

    def move_r(self, joint_index: int, delta: float) -> None:
        """MoveR: turn one joint by ``delta`` rad, the others stay."""
        joints = self.info_get_joints()
        if not 0 <= joint_index < len(joints):
            raise MotionCommanderError(f"joint index {joint_index} out of range 0..{len(joints) - 1}")
        joints[joint_index] += float(delta)
        self.move_j(joints)

    def move_l(self, vector: Sequence[float]) -> None:
        """MoveL: move the tool by a relative Cartesian vector (m, base frame)."""
        position, orientation = self.info_getPose()
        self.controller.move_l(list(position + np.asarray(vector, dtype=float)), list(orientation))

    def move_rot(self, rpy: Sequence[float]) -> None:
        """MoveROT: rotate the tool about its own axes by roll, pitch, yaw (rad), in place."""
        position, orientation = self.info_getPose()
        rotated = Rotation.from_quat(orientation) * Rotation.from_euler("xyz", rpy)
        self.controller.move_l(list(position), list(rotated.as_quat()))

    def move_rp(self, rpy: Sequence[float], pivot: Sequence[float]) -> None:
        """MoveRP: rotate the tool by roll, pitch, yaw (rad, base axes) about a pivot point
        (m, base frame), e.g. to tilt a held part about its tip."""
        position, orientation = self.info_getPose()
        turn = Rotation.from_euler("xyz", rpy)
        pivot = np.asarray(pivot, dtype=float)
        new_position = pivot + turn.apply(position - pivot)
        self.controller.move_l(list(new_position), list((turn * Rotation.from_quat(orientation)).as_quat()))

    # -- pick and place ----------------------------------------------------------------------
    def _above(self, position):
        return np.asarray(position, dtype=float) + [0.0, 0.0, self.approach_height]

    def pick(self, position, orientation: Sequence[float] | None = None) -> None:
        """Approach above, descend, grip, retreat. Orientation defaults to the current one."""
        self._visit(position, orientation, grip=True)

    def place(self, position, orientation: Sequence[float] | None = None) -> None:
        """Approach above, descend, release, retreat."""
        self._visit(position, orientation, grip=False)

    def _visit(self, position, orientation, grip: bool) -> None:
        orientation = list(self.info_getPose()[1] if orientation is None else orientation)
        self.controller.move_l(list(self._above(position)), orientation)
        self.controller.move_l(list(position), orientation)
        self.controller.set_gripper(grip)
        self.controller.move_l(list(self._above(position)), orientation)

    def pick_and_place(self, pick_position, place_position, orientation=None) -> None:
        """Pick at one position and place at another, releasing the gripper if anything fails."""
        try:
            self.pick(pick_position, orientation)
            self.place(place_position, orientation)
        except Exception:
            # Never leave a part hanging after a refused motion.
            self.controller.set_gripper(False)
            raise
