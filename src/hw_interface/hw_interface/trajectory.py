"""Time parameterisation of MoveJ / MoveL paths with a trapezoidal speed profile."""

import numpy as np


def trapezoid_duration(distance: float, max_velocity: float, max_acceleration: float) -> float:
    """Shortest time to cover ``distance`` from rest to rest within the two limits."""
    if distance <= 0:
        return 0.0
    ramp_distance = max_velocity**2 / max_acceleration
    if distance <= ramp_distance:
        return 2.0 * np.sqrt(distance / max_acceleration)
    return distance / max_velocity + max_velocity / max_acceleration


def trapezoid_progress(t: float, duration: float) -> float:
    """Path fraction s(t) in [0, 1] of a symmetric trapezoid with 1/4-duration ramps.

    The fixed ramp share keeps every joint within its limits when the duration was taken
    from the most constrained joint with trapezoid_duration and margins below.
    """
    if duration <= 0 or t >= duration:
        return 1.0
    if t <= 0:
        return 0.0
    ramp = duration / 4.0
    peak = 1.0 / (duration - ramp)
    if t < ramp:
        return 0.5 * peak / ramp * t * t
    if t > duration - ramp:
        remaining = duration - t
        return 1.0 - 0.5 * peak / ramp * remaining * remaining
    return 0.5 * peak * ramp + peak * (t - ramp)


class JointPath:
    """A joint path through waypoints, followed in ``duration`` seconds.

    ``waypoints`` (n x dof) are evenly spaced in path fraction; with two rows it is a
    straight joint-space line (MoveJ), with many it follows a Cartesian line (MoveL).
    """

    def __init__(self, waypoints, duration: float):
        self.waypoints = np.atleast_2d(np.asarray(waypoints, dtype=float))
        self.duration = float(duration)

    def sample(self, t: float) -> np.ndarray:
        """Joint target at ``t`` seconds after the start."""
        s = trapezoid_progress(t, self.duration) * (len(self.waypoints) - 1)
        index = min(int(s), len(self.waypoints) - 2) if len(self.waypoints) > 1 else 0
        if len(self.waypoints) == 1:
            return self.waypoints[0].copy()
        frac = s - index
        return (1 - frac) * self.waypoints[index] + frac * self.waypoints[index + 1]

    @property
    def end(self) -> np.ndarray:
        """The final joint target."""
        return self.waypoints[-1].copy()


def joint_move_duration(start, goal, max_velocity, max_acceleration) -> float:
    """Duration of a synchronised joint move (trapezoid with 1/4 ramps) within the limits."""
    distance = np.abs(np.asarray(goal, dtype=float) - np.asarray(start, dtype=float))
    # With 1/4-duration ramps the peak speed is 4/3 of the mean and the acceleration
    # 16/3 * d / T^2, so both limits give a lower bound on T.
    t_velocity = np.max(4.0 / 3.0 * distance / max_velocity)
    t_acceleration = np.max(np.sqrt(16.0 / 3.0 * distance / max_acceleration))
    return float(max(t_velocity, t_acceleration))
