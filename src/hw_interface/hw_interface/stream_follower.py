"""Streamed joint targets followed within the joint velocity AND acceleration limits, in
simulated time.

A teleop client limits its own steps in SENSOR time, but its commands reach the driver in
ARRIVAL time: a burst of three queued commands arrives within a millisecond, and a client
may simply ask for too much (any step up to the server's max_stream_step is accepted). A
servo told to jump there moves as fast as its motor allows (60 rad/s in pybullet). A real
controller never exceeds its joint speed limits, so the simulation must not either: each
physics step moves the servo setpoint toward the latest streamed target by at most the
velocity limits times the step, scaled uniformly so the tool stays on the straight joint
path. With ``acceleration`` set, the setpoint's velocity also changes by at most the
acceleration times the step (each on its own for the joints slowing down, the others by one
factor), and it brakes in time to stop at the target: a client bug (a
stale target after a restart, a burst) can then never make the arm lurch. Moving toward a
fixed goal passes it by at most the last steps' rounding (< 0.1 mrad); a goal that moves
back under a fast setpoint is passed and come back to, within the limits, as a real servo
would.
"""

import numpy as np

from motion_common.params import Param

__all__ = ["StreamFollower", "STREAM_ACCELERATION_PARAM"]

#: The drivers' parameter of the follower's acceleration limit (one declaration for both).
STREAM_ACCELERATION_PARAM = Param(
    "stream_acceleration",
    200.0,
    "rad/s^2",
    "largest joint acceleration of a streamed (SET_JOINTS) motion, enforced in the driver whatever the client "
    "sends (the setpoint also keeps the URDF speed limits and brakes in time to stop at each target)",
    low=0.0,
    high=10000.0,
    low_open=True,
)


class StreamFollower:
    """Servo setpoint that chases the latest streamed goal at bounded joint speed and
    acceleration.

    ``velocity_limits`` in rad/s (m/s for prismatic joints), one per joint;
    ``acceleration`` in rad/s^2 (one value, or one per joint; None: unlimited).
    """

    def __init__(self, velocity_limits, start, acceleration=None):
        self.velocity_limits = np.asarray(velocity_limits, dtype=float)
        if not np.all(np.isfinite(self.velocity_limits)) or np.any(self.velocity_limits <= 0):
            raise ValueError("every joint needs a finite velocity limit > 0 (check the URDF)")
        self.acceleration = None
        if acceleration is not None:
            self.acceleration = np.broadcast_to(
                np.asarray(acceleration, dtype=float), self.velocity_limits.shape
            ).copy()
            if not np.all(np.isfinite(self.acceleration)) or np.any(self.acceleration <= 0):
                raise ValueError("the stream acceleration limit must be finite and > 0")
        self.setpoint = np.array(start, dtype=float)
        self.goal = self.setpoint.copy()
        self.velocity = np.zeros_like(self.setpoint)

    def reset(self, position) -> None:
        """Hold ``position`` (after a stop, a MoveJ/MoveL or a reset): goal and setpoint, at rest."""
        self.setpoint = np.array(position, dtype=float)
        self.goal = self.setpoint.copy()
        self.velocity = np.zeros_like(self.setpoint)

    def set_goal(self, goal) -> None:
        """The latest streamed target."""
        self.goal = np.array(goal, dtype=float)

    def brake(self) -> None:
        """The stream stopped: come to rest as soon as the acceleration limit allows (at
        once without one), where braking from the present velocity ends."""
        if self.acceleration is None:
            self.goal = self.setpoint.copy()
            self.velocity[:] = 0.0
            return
        self.goal = self.setpoint + self.velocity * np.abs(self.velocity) / (2.0 * self.acceleration)

    def step(self, dt: float) -> np.ndarray:
        """Advance the setpoint by one step of ``dt`` seconds; return it."""
        error = self.goal - self.setpoint
        if self.acceleration is None:
            reach = self.velocity_limits * dt
            ratio = float(np.max(np.abs(error) / reach)) if dt > 0 else float("inf")
            if ratio <= 1.0:
                self.setpoint = self.goal.copy()
            elif np.isfinite(ratio):
                self.setpoint = self.setpoint + error / ratio
            return self.setpoint
        if not dt > 0:
            return self.setpoint
        # The velocity that would reach the goal in this step, capped by the speed limits and
        # by what still allows a stop at the goal (v <= sqrt(2 a d)), scaled uniformly.
        desired = error / dt
        # (The discrete-time form of v <= sqrt(2 a d): the largest speed from which steps of
        # a * dt of braking still stop within the distance left, so the last step needs no
        # harder braking than the others.)
        a_dt = self.acceleration * dt
        brake = a_dt * (np.sqrt(0.25 + 2.0 * np.abs(error) / (a_dt * dt)) - 0.5)
        cap = np.minimum(self.velocity_limits, brake)
        moving = np.abs(desired) > 0.0
        if np.any(moving):
            ratio = float(np.max(np.abs(desired[moving]) / np.maximum(cap[moving], 1e-12)))
            if ratio > 1.0:
                desired = desired / ratio
        # Change the velocity toward it by at most a * dt: uniformly, so the path stays
        # straight, for the joints speeding up or turning; each on its own for the joints
        # slowing down. Scaled with the others, a joint that must stop would keep the speed a
        # wrist turning hard left it, and the tool would run past a goal that stopped (by
        # 1.4 mm on a real hand's recording).
        previous = self.velocity
        change = desired - previous
        braking = change * previous < 0.0
        change = np.where(braking, np.clip(change, -a_dt, a_dt), change)
        others = ~braking
        if np.any(others):
            ratio = float(np.max(np.abs(change[others]) / a_dt[others]))
            if ratio > 1.0:
                change = np.where(others, change / ratio, change)
        self.velocity = previous + change
        new = self.setpoint + self.velocity * dt
        # Landing: a joint whose goal lies within this step stops on it when that takes no
        # more than the acceleration limit (from its speed to the landing step's, and from
        # that to rest). One going faster (its goal moved back under it) passes the goal and
        # comes back within the limit, as a real servo would.
        landing_speed = error / dt
        gentle = (np.abs(previous - landing_speed) <= a_dt * (1 + 1e-9)) & (np.abs(landing_speed) <= a_dt * (1 + 1e-9))
        landing = gentle & (np.sign(self.goal - new) * np.sign(error) <= 0)
        if np.any(landing):
            new[landing] = self.goal[landing]
            # The speed of the landing step: the next step brakes from it to rest.
            self.velocity[landing] = landing_speed[landing]
        self.setpoint = new
        return self.setpoint

    @property
    def at_rest(self) -> bool:
        """True when the setpoint has stopped at its goal."""
        return bool(np.all(self.velocity == 0.0) and np.array_equal(self.setpoint, self.goal))

    def __repr__(self):  # pragma: no cover - debugging aid
        speed = float(np.max(np.abs(self.velocity))) if self.velocity.size else 0.0
        return f"StreamFollower(speed={speed:.3f}, remaining={float(np.max(np.abs(self.goal - self.setpoint))):.4f})"
