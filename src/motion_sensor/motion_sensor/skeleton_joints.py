"""The one canonical hand skeleton of the framework, and the mapping of every device's
joint set onto it.

Canonical set: the 22 joints of SHREC'17 / DHG (the gesture recognizer is trained on
them), in this order::

    0 wrist, 1 palm,
    2-5  thumb  (base, first joint, second joint, tip),
    6-9  index  (base, first, second, tip),
    10-13 middle, 14-17 ring, 18-21 pinky   (same four each).

Positions are metres in the device frame with REP 103 axes (x forward away from the
operator, y left, z up), as ``hand.msg``.

Where each device's joints go:

- **SHREC'17 / DHG** (``shrec_to_canonical``): same order. The coordinates of the shared
  training file are, as measured in it, x to the performer's right, y up and z away from
  the camera (swipes up move the palm +y, swipes right +x, fingertips sit above the
  wrist; its README's "y down" does not match the data), the frame of a Leap with the
  camera in the Leap's place. They are turned into REP 103 as Leap's are: x = -z,
  y = -x, z = y.
- **Leap Motion** (``leap_to_canonical``): per finger the joints of its bones as the
  v6 protocol gives them (``mcpPosition``, ``pipPosition``, ``dipPosition``,
  ``tipPosition``): finger base = MCP, first joint = PIP, second joint = DIP, tip = tip
  (for the thumb, whose metacarpal Leap models with zero length, the same fields give the
  thumb's base, first and second joints and tip). Palm = the palm position. The v6
  protocol has no wrist: it is placed behind the palm along the hand's direction, as far
  from the palm as the middle finger's base is in front of it (``wrist`` overrides it).
- **MediaPipe Hands** (``mediapipe_to_canonical``, 21 landmarks): 0 wrist; thumb
  1 CMC, 2 MCP, 3 IP, 4 tip; index 5 MCP, 6 PIP, 7 DIP, 8 tip; middle 9-12; ring
  13-16; pinky 17-20. Finger base = MCP, first = PIP, second = DIP, tip = tip; thumb
  base = CMC, first = MCP, second = IP. The palm, which MediaPipe does not give, is the
  mean of the wrist and the index, middle, ring and pinky MCPs.

Every consumer of skeletons (the recognizer, the spotter, the devices publishing
``HandSkeleton``) goes through this module. No ROS import.
"""

import math

import numpy as np

__all__ = [
    "JOINT_NAMES",
    "N_JOINTS",
    "FINGERS",
    "SHREC_TO_REP103",
    "shrec_to_canonical",
    "leap_to_canonical",
    "mediapipe_to_canonical",
    "check_skeleton",
    "palm_quaternion",
]

FINGERS = ("thumb", "index", "middle", "ring", "pinky")
_PARTS = ("base", "first", "second", "tip")
JOINT_NAMES = ("wrist", "palm") + tuple(f"{finger}_{part}" for finger in FINGERS for part in _PARTS)
N_JOINTS = len(JOINT_NAMES)  # 22

# Rows: REP 103 axes expressed in the SHREC file's axes (x performer's right, y up, z away
# from the camera). A proper rotation (det = +1).
SHREC_TO_REP103 = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

# MediaPipe landmark index of each canonical joint after the palm (2..21).
_MEDIAPIPE_FINGERS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20)
_MEDIAPIPE_PALM = (0, 5, 9, 13, 17)


def check_skeleton(joints, source="skeleton"):
    """``joints`` as a float (22, 3) array, or ValueError naming ``source`` and the problem."""
    array = np.asarray(joints, dtype=float)
    if array.shape != (N_JOINTS, 3):
        raise ValueError(f"{source}: expected {N_JOINTS} joints x 3 coordinates, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{source}: joint coordinates must be finite")
    return array


def shrec_to_canonical(joints):
    """SHREC'17 joints (..., 22, 3) in the file's frame -> REP 103 (same order, metres)."""
    array = np.asarray(joints, dtype=np.float64)
    if array.shape[-2:] != (N_JOINTS, 3):
        raise ValueError(f"SHREC joints: expected (..., {N_JOINTS}, 3), got shape {array.shape}")
    return array @ SHREC_TO_REP103.T


def leap_to_canonical(palm, direction, fingers, wrist=None):
    """Leap joints -> canonical (22, 3), all in REP 103 metres.

    ``palm``: (3,); ``direction``: (3,) palm towards the fingers; ``fingers``: (5, 4, 3),
    thumb to pinky, each MCP, PIP, DIP, tip; ``wrist``: (3,) or None (estimated).
    """
    joints = np.asarray(fingers, dtype=float)
    if joints.shape != (5, 4, 3):
        raise ValueError(f"Leap fingers: expected 5 fingers x (mcp, pip, dip, tip) x 3, got {joints.shape}")
    palm = np.asarray(palm, dtype=float)
    out = np.empty((N_JOINTS, 3))
    if wrist is None:
        heading = np.asarray(direction, dtype=float)
        reach = math.dist(joints[2, 0], palm) / max(math.hypot(*heading), 1e-9)
        wrist = palm - heading * reach
    out[0] = wrist
    out[1] = palm
    out[2:] = joints.reshape(20, 3)
    if not np.isfinite(out).all():
        raise ValueError("Leap skeleton: joint coordinates must be finite")
    return out


def mediapipe_to_canonical(landmarks):
    """MediaPipe's 21 hand landmarks (21, 3), already metric REP 103 -> canonical (22, 3)."""
    points = np.asarray(landmarks, dtype=float)
    if points.shape != (21, 3):
        raise ValueError(f"MediaPipe landmarks: expected (21, 3), got {points.shape}")
    out = np.empty((N_JOINTS, 3))
    out[0] = points[0]
    out[1] = points[list(_MEDIAPIPE_PALM)].mean(axis=0)
    out[2:] = points[list(_MEDIAPIPE_FINGERS)]
    return check_skeleton(out, "MediaPipe skeleton")


def palm_quaternion(joints):
    """Palm orientation (x, y, z, w) of a canonical skeleton in its frame, as ``hand.msg``
    defines it: x along the fingers (wrist to middle base), z out of the back of the hand,
    y completing the frame. A right hand's thumb is on +y, a left hand's on -y; the back
    of the hand is taken as the side that makes the frame right-handed with the thumb on
    +y, so a left hand's z points out of its palm (it cannot be told without the side)."""
    from scipy.spatial.transform import Rotation

    points = check_skeleton(joints)
    x = points[JOINT_NAMES.index("middle_base")] - points[0]
    across = points[JOINT_NAMES.index("index_base")] - points[JOINT_NAMES.index("pinky_base")]
    x = x / max(float(np.linalg.norm(x)), 1e-9)
    y = across - x * float(np.dot(across, x))
    norm = float(np.linalg.norm(y))
    if norm < 1e-9:
        return np.array([0.0, 0.0, 0.0, 1.0])
    y = y / norm
    return Rotation.from_matrix(np.column_stack([x, y, np.cross(x, y)])).as_quat()
