"""The episode panel's readings: the recorder's JSON messages (episodes/status,
episodes/list) checked, and turned into the panel's status line and table rows. A malformed
message is refused with its reason (the node logs it and keeps the last good one). Plain
Python."""

import json

__all__ = ["parse_episode_message", "episode_status_text", "episode_rows"]


def parse_episode_message(text: str, kind: type):
    """(value, "") from a recorder message holding a JSON ``kind`` (dict or list), or
    (None, reason)."""
    try:
        value = json.loads(text)
    except ValueError as exc:
        return None, f"not JSON: {exc}"
    if not isinstance(value, kind):
        return None, f"a JSON {kind.__name__} was expected, got {type(value).__name__}"
    return value, ""


def episode_status_text(status) -> str:
    if status is None:
        return "no episode recorder (start the session with dataset:=FOLDER)"
    if status.get("recording"):
        mark = {True: ", marked success", False: ", marked failure"}.get(status.get("success"), "")
        text = f"recording episode {status.get('episode_index')}: {status.get('frames', 0)} frames{mark}"
    else:
        text = "idle"
    last = status.get("last_result")
    return f"{text} - {last}" if last else text


def episode_rows(episodes: list) -> list:
    """Newest first: index, task, frames, seconds, outcome, camera loss."""
    rows = []
    for record in reversed(episodes):
        if not isinstance(record, dict):
            continue
        loss = record.get("camera_loss_fraction")
        rows.append(
            {
                "episode": record.get("episode_index", "?"),
                "task": record.get("task", ""),
                "frames": record.get("frames", 0),
                "seconds": record.get("duration_s", ""),
                "outcome": "success" if record.get("success") else "failure",
                "camera loss": "-" if loss is None else f"{100 * float(loss):.1f} %",
            }
        )
    return rows
