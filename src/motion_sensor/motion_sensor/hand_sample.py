"""HandSample: the ROS-free form of one motion_sensor/hand message."""

from dataclasses import dataclass, field

import numpy as np

#: The value of confidence / grab_strength / pinch_strength a device cannot measure.
UNKNOWN = -1.0


@dataclass
class HandSample:
    """One tracking frame of the primary hand, in metres and REP 103 axes.

    ``stamp`` is in seconds (the ROS header stamp), ``orientation`` is a unit quaternion
    (x, y, z, w). ``hand_id`` identifies the tracked hand across frames when the device
    provides it (-1 otherwise); ``device`` names the device that produced the frame.
    ``confidence``, ``grab_strength`` and ``pinch_strength`` are 0-1, or UNKNOWN (-1) when
    the device cannot tell; ``index_tip`` is the index finger tip (m) or None.
    ``skeletons``: a ``SkeletonSample`` per hand whose whole skeleton the device saw
    (published on ``motion_sensor/raw_hand_skeleton``; empty when it sees no fingers).
    """

    stamp: float
    position: np.ndarray
    orientation: np.ndarray
    hands_num: int = 1
    hand_types: tuple[str, ...] = ("right",)
    frame_id: str = "leap"
    hand_id: int = -1
    device: str = ""
    extra: dict = field(default_factory=dict)
    confidence: float = -1.0
    grab_strength: float = -1.0
    pinch_strength: float = -1.0
    index_tip: np.ndarray | None = None
    skeletons: tuple = ()

    @property
    def primary_type(self) -> str:
        """Type ("left"/"right") of the primary hand, or "" when no hand is seen."""
        return self.hand_types[0] if self.hand_types else ""
