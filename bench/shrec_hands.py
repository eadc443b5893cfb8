"""Real hand motion for the depth hand bench: a fixed, seeded subset of the SHREC'17
training skeletons (../shared/data/shrec17_train, never copied into the project), split by
subject into a tuning set and a held-out evaluation set, and placed in front of the depth
camera.

Selection (``select``): the 20 subjects are shuffled with the seed; the first half is the
tuning set, the second the evaluation set. From each subject, ``per_subject`` sequences of
different gestures are drawn (seeded), alternating one-finger and whole-hand performances,
so both sets mix subjects, gestures and hand shapes.

Placement (``place``): SHREC's frame is a camera frame (x right, y down, z forward, metres)
whose origin is not on the hand; each sequence is moved rigidly (a translation only: its
motion is untouched) so that its mean palm centre lies on the optical axis, and pushed
``depth_shift_m`` further away, which puts the palms at 0.6-1.0 m, inside the depth
tracker's working volume as for a Kinect-like camera.
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "src", "motion_sensor"))

from motion_sensor.testing.skeleton_depth import place_in_view  # noqa: E402

__all__ = ["SHREC", "Sequence", "load", "select", "place"]

SHREC = os.path.normpath(
    os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "shrec17_train", "shrec17_train.npz")
)


class Sequence:
    """One SHREC sequence: its index, subject, gesture, finger count and joints (n, 22, 3)."""

    def __init__(self, index, subject, gesture, finger, joints):
        self.index, self.subject, self.gesture, self.finger = int(index), int(subject), int(gesture), int(finger)
        self.joints = np.asarray(joints, dtype=float)

    def describe(self) -> dict:
        return {
            "sequence": self.index,
            "subject": self.subject,
            "gesture": self.gesture,
            "finger": self.finger,
            "frames": len(self.joints),
        }


def load(path: str = SHREC):
    """The npz arrays, or None when the shared data is absent."""
    if not os.path.exists(path):
        return None
    return np.load(path)


def select(data, seed: int, per_subject: int) -> tuple[list[Sequence], list[Sequence]]:
    """(tuning, evaluation) sequences; see the module."""
    rng = np.random.default_rng(seed)
    subjects = np.unique(data["subject"])
    subjects = subjects[rng.permutation(len(subjects))]
    half = len(subjects) // 2
    offsets = data["offsets"]
    sets = []
    for group in (subjects[:half], subjects[half:]):
        chosen = []
        for subject in sorted(group.tolist()):
            mine = np.nonzero(data["subject"] == subject)[0]
            mine = mine[rng.permutation(len(mine))]
            gestures = set()
            for k in range(per_subject):
                finger = 1 + (k + subject) % 2
                pick = next(
                    (i for i in mine if data["finger"][i] == finger and data["gesture"][i] not in gestures),
                    None,
                )
                if pick is None:
                    continue
                gestures.add(int(data["gesture"][pick]))
                chosen.append(
                    Sequence(
                        pick,
                        subject,
                        data["gesture"][pick],
                        data["finger"][pick],
                        data["joints"][offsets[pick] : offsets[pick + 1]],
                    )
                )
        sets.append(chosen)
    return sets[0], sets[1]


def place(joints: np.ndarray, depth_shift_m: float = 0.30) -> np.ndarray:
    """The sequence's joints moved so that their mean palm centre is on the optical axis,
    ``depth_shift_m`` further away (see the module)."""
    return place_in_view(joints, depth_shift_m)
