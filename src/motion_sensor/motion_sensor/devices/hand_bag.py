"""A rosbag of a session's hand streams (``record_hands``) read back as HandSamples with
their whole-hand skeletons, for the replay.

The hand stream read is one ``motion_sensor/hand`` topic: the device's raw stream (the
topic ending in ``raw_hand``) when the bag has it, as the replay stands in for the device,
else the first hand topic by name (a bag holding both the raw and the filtered stream
would otherwise play every frame twice). Its skeletons are the ``motion_sensor/HandSkeleton``
messages of the topic of the same name plus ``_skeleton`` (``raw_hand_skeleton`` with
``raw_hand``), joined to the hand frame of the same header stamp, as the device published
them. A skeleton message that is malformed (not the canonical joints) or matches no hand
frame is left out and listed with the reason; the rest plays.
"""

from collections import defaultdict

from motion_sensor.errors import MotionSensorError

__all__ = ["read_bag", "hand_topic"]

HAND_TYPE = "motion_sensor/hand"
SKELETON_TYPE = "motion_sensor/HandSkeleton"


def hand_topic(topics: dict) -> str | None:
    """The hand topic to replay among {topic: message type}: the raw stream, else the
    first by name; None when there is none."""
    hands = sorted(topic for topic, kind in topics.items() if kind == HAND_TYPE)
    raw = [topic for topic in hands if topic.rstrip("/").endswith("raw_hand")]
    return (raw or hands or [None])[0]


def read_bag(path: str, frame_id: str = "leap"):
    """([(recorded stamp s, HandSample)], rejected) of a bag; MotionSensorError when it
    cannot be read or holds no hand message."""
    import rosbag

    from motion_sensor.ros_conversions import msg_to_sample, msg_to_skeleton

    rejected = []
    try:
        with rosbag.Bag(path) as bag:
            topics = {topic: info.msg_type for topic, info in bag.get_type_and_topic_info().topics.items()}
            hands_topic = hand_topic(topics)
            if hands_topic is None:
                raise MotionSensorError(f"bag {path} has no motion_sensor/hand message (topics: {sorted(topics)})")
            skeleton_topic = hands_topic + "_skeleton"
            if topics.get(skeleton_topic) != SKELETON_TYPE:
                skeleton_topic = None
            frames, skeletons = [], defaultdict(list)
            wanted = [hands_topic] + ([skeleton_topic] if skeleton_topic else [])
            for index, (topic, msg, t) in enumerate(bag.read_messages(topics=wanted)):
                stamp = msg.header.stamp.to_sec() if msg.header.stamp else t.to_sec()
                if topic == hands_topic:
                    sample = msg_to_sample(msg, device="bag")
                    sample.frame_id = msg.header.frame_id or frame_id
                    frames.append((stamp, sample))
                    continue
                try:
                    skeletons[stamp].append(msg_to_skeleton(msg, device="bag"))
                except ValueError as exc:
                    rejected.append(f"{topic} message {index} at {stamp:.3f} s: {exc}")
    except (OSError, rosbag.ROSBagException) as exc:
        raise MotionSensorError(f"cannot read bag {path}: {exc}") from None
    if not frames:
        raise MotionSensorError(f"bag {path} has no motion_sensor/hand message on {hands_topic}")
    for stamp, sample in frames:
        found = skeletons.pop(stamp, None)
        if found:
            # The steering hand's skeleton first, as the device sent them.
            found.sort(key=lambda s: s.hand_type != sample.primary_type)
            sample.skeletons = tuple(found)
    if skeletons:
        count = sum(len(found) for found in skeletons.values())
        rejected.append(f"{skeleton_topic}: {count} skeleton(s) match no {hands_topic} frame by stamp")
    return frames, rejected
