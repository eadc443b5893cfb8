"""A stream's value at an instant between two stamped samples (plain numpy): what a frame of
a recorded episode holds for the measured joints, the tool, and the core's command and
target. The producers blend their own samples at each frame instant
(``motion_common.frame_tap``); the recorder and the replay use the same functions.

Linear between the two samples stamped around the instant, quaternions normalised after
the blend; a joint rate from two samples when the stream carries positions only.
"""

import numpy as np

__all__ = ["blend", "rate_between", "sample_at"]

_QUATERNION = slice(3, 7)  # x y z qx qy qz qw


def blend(before: np.ndarray, after: np.ndarray, u: float, quaternion: slice | None = None) -> np.ndarray:
    """``before`` + u (``after`` - ``before``); the ``quaternion`` part normalised, with
    ``after`` flipped to ``before``'s hemisphere first."""
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    if quaternion is not None and float(np.dot(before[quaternion], after[quaternion])) < 0:
        after = after.copy()
        after[quaternion] = -after[quaternion]
    out = before + (after - before) * u
    if quaternion is not None:
        norm = np.linalg.norm(out[quaternion])
        if norm > 0:
            out[quaternion] = out[quaternion] / norm
    return out


def rate_between(before: np.ndarray, after: np.ndarray, stamp_before: float, stamp_after: float) -> np.ndarray:
    """(``after`` - ``before``) per second between two stamped samples: the velocity a
    stream without one (a driver's joint_states carry positions only) had between them;
    zeros when both are the same sample (an end of the history)."""
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    dt = float(stamp_after) - float(stamp_before)
    return (after - before) / dt if dt > 0 else np.zeros_like(after)


def sample_at(stamp_before: float, before, stamp_after: float, after, instant: float):
    """(joints, joint rate, pose) at ``instant`` from two samples ``(joints, pose)`` (pose
    x y z qx qy qz qw) stamped around it; the rate is the one between the two samples (the
    measured joints' velocity, the commands' own rate). Samples of a different joint count:
    the later one as it is."""
    joints_before, pose_before = before
    joints_after, pose_after = after
    span = float(stamp_after) - float(stamp_before)
    u = min(max((instant - stamp_before) / span, 0.0), 1.0) if span > 0 else 1.0
    if len(joints_before) != len(joints_after):
        joints_before, pose_before, u, span = joints_after, pose_after, 1.0, 0.0
    joints = blend(joints_before, joints_after, u)
    pose = blend(pose_before, pose_after, u, quaternion=_QUATERNION)
    return joints, rate_between(joints_before, joints_after, 0.0, span), pose
