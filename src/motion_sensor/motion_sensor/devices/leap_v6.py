"""Parsing of the Leap Motion WebSocket JSON protocol, version 6.

The Leap service sends ``{"version":6}`` on connect, then one JSON object per tracking
frame. Leap's axes are x right, y up (away from the device), z toward the operator, in
millimetres; everything leaving this module is in metres and REP 103 axes
(x forward away from the operator, y left, z up).
"""

import gzip
import json
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import HandSample
from motion_sensor.skeleton_joints import leap_to_canonical
from motion_sensor.skeleton_sample import SkeletonSample

# Rows map Leap (x right, y up, z toward operator) to REP 103 (x forward, y left, z up):
# forward = -z_leap, left = -x_leap, up = y_leap. A proper rotation (det = +1).
LEAP_TO_REP103 = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

# A Leap frame with all its pointables is 5-15 kB; anything far larger is not a frame.
MAX_MESSAGE_BYTES = 256 * 1024


@dataclass
class LeapHand:
    """One hand of a Leap frame, already in metres and REP 103 axes."""

    hand_id: int
    hand_type: str
    confidence: float
    position: np.ndarray
    orientation: np.ndarray
    stabilized_position: np.ndarray | None
    grab_strength: float = -1.0  # 0 open .. 1 fist; -1 when the frame lacks it
    pinch_strength: float = -1.0  # 0 apart .. 1 touching; -1 when the frame lacks it
    index_tip: np.ndarray | None = None  # m, REP 103; from the frame's pointables
    skeleton: np.ndarray | None = None  # (22, 3) canonical joints (motion_sensor.skeleton_joints), m, REP 103
    direction: np.ndarray | None = None  # palm towards the fingers, unit, REP 103


@dataclass
class LeapFrame:
    """One Leap tracking frame: device timestamp in seconds and its hands."""

    frame_id: int
    timestamp: float
    hands: list[LeapHand]


def _vector(hand: dict, key: str) -> np.ndarray:
    value = hand.get(key)
    if not isinstance(value, list) or len(value) != 3:
        raise MotionSensorError(f"hand field '{key}' must be a list of 3 numbers, got {value!r:.60}")
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise MotionSensorError(f"hand field '{key}' has a non-numeric entry: {value!r:.60}")
    vec = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(vec)):
        raise MotionSensorError(f"hand field '{key}' is not finite: {value!r:.60}")
    return vec


def palm_orientation(palm_normal_leap: np.ndarray, direction_leap: np.ndarray) -> np.ndarray:
    """Quaternion (x, y, z, w) of the hand frame in REP 103 axes.

    The hand frame has x along ``direction`` (palm toward fingers) and z opposite the palm
    normal (out of the back of the hand), so a flat, palm-down hand pointing away from the
    operator is the identity.
    """
    x_axis = LEAP_TO_REP103 @ direction_leap
    z_axis = -(LEAP_TO_REP103 @ palm_normal_leap)
    x_norm = np.linalg.norm(x_axis)
    if x_norm < 1e-6:
        raise MotionSensorError("hand 'direction' is a zero vector; the frame cannot give an orientation")
    x_axis = x_axis / x_norm
    # Leap's two vectors are only nearly orthogonal; Gram-Schmidt keeps direction exact.
    z_axis = z_axis - np.dot(z_axis, x_axis) * x_axis
    z_norm = np.linalg.norm(z_axis)
    if z_norm < 1e-6:
        raise MotionSensorError("hand 'palmNormal' is parallel to 'direction'; the frame cannot give an orientation")
    z_axis = z_axis / z_norm
    y_axis = np.cross(z_axis, x_axis)
    return Rotation.from_matrix(np.column_stack([x_axis, y_axis, z_axis])).as_quat()


def _strength(hand: dict, key: str) -> float:
    """A 0-1 strength field, or -1 (unknown) when absent."""
    if key not in hand:
        return -1.0
    value = hand[key]
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not 0.0 <= value <= 1.0:
        raise MotionSensorError(f"hand field '{key}' must be a number in [0, 1], got {value!r:.40}")
    return float(value)


INDEX_FINGER = 1  # Leap pointable type: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky


def index_tips(pointables) -> dict:
    """{hand id: index finger tip (m, REP 103)} from a frame's pointables; bad ones skipped
    (a pointable is optional detail: it never costs the frame)."""
    tips = {}
    if not isinstance(pointables, list):
        return tips
    for pointable in pointables:
        if not isinstance(pointable, dict) or pointable.get("type") != INDEX_FINGER:
            continue
        try:
            tips[pointable.get("handId")] = LEAP_TO_REP103 @ _vector(pointable, "tipPosition") / 1000.0
        except MotionSensorError:
            continue
    return tips


_FINGER_JOINTS = ("mcpPosition", "pipPosition", "dipPosition", "tipPosition")


def hand_skeletons(pointables, hands) -> dict:
    """{hand id: canonical (22, 3) skeleton} of the hands whose five fingers all have their
    four joints in the frame's pointables (``skeleton_joints.leap_to_canonical``); a hand
    with a missing or malformed finger gets none (the palm stream never depends on it)."""
    fingers = {}
    if not isinstance(pointables, list):
        return {}
    for pointable in pointables:
        # Plain lists and one array per finger: this runs on every frame before the palm
        # is published (a per-vector validation cost twice the palm's own parse).
        if not isinstance(pointable, dict) or pointable.get("type") not in (0, 1, 2, 3, 4):
            continue
        try:
            joints = np.array([pointable[key] for key in _FINGER_JOINTS], dtype=float)
        except (KeyError, TypeError, ValueError):
            continue
        if joints.shape == (4, 3):
            fingers.setdefault(pointable.get("handId"), {})[pointable["type"]] = joints
    skeletons = {}
    for hand in hands:
        found = fingers.get(hand.hand_id, {})
        if len(found) != 5 or hand.direction is None:
            continue
        leap = np.stack([found[f] for f in range(5)])  # (5, 4, 3) mm, Leap axes
        if not np.all(np.isfinite(leap)):
            continue
        skeletons[hand.hand_id] = leap_to_canonical(hand.position, hand.direction, leap @ (LEAP_TO_REP103.T / 1000.0))
    return skeletons


def parse_hand(hand: dict) -> LeapHand:
    """Convert one Leap v6 hand object; raise MotionSensorError naming the bad field."""
    if not isinstance(hand, dict):
        raise MotionSensorError(f"a hand must be a JSON object, got {type(hand).__name__}")
    hand_type = hand.get("type")
    if hand_type not in ("left", "right"):
        raise MotionSensorError(f'hand field \'type\' must be "left" or "right", got {hand_type!r:.40}')
    hand_id = hand.get("id")
    if not isinstance(hand_id, int) or isinstance(hand_id, bool):
        raise MotionSensorError(f"hand field 'id' must be an integer, got {hand_id!r:.40}")
    confidence = hand.get("confidence", 1.0)
    if not isinstance(confidence, (int, float)) or not math.isfinite(confidence):
        raise MotionSensorError(f"hand field 'confidence' must be a finite number, got {confidence!r:.40}")
    position = LEAP_TO_REP103 @ _vector(hand, "palmPosition") / 1000.0
    orientation = palm_orientation(_vector(hand, "palmNormal"), _vector(hand, "direction"))
    direction = LEAP_TO_REP103 @ _vector(hand, "direction")
    direction = direction / max(float(np.linalg.norm(direction)), 1e-9)
    stabilized = None
    if "stabilizedPalmPosition" in hand:
        stabilized = LEAP_TO_REP103 @ _vector(hand, "stabilizedPalmPosition") / 1000.0
    return LeapHand(
        hand_id,
        hand_type,
        float(confidence),
        position,
        orientation,
        stabilized,
        _strength(hand, "grabStrength"),
        _strength(hand, "pinchStrength"),
        direction=direction,
    )


def parse_message(text, max_bytes: int = MAX_MESSAGE_BYTES) -> LeapFrame | None:
    """Parse one WebSocket message; return its LeapFrame, or None for a non-frame message.

    Non-frame messages are the ``{"version": N}`` handshake and event messages. Raises
    MotionSensorError for oversized, malformed or truncated JSON and for missing or
    wrong-typed fields, so the caller can count and skip the message.
    """
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="replace")
    if len(text) > max_bytes:
        raise MotionSensorError(f"message of {len(text)} bytes exceeds the {max_bytes}-byte limit")
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise MotionSensorError(f"malformed or truncated JSON ({exc.msg} at char {exc.pos})") from None
    if not isinstance(obj, dict):
        raise MotionSensorError(f"a Leap message must be a JSON object, got {type(obj).__name__}")
    if "hands" not in obj and ("version" in obj or "event" in obj):
        return None
    timestamp = obj.get("timestamp")
    if not isinstance(timestamp, (int, float)) or isinstance(timestamp, bool) or not math.isfinite(timestamp):
        raise MotionSensorError(f"frame field 'timestamp' must be a number of microseconds, got {timestamp!r:.40}")
    hands = obj.get("hands")
    if not isinstance(hands, list):
        raise MotionSensorError(f"frame field 'hands' must be a list, got {type(hands).__name__}")
    frame_id = obj.get("id", -1)
    if not isinstance(frame_id, int) or isinstance(frame_id, bool):
        raise MotionSensorError(f"frame field 'id' must be an integer, got {frame_id!r:.40}")
    parsed = [parse_hand(h) for h in hands]
    tips = index_tips(obj.get("pointables"))
    skeletons = hand_skeletons(obj.get("pointables"), parsed)
    for leap_hand in parsed:
        leap_hand.index_tip = tips.get(leap_hand.hand_id)
        leap_hand.skeleton = skeletons.get(leap_hand.hand_id)
    return LeapFrame(frame_id, timestamp * 1e-6, parsed)


def select_primary(frame: LeapFrame, preference: str = "right", strict: bool = False) -> LeapHand | None:
    """Pick the primary hand: the preferred type if present, else the first hand.

    ``preference`` is "right", "left" or "first" (device order). With ``strict`` only the
    preferred type is ever picked (None without it): each arm of a bimanual session
    follows its own hand and never falls over to the other one.
    """
    if preference not in ("right", "left", "first"):
        raise MotionSensorError(f"primary hand preference must be right, left or first, not {preference!r}")
    if not frame.hands:
        return None
    if preference != "first":
        for hand in frame.hands:
            if hand.hand_type == preference:
                return hand
        if strict:
            return None
    return frame.hands[0]


def frame_to_sample(
    frame: LeapFrame, stamp: float, preference: str = "right", frame_id: str = "leap", strict: bool = False
) -> HandSample | None:
    """Build the HandSample of a frame's primary hand, or None when no hand is seen.

    The primary hand is listed first in ``hand_types`` so consumers can read its type.
    """
    primary = select_primary(frame, preference, strict)
    if primary is None:
        return None
    others = [h.hand_type for h in frame.hands if h is not primary]
    return HandSample(
        stamp=stamp,
        position=primary.position,
        orientation=primary.orientation,
        hands_num=len(frame.hands),
        hand_types=tuple([primary.hand_type] + others),
        frame_id=frame_id,
        hand_id=primary.hand_id,
        device="leap",
        extra={"confidence": primary.confidence, "device_time": frame.timestamp},
        confidence=primary.confidence,
        grab_strength=primary.grab_strength,
        pinch_strength=primary.pinch_strength,
        index_tip=primary.index_tip,
        skeletons=tuple(
            SkeletonSample(stamp, h.skeleton, h.hand_type, h.hand_id, h.confidence, frame_id, "leap")
            for h in [primary] + [h for h in frame.hands if h is not primary]
            if h.skeleton is not None
        ),
    )


@dataclass
class LeapRecording:
    """A Leap v6 recording: its frames and the lines that could not be used."""

    path: str
    frames: list[LeapFrame]
    rejected: list[str]

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame (device clock)."""
        return self.frames[-1].timestamp - self.frames[0].timestamp if len(self.frames) > 1 else 0.0


def read_recording(path: str) -> LeapRecording:
    """Read a ``.jsonl`` or ``.jsonl.gz`` Leap v6 recording (one message per line).

    Bad lines are skipped and listed in ``rejected`` with their line number and reason, so
    one corrupt frame never loses the rest of a recording.
    """
    opener = gzip.open if path.endswith(".gz") else open
    frames, rejected = [], []
    try:
        with opener(path, "rt", encoding="utf-8") as fh:
            for lineno, line in enumerate(fh, start=1):
                if not line.strip():
                    continue
                try:
                    frame = parse_message(line)
                except MotionSensorError as exc:
                    rejected.append(f"line {lineno}: {exc}")
                    continue
                if frame is not None:
                    frames.append(frame)
    except (OSError, EOFError, UnicodeDecodeError) as exc:
        raise MotionSensorError(
            f"cannot read Leap recording {path}: {exc}; give a .jsonl or .jsonl.gz file in the Leap v6 format"
        ) from None
    if not frames:
        raise MotionSensorError(
            f"Leap recording {path} holds no tracking frame "
            f"({len(rejected)} lines rejected); is it a Leap v6 .jsonl recording?"
        )
    return LeapRecording(path, frames, rejected)
