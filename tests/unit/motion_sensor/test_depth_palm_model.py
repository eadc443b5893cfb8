"""The depth tracker's learned palm correction (motion_sensor.devices.depth_palm_model): the
crop it sees, its fallbacks, and the shipped model on real hand motion of a subject it was
not trained on (SHREC'17 slice, subject 22: a held-out subject of the depth bench's split)."""

import numpy as np
import pytest

from motion_sensor.devices.depth_hand import OPTICAL_TO_BODY, TRACKER_PARAMS, DepthHandTracker
from motion_sensor.devices.depth_palm_model import CROP_PX, PalmModel, crop_window, palm_crop
from motion_sensor.errors import MotionSensorError
from motion_sensor.testing.skeleton_depth import PALM, place_in_view, render_skeleton
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR
from motion_sensor.testing.synthetic_depth import HAND_UPRIGHT, HandPose, render_hand

from .test_skeleton_depth import SLICE


def blob_at(depth_m=0.8, size_px=60):
    """A flat square blob in the middle of the image and its window (z, top, left)."""
    z = np.zeros((200, 200), np.float32)
    z[70 : 70 + size_px, 70 : 70 + size_px] = depth_m
    return z, 140, 220  # the window's first row and column in the 480x640 image


def test_crop_is_centred_on_the_estimate_and_relative_to_its_depth():
    z, top, left = blob_at()
    # The blob's middle pixel (row 240, column 320) at 0.8 m, estimate 20 mm behind it.
    estimate = np.array([(320 - INTR.cx) / INTR.fx * 0.82, (240 - INTR.cy) / INTR.fy * 0.82, 0.82])
    crop = palm_crop(z, top, left, estimate, INTR)
    assert crop.image.shape == (2, CROP_PX, CROP_PX) and crop.image.dtype == np.float32
    depth, cover = crop.image
    middle = slice(CROP_PX // 2 - 3, CROP_PX // 2 + 3)
    assert np.allclose(depth[middle, middle], -0.2) and np.allclose(cover[middle, middle], 1.0)
    assert np.all(depth[cover == 0] == 1.0)  # no blob: as far as the input goes
    # The crop's centre is within a pixel of the estimate, at its depth.
    assert np.linalg.norm(crop.origin - estimate) < 0.82 / INTR.fx
    # A 60-pixel square at 0.8 m is 84 mm of the 240 mm crop: about 11 cells of 32.
    assert 9 <= int(np.count_nonzero(cover[CROP_PX // 2] > 0.5)) <= 13


@pytest.mark.parametrize(
    "estimate",
    [np.array([0.0, 0.0, -0.5]), np.array([0.0, 0.0, np.nan]), np.array([2.0, 0.0, 0.8])],
    ids=["behind the camera", "no depth", "outside the image"],
)
def test_no_crop_for_an_estimate_out_of_view(estimate):
    z, top, left = blob_at()
    assert crop_window(z, top, left, estimate, INTR) is None
    assert palm_crop(z, top, left, estimate, INTR) is None


def test_no_crop_when_the_blob_is_elsewhere():
    z, top, left = blob_at(size_px=4)
    far = np.array([(520 - INTR.cx) / INTR.fx * 0.8, 0.0, 0.8])  # 200 px right of the blob
    assert palm_crop(z, top, left, far, INTR) is None


#: The tracker's own bound on a correction (palm_model_max_offset_m).
DEFAULT_BOUND = TRACKER_PARAMS.defaults()["palm_model_max_offset_m"]


class FixedModel(PalmModel):
    """The shipped model's checks with a chosen output."""

    def __init__(self, offset, max_offset_m=DEFAULT_BOUND):
        super().__init__(max_offset_m=max_offset_m)
        self.fixed = np.asarray(offset, float)

    def offsets(self, images):
        return np.tile(self.fixed, (len(images), 1))


@pytest.mark.parametrize(
    "offset, kept",
    [
        ([0.0, 0.01, 0.0], True),
        # A palm tilted well away can be 5-12 cm from the estimate: the bound was 5 cm and
        # threw away the corrections those frames needed most.
        ([0.0, 0.09, 0.0], True),
        ([0.0, 0.13, 0.0], False),
        ([np.nan, 0.0, 0.0], False),
    ],
    ids=["plausible", "large", "outside the crop", "not finite"],
)
def test_an_implausible_output_falls_back_to_the_estimate(offset, kept):
    z, top, left = blob_at()
    estimate = np.array([(320 - INTR.cx) / INTR.fx * 0.8, (240 - INTR.cy) / INTR.fy * 0.8, 0.8])
    palm = FixedModel(offset).correct(z, top, left, estimate, INTR)
    if kept:
        assert np.linalg.norm(palm - estimate - np.asarray(offset)) < 0.8 / INTR.fx
    else:
        assert palm is None


def test_a_missing_or_broken_model_is_refused_naming_the_file(tmp_path):
    with pytest.raises(MotionSensorError, match="nowhere.onnx"):
        PalmModel(str(tmp_path / "nowhere.onnx"))
    broken = tmp_path / "broken.onnx"
    broken.write_bytes(b"not a model")
    with pytest.raises(MotionSensorError, match="broken.onnx"):
        PalmModel(str(broken))


def test_the_tracker_keeps_its_estimate_when_the_model_falls_back():
    pose = HandPose(np.array([0.0, 0.0, 0.8]), HAND_UPRIGHT)
    depth = render_hand(pose, noise_per_m2=0.0015, rng=np.random.default_rng(0))
    plain = DepthHandTracker({"palm_model": False}).track(depth, INTR)
    tracker = DepthHandTracker({"palm_model": True})
    tracker.palm_model = FixedModel([0.0, 0.3, 0.0])  # always implausible
    fallen_back = tracker.track(depth, INTR)
    assert np.array_equal(plain.position, fallen_back.position)


def palm_rms(sequence, frames_used, palm_model):
    data = np.load(SLICE)
    offsets = data["offsets"]
    assert data["subject"][sequence] == 22  # held out of the model's training
    frames = place_in_view(data["joints"][offsets[sequence] : offsets[sequence + 1]].astype(float), 0.30)
    frames = frames[:frames_used]
    rng = np.random.default_rng(5)
    tracker = DepthHandTracker({"palm_model": palm_model})
    error = []
    for joints in frames:
        hand = tracker.track(render_skeleton(joints, INTR, rng=rng), INTR)
        assert hand is not None, tracker.last_reason
        error.append(OPTICAL_TO_BODY.T @ hand.position - joints[PALM])
    error = np.array(error)
    return float(np.sqrt(np.mean(np.sum((error - error.mean(axis=0)) ** 2, axis=1))))


def test_the_model_holds_the_palm_of_a_held_out_subject():
    """Subject 22's second expand gesture, its palm tilted away: the tracker's own estimate
    is 13.3 mm RMS over these 40 frames, the shipped model's correction 4.7 (7.2 for the
    model trained on 16 sequences a subject, which this bound fails)."""
    without, with_model = palm_rms(37, 40, False), palm_rms(37, 40, True)
    assert without > 0.011, f"{without * 1000:.1f} mm RMS without the model"
    assert with_model < 0.0065, f"{with_model * 1000:.1f} mm RMS with the model"
