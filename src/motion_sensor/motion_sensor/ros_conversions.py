"""Conversions between motion_sensor/hand messages and HandSample.

This is the only module of the package that touches ROS message classes (not rospy); the
nodes use it at the edges.
"""
import numpy as np

from motion_sensor.msg import hand

from .hand_sample import HandSample


def sample_to_msg(sample: HandSample) -> hand:
    """motion_sensor/hand message of a HandSample (stamp is left for the caller to set)."""
    msg = hand()
    msg.header.frame_id = sample.frame_id
    msg.hands_num = sample.hands_num
    msg.hand_type = list(sample.hand_types)
    msg.position.x, msg.position.y, msg.position.z = (float(v) for v in sample.position)
    o = msg.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in sample.orientation)
    return msg


def msg_to_sample(msg: hand, device: str = "") -> HandSample:
    """HandSample of a motion_sensor/hand message (stamp in seconds)."""
    p, o = msg.position, msg.orientation
    return HandSample(stamp=msg.header.stamp.to_sec(), position=np.array([p.x, p.y, p.z]),
                      orientation=np.array([o.x, o.y, o.z, o.w]), hands_num=msg.hands_num,
                      hand_types=tuple(msg.hand_type), frame_id=msg.header.frame_id, device=device)
