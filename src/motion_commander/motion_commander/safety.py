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

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from motion_common.float_list import float_list
from motion_common.kinematics import singular_values

from .errors import MotionCommanderError


def braking_speed(distance: float, acceleration: float, dt: float) -> float:
    """Largest speed from which steps of ``dt`` s, decelerating by ``acceleration`` each,
    stop within ``distance`` (>= 0; same unit as distance per s).

    Stopping from v = n a dt covers a dt^2 n (n + 1) / 2 including this step's own move;
    solving for n gives the discrete form of the familiar sqrt(2 a d).
    """
    return acceleration * dt * (math.sqrt(0.25 + 2.0 * distance / (acceleration * dt * dt)) - 0.5)


class JointStepLimiter:
    """Limits each command's joint step to the velocity and acceleration limits.

    ``velocity_limits`` in rad/s (m/s for prismatic joints); ``scale`` (0, 1] is the
    fraction of them teleop may use; ``acceleration_limit`` in rad/s^2 (None: no limit).
    The whole step is scaled by one factor, not joint by joint: clipping joints separately
    would change the direction of motion and pull the tool off its path, while a uniform
    scale only makes it lag along the path. With an acceleration limit the step is also
    kept slow enough to stop AT the target (braking_speed): a command catching up with a
    hand that reverses brakes in time instead of running past the reversal point.

    When the acceleration limit binds and the caller gives the tool's Jacobian, the step is
    the one within every joint's acceleration (and speed) bounds that keeps the tool's
    position closest to the intended step, the orientation weighted by
    ``ROTATION_WEIGHT_M`` (scipy's bounded least squares): scaling every joint's change of
    velocity by one factor would let a wrist that turns hard (a real hand's orientation is
    noisy) hold back the joints that carry the position, and the tool would run past a hand
    that stops.
    """

    ROTATION_WEIGHT_M = 0.05  # m of tool position worth one rad of orientation, where they conflict

    def __init__(
        self, velocity_limits, scale: float = 0.5, acceleration_limit=None, min_dt: float = 0.002, max_dt: float = 0.05
    ):
        limits = np.asarray(velocity_limits, dtype=float)
        if not (0 < scale <= 1):
            raise MotionCommanderError(f"joint speed scale must be in (0, 1], got {scale!r}")
        if not np.all(np.isfinite(limits)) or np.any(limits <= 0):
            raise MotionCommanderError("every joint needs a finite velocity limit > 0 in the URDF")
        if acceleration_limit is not None and not acceleration_limit > 0:
            raise MotionCommanderError(f"acceleration limit must be > 0 rad/s^2, got {acceleration_limit!r}")
        self.max_velocity = limits * scale  # rad/s per joint
        self._max_velocity = [float(v) for v in self.max_velocity]  # the same, for the per-frame path
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

    # The methods below run on every teleop frame, on its latency. They work on plain
    # float lists: a numpy call on a 6-vector costs ~1 us in a hot loop but ~6 us after the
    # ~9 ms of idle between frames (cold caches), ~4x a plain-Python loop doing the same
    # (bench/e2e_latency --breakdown).

    def observe_target(self, target, dt: float) -> None:
        """Record this frame's unlimited joint target: its velocity lets a command that
        follows a moving target keep pace instead of braking as if it were to stop there."""
        target = float_list(target)
        dt = self._clamped_dt(dt)
        previous = self._target
        self._target_velocity = None if previous is None else [(t - p) / dt for t, p in zip(target, previous)]
        self._target = target

    def _clamped_dt(self, dt: float) -> float:
        return min(max(float(dt), self.min_dt), self.max_dt)

    def _max_steps(self, previous, goal, dt: float, speed_fraction: float) -> list:
        """Largest joint step (abs, per joint) allowed toward ``goal`` this step."""
        scale = dt * max(speed_fraction, 0.0)
        max_steps = [limit * scale for limit in self._max_velocity]
        acceleration = self.max_acceleration
        if acceleration is None:
            return max_steps
        target_velocity = self._target_velocity
        for i, (p, g) in enumerate(zip(previous, goal)):
            direction = g - p
            if direction == 0.0:
                max_steps[i] = 0.0  # already there: no room to move in either direction
                continue
            error = direction
            # Slow enough to stop where the goal itself would stop if it braked as hard as
            # we may: a goal moving on at v stops v^2/2a further on (so we keep pace), a goal
            # slowing down for a reversal brings that point back to its peak (so we brake in
            # time), and a goal already coming back leaves no distance at all (so we brake now).
            if target_velocity is not None:
                v = target_velocity[i]
                error += v * abs(v) / (2.0 * acceleration)
            room = error if direction > 0.0 else -error
            if room <= 0.0:
                max_steps[i] = 0.0
            else:
                max_steps[i] = min(max_steps[i], braking_speed(room, acceleration, dt) * dt)
        return max_steps

    def overshoot(self, previous, target, dt: float, speed_fraction: float = 1.0, goal=None) -> float:
        """How many times too large the step to ``target`` is for the velocity limit and,
        with an acceleration limit, for stopping at ``goal`` (default: target) (<= 1:
        allowed as is). No side effect."""
        previous = float_list(previous)
        target = float_list(target)
        goal = target if goal is None else float_list(goal)
        max_steps = self._max_steps(previous, goal, self._clamped_dt(dt), speed_fraction)
        ratio = 0.0
        for p, t, max_step in zip(previous, target, max_steps):
            step = abs(t - p)
            if max_step <= 0.0:
                if step > 0.0:
                    return float("inf")
                continue  # nothing to do there: ratio 0
            if step / max_step > ratio:
                ratio = step / max_step
        return ratio

    def fraction_within(self, previous, start, goal, dt: float, speed_fraction: float = 1.0):
        """Largest f in [0, 1] for which the step from ``previous`` to start + f (goal - start)
        keeps every joint within its speed limit and, on the goal's side, able to stop at the
        goal (or no further than ``start`` already goes); None when ``start`` itself (f = 0)
        is beyond the speed limit.

        ``start`` is a step that must be taken whole (the tool position): it may move joints
        away from the goal or past it, which is fine as long as it is within the speed limit.
        The rest of the way toward ``goal`` (the orientation) gets what the limits leave.
        Each joint's step a + f b must lie between bounds down and up: linear in f, solved
        joint by joint, the smallest winning."""
        previous, start, goal = float_list(previous), float_list(start), float_list(goal)
        dt = self._clamped_dt(dt)
        scale = dt * max(speed_fraction, 0.0)
        brakes = self._max_steps(previous, goal, dt, speed_fraction)
        fraction = 1.0
        for i, (p, s, g) in enumerate(zip(previous, start, goal)):
            speed_step = self._max_velocity[i] * scale
            a, b = s - p, g - s
            if abs(a) > speed_step * (1.0 + 1e-9):
                return None
            up = down = speed_step
            toward = g - p
            if toward > 0.0:
                up = max(brakes[i], a)
            elif toward < 0.0:
                down = max(brakes[i], -a)
            if b > 0.0:
                fraction = min(fraction, (up - a) / b)
            elif b < 0.0:
                fraction = min(fraction, (-down - a) / b)
        return max(fraction, 0.0)

    def speed_ratio(self, previous, target, dt: float, speed_fraction: float = 1.0) -> float:
        """How many times too large the step to ``target`` is for the speed limit alone."""
        scale = self._clamped_dt(dt) * max(speed_fraction, 0.0)
        ratio = 0.0
        for p, t, limit in zip(float_list(previous), float_list(target), self._max_velocity):
            step = abs(t - p)
            if step > 0.0:
                ratio = max(ratio, step / (limit * scale) if scale > 0.0 else float("inf"))
        return ratio

    def braking_fraction(self, previous, target, goal, dt: float, speed_fraction: float = 1.0) -> float:
        """Largest f in [0, 1] for which every joint's step f (target - previous) that moves
        toward ``goal`` stays able to stop at the goal (braking_speed, the goal's own motion
        counted as in overshoot()). For a step that must keep its direction (the tool
        position's): scaled down, the tool stays on its path and still stops in time.
        Joints whose goal is already coming back do not count (see below)."""
        previous, target, goal = float_list(previous), float_list(target), float_list(goal)
        if self.max_acceleration is None:
            return 1.0
        brakes = self._max_steps(previous, goal, self._clamped_dt(dt), speed_fraction)
        fraction = 1.0
        for p, t, g, brake in zip(previous, target, goal, brakes):
            step, toward = t - p, g - p
            # A joint whose goal is already coming back (no room: brake 0) would hold the
            # whole position still; it is left to the acceleration limit, as before.
            if brake > 0.0 and step * toward > 0.0 and abs(step) > brake:
                fraction = min(fraction, brake / abs(step))
        return fraction

    def limit(self, previous, target, dt: float, speed_fraction: float = 1.0, goal=None, ratio=None, jacobian=None):
        """Return (command, limited): previous moved toward target within the limits.

        ``speed_fraction`` in [0, 1] scales the velocity limit (ramps, singularity slow-down).
        ``goal`` is where the motion must be able to stop (default: target); the core
        passes the frame's full IK target when ``target`` is a partial step toward it.
        ``ratio`` is this same step's ``overshoot()``, when the caller has computed it.
        ``jacobian``: a callable giving the 6 x n tool Jacobian at ``previous`` (linear rows
        first), called only when the acceleration limit binds (see the class).
        """
        previous = float_list(previous)
        step = [t - p for t, p in zip(float_list(target), previous)]
        dt = self._clamped_dt(dt)
        if ratio is None:
            ratio = self.overshoot(previous, target, dt, speed_fraction, goal)
        limited = ratio > 1.0
        if limited:
            step = [s / ratio for s in step] if math.isfinite(ratio) else [0.0] * len(step)
        if self.max_acceleration is not None:
            previous_velocity = self._velocity or [0.0] * len(step)
            dv = [s / dt - v for s, v in zip(step, previous_velocity)]
            excess = max(abs(d) for d in dv) / (self.max_acceleration * dt)
            if excess > 1.0:
                if jacobian is None:
                    step = [(v + d / excess) * dt for v, d in zip(previous_velocity, dv)]
                else:
                    step = self._closest_tool_step(step, previous_velocity, dt, speed_fraction, jacobian())
                limited = True
        self._velocity = [s / dt for s in step]
        return np.array([p + s for p, s in zip(previous, step)]), limited

    def _closest_tool_step(self, step, previous_velocity, dt: float, speed_fraction: float, jacobian) -> list:
        """The joint step within each joint's acceleration bounds (and its speed bounds,
        where the two overlap) whose tool motion is closest to that of ``step``."""
        velocity = np.asarray(previous_velocity, dtype=float)
        change = self.max_acceleration * dt * dt
        lower, upper = velocity * dt - change, velocity * dt + change
        speed = self.max_velocity * (max(speed_fraction, 0.0) * dt)
        # A joint already faster than a speed cap that just dropped (a ramp, a singularity)
        # slows down at the acceleration limit: its bounds are then the acceleration's alone.
        capped_lower, capped_upper = np.maximum(lower, -speed), np.minimum(upper, speed)
        overlap = capped_lower <= capped_upper
        lower = np.where(overlap, capped_lower, lower)
        upper = np.where(overlap, capped_upper, upper)
        weights = np.array([1.0, 1.0, 1.0] + [self.ROTATION_WEIGHT_M] * 3)[:, None]
        # The small identity rows make the solution unique where the Jacobian is not.
        design = np.vstack([weights * np.asarray(jacobian, dtype=float), 1e-3 * np.eye(len(step))])
        wanted = np.asarray(step, dtype=float)
        solved = lsq_linear(design, design @ wanted, bounds=(lower, np.nextafter(upper, np.inf)), method="bvls").x
        return np.clip(solved, lower, upper).tolist()


class JointLimitMargin:
    """Clips joint targets to the URDF limits shrunk by ``margin`` (rad)."""

    def __init__(self, lower, upper, margin: float = 0.05):
        self.lower = np.asarray(lower, dtype=float) + margin
        self.upper = np.asarray(upper, dtype=float) - margin
        if np.any(self.lower >= self.upper):
            raise MotionCommanderError(f"joint limit margin {margin} rad leaves no range for some joint")
        self._lower, self._upper = self.lower.tolist(), self.upper.tolist()

    def apply(self, joints):
        """Return (clipped joints, whether any joint was clipped)."""
        # Per frame: plain floats (see JointStepLimiter), one array built at the end.
        q = float_list(joints)
        clipped = [min(max(v, low), high) for v, low, high in zip(q, self._lower, self._upper)]
        return np.array(clipped), clipped != q


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
    largest, smallest = extreme_singular_values(jacobian)
    return largest / smallest if smallest > 1e-12 else float("inf")


def extreme_singular_values(jacobian) -> tuple:
    """(largest, smallest) singular value of a Jacobian, as Python floats (no numpy scalar
    arithmetic after it)."""
    singular = singular_values(np.asarray(jacobian, dtype=float))
    return float(singular[0]), float(singular[-1])


def condition_certainly_below(jacobian, reference, reference_extremes, threshold: float) -> bool:
    """True when the condition number of ``jacobian`` is certainly below ``threshold``,
    known from a ``reference`` Jacobian nearby whose (largest, smallest) singular values are
    ``reference_extremes``, without a singular value decomposition of ``jacobian``.

    Weyl's inequality bounds how far each singular value moves: |s_i(J) - s_i(R)| <=
    ||J - R||_2 <= ||J - R||_F. A teleop frame's IK solution lies close to the previous
    one, so the bound is tight and usually settles the question (the SVD is the
    largest single item of the core's per-frame work). False means: compute it.
    """
    difference = np.asarray(jacobian, dtype=float) - reference
    distance = math.sqrt(float(np.vdot(difference, difference)))
    largest, smallest = reference_extremes
    lowest = smallest - distance
    return lowest > 0.0 and (largest + distance) < threshold * lowest


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
        self._floored_lower = self.lower.tolist()
        self._floored_lower[2] = max(self._floored_lower[2], float(self.floor_z))
        self._upper = self.upper.tolist()

    def clamp(self, position):
        """Return (position clamped into the fence, whether it was outside)."""
        # Per frame: plain floats (see JointStepLimiter), one array built at the end.
        p = float_list(position)
        clamped = [min(max(v, low), high) for v, low, high in zip(p, self._floored_lower, self._upper)]
        return np.array(clamped), clamped != p


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
