"""What a change of the driver's status is worth saying on the console, and how loudly.

motion_controller_server polls the driver's status (DriverStatus) at its publish rate and
publishes all of it on motion_controller/status. The console hears only what an operator
must know: a fault or a protective stop (error), their clearing and connection changes
(info). Motion and gripper changes, which every pick toggles, go to debug: printed at info
they buried a kitting run's progress bar under a dictionary every half second.
"""

from .robot_hw import DriverStatus

__all__ = ["status_change"]


def status_change(old: DriverStatus | None, new: DriverStatus) -> tuple[str, str]:
    """(level, message) of the change from ``old`` (None: the first status) to ``new``;
    level is "error", "info" or "debug"."""
    if new.fault and new.fault != getattr(old, "fault", ""):
        return "error", f"driver fault: {new.fault}"
    if new.protective_stop and not getattr(old, "protective_stop", False):
        return "error", f"protective stop (safety mode {new.safety_mode or 'unknown'})"
    if old is not None and old.fault and not new.fault:
        return "info", "driver fault cleared"
    if old is not None and old.protective_stop and not new.protective_stop:
        return "info", "protective stop cleared"
    if old is None or new.connected != old.connected:
        return "info", "driver connected" if new.connected else "driver not connected"
    return "debug", f"driver status {vars(new)}"
