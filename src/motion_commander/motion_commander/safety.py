"""Joint-space safety rules applied to every teleop command before it leaves the core."""
import numpy as np

from .errors import MotionCommanderError


class JointStepLimiter:
    """Limits each joint's step between two commands to ``velocity_limits * dt``.

    The whole step is scaled by one factor, not joint by joint: clipping joints separately
    would change the direction of motion and pull the tool off its path, while a uniform
    scale only makes it lag along the path.

    Velocity limits are in rad/s (m/s for prismatic joints); ``scale`` (0, 1] is the
    fraction of the robot's rated speed teleop may use.
    """

    def __init__(self, velocity_limits, scale: float = 0.5, min_dt: float = 0.002, max_dt: float = 0.05):
        limits = np.asarray(velocity_limits, dtype=float)
        if not (0 < scale <= 1):
            raise MotionCommanderError(f"joint speed scale must be in (0, 1], got {scale!r}")
        if not np.all(np.isfinite(limits)) or np.any(limits <= 0):
            raise MotionCommanderError("every joint needs a finite velocity limit > 0 in the URDF")
        self.max_velocity = limits * scale
        # dt is clamped: a long gap (hand lost, then back) must not permit a big jump.
        self.min_dt = min_dt
        self.max_dt = max_dt

    def limit(self, previous, target, dt: float):
        """Return (command, limited): previous moved toward target by at most max_velocity*dt per joint."""
        previous = np.asarray(previous, dtype=float)
        target = np.asarray(target, dtype=float)
        max_step = self.max_velocity * float(np.clip(dt, self.min_dt, self.max_dt))
        step = target - previous
        ratio = float(np.max(np.abs(step) / max_step))
        if ratio <= 1.0:
            return target.copy(), False
        return previous + step / ratio, True
