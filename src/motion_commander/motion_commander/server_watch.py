"""ServerWatch: is the robot server (motion_controller) alive, as the core sees it?

The server counts as lost when a call to it fails, or when its joint_states have been
silent for longer than ``stale_after_s`` (it publishes them at 100 Hz). While it is lost
the core streams nothing, reports SERVER_LOST and drops its ready flag; it probes the server
again with exponential backoff (not on every frame), and counts it back only once a probe
succeeded AND fresh joint_states arrived. Recovery never resumes a stream: the operator
engages afresh, from the measured joints, through the engage ramp.

Plain Python with an injected clock: ``now`` is passed to every method.
"""

import enum

from .errors import MotionCommanderError

__all__ = ["ServerState", "ServerWatch"]


class ServerState(enum.Enum):
    """What the watch says about the server."""

    UNKNOWN = 0  # no joint_states yet (start-up): not lost, not ready
    ALIVE = 1
    LOST = 2


class ServerWatch:
    """Tracks call failures and joint_states staleness; schedules probes with backoff."""

    def __init__(self, stale_after_s: float = 0.5, backoff_initial_s: float = 0.2, backoff_max_s: float = 2.0):
        if not stale_after_s > 0 or not 0 < backoff_initial_s <= backoff_max_s:
            raise MotionCommanderError(
                "server watch: stale_after_s must be > 0 and 0 < backoff_initial_s <= backoff_max_s"
            )
        self.stale_after_s = float(stale_after_s)
        self.backoff_initial_s = float(backoff_initial_s)
        self.backoff_max_s = float(backoff_max_s)
        self.state = ServerState.UNKNOWN
        self.reason = ""
        self.lost_at: float | None = None
        self.losses = 0
        self._last_joint_state: float | None = None
        self._probe_ok = False
        self._next_probe = 0.0
        self._backoff = self.backoff_initial_s

    @property
    def lost(self) -> bool:
        return self.state == ServerState.LOST

    def on_joint_state(self, now: float) -> None:
        """A joint_states message arrived."""
        self._last_joint_state = now
        if self.state == ServerState.UNKNOWN:
            self.state = ServerState.ALIVE

    def on_call_failed(self, now: float, why: str) -> bool:
        """A call to the server failed (no answer); return True when this loses it."""
        return self._lose(now, f"call failed: {why}")

    def check(self, now: float) -> bool:
        """Periodic check; return True when the server has just been lost (stale state)."""
        if self.state != ServerState.ALIVE or self._last_joint_state is None:
            return False
        silent = now - self._last_joint_state
        if silent > self.stale_after_s:
            return self._lose(now, f"no joint_states for {silent:.2f} s (bound {self.stale_after_s:.2f} s)")
        return False

    def probe_due(self, now: float) -> bool:
        """While lost: whether to try the server again now (exponential backoff)."""
        return self.lost and now >= self._next_probe

    def on_probe(self, now: float, ok: bool) -> bool:
        """The result of a probe; return True when the server counts as back."""
        if not self.lost:
            return False
        if not ok:
            self._probe_ok = False
            self._backoff = min(self._backoff * 2.0, self.backoff_max_s)
            self._next_probe = now + self._backoff
            return False
        self._probe_ok = True
        return self._recover(now)

    def recovered(self, now: float) -> bool:
        """While lost after a good probe: True once joint_states are fresh again."""
        return self.lost and self._probe_ok and self._recover(now)

    def _recover(self, now: float) -> bool:
        fresh = self._last_joint_state is not None and now - self._last_joint_state <= self.stale_after_s
        if not (fresh and self._last_joint_state >= (self.lost_at or 0.0)):
            return False
        self.state = ServerState.ALIVE
        self.reason = ""
        self._backoff = self.backoff_initial_s
        return True

    def _lose(self, now: float, reason: str) -> bool:
        if self.lost:
            return False
        self.state = ServerState.LOST
        self.reason = reason
        self.lost_at = now
        self.losses += 1
        self._probe_ok = False
        self._backoff = self.backoff_initial_s
        self._next_probe = now + self._backoff
        return True
