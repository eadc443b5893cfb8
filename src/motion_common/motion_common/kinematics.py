"""Robot kinematics from a URDF with pinocchio: forward kinematics, Jacobians and
damped-least-squares inverse kinematics warm-started from the current joints."""

import math
import os
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import lapack

from .errors import RobotModelError
from .rotations import matrix_to_quaternion


def solve_positive_definite(matrix: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``matrix``^-1 ``vector`` for a symmetric positive definite matrix, by Cholesky.

    LAPACK's dposv through scipy's thin wrapper: on the per-frame path, after the idle
    between frames, np.linalg.solve's Python-level checks cost more than the 6x6 solve
    (~180 against ~90 us with cold caches). LU (np.linalg.solve) is the fallback
    when the matrix is not positive definite to working precision.
    """
    _, solution, info = lapack.dposv(matrix, vector)
    return solution if info == 0 else np.linalg.solve(matrix, vector)


def singular_values(matrix: np.ndarray) -> np.ndarray:
    """Singular values of ``matrix``, largest first (LAPACK dgesdd through scipy's thin
    wrapper, for the same reason as solve_positive_definite; np.linalg.svd as fallback)."""
    values, info = lapack.dgesdd(matrix, compute_uv=0)[1::2]
    return values if info == 0 else np.linalg.svd(matrix, compute_uv=False)


def pose_to_se3(position, orientation) -> pin.SE3:
    """SE3 from a position (m) and a quaternion (x, y, z, w)."""
    quat = np.asarray(orientation, dtype=float)
    return pin.XYZQUATToSE3(np.concatenate([np.asarray(position, dtype=float), quat / np.linalg.norm(quat)]))


def se3_to_pose(transform: pin.SE3):
    """(position, quaternion x, y, z, w) of an SE3."""
    xyzquat = pin.SE3ToXYZQUAT(transform)
    return np.array(xyzquat[:3]), np.array(xyzquat[3:])


def quat_to_matrix(quaternion) -> np.ndarray:
    """3x3 rotation matrix of a quaternion (x, y, z, w); normalised first."""
    # Plain floats into pinocchio's scalar constructor (w, x, y, z): the teleop mapper calls
    # this on every frame, where numpy's norm and an array conversion cost more than the
    # arithmetic when the caches are cold between frames.
    x, y, z, w = quaternion.tolist() if isinstance(quaternion, np.ndarray) else quaternion
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not norm > 0.0:
        raise ValueError(f"quaternion {list(quaternion)} has no direction (norm {norm}); pass x, y, z, w of a rotation")
    return pin.Quaternion(w / norm, x / norm, y / norm, z / norm).matrix()


def matrix_to_quat(matrix) -> np.ndarray:
    """Quaternion (x, y, z, w) of a 3x3 rotation matrix (``rotations.matrix_to_quaternion``:
    pinocchio's matrix constructor of a quaternion leaks memory on every call)."""
    return matrix_to_quaternion(matrix)


def slerp(q0, q1, fraction: float) -> np.ndarray:
    """Spherical interpolation between quaternions (x, y, z, w), shortest way."""
    a = pin.Quaternion(np.asarray(q0, dtype=float))
    b = pin.Quaternion(np.asarray(q1, dtype=float))
    return np.array(a.slerp(float(fraction), b).coeffs())


@dataclass
class LinePath:
    """Joint waypoints along a straight tool line (MoveL): ``joints`` (n x dof, the start
    first), the line's ``distance`` (m) and turn ``angle`` (rad). When IK fails part-way,
    ``failed_at`` is the path fraction and ``ik_error`` the residual (m)."""

    joints: np.ndarray
    distance: float
    angle: float
    failed_at: float | None = None
    ik_error: float = 0.0

    @property
    def reachable(self) -> bool:
        """True when every point of the line was solved."""
        return self.failed_at is None


@dataclass
class PreparedSeed:
    """What an IK solve computes first at its seed, computed ahead of time
    (RobotKinematics.prepare_seed): the seed clipped to the joint limits, the tool pose there
    and the tool Jacobian in the LOCAL frame. A teleop frame's IK starts from a seed known
    before the frame arrives, so this work can leave the frame's latency."""

    joints: np.ndarray
    tool_pose: pin.SE3
    local_jacobian: np.ndarray


@dataclass
class IkResult:
    """Outcome of an IK solve: joints, whether the tolerance was met, residual error."""

    joints: np.ndarray
    success: bool
    position_error: float
    rotation_error: float
    iterations: int


class RobotKinematics:
    """Kinematics of one serial arm loaded from a URDF file.

    Not thread-safe: it keeps one pinocchio Data buffer; give each thread its own instance.
    """

    def __init__(self, urdf_path: str, tool_frame: str = "tool0"):
        if not os.path.isfile(urdf_path):
            raise RobotModelError(f"URDF file {urdf_path!r} does not exist; pass the path of the robot's URDF")
        try:
            self.model = pin.buildModelFromUrdf(urdf_path)
        except (RuntimeError, ValueError) as exc:
            raise RobotModelError(f"pinocchio cannot load URDF {urdf_path!r}: {exc}") from None
        if not self.model.existFrame(tool_frame):
            frames = [f.name for f in self.model.frames]
            raise RobotModelError(f"URDF {urdf_path!r} has no frame {tool_frame!r}; its frames are {frames}")
        if self.model.nq != self.model.nv:
            raise RobotModelError("only arms of revolute/prismatic joints are supported (nq != nv)")
        self.urdf_path = urdf_path
        self.data = self.model.createData()
        self.tool_frame = tool_frame
        self.tool_id = self.model.getFrameId(tool_frame)
        self.joint_names = [name for name in list(self.model.names)[1:]]
        self.lower = np.array(self.model.lowerPositionLimit)
        self.upper = np.array(self.model.upperPositionLimit)
        self.velocity_limits = np.array(self.model.velocityLimit)
        self._damping_eyes = {}  # damping -> damping * I6, built once per value (solve_ik runs per frame)

    @property
    def dof(self) -> int:
        """Number of joints."""
        return self.model.nq

    def forward(self, joints) -> pin.SE3:
        """Tool pose in the base frame at ``joints``."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(joints, dtype=float))
        return self.data.oMf[self.tool_id].copy()

    def forward_pose(self, joints):
        """Tool (position, quaternion x, y, z, w) in the base frame at ``joints``."""
        return se3_to_pose(self.forward(joints))

    def jacobian(self, joints) -> np.ndarray:
        """6 x dof tool Jacobian in the LOCAL_WORLD_ALIGNED frame (linear rows first)."""
        q = np.asarray(joints, dtype=float)
        return pin.computeFrameJacobian(self.model, self.data, q, self.tool_id, pin.LOCAL_WORLD_ALIGNED)

    def local_jacobian(self, joints) -> np.ndarray:
        """6 x dof tool Jacobian in the tool's LOCAL frame (linear rows first): the same
        singular values as jacobian(), the frame the IK works in."""
        q = np.asarray(joints, dtype=float)
        return pin.computeFrameJacobian(self.model, self.data, q, self.tool_id, pin.LOCAL)

    def within_limits(self, joints, margin: float = 0.0) -> bool:
        """True when every joint lies inside its limits shrunk by ``margin``."""
        q = np.asarray(joints, dtype=float)
        return bool(np.all(q >= self.lower + margin) and np.all(q <= self.upper - margin))

    def _clipped_to_limits(self, joints) -> np.ndarray:
        """``joints`` as an array clipped to the joint limits (an IK's start)."""
        return np.minimum(np.maximum(np.asarray(joints, dtype=float), self.lower), self.upper)

    def prepare_seed(self, seed) -> PreparedSeed:
        """The first step of solve_ik() at ``seed`` (clip, tool pose, LOCAL Jacobian), to be
        passed to solve_ik(..., prepared=) later: the solve then gives exactly the result it
        would give from ``seed``, with that work done beforehand."""
        q = self._clipped_to_limits(seed)
        return PreparedSeed(q, self.forward(q), self.local_jacobian(q))

    def solve_ik(
        self,
        target: pin.SE3,
        seed,
        max_iterations: int = 50,
        position_tolerance: float = 1e-4,
        rotation_tolerance: float = 1e-3,
        damping: float = 1e-4,
        prepared: PreparedSeed | None = None,
    ) -> IkResult:
        """Damped-least-squares IK toward ``target`` starting at ``seed`` (warm start).

        Each step is clipped to the joint limits, so the result is always inside them; when
        the target is unreachable the closest solution found is returned with success False.
        ``prepared`` (prepare_seed() of this same seed) skips the work done there.
        """
        # This runs once or twice per teleop frame, on the latency-critical path: plain
        # dot products and preallocated arrays, since numpy's per-call overhead (norm, clip,
        # eye) costs more than the 6x6 arithmetic itself.
        model, data, tool_id, lower, upper = self.model, self.data, self.tool_id, self.lower, self.upper
        if prepared is not None:
            q, tool_pose, prepared_jacobian = prepared.joints, prepared.tool_pose, prepared.local_jacobian
        else:
            q = self._clipped_to_limits(seed)
        damping_eye = self._damping_eyes.get(damping)
        if damping_eye is None:
            damping_eye = self._damping_eyes[damping] = damping * np.eye(6)
        position_limit, rotation_limit = position_tolerance**2, rotation_tolerance**2
        error = np.zeros(6)
        for iteration in range(max_iterations + 1):
            if prepared is None or iteration:
                pin.framesForwardKinematics(model, data, q)
                tool_pose = data.oMf[tool_id]
            current_to_target = tool_pose.actInv(target)
            error = pin.log6(current_to_target).vector
            # The check in plain floats: one conversion instead of four numpy calls.
            ex, ey, ez, ea, eb, ec = error.tolist()
            linear2, angular2 = ex * ex + ey * ey + ez * ez, ea * ea + eb * eb + ec * ec
            if linear2 < position_limit and angular2 < rotation_limit:
                return IkResult(q, True, math.sqrt(linear2), math.sqrt(angular2), iteration)
            if iteration == max_iterations:
                break
            if prepared is not None and not iteration:
                jac = prepared_jacobian
            else:
                jac = pin.computeFrameJacobian(model, data, q, tool_id, pin.LOCAL)
            jac = pin.Jlog6(current_to_target.inverse()) @ jac
            # Damping keeps the step bounded near singularities instead of exploding.
            step = jac.T @ solve_positive_definite(jac @ jac.T + damping_eye, error)
            q = np.minimum(np.maximum(pin.integrate(model, q, step), lower), upper)
        return IkResult(q, False, float(np.linalg.norm(error[:3])), float(np.linalg.norm(error[3:])), max_iterations)

    def line_path(
        self,
        start_joints,
        goal_position,
        goal_orientation,
        max_step: float = 0.005,
        max_angle_step: float = np.radians(2.0),
    ) -> LinePath:
        """Joint waypoints of a straight tool line from ``start_joints`` to the goal pose,
        orientation slerped: one IK solve (warm-started from the previous one) per
        ``max_step`` m / ``max_angle_step`` rad, so the joint-space chords stay close to the
        line. Stops at the first unreachable point (``failed_at``)."""
        start = np.asarray(start_joints, dtype=float)
        start_pos, start_quat = self.forward_pose(start)
        goal_pos = np.asarray(goal_position, dtype=float)
        goal_quat = np.asarray(goal_orientation, dtype=float)
        distance = float(np.linalg.norm(goal_pos - start_pos))
        angle = float(2.0 * np.arccos(min(1.0, abs(float(np.dot(start_quat, goal_quat / np.linalg.norm(goal_quat)))))))
        count = int(max(2, np.ceil(distance / max_step), np.ceil(angle / max_angle_step))) + 1
        waypoints, seed = [start], start
        for fraction in np.linspace(0.0, 1.0, count)[1:]:
            target = pose_to_se3(start_pos + fraction * (goal_pos - start_pos), slerp(start_quat, goal_quat, fraction))
            result = self.solve_ik(target, seed)
            if not result.success:
                return LinePath(np.array(waypoints), distance, angle, float(fraction), result.position_error)
            waypoints.append(result.joints)
            seed = result.joints
        return LinePath(np.array(waypoints), distance, angle)
