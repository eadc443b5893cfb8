"""SkeletonSample: the ROS-free form of one motion_sensor/HandSkeleton message."""

from dataclasses import dataclass

import numpy as np

from motion_sensor.skeleton_joints import check_skeleton

__all__ = ["SkeletonSample"]


@dataclass
class SkeletonSample:
    """The canonical skeleton (``motion_sensor.skeleton_joints``) of one hand in one frame:
    ``joints`` (22, 3) metres, REP 103, in ``frame_id``; ``stamp`` seconds (the frame's);
    ``hand_type`` "left"/"right"/""; ``hand_id`` and ``confidence`` -1 when unknown."""

    stamp: float
    joints: np.ndarray
    hand_type: str = ""
    hand_id: int = -1
    confidence: float = -1.0
    frame_id: str = "device"
    device: str = ""

    def problem(self) -> str | None:
        """Why this skeleton must not be published, or None when it is good."""
        try:
            check_skeleton(self.joints, "skeleton")
        except ValueError as exc:
            return str(exc)
        if not np.isfinite(self.stamp):
            return f"stamp {self.stamp!r} is not finite"
        return None
