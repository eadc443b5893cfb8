"""Plain readings of ROS message contents for the page (no ROS import: the node passes
key/value pairs and numbers)."""

from collections import deque
from collections.abc import Iterable

import numpy as np


def sequencer_counters(values: Iterable[tuple[str, str]]) -> dict[str, object]:
    """Frames in/out, drops by reason and latency from the sequencer's /diagnostics values.

    Values that are not numbers are kept as text (e.g. active_device); unparsable numbers
    are skipped rather than failing the whole message.
    """
    drops, out = {}, {}
    for key, value in values:
        if key.startswith("dropped_") and key != "dropped_total":
            try:
                drops[key[len("dropped_") :]] = int(value)
            except ValueError:
                continue
        elif key in ("frames_in", "frames_out", "dropped_total", "filter_switches"):
            try:
                out[key] = int(value)
            except ValueError:
                continue
        elif key in ("latency_p50_ms", "latency_p99_ms"):
            try:
                out[key] = float(value)
            except ValueError:
                continue
        elif key == "active_device":
            out[key] = value
    out["drops"] = dict(sorted(drops.items()))
    return out


def _truth(text: str) -> bool | None:
    return {"true": True, "false": False}.get(str(text).strip().lower())


def driver_status(values: Iterable[tuple[str, str]], message: str, level: int) -> dict[str, object]:
    """Connected, fault, protective stop and latched stop from /motion_controller/status."""
    by_key = dict(values)
    fault = by_key.get("fault", "")
    return {
        "connected": _truth(by_key.get("connected", "")),
        "fault": "" if fault in ("", "None") else fault,
        "protective_stop": _truth(by_key.get("protective_stop", "")),
        "stop_latched": _truth(by_key.get("stop_latched", "")),
        "message": message,
        "level": int(level),
    }


class LatencyWindow:
    """The last ``size`` sensor-to-driver latencies (s), for p50/p99 on the page."""

    def __init__(self, size: int = 500):
        self._values = deque(maxlen=size)

    def add(self, seconds: float) -> None:
        """Record one command's latency; non-finite or negative values are ignored."""
        if np.isfinite(seconds) and seconds >= 0.0:
            self._values.append(float(seconds))

    def percentiles_ms(self) -> tuple[float, float, int] | None:
        """(p50, p99, count) in ms, or None before the first command."""
        if not self._values:
            return None
        p50, p99 = np.percentile(np.asarray(self._values) * 1000.0, [50, 99])
        return float(p50), float(p99), len(self._values)


def tool_reading(position, quaternion) -> dict[str, list]:
    """Tool pose for the page: xyz in mm and roll/pitch/yaw (fixed x-y-z axes) in degrees
    from a quaternion (x, y, z, w)."""
    x, y, z, w = (float(v) for v in quaternion)
    norm = float(np.sqrt(x * x + y * y + z * z + w * w)) or 1.0
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return {
        "xyz_mm": [1000.0 * float(v) for v in position],
        "rpy_deg": [float(np.degrees(a)) for a in (roll, pitch, yaw)],
    }


def device_label(launch_device: str, active_device: str | None, application: str = "teleop") -> str:
    """The input device as the operator knows it: the session launch's ``device`` argument
    (replay, leap, webcam, ...), with the sequencer's active input after it when that adds
    something. The sequencer names a lone input "default", which says nothing to an
    operator, so it is never shown alone."""
    launch_device = (launch_device or "").strip()
    active = (active_device or "").strip()
    if application == "kitting" and launch_device.isdigit():
        launch_device = f"camera /dev/video{launch_device}"
    informative = active and active != "default" and active != launch_device
    if launch_device:
        return f"{launch_device} (input {active})" if informative else launch_device
    if informative:
        return active
    if active:
        return "one input (the launch did not name the device)"
    return "-"


def image_data_url(data: bytes, image_format: str) -> str | None:
    """A compressed camera frame (sensor_msgs/CompressedImage: ``format`` "jpeg" or "png",
    possibly with a prefix such as "bgr8; jpeg compressed bgr8") as a data URL an <img> shows
    directly; None for a format a browser cannot show or an empty frame."""
    import base64

    kind = str(image_format).lower()
    mime = "image/jpeg" if ("jpeg" in kind or "jpg" in kind) else "image/png" if "png" in kind else None
    if mime is None or not data:
        return None
    return f"data:{mime};base64,{base64.b64encode(bytes(data)).decode('ascii')}"


def campaign_line(key: str, data: dict) -> str:
    """A kitting campaign's progress or result (kitting_trials' JSON) as one log line."""
    if not isinstance(data, dict):
        return f"{key}: unreadable"
    if "error" in data:
        return f"campaign error: {data['error']}"
    per_class = data.get("per_class") or {}
    picked = sum(int(row.get("picked", 0)) for row in per_class.values() if isinstance(row, dict))
    placed = sum(int(row.get("placed", 0)) for row in per_class.values() if isinstance(row, dict))
    kits = kit_score_text(data)
    if key == "campaign_result":
        return f"campaign done: {data.get('successes', placed)}/{data.get('trials', '?')} placed" + kits
    return (
        f"trial {data.get('done', '?')}/{data.get('trials', '?')} done: {picked} picked, {placed} placed so far" + kits
    )


def kit_score_text(data: dict) -> str:
    """', kit score S/M (P %) over K kit(s)' (ARIAC's kitting score of the trays swapped so
    far), or '' before the first kit is scored."""
    try:
        kits, score, best = int(data["kits"]), float(data["kit_score"]), float(data["kit_score_max"])
    except (KeyError, TypeError, ValueError):
        return ""
    if kits <= 0 or best <= 0:
        return ""
    return f", kit score {score:g}/{best:g} ({100 * score / best:.0f} %) over {kits} kit(s)"


def kitting_event_line(event: str, class_name: str, track_id: int, reason: str = "") -> str:
    """One /kitting/events message (pick, place, miss, ...) as a log line."""
    text = f"{event} {class_name or 'part'} #{int(track_id)}"
    return f"{text}: {reason}" if reason else text
