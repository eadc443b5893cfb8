"""Skeletons from every replay: a Leap recording converted to the CSV layout and back, a
rosbag written as record_hands writes a session (raw and filtered hands, their skeletons),
and malformed rows and messages left out with a reason while the rest plays. No roscore:
the bag is written and read with rosbag's Python API."""

import glob
import os

import numpy as np
import pytest

import motion_sensor
from motion_sensor.devices.device import DeviceRunner
from motion_sensor.devices.hand_bag import hand_topic
from motion_sensor.devices.hand_csv import SKELETON_COLUMNS, read_csv, write_csv
from motion_sensor.devices.replay import ReplayDevice, load_samples
from motion_sensor.errors import MotionSensorError
from motion_sensor.skeleton_joints import JOINT_NAMES

from ..conftest import DATA, ROOT
from .test_device import FakeClock

TWO_HANDS = os.path.join(ROOT, "src", "motion_sensor", "data", "two-hands-flapping.jsonl.gz")
GRAB = os.path.join(DATA, "grab.jsonl.gz")


def replay(path, **values):
    clock = FakeClock(500.0)
    config = ReplayDevice.params.validate({"recording": path, **values}, "test")
    device = ReplayDevice(config, clock=clock, sleep=clock.sleep)
    published = []
    DeviceRunner(device, published.append, lambda: False, clock=clock, sleep=clock.sleep).run()
    return device, published


def assert_same_stream(expected, got):
    assert len(got) == len(expected)
    for (_, a), (_, b) in zip(expected, got):
        assert a.hand_types == b.hand_types and a.hands_num == b.hands_num
        np.testing.assert_allclose(b.position, a.position, atol=1e-12)
        assert [s.hand_type for s in b.skeletons] == [s.hand_type for s in a.skeletons]
        for sa, sb in zip(a.skeletons, b.skeletons):
            np.testing.assert_allclose(sb.joints, sa.joints, atol=1e-12)
            assert sb.hand_id == sa.hand_id


def test_csv_layout_names_the_canonical_joints():
    assert len(SKELETON_COLUMNS) == 3 * len(JOINT_NAMES)
    assert SKELETON_COLUMNS[:4] == ("wrist_x", "wrist_y", "wrist_z", "palm_x")
    assert SKELETON_COLUMNS[-1] == "pinky_tip_z"


def test_two_hand_leap_recording_round_trips_through_csv_and_replays_both_skeletons(tmp_path):
    leap, _ = load_samples(TWO_HANDS, "left")
    assert all(len(s.skeletons) == 2 for _, s in leap)
    path = str(tmp_path / "hands.csv")
    assert write_csv(path, (s for _, s in leap)) == 2 * len(leap)
    assert_same_stream(leap, load_samples(path, "left")[0])
    # The steering hand follows primary_hand, as with the Leap recording itself.
    right = load_samples(path, "right")[0]
    assert right[0][1].hand_types[0] == "right" and right[0][1].skeletons[0].hand_type == "right"
    device, published = replay(path, rate=0.0)
    assert len(published) == len(leap) and device.counters["rejected"] == 0
    # Every skeleton goes out with the frame's publishing stamp.
    assert all(len(s.skeletons) == 2 and {k.stamp for k in s.skeletons} == {s.stamp} for s in published)


def test_malformed_csv_rows_are_rejected_with_their_reason_and_the_rest_plays(tmp_path):
    leap, _ = load_samples(GRAB)
    path = tmp_path / "hands.csv"
    write_csv(str(path), (s for _, s in leap[:6]))
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    joint = header.index("index_tip_y")
    bad = lines[2].split(",")
    bad[joint] = "oops"  # line 3: a joint that is no number
    partial = lines[3].split(",")
    partial[joint] = ""  # line 4: a partial skeleton
    posed = lines[4].split(",")
    posed[1:8] = [""] * 7  # line 5: no pose, taken from the skeleton
    lines[2:5] = [",".join(bad), ",".join(partial), ",".join(posed)]
    lines.append(lines[-1].replace(",right,", ",middle,").replace(",left,", ",middle,"))  # line 8
    path.write_text("\n".join(lines) + "\n")
    samples, rejected = read_csv(str(path))
    assert [r.split(":")[0] for r in rejected] == ["line 3", "line 4", "line 8"]
    assert "index_tip_y 'oops' is not a number" in rejected[0]
    assert "not a number" in rejected[1] and "hand_type" in rejected[2]
    assert len(samples) == 4 and all(len(s.skeletons) == 1 for s in samples)
    palm = samples[1].skeletons[0].joints[JOINT_NAMES.index("palm")]
    np.testing.assert_allclose(samples[1].position, palm)
    assert abs(np.linalg.norm(samples[1].orientation) - 1.0) < 1e-9
    device, published = replay(str(path), rate=0.0)
    assert len(published) == 4 and device.counters["rejected"] == 3
    # A file with some skeleton columns but not all is refused whole, naming what is missing.
    (tmp_path / "cut.csv").write_text(",".join(header[:20]) + "\n")
    with pytest.raises(MotionSensorError, match="skeleton columns"):
        read_csv(str(tmp_path / "cut.csv"))


@pytest.fixture
def bag_messages():
    """rosbag and the generated messages of the built workspace (scripts/test builds it)."""
    devel = glob.glob(os.path.join(ROOT, "catkin_ws", "devel", "lib", "python3*", "dist-packages", "motion_sensor"))
    if not devel:
        pytest.skip("the catkin workspace is not built (scripts/setup --test)")
    if devel[0] not in motion_sensor.__path__:
        motion_sensor.__path__.append(devel[0])
    import rosbag

    from motion_sensor import ros_conversions

    return rosbag, ros_conversions


def test_session_bag_replays_the_raw_stream_with_its_skeletons(tmp_path, bag_messages):
    rosbag, conversions = bag_messages
    import rospy

    leap, _ = load_samples(TWO_HANDS)
    path = str(tmp_path / "hands.bag")
    with rosbag.Bag(path, "w") as bag:  # as record_hands writes a session
        for i, (stamp, sample) in enumerate(leap):
            msg = conversions.sample_to_msg(sample)
            msg.header.stamp = rospy.Time.from_sec(stamp)
            bag.write("motion_sensor/raw_hand", msg, msg.header.stamp)
            bag.write("motion_sensor/hand", msg, msg.header.stamp)  # the filtered copy: not replayed
            for skeleton in sample.skeletons:
                bag.write("motion_sensor/raw_hand_skeleton", conversions.skeleton_to_msg(skeleton, msg.header))
                bag.write("motion_sensor/hand_skeleton", conversions.skeleton_to_msg(skeleton, msg.header))
            if i == 3:  # a malformed skeleton message: rejected, the frame keeps its good ones
                broken = conversions.skeleton_to_msg(sample.skeletons[0], msg.header)
                broken.joints = broken.joints[:5]
                bag.write("motion_sensor/raw_hand_skeleton", broken, msg.header.stamp)
        orphan = conversions.skeleton_to_msg(leap[0][1].skeletons[0])
        orphan.header.stamp = rospy.Time.from_sec(leap[-1][0] + 5.0)
        bag.write("motion_sensor/raw_hand_skeleton", orphan, orphan.header.stamp)
    samples, rejected = load_samples(path)
    assert_same_stream(leap, samples)
    assert len(rejected) == 2
    assert "expected 22 joints" in rejected[0] and "match no motion_sensor/raw_hand frame" in rejected[1]
    device, published = replay(path, rate=0.0)
    assert len(published) == len(leap) and device.counters["rejected"] == 2
    assert all(len(s.skeletons) == 2 for s in published)
    # A bag of the old recorder (hands only) still plays, without skeletons.
    old = str(tmp_path / "old.bag")
    with rosbag.Bag(old, "w") as bag:
        msg = conversions.sample_to_msg(leap[0][1])
        msg.header.stamp = rospy.Time.from_sec(leap[0][0])
        bag.write("motion_sensor/raw_hand", msg, msg.header.stamp)
    samples, rejected = load_samples(old)
    assert len(samples) == 1 and samples[0][1].skeletons == () and rejected == []


def test_the_replayed_hand_topic_is_the_raw_stream():
    hand = "motion_sensor/hand"
    assert hand_topic({"/motion_sensor/hand": hand, "/motion_sensor/raw_hand": hand}) == "/motion_sensor/raw_hand"
    assert hand_topic({"b/hand": hand, "a/hand": hand, "x": "motion_sensor/HandSkeleton"}) == "a/hand"
    assert hand_topic({"x": "motion_sensor/HandSkeleton"}) is None
