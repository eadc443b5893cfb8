"""The teleop status as the page shows it: the README status table's name and a colour."""

from motion_commander.teleop_core import TeleopStatus

# Green: streaming; amber: streaming but limited; orange: holding for a reason; red: the
# e-stop or a lost robot server; grey: idle. Every TeleopStatus has a colour
# (tests/unit/dashboard/test_dashboard_state.py).
STATUS_COLOURS = {
    TeleopStatus.WAITING_FOR_ROBOT: "grey",
    TeleopStatus.DISENGAGED: "grey",
    TeleopStatus.ENGAGED: "green",
    TeleopStatus.RAMPING: "green",
    TeleopStatus.JOINT_SPEED_LIMITED: "amber",
    TeleopStatus.SINGULARITY_SLOWDOWN: "amber",
    TeleopStatus.WORKSPACE_LIMIT: "amber",
    TeleopStatus.JOINT_LIMIT_MARGIN: "amber",
    TeleopStatus.IK_FAILED: "orange",
    TeleopStatus.BAD_INPUT: "orange",
    TeleopStatus.STALE_INPUT_HALT: "orange",
    TeleopStatus.SINGULARITY_HALT: "orange",
    TeleopStatus.ESTOP: "red",
    TeleopStatus.SERVER_LOST: "red",
}

# The clutch is closed (the hand steers the tool) in these states.
ENGAGED_STATUSES = frozenset(STATUS_COLOURS) - {
    TeleopStatus.WAITING_FOR_ROBOT,
    TeleopStatus.DISENGAGED,
    TeleopStatus.ESTOP,
    TeleopStatus.BAD_INPUT,
    TeleopStatus.SERVER_LOST,
}


def status_view(code: int | None) -> tuple[str, str]:
    """(name, colour) of a /motion_commander/status code; None means not heard yet."""
    if code is None:
        return "NO STATUS", "grey"
    try:
        status = TeleopStatus(int(code))
    except ValueError:
        return f"UNKNOWN ({code})", "grey"
    return status.name, STATUS_COLOURS[status]


def is_engaged(code: int | None) -> bool:
    """True when the status code means the clutch is closed."""
    return code in ENGAGED_STATUSES  # IntEnum members hash and compare as their ints


def log_text(code: int | None) -> str:
    """The status as the event log names it. Streaming states (green and amber) are one
    entry, "engaged": a moving hand flips between ENGAGED and JOINT_SPEED_LIMITED many
    times a second, which belongs in the status chart, not in a log a person reads; a halt,
    a refusal or the clutch opening is logged by name."""
    name, colour = status_view(code)
    return "engaged (streaming)" if colour in ("green", "amber") else name
