"""Varied hands for the skeleton renderer (motion_sensor.testing.varied_hands): bone
lengths, hand model, tilt, roll and distance drawn per sequence, seeded; nothing of the
renderer's defaults changes."""

import os

import numpy as np
import pytest

from motion_sensor.testing.skeleton_depth import FINGERS, PALM, THUMB, WRIST, HandModel, render_skeleton
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR
from motion_sensor.testing.varied_hands import (
    HandVariation,
    palm_normal,
    scale_bones,
    tilting_rotation,
    turn_sequence,
    varied_model,
    vary_sequence,
)

SLICE = os.path.join(os.path.dirname(__file__), "..", "..", "data", "shrec17_slice.npz")
# No variation at all: every factor 1, the palm's tilt and depth as the sequence has them.
NONE = HandVariation(
    overall_scale=(1.0, 1.0),
    finger_scale=(1.0, 1.0),
    radius_scale=(1.0, 1.0),
    palm_thickness_scale=(1.0, 1.0),
    wrist_width_scale=(1.0, 1.0),
    thenar_scale=(1.0, 1.0),
    forearm_scale=(1.0, 1.0),
)


def sequence(index=31):
    data = np.load(SLICE)
    offsets = data["offsets"]
    return data["joints"][offsets[index] : offsets[index + 1]].astype(float)


def tilt_deg(normal):
    return float(np.degrees(np.arccos(min(1.0, abs(normal[2]) / np.linalg.norm(normal)))))


def test_no_variation_keeps_the_default_hand_model():
    assert varied_model(np.random.default_rng(1), 1.0, NONE) == HandModel()
    joints = sequence()
    assert np.allclose(scale_bones(joints, 1.0), joints)


def test_bones_are_scaled_overall_and_per_finger():
    joints = sequence()[0]
    scaled = scale_bones(joints, 1.2, (1.0, 0.9, 1.0, 1.1, 1.0))
    length = np.linalg.norm
    assert length(scaled[PALM] - scaled[WRIST]) == pytest.approx(1.2 * length(joints[PALM] - joints[WRIST]))
    for chain, factor in zip((THUMB,) + FINGERS, (1.0, 0.9, 1.0, 1.1, 1.0)):
        # The finger's base moves with the hand; each of its phalanges by its own factor too.
        assert length(scaled[chain[0]] - scaled[WRIST]) == pytest.approx(1.2 * length(joints[chain[0]] - joints[WRIST]))
        for a, b in zip(chain, chain[1:]):
            assert length(scaled[b] - scaled[a]) == pytest.approx(1.2 * factor * length(joints[b] - joints[a]))
    assert np.array_equal(scaled[WRIST], joints[WRIST])


def test_rotation_tilts_the_palm_as_asked_and_keeps_its_face():
    normal = palm_normal(sequence()[0])
    for tilt in (0.0, 30.0, 60.0, 89.0):
        for roll in (-70.0, 0.0, 45.0):
            rotation = tilting_rotation(normal, tilt, 120.0, roll)
            assert np.allclose(rotation @ rotation.T, np.eye(3)) and np.linalg.det(rotation) == pytest.approx(1.0)
            turned = rotation @ normal
            assert tilt_deg(turned) == pytest.approx(tilt, abs=1e-6)
            assert np.sign(turned[2]) == np.sign(normal[2]) or tilt > 88
    joints = sequence()
    turned = turn_sequence(joints, tilting_rotation(normal, 70.0, 0.0, 30.0))
    assert np.allclose(turned[:, PALM].mean(axis=0), joints[:, PALM].mean(axis=0))  # about the mean palm
    # Rigid: the hand's own distances are kept.
    assert np.allclose(
        np.linalg.norm(turned[:, 9] - turned[:, 0], axis=1), np.linalg.norm(joints[:, 9] - joints[:, 0], axis=1)
    )


def test_varied_sequences_are_seeded_placed_and_tilted_across_the_range():
    joints = sequence()
    first, model = vary_sequence(joints, np.random.default_rng(5))
    again, model_again = vary_sequence(joints, np.random.default_rng(5))
    assert np.array_equal(first, again) and model == model_again
    tilts, depths, sizes = [], [], []
    rng = np.random.default_rng(6)
    for _ in range(40):
        varied, model = vary_sequence(joints, rng)
        palm = varied[:, PALM].mean(axis=0)
        assert np.allclose(palm[:2], 0.0, atol=1e-12) and 0.6 <= palm[2] <= 1.0
        tilts.append(tilt_deg(palm_normal(varied).mean(axis=0)))
        depths.append(palm[2])
        sizes.append(np.linalg.norm(varied[0, 9] - varied[0, WRIST]) / np.linalg.norm(joints[0, 9] - joints[0, WRIST]))
        assert model != HandModel()
    assert min(tilts) < 20 and max(tilts) > 70  # faced and edge-on palms both drawn
    assert max(depths) - min(depths) > 0.25
    assert min(sizes) < 0.95 and max(sizes) > 1.05


def test_a_varied_hand_renders_differently_and_seeded():
    joints = sequence()
    placed = joints + np.array([0.0, 0.0, 0.3]) - np.append(joints[:, PALM].mean(axis=0)[:2], 0.0)
    default = render_skeleton(placed[0], INTR, rng=np.random.default_rng(2))
    varied, model = vary_sequence(joints, np.random.default_rng(0))
    image = render_skeleton(varied[0], INTR, model, rng=np.random.default_rng(2))
    again = render_skeleton(varied[0], INTR, model, rng=np.random.default_rng(2))
    assert np.array_equal(image, again)
    assert (image > 0).sum() > 1000
    assert abs(int((image > 0).sum()) - int((default > 0).sum())) > 100
    # The model alone, on the same skeleton, changes the render too.
    assert not np.array_equal(
        render_skeleton(placed[0], INTR, model, noise=None), render_skeleton(placed[0], INTR, noise=None)
    )


def test_bad_sequences_are_rejected():
    with pytest.raises(ValueError, match=r"\(n, 22, 3\)"):
        vary_sequence(np.zeros((22, 3)), np.random.default_rng(0))
    bad = sequence()
    bad[3, 4, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        vary_sequence(bad, np.random.default_rng(0))
    with pytest.raises(ValueError, match="per_finger"):
        scale_bones(sequence()[0], 1.0, (1.0, 1.0))
