"""SHREC'17-layout skeleton gesture files (.npz), checked on load.

A file holds ``joints`` (frames, 22, 3) metres in the SHREC camera frame, ``offsets``
(n + 1,) so that sequence i is ``joints[offsets[i]:offsets[i + 1]]``, and per sequence
``label14`` (1-14), ``label28`` (1-28) and ``subject``; ``gesture``, ``finger`` and
``essai`` may be there too. Sequences come out in the canonical REP 103 frame
(``motion_sensor.skeleton_joints``), labels 0-based. A missing or malformed array raises
``MotionSensorError`` naming the file and the array.
"""

import os
from dataclasses import dataclass

import numpy as np

from motion_sensor.errors import MotionSensorError
from motion_sensor.skeleton_joints import N_JOINTS, shrec_to_canonical

__all__ = ["GESTURES_14", "CLASSES_14", "CLASSES_28", "SkeletonDataset", "load_skeleton_dataset", "save_skeleton_npz"]

GESTURES_14 = (
    "grab",
    "tap",
    "expand",
    "pinch",
    "rotation_cw",
    "rotation_ccw",
    "swipe_right",
    "swipe_left",
    "swipe_up",
    "swipe_down",
    "swipe_x",
    "swipe_plus",
    "swipe_v",
    "shake",
)
CLASSES_14 = GESTURES_14
# label28 = 2 * (gesture - 1) + finger: one finger first, then the whole hand.
CLASSES_28 = tuple(f"{g}_{way}" for g in GESTURES_14 for way in ("one_finger", "whole_hand"))
_REQUIRED = ("joints", "offsets", "label14", "label28", "subject")


@dataclass
class SkeletonDataset:
    """Segmented sequences (canonical frame) with 0-based labels and subject ids."""

    sequences: list
    label14: np.ndarray
    label28: np.ndarray
    subject: np.ndarray
    source: str = ""

    def __len__(self):
        return len(self.sequences)

    def subset(self, mask):
        """The sequences where the boolean ``mask`` is true."""
        mask = np.asarray(mask, dtype=bool)
        return SkeletonDataset(
            [s for s, keep in zip(self.sequences, mask, strict=True) if keep],
            self.label14[mask],
            self.label28[mask],
            self.subject[mask],
            self.source,
        )


def _fail(path, message):
    raise MotionSensorError(f"{path}: {message}")


def load_skeleton_dataset(path):
    """Read and check a SHREC'17-layout .npz; see the module doc."""
    if not os.path.isfile(path):
        _fail(path, "no such file (expected a SHREC'17-layout .npz)")
    try:
        data = np.load(path, allow_pickle=False)
        arrays = {name: data[name] for name in data.files}
    except Exception as exc:  # noqa: BLE001 - any unreadable file is the same user error
        _fail(path, f"not a readable .npz file ({exc})")
    missing = [name for name in _REQUIRED if name not in arrays]
    if missing:
        _fail(path, f"missing array(s) {', '.join(missing)} (has: {', '.join(sorted(arrays)) or 'none'})")
    joints, offsets = arrays["joints"], arrays["offsets"]
    if joints.ndim != 3 or joints.shape[1:] != (N_JOINTS, 3):
        _fail(path, f"array 'joints' must be (frames, {N_JOINTS}, 3), got {joints.shape}")
    if not np.issubdtype(joints.dtype, np.number) or not np.all(np.isfinite(joints)):
        _fail(path, "array 'joints' must hold finite numbers")
    if offsets.ndim != 1 or len(offsets) < 2 or not np.issubdtype(offsets.dtype, np.integer):
        _fail(path, f"array 'offsets' must be 1-D integers with at least 2 entries, got {offsets.shape}")
    if offsets[0] != 0 or offsets[-1] != len(joints) or np.any(np.diff(offsets) < 2):
        _fail(path, "array 'offsets' must start at 0, end at len(joints) and give sequences of >= 2 frames")
    count = len(offsets) - 1
    for name, top in (("label14", 14), ("label28", 28), ("subject", None)):
        values = arrays[name]
        if values.shape != (count,) or not np.issubdtype(values.dtype, np.integer):
            _fail(path, f"array '{name}' must be {count} integers (one per sequence), got {values.shape}")
        if top is not None and (values.min() < 1 or values.max() > top):
            _fail(path, f"array '{name}' must hold classes 1-{top}, got {values.min()}-{values.max()}")
    canonical = shrec_to_canonical(joints)
    sequences = [canonical[offsets[i] : offsets[i + 1]] for i in range(count)]
    return SkeletonDataset(
        sequences,
        arrays["label14"].astype(np.int64) - 1,
        arrays["label28"].astype(np.int64) - 1,
        arrays["subject"].astype(np.int64),
        path,
    )


def save_skeleton_npz(path, joints_list, label14, label28, subject, **extra):
    """Write sequences (SHREC camera frame) as a SHREC'17-layout .npz, atomically."""
    lengths = [len(j) for j in joints_list]
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    tmp = f"{path}.tmp.npz"
    np.savez_compressed(
        tmp,
        joints=np.concatenate(joints_list).astype(np.float32),
        offsets=offsets,
        label14=np.asarray(label14, dtype=np.int16),
        label28=np.asarray(label28, dtype=np.int16),
        subject=np.asarray(subject, dtype=np.int16),
        **extra,
    )
    os.replace(tmp, path)
