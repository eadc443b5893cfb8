"""The per-frame input and the output events of gesture recognition (no ROS).

``GestureFrame`` is what the recognisers need from one hand message: the stamp (s), the
palm position (m, REP 103 axes), grab and pinch strength (0-1 as Leap's grabStrength and
pinchStrength; -1 = the device does not say), the number of hands seen and, when the
device gives it, the index fingertip (m). ``GestureEvent`` is what they emit: a name, a
confidence in [0, 1] and the stamp of the frame that completed it.

``frames_from_recording`` turns a Leap v6 recording (``.jsonl[.gz]``, as read by
``leap_v6``) into GestureFrames, and ``frame_from_sample`` a HandSample (what a
motion_sensor/hand message carries) into one.
"""

import gzip
from dataclasses import dataclass

import numpy as np

from motion_sensor.devices.leap_v6 import frame_to_sample, parse_message
from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import UNKNOWN, HandSample


@dataclass
class GestureFrame:
    """One tracking frame as the gesture recognisers see it (SI units, REP 103 axes)."""

    stamp: float
    palm: np.ndarray
    grab: float = UNKNOWN
    pinch: float = UNKNOWN
    hands_num: int = 1
    index_tip: np.ndarray | None = None

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
    info: dict | None = None


def frame_from_sample(sample: HandSample) -> GestureFrame:
    """GestureFrame of a HandSample: palm, grab, pinch, hands and the index tip."""
    return GestureFrame(
        stamp=sample.stamp,
        palm=np.asarray(sample.position, dtype=float),
        grab=float(sample.grab_strength),
        pinch=float(sample.pinch_strength),
        hands_num=int(sample.hands_num),
        index_tip=None if sample.index_tip is None else np.asarray(sample.index_tip, dtype=float),
    )


def frame_from_json(line, stamp: float | None = None, preference: str = "right") -> GestureFrame | None:
    """GestureFrame of one Leap v6 message (JSON text), or None for a frame without a hand
    or a non-frame message; ``stamp`` defaults to the device clock (s). Raises
    MotionSensorError on a malformed frame."""
    parsed = parse_message(line)
    if parsed is None:
        return None
    sample = frame_to_sample(parsed, parsed.timestamp if stamp is None else stamp, preference)
    return None if sample is None else frame_from_sample(sample)


def frames_from_recording(path: str, preference: str = "right") -> list[GestureFrame]:
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
