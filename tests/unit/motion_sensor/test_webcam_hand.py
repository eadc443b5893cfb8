"""Webcam hand maths, tracker and device on synthetic landmarks and fake captures (no
MediaPipe, no camera): depth from apparent size, palm pose and axes, grab and pinch,
bad frames, primary hand and tracking id, video playback timing, decode failures."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_sensor.devices.device import DeviceRunner
from motion_sensor.devices.hand_landmarks import (
    OPTICAL_TO_REP103,
    DetectedHand,
    GestureThresholds,
    Intrinsics,
    calibrate_depth_scale,
    estimate_depth,
    finger_curls,
    grab_strength,
    landmark_problem,
    palm_pose,
    pinch_strength,
)
from motion_sensor.devices.mediapipe_hands import HandDetector
from motion_sensor.devices.webcam_device import WebcamHandDevice, load_depth_scale
from motion_sensor.devices.webcam_hand import FrameLimits, WebcamHandTracker, frame_problem
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError

K = Intrinsics(600.0, 600.0, 320.0, 240.0)
# Finger bases (x along the fingers, y towards the thumb of a right hand, m) and segment lengths.
BASES = {5: (0.085, 0.024), 9: (0.088, 0.0), 13: (0.083, -0.021), 17: (0.075, -0.040)}
SEGMENTS = (0.040, 0.025, 0.020)


def local_hand(curl_deg=0.0, handedness="right", thumb_tip=None):
    """21 landmarks of a hand in its own frame (x fingers, z out of the back), m; every
    finger joint bent by ``curl_deg`` towards the palm."""
    points = np.zeros((21, 3))
    points[1:5] = [(0.02, 0.025, 0), (0.04, 0.045, 0), (0.06, 0.06, 0), (0.08, 0.07, 0)]
    bend = np.radians(curl_deg)
    for base, (x, y) in BASES.items():
        position = np.array([x, y, 0.0])
        points[base] = position
        for k, length in enumerate(SEGMENTS, start=1):
            angle = k * bend
            position = position + length * np.array([np.cos(angle), 0.0, -np.sin(angle)])
            points[base + k] = position
    if thumb_tip is not None:
        points[4] = thumb_tip(points)
    if handedness == "left":
        points[:, 1] *= -1
    return points


def place(local, rotation, centre_optical, intrinsics=K, handedness="right", score=0.9):
    """A DetectedHand of ``local`` turned by ``rotation`` (hand frame -> optical) with its
    palm centre at ``centre_optical`` (m): exact perspective image, world landmarks centred."""
    palm = local[[0, 5, 9, 13, 17]].mean(axis=0)
    world = (rotation @ (local - palm).T).T
    camera = world + np.asarray(centre_optical)
    image = np.column_stack(
        [
            intrinsics.fx * camera[:, 0] / camera[:, 2] + intrinsics.cx,
            intrinsics.fy * camera[:, 1] / camera[:, 2] + intrinsics.cy,
        ]
    )
    return DetectedHand(image=image, world=world - world.mean(axis=0), handedness=handedness, score=score)


def facing_camera():
    """Hand frame -> optical: fingers up (-y optical), back of the hand away (+z), so a
    right hand's thumb side (+y) is on the image's right."""
    return np.column_stack([[0, -1, 0], [1, 0, 0], [0, 0, 1]]).astype(float)


@pytest.mark.parametrize("depth", [0.3, 0.5, 0.9])
def test_depth_from_apparent_size(depth, rng):
    for _ in range(5):
        tilt = Rotation.from_euler("xyz", rng.uniform(-35, 35, 3), degrees=True).as_matrix()
        hand = place(local_hand(), tilt @ facing_camera(), [rng.uniform(-0.1, 0.1), rng.uniform(-0.05, 0.05), depth])
        assert estimate_depth(hand.image, hand.world, K) == pytest.approx(depth, rel=1e-6)


def test_palm_pose_position_and_axes(rng):
    for handedness in ("right", "left"):
        for _ in range(10):
            rotation = Rotation.from_euler("xyz", rng.uniform(-40, 40, 3), degrees=True).as_matrix() @ facing_camera()
            centre = np.array([rng.uniform(-0.15, 0.15), rng.uniform(-0.1, 0.1), rng.uniform(0.35, 0.8)])
            hand = place(local_hand(handedness=handedness), rotation, centre, handedness=handedness)
            pose = palm_pose(hand, K)
            assert np.linalg.norm(pose.position - OPTICAL_TO_REP103 @ centre) < 0.02 * centre[2]
            expected = Rotation.from_matrix(OPTICAL_TO_REP103 @ rotation)
            error = (Rotation.from_quat(pose.orientation) * expected.inv()).magnitude()
            assert np.degrees(error) < 5.0, handedness
            assert np.linalg.norm(pose.orientation) == pytest.approx(1.0)


def test_rep103_axes_of_a_hand_facing_the_camera():
    pose = palm_pose(place(local_hand(), facing_camera(), [0.05, -0.02, 0.5]), K)
    matrix = Rotation.from_quat(pose.orientation).as_matrix()
    assert pose.position[0] == pytest.approx(0.5, abs=0.02)  # forward = depth
    assert pose.position[1] == pytest.approx(-0.05, abs=0.01)  # image right = -y (left)
    assert pose.position[2] == pytest.approx(0.02, abs=0.01)  # image up = +z
    np.testing.assert_allclose(matrix[:, 0], [0, 0, 1], atol=0.05)  # fingers up
    np.testing.assert_allclose(matrix[:, 2], [1, 0, 0], atol=0.05)  # back of the hand away from the camera


def test_depth_scale_scales_position_and_calibration_recovers_it():
    hand = place(local_hand(), facing_camera(), [0.0, 0.0, 0.5])
    raw = palm_pose(hand, K)
    scaled = palm_pose(hand, K, depth_scale=1.25)
    np.testing.assert_allclose(scaled.position, 1.25 * raw.position, rtol=1e-9)
    assert calibrate_depth_scale([raw.raw_depth] * 5 + [float("nan")], 0.6) == pytest.approx(0.6 / raw.raw_depth)
    with pytest.raises(ValueError):
        calibrate_depth_scale([float("nan")], 0.6)


def test_grab_strength_from_curl():
    # Curl is the sum of the three joints' bends: 0 flat, 3 x 90 = 270 degrees a fist.
    values = [grab_strength(local_hand(curl_deg=c)) for c in (0, 20, 35, 50, 90)]
    assert values[0] == 0.0
    assert values[-1] == 1.0
    assert all(a <= b for a, b in zip(values, values[1:])) and 0 < values[2] < 1
    np.testing.assert_allclose(finger_curls(local_hand(curl_deg=30)), 90.0, atol=15)


def test_pinch_strength_from_thumb_to_nearest_tip():
    touching = local_hand(thumb_tip=lambda p: p[8] + [0.0, 0.005, 0.0])
    apart = local_hand(thumb_tip=lambda p: p[8] + [0.0, 0.12, 0.0])
    halfway = local_hand(thumb_tip=lambda p: p[8] + [0.0, 0.045, 0.0])
    assert pinch_strength(touching) == 1.0
    assert pinch_strength(apart) == 0.0
    assert pinch_strength(halfway) == pytest.approx(0.5, abs=0.01)
    assert pinch_strength(apart, GestureThresholds(pinch_open_m=0.2)) > 0


def test_landmark_problems():
    good = place(local_hand(), facing_camera(), [0, 0, 0.5])
    assert landmark_problem(good) is None
    assert "shape" in landmark_problem(DetectedHand(good.image[:20], good.world, "right", 1.0))
    nan = good.world.copy()
    nan[3, 1] = np.nan
    assert "non-finite" in landmark_problem(DetectedHand(good.image, nan, "right", 1.0))
    assert "handedness" in landmark_problem(DetectedHand(good.image, good.world, "Right", 1.0))


class FakeDetector(HandDetector):
    """Returns the queued detections, one list per call, and remembers the images."""

    def __init__(self, detections):
        self.detections = list(detections)
        self.images = []

    def detect(self, rgb):
        self.images.append(rgb)
        return self.detections.pop(0) if self.detections else []


def grey_frame(value=128):
    return np.full((480, 640, 3), value, np.uint8)


def test_frame_problems():
    assert frame_problem(grey_frame()) is None
    assert frame_problem(grey_frame(3))[0] == "black_frames"
    assert frame_problem(grey_frame(255))[0] == "saturated_frames"
    assert frame_problem(np.zeros((480, 640), np.uint8))[0] == "bad_frames"
    assert frame_problem(grey_frame().astype(np.float32))[0] == "bad_frames"
    assert frame_problem(None)[0] == "bad_frames"
    assert frame_problem(grey_frame(8), FrameLimits(black_level=5)) is None


def test_tracker_bad_frames_go_out_without_a_hand_and_are_counted():
    right = place(local_hand(), facing_camera(), [0, 0, 0.5])
    detector = FakeDetector([[right]])
    tracker = WebcamHandTracker(detector, intrinsics=K)
    outputs = [
        tracker.process(grey_frame(0), 1.0),
        tracker.process(grey_frame(255), 2.0),
        tracker.process(grey_frame(), 3.0),
    ]
    assert [s.hands_num for s in outputs] == [0, 0, 1]
    assert [s.stamp for s in outputs] == [1.0, 2.0, 3.0]
    assert len(detector.images) == 1  # bad frames never reach the detector
    assert tracker.counters["black_frames"] == 1 and tracker.counters["saturated_frames"] == 1
    assert tracker.process(grey_frame(), 4.0).hands_num == 0
    assert tracker.counters["no_hand"] == 1 and tracker.counters["frames"] == 4


def test_tracker_primary_hand_types_gesture_fields_and_ids():
    right = place(local_hand(), facing_camera(), [0.05, 0, 0.5], score=0.7)
    left = place(local_hand(handedness="left"), facing_camera(), [-0.1, 0, 0.5], handedness="left", score=0.95)
    broken = DetectedHand(np.zeros((3, 2)), np.zeros((3, 3)), "right", 0.99)
    detector = FakeDetector([[left, right], [broken, left, right], [left], [], [right]])
    tracker = WebcamHandTracker(detector, intrinsics=K, primary_hand="right")
    samples = [tracker.process(grey_frame(), float(i)) for i in range(5)]
    assert samples[0].hand_types == ("right", "left") and samples[0].hands_num == 2
    assert samples[0].position[1] == pytest.approx(-0.05, abs=0.01)
    assert samples[0].confidence == pytest.approx(0.7)
    assert 0 <= samples[0].grab_strength <= 0.1 and samples[0].pinch_strength == 0.0
    assert samples[0].index_tip is not None and samples[0].index_tip[2] > samples[0].position[2]
    assert samples[1].hand_types == ("right", "left") and tracker.counters["bad_landmarks"] == 1
    assert samples[2].hand_types == ("left",)  # no right hand: the one seen steers
    ids = [s.hand_id for s in samples]
    assert ids[0] == ids[1] and ids[2] != ids[1]  # the steering hand changed
    assert samples[3].hands_num == 0 and ids[4] not in (ids[0], ids[2])  # a hand after none is new


def test_mirrored_frames_are_flipped_before_detection():
    frame = grey_frame()
    frame[:, :10] = 200
    detector = FakeDetector([])
    WebcamHandTracker(detector, mirrored=True).process(frame, 0.0)
    assert detector.images[0][0, -1, 0] == 200 and detector.images[0][0, 0, 0] == 128


class FakeCapture:
    """cv2.VideoCapture stand-in: a list of frames (None = fails to decode)."""

    def __init__(self, frames, fps=25.0, opened=True, grab_fails_at=None):
        self.frames, self.fps, self.opened, self.grab_fails_at = list(frames), fps, opened, grab_fails_at
        self.index = -1
        self.released = False

    def isOpened(self):
        return self.opened

    def get(self, prop):
        import cv2

        return {cv2.CAP_PROP_FPS: self.fps, cv2.CAP_PROP_FRAME_COUNT: len(self.frames)}.get(prop, 0.0)

    def set(self, prop, value):
        return True

    def grab(self):
        if self.grab_fails_at is not None and self.index + 1 >= self.grab_fails_at:
            return False
        self.index += 1
        return self.index < len(self.frames)

    def retrieve(self):
        frame = self.frames[self.index]
        return (frame is not None), frame

    def release(self):
        self.released = True


class FakeClock:
    def __init__(self, start=100.0):
        self.now = start

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


def webcam_device(tmp_path, frames, detections, **overrides):
    video = tmp_path / "clip.avi"
    video.write_bytes(b"not read: the capture is a fake")
    config = WebcamHandDevice.params.validate(
        {"video": str(video), "camera": -1, "fx": 600.0, "cx": 320.0, "cy": 240.0, **overrides}, "test"
    )
    clock = FakeClock()
    capture = FakeCapture(frames)
    device = WebcamHandDevice(
        config,
        detector_factory=lambda cfg: FakeDetector(detections),
        capture_factory=lambda source: capture,
        clock=clock,
        sleep=clock.sleep,
    )
    return device, clock, capture


def test_video_plays_each_frame_once_at_its_time_then_ends(tmp_path):
    hand = place(local_hand(), facing_camera(), [0, 0, 0.5])
    frames = [grey_frame()] * 3 + [None] + [grey_frame()] * 2
    device, clock, capture = webcam_device(tmp_path, frames, [[]] + [[hand]] * 5)  # [] for the warm-up
    published = []
    runner = DeviceRunner(device, published.append, stopped=lambda: False)
    assert runner.run() is True  # EndOfStream: finished
    assert len(published) == 5  # one message per decoded frame
    stamps = [s.stamp for s in published]
    np.testing.assert_allclose(stamps, 100.0 + np.array([0, 1, 2, 4, 5]) / 25.0)  # each frame's own time
    assert device.counters["decode_failures"] == 1 and device.counters["hands"] == 5
    assert capture.released


def test_video_that_fell_behind_plays_on_from_now(tmp_path):
    device, clock, _ = webcam_device(tmp_path, [grey_frame()] * 3, [])
    device.open()
    first = device.read(clock())
    clock.now += 1.0  # a stall of 25 frame periods
    second = device.read(clock())
    assert second.stamp == pytest.approx(clock.now) and second.stamp - first.stamp > 0.9
    assert device.counters["late_frames"] == 1
    device.read(clock())
    with pytest.raises(EndOfStream):
        device.read(clock())


def test_camera_errors_are_retryable_and_bad_settings_fatal(tmp_path):
    config = WebcamHandDevice.params.validate({"camera": 0}, "test")
    closed = WebcamHandDevice(
        config,
        detector_factory=lambda cfg: FakeDetector([]),
        capture_factory=lambda source: FakeCapture([], opened=False),
    )
    with pytest.raises(DeviceUnavailable):
        closed.open()
    unplugged = WebcamHandDevice(
        config,
        detector_factory=lambda cfg: FakeDetector([]),
        capture_factory=lambda source: FakeCapture([grey_frame()] * 5, grab_fails_at=1),
    )
    unplugged.open()
    assert unplugged.read(0.0).hands_num == 0
    with pytest.raises(DeviceUnavailable):
        unplugged.read(0.0)
    with pytest.raises(MotionSensorError, match="camera index"):
        WebcamHandDevice(WebcamHandDevice.params.validate({"camera": -1}, "test"))
    with pytest.raises(MotionSensorError, match="does not exist"):
        WebcamHandDevice(WebcamHandDevice.params.validate({"video": str(tmp_path / "none.avi")}, "test"))
    with pytest.raises(MotionSensorError, match="cx and cy"):
        WebcamHandDevice(WebcamHandDevice.params.validate({"fx": 500.0}, "test"))


def test_calibration_file(tmp_path):
    good = tmp_path / "cal.yaml"
    good.write_text("depth_scale: 1.3\n")
    assert load_depth_scale(str(good)) == 1.3
    bad = tmp_path / "bad.yaml"
    bad.write_text("depth_scale: -2\n")
    with pytest.raises(MotionSensorError, match="depth_scale"):
        load_depth_scale(str(bad))
    with pytest.raises(MotionSensorError, match="cannot read"):
        load_depth_scale(str(tmp_path / "missing.yaml"))
    config = WebcamHandDevice.params.validate({"calibration_file": str(good)}, "test")
    assert WebcamHandDevice(config).tracker.depth_scale == 1.3


def test_every_hand_seen_has_its_skeleton_with_its_handedness_and_number():
    right = place(local_hand(), facing_camera(), [0.05, 0, 0.5], score=0.7)
    left = place(local_hand(handedness="left"), facing_camera(), [-0.1, 0, 0.5], handedness="left", score=0.95)
    twin = place(local_hand(), facing_camera(), [0.0, 0, 0.4], score=0.6)  # a second "right": no skeleton
    detector = FakeDetector([[left, right], [left, right, twin], [right], [left, right]])
    tracker = WebcamHandTracker(detector, intrinsics=K, primary_hand="right")
    samples = [tracker.process(grey_frame(), float(i)) for i in range(4)]
    kinds = [[(s.hand_type, s.hand_id) for s in sample.skeletons] for sample in samples]
    # The primary first; each type keeps its number while in view, a returning one is new.
    assert kinds[0] == [("right", 1), ("left", 2)] and kinds[1] == kinds[0]
    assert kinds[2] == [("right", 1)] and kinds[3] == [("right", 1), ("left", 3)]
    assert tracker.counters["duplicate_hands"] == 1 and samples[1].hands_num == 3
    first = samples[0].skeletons
    assert all(s.problem() is None and s.stamp == 0.0 for s in first)
    assert first[0].confidence == pytest.approx(0.7) and first[1].confidence == pytest.approx(0.95)
    palm = [s.joints[1] for s in first]  # canonical palm: the right hand's on the camera's left (-y)
    assert palm[0][1] == pytest.approx(-0.05, abs=0.01) and palm[1][1] == pytest.approx(0.1, abs=0.01)
    np.testing.assert_allclose(palm[0], samples[0].position, atol=0.01)
