"""The shipped skeleton gesture model (ONNX) run through onnxruntime on the CPU.

``SkeletonClassifier().classify(sequence)`` takes one segmented gesture, canonical
skeletons (``motion_sensor.skeleton_joints``: (frames, 22, 3), metres, REP 103), and
returns a ``SkeletonResult``: the 14-gesture and 28-class (gesture x one finger / whole
hand) probabilities and their best labels. The 14-class answer averages the network's
14-class head with its 28-class head summed over the finger variants. One intra-op
thread by default (a node shares the machine). Training: ``train_skeleton_gestures``.
"""

import os
from dataclasses import dataclass

import numpy as np

from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, CLASSES_28
from motion_sensor.gestures.skeleton_features import batch_features, to_model_frame
from motion_sensor.onnx_session import cpu_session

__all__ = ["DEFAULT_MODEL", "SkeletonResult", "SkeletonClassifier"]

DEFAULT_MODEL = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "data", "skeleton_gestures.onnx"))


@dataclass
class SkeletonResult:
    """Probabilities of one sequence and the best class of each problem."""

    prob14: np.ndarray
    prob28: np.ndarray

    @property
    def label14(self) -> str:
        return CLASSES_14[int(np.argmax(self.prob14))]

    @property
    def label28(self) -> str:
        return CLASSES_28[int(np.argmax(self.prob28))]

    @property
    def confidence(self) -> float:
        """The 14-class winner's probability."""
        return float(np.max(self.prob14))

    def label(self, classes=14):
        return self.label14 if classes == 14 else self.label28

    def index(self, classes=14):
        return int(np.argmax(self.prob14 if classes == 14 else self.prob28))


class SkeletonClassifier:
    """An exported ``SkeletonNet`` (inputs jcd/slow/fast, outputs prob14/prob28)."""

    def __init__(self, model_path=None, threads=1):
        self.model_path = model_path or DEFAULT_MODEL
        if not os.path.isfile(self.model_path):
            raise MotionSensorError(
                f"skeleton gesture model {self.model_path} not found (train one with train_skeleton_gestures)"
            )
        self._session = cpu_session(self.model_path, "skeleton gesture model", threads)
        names = {i.name for i in self._session.get_inputs()}
        if names != {"jcd", "slow", "fast"}:
            raise MotionSensorError(f"{self.model_path}: expected inputs jcd, slow, fast, got {sorted(names)}")

    def classify_batch(self, sequences):
        """Results of several sequences (one onnxruntime run)."""
        jcd, slow, fast = batch_features([to_model_frame(s) for s in sequences])
        prob14, prob28 = self._session.run(["prob14", "prob28"], {"jcd": jcd, "slow": slow, "fast": fast})
        folded = prob28.reshape(len(prob28), 14, 2).sum(axis=2)
        prob14 = 0.5 * (prob14 + folded)
        return [SkeletonResult(p14, p28) for p14, p28 in zip(prob14, prob28, strict=True)]

    def classify(self, sequence):
        """The result of one sequence (frames, 22, 3)."""
        return self.classify_batch([sequence])[0]
