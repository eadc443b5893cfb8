"""Teleop safety rules, after the set moveit_servo has proven (servo_calcs.cpp), as plain
classes the core applies to every command before it leaves for the driver.

Each rule is small and separately testable:
- JointStepLimiter: joint velocity and acceleration limits, one uniform scale per step;
- JointLimitMargin: keeps targets a margin inside the URDF joint limits;
- SingularityGuard: slows down, then halts motion toward a singularity (Jacobian
  condition number);
- WorkspaceFence: a box and a floor plane the tool target is clamped into;
- EngageRamp: the allowed speed ramps from zero after engage or resume (no start-up jerk);
- StaleCommandWatchdog: a command older than the timeout halts the robot.
"""
from dataclasses import dataclass

import numpy as np

from .errors import MotionCommanderError


def braking_speed(distance, acceleration: float, dt: float):
    """Largest speed from which steps of ``dt`` s, decelerating by ``acceleration`` each,
    stop within ``distance`` (element-wise, same unit as distance per s).

    Stopping from v = n a dt covers a dt^2 n (n + 1) / 2 including this step's own move;
    solving for n gives the discrete form of the familiar sqrt(2 a d).
    """
    d = np.abs(np.asarray(distance, dtype=float))
    return acceleration * dt * (np.sqrt(0.25 + 2.0 * d / (acceleration * dt * dt)) - 0.5)


class JointStepLimiter:
    """Limits each command's joint step to the velocity and acceleration limits.

    ``velocity_limits`` in rad/s (m/s for prismatic joints); ``scale`` (0, 1] is the
    fraction of them teleop may use; ``acceleration_limit`` in rad/s^2 (None: no limit).
    The whole step is scaled by one factor, not joint by joint: clipping joints separately
    would change the direction of motion and pull the tool off its path, while a uniform
    scale only makes it lag along the path. With an acceleration limit the step is also
    kept slow enough to stop AT the target (braking_speed): a command catching up with a
    hand that reverses brakes in time instead of running past the reversal point.
    """

    def __init__(self, velocity_limits, scale: float = 0.5, acceleration_limit=None, min_dt: float = 0.002,
                 max_dt: float = 0.05):
        limits = np.asarray(velocity_limits, dtype=float)
        if not (0 < scale <= 1):
            raise MotionCommanderError(f"joint speed scale must be in (0, 1], got {scale!r}")
        if not np.all(np.isfinite(limits)) or np.any(limits <= 0):
            raise MotionCommanderError("every joint needs a finite velocity limit > 0 in the URDF")
        if acceleration_limit is not None and not acceleration_limit > 0:
            raise MotionCommanderError(f"acceleration limit must be > 0 rad/s^2, got {acceleration_limit!r}")
        self.max_velocity = limits * scale
        self.max_acceleration = acceleration_limit
        # dt is clamped: a long gap (hand lost, then back) must not permit a big jump.
        self.min_dt = min_dt
        self.max_dt = max_dt
        self.reset()

    def reset(self) -> None:
        """Start from rest (after engage, resume or a halt)."""
        self._velocity = None
        self._target = None
        self._target_velocity = None

    def observe_target(self, target, dt: float) -> None:
        """Record this frame's unlimited joint target: its velocity lets a command that
        follows a moving target keep pace instead of braking as if it were to stop there."""
        target = np.asarray(target, dtype=float)
        dt = float(np.clip(dt, self.min_dt, self.max_dt))
        self._target_velocity = None if self._target is None else (target - self._target) / dt
        self._target = target

    def _clamped_dt(self, dt: float) -> float:
        return min(max(float(dt), self.min_dt), self.max_dt)

    def _max_step(self, previous: np.ndarray, goal: np.ndarray, dt: float, speed_fraction: float):
        """Largest joint step (abs, per joint) allowed toward ``goal`` this step."""
        max_step = self.max_velocity * (dt * max(speed_fraction, 0.0))
        if self.max_acceleration is None:
            return max_step
        direction = goal - previous
        error = direction
        # Slow enough to stop where the goal itself would stop if it braked as hard as we
        # may: a goal moving on at v stops v^2/2a further on (so we keep pace), a goal
        # slowing down for a reversal brings that point back to its peak (so we brake in
        # time), and a goal already coming back leaves no distance at all (so we brake now).
        if self._target_velocity is not None:
            v = self._target_velocity
            error = direction + v * np.abs(v) / (2.0 * self.max_acceleration)
        room = np.maximum(error * np.sign(direction), 0.0)
        return np.minimum(max_step, braking_speed(room, self.max_acceleration, dt) * dt)

    def overshoot(self, previous, target, dt: float, speed_fraction: float = 1.0, goal=None) -> float:
        """How many times too large the step to ``target`` is for the velocity limit and,
        with an acceleration limit, for stopping at ``goal`` (default: target) (<= 1:
        allowed as is). No side effect."""
        # Runs on every teleop frame: plain float and array operations, no np.clip or
        # np.errstate (their call overhead is larger than this arithmetic).
        previous = np.asarray(previous, dtype=float)
        target = np.asarray(target, dtype=float)
        goal = target if goal is None else np.asarray(goal, dtype=float)
        step = np.abs(target - previous)
        max_step = self._max_step(previous, goal, self._clamped_dt(dt), speed_fraction)
        blocked = max_step <= 0
        if blocked.any():
            if (step[blocked] > 0).any():
                return float("inf")
            max_step = np.where(blocked, np.inf, max_step)  # nothing to do there: ratio 0
        return float((step / max_step).max())

    def limit(self, previous, target, dt: float, speed_fraction: float = 1.0, goal=None, ratio=None):
        """Return (command, limited): previous moved toward target within the limits.

        ``speed_fraction`` in [0, 1] scales the velocity limit (ramps, singularity slow-down).
        ``goal`` is where the motion must be able to stop (default: target); the core
        passes the frame's full IK target when ``target`` is a partial step toward it.
        ``ratio`` is this same step's ``overshoot()``, when the caller has computed it.
        """
        previous = np.asarray(previous, dtype=float)
        step = np.asarray(target, dtype=float) - previous
        dt = self._clamped_dt(dt)
        if ratio is None:
            ratio = self.overshoot(previous, target, dt, speed_fraction, goal)
        limited = ratio > 1.0
        if limited:
            step = step / ratio if np.isfinite(ratio) else np.zeros_like(step)
        if self.max_acceleration is not None:
            previous_velocity = np.zeros_like(step) if self._velocity is None else self._velocity
            dv = step / dt - previous_velocity
            excess = float(np.max(np.abs(dv)) / (self.max_acceleration * dt))
            if excess > 1.0:
                step = (previous_velocity + dv / excess) * dt
                limited = True
        self._velocity = step / dt
        return previous + step, limited


class JointLimitMargin:
    """Clips joint targets to the URDF limits shrunk by ``margin`` (rad)."""

    def __init__(self, lower, upper, margin: float = 0.05):
        self.lower = np.asarray(lower, dtype=float) + margin
        self.upper = np.asarray(upper, dtype=float) - margin
        if np.any(self.lower >= self.upper):
            raise MotionCommanderError(f"joint limit margin {margin} rad leaves no range for some joint")

    def apply(self, joints):
        """Return (clipped joints, whether any joint was clipped)."""
        q = np.asarray(joints, dtype=float)
        clipped = np.minimum(np.maximum(q, self.lower), self.upper)  # np.clip's dispatch costs more
        return clipped, bool((clipped != q).any())


class SingularityGuard:
    """Scales motion down as the Jacobian's condition number rises, as moveit_servo does.

    Below ``slowdown_threshold`` full speed; between it and ``halt_threshold`` the speed
    falls linearly to zero for motion that increases the condition number; at or above
    ``halt_threshold`` such motion halts. Motion away from the singularity is never slowed,
    so the operator can always back out.
    """

    def __init__(self, slowdown_threshold: float = 40.0, halt_threshold: float = 80.0):
        if not 1.0 <= slowdown_threshold < halt_threshold:
            raise MotionCommanderError("singularity thresholds need 1 <= slowdown < halt")
        self.slowdown = slowdown_threshold
        self.halt = halt_threshold

    def speed_fraction(self, condition_now: float, condition_next: float) -> float:
        """Allowed fraction of full speed for a step from condition_now to condition_next."""
        if condition_next <= condition_now or condition_next < self.slowdown:
            return 1.0
        if condition_next >= self.halt:
            return 0.0
        return float((self.halt - condition_next) / (self.halt - self.slowdown))


def condition_number(jacobian) -> float:
    """Condition number of the full 6 x n Jacobian, as moveit_servo computes it.

    The translational rows alone miss wrist and elbow singularities of arms whose wrist
    offsets still give translation, so all six rows are used.
    """
    singular = np.linalg.svd(np.asarray(jacobian), compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 1e-12 else float("inf")


@dataclass
class WorkspaceFence:
    """Box (m, robot base frame) and floor height the tool target must stay within."""

    lower: np.ndarray
    upper: np.ndarray
    floor_z: float = 0.0

    def __post_init__(self):
        self.lower = np.asarray(self.lower, dtype=float)
        self.upper = np.asarray(self.upper, dtype=float)
        if self.lower.shape != (3,) or self.upper.shape != (3,) or np.any(self.lower >= self.upper):
            raise MotionCommanderError("workspace box needs lower < upper, 3 values each (m)")
        # The box's lower corner raised to the floor, once (clamp runs on every frame).
        self._floored_lower = self.lower.copy()
        self._floored_lower[2] = max(self._floored_lower[2], self.floor_z)

    def clamp(self, position):
        """Return (position clamped into the fence, whether it was outside)."""
        p = np.asarray(position, dtype=float)
        clamped = np.minimum(np.maximum(p, self._floored_lower), self.upper)
        return clamped, bool((clamped != p).any())


class EngageRamp:
    """Speed fraction rising linearly from 0 to 1 over ``duration`` s after engage."""

    def __init__(self, duration: float = 0.5):
        if duration < 0:
            raise MotionCommanderError("engage ramp duration must be >= 0 s")
        self.duration = duration
        self._start = None

    def start(self, stamp: float) -> None:
        """Begin a ramp at ``stamp`` (engage or resume)."""
        self._start = stamp

    def fraction(self, stamp: float) -> float:
        """Allowed speed fraction at ``stamp``."""
        if self._start is None or self.duration == 0:
            return 1.0
        # Never zero: a tiny first step lets the ramp start moving at all.
        return min(max((stamp - self._start) / self.duration, 0.02), 1.0)


class StaleCommandWatchdog:
    """Says when the last command is older than ``timeout`` s (moveit_servo: 0.1 s)."""

    def __init__(self, timeout: float = 0.1):
        if not timeout > 0:
            raise MotionCommanderError("stale command timeout must be > 0 s")
        self.timeout = timeout
        self._last = None

    def commanded(self, now: float) -> None:
        """Record that a command went out at ``now``."""
        self._last = now

    def clear(self) -> None:
        """Forget the last command (after a halt, so it triggers once)."""
        self._last = None

    def expired(self, now: float) -> bool:
        """True once the last command is older than the timeout."""
        return self._last is not None and now - self._last > self.timeout
