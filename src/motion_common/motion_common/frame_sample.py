"""The message a dataset recorder's tap sends for one frame instant (``FrameSample``):
made by the stream's own node from its two samples stamped around the instant
(``motion_common.frame_blend.sample_at``), so one message a frame goes out where two on
each of two streams did. The server's samples are its measured joints and tool; the core's
its command and tool target. The message class (``motion_commander/FrameSample``) is given
by the node; no rospy: its stamp is genpy's.
"""

import genpy

from .frame_blend import sample_at

__all__ = ["FrameSampler"]


class FrameSampler:
    """``FrameTap``'s ``at_instant`` for samples ``(joints, pose x y z qx qy qz qw)`` of the
    joints ``names``, as ``message`` (FrameSample's class), with the joints' rate between
    the samples (the measured joints' velocity, the commands' own rate)."""

    def __init__(self, message, names):
        self.message = message
        self.names = list(names)

    def __call__(self, stamp_before: float, before, stamp_after: float, after, instant: float):
        joints, velocity, pose = sample_at(stamp_before, before, stamp_after, after, instant)
        msg = self.message(name=self.names, position=joints.tolist(), velocity=velocity.tolist())
        msg.header.stamp = genpy.Time.from_sec(instant)
        p, o = msg.pose.position, msg.pose.orientation
        p.x, p.y, p.z, o.x, o.y, o.z, o.w = pose.tolist()
        return msg
