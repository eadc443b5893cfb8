"""Pose filters of the sequencer. Positions are filtered in R^3, orientations on the unit
sphere: quaternions are never averaged component-wise and published un-normalised."""

import math
from collections import deque

import numpy as np

from motion_common.float_list import float_list
from motion_common.params import Param, ParamSchema
from motion_sensor.errors import MotionSensorError


def average_quaternions(quats) -> np.ndarray:
    """Mean rotation of quaternions (x, y, z, w) rows, as a unit quaternion.

    Markley's method: the principal eigenvector of sum(q q^T). It is blind to the sign of
    each quaternion (q and -q are the same rotation), so no sign alignment can go wrong.
    """
    rows = [float_list(q) for q in (quats.tolist() if isinstance(quats, np.ndarray) else quats)]
    if not rows or any(len(q) != 4 for q in rows):
        raise ValueError("average_quaternions needs one or more (x, y, z, w) rows")
    gram = _gram(rows)
    newest = rows[-1]
    mean = _principal_vector(gram, newest)
    if mean is None:  # no clear principal direction (quaternions spread widely): exact solver
        _, vectors = np.linalg.eigh(np.array(gram))
        mean = vectors[:, -1].tolist()
    # Keep the sign of the newest sample so consecutive outputs do not flip sign.
    if sum(m * n for m, n in zip(mean, newest)) < 0:
        mean = [-m for m in mean]
    norm = math.sqrt(sum(m * m for m in mean))
    return np.array([m / norm for m in mean])


def _gram(rows) -> list:
    """sum(q q^T) over quaternion rows (lists of 4 floats), as nested lists.

    Plain floats, one pass: on the sequencer's per-frame path (10 rows), numpy's array
    construction and product cost more than the 100 multiply-adds when the caches are cold
    between frames (bench/e2e_latency)."""
    xx = xy = xz = xw = yy = yz = yw = zz = zw = ww = 0.0
    for x, y, z, w in rows:
        xx += x * x
        xy += x * y
        xz += x * z
        xw += x * w
        yy += y * y
        yz += y * z
        yw += y * w
        zz += z * z
        zw += z * w
        ww += w * w
    return [[xx, xy, xz, xw], [xy, yy, yz, yw], [xz, yz, zz, zw], [xw, yw, zw, ww]]


def _principal_vector(gram, start, iterations: int = 50):
    """Principal eigenvector (a list) of the 4x4 ``gram`` (nested lists) by power iteration
    from ``start``, or None when it has not converged within ``iterations``.

    Frames of one hand a few milliseconds apart are close rotations, so the principal
    eigenvalue dwarfs the others and a handful of iterations reach float precision. This
    runs on every frame of the stream: plain floats, since after the pause between two
    frames a numpy call on a 4-vector costs several times its arithmetic, and LAPACK's eigh
    more still (bench/e2e_latency).
    """
    norm = math.sqrt(sum(x * x for x in start))
    v = [x / norm for x in start]
    for _ in range(iterations):
        w = [row[0] * v[0] + row[1] * v[1] + row[2] * v[2] + row[3] * v[3] for row in gram]
        norm = math.sqrt(sum(x * x for x in w))
        if norm == 0.0:
            return None
        w = [x / norm for x in w]
        change = sum((x - y) * (x - y) for x, y in zip(w, v))
        v = w
        if change < 1e-24:
            return v
    return None


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
        # Plain floats (every frame, on its latency): see _principal_vector.
        self._positions.append(float_list(position))
        self._orientations.append(float_list(orientation))
        count = len(self._positions)
        mean_position = np.array([sum(axis) / count for axis in zip(*self._positions)])
        return mean_position, average_quaternions(self._orientations)


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
    still, ``beta`` (Hz per m/s) how fast the cutoff opens with speed, ``dcutoff`` (Hz) the
    smoothing of the speed estimate. The rate comes from the stamps, so irregular frame
    gaps are handled. Orientation uses the same scheme on the unit sphere (slerp toward the
    new sample, cutoff opened by the angular speed in rad/s, ``beta_rot``).

    ``speed_threshold`` (m/s) is the speed the cutoff starts to open at:
    ``cutoff = mincutoff + beta * max(0, speed - speed_threshold)``; the classic filter is
    ``speed_threshold=0``. Why: a hand held "still" is not still. Its tremor and drift
    read 0.02 m/s median and 0.04-0.06 m/s at the 90th-99th percentile on the still
    recordings, while a wave, a flap or a paddle reads 0.12-0.21 m/s median. In the
    classic filter a beta large enough to follow a real move also opens the cutoff on a
    still hand and lets the tremor through. With the threshold the filter is a fixed
    ``mincutoff`` low-pass below it and opens fast above it: on the recordings this gives
    about a quarter of mean-10's lag at its jitter (bench/filter_bench.py). Raise it for an
    operator whose still hand trembles more. Slow moves below it are followed with the
    ``mincutoff`` time constant.

    ``deadband`` (m, default 0 = off) adds a hysteresis stage after the low-pass: the
    output moves only by what the filtered position exceeds that radius around it, so a
    hand held still gives a still output, and a moving one is followed at most
    ``deadband`` behind.

    ``speed_window`` (s, 0 = off) measures the speed that opens the cutoff as the net
    displacement over that window instead: a still hand's tremor goes back and forth and
    nets little, while a slow deliberate move adds up, so slow moves are told from tremor
    sooner and followed with less lag. ``lag_compensation`` (0-1) adds back that fraction of
    the low-pass's own lag on a steady move (the speed times the time constant
    1 / (2 pi cutoff)), never more than ``max_lead`` (m); the lead lives only on each frame's
    output, so a hand that is lost is never extrapolated.

    ``drift_window`` (s, 0 = off) and ``drift_threshold`` (m/s) open the cutoff on a slow
    move that the speed gate misses: the net move over the longer window, once the hand has
    been seen that long, also opens it above its own threshold (``cutoff = mincutoff + beta
    * max(0, speed - speed_threshold, drift - drift_threshold)``). Why: a still hand's palm
    wanders back and forth at up to the gate's speed over 0.2 s (a hand opening and closing
    moves it so), but over a longer window it nets less, while a slow deliberate move keeps
    its speed over any window. The threshold lies above what the still recordings net over that window
    (bench/filter_bench.py), so the still hands recorded there are filtered as without it.
    """

    # Defaults from bench/filter_bench.py on the real recordings: steadier than mean-10
    # with a tenth of its lag on the tuning recordings, and steadier with a third of it on
    # held-out ones (figures in bench/results/filter_bench.json).
    def __init__(
        self,
        mincutoff: float = 3.0,
        beta: float = 1280.0,
        dcutoff: float = 1.0,
        beta_rot: float = 0.5,
        deadband: float = 0.0,
        speed_threshold: float = 0.08,
        speed_window: float = 0.2,
        lag_compensation: float = 0.0,
        max_lead: float = 0.005,
        drift_window: float = 0.3,
        drift_threshold: float = 0.065,
    ):
        for name, value in (("mincutoff", mincutoff), ("dcutoff", dcutoff)):
            if not value > 0:
                raise MotionSensorError(f"one_euro {name} must be > 0 Hz, got {value!r}")
        for name, value in (
            ("beta", beta),
            ("beta_rot", beta_rot),
            ("deadband", deadband),
            ("speed_threshold", speed_threshold),
            ("speed_window", speed_window),
            ("max_lead", max_lead),
            ("drift_window", drift_window),
            ("drift_threshold", drift_threshold),
        ):
            if not value >= 0:
                raise MotionSensorError(f"one_euro {name} must be >= 0, got {value!r}")
        if not 0.0 <= lag_compensation <= 1.0:
            raise MotionSensorError(f"one_euro lag_compensation must be in [0, 1], got {lag_compensation!r}")
        self.mincutoff, self.beta, self.dcutoff, self.beta_rot = mincutoff, beta, dcutoff, beta_rot
        self.deadband = float(deadband)
        self.speed_threshold = float(speed_threshold)
        self.speed_window = float(speed_window)
        self.lag_compensation = float(lag_compensation)
        self.max_lead = float(max_lead)
        self.drift_window = float(drift_window)
        self.drift_threshold = float(drift_threshold)
        self.reset()

    def reset(self) -> None:
        """Forget all history."""
        self._stamp = None
        self._position = None
        self._last_input = None
        self._velocity = np.zeros(3)
        self._orientation = None
        self._angular_speed = 0.0
        self._output = None
        # (stamp, position) of the inputs within speed_window; bounded by time and by count
        # (a 1 kHz device over the longest sensible window).
        self._recent = deque(maxlen=1024)
        self._drift = deque(maxlen=4096)  # the same over drift_window
        self._lead = np.zeros(3)

    def _window_velocity(self, stamp: float, position: np.ndarray) -> np.ndarray:
        """Net displacement over the last ``speed_window`` s divided by its time: a still
        hand's tremor goes back and forth and nets little, a slow move adds up."""
        recent = self._recent
        recent.append((stamp, position))
        while len(recent) > 2 and stamp - recent[1][0] >= self.speed_window:
            recent.popleft()
        start, origin = recent[0]
        return (position - origin) / (stamp - start) if stamp > start else np.zeros(3)

    def _drift_speed(self, stamp: float, position: np.ndarray) -> float:
        """Net move over the last ``drift_window`` s divided by its time; 0 until the hand
        has been seen for the whole window (a short span would read noise as speed)."""
        recent = self._drift
        recent.append((stamp, position))
        while len(recent) > 2 and stamp - recent[1][0] >= self.drift_window:
            recent.popleft()
        start, origin = recent[0]
        if stamp - start < self.drift_window:
            return 0.0
        return float(np.linalg.norm(position - origin)) / (stamp - start)

    def _hysteresis(self) -> np.ndarray:
        if self.deadband == 0.0 or self._output is None:
            self._output = self._position.copy()
            return self._output + self._lead
        excess = self._position - self._output
        distance = float(np.linalg.norm(excess))
        if distance > self.deadband:
            self._output = self._output + excess * (1.0 - self.deadband / distance)
        return self._output + self._lead

    def update(self, stamp: float, position: np.ndarray, orientation: np.ndarray):
        """Filter one pose; return (position, orientation)."""
        position = np.asarray(position, dtype=float)
        orientation = np.asarray(orientation, dtype=float)
        if self._stamp is None:
            self._stamp, self._position, self._orientation = stamp, position.copy(), orientation.copy()
            self._last_input = position.copy()
            if self.speed_window > 0.0:
                self._recent.append((stamp, position.copy()))
            if self.drift_window > 0.0:
                self._drift.append((stamp, position.copy()))
            return self._hysteresis(), self._orientation.copy()
        dt = stamp - self._stamp
        if dt <= 0:
            return self._hysteresis(), self._orientation.copy()
        self._stamp = stamp
        # Position: filtered speed opens the cutoff.
        # Speed from consecutive inputs, as in Casiez and Roussel's reference code (the
        # paper's pseudocode uses the previous output): with a low mincutoff the output
        # trails a still hand's drift, and that trail would read as speed.
        raw_velocity = (position - self._last_input) / dt
        self._last_input = position.copy()
        a_d = _smoothing_factor(dt, self.dcutoff)
        self._velocity = a_d * raw_velocity + (1 - a_d) * self._velocity
        velocity = self._window_velocity(stamp, position.copy()) if self.speed_window > 0.0 else self._velocity
        speed = float(np.linalg.norm(velocity))
        excess = speed - self.speed_threshold
        if self.drift_window > 0.0:
            excess = max(excess, self._drift_speed(stamp, position.copy()) - self.drift_threshold)
        cutoff = self.mincutoff + self.beta * max(0.0, excess)
        a = _smoothing_factor(dt, cutoff)
        self._position = a * position + (1 - a) * self._position
        if self.lag_compensation > 0.0:
            # A first-order low-pass trails a steady move by its time constant times the
            # speed: add that fraction of it back, never more than max_lead. The lead exists
            # only on a frame's own output; without frames (a lost hand) nothing is output.
            lead = self.lag_compensation * velocity / (2.0 * math.pi * cutoff)
            size = float(np.linalg.norm(lead))
            self._lead = lead * (self.max_lead / size) if size > self.max_lead else lead
        # Orientation: the same on the sphere.
        dot = abs(float(np.dot(self._orientation, orientation)))
        raw_angular = 2.0 * np.arccos(min(dot, 1.0)) / dt
        self._angular_speed = a_d * raw_angular + (1 - a_d) * self._angular_speed
        a_rot = _smoothing_factor(dt, self.mincutoff + self.beta_rot * self._angular_speed)
        self._orientation = _slerp(self._orientation, orientation, a_rot)
        return self._hysteresis(), self._orientation.copy()


def _gaussian_log_density(residual: np.ndarray, covariance: np.ndarray) -> float:
    """log N(residual; 0, covariance) through a Cholesky factor."""
    factor = np.linalg.cholesky(covariance)
    whitened = np.linalg.solve(factor, residual)
    return float(
        -0.5 * whitened @ whitened - np.sum(np.log(np.diag(factor))) - 0.5 * len(residual) * np.log(2.0 * np.pi)
    )


_KALMAN_CLASS = None


def _kalman_class():
    """filterpy's KalmanFilter with a faster measurement likelihood.

    The IMM asks each model for its likelihood every frame; filterpy computes it with
    scipy.stats.multivariate_normal, which costs more than the whole filter step (it
    checks and decomposes the covariance generically). The innovation covariance here is
    a 3x3 positive-definite matrix, so a Cholesky factor gives the same number in a
    fraction of the time; should it ever fail, filterpy's own path is used.
    """
    global _KALMAN_CLASS
    if _KALMAN_CLASS is None:
        from filterpy.kalman import KalmanFilter as FilterPyKalman

        class _FastLikelihoodKalman(FilterPyKalman):
            @property
            def log_likelihood(self):
                if self._log_likelihood is None:
                    try:
                        self._log_likelihood = _gaussian_log_density(np.ravel(self.y), self.S)
                    except np.linalg.LinAlgError:
                        return FilterPyKalman.log_likelihood.fget(self)
                return self._log_likelihood

        _KALMAN_CLASS = _FastLikelihoodKalman
    return _KALMAN_CLASS


class KalmanFilter:
    """Constant-velocity Kalman filter (filterpy) on the position, per frame dt from stamps,
    by default as an interacting multiple model (IMM) of a steady and a manoeuvring hand.

    ``process_noise`` is the white-noise acceleration spectral density (m^2/s^3) of the
    steady model, ``measurement_noise`` the position noise (m, standard deviation) the
    filter assumes. ``maneuver_process_noise`` (m^2/s^3) is that of the manoeuvring model;
    0 gives the plain single-model CV filter. ``switch_probability`` is the chance per
    frame that the hand changes between the two.

    Why two models: a single CV filter has one fixed gain, so it either passes the tremor
    of a still hand or lags a real move (on the recordings it is no better than mean-10).
    The IMM weighs the two models by how well each predicts the new frame: tremor fits the
    steady model, which treats it as noise (hence a measurement noise of millimetres, not
    the sensor's 0.3 mm), and a real move fits the manoeuvring one, which follows with
    little lag. The defaults come from bench/filter_bench.py.

    Orientation has no velocity model here; it is smoothed on the sphere as in
    OneEuroFilter (``mincutoff``, ``beta_rot``).
    """

    def __init__(
        self,
        process_noise: float = 1e-5,
        measurement_noise: float = 0.005,
        maneuver_process_noise: float = 10.0,
        switch_probability: float = 0.005,
        mincutoff: float = 1.0,
        beta_rot: float = 0.5,
    ):
        if not process_noise > 0 or not measurement_noise > 0:
            raise MotionSensorError("kalman process_noise and measurement_noise must be > 0")
        if not maneuver_process_noise >= 0:
            raise MotionSensorError("kalman maneuver_process_noise must be >= 0 (0 = single CV model)")
        if not 0 < switch_probability < 0.5:
            raise MotionSensorError(f"kalman switch_probability must be in (0, 0.5), got {switch_probability!r}")
        self.process_noise = float(process_noise)
        self.measurement_noise = float(measurement_noise)
        self.maneuver_process_noise = float(maneuver_process_noise)
        self.switch_probability = float(switch_probability)
        self._noises = [self.process_noise] + ([self.maneuver_process_noise] if self.maneuver_process_noise else [])
        self._orientation = OneEuroFilter(mincutoff=mincutoff, beta=0.0, beta_rot=beta_rot, speed_threshold=0.0)
        # filterpy takes seconds to import (it pulls in scipy.stats): do it now, at start-up,
        # not on the first frame, where it would stall the stream and go stale.
        from filterpy.kalman import IMMEstimator

        self._imm_class = IMMEstimator
        self._model_class = _kalman_class()
        self.reset()

    def reset(self) -> None:
        """Forget all history."""
        self._stamp = None
        self._models = []
        self._imm = None
        self._orientation.reset()

    @property
    def maneuver_probability(self) -> float:
        """Probability (0..1) the IMM gives the manoeuvring model now; 0 for a single model."""
        return float(self._imm.mu[1]) if self._imm is not None else 0.0

    def _seed(self, position: np.ndarray) -> None:
        self._models = []
        for _ in self._noises:
            kf = self._model_class(dim_x=6, dim_z=3)
            kf.H = np.hstack([np.eye(3), np.zeros((3, 3))])
            kf.R = np.eye(3) * self.measurement_noise**2
            kf.x = np.concatenate([position, np.zeros(3)])
            kf.P = np.diag([self.measurement_noise**2] * 3 + [1.0] * 3)
            self._models.append(kf)
        self._imm = None
        if len(self._models) == 2:
            p = self.switch_probability
            self._imm = self._imm_class(self._models, np.array([0.9, 0.1]), np.array([[1 - p, p], [p, 1 - p]]))

    def update(self, stamp: float, position: np.ndarray, orientation: np.ndarray):
        """Filter one pose; return (position, orientation)."""
        position = np.asarray(position, dtype=float)
        _, filtered_orientation = self._orientation.update(stamp, position, orientation)
        if self._stamp is None:
            self._seed(position)
            self._stamp = stamp
            return position.copy(), filtered_orientation
        estimator = self._imm if self._imm is not None else self._models[0]
        dt = stamp - self._stamp
        if dt <= 0:
            return estimator.x[:3].copy(), filtered_orientation
        self._stamp = stamp
        transition = np.eye(6)
        transition[:3, 3:] = np.eye(3) * dt
        # Continuous white-noise acceleration model discretised over this frame's dt.
        block = np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        for kf, q in zip(self._models, self._noises):
            kf.F = transition
            kf.Q = np.kron(block * q, np.eye(3))
        estimator.predict()
        estimator.update(position)
        estimate = estimator.x[:3].copy()
        if not np.all(np.isfinite(estimate)):
            # Numerical breakdown (e.g. both models' likelihoods underflow after a huge
            # accepted move): start again from the measurement rather than publish NaN.
            self._seed(position)
            return position.copy(), filtered_orientation
        return estimate, filtered_orientation


FILTERS["one_euro"] = OneEuroFilter
FILTERS["kalman"] = KalmanFilter


# Every filter's parameters with units and ranges: sequencer.yaml's ``filter_params`` is
# checked against these (an unknown key stops the sequencer). The defaults are the
# constructors' (a unit test keeps them equal).
FILTER_PARAMS = ParamSchema(
    [
        Param(
            "mean",
            {},
            doc="MeanFilter",
            schema=ParamSchema(
                [
                    Param("queue_size", 10, unit="frames", low=1, high=10000, doc="poses averaged"),
                ]
            ),
        ),
        Param(
            "one_euro",
            {},
            doc="OneEuroFilter",
            schema=ParamSchema(
                [
                    Param(
                        "mincutoff",
                        3.0,
                        unit="Hz",
                        low=0,
                        low_open=True,
                        doc="cutoff while slower than speed_threshold",
                    ),
                    Param(
                        "beta", 1280.0, unit="Hz per m/s", low=0, doc="cutoff growth with speed above speed_threshold"
                    ),
                    Param("dcutoff", 1.0, unit="Hz", low=0, low_open=True, doc="smoothing of the speed estimate"),
                    Param("beta_rot", 0.5, unit="Hz per rad/s", low=0, doc="cutoff growth with turn rate"),
                    Param("deadband", 0.0, unit="m", low=0, doc="hysteresis after the low-pass (0 = off)"),
                    Param(
                        "speed_threshold",
                        0.08,
                        unit="m/s",
                        low=0,
                        doc="speed below which the cutoff stays at mincutoff",
                    ),
                    Param(
                        "speed_window",
                        0.2,
                        unit="s",
                        low=0,
                        high=1.0,
                        doc="speed as the net move over this window (0: consecutive inputs smoothed at dcutoff)",
                    ),
                    Param(
                        "lag_compensation",
                        0.0,
                        unit="fraction",
                        low=0,
                        high=1.0,
                        doc="part of the low-pass's lag on a steady move added back (speed x time constant)",
                    ),
                    Param("max_lead", 0.005, unit="m", low=0, doc="largest lag compensation"),
                    Param(
                        "drift_window",
                        0.3,
                        unit="s",
                        low=0,
                        high=2.0,
                        doc="a slow move as the net move over this longer window also opens the cutoff (0: off)",
                    ),
                    Param(
                        "drift_threshold",
                        0.065,
                        unit="m/s",
                        low=0,
                        doc="net speed over drift_window above which the cutoff opens",
                    ),
                ]
            ),
        ),
        Param(
            "kalman",
            {},
            doc="KalmanFilter (IMM of a steady and a manoeuvring model)",
            schema=ParamSchema(
                [
                    Param(
                        "process_noise",
                        1e-5,
                        unit="m^2/s^3",
                        low=0,
                        low_open=True,
                        doc="steady constant-velocity model",
                    ),
                    Param(
                        "measurement_noise", 0.005, unit="m", low=0, low_open=True, doc="what the steady model ignores"
                    ),
                    Param(
                        "maneuver_process_noise",
                        10.0,
                        unit="m^2/s^3",
                        low=0,
                        doc="manoeuvring model (0 = single CV model)",
                    ),
                    Param(
                        "switch_probability",
                        0.005,
                        unit="per frame",
                        low=0,
                        low_open=True,
                        high=0.4999,
                        doc="between the two models",
                    ),
                    Param("mincutoff", 1.0, unit="Hz", low=0, low_open=True, doc="orientation low-pass cutoff"),
                    Param("beta_rot", 0.5, unit="Hz per rad/s", low=0, doc="orientation cutoff growth with turn rate"),
                ]
            ),
        ),
    ]
)
