"""The CSV layout of a recorded hand stream, with or without whole-hand skeletons:
reading it (the replay) and writing it (``hands_to_csv``).

One row per hand seen and frame, in time order; consecutive rows with the same ``stamp``
are one frame (a frame with two hands has two rows, the steering hand first). Columns:

- ``stamp`` (s, any origin), ``x,y,z`` (palm, m, REP 103), ``qx,qy,qz,qw`` (palm
  orientation, unit quaternion), ``hand_type`` ("left", "right"; empty: a frame without a
  hand, whose other cells may be empty);
- optional ``hand_id`` (integer, -1 unknown) and ``confidence`` (0-1, -1 unknown);
- optional skeleton: the 66 columns ``<joint>_x,<joint>_y,<joint>_z`` for each joint of
  ``motion_sensor.skeleton_joints.JOINT_NAMES`` (``wrist_x`` ... ``pinky_tip_z``; metres,
  REP 103, the device frame). A row gives all 66 or none (a hand seen without fingers).
  With a skeleton the palm pose may be left empty: it is then the skeleton's palm joint
  and ``palm_quaternion``.

A row that cannot be used (a cell that is no number, a partial skeleton, an unknown
hand_type, neither pose nor skeleton) is skipped and listed with its line and reason; it
never stops the replay. A file without the required columns, or without one usable row,
is rejected whole (MotionSensorError naming it).
"""

import csv
import math
import os
import tempfile

import numpy as np

from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import HandSample
from motion_sensor.skeleton_joints import JOINT_NAMES, check_skeleton, palm_quaternion
from motion_sensor.skeleton_sample import SkeletonSample

__all__ = ["CSV_COLUMNS", "OPTIONAL_COLUMNS", "SKELETON_COLUMNS", "read_csv", "write_csv"]

CSV_COLUMNS = ("stamp", "x", "y", "z", "qx", "qy", "qz", "qw", "hand_type")
OPTIONAL_COLUMNS = ("hand_id", "confidence")
SKELETON_COLUMNS = tuple(f"{joint}_{axis}" for joint in JOINT_NAMES for axis in "xyz")
_POSE = CSV_COLUMNS[1:8]


class _RowError(ValueError):
    """Why one row cannot be used."""


def _number(row, column) -> float:
    text = (row.get(column) or "").strip()
    try:
        value = float(text)
    except ValueError:
        raise _RowError(f"{column} {text!r} is not a number") from None
    if not math.isfinite(value):
        raise _RowError(f"{column} {text!r} is not finite")
    return value


def _empty(row, columns) -> bool:
    return all(not (row.get(column) or "").strip() for column in columns)


def _parse_row(row, has_skeleton: bool) -> dict:
    """One data row as {stamp, hand_type, position, orientation, hand_id, confidence,
    joints}, or _RowError."""
    stamp = _number(row, "stamp")
    hand_type = (row.get("hand_type") or "").strip()
    if hand_type not in ("", "left", "right"):
        raise _RowError(f"hand_type must be left, right or empty, not {hand_type!r}")
    parsed = {"stamp": stamp, "hand_type": hand_type, "joints": None}
    if not hand_type:
        return parsed
    if has_skeleton and not _empty(row, SKELETON_COLUMNS):
        joints = np.array([_number(row, column) for column in SKELETON_COLUMNS]).reshape(len(JOINT_NAMES), 3)
        parsed["joints"] = check_skeleton(joints, "skeleton")
    if _empty(row, _POSE):
        if parsed["joints"] is None:
            raise _RowError("neither a palm pose (x..qw) nor a skeleton")
        parsed["position"] = parsed["joints"][JOINT_NAMES.index("palm")].copy()
        parsed["orientation"] = palm_quaternion(parsed["joints"])
    else:
        values = np.array([_number(row, column) for column in _POSE])
        parsed["position"], parsed["orientation"] = values[:3], values[3:]
    parsed["hand_id"] = int(_number(row, "hand_id")) if not _empty(row, ("hand_id",)) else -1
    parsed["confidence"] = _number(row, "confidence") if not _empty(row, ("confidence",)) else -1.0
    return parsed


def _frame_sample(rows, preference: str, strict: bool, frame_id: str) -> HandSample:
    """The HandSample of one frame's rows: the preferred hand steers (as the Leap driver
    picks its primary hand), every hand's skeleton rides along, the steering one first."""
    stamp = rows[0]["stamp"]
    hands = [row for row in rows if row["hand_type"]]
    primary = next((row for row in hands if row["hand_type"] == preference), None)
    if primary is None and not strict and hands:
        primary = hands[0]
    if primary is None:
        return HandSample(stamp, np.zeros(3), np.zeros(4), 0, (), frame_id, device="csv")
    ordered = [primary] + [row for row in hands if row is not primary]
    return HandSample(
        stamp=stamp,
        position=primary["position"],
        orientation=primary["orientation"],
        hands_num=len(ordered),
        hand_types=tuple(row["hand_type"] for row in ordered),
        frame_id=frame_id,
        hand_id=primary["hand_id"],
        device="csv",
        confidence=primary["confidence"],
        skeletons=tuple(
            SkeletonSample(stamp, row["joints"], row["hand_type"], row["hand_id"], row["confidence"], frame_id, "csv")
            for row in ordered
            if row["joints"] is not None
        ),
    )


def read_csv(path: str, preference: str = "right", strict: bool = False, frame_id: str = "leap"):
    """(HandSamples, rejected lines) of a CSV hand stream (the module's layout).

    ``preference`` ("right", "left", "first") picks the steering hand of a frame with two;
    with ``strict`` a frame without that hand type is one without a hand. Bad rows are
    skipped and listed ("line N: reason"), never fatal."""
    frames, rejected = [], []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            header = reader.fieldnames or []
            missing = [c for c in CSV_COLUMNS if c not in header]
            if missing:
                raise MotionSensorError(f"CSV {path} lacks columns {missing}; expected {','.join(CSV_COLUMNS)}")
            given = [c for c in SKELETON_COLUMNS if c in header]
            if given and len(given) < len(SKELETON_COLUMNS):
                absent = [c for c in SKELETON_COLUMNS if c not in header]
                raise MotionSensorError(
                    f"CSV {path} has {len(given)} of the {len(SKELETON_COLUMNS)} skeleton columns "
                    f"(missing {absent[:3]}...): give all of wrist_x ... pinky_tip_z or none"
                )
            for lineno, row in enumerate(reader, start=2):
                try:
                    parsed = _parse_row(row, bool(given))
                except (_RowError, ValueError) as exc:
                    rejected.append(f"line {lineno}: {exc}")
                    continue
                if frames and frames[-1][0]["stamp"] == parsed["stamp"]:
                    frame = frames[-1]
                    if not parsed["hand_type"] or not all(r["hand_type"] for r in frame):
                        rejected.append(f"line {lineno}: a frame's rows are either hands or one row without a hand")
                    elif any(r["hand_type"] == parsed["hand_type"] for r in frame):
                        rejected.append(f"line {lineno}: a second {parsed['hand_type']} hand in one frame")
                    else:
                        frame.append(parsed)
                else:
                    frames.append([parsed])
    except OSError as exc:
        raise MotionSensorError(f"cannot read CSV {path}: {exc}") from None
    except csv.Error as exc:
        raise MotionSensorError(f"CSV {path} is not readable as CSV: {exc}") from None
    if not frames:
        raise MotionSensorError(f"CSV {path} holds no usable row ({len(rejected)} rejected)")
    return [_frame_sample(rows, preference, strict, frame_id) for rows in frames], rejected


def _cells(values) -> list[str]:
    return [repr(float(v)) for v in values]


def write_csv(path: str, samples) -> int:
    """Write HandSamples (with their skeletons, if any) as a CSV of this layout, atomically
    (a temporary file, then os.replace: a failed write leaves an existing file as it was).
    A hand other than the steering one is written only when its skeleton is known (its pose
    is then the skeleton's). Returns the number of rows written."""
    header = list(CSV_COLUMNS) + list(OPTIONAL_COLUMNS) + list(SKELETON_COLUMNS)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    rows = 0
    fd, tmp = tempfile.mkstemp(prefix=".hands-", suffix=".csv.tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as fh:
            writer = csv.writer(fh)
            writer.writerow(header)
            for sample in samples:
                stamp = repr(float(sample.stamp))
                if not sample.hands_num or not sample.hand_types:
                    writer.writerow([stamp] + [""] * (len(header) - 1))
                    rows += 1
                    continue
                skeletons = {s.hand_type: s for s in sample.skeletons}
                for index, hand_type in enumerate(sample.hand_types):
                    skeleton = skeletons.get(hand_type)
                    if index == 0:
                        pose = _cells(np.concatenate([sample.position, sample.orientation]))
                        hand_id, confidence = sample.hand_id, sample.confidence
                    elif skeleton is not None:
                        pose = [""] * len(_POSE)
                        hand_id, confidence = skeleton.hand_id, skeleton.confidence
                    else:
                        continue
                    joints = _cells(np.ravel(skeleton.joints)) if skeleton is not None else [""] * len(SKELETON_COLUMNS)
                    writer.writerow([stamp] + pose + [hand_type, str(int(hand_id)), repr(float(confidence))] + joints)
                    rows += 1
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return rows
