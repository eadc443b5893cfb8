"""The camera's intrinsics file on disk: a ROS camera_info YAML (camera_calibration_parsers'
format, as ``kitting.calibration.write_intrinsics_yaml`` writes and ROS's camera_calibration
tool saves).

- saving is ``kitting.calibration.write_intrinsics_yaml`` (atomic: a crash leaves the old
  file or the new one, never half);
- ``load_camera_info_yaml(path)`` -> ``sensor_msgs/CameraInfo`` with K, D, R, P, size and
  distortion model from the file (R defaults to I and P to [K | 0] when absent). A missing,
  unparsable or inconsistent file raises ``IntrinsicsFileError`` naming the file, the key
  and what to do.
- ``resolve_camera_info_url(url, package_path)``: ``file:///abs/x.yaml``,
  ``package://pkg/rel/x.yaml`` (``package_path(pkg)`` is injected: a node passes rospkg's)
  or a plain path -> a path.
"""

import math
import os
from collections.abc import Callable

from sensor_msgs.msg import CameraInfo

from .image_msgs import intrinsics_from_camera_info


class IntrinsicsFileError(Exception):
    """An intrinsics file that cannot be used; the message names the file and what to do."""


def _matrix(data: dict, key: str, size: int, path: str, required: bool = True) -> list | None:
    entry = data.get(key)
    if entry is None:
        if required:
            raise IntrinsicsFileError(
                f"{path}: '{key}' is missing (a camera_info YAML needs image_width, "
                "image_height, camera_matrix, distortion_coefficients; "
                "write one with calibrate_camera)"
            )
        return None
    values = entry.get("data") if isinstance(entry, dict) else None
    if not isinstance(values, list):
        raise IntrinsicsFileError(f"{path}: '{key}' must be a mapping with a 'data' list (rows, cols, data)")
    if size and len(values) != size:
        raise IntrinsicsFileError(f"{path}: '{key}' must hold {size} numbers, got {len(values)}")
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
        raise IntrinsicsFileError(f"{path}: '{key}' must hold finite numbers, got {values!r}")
    return [float(v) for v in values]


def load_camera_info_yaml(path: str) -> CameraInfo:
    """The CameraInfo (stamp zero, no frame_id) of a camera_info YAML file."""
    import yaml

    try:
        with open(path, encoding="utf-8") as stream:
            data = yaml.safe_load(stream)
    except OSError as exc:
        raise IntrinsicsFileError(
            f"{path}: cannot read the intrinsics file: {exc.strerror or exc} "
            "(calibrate with `rosrun kitting calibrate_camera ... --output FILE`)"
        ) from None
    except UnicodeDecodeError:
        raise IntrinsicsFileError(
            f"{path}: not a text file (give the camera_info YAML that calibrate_camera wrote)"
        ) from None
    except yaml.YAMLError as exc:
        raise IntrinsicsFileError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise IntrinsicsFileError(f"{path}: expected a camera_info mapping, got {type(data).__name__}")
    msg = CameraInfo()
    for key in ("image_width", "image_height"):
        value = data.get(key)
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise IntrinsicsFileError(f"{path}: '{key}' must be a whole number of pixels > 0, got {value!r}")
    msg.width, msg.height = data["image_width"], data["image_height"]
    msg.K = _matrix(data, "camera_matrix", 9, path)
    msg.D = _matrix(data, "distortion_coefficients", 0, path)
    msg.distortion_model = str(data.get("distortion_model", "plumb_bob"))
    msg.R = _matrix(data, "rectification_matrix", 9, path, required=False) or [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0]
    P = _matrix(data, "projection_matrix", 12, path, required=False)
    msg.P = P or [
        msg.K[0],
        msg.K[1],
        msg.K[2],
        0.0,
        msg.K[3],
        msg.K[4],
        msg.K[5],
        0.0,
        msg.K[6],
        msg.K[7],
        msg.K[8],
        0.0,
    ]
    _, why = intrinsics_from_camera_info(msg)
    if why:
        raise IntrinsicsFileError(f"{path}: {why}")
    return msg


def resolve_camera_info_url(url: str, package_path: Callable[[str], str] | None = None) -> str:
    """The file path of a camera_info URL (file://, package://) or of a plain path."""
    if url.startswith("file://"):
        return url[len("file://") :]
    if url.startswith("package://"):
        package, _, relative = url[len("package://") :].partition("/")
        if not package or not relative:
            raise IntrinsicsFileError(f"camera_info_url {url!r} must look like package://PACKAGE/path/file.yaml")
        if package_path is None:
            raise IntrinsicsFileError(f"camera_info_url {url!r}: package:// needs a ROS environment")
        try:
            return os.path.join(package_path(package), relative)
        except Exception as exc:  # rospkg.ResourceNotFound and friends
            raise IntrinsicsFileError(
                f"camera_info_url {url!r}: package {package!r} not found ({exc}); "
                "source the workspace's devel/setup.bash"
            ) from None
    if "://" in url:
        raise IntrinsicsFileError(f"camera_info_url {url!r}: only file:// and package:// URLs are supported")
    return os.path.expanduser(url)
