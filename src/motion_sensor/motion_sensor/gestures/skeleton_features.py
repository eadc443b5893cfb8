"""Features of a hand-skeleton gesture, DD-Net style (Yang et al., "Make Skeleton-based
Action Recognition Model Smaller, Faster and Better", 2019).

A sequence of canonical skeletons (``motion_sensor.skeleton_joints``: (L, 22, 3), metres,
REP 103) is resampled to a fixed ``FRAMES`` frames (linear interpolation in time), then:

- ``jcd`` (FRAMES, 231): joint collection distances, the upper triangle of the 22 x 22
  joint distance matrix of each frame (location- and viewpoint-invariant);
- ``slow`` (FRAMES, 66): global motion at the frame scale, the joint displacements
  between consecutive frames, resampled back to FRAMES;
- ``fast`` (FRAMES // 2, 66): global motion at twice the scale, the displacements
  between every other frame.

The three arrays are the inputs of the skeleton network (``skeleton_classifier``).

The network's input frame is REP 103 turned half a turn about x (``MODEL_FROM_REP103``:
y and z negated), the frame the shipped model was trained in; ``to_model_frame`` turns a
canonical sequence into it, and the classifier and the training both call it, so callers
always pass REP 103. No ROS, no torch.
"""

import numpy as np

from motion_sensor.skeleton_joints import N_JOINTS

__all__ = [
    "FRAMES",
    "JCD_SIZE",
    "MOTION_SIZE",
    "MODEL_FROM_REP103",
    "to_model_frame",
    "resample",
    "skeleton_features",
    "batch_features",
]

FRAMES = 32
JCD_SIZE = N_JOINTS * (N_JOINTS - 1) // 2  # 231
MOTION_SIZE = N_JOINTS * 3  # 66
_UPPER = np.triu_indices(N_JOINTS, k=1)
MODEL_FROM_REP103 = np.diag([1.0, -1.0, -1.0])


def to_model_frame(sequence):
    """A canonical (REP 103) sequence (..., 22, 3) in the network's input frame."""
    return np.asarray(sequence, dtype=np.float64) @ MODEL_FROM_REP103.T


def resample(sequence, frames=FRAMES, positions=None):
    """(L, ...) -> (frames, ...) by linear interpolation along time.

    ``positions`` (frames,) are the fractional source frames to sample (default: evenly
    spread over the whole sequence); the training's time warp passes its own.
    """
    seq = np.asarray(sequence, dtype=np.float64)
    length = len(seq)
    if length < 2:
        raise ValueError(f"a skeleton sequence needs at least 2 frames, got {length}")
    if positions is None:
        positions = np.linspace(0.0, length - 1, frames)
    positions = np.clip(np.asarray(positions, dtype=np.float64), 0.0, length - 1)
    low = np.minimum(np.floor(positions).astype(int), length - 2)
    frac = (positions - low).reshape((-1,) + (1,) * (seq.ndim - 1))
    return seq[low] * (1.0 - frac) + seq[low + 1] * frac


def _motion(points, frames):
    diff = points[1:] - points[:-1]
    return resample(diff.reshape(len(diff), -1), frames)


def skeleton_features(sequence, positions=None):
    """Features of one sequence (L, 22, 3) -> (jcd, slow, fast) float32 arrays."""
    seq = np.asarray(sequence, dtype=np.float64)
    if seq.ndim != 3 or seq.shape[1:] != (N_JOINTS, 3):
        raise ValueError(f"a skeleton sequence is (frames, {N_JOINTS}, 3), got shape {seq.shape}")
    points = resample(seq, FRAMES, positions)
    delta = points[:, _UPPER[0]] - points[:, _UPPER[1]]
    jcd = np.sqrt(np.einsum("fjk,fjk->fj", delta, delta))
    slow = _motion(points, FRAMES)
    fast = _motion(points[::2], FRAMES // 2)
    return jcd.astype(np.float32), slow.astype(np.float32), fast.astype(np.float32)


def batch_features(sequences, positions=None):
    """Stacked features of several sequences: (jcd (N, F, 231), slow (N, F, 66), fast (N, F/2, 66))."""
    parts = [skeleton_features(s, None if positions is None else positions[i]) for i, s in enumerate(sequences)]
    if not parts:
        shapes = ((0, FRAMES, JCD_SIZE), (0, FRAMES, MOTION_SIZE), (0, FRAMES // 2, MOTION_SIZE))
        return tuple(np.zeros(s, dtype=np.float32) for s in shapes)
    return tuple(np.stack(arrays) for arrays in zip(*parts, strict=True))
