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

- **SHREC'17 / DHG** (``shrec_to_canonical``): same order; the camera frame (x right,
  y down, z away from the camera, the camera facing the operator) is turned into REP 103:
  x = -z, y = x, z = -y.
- **Leap Motion** (``leap_to_canonical``): per finger four bones (metacarpal, proximal,
  intermediate, distal), each with a previous (proximal) and next (distal) joint. Finger
  base = metacarpal's next joint (the knuckle), first joint = proximal's next, second
  joint = intermediate's next, tip = distal's next. The thumb's metacarpal has zero
  length in Leap's model, so the thumb base is the proximal bone's previous joint
  (= the metacarpal's next joint, the same point). Wrist = the arm's wrist (or, without
  it, the mean of the metacarpals' previous joints); palm = the palm position.
- **MediaPipe Hands** (``mediapipe_to_canonical``, 21 landmarks): 0 wrist; thumb
  1 CMC, 2 MCP, 3 IP, 4 tip; index 5 MCP, 6 PIP, 7 DIP, 8 tip; middle 9-12; ring
  13-16; pinky 17-20. Finger base = MCP, first = PIP, second = DIP, tip = tip; thumb
  base = CMC, first = MCP, second = IP. The palm, which MediaPipe does not give, is the
  mean of the wrist and the index, middle, ring and pinky MCPs.

Every consumer of skeletons (the recognizer, the spotter, the devices publishing
``HandSkeleton``) goes through this module. No ROS import.
"""

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
]

FINGERS = ("thumb", "index", "middle", "ring", "pinky")
_PARTS = ("base", "first", "second", "tip")
JOINT_NAMES = ("wrist", "palm") + tuple(f"{finger}_{part}" for finger in FINGERS for part in _PARTS)
N_JOINTS = len(JOINT_NAMES)  # 22

# Rows: REP 103 axes expressed in the SHREC camera axes (x right, y down, z away).
SHREC_TO_REP103 = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])

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
    """SHREC'17 joints (..., 22, 3) in the camera frame -> REP 103 (same order, metres)."""
    array = np.asarray(joints, dtype=np.float64)
    if array.shape[-2:] != (N_JOINTS, 3):
        raise ValueError(f"SHREC joints: expected (..., {N_JOINTS}, 3), got shape {array.shape}")
    return array @ SHREC_TO_REP103.T


def leap_to_canonical(palm, fingers, wrist=None):
    """Leap joints -> canonical (22, 3).

    ``palm``: (3,); ``fingers``: five fingers thumb to pinky, each four bones (metacarpal,
    proximal, intermediate, distal), each a ``(prev_joint, next_joint)`` pair of 3-vectors,
    already in REP 103 metres; ``wrist``: (3,) or None.
    """
    bones = np.asarray(fingers, dtype=float)
    if bones.shape != (5, 4, 2, 3):
        raise ValueError(f"Leap fingers: expected 5 fingers x 4 bones x (prev, next) x 3, got {bones.shape}")
    out = np.empty((N_JOINTS, 3))
    out[0] = np.mean(bones[1:, 0, 0], axis=0) if wrist is None else np.asarray(wrist, dtype=float)
    out[1] = np.asarray(palm, dtype=float)
    for f in range(5):
        base = bones[f, 1, 0] if f == 0 else bones[f, 0, 1]
        out[2 + 4 * f] = base
        out[3 + 4 * f : 6 + 4 * f] = bones[f, 1:, 1]
    return check_skeleton(out, "Leap skeleton")


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
