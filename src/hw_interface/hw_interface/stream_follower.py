"""Streamed joint targets followed within the joint velocity limits, in simulated time.

A teleop client limits its own steps in SENSOR time, but its commands reach the driver in
ARRIVAL time: a burst of three queued commands arrives within a millisecond, and a client
may simply ask for too much (any step up to the server's max_stream_step is accepted). A
servo told to jump there moves as fast as its motor allows (60 rad/s in pybullet). A real
controller never exceeds its joint speed limits, so the simulation must not either: each
physics step moves the servo setpoint toward the latest streamed target by at most the
velocity limits times the step, scaled uniformly so the tool stays on the straight joint
path. Moving toward a fixed goal with a capped speed never passes it, so nothing overshoots.
"""

import numpy as np


class StreamFollower:
    """Servo setpoint that chases the latest streamed goal at bounded joint speed.

    ``velocity_limits`` in rad/s (m/s for prismatic joints), one per joint.
    """

    def __init__(self, velocity_limits, start):
        self.velocity_limits = np.asarray(velocity_limits, dtype=float)
        if not np.all(np.isfinite(self.velocity_limits)) or np.any(self.velocity_limits <= 0):
            raise ValueError("every joint needs a finite velocity limit > 0 (check the URDF)")
        self.setpoint = np.array(start, dtype=float)
        self.goal = self.setpoint.copy()

    def reset(self, position) -> None:
        """Hold ``position`` (after a stop, a MoveJ/MoveL or a reset): goal and setpoint."""
        self.setpoint = np.array(position, dtype=float)
        self.goal = self.setpoint.copy()

    def set_goal(self, goal) -> None:
        """The latest streamed target."""
        self.goal = np.array(goal, dtype=float)

    def step(self, dt: float) -> np.ndarray:
        """Advance the setpoint by one step of ``dt`` seconds; return it."""
        error = self.goal - self.setpoint
        reach = self.velocity_limits * dt
        ratio = float(np.max(np.abs(error) / reach)) if dt > 0 else float("inf")
        if ratio <= 1.0:
            self.setpoint = self.goal.copy()
        elif np.isfinite(ratio):
            self.setpoint = self.setpoint + error / ratio
        return self.setpoint
