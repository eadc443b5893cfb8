"""The skeleton gesture recognizer: joint mapping, features, the .npz checks, a tiny
seeded retrain that must learn, and the shipped ONNX model on real sequences
(tests/data/shrec17_slice.npz, SHREC'17, see tests/data/README.md)."""

import os

import numpy as np
import pytest

from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, CLASSES_28, load_skeleton_dataset
from motion_sensor.gestures.skeleton_features import FRAMES, JCD_SIZE, MOTION_SIZE, skeleton_features
from motion_sensor.skeleton_joints import (
    JOINT_NAMES,
    leap_to_canonical,
    mediapipe_to_canonical,
    shrec_to_canonical,
)

from ..conftest import DATA

SLICE = os.path.join(DATA, "shrec17_slice.npz")


def _rotation_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_canonical_set_and_shrec_axes():
    assert len(JOINT_NAMES) == 22 and JOINT_NAMES[:3] == ("wrist", "palm", "thumb_base")
    assert JOINT_NAMES[9] == "index_tip" and JOINT_NAMES[21] == "pinky_tip"
    shrec = np.zeros((22, 3))
    shrec[:, 0] = 0.1  # 10 cm to the performer's right
    shrec[:, 1] = 0.2  # 20 cm up
    shrec[:, 2] = 0.5  # half a metre from the camera
    rep = shrec_to_canonical(shrec)
    np.testing.assert_allclose(rep[0], [-0.5, -0.1, 0.2])  # x towards the camera, y left, z up


def test_shrec_swipes_go_their_way_in_rep103():
    data = load_skeleton_dataset(SLICE)
    palm_moves = {}
    for sequence, label in zip(data.sequences, data.label14, strict=True):
        palm_moves.setdefault(CLASSES_14[label], []).append(sequence[-1, 1] - sequence[0, 1])
    assert np.mean(palm_moves["swipe_left"], axis=0)[1] > 0.03  # +y is the operator's left
    fingers_up = np.mean([np.mean(s[:, 9, 2] - s[:, 0, 2]) for s in data.sequences])
    assert fingers_up > 0.05  # hands held up: the index tip above the wrist


def test_mediapipe_and_leap_mapping():
    landmarks = np.arange(63, dtype=float).reshape(21, 3)
    out = mediapipe_to_canonical(landmarks)
    np.testing.assert_allclose(out[0], landmarks[0])
    np.testing.assert_allclose(out[1], landmarks[[0, 5, 9, 13, 17]].mean(axis=0))
    np.testing.assert_allclose(out[JOINT_NAMES.index("index_tip")], landmarks[8])
    np.testing.assert_allclose(out[JOINT_NAMES.index("thumb_base")], landmarks[1])
    fingers = np.arange(5 * 4 * 3, dtype=float).reshape(5, 4, 3) / 100.0
    leap = leap_to_canonical([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], fingers)
    np.testing.assert_allclose(leap[JOINT_NAMES.index("index_base")], fingers[1, 0])
    np.testing.assert_allclose(leap[JOINT_NAMES.index("index_tip")], fingers[1, 3])
    np.testing.assert_allclose(leap[JOINT_NAMES.index("thumb_base")], fingers[0, 0])
    behind = -np.linalg.norm(fingers[2, 0])
    np.testing.assert_allclose(leap[0], [behind, 0.0, 0.0])  # wrist as far behind as the middle base is ahead
    with pytest.raises(ValueError, match="MediaPipe landmarks"):
        mediapipe_to_canonical(np.zeros((20, 3)))


def test_features_shapes_and_invariance(rng):
    sequence = rng.normal(0.0, 0.05, (47, 22, 3))
    jcd, slow, fast = skeleton_features(sequence)
    assert jcd.shape == (FRAMES, JCD_SIZE) and slow.shape == (FRAMES, MOTION_SIZE)
    assert fast.shape == (FRAMES // 2, MOTION_SIZE)
    moved = sequence @ _rotation_z(0.7).T + np.array([0.3, -0.2, 0.1])
    jcd2, slow2, _ = skeleton_features(moved)
    np.testing.assert_allclose(jcd2, jcd, atol=1e-5)  # distances ignore where and how the hand is turned
    assert not np.allclose(slow2, slow, atol=1e-4)  # global motion keeps the direction
    with pytest.raises(ValueError, match="at least 2 frames"):
        skeleton_features(sequence[:1])


def _write(path, **arrays):
    np.savez(path, **arrays)
    return str(path)


def test_dataset_errors_name_the_array(tmp_path):
    good = {
        "joints": np.zeros((10, 22, 3), np.float32),
        "offsets": np.array([0, 4, 10]),
        "label14": np.array([1, 2], np.int16),
        "label28": np.array([1, 3], np.int16),
        "subject": np.array([5, 6], np.int16),
    }
    data = load_skeleton_dataset(_write(tmp_path / "good.npz", **good))
    assert len(data) == 2 and data.label14.tolist() == [0, 1] and len(data.sequences[1]) == 6
    missing = dict(good)
    del missing["label28"]
    with pytest.raises(MotionSensorError, match="missing array.*label28"):
        load_skeleton_dataset(_write(tmp_path / "missing.npz", **missing))
    with pytest.raises(MotionSensorError, match="'joints' must be"):
        load_skeleton_dataset(_write(tmp_path / "shape.npz", **{**good, "joints": np.zeros((10, 21, 3))}))
    with pytest.raises(MotionSensorError, match="'label14' must hold classes 1-14"):
        load_skeleton_dataset(_write(tmp_path / "range.npz", **{**good, "label14": np.array([0, 15])}))
    with pytest.raises(MotionSensorError, match="'offsets'"):
        load_skeleton_dataset(_write(tmp_path / "offsets.npz", **{**good, "offsets": np.array([0, 4, 9])}))
    with pytest.raises(MotionSensorError, match="no such file"):
        load_skeleton_dataset(str(tmp_path / "absent.npz"))
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(MotionSensorError, match="not a readable"):
        load_skeleton_dataset(str(tmp_path / "text.npz"))


def test_tiny_retrain_learns_user_independently(tiny_model):
    """Seeded: trained on one person of the slice (the shared tiny model), it must
    recognise the other's five gestures far above chance (0.2)."""
    from motion_sensor.gestures.skeleton_training import predict

    model, data, held_out = tiny_model
    train_prob, _ = predict(model, data.subset(~held_out).sequences)
    test_prob, _ = predict(model, data.subset(held_out).sequences)
    assert np.mean(train_prob.argmax(1) == data.label14[~held_out]) >= 0.8
    assert np.mean(test_prob.argmax(1) == data.label14[held_out]) >= 0.6


def test_tiny_model_exports_and_runs_in_onnxruntime(tmp_path, tiny_model):
    from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier
    from motion_sensor.gestures.skeleton_training import export_onnx, predict

    model, data, _ = tiny_model
    path = str(tmp_path / "tiny.onnx")
    export_onnx(model, path)
    torch_prob, _ = predict(model, data.sequences)
    results = SkeletonClassifier(path).classify_batch(data.sequences)
    np.testing.assert_allclose([r.prob14 for r in results], torch_prob, atol=1e-4)
    assert len(set(int(np.argmax(r.prob14)) for r in results)) >= 3  # a trained network, not a constant


def test_shipped_model_classifies_real_sequences():
    from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier

    data = load_skeleton_dataset(SLICE)
    classifier = SkeletonClassifier()
    results = classifier.classify_batch(data.sequences)
    labels = [CLASSES_14[i] for i in data.label14]
    assert results[0].label14 == labels[0] and results[0].confidence > 0.5
    assert np.mean([r.label14 == label for r, label in zip(results, labels, strict=True)]) >= 0.9
    assert np.mean([r.label28 == CLASSES_28[i] for r, i in zip(results, data.label28, strict=True)]) >= 0.8
    with pytest.raises(MotionSensorError, match="not found"):
        SkeletonClassifier("/nonexistent/model.onnx")


def test_gesture_eval_skeleton_cli(tmp_path):
    """gesture_eval --skeleton on the slice: the last line is JSON; a bad file is named."""
    import json
    import subprocess
    import sys

    from ..conftest import ROOT

    script = os.path.join(ROOT, "src", "motion_sensor", "nodes", "gesture_eval")
    done = subprocess.run(
        [sys.executable, script, "--skeleton", "--test", SLICE, "--classes", "28", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["n_test"] == 40 and result["accuracy"] >= 0.8
    assert 0 < result["ms_per_classification_p50"] <= result["ms_per_classification_p99"]
    bad = tmp_path / "bad.npz"
    np.savez(bad, joints=np.zeros((4, 22, 3)), offsets=np.array([0, 4]))
    done = subprocess.run(
        [sys.executable, script, "--skeleton", "--test", str(bad), "--classes", "14"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and "missing array(s) label14, label28, subject" in done.stderr
