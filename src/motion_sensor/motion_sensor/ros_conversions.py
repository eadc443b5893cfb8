"""Conversions between motion_sensor/hand messages and HandSample.

This is the only module of the package that touches ROS message classes (not rospy); the
nodes use it at the edges.
"""

import numpy as np

from motion_sensor.hand_sample import HandSample
from motion_sensor.msg import hand


def sample_to_msg(sample: HandSample) -> hand:
    """motion_sensor/hand message of a HandSample (stamp is left for the caller to set)."""
    msg = hand()
    msg.header.frame_id = sample.frame_id
    msg.hands_num = sample.hands_num
    msg.hand_type = list(sample.hand_types)
    msg.position.x, msg.position.y, msg.position.z = (float(v) for v in sample.position)
    o = msg.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in sample.orientation)
    msg.hand_id = int(sample.hand_id)
    msg.confidence = float(sample.confidence)
    msg.grab_strength = float(sample.grab_strength)
    msg.pinch_strength = float(sample.pinch_strength)
    if sample.index_tip is not None:
        msg.index_tip.x, msg.index_tip.y, msg.index_tip.z = (float(v) for v in sample.index_tip)
        msg.index_tip_known = True
    return msg


def msg_to_sample(msg: hand, device: str = "") -> HandSample:
    """HandSample of a motion_sensor/hand message (stamp in seconds)."""
    p, o, tip = msg.position, msg.orientation, msg.index_tip
    return HandSample(
        stamp=msg.header.stamp.to_sec(),
        position=np.array([p.x, p.y, p.z]),
        orientation=np.array([o.x, o.y, o.z, o.w]),
        hands_num=msg.hands_num,
        hand_types=tuple(msg.hand_type),
        frame_id=msg.header.frame_id,
        device=device,
        hand_id=msg.hand_id,
        confidence=msg.confidence,
        grab_strength=msg.grab_strength,
        pinch_strength=msg.pinch_strength,
        index_tip=np.array([tip.x, tip.y, tip.z]) if msg.index_tip_known else None,
    )
