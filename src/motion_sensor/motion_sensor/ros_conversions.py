"""Conversions between motion_sensor/hand messages and HandSample.

This is the only module of the package that touches ROS message classes (not rospy); the
nodes use it at the edges.
"""

import numpy as np
from geometry_msgs.msg import Point

from motion_sensor.hand_sample import HandSample
from motion_sensor.msg import HandSkeleton, hand
from motion_sensor.skeleton_joints import JOINT_NAMES, check_skeleton
from motion_sensor.skeleton_sample import SkeletonSample


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


def skeleton_to_msg(skeleton: SkeletonSample, header=None) -> HandSkeleton:
    """motion_sensor/HandSkeleton of a SkeletonSample; ``header`` (the palm frame's) gives
    the stamp and frame, else the stamp is left for the caller and frame_id is the sample's."""
    msg = HandSkeleton()
    if header is not None:
        msg.header.stamp, msg.header.frame_id = header.stamp, header.frame_id
    else:
        msg.header.frame_id = skeleton.frame_id
    msg.hand_type = skeleton.hand_type
    msg.hand_id = int(skeleton.hand_id)
    msg.confidence = float(skeleton.confidence)
    msg.joint_names = list(JOINT_NAMES)
    msg.joints = [Point(float(x), float(y), float(z)) for x, y, z in np.asarray(skeleton.joints, dtype=float)]
    return msg


def msg_to_skeleton(msg: HandSkeleton, device: str = "") -> SkeletonSample:
    """SkeletonSample of a HandSkeleton message; ValueError naming the problem when its
    joints are not the canonical set (names, count, finite values)."""
    if tuple(msg.joint_names) != JOINT_NAMES:
        raise ValueError(
            f"joint_names must be the canonical {len(JOINT_NAMES)} names, got {list(msg.joint_names)[:3]}..."
        )
    joints = check_skeleton([(p.x, p.y, p.z) for p in msg.joints], "HandSkeleton joints")
    return SkeletonSample(
        msg.header.stamp.to_sec(),
        joints,
        msg.hand_type,
        msg.hand_id,
        msg.confidence,
        msg.header.frame_id,
        device,
    )
