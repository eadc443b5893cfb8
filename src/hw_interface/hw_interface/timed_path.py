"""A timed joint path (FOLLOW_PATH) checked as a whole before anything moves, and sampled
by the driver's own clock (plain Python: the dispatcher checks it, the drivers sample it,
tests feed it their own times).

A client that streams SET_JOINTS bends the arm's path whenever it, or the server handing
a target on, is held up (on a busy machine 10-90 ms); a path sent once and sampled by the
driver's control loop, as ros_control's joint_trajectory_controller does, cannot be bent
by either.

Between samples the path is a cubic Hermite curve with PCHIP's slopes (Fritsch-Carlson,
scipy's PchipInterpolator) at the inner samples and zero slope at the first and last: it
never overshoots a sample (so the joint limits checked at the samples hold between them),
it is C1 (no speed jump for the servo), and it starts and ends at rest (an arm at rest
before, holding the end after). Linear interpolation would have a speed jump at every
sample (unbounded acceleration between 10 fps samples); a natural spline overshoots. Its
speed and acceleration are checked exactly, per interval, from the cubic's coefficients.
"""

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

from .errors import HwInterfaceError
from .protocol import Result

__all__ = ["TimedPath", "check_timed_path", "check_path_start", "MAX_PATH_SAMPLES", "MAX_PATH_DURATION", "START_BLEND"]

#: Most samples one path may hold: 10 minutes at 100 Hz (6 joints: 360000 float32 on the
#: wire, ~1.4 MB). Longer demonstrations are sent in several paths.
MAX_PATH_SAMPLES = 60000
#: s: the longest path (times in milliseconds by mistake would otherwise pass as a path a
#: thousand times slower, blocking the robot for hours).
MAX_PATH_DURATION = 3600.0
#: s: a path eases from the measured joints onto its first sample over this time (a
#: smoothstep), so its first command is where the arm is, never a step.
START_BLEND = 0.25


class TimedPath:
    """Joints ``joints`` (n x dof) at ``times`` (s from the start, first 0, strictly
    increasing; n >= 2), already checked (``check_timed_path``)."""

    def __init__(self, times, joints):
        self.times = np.asarray(times, dtype=np.float64)
        self.joints = np.asarray(joints, dtype=np.float64)
        slopes = PchipInterpolator(self.times, self.joints, axis=0).derivative()(self.times)
        slopes[0] = slopes[-1] = 0.0
        self._curve = CubicHermiteSpline(self.times, self.joints, slopes, axis=0)
        self._speed = self._curve.derivative()
        self._offset = np.zeros(self.joints.shape[1])  # measured joints - first sample
        self._blend = 0.0

    def start_from(self, measured, blend: float = START_BLEND) -> tuple[np.ndarray, np.ndarray]:
        """Begin at the ``measured`` joints instead of the first sample, easing onto the
        path over its first ``blend`` s (at most its duration) with a smoothstep (C1, no
        speed step); return the (speed, acceleration) that the easing adds at most, per
        joint (1.5 and 6 times the gap over blend and blend squared)."""
        self._offset = np.asarray(measured, dtype=np.float64) - self.joints[0]
        self._blend = min(float(blend), self.duration)
        gap = np.abs(self._offset)
        return gap * 1.5 / self._blend, gap * 6.0 / self._blend**2

    def _easing(self, t: float) -> tuple[float, float]:
        """(weight of the start offset, its rate per s) at ``t``."""
        if self._blend <= 0.0 or t >= self._blend:
            return 0.0, 0.0
        x = max(t, 0.0) / self._blend
        return 1.0 - x * x * (3.0 - 2.0 * x), -6.0 * x * (1.0 - x) / self._blend

    @property
    def duration(self) -> float:
        """Seconds from the first sample to the last."""
        return float(self.times[-1])

    @property
    def start(self) -> np.ndarray:
        """The first joint sample."""
        return self.joints[0].copy()

    @property
    def end(self) -> np.ndarray:
        """The last joint sample: held after the path's end."""
        return self.joints[-1].copy()

    def sample(self, t: float) -> np.ndarray:
        """Joint target at ``t`` s from the start (the start before, the last sample after)."""
        t = float(t)
        weight, _ = self._easing(t)
        return self._curve(min(max(t, 0.0), self.duration)) + weight * self._offset

    def velocity(self, t: float) -> np.ndarray:
        """Joint velocity (rad/s) of the curve at ``t`` (0 outside the path)."""
        if not 0.0 < t < self.duration:
            return np.zeros(self.joints.shape[1])
        _, rate = self._easing(float(t))
        return self._speed(float(t)) + rate * self._offset

    def peaks(self) -> tuple[np.ndarray, np.ndarray]:
        """(largest |speed|, largest |acceleration|) of each interval and joint, (n-1) x dof:
        exact for the cubic (its speed is a parabola, its acceleration a line per interval)."""
        c = self._curve.c  # (4, n-1, dof): c0 x^3 + c1 x^2 + c2 x + c3, x = t - times[i]
        h = np.diff(self.times)[:, None]
        speed_ends = np.maximum(np.abs(c[2]), np.abs(3 * c[0] * h * h + 2 * c[1] * h + c[2]))
        with np.errstate(divide="ignore", invalid="ignore"):
            vertex = np.where(c[0] != 0.0, -c[1] / (3 * c[0]), -1.0)
        inside = (vertex > 0.0) & (vertex < h)
        at_vertex = np.where(inside, np.abs(3 * c[0] * vertex * vertex + 2 * c[1] * vertex + c[2]), 0.0)
        acceleration = np.maximum(np.abs(2 * c[1]), np.abs(6 * c[0] * h + 2 * c[1]))
        return np.maximum(speed_ends, at_vertex), acceleration


def _refuse(result: Result, reason: str):
    raise HwInterfaceError(f"FOLLOW_PATH refused: {reason}", result)


def check_timed_path(
    times,
    joints,
    joint_names,
    limits,
    max_speed,
    max_acceleration,
    max_samples: int = MAX_PATH_SAMPLES,
) -> TimedPath:
    """The TimedPath of ``times`` (n) and ``joints`` (n x dof, flat or not, the robot's
    joint order), or HwInterfaceError with the Result and a reason naming the sample that
    fails: size, lengths, finite, times, joint ``limits`` ((lower, upper)) at every sample,
    speed and acceleration of the driver's interpolation against ``max_speed`` (rad/s) and
    ``max_acceleration`` (rad/s^2, per joint or one value)."""
    dof = len(joint_names)
    count = len(times)
    if count < 2:
        _refuse(Result.WRONG_LENGTH, f"a path needs at least 2 samples (times), got {count}")
    if count > max_samples:
        _refuse(Result.WRONG_LENGTH, f"{count} samples: a path holds at most {max_samples}; send it in parts")
    flat = np.asarray(joints, dtype=np.float64).ravel()
    if flat.size != count * dof:
        _refuse(
            Result.WRONG_LENGTH,
            f"joints needs {count} samples x {dof} joints = {count * dof} values for {count} times, got {flat.size}",
        )
    t = np.asarray(times, dtype=np.float64)
    q = flat.reshape(count, dof)
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        _refuse(Result.NOT_FINITE, f"times[{bad[0]}] is {t[bad[0]]}")
    bad = np.flatnonzero(~np.all(np.isfinite(q), axis=1))
    if bad.size:
        _refuse(Result.NOT_FINITE, f"sample {bad[0]} (t={t[bad[0]]:.3f} s) has NaN or inf joints: {q[bad[0]].tolist()}")
    if t[0] != 0.0:
        _refuse(Result.WRONG_LENGTH, f"times[0] is {t[0]:g} s: a path's times count from its start, 0")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        i = bad[0] + 1
        _refuse(Result.WRONG_LENGTH, f"times must increase strictly: sample {i} at {t[i]:g} s after {t[i - 1]:g} s")
    if t[-1] > MAX_PATH_DURATION:
        _refuse(
            Result.WRONG_LENGTH,
            f"the path lasts {t[-1]:g} s, over the {MAX_PATH_DURATION:g} s a path may (times are in seconds)",
        )
    lower, upper = (np.asarray(v, dtype=np.float64) for v in limits)
    outside = (q < lower) | (q > upper)
    if outside.any():
        i, j = np.argwhere(outside)[0]
        _refuse(
            Result.JOINT_LIMIT,
            f"sample {i} (t={t[i]:.3f} s): {joint_names[j]} at {q[i, j]:.4f} outside its limits "
            f"{lower[j]:.4f}..{upper[j]:.4f}",
        )
    path = TimedPath(t, q)
    speeds, accelerations = path.peaks()
    for peaks, limit, what, unit in (
        (speeds, max_speed, "speed", "rad/s"),
        (accelerations, max_acceleration, "acceleration", "rad/s^2"),
    ):
        allowed = np.broadcast_to(np.asarray(limit, dtype=np.float64), (dof,))
        over = peaks > allowed
        if over.any():
            i, j = np.argwhere(over)[0]
            _refuse(
                Result.TOO_FAR,
                f"between samples {i} and {i + 1} (t={t[i]:.3f}-{t[i + 1]:.3f} s) {joint_names[j]}'s {what} "
                f"reaches {peaks[i, j]:.3g} {unit}, over the driver's {allowed[j]:.3g} (the curve between samples is "
                "a cubic with PCHIP slopes, at rest at both ends: sample densely, slow down, or start and end slower)",
            )
    return path


def check_path_start(path: TimedPath, measured, joint_names, limits, max_speed, max_acceleration) -> None:
    """Start ``path`` from the ``measured`` joints (TimedPath.start_from), refusing with
    JOINT_LIMIT when the easing onto it could take a joint past its ``limits`` ((lower,
    upper)), and TOO_FAR when, on top of the path's own first ``START_BLEND`` s, it would
    pass the driver's speed or acceleration limits."""
    extra_speed, extra_acceleration = path.start_from(measured)
    speeds, accelerations = path.peaks()
    early = path.times[:-1] < path._blend  # the intervals the easing overlaps
    dof = len(joint_names)
    # The curve stays within its samples; the easing adds at most the offset (weight 0..1).
    reach = path.joints[: int(np.count_nonzero(early)) + 1]
    lower, upper = (np.asarray(v, dtype=np.float64) for v in limits)
    high = reach.max(axis=0) + np.maximum(path._offset, 0.0)
    low = reach.min(axis=0) + np.minimum(path._offset, 0.0)
    outside = np.flatnonzero((high > upper) | (low < lower))
    if outside.size:
        j = outside[0]
        _refuse(
            Result.JOINT_LIMIT,
            f"easing from the measured joints onto the first sample ({path._offset[j]:+.4f} rad away) could take "
            f"{joint_names[j]} to {low[j]:.4f}..{high[j]:.4f}, outside its limits {lower[j]:.4f}..{upper[j]:.4f}: "
            "start the path where the arm is (MOVE_J there first)",
        )
    for peaks, extra, limit, what, unit in (
        (speeds, extra_speed, max_speed, "speed", "rad/s"),
        (accelerations, extra_acceleration, max_acceleration, "acceleration", "rad/s^2"),
    ):
        allowed = np.broadcast_to(np.asarray(limit, dtype=np.float64), (dof,))
        worst = np.max(peaks[early], axis=0) + extra
        over = np.flatnonzero(worst > allowed)
        if over.size:
            j = over[0]
            _refuse(
                Result.TOO_FAR,
                f"easing from the measured joints onto the first sample ({abs(path._offset[j]):.4f} rad away) "
                f"over {path._blend:g} s takes {joint_names[j]}'s {what} to {worst[j]:.3g} {unit}, over the driver's "
                f"{allowed[j]:.3g}: start the path where the arm is (MOVE_J there first)",
            )
