"""The skeleton hand renderer (motion_sensor.testing.skeleton_depth): its geometry on a
hand built by hand, its sensor model, and the depth tracker on real hand motion rendered by
it (two SHREC'17 sequences of the tests' slice, tests/data/shrec17_slice.npz, of a subject
the benchmark holds out)."""

import os

import numpy as np
import pytest

from motion_sensor.devices.depth_hand import OPTICAL_TO_BODY, DepthHandTracker
from motion_sensor.testing.skeleton_depth import (
    PALM,
    HandModel,
    hand_primitives,
    place_in_view,
    render_skeleton,
)
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR

SLICE = os.path.join(os.path.dirname(__file__), "..", "..", "data", "shrec17_slice.npz")
MODEL = HandModel()


def flat_hand(z=0.7):
    """A right hand facing the camera at depth z: fingers straight down the image (+y),
    the wrist above the palm, the thumb out to the side (+x)."""
    j = np.zeros((22, 3))
    j[0] = [0.0, -0.05, z]  # wrist
    j[1] = [0.0, 0.0, z]  # palm centre
    thumb = np.array([0.03, -0.02, z])
    for k in range(4):
        j[2 + k] = thumb + [0.025 * k, 0.01 * k, 0.0]
    for f, x in enumerate((0.03, 0.01, -0.01, -0.03)):
        for k in range(4):
            j[6 + 4 * f + k] = [x, 0.05 + 0.03 * k, z]
    return j


def pixel(point):
    return int(round(INTR.cx + INTR.fx * point[0] / point[2])), int(round(INTR.cy + INTR.fy * point[1] / point[2]))


def test_palm_slab_fingers_and_forearm_are_where_the_skeleton_puts_them():
    joints = flat_hand()
    depth = render_skeleton(joints, INTR, noise=None)
    u, v = pixel(joints[PALM])
    assert depth[v, u] == pytest.approx(0.7 - MODEL.palm_half_thickness, abs=2e-4)
    # Middle finger, middle phalanx: a capsule of the middle radius lying in z = 0.7.
    u, v = pixel((joints[11] + joints[12]) / 2)
    assert depth[v, u] == pytest.approx(0.7 - MODEL.finger_radii[1], abs=2e-4)
    # Between two spread fingertips: nothing.
    u, v = pixel((joints[9] + joints[13]) / 2)
    assert depth[v, u] == 0.0
    # The forearm continues the palm -> wrist axis (up the image) and, pointing straight
    # across the view, is bent 10 degrees away from the camera: deeper further up.
    near = pixel(joints[0] + [0.0, -0.1, 0.0])
    far = pixel(joints[0] + [0.0, -0.2, 0.0])
    assert 0 < depth[near[1], near[0]] < depth[far[1], far[0]]
    assert not np.any(depth[: far[1], : pixel(joints[0] + [-0.1, 0, 0])[0]])  # nothing left of the arm


def test_forearm_never_comes_towards_the_camera():
    joints = flat_hand()
    joints[0, 2] -= 0.04  # the wrist nearer than the palm: the hand tilted, fingers away
    capsules, _ = hand_primitives(joints, MODEL)
    wrist, elbow = capsules[-2][0], capsules[-1][1]
    direction = (elbow - wrist) / np.linalg.norm(elbow - wrist)
    assert direction[2] == pytest.approx(np.sin(np.radians(MODEL.forearm_min_away_deg)), abs=1e-9)
    # Without the tilt the palm -> wrist axis is kept as it is.
    upright = flat_hand()
    upright[0, 2] += 0.03
    capsules, _ = hand_primitives(upright, MODEL)
    expected = (upright[0] - upright[1]) / np.linalg.norm(upright[0] - upright[1])
    got = capsules[-1][1] - capsules[-2][0]
    assert np.allclose(got / np.linalg.norm(got), expected)


def test_sensor_noise_quantises_drops_silhouettes_and_is_seeded():
    joints = flat_hand(0.9)
    exact = render_skeleton(joints, INTR, noise=None)
    noisy = render_skeleton(joints, INTR, rng=np.random.default_rng(4))
    again = render_skeleton(joints, INTR, rng=np.random.default_rng(4))
    assert np.array_equal(noisy, again)
    measured = noisy > 0
    assert np.allclose(noisy[measured] * 1000, np.round(noisy[measured] * 1000), atol=1e-3)  # whole mm
    hand = exact > 0
    both = hand & measured
    residual = noisy[both] - exact[both]
    # sigma 1.5 mm * z^2 plus disparity and mm steps (~2 mm at 0.9 m): a few mm, unbiased.
    assert 0.0008 < residual.std() < 0.004 and abs(residual.mean()) < 0.001
    lost = hand & ~measured
    assert 0 < lost.sum() < 0.1 * hand.sum()
    # Dropout is at the silhouette (any lost pixel beyond the random 0.2 % touches the background).
    inner = hand.copy()
    inner[1:-1, 1:-1] &= hand[:-2, 1:-1] & hand[2:, 1:-1] & hand[1:-1, :-2] & hand[1:-1, 2:]
    assert (lost & inner).sum() < 0.01 * inner.sum()
    assert not np.any(noisy[~hand])


def test_bad_skeleton_is_rejected():
    with pytest.raises(ValueError, match="22 finite"):
        render_skeleton(np.zeros((21, 3)), INTR)
    bad = flat_hand()
    bad[5, 0] = np.nan
    with pytest.raises(ValueError, match="22 finite"):
        render_skeleton(bad, INTR)


def palm_errors(sequence, frames_used, subject=None):
    """The tracker's palm minus SHREC's palm joint (m, optical frame) over the first
    ``frames_used`` frames of a slice sequence, rendered with seeded noise."""
    data = np.load(SLICE)
    offsets = data["offsets"]
    if subject is not None:
        assert data["subject"][sequence] == subject
    frames = place_in_view(data["joints"][offsets[sequence] : offsets[sequence + 1]].astype(float), 0.30)
    frames = frames[:frames_used]
    rng = np.random.default_rng(3)
    tracker = DepthHandTracker({})
    seen = []
    for joints in frames:
        hand = tracker.track(render_skeleton(joints, INTR, rng=rng), INTR)
        assert hand is not None, tracker.last_reason
        seen.append(OPTICAL_TO_BODY.T @ hand.position)
    return np.array(seen) - frames[:, PALM]


@pytest.mark.parametrize("sequence", [31, 34])  # subject 22: grab, expand
def test_tracker_follows_a_real_hand_within_10_mm(sequence):
    error = palm_errors(sequence, 20, subject=22)
    # The palm centre, not the surface: within a few mm of SHREC's palm joint on average.
    assert np.linalg.norm(error.mean(axis=0)) < 0.015, error.mean(axis=0)
    rms = float(np.sqrt(np.mean(np.sum((error - error.mean(axis=0)) ** 2, axis=1))))
    # The forearm taking over the palm, as before the tracker closed dropouts, is ~100 mm.
    assert rms < 0.010, f"{rms * 1000:.1f} mm RMS"


@pytest.mark.parametrize("sequence, frame", [(16, 15), (18, 36)])  # subject 10: swipe left, shake
def test_a_palm_narrower_than_the_forearm_is_still_the_palm(sequence, frame):
    """Real hands whose palm, tilted away, is narrower in the image than the forearm behind
    it: the widest part of the blob is the forearm there (the tracker once reported it,
    110-140 mm from the palm), the palm lies beyond the wrist's narrowing."""
    data = np.load(SLICE)
    offsets = data["offsets"]
    assert data["subject"][sequence] == 10
    joints = place_in_view(data["joints"][offsets[sequence] : offsets[sequence + 1]].astype(float), 0.30)[frame]
    hand = DepthHandTracker({}).track(render_skeleton(joints, INTR, rng=np.random.default_rng(0)), INTR)
    assert hand is not None
    error = np.linalg.norm(OPTICAL_TO_BODY.T @ hand.position - joints[PALM])
    assert error < 0.025, f"{error * 1000:.0f} mm from the palm"


@pytest.mark.parametrize("sequence", [10, 36])  # subject 10 grab, subject 22 swipe: fingers held together
def test_palm_core_holds_the_palm_where_the_widest_part_slides(sequence):
    """Fingers held together make a plate as wide as the palm, and the distance transform's
    maximum slides onto it (16.1 and 13.9 mm RMS over these 30 frames with the core off,
    ``palm_core_width_m: 0``); the centroid of the palm's core stays on the palm."""
    error = palm_errors(sequence, 30)
    rms = float(np.sqrt(np.mean(np.sum((error - error.mean(axis=0)) ** 2, axis=1))))
    assert rms < 0.009, f"{rms * 1000:.1f} mm RMS"
