"""Intercept pick planning on a moving belt (the paper's future work: its robot treated
parts as still).

Given a part's track (position and velocity on the belt plane at time t0), the arm's time
to reach a point (a constant or a function of the point), and the reach window along the
belt [x_min, x_max], the plan is the earliest time t >= now at which the arm can be at the
part: (t - now) >= reach_time(p(t)) + margin and x(t) inside the window. The feasible set
is searched on a fine time grid and its first point refined by bisection. No plan comes
with a reason: the part is not moving towards the window, has already left it, or leaves
it before the arm can get there.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass
class Intercept:
    ok: bool
    reason: str = ""
    time: float = math.nan  # s, absolute
    point: np.ndarray | None = None  # (x, y) m, base frame
    slack: float = math.nan  # s, time left in the window after the intercept


def plan_intercept(
    position,
    velocity,
    t0: float,
    now: float,
    reach_time: float | Callable[[np.ndarray], float],
    x_min: float,
    x_max: float,
    margin: float = 0.0,
    resolution: float = 0.01,
) -> Intercept:
    """Earliest feasible intercept of a part at ``position`` (x, y; m) at time ``t0`` moving
    at ``velocity`` (m/s), planned at time ``now`` (s)."""
    position, velocity = np.asarray(position, float), np.asarray(velocity, float)
    reach = reach_time if callable(reach_time) else (lambda _p, c=float(reach_time): c)
    if x_max <= x_min:
        return Intercept(False, "empty reach window")

    def at(t):
        return position + velocity * (t - t0)

    vx = velocity[0]
    x_now = at(now)[0]
    if abs(vx) < 1e-9:
        if not x_min <= x_now <= x_max:
            return Intercept(False, "part is still and outside the reach window")
        t_enter, t_exit = now, math.inf
    else:
        t_a, t_b = t0 + (x_min - position[0]) / vx, t0 + (x_max - position[0]) / vx
        t_enter, t_exit = min(t_a, t_b), max(t_a, t_b)
        if t_exit < now:
            return Intercept(False, "part has already left the reach window")
    start = max(now, t_enter)
    end = t_exit if math.isfinite(t_exit) else start + 3600.0

    def feasible(t):
        return (t - now) >= reach(at(t)) + margin

    if feasible(start):
        return Intercept(True, "", start, at(start), end - start)
    t, previous = start, start
    while t < end:
        previous, t = t, min(t + resolution, end)
        if feasible(t):
            lo, hi = previous, t
            for _ in range(40):
                mid = (lo + hi) / 2
                lo, hi = (lo, mid) if feasible(mid) else (mid, hi)
            return Intercept(True, "", hi, at(hi), end - hi)
    return Intercept(False, f"part leaves the reach window at t={end:.2f} s before the arm can get there")
