"""Motion that is no gesture (motion_sensor.gestures.skeleton_negatives) and the training
that learns to reject it: real Leap frames of tests/data and the SHREC'17 slice
(tests/data/README.md)."""

import os

import numpy as np
import pytest

from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_dataset import load_skeleton_dataset
from motion_sensor.gestures.skeleton_negatives import RATE, NegativeSource, leap_motion, transition

from ..conftest import DATA

SLICE = os.path.join(DATA, "shrec17_slice.npz")
LEAP = [os.path.join(DATA, name) for name in ("wave.jsonl.gz", "flapping.jsonl.gz", "brian.jsonl.gz")]


def test_leap_motion_is_resampled_canonical_runs():
    runs = leap_motion(LEAP)
    assert runs and all(r.ndim == 3 and r.shape[1:] == (22, 3) and len(r) >= 15 for r in runs)
    seconds = sum(len(r) for r in runs) / RATE
    assert 5.0 < seconds < 12.0  # the three recordings last about 10 s together
    hand = np.linalg.norm(runs[0][:, 9] - runs[0][:, 0], axis=1)  # index tip to wrist, metres
    assert 0.05 < np.median(hand) < 0.25
    with pytest.raises(MotionSensorError, match="absent.jsonl.gz"):
        leap_motion([os.path.join(DATA, "absent.jsonl.gz")])


def test_transition_and_draw_are_seeded_and_bounded():
    data = load_skeleton_dataset(SLICE)
    a, b = data.sequences[0], data.sequences[1]
    window = transition(a, b, np.random.default_rng(1))
    assert window.shape[1:] == (22, 3)
    assert len(window) < len(a) * 0.3 + 1.5 * RATE + 0.7 * RATE + len(b) * 0.3 + 2
    assert any(np.allclose(window[0], frame) for frame in a[-int(len(a) * 0.3) - 1 :])  # from a's end
    assert np.allclose(window[-1], b[0], atol=0.01) or any(np.allclose(window[-1], f) for f in b)  # into b
    source = NegativeSource(leap_motion(LEAP[:1]), data.sequences, data.subject)
    first = source.draw(np.random.default_rng(5), 6)
    again = source.draw(np.random.default_rng(5), 6)
    assert len(first) == 6 and all(np.array_equal(x, y) for x, y in zip(first, again, strict=True))
    assert all(15 <= len(w) <= 4 * RATE for w in first)
    assert not NegativeSource()


def test_tiny_retrain_learns_to_reject_non_gestures(tiny_model):
    """Seeded: with rejection on, the network is less sure on real Leap motion it never saw
    than the same training without it (the shared tiny model), and still recognises a
    held-out person's gestures."""
    from motion_sensor.gestures.skeleton_training import TrainConfig, predict, train_model

    from .conftest import TINY_SETTINGS

    plain, data, held_out = tiny_model
    train = data.subset(~held_out)
    unseen = [w for r in leap_motion([os.path.join(DATA, "rollAndPitchCropped.jsonl.gz")]) for w in (r[:45], r[45:90])]
    source = NegativeSource(leap_motion(LEAP), train.sequences, train.subject)
    rejecting = train_model(train, TrainConfig(**TINY_SETTINGS, reject_share=0.5), negatives=source)
    sure_plain = predict(plain, unseen)[0].max(1).mean()
    sure_rejecting = predict(rejecting, unseen)[0].max(1).mean()
    assert sure_rejecting < sure_plain - 0.1
    test_prob, _ = predict(rejecting, data.subset(held_out).sequences)
    assert np.mean(test_prob.argmax(1) == data.label14[held_out]) >= 0.6
