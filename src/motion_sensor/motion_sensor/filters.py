"""Pose filters of the sequencer. Positions are filtered in R^3, orientations on the unit
sphere: quaternions are never averaged component-wise and published un-normalised."""
from collections import deque

import numpy as np

from .errors import MotionSensorError


def average_quaternions(quats: np.ndarray) -> np.ndarray:
    """Mean rotation of quaternions (x, y, z, w) rows, as a unit quaternion.

    Markley's method: the principal eigenvector of sum(q q^T). It is blind to the sign of
    each quaternion (q and -q are the same rotation), so no sign alignment can go wrong.
    """
    quats = np.asarray(quats, dtype=float)
    _, vectors = np.linalg.eigh(quats.T @ quats)
    mean = vectors[:, -1]
    # Keep the sign of the newest sample so consecutive outputs do not flip sign.
    if np.dot(mean, quats[-1]) < 0:
        mean = -mean
    return mean / np.linalg.norm(mean)


class MeanFilter:
    """The paper's moving-average filter over the last ``queue_size`` poses (default 10)."""

    def __init__(self, queue_size: int = 10):
        if not isinstance(queue_size, int) or queue_size < 1:
            raise MotionSensorError(f"mean filter queue_size must be an integer >= 1, got {queue_size!r}")
        self.queue_size = queue_size
        self._positions = deque(maxlen=queue_size)
        self._orientations = deque(maxlen=queue_size)

    def reset(self) -> None:
        """Forget all history, e.g. when a different hand appears."""
        self._positions.clear()
        self._orientations.clear()

    def update(self, stamp: float, position: np.ndarray, orientation: np.ndarray):
        """Add a pose and return the filtered (position, orientation)."""
        del stamp  # a moving average is rate-blind by definition
        self._positions.append(np.asarray(position, dtype=float))
        self._orientations.append(np.asarray(orientation, dtype=float))
        return np.mean(self._positions, axis=0), average_quaternions(np.array(self._orientations))


FILTERS = {"mean": MeanFilter}


def make_filter(name: str, **params):
    """Build a pose filter by name (see FILTERS) with its parameters."""
    try:
        cls = FILTERS[name]
    except KeyError:
        raise MotionSensorError(f"unknown filter {name!r}; choose one of {sorted(FILTERS)}") from None
    try:
        return cls(**params)
    except TypeError as exc:
        raise MotionSensorError(f"bad parameters for filter {name!r}: {exc}") from None
