"""The webcam hand driver with the real MediaPipe Hands on real hand photos (Debian's
opencv-doc, tests/data/README.md): moving sequences made by warping them (the known warp
is the ground truth of the image motion), gesture strengths on open and gripping hands,
and a video file played through the device: one message per frame, each frame's stamp,
then the end of the stream."""

import os
import sys

import cv2
import numpy as np
import pytest

from motion_sensor.devices.device import DeviceRunner
from motion_sensor.devices.mediapipe_hands import MediaPipeHandDetector
from motion_sensor.devices.webcam_device import WebcamHandDevice
from motion_sensor.devices.webcam_hand import WebcamHandTracker

from ..conftest import DATA, ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
from hand_warp import HEIGHT, WIDTH, warped_sequence  # noqa: E402

FOCAL = 0.5 * WIDTH / np.tan(np.radians(60.0) / 2)  # the tracker's default hfov_deg 60


def reprojected_pixels(samples):
    """Palm pixels (N x 2, NaN without a hand) from the published REP 103 positions."""
    pixels = np.full((len(samples), 2), np.nan)
    for i, sample in enumerate(samples):
        if sample.hands_num:
            x, y, z = sample.position
            pixels[i] = (WIDTH / 2 - FOCAL * y / x, HEIGHT / 2 - FOCAL * z / x)
    return pixels


@pytest.mark.parametrize("photo,seed", [("handSrc", 3), ("Back_Projection_Theory0", 4)])
def test_palm_path_follows_the_image_motion(photo, seed):
    sequence = warped_sequence(photo, frames=45, seed=seed, period_frames=45)
    tracker = WebcamHandTracker(MediaPipeHandDetector(static_image_mode=False))  # tracking mode, as live
    samples = [tracker.process(frame, 0.05 * i) for i, frame in enumerate(sequence.frames)]
    found = np.array([s.hands_num > 0 for s in samples])
    assert found.mean() >= 0.9, dict(tracker.counters)
    pixels = reprojected_pixels(samples)
    # Ground truth: the palm's photo point (from the first frame with a hand) moved by each warp.
    first = int(np.argmax(found))
    affine = np.vstack([sequence.transforms[first], [0, 0, 1]])
    truth = sequence.image_point(np.linalg.solve(affine, [*pixels[first], 1.0])[:2])
    for axis in (0, 1):
        assert np.corrcoef(pixels[found, axis], truth[found, axis])[0, 1] > 0.95, axis
        steps, true_steps = np.diff(pixels[found, axis]), np.diff(truth[found, axis])
        moving = np.abs(true_steps) > 2.0
        assert np.mean(np.sign(steps[moving]) == np.sign(true_steps[moving])) >= 0.9, axis
    assert np.sqrt(np.nanmean(np.sum((pixels - truth) ** 2, axis=1))) < 15.0  # px
    # Depth from apparent size: a photo shown larger is a hand nearer the camera.
    depth = np.array([s.position[0] for s, f in zip(samples, found) if f])
    inverse_scale = 1.0 / sequence.scales[found]
    assert np.corrcoef(depth, inverse_scale)[0, 1] > 0.95
    product = depth * sequence.scales[found]
    assert np.std(product) / np.mean(product) < 0.05
    assert all(s.hand_types[0] in ("left", "right") and 0 <= s.grab_strength <= 1 for s in samples if s.hands_num)


def test_gesture_strengths_on_open_and_gripping_hands():
    tracker = WebcamHandTracker(MediaPipeHandDetector(static_image_mode=True))
    grab = {}
    for name in ("handSrc.jpg", "Back_Projection_Theory0.jpg", "right04.jpg"):
        sample = tracker.process(cv2.imread(os.path.join(DATA, name)), 0.0)
        assert sample.hands_num == 1, name
        assert np.all(np.isfinite(sample.position)) and sample.position[0] > 0.05
        grab[name] = sample.grab_strength
    assert grab["handSrc.jpg"] < 0.2 and grab["Back_Projection_Theory0.jpg"] < 0.2  # open hands
    assert grab["right04.jpg"] > 0.3  # fingers round a board


class FakeClock:
    def __init__(self, start=50.0):
        self.now = start

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


def test_video_file_plays_once_one_message_per_frame(tmp_path):
    sequence = warped_sequence("handSrc", frames=20, seed=5, period_frames=20)
    path = str(tmp_path / "hand.avi")
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (WIDTH, HEIGHT))
    assert writer.isOpened()
    for frame in sequence.frames:
        writer.write(frame)
    writer.release()
    config = WebcamHandDevice.params.validate({"video": path, "camera": -1}, "test")
    clock = FakeClock()
    device = WebcamHandDevice(config, clock=clock, sleep=clock.sleep)
    published = []
    try:
        assert DeviceRunner(device, published.append, stopped=lambda: False).run() is True  # ended by itself
    finally:
        device.shutdown()
    assert len(published) == len(sequence.frames)
    np.testing.assert_allclose([s.stamp for s in published], 50.0 + np.arange(20) / 15.0, atol=1e-9)
    assert sum(s.hands_num > 0 for s in published) >= 18
    assert device.counters["decode_failures"] == 0 and device.counters["frames"] == 20


@pytest.mark.parametrize("photo", ["handSrc.jpg", "Back_Projection_Theory0.jpg"])
def test_a_photo_beside_its_mirror_gives_two_skeletons_of_opposite_hands(photo):
    """The mirror image of a hand is the other hand: MediaPipe sees two, and both skeletons
    go out, each with its handedness, the mirrored one on the other side of the image."""
    image = cv2.imread(os.path.join(DATA, photo))
    both = np.hstack([image, cv2.flip(image, 1)])
    tracker = WebcamHandTracker(MediaPipeHandDetector(static_image_mode=True), primary_hand="right")
    sample = tracker.process(both, 1.5)
    assert sample.hands_num == 2 and sorted(sample.hand_types) == ["left", "right"]
    skeletons = sample.skeletons
    assert [s.hand_type for s in skeletons] == ["right", "left"] and skeletons[0].hand_id != skeletons[1].hand_id
    assert all(s.problem() is None and s.stamp == 1.5 for s in skeletons)
    np.testing.assert_allclose(skeletons[0].joints[1], sample.position, atol=0.02)
    # REP 103: y is to the camera's left; the two hands are on either side of the seam.
    palms_y = sorted(s.joints[1][1] for s in skeletons)
    assert palms_y[0] < -0.02 and palms_y[1] > 0.02
    # Mirrored hands have mirrored shapes: the same finger lengths.
    lengths = [np.linalg.norm(s.joints[9] - s.joints[6]) for s in skeletons]
    assert lengths[0] == pytest.approx(lengths[1], rel=0.1)
