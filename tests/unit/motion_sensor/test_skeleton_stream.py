"""Skeletons through the framework without ROS: the Leap parser's skeletons, the SHREC'17
stream device, the sequencer's skeleton gate, and the spotter's rest-bounded segments and
refractory period (with a stand-in classifier), then the spotter with the
shipped model on a stream of real sequences (tests/data/shrec17_slice.npz)."""

import os

import numpy as np
import pytest

from motion_common.errors import ParameterError
from motion_sensor.devices.device import DeviceRunner
from motion_sensor.devices.leap_v6 import frame_to_sample, read_recording
from motion_sensor.devices.shrec_stream import ShrecStreamDevice
from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_classifier import SkeletonResult
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, load_skeleton_dataset
from motion_sensor.gestures.skeleton_spotter import SkeletonSpotter, motion_extent
from motion_sensor.gestures.skeleton_stream import build_stream
from motion_sensor.sequencing.skeleton_gate import SkeletonGate
from motion_sensor.skeleton_joints import JOINT_NAMES
from motion_sensor.skeleton_sample import SkeletonSample

from ..conftest import DATA

SLICE = os.path.join(DATA, "shrec17_slice.npz")


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


def test_leap_frames_carry_their_skeleton():
    recording = read_recording(os.path.join(DATA, "grab.jsonl.gz"))
    frame = next(f for f in recording.frames if f.hands)
    sample = frame_to_sample(frame, stamp=5.0)
    assert len(sample.skeletons) == len(frame.hands)
    joints = sample.skeletons[0].joints
    assert joints.shape == (22, 3) and sample.skeletons[0].problem() is None
    np.testing.assert_allclose(joints[1], sample.position)  # the palm joint is the palm
    np.testing.assert_allclose(joints[JOINT_NAMES.index("index_tip")], sample.index_tip)
    span = np.linalg.norm(joints[JOINT_NAMES.index("middle_tip")] - joints[0])
    assert 0.08 < span < 0.3  # a hand, in metres


def test_shrec_stream_device_plays_the_file_as_a_live_hand():
    clock = FakeClock()
    config = {"sequences_file": SLICE, "labels": ["grab", "shake"], "limit": 3, "idle_s": 1.0, "seed": -1}
    device = ShrecStreamDevice(ShrecStreamDevice.params.validate(config, "test"), clock=clock, sleep=clock.sleep)
    assert [label for label, *_ in device.truth] == ["grab", "grab", "shake"]
    published = []
    runner = DeviceRunner(device, published.append, lambda: False, sleep=clock.sleep, clock=clock)
    assert runner.run() is True  # finished
    assert len(published) == len(device.stamps)
    first = published[int(round(device.truth[0][1] * 30.0))]  # the first gesture's first frame, after a rest
    assert first.skeletons[0].joints.shape == (22, 3) and first.device == "shrec_stream"
    data = load_skeleton_dataset(SLICE)
    np.testing.assert_allclose(first.skeletons[0].joints, data.sequences[0][0], atol=1e-9)
    np.testing.assert_allclose(first.position, data.sequences[0][0][1])
    # REP 103: the fingers of a hand held up before the camera are above the wrist.
    assert np.mean([s.skeletons[0].joints[9, 2] - s.skeletons[0].joints[0, 2] for s in published]) > 0
    stamps = [s.stamp for s in published]
    assert np.all(np.diff(stamps) > 0) and stamps[-1] - stamps[0] == pytest.approx(device.stamps[-1], abs=1e-6)
    with pytest.raises(MotionSensorError, match="unknown gestures"):
        ShrecStreamDevice(ShrecStreamDevice.params.validate({"sequences_file": SLICE, "labels": ["wave"]}, "test"))


def _skeleton(stamp, offset=0.0):
    return SkeletonSample(stamp, np.full((22, 3), offset) + np.arange(22)[:, None] * 0.01)


def test_gate_passes_a_skeleton_only_with_its_palm_frame():
    gate = SkeletonGate()
    assert gate.on_skeleton(_skeleton(1.0)) == []  # waits for its palm frame
    assert [s.stamp for s in gate.on_palm(1.0)] == [1.0]
    assert [s.stamp for s in gate.on_skeleton(_skeleton(1.0, 0.5))] == [1.0]  # second hand, after the palm
    gate.on_skeleton(_skeleton(2.0))  # its palm frame is dropped by the sequencer ...
    gate.on_skeleton(_skeleton(3.0))
    assert [s.stamp for s in gate.on_palm(3.0)] == [3.0]  # ... so it never passes
    assert gate.counters["dropped_with_palm"] == 1
    assert gate.on_skeleton(_skeleton(2.5)) == []  # late, older than a passed frame
    bad = _skeleton(4.0)
    bad.joints[3, 0] = np.nan
    assert gate.on_skeleton(bad) == [] and gate.counters["dropped_invalid"] == 1
    assert gate.counters["passed"] == 3


class StandIn:
    """Labels a window 'grab' (confident) when the hand's x moved more than 5 cm in it."""

    def __init__(self):
        self.calls = 0

    def classify_batch(self, sequences):
        self.calls += 1
        out = []
        for seq in sequences:
            prob = np.full(14, 0.01)
            moved = np.ptp(seq[:, 1, 0]) > 0.05
            prob[0 if moved else 13] = 0.9 if moved else 0.5
            out.append(SkeletonResult(prob / prob.sum() * (0.99 if moved else 1.0), np.full(28, 1 / 28)))
        return out


def _hand_stream(moves, rate=30.0):
    """Still hand with tremor, and a 0.6 s, 15 cm move at each time in ``moves``."""
    rng = np.random.default_rng(3)
    stamps = np.arange(0.0, 12.0, 1.0 / rate)
    base = np.arange(66, dtype=float).reshape(22, 3) * 0.005
    frames = []
    for t in stamps:
        shift = sum(0.15 * np.clip((t - m) / 0.6, 0.0, 1.0) for m in moves)
        curl = sum(0.02 * np.sin(np.pi * np.clip((t - m) / 0.6, 0.0, 1.0)) for m in moves)
        frame = base + rng.normal(0.0, 0.0005, base.shape)
        frame[:, 0] += shift
        frame[2:, 2] += curl
        frames.append(frame)
    return stamps, frames


def test_spotter_segments_between_rests():
    stand_in = StandIn()
    spotter = SkeletonSpotter(stand_in, {"min_confidence": 0.8})
    stamps, frames = _hand_stream(moves=[3.0, 8.0])
    events = []
    for stamp, frame in zip(stamps, frames, strict=True):
        events.extend(spotter.update(stamp, frame))
    events.extend(spotter.finish())
    assert [e.name for e in events] == ["grab", "grab"]  # one event per move, not one per window
    for event, move in zip(events, (3.0, 8.0), strict=True):
        assert event.info["start"] <= move + 0.6 and event.info["end"] >= move  # it overlaps the move
    assert spotter.counters["segments"] == 2  # the still hand between the moves was no segment
    still = SkeletonSpotter(StandIn())
    for stamp, frame in zip(*_hand_stream(moves=[]), strict=True):
        assert still.update(stamp, frame) == []
    assert still.counters["segments"] == 0
    assert motion_extent(np.array(frames[:30])) < 0.002  # tremor
    assert motion_extent(np.array(frames[90:108])) > 0.03  # the move


def test_spotter_rejects_bad_settings_and_survives_gaps():
    with pytest.raises(ValueError, match="unknown labels"):
        SkeletonSpotter(StandIn(), {"labels": ["wave"]})
    spotter = SkeletonSpotter(StandIn())
    stamps, frames = _hand_stream(moves=[3.0])
    for stamp, frame in zip(stamps[:60], frames[:60], strict=True):
        spotter.update(stamp, frame)
    spotter.update(stamps[10], frames[10])  # out of order: ignored
    assert spotter.counters["out_of_order"] == 1
    spotter.update(stamps[59] + 1.0, frames[59])  # the hand was lost: history cleared
    assert spotter.counters["gaps"] == 1


def test_spotter_with_the_shipped_model_on_real_sequences():
    from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier

    data = load_skeleton_dataset(SLICE)
    chosen = [i for i in range(len(data)) if data.subject[i] == 19]
    stamps, joints, truth = build_stream(
        [data.sequences[i] for i in chosen],
        [CLASSES_14[data.label14[i]] for i in chosen],
        np.random.default_rng(7),
    )
    spotter = SkeletonSpotter(SkeletonClassifier())
    events = []
    for stamp, frame in zip(stamps, joints, strict=True):
        events.extend(spotter.update(stamp, frame))
    events.extend(spotter.finish())
    hits = sum(any(e.name == label and start <= e.stamp <= end + 1.0 for e in events) for label, start, end in truth)
    assert hits >= 0.7 * len(truth)
    assert len(events) <= len(truth) + 2


def test_webcam_landmarks_give_a_metric_skeleton_where_the_palm_is():
    from motion_sensor.devices.hand_landmarks import palm_pose
    from motion_sensor.skeleton_joints import mediapipe_to_canonical

    from .test_webcam_hand import K, facing_camera, local_hand, place

    pose = palm_pose(place(local_hand(), facing_camera(), [0.05, -0.02, 0.5]), K)
    skeleton = mediapipe_to_canonical(pose.landmarks)
    np.testing.assert_allclose(skeleton[1], pose.position, atol=1e-9)  # the same palm centre
    np.testing.assert_allclose(skeleton[JOINT_NAMES.index("index_tip")], pose.index_tip, atol=1e-9)
    assert skeleton[JOINT_NAMES.index("middle_tip"), 2] > skeleton[0, 2] + 0.05  # fingers up, in metres


def test_spotter_classifies_windows_and_takes_the_most_confident():
    """The whole segment and the segment from ``window_starts`` on go in one batch; the
    window without the way in wins here, and the event starts where it starts."""

    class Later:
        def __init__(self):
            self.batches = []

        def classify_batch(self, sequences):
            self.batches.append([len(s) for s in sequences])
            longest = max(len(s) for s in sequences)
            out = []
            for seq in sequences:
                prob = np.full(14, 0.01)
                prob[1] = 0.3 if len(seq) == longest else 0.9  # tap, sure only without the start
                out.append(SkeletonResult(prob / prob.sum(), np.full(28, 1 / 28)))
            return out

    stand_in = Later()
    spotter = SkeletonSpotter(stand_in, {"window_starts": [0.0, 0.2], "min_confidence": 0.8})
    events = []
    for stamp, frame in zip(*_hand_stream(moves=[3.0]), strict=True):
        events.extend(spotter.update(stamp, frame))
    assert [e.name for e in events] == ["tap"]
    assert len(stand_in.batches) == 1 and len(stand_in.batches[0]) == 2
    whole, later = stand_in.batches[0]
    assert later < whole
    segment_start = events[0].info["end"] - (whole - 1) / 30.0
    assert events[0].info["start"] > segment_start + 0.1  # the later window's start
    with pytest.raises(ParameterError, match="window_starts"):
        SkeletonSpotter(stand_in, {"window_starts": [0.95]})


def test_a_window_where_a_gesture_outside_the_labels_is_likely_does_not_count():
    """With labels set, max_other_probability drops each window in which a gesture that may
    not fire is that probable: the whole segment (a pinch's weight on a grab) is dropped and
    the later window, clean, wins; when every window has it, nothing fires."""

    class PinchWeighed:
        def __init__(self, later_pinch):
            self.later_pinch = later_pinch

        def classify_batch(self, sequences):
            longest = max(len(s) for s in sequences)
            out = []
            for seq in sequences:
                prob = np.full(14, 0.001)
                whole = len(seq) == longest
                prob[0] = 0.9 if whole else 0.8  # grab, surer on the whole segment
                prob[CLASSES_14.index("pinch")] = 0.08 if whole or self.later_pinch else 0.01
                prob[1] = 1.0 - prob.sum() + prob[1]  # tap takes the rest
                out.append(SkeletonResult(prob, np.full(28, 1 / 28)))
            return out

    settings = {"labels": ["grab", "tap"], "min_confidence": 0.6, "window_starts": [0.0, 0.2]}

    def spot(classifier, **extra):
        spotter = SkeletonSpotter(classifier, {**settings, **extra})
        events = []
        for stamp, frame in zip(*_hand_stream(moves=[3.0]), strict=True):
            events.extend(spotter.update(stamp, frame))
        return events, spotter.counters

    events, _ = spot(PinchWeighed(later_pinch=False))
    assert [(e.name, round(e.confidence, 2)) for e in events] == [("grab", 0.9)]  # off by default: the surer
    events, _ = spot(PinchWeighed(later_pinch=False), max_other_probability=0.05)
    assert [(e.name, round(e.confidence, 2)) for e in events] == [("grab", 0.8)]  # the clean window
    events, counters = spot(PinchWeighed(later_pinch=True), max_other_probability=0.05)
    assert events == [] and counters["other"] == 1
    events, _ = spot(PinchWeighed(later_pinch=True), max_other_probability=0.1)
    assert [e.name for e in events] == ["grab"]
    with pytest.raises(ParameterError, match="max_other_probability"):
        SkeletonSpotter(PinchWeighed(False), {"max_other_probability": 0.0})


def test_a_longer_pause_keeps_a_gesture_the_hand_pauses_in_one_segment():
    """A gesture with a brief stop in it (the hand still for 0.55 s between two moves):
    the spotter's default 0.3 s rest cuts it in two segments, each classified on its own;
    the teach settings' 0.45 s keeps it one."""
    stamps, frames = _hand_stream(moves=[3.0, 4.15])
    segments = {}
    for pause in (0.3, 0.45):
        spotter = SkeletonSpotter(StandIn(), {"pause_s": pause})
        for stamp, frame in zip(stamps, frames, strict=True):
            spotter.update(stamp, frame)
        spotter.finish()
        segments[pause] = spotter.counters["segments"]
    assert segments == {0.3: 2, 0.45: 1}
