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


def _slerp(q0: np.ndarray, q1: np.ndarray, fraction: float) -> np.ndarray:
    """Slerp between unit quaternions (x, y, z, w), the short way, renormalised."""
    dot = float(np.dot(q0, q1))
    if dot < 0.0:  # q and -q are the same rotation: take the short arc
        q1, dot = -q1, -dot
    if dot > 0.9995:  # nearly equal: linear blend is exact to float precision
        out = q0 + fraction * (q1 - q0)
    else:
        theta = np.arccos(min(dot, 1.0))
        out = (np.sin((1 - fraction) * theta) * q0 + np.sin(fraction * theta) * q1) / np.sin(theta)
    return out / np.linalg.norm(out)


def _smoothing_factor(dt: float, cutoff: float) -> float:
    """Exponential smoothing factor of a first-order low-pass at ``cutoff`` Hz."""
    tau = 1.0 / (2.0 * np.pi * cutoff)
    return 1.0 / (1.0 + tau / dt)


class OneEuroFilter:
    """The One Euro filter (Casiez, Roussel, Vogel, CHI 2012) for a pose.

    A low-pass whose cutoff rises with speed: ``mincutoff`` (Hz) sets the smoothing when
    still, ``beta`` (s/m for positions) how fast the cutoff opens with speed, ``dcutoff``
    (Hz) the smoothing of the speed estimate. The rate comes from the stamps, so irregular
    frame gaps are handled. Orientation uses the same scheme on the unit sphere (slerp
    toward the new sample, cutoff opened by the angular speed in rad/s, ``beta_rot``).

    ``deadband`` (m, default 0 = off) adds a hysteresis stage after the low-pass: the
    output moves only by what the filtered position exceeds that radius around it, so a
    hand held still gives a still output, and a moving one is followed at most
    ``deadband`` behind.
    """

    # Defaults from bench/filter_bench.py on the real recordings: steadier than mean-10
    # (0.37 vs 0.44 mm jitter) with about half its lag (5.4 vs 9.8 mm).
    def __init__(self, mincutoff: float = 1.0, beta: float = 40.0, dcutoff: float = 0.3, beta_rot: float = 0.5,
                 deadband: float = 0.0):
        for name, value in (("mincutoff", mincutoff), ("dcutoff", dcutoff)):
            if not value > 0:
                raise MotionSensorError(f"one_euro {name} must be > 0 Hz, got {value!r}")
        if beta < 0 or beta_rot < 0 or deadband < 0:
            raise MotionSensorError("one_euro beta, beta_rot and deadband must be >= 0")
        self.mincutoff, self.beta, self.dcutoff, self.beta_rot = mincutoff, beta, dcutoff, beta_rot
        self.deadband = float(deadband)
        self.reset()

    def reset(self) -> None:
        """Forget all history."""
        self._stamp = None
        self._position = None
        self._velocity = np.zeros(3)
        self._orientation = None
        self._angular_speed = 0.0
        self._output = None

    def _hysteresis(self) -> np.ndarray:
        if self.deadband == 0.0 or self._output is None:
            self._output = self._position.copy()
            return self._output.copy()
        excess = self._position - self._output
        distance = float(np.linalg.norm(excess))
        if distance > self.deadband:
            self._output = self._output + excess * (1.0 - self.deadband / distance)
        return self._output.copy()

    def update(self, stamp: float, position: np.ndarray, orientation: np.ndarray):
        """Filter one pose; return (position, orientation)."""
        position = np.asarray(position, dtype=float)
        orientation = np.asarray(orientation, dtype=float)
        if self._stamp is None:
            self._stamp, self._position, self._orientation = stamp, position.copy(), orientation.copy()
            return self._hysteresis(), self._orientation.copy()
        dt = stamp - self._stamp
        if dt <= 0:
            return self._hysteresis(), self._orientation.copy()
        self._stamp = stamp
        # Position: filtered speed opens the cutoff.
        raw_velocity = (position - self._position) / dt
        a_d = _smoothing_factor(dt, self.dcutoff)
        self._velocity = a_d * raw_velocity + (1 - a_d) * self._velocity
        cutoff = self.mincutoff + self.beta * float(np.linalg.norm(self._velocity))
        a = _smoothing_factor(dt, cutoff)
        self._position = a * position + (1 - a) * self._position
        # Orientation: the same on the sphere.
        dot = abs(float(np.dot(self._orientation, orientation)))
        raw_angular = 2.0 * np.arccos(min(dot, 1.0)) / dt
        self._angular_speed = a_d * raw_angular + (1 - a_d) * self._angular_speed
        a_rot = _smoothing_factor(dt, self.mincutoff + self.beta_rot * self._angular_speed)
        self._orientation = _slerp(self._orientation, orientation, a_rot)
        return self._hysteresis(), self._orientation.copy()


class KalmanFilter:
    """Constant-velocity Kalman filter (filterpy) on the position, per frame dt from stamps.

    ``process_noise`` is the white-noise acceleration spectral density (m^2/s^3),
    ``measurement_noise`` the position noise (m, standard deviation). Orientation has no
    velocity model here; it is smoothed on the sphere as in OneEuroFilter (``mincutoff``,
    ``beta_rot``).
    """

    # Defaults from bench/filter_bench.py: 0.56 mm jitter, 6.3 mm lag on the recordings.
    def __init__(self, process_noise: float = 1e-4, measurement_noise: float = 3e-4, mincutoff: float = 1.0,
                 beta_rot: float = 0.5):
        from filterpy.kalman import KalmanFilter as FilterPyKalman  # imported here: only this filter needs it
        if not process_noise > 0 or not measurement_noise > 0:
            raise MotionSensorError("kalman process_noise and measurement_noise must be > 0")
        self.process_noise = float(process_noise)
        self.measurement_noise = float(measurement_noise)
        self._kf = FilterPyKalman(dim_x=6, dim_z=3)
        self._kf.H = np.hstack([np.eye(3), np.zeros((3, 3))])
        self._kf.R = np.eye(3) * self.measurement_noise ** 2
        self._orientation = OneEuroFilter(mincutoff=mincutoff, beta=0.0, beta_rot=beta_rot)
        self.reset()

    def reset(self) -> None:
        """Forget all history."""
        self._stamp = None
        self._orientation.reset()

    def update(self, stamp: float, position: np.ndarray, orientation: np.ndarray):
        """Filter one pose; return (position, orientation)."""
        position = np.asarray(position, dtype=float)
        _, filtered_orientation = self._orientation.update(stamp, position, orientation)
        kf = self._kf
        if self._stamp is None:
            kf.x = np.concatenate([position, np.zeros(3)])
            kf.P = np.diag([self.measurement_noise ** 2] * 3 + [1.0] * 3)
            self._stamp = stamp
            return position.copy(), filtered_orientation
        dt = stamp - self._stamp
        if dt <= 0:
            return kf.x[:3].copy(), filtered_orientation
        self._stamp = stamp
        kf.F = np.eye(6)
        kf.F[:3, 3:] = np.eye(3) * dt
        # Continuous white-noise acceleration model discretised over dt.
        q = self.process_noise
        block = np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]]) * q
        kf.Q = np.kron(block, np.eye(3))
        kf.predict()
        kf.update(position)
        return kf.x[:3].copy(), filtered_orientation


FILTERS["one_euro"] = OneEuroFilter
FILTERS["kalman"] = KalmanFilter
