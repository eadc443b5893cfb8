"""Training windows cut by the spotter's own segmentation
(motion_sensor.gestures.skeleton_spotted_windows) from the SHREC'17 slice
(tests/data/README.md), and a training that uses them."""

import os

import numpy as np

from motion_sensor.gestures.skeleton_dataset import load_skeleton_dataset
from motion_sensor.gestures.skeleton_spotted_windows import spotted_windows

from ..conftest import DATA

SLICE = os.path.join(DATA, "shrec17_slice.npz")


def test_windows_are_the_spotters_and_carry_the_gesture_they_cover():
    data = load_skeleton_dataset(SLICE)
    found = spotted_windows(data, np.random.default_rng(3), params={"window_starts": [0.0, 0.2]})
    again = spotted_windows(data, np.random.default_rng(3), params={"window_starts": [0.0, 0.2]})
    assert len(found) == len(again) and all(
        np.array_equal(a, b) for a, b in zip(found.windows, again.windows, strict=True)
    )
    # Two windows per segment and about one segment per gesture (the streams' rests split them).
    assert len(data) <= len(found) <= 2 * len(data) + 4
    positive = found.label14 >= 0
    assert positive.mean() > 0.8 and np.all(found.cover[positive] >= 0.5) and np.all(found.cover[~positive] < 0.5)
    assert np.array_equal(found.label14[positive], found.label28[positive] // 2)  # 28 = gesture x finger
    # A labelled window holds frames of a sequence of its gesture (and rest and way in).
    for window, label in zip(found.windows, found.label14, strict=True):
        assert window.shape[1:] == (22, 3) and len(window) >= 4
        if label >= 0:
            frames = np.concatenate([s for s, k in zip(data.sequences, data.label14, strict=True) if k == label])
            shared = (np.abs(frames[:, None] - window[None]).max(axis=(2, 3)) < 1e-9).any(axis=0)
            assert shared.sum() >= 0.3 * len(window)


def test_tiny_training_with_spotted_windows_and_pair_weight_runs_seeded(tiny_model):
    from motion_sensor.gestures.skeleton_training import TrainConfig, predict, train_model

    from .conftest import TINY_SETTINGS

    _, data, held_out = tiny_model
    train = data.subset(~held_out)
    settings = dict(TINY_SETTINGS, epochs=4, spot_share=0.5, pair_weight=2.0)
    first = predict(train_model(train, TrainConfig(**settings)), data.subset(held_out).sequences)[0]
    second = predict(train_model(train, TrainConfig(**settings)), data.subset(held_out).sequences)[0]
    assert np.array_equal(first, second)
    assert np.allclose(first.sum(axis=1), 1.0, atol=1e-5)
