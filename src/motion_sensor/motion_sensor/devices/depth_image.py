"""Depth images and camera intrinsics, checked, without ROS.

``decode_depth`` turns the fields of a sensor_msgs/Image (16UC1 in millimetres or 32FC1 in
metres, the two encodings REP 118 allows for depth) into a float32 array of metres where 0
means "no measurement" (NaN, inf, 0 and out-of-range values all become 0, so the tracker
compares numbers only). ``intrinsics_from_camera_info`` reads the pinhole part of a
sensor_msgs/CameraInfo (checked by ``motion_common.camera_model``). Anything unusable
raises ``DepthImageError`` whose ``reason`` is a short key the device counts on
/diagnostics (``rejected_<reason>``).
"""

from collections.abc import Sequence

import numpy as np

from motion_common.camera_model import CameraInfoError, Intrinsics
from motion_common.camera_model import intrinsics_from_camera_info as _intrinsics_from_camera_info
from motion_sensor.errors import MotionSensorError

#: Depths beyond this are no measurement (m): no depth camera sees further.
MAX_RANGE_M = 20.0


class DepthImageError(MotionSensorError):
    """A depth image or camera info that cannot be used; ``reason`` is its counter key."""

    def __init__(self, reason: str, message: str):
        super().__init__(message)
        self.reason = reason


def intrinsics_from_camera_info(k: Sequence[float], width: int, height: int) -> Intrinsics:
    """Intrinsics from CameraInfo's row-major 3x3 ``K`` and image size; DepthImageError
    ("invalid_camera_info") when they describe no usable pinhole camera."""
    try:
        return _intrinsics_from_camera_info({"K": k, "width": width, "height": height})
    except CameraInfoError as exc:
        hint = ": calibrate the camera" if exc.reason == "uncalibrated" else ""
        raise DepthImageError("invalid_camera_info", f"{exc}{hint}") from None


_ENCODINGS = {"16UC1": (np.uint16, 2, 0.001), "mono16": (np.uint16, 2, 0.001), "32FC1": (np.float32, 4, 1.0)}


def decode_depth(
    encoding: str,
    width: int,
    height: int,
    step: int,
    data,
    is_bigendian: bool = False,
    min_valid_fraction: float = 0.001,
) -> np.ndarray:
    """Metres, float32 (height, width), 0 where there is no measurement.

    Raises DepthImageError with reason ``encoding`` (not 16UC1/32FC1), ``size`` (step or
    data length inconsistent with width and height), ``empty_depth`` (almost no pixel
    measured: all-zero, all-NaN, a covered lens) or ``saturated_depth`` (almost every pixel
    at the encoding's maximum or beyond range).
    """
    if encoding not in _ENCODINGS:
        raise DepthImageError(
            "encoding",
            f"depth encoding {encoding!r} is not 16UC1 (mm) or 32FC1 (m); "
            "point the driver at the depth image topic, not the colour one",
        )
    dtype, size, scale = _ENCODINGS[encoding]
    if width <= 0 or height <= 0 or step < width * size:
        raise DepthImageError("size", f"depth image {width}x{height} with step {step} (need >= {width * size})")
    buffer = memoryview(data).cast("B") if not isinstance(data, (bytes, bytearray)) else data
    if len(buffer) != step * height:
        raise DepthImageError("size", f"depth image data holds {len(buffer)} bytes, step*height is {step * height}")
    if step % size:
        raise DepthImageError("size", f"depth image step {step} is not a multiple of the pixel size {size}")
    order = ">" if is_bigendian else "<"
    raw = np.frombuffer(buffer, dtype=np.dtype(dtype).newbyteorder(order)).reshape(height, step // size)[:, :width]
    if dtype is np.uint16:
        saturated = raw == 0xFFFF
        depth = raw.astype(np.float32) * np.float32(scale)
        depth[saturated] = 0.0
    else:
        depth = raw.astype(np.float32)
        saturated = np.isposinf(depth) | (depth > MAX_RANGE_M)
        depth[~np.isfinite(depth) | (depth < 0) | (depth > MAX_RANGE_M)] = 0.0
    valid = np.count_nonzero(depth)
    if valid < min_valid_fraction * depth.size:
        if np.count_nonzero(saturated) > 0.5 * depth.size:
            raise DepthImageError(
                "saturated_depth",
                f"depth image saturated: {np.count_nonzero(saturated)} of "
                f"{depth.size} pixels at the maximum; too close or blinded",
            )
        raise DepthImageError(
            "empty_depth",
            f"depth image has {valid} measured pixels of {depth.size} "
            "(all zero or NaN): lens covered or the camera not streaming",
        )
    return depth


def encode_depth_mm(depth_m: np.ndarray) -> bytes:
    """16UC1 little-endian bytes (mm) of a metres array, 0 where depth is 0 (tests, demos)."""
    return np.clip(np.rint(np.asarray(depth_m) * 1000.0), 0, 65534).astype("<u2").tobytes()
