"""The arm as the page draws it: joint frames from the project's kinematics
(``motion_common.kinematics.RobotKinematics``, pinocchio on the robot's URDF), the links as
straight segments between consecutive joint origins, and each joint's reading against its
URDF limits. Plain Python (numpy); the page turns segments into ``ui.scene`` cylinders.
"""

import threading
from dataclasses import dataclass

import numpy as np

from motion_common.kinematics import RobotKinematics

__all__ = ["LinkSegment", "JointReading", "RobotView", "segment_pose", "joint_readings"]

# Segments shorter than this (coincident joint origins, e.g. a UR's shoulder pan and lift)
# are drawn as a sphere only: a zero-length cylinder has no direction.
MIN_LINK_M = 1e-4
# A joint within this fraction of its range from a limit is shown as near it.
NEAR_LIMIT_FRACTION = 0.05


@dataclass(frozen=True)
class LinkSegment:
    """One link drawn as a cylinder along the segment start -> end (m, base frame):
    ``center``, ``rotation`` (3x3, rows, mapping the cylinder's own y axis onto the
    segment) and ``length``."""

    start: tuple
    end: tuple
    center: tuple
    rotation: list
    length: float


def segment_pose(start, end) -> LinkSegment:
    """The pose of a cylinder (three.js: axis along its local y) spanning start -> end."""
    a = np.asarray(start, dtype=float)
    b = np.asarray(end, dtype=float)
    axis = b - a
    length = float(np.linalg.norm(axis))
    center = tuple(float(v) for v in (a + b) / 2.0)
    if length < MIN_LINK_M:
        return LinkSegment(tuple(a.tolist()), tuple(b.tolist()), center, np.eye(3).tolist(), 0.0)
    y = axis / length
    # Any x perpendicular to y; the cylinder is round, so its turn about y does not show.
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    rotation = np.column_stack([x, y, z])
    return LinkSegment(tuple(a.tolist()), tuple(b.tolist()), center, rotation.tolist(), length)


@dataclass(frozen=True)
class JointReading:
    """One joint as the page lists it: angle in degrees, its URDF limits, and where it
    lies between them (0 at the lower limit, 1 at the upper)."""

    name: str
    degrees: float
    lower_deg: float
    upper_deg: float
    fraction: float
    near_limit: bool


def joint_readings(names, positions_rad, lower_rad, upper_rad) -> list[JointReading]:
    """Readings of joints in one order (names, positions, limits all alike)."""
    out = []
    for name, q, low, high in zip(names, positions_rad, lower_rad, upper_rad, strict=True):
        span = float(high - low)
        fraction = float(np.clip((q - low) / span, 0.0, 1.0)) if span > 0 else 0.5
        near = min(fraction, 1.0 - fraction) < NEAR_LIMIT_FRACTION
        out.append(
            JointReading(
                name,
                float(np.degrees(q)),
                float(np.degrees(low)),
                float(np.degrees(high)),
                fraction,
                bool(near),
            )
        )
    return out


class RobotView:
    """The robot model behind the 3-D view and the joint bars.

    ``RobotKinematics`` keeps one pinocchio Data buffer; a lock makes the page's timers of
    several browser tabs take turns.
    """

    def __init__(self, urdf_path: str, tool_frame: str = "tool0"):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        self.joint_names = list(self.kinematics.joint_names)
        self.lower = np.array(self.kinematics.lower, dtype=float)
        self.upper = np.array(self.kinematics.upper, dtype=float)
        self._lock = threading.Lock()

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    def model_order(self, names, positions) -> np.ndarray | None:
        """``positions`` (a joint_states message's, in its own ``names`` order) in the
        model's joint order; None when a model joint is missing. Without names, the
        message's order is taken as the model's if the counts agree."""
        positions = [float(p) for p in positions]
        if not names:
            return np.array(positions) if len(positions) == self.dof else None
        by_name = dict(zip(names, positions, strict=False))
        try:
            return np.array([by_name[name] for name in self.joint_names])
        except KeyError:
            return None

    def frame_points(self, joints) -> list[tuple[float, float, float]]:
        """Base origin, each joint's origin and the tool frame (m, base frame) at ``joints``:
        the kinematics' forward pass fills every joint placement along the way."""
        q = np.asarray(joints, dtype=float)
        with self._lock:
            tool = self.kinematics.forward(q)
            data = self.kinematics.data
            points = [tuple(float(v) for v in data.oMi[i].translation) for i in range(1, self.kinematics.model.njoints)]
        return [(0.0, 0.0, 0.0), *points, tuple(float(v) for v in tool.translation)]

    def segments(self, joints) -> list[LinkSegment]:
        """The links at ``joints``: one segment between consecutive frame points."""
        points = self.frame_points(joints)
        return [segment_pose(a, b) for a, b in zip(points[:-1], points[1:], strict=True)]

    def readings(self, joints) -> list[JointReading]:
        """Every joint's reading at ``joints`` (model order)."""
        return joint_readings(self.joint_names, joints, self.lower, self.upper)
