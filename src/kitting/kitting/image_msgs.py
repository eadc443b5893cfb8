"""numpy <-> sensor_msgs/Image and intrinsics <-> sensor_msgs/CameraInfo, without cv_bridge.

cv_bridge is not importable from the project's venv, and 8-bit images need nothing of it:
the data is the rows of the image, ``step`` bytes each. No rospy either: the message classes and
``genpy.Time`` work without a ROS master, so this is unit-tested like any module.

- ``image_to_bgr(msg)`` -> (H x W x 3 uint8 BGR array, "") or (None, reason): bgr8, rgb8
  and mono8 are accepted; a message whose step, data size or encoding do not add up is
  refused with the reason (a node logs and counts it and goes on).
- ``bgr_to_image(array, stamp, frame_id)`` -> Image (bgr8); ``array_to_image`` for rgb8 and
  mono8. A wrong array is a programming error: ValueError.
- ``camera_info_from_intrinsics(intrinsics, stamp, frame_id)`` -> CameraInfo (R = I,
  P = [K | 0]) from a ``motion_common.camera_model.Intrinsics``, a
  ``kitting.calibration.CalibrationResult`` (or anything with ``K``, ``distortion``,
  ``image_size``).
- ``intrinsics_from_camera_info(msg)`` -> (Intrinsics, "") or (None, reason): an
  uncalibrated camera_info (K all zeros, the ROS convention) or a malformed one is refused
  (the checks are ``motion_common.camera_model``'s).

Stamps are seconds (float), a ``genpy.Time``/``rospy.Time``, or None (zero).
"""

import math

import genpy
import numpy as np
from sensor_msgs.msg import CameraInfo, Image

from motion_common import camera_model
from motion_common.camera_model import CameraInfoError, Intrinsics, camera_info_fields

# encoding -> channels (all 8-bit).
ENCODINGS = {"bgr8": 3, "rgb8": 3, "mono8": 1}


def to_time(stamp) -> genpy.Time:
    """A message stamp from seconds, a genpy/rospy Time, or None (zero)."""
    if stamp is None:
        return genpy.Time()
    if isinstance(stamp, genpy.Time):
        return genpy.Time(stamp.secs, stamp.nsecs)
    seconds = float(stamp)
    if not math.isfinite(seconds) or seconds < 0:
        raise ValueError(f"stamp {stamp!r} is not a finite time >= 0 s")
    return genpy.Time.from_sec(seconds)


def _data_bytes(data) -> tuple[np.ndarray | None, str]:
    if isinstance(data, (bytes, bytearray, memoryview)):
        return np.frombuffer(data, np.uint8), ""
    try:
        array = np.asarray(data)
    except (TypeError, ValueError) as exc:
        return None, f"data is not bytes ({exc})"
    if array.ndim != 1 or (array.size and not np.issubdtype(array.dtype, np.integer)):
        return None, f"data is not a flat list of bytes (dtype {array.dtype}, shape {array.shape})"
    if array.size and (array.min() < 0 or array.max() > 255):
        return None, "data holds values outside 0..255"
    return array.astype(np.uint8), ""


def image_to_array(msg) -> tuple[np.ndarray | None, str]:
    """(H x W x C uint8 array in the message's own channel order, "") or (None, reason)."""
    encoding = msg.encoding
    channels = ENCODINGS.get(encoding)
    if channels is None:
        return None, f"unsupported encoding {encoding!r} (accepted: {', '.join(ENCODINGS)})"
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    if height <= 0 or width <= 0:
        return None, f"empty image ({width} x {height} px)"
    row = width * channels
    if step < row:
        return None, f"step {step} bytes is shorter than a row ({width} px x {channels} bytes = {row})"
    data, why = _data_bytes(msg.data)
    if data is None:
        return None, why
    if data.size != step * height:
        return None, f"data has {data.size} bytes, expected step {step} x height {height} = {step * height}"
    array = data.reshape(height, step)[:, :row].reshape(height, width, channels).copy()
    return array, ""


def image_to_bgr(msg) -> tuple[np.ndarray | None, str]:
    """(H x W x 3 uint8 BGR array, "") or (None, reason) from a bgr8/rgb8/mono8 Image."""
    array, why = image_to_array(msg)
    if array is None:
        return None, why
    if msg.encoding == "rgb8":
        return np.ascontiguousarray(array[:, :, ::-1]), ""
    if msg.encoding == "mono8":
        return np.repeat(array, 3, axis=2), ""
    return array, ""


def array_to_image(array, stamp=None, frame_id: str = "", encoding: str = "bgr8") -> Image:
    """An Image of an H x W x C uint8 array already in ``encoding``'s channel order (an
    H x W array for mono8); ValueError on anything else."""
    channels = ENCODINGS.get(encoding)
    if channels is None:
        raise ValueError(f"unsupported encoding {encoding!r} (use one of {', '.join(ENCODINGS)})")
    array = np.asarray(array)
    if array.dtype != np.uint8:
        raise ValueError(f"image must be uint8, got {array.dtype}")
    if channels == 1 and array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    expected = (2,) if channels == 1 else (3,)
    if array.ndim not in expected or (channels > 1 and array.shape[2] != channels) or array.size == 0:
        raise ValueError(f"{encoding} needs an H x W{'' if channels == 1 else ' x 3'} array, got shape {array.shape}")
    msg = Image()
    msg.header.stamp = to_time(stamp)
    msg.header.frame_id = frame_id
    msg.height, msg.width = int(array.shape[0]), int(array.shape[1])
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = msg.width * channels
    msg.data = np.ascontiguousarray(array).tobytes()
    return msg


def bgr_to_image(array, stamp=None, frame_id: str = "") -> Image:
    """A bgr8 Image of an H x W x 3 uint8 BGR array (as OpenCV gives)."""
    return array_to_image(array, stamp, frame_id, "bgr8")


def camera_info_from_intrinsics(intrinsics, stamp=None, frame_id: str = "") -> CameraInfo:
    """CameraInfo of a monocular camera (``motion_common.camera_model.camera_info_fields``:
    D plumb_bob for up to 5 coefficients, padded; rational_polynomial for 8; R = I,
    P = [K | 0])."""
    fields = camera_info_fields(intrinsics)
    msg = CameraInfo()
    msg.header.stamp = to_time(stamp)
    msg.header.frame_id = frame_id
    msg.width, msg.height = fields["width"], fields["height"]
    msg.distortion_model = fields["distortion_model"]
    msg.D, msg.K, msg.R, msg.P = fields["D"], fields["K"], fields["R"], fields["P"]
    return msg


def intrinsics_from_camera_info(msg) -> tuple[Intrinsics | None, str]:
    """(the camera's Intrinsics, "") or (None, reason): the checks of
    ``motion_common.camera_model.intrinsics_from_camera_info``, for callers that log and
    go on rather than stop."""
    try:
        return camera_model.intrinsics_from_camera_info(msg), ""
    except CameraInfoError as exc:
        hint = ": calibrate with calibrate_camera" if exc.reason == "uncalibrated" else ""
        return None, f"{exc}{hint}"
