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
