"""``gesture_eval --skeleton``: classify every sequence of a SHREC'17-layout .npz with the
shipped skeleton model (no training) and report accuracy, the confusion and the time per
classification (one sequence at a time, features included, p50/p99).

``--train FILE.npz`` (development) first trains a model on that file with the training
defaults (``skeleton_training``, needs torch), exports it to a temporary ONNX file and
evaluates that one instead.
"""

import os
import sys
import tempfile
import time

import numpy as np

from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, CLASSES_28, load_skeleton_dataset

__all__ = ["evaluate_skeleton", "run_skeleton_eval"]


def evaluate_skeleton(classifier, dataset, classes=14, progress=None):
    """Accuracy, confusion matrix and per-sequence timing of ``classifier`` on ``dataset``."""
    truth = dataset.label14 if classes == 14 else dataset.label28
    names = CLASSES_14 if classes == 14 else CLASSES_28
    matrix = np.zeros((classes, classes), dtype=int)
    times = np.empty(len(dataset))
    classifier.classify(dataset.sequences[0])  # the first run allocates; not timed
    for n, sequence in enumerate(dataset.sequences):
        start = time.perf_counter()
        result = classifier.classify(sequence)
        times[n] = time.perf_counter() - start
        matrix[truth[n], result.index(classes)] += 1
        if progress and (n + 1) % 200 == 0:
            progress(f"{n + 1}/{len(dataset)} classified, running accuracy {np.trace(matrix) / (n + 1):.4f}")
    ms = times * 1000.0
    return {
        "accuracy": round(float(np.trace(matrix) / len(dataset)), 6),
        "ms_per_classification_p50": round(float(np.percentile(ms, 50)), 4),
        "ms_per_classification_p99": round(float(np.percentile(ms, 99)), 4),
        "n_test": len(dataset),
        "n_subjects": len(set(dataset.subject.tolist())),
        "classes": list(names),
        "confusion": matrix.tolist(),
    }


def _log(message):
    print(f"gesture_eval: {message}", file=sys.stderr, flush=True)


def run_skeleton_eval(test_path, classes, model_path=None, train_path=None):
    """The report dict of ``gesture_eval --skeleton`` (raises MotionSensorError on bad input)."""
    if classes not in (14, 28):
        raise MotionSensorError(f"--classes must be 14 or 28, got {classes}")
    test = load_skeleton_dataset(test_path)
    _log(f"test {test_path}: {len(test)} sequences, {len(set(test.subject.tolist()))} subjects")
    with tempfile.TemporaryDirectory() as folder:
        if train_path:
            from motion_sensor.gestures.skeleton_training import TrainConfig, export_onnx, train_model

            train = load_skeleton_dataset(train_path)
            shared = set(train.subject.tolist()) & set(test.subject.tolist())
            if shared:
                _log(f"warning: subjects {sorted(shared)} are in both files (not user-independent)")
            _log(f"training on {len(train)} sequences (torch, {TrainConfig().epochs} epochs)")
            model_path = os.path.join(folder, "trained.onnx")
            export_onnx(train_model(train, TrainConfig(), _log), model_path)
        classifier = SkeletonClassifier(model_path)
        report = evaluate_skeleton(classifier, test, classes, _log)
    report["model"] = "trained on " + os.path.basename(train_path) if train_path else classifier.model_path
    report["model_bytes"] = None if train_path else os.path.getsize(classifier.model_path)
    return report
