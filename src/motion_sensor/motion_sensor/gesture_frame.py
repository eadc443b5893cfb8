"""The per-frame input and the output events of gesture recognition (no ROS).

``GestureFrame`` is what the recognisers need from one hand message: the stamp (s), the
palm position (m, REP 103 axes), grab and pinch strength (0-1 as Leap's grabStrength and
pinchStrength; -1 = the device does not say), the number of hands seen and, when the
device gives it, the index fingertip (m). ``GestureEvent`` is what they emit: a name, a
confidence in [0, 1] and the stamp of the frame that completed it.

``frames_from_recording`` turns a Leap v6 recording (``.jsonl[.gz]``, as read by
``leap_v6``) into GestureFrames: the palm comes from ``leap_v6.parse_message`` /
``frame_to_sample`` (metres, REP 103); grab, pinch and the index tip (pointable type 1 of
the primary hand) are read from the same JSON line, since LeapFrame does not keep them.
"""
import gzip
import json
from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from .errors import MotionSensorError
from .leap_v6 import LEAP_TO_REP103, frame_to_sample, parse_message, select_primary

UNKNOWN = -1.0
INDEX_FINGER = 1  # Leap pointable type of the index finger


@dataclass
class GestureFrame:
    """One tracking frame as the gesture recognisers see it (SI units, REP 103 axes)."""

    stamp: float
    palm: np.ndarray
    grab: float = UNKNOWN
    pinch: float = UNKNOWN
    hands_num: int = 1
    index_tip: Optional[np.ndarray] = None

    def point(self, source: str = "palm") -> np.ndarray:
        """The tracked point: "palm", or "index" (the palm when the tip is unknown)."""
        if source == "index" and self.index_tip is not None:
            return self.index_tip
        return self.palm


@dataclass
class GestureEvent:
    """A recognised gesture: ``name``, ``confidence`` (0-1), ``stamp`` (s) of the frame
    that completed it; ``info`` holds detector details (e.g. the DTW distance)."""

    name: str
    confidence: float
    stamp: float
    info: Optional[dict] = None


def _strength(hand: dict, key: str) -> float:
    value = hand.get(key)
    if isinstance(value, (int, float)) and not isinstance(value, bool) and 0.0 <= value <= 1.0:
        return float(value)
    return UNKNOWN


def frame_from_json(line, stamp: Optional[float] = None, preference: str = "right") -> Optional[GestureFrame]:
    """GestureFrame of one Leap v6 message (JSON text), or None for a frame without a hand
    or a non-frame message; ``stamp`` defaults to the device clock (s). Raises
    MotionSensorError on a malformed frame."""
    parsed = parse_message(line)
    if parsed is None:
        return None
    sample = frame_to_sample(parsed, parsed.timestamp if stamp is None else stamp, preference)
    if sample is None:
        return None
    return _with_raw(parsed, json.loads(line), sample, preference)


def frames_from_recording(path: str, preference: str = "right") -> List[GestureFrame]:
    """Every frame with a hand of a Leap v6 recording, stamped with the device clock (s).
    Malformed lines are skipped (as ``leap_v6.read_recording`` does)."""
    opener = gzip.open if path.endswith(".gz") else open
    frames = []
    try:
        with opener(path, "rt", encoding="utf-8") as fh:
            for line in fh:
                if not line.strip():
                    continue
                try:
                    frame = frame_from_json(line, None, preference)
                except MotionSensorError:
                    continue
                if frame is not None:
                    frames.append(frame)
    except (OSError, EOFError, UnicodeDecodeError) as exc:
        raise MotionSensorError(f"cannot read Leap recording {path}: {exc}") from None
    return frames


def _with_raw(parsed, obj, sample, preference) -> GestureFrame:
    primary = select_primary(parsed, preference)
    raw = next((h for h in obj.get("hands", []) if h.get("id") == primary.hand_id), {})
    tip = None
    for pointable in obj.get("pointables", []) or []:
        if pointable.get("type") == INDEX_FINGER and pointable.get("handId") == primary.hand_id:
            value = pointable.get("tipPosition")
            if isinstance(value, list) and len(value) == 3 and all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                tip = LEAP_TO_REP103 @ np.asarray(value, dtype=float) / 1000.0
            break
    return GestureFrame(stamp=sample.stamp, palm=np.asarray(sample.position, dtype=float),
                        grab=_strength(raw, "grabStrength"), pinch=_strength(raw, "pinchStrength"),
                        hands_num=sample.hands_num, index_tip=tip)
