"""What the drivers of real controllers (``ur_driver``, ``industrial_driver``) do alike:
the arming gate before any connection, the reconnect backoff schedule, and the bookkeeping
of a blocking move that is watched on the measured joints (its token, INTERRUPTED on a
stop, TIMEOUT, the arrival errors against the goal tolerances).

How each driver talks to its controller, stops it and decides that a move has ended
differs, and stays in the driver.
"""

import threading

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import HwInterfaceError
from .protocol import Result

__all__ = ["RealControllerMixin"]


class RealControllerMixin:
    """Shared by the drivers of real controllers. The driver calls ``_init_controller``
    in its constructor and provides ``kinematics``, ``_lock`` (the driver lock) and
    ``stop()``."""

    def _init_controller(self, reconnect_attempts, reconnect_backoff, goal_tolerance, goal_position_tolerance, sleep):
        """The settings this mixin uses (``sleep`` is injected: tests need no real sleeping)
        and the move bookkeeping, which ``_lock`` guards."""
        self.reconnect_attempts = int(reconnect_attempts)
        self.reconnect_backoff = float(reconnect_backoff)
        self.goal_tolerance = float(goal_tolerance)
        self.goal_position_tolerance = float(goal_position_tolerance)
        self._sleep = sleep
        self._active_move = None  # "moveJ" / "moveL" while a move runs
        self._move_token = 0  # increases with every move
        self._stopped_token = 0  # the last move token a stop() cut short
        self._stop_reason = ""
        self._wake = threading.Event()  # wakes a watching move at once on stop() (or a fault)

    @staticmethod
    def _check_armed(host: str, armed: bool, controller: str) -> None:
        """Raise LOGIN_FAILED unless there is an address to reach and the driver is armed:
        nothing real is ever connected to by accident."""
        if not host:
            raise HwInterfaceError(
                f"no robot_ip: pass robot_ip:=<controller address> to connect to {controller}", Result.LOGIN_FAILED
            )
        if not armed:
            raise HwInterfaceError(
                f"refusing to connect to the real robot at {host}: the driver is not armed; "
                "check the cell is clear, then start with armed:=true",
                Result.LOGIN_FAILED,
            )

    def _backoff_attempts(self):
        """The attempt numbers 1..``reconnect_attempts``; between two of them (never after
        the last) it sleeps ``reconnect_backoff``, doubled each time. The caller iterates
        holding no lock, so the sleep never blocks a STOP or a status read."""
        delay = self.reconnect_backoff
        for attempt in range(1, self.reconnect_attempts + 1):
            yield attempt
            if attempt < self.reconnect_attempts:
                self._sleep(delay)
                delay *= 2

    # -- moves watched on the measured joints ----------------------------------------------
    def _set_stream_target(self, joints, now):
        """Keep ``joints`` as the latest streamed target, arrived at ``now``; BUSY while a
        move runs, which a stream must not fight (caller holds the lock)."""
        if self._active_move is not None:
            raise HwInterfaceError(f"a {self._active_move} is running; STOP it before streaming", Result.BUSY)
        self._target = np.asarray(joints, dtype=float)
        self._target_time = now

    def _end_move(self, token):
        """Move ``token`` is over: no move runs unless a newer one started (caller holds the lock)."""
        if self._move_token == token:
            self._active_move = None

    def _interrupted(self, kind, token, why):
        """The INTERRUPTED error of move ``token``, which ends it."""
        with self._lock:
            self._end_move(token)
        return HwInterfaceError(f"{kind} interrupted: {why}", Result.INTERRUPTED)

    def _raise_if_stopped(self, kind, token):
        """INTERRUPTED when a stop() cut move ``token`` short (caller holds the lock)."""
        if self._stopped_token >= token:
            raise self._interrupted(kind, token, f"{self._stop_reason} (robot stopped short of the goal)")

    def _timed_out(self, kind, timeout):
        """Stop the robot; the TIMEOUT error of a move that did not finish in ``timeout`` s."""
        self.stop(reason="timeout")
        return HwInterfaceError(f"{kind} did not finish within {timeout:.1f} s; robot stopped", Result.TIMEOUT)

    def _joint_error(self, q, goal):
        """(error, tolerance, unit) of measured joints ``q`` against a MoveJ goal."""
        return float(np.max(np.abs(q - goal))), self.goal_tolerance, "rad"

    def _pose_error(self, q, position, orientation):
        """(error, tolerance, unit) of measured joints ``q`` against a MoveL goal pose."""
        reached, quat = self.kinematics.forward_pose(q)
        distance = float(np.linalg.norm(reached - np.asarray(position, dtype=float)))
        angle = float((Rotation.from_quat(quat).inv() * Rotation.from_quat(orientation)).magnitude())
        # Report the worse of the two as a fraction of its tolerance, in metres for the message.
        ratio = max(distance / self.goal_position_tolerance, angle / self.goal_tolerance)
        return ratio * self.goal_position_tolerance, self.goal_position_tolerance, "m (position/orientation)"
