"""The kitting tray as the kitting panel shows it: the kitting node's latched
``kitting/tray`` message (JSON: the slots' classes, those filled since the last swap,
whether the kit is complete) read and checked, and its one-line reading."""

from .episodes import parse_episode_message as parse_json_message

__all__ = ["parse_tray", "tray_text"]


def parse_tray(text: str):
    """({"slots", "filled", "complete"}, "") from a ``kitting/tray`` message, or (None, why)."""
    data, reason = parse_json_message(text, dict)
    if data is None:
        return None, reason
    slots, filled = data.get("slots"), data.get("filled")
    if not isinstance(slots, list) or not slots or not all(isinstance(name, str) for name in slots):
        return None, "'slots' must be a non-empty list of class names"
    if not isinstance(filled, list) or not all(isinstance(name, str) and name in slots for name in filled):
        return None, "'filled' must list classes of the tray's slots"
    every = set(filled) == set(slots)
    complete = data.get("complete", every)
    if not isinstance(complete, bool):
        return None, "'complete' must be true or false"
    if complete != every:
        return None, f"'complete' is {str(complete).lower()} with {len(set(filled))} of {len(slots)} slots filled"
    return {"slots": slots, "filled": filled, "complete": complete}, ""


def tray_text(tray) -> str:
    """'tray: 2/6 slots filled (bolt_silver, nut_yellow)', or what to do when the kit is
    complete, or that no kitting node reports a tray."""
    if tray is None:
        return "tray: no kitting node (kitting/tray)"
    filled, slots = tray["filled"], tray["slots"]
    if tray["complete"]:
        return f"kit complete ({len(slots)}/{len(slots)} slots): take the tray away, then press Tray swapped"
    return f"tray: {len(filled)}/{len(slots)} slots filled" + (f" ({', '.join(filled)})" if filled else "")
