"""A serialised ``motion_sensor/HandSkeleton``'s joint names and points, read straight from
its bytes (plain Python: the recorder node feeds it, tests feed it directly).

genpy decodes a skeleton field by field, 22 strings and 22 points each through struct: about
0.25 ms, most of the recorder's decoding per frame. The names are the same from one
skeleton to the next, so they are decoded once and recognised by their bytes after that;
the points are one NumPy view. Layout (ROS serialisation, little-endian): header (seq,
stamp secs and nsecs, frame_id), hand_type, hand_id (int32), confidence (float32),
joint_names (count, then each length and bytes), joints (count, then x y z float64 each).
"""

import struct

import numpy as np

__all__ = ["SkeletonReader"]

_U32 = struct.Struct("<I")


class SkeletonReader:
    """``read(raw)`` -> (joint names, points as an N x 3 float64 array); ValueError naming
    what does not add up in a malformed message."""

    def __init__(self):
        self._names_bytes = None
        self._names = []

    def read(self, raw: bytes) -> tuple[list, np.ndarray]:
        try:
            offset = 12  # seq, stamp
            for _ in range(2):  # frame_id, hand_type
                offset += 4 + _U32.unpack_from(raw, offset)[0]
            offset += 8  # hand_id, confidence
            start = offset
            known = self._names_bytes
            if known is not None and raw[start : start + len(known)] == known:
                names, offset = self._names, start + len(known)
            else:
                (count,) = _U32.unpack_from(raw, offset)
                offset += 4
                names = []
                for _ in range(count):
                    (length,) = _U32.unpack_from(raw, offset)
                    names.append(bytes(raw[offset + 4 : offset + 4 + length]).decode("utf-8"))
                    offset += 4 + length
                if offset > len(raw):
                    raise ValueError("joint names run past the end")
                self._names_bytes, self._names = bytes(raw[start:offset]), names
            (count,) = _U32.unpack_from(raw, offset)
        except struct.error as exc:
            raise ValueError(f"HandSkeleton of {len(raw)} bytes: {exc}") from None
        end = offset + 4 + 24 * count
        if end > len(raw):
            raise ValueError(f"HandSkeleton of {len(raw)} bytes: {count} joints do not fit")
        points = np.frombuffer(raw, dtype="<f8", count=3 * count, offset=offset + 4).reshape(count, 3)
        return names, points
