"""Which controls can act now, and why not: every rule of the page in one function; and
the check of what the operator types (the speed ratio) before anything is sent.

A control that cannot act is disabled and its reason is shown next to it (refusing a
replay while teleop is engaged is one such rule). STOP is never disabled. A typed value
that cannot be used is refused with a message naming the accepted range.
"""

from dataclasses import dataclass

from .status_style import is_engaged

__all__ = ["ControlState", "control_states", "episode_states", "RatioDecision", "check_speed_ratio", "CONFIRM_FACTOR"]


@dataclass(frozen=True)
class ControlState:
    """Whether a control is enabled, and the reason when it is not."""

    enabled: bool
    reason: str = ""


ON = ControlState(True)


def _first(*rules) -> ControlState:
    """The first failing rule's reason (rules are (condition_that_blocks, reason))."""
    for blocked, reason in rules:
        if blocked:
            return ControlState(False, reason)
    return ON


def _campaign_running(values) -> bool:
    """A campaign's progress says trials remain and no result has come (one this page did not
    start, e.g. scripts/kitting_sim)."""
    progress = values.get("campaign_progress")
    if not isinstance(progress, dict) or values.get("campaign_result") is not None:
        return False
    try:
        return int(progress.get("done", 0)) < int(progress.get("trials", 0))
    except (TypeError, ValueError):
        return False


def control_states(
    values: dict[str, object],
    program_job: bool = False,
    campaign_job: bool = False,
    selected_program: str | None = None,
) -> dict[str, ControlState]:
    """Enabled/reason of every control from a state snapshot's values and the running jobs.

    Keys read: status (TeleopStatus code), engage_mode, stop_latched, server_up,
    speed_ratio, filter, kitting_cell, tray (dashboard.tray.parse_tray's), campaign_progress,
    campaign_result, episodes_status.
    """
    status = values.get("status")
    latched = bool(values.get("stop_latched"))
    engaged = is_engaged(status)
    core_up = status is not None
    server_up = bool(values.get("server_up"))
    button_mode = values.get("engage_mode") == "button"
    mode = values.get("engage_mode") or "unknown"
    not_button = (
        f"engage mode is '{mode}': the hand works the clutch "
        "(start the session with engage:=button to engage from here)"
    )
    no_program = selected_program is None
    busy = "a program run is in progress (wait for it or press STOP)"
    return {
        "stop": ON,
        "release": _first((not latched, "the stop is not latched")),
        "engage": _first(
            (not core_up, "motion_commander is not running (no /motion_commander/status)"),
            (not button_mode, not_button),
            (latched, "the stop is latched: Release first"),
            (status == 0, "no robot state yet (waiting for /joint_states)"),
            (engaged, "already engaged"),
        ),
        "disengage": _first(
            (not core_up, "motion_commander is not running (no /motion_commander/status)"),
            (not button_mode, not_button),
            (not engaged, "not engaged"),
        ),
        "speed_ratio": _first(
            (values.get("speed_ratio") is None, "motion_commander is not running (no /motion_commander/speed_ratio)")
        ),
        "filter": _first((values.get("filter") is None, "no sequencer (no /motion_sensor/filter)")),
        "dry_run": _first((no_program, "select a program"), (program_job, busy)),
        "replay": _first(
            (no_program, "select a program"),
            (program_job, busy),
            (not server_up, "no robot server (/motion_controller/latch_stop not available)"),
            (latched, "the stop is latched: Release first"),
            (engaged, "teleop is engaged: take the hand away (or disengage) first"),
            (campaign_job, "a kitting campaign is running"),
        ),
        "delete": _first((no_program, "select a program"), (program_job, busy)),
        "campaign_start": _first(
            (
                not values.get("kitting_cell"),
                "no simulated kitting cell (/kitting_cell_sim/spawn): run launch/kitting_sim.launch",
            ),
            (campaign_job, "a campaign is running"),
            (latched, "the stop is latched: Release first"),
            (program_job, "a program run is in progress"),
        ),
        "campaign_end": _first((not campaign_job, "no campaign is running")),
        "tray_swapped": _first(
            (values.get("tray") is None, "no kitting node (no /kitting/tray)"),
            (campaign_job or _campaign_running(values), "the campaign swaps the tray itself"),
            (not (values.get("tray") or {}).get("filled"), "the tray is empty"),
        ),
        **episode_states(values.get("episodes_status")),
    }


def episode_states(status) -> dict[str, ControlState]:
    """The episode panel's buttons from the recorder's status (None: no recorder)."""
    none = "no episode recorder (start the session with dataset:=FOLDER)"
    recording = bool(status and status.get("recording"))
    idle = "no episode is being recorded"
    return {
        "episode_start": _first((status is None, none), (recording, "an episode is being recorded")),
        "episode_stop": _first((status is None, none), (not recording, idle)),
        "episode_discard": _first((status is None, none), (not recording, idle)),
        "episode_success": _first((status is None, none)),
        "episode_failure": _first((status is None, none)),
    }


@dataclass(frozen=True)
class RatioDecision:
    """What to do with a speed ratio the operator typed: ``value`` to send when ``ok``;
    ``confirm`` when the change is large enough to ask first; ``message`` for the operator
    (why it was refused, or what the confirmation is about)."""

    ok: bool
    value: float | None = None
    confirm: bool = False
    message: str = ""


# A new ratio above this multiple of the one in force is confirmed first: the tool would
# move more than twice as far per hand motion as the operator is used to. Lowering the
# ratio only slows the tool, so it is never held up by a question.
CONFIRM_FACTOR = 2.0


def _range_text(low, high, low_open) -> str:
    return f"{'more than' if low_open else 'from'} {low:g} {'and up to' if low_open else 'to'} {high:g}"


def check_speed_ratio(text, current, low: float, high: float, low_open: bool = False) -> RatioDecision:
    """Check a typed speed ratio against its declared range [low, high] (``low_open``: low
    itself excluded) and the ratio in force (``current``, None when unknown).

    Every refusal names the accepted range; no Python exception text reaches the operator.
    """
    accepted = f"accepted: a number {_range_text(low, high, low_open)}"
    raw = "" if text is None else str(text).strip()
    if not raw:
        return RatioDecision(False, message=f"enter a speed ratio ({accepted})")
    try:
        value = float(raw)
    except ValueError:
        return RatioDecision(False, message=f"'{raw}' is not a number ({accepted})")
    if value != value or value in (float("inf"), float("-inf")):
        return RatioDecision(False, message=f"'{raw}' is not a finite number ({accepted})")
    if value < low or value > high or (low_open and value == low):
        return RatioDecision(False, message=f"{value:g} is out of range ({accepted})")
    if current is not None and current > 0 and value > CONFIRM_FACTOR * current:
        return RatioDecision(
            True,
            value,
            confirm=True,
            message=f"raise the speed ratio from {current:.2f} to {value:.2f} ({value / current:.1f}x)? "
            "The tool will move that much farther per hand motion.",
        )
    return RatioDecision(True, value)
