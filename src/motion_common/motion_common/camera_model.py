"""The pinhole camera model, without ROS and without a renderer.

Conventions (OpenCV's, which sensor_msgs/CameraInfo shares):

- pixels: u right, v down, in pixels, the centre of the top-left pixel at (0, 0) (a pixel
  spans [i - 0.5, i + 0.5]); the principal point (cx, cy) is in these coordinates;
- the optical frame: z forward along the optical axis, x right, y down (REP 103's
  ``*_optical`` frames); a point (x, y, z) there projects to (fx x / z + skew y / z + cx,
  fy y / z + cy) before distortion;
- distortion coefficients in OpenCV's order: k1, k2, p1, p2, k3 (``plumb_bob``), or the
  eight of ``rational_polynomial`` (k1, k2, p1, p2, k3, k4, k5, k6); none means zero;
- a camera pose is the 4x4 transform of the optical frame in the base frame.

``Intrinsics`` is the camera alone (focal lengths, principal point, image size,
distortion); ``PinholeCamera`` adds its pose and projects between the base frame and
pixels. ``intrinsics_from_camera_info`` reads the pinhole part of a CameraInfo (the
message or a mapping with its field names) and raises ``CameraInfoError`` with a short
``reason`` when it gives no usable camera; ``camera_info_fields`` is the way back.
OpenCV is imported by the two methods that need it (``project``, ``rays``) only.
"""

import math
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "CameraInfoError",
    "Intrinsics",
    "PinholeCamera",
    "DISTORTION_MODELS",
    "intrinsics_from_camera_info",
    "camera_info_fields",
]

#: CameraInfo distortion model -> the coefficient count ROS tools understand for it.
DISTORTION_MODELS: dict[str, int] = {"plumb_bob": 5, "rational_polynomial": 8}


class CameraInfoError(ValueError):
    """A CameraInfo that describes no usable pinhole camera. ``reason`` says which check
    failed (``no_image_size``, ``bad_matrix``, ``uncalibrated``, ``bad_distortion``); the
    message says what was wrong."""

    def __init__(self, reason: str, message: str):
        super().__init__(message)
        self.reason = reason


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels: focal lengths, principal point, the image size they
    belong to (0 when a device does not know it yet, e.g. before its first frame), the
    distortion coefficients (OpenCV order; empty: none) and the skew (K[0, 1], 0 for every
    camera OpenCV calibrates)."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int = 0
    height: int = 0
    distortion: tuple[float, ...] = ()
    skew: float = 0.0

    def __post_init__(self):
        # A tuple of floats whatever was passed (an array, a list), so that instances
        # compare and hash by value.
        object.__setattr__(self, "distortion", tuple(float(v) for v in np.ravel(self.distortion)))

    @classmethod
    def from_matrix(cls, K, distortion=(), image_size: tuple[int, int] = (0, 0)) -> "Intrinsics":
        """From a 3x3 camera matrix (row-major; its last row is taken to be 0 0 1), the
        distortion coefficients and the image size (width, height)."""
        K = np.asarray(K, dtype=float).reshape(3, 3)
        width, height = image_size
        return cls(
            float(K[0, 0]),
            float(K[1, 1]),
            float(K[0, 2]),
            float(K[1, 2]),
            int(width),
            int(height),
            distortion,
            float(K[0, 1]),
        )

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_deg: float) -> "Intrinsics":
        """Square pixels, centred principal point, focal length from the horizontal field of
        view (a webcam's data sheet value when it was never calibrated)."""
        fx = 0.5 * width / np.tan(np.radians(hfov_deg) / 2.0)
        return cls(fx, fx, 0.5 * width, 0.5 * height, int(width), int(height))

    @property
    def K(self) -> np.ndarray:
        """The 3x3 camera matrix (a new array)."""
        return np.array([[self.fx, self.skew, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def image_size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.width, self.height

    def scaled(self, width: int, height: int) -> "Intrinsics":
        """The same camera at another resolution: focal lengths scaled, and the principal
        point moved so that pixel edges (not centres) scale onto each other."""
        sx, sy = width / self.width, height / self.height
        return replace(
            self,
            fx=self.fx * sx,
            fy=self.fy * sy,
            cx=(self.cx + 0.5) * sx - 0.5,
            cy=(self.cy + 0.5) * sy - 0.5,
            skew=self.skew * sx,
            width=int(width),
            height=int(height),
        )


def _field(info, name, default=None):
    """A CameraInfo field of a message (attribute) or a mapping (key)."""
    if isinstance(info, dict):
        return info.get(name, default)
    return getattr(info, name, default)


def intrinsics_from_camera_info(info) -> Intrinsics:
    """The pinhole camera of a sensor_msgs/CameraInfo, or of a mapping with its field names
    (``width``, ``height``, ``K`` row-major, and optionally ``D`` and ``distortion_model``).

    Raises CameraInfoError when the image size is missing (``no_image_size``), K is not 9
    finite numbers of a camera matrix (``bad_matrix``: fx, fy > 0, last row 0 0 1, zeros
    below the diagonal), K is all zeros, the ROS convention for a camera without
    calibration (``uncalibrated``), or D does not fit a supported distortion model
    (``bad_distortion``). A CameraInfo without distortion gives five zero coefficients
    (plumb_bob without distortion), which projects as no coefficients do.
    """
    width, height = _field(info, "width", 0), _field(info, "height", 0)
    try:
        width, height = int(width), int(height)
    except (TypeError, ValueError):
        width = height = 0
    if width <= 0 or height <= 0:
        raise CameraInfoError("no_image_size", f"camera_info has no image size ({width} x {height})")
    raw_k = _field(info, "K", ())
    try:
        K = np.asarray(raw_k, dtype=float).ravel()
    except (TypeError, ValueError):
        K = np.array([math.nan])
    if K.size != 9 or not np.all(np.isfinite(K)):
        raise CameraInfoError("bad_matrix", f"camera_info K must be 9 finite numbers, got {list(raw_k)}")
    K = K.reshape(3, 3)
    if not np.any(K):
        raise CameraInfoError(
            "uncalibrated", "camera_info is uncalibrated (K is all zeros: the camera driver publishes no calibration)"
        )
    if K[0, 0] <= 0 or K[1, 1] <= 0 or K[2, 2] != 1.0 or K[1, 0] or K[2, 0] or K[2, 1]:
        raise CameraInfoError(
            "bad_matrix",
            f"camera_info K is not a camera matrix (need fx, fy > 0, last row 0 0 1): {K.ravel().tolist()}",
        )
    raw_d = _field(info, "D", ())
    raw_d = () if raw_d is None else raw_d
    model = _field(info, "distortion_model", "") or ""
    try:
        D = np.asarray(raw_d, dtype=float).ravel()
    except (TypeError, ValueError):
        D = np.array([math.nan])
    if not np.all(np.isfinite(D)):
        raise CameraInfoError("bad_distortion", f"camera_info D holds non-finite values: {list(raw_d)}")
    count = DISTORTION_MODELS.get(model)
    if count is None and (model or D.size):
        raise CameraInfoError(
            "bad_distortion", f"distortion model {model!r} is not supported (use one of {', '.join(DISTORTION_MODELS)})"
        )
    if count is not None and D.size != count and not (model == "plumb_bob" and D.size <= count):
        raise CameraInfoError("bad_distortion", f"{model} needs {count} coefficients, got {D.size}")
    if D.size == 0:
        D = np.zeros(DISTORTION_MODELS["plumb_bob"])
    return Intrinsics.from_matrix(K, D, (width, height))


def camera_info_fields(intrinsics) -> dict:
    """The CameraInfo fields of a monocular camera (``width``, ``height``,
    ``distortion_model``, ``D``, ``K``, ``R`` = I, ``P`` = [K | 0], as lists of floats) from
    anything with ``K``, ``distortion`` and ``image_size``: plumb_bob for up to 5
    coefficients (padded with zeros), rational_polynomial for 8; ValueError otherwise."""
    K = np.asarray(intrinsics.K, float).reshape(3, 3)
    D = [float(v) for v in np.ravel(intrinsics.distortion)]
    if len(D) <= DISTORTION_MODELS["plumb_bob"]:
        model, D = "plumb_bob", D + [0.0] * (DISTORTION_MODELS["plumb_bob"] - len(D))
    elif len(D) == DISTORTION_MODELS["rational_polynomial"]:
        model = "rational_polynomial"
    else:
        raise ValueError(f"{len(D)} distortion coefficients have no ROS distortion model (use 5 or 8)")
    width, height = intrinsics.image_size
    return {
        "width": int(width),
        "height": int(height),
        "distortion_model": model,
        "D": D,
        "K": [float(v) for v in K.ravel()],
        "R": [float(v) for v in np.eye(3).ravel()],
        "P": [float(v) for v in np.c_[K, np.zeros(3)].ravel()],
    }


@dataclass
class PinholeCamera:
    """A posed pinhole camera: image size (px), camera matrix K, distortion (OpenCV order),
    the optical frame's pose in the base frame, and the depth range (m) a renderer draws."""

    width: int
    height: int
    K: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))  # optical frame in base
    near: float = 0.05
    far: float = 2.0

    @classmethod
    def from_spec(cls, spec) -> "PinholeCamera":
        """From anything with ``width``, ``height``, ``K``, ``distortion``, ``pose``,
        ``near`` and ``far`` (a ``kitting.cell.CameraSpec``)."""
        return cls(
            spec.width,
            spec.height,
            np.array(spec.K, float),
            np.array(spec.distortion, float),
            np.array(spec.pose, float),
            spec.near,
            spec.far,
        )

    @classmethod
    def from_intrinsics(
        cls, intrinsics: Intrinsics, pose=None, near: float = 0.05, far: float = 2.0
    ) -> "PinholeCamera":
        """``intrinsics`` (its image size must be known) at ``pose`` (default: the base frame)."""
        return cls(
            intrinsics.width,
            intrinsics.height,
            intrinsics.K,
            np.array(intrinsics.distortion, float),
            np.eye(4) if pose is None else np.array(pose, float),
            near,
            far,
        )

    @property
    def intrinsics(self) -> Intrinsics:
        return Intrinsics.from_matrix(self.K, self.distortion, (self.width, self.height))

    @property
    def fx(self) -> float:
        return float(self.K[0, 0])

    @property
    def fy(self) -> float:
        return float(self.K[1, 1])

    def scaled(self, width: int, height: int) -> "PinholeCamera":
        """The same camera at another resolution (``Intrinsics.scaled``)."""
        return replace(self, width=width, height=height, K=self.intrinsics.scaled(width, height).K)

    def with_pose(self, pose) -> "PinholeCamera":
        return replace(self, pose=np.array(pose, float))

    def world_to_camera(self) -> np.ndarray:
        """4x4 transform from base coordinates to optical-frame coordinates."""
        return np.linalg.inv(self.pose)

    def project(self, points) -> np.ndarray:
        """N x 2 pixels of N x 3 base-frame points (with the distortion model)."""
        import cv2

        points = np.asarray(points, float).reshape(-1, 3)
        T = self.world_to_camera()
        rvec, _ = cv2.Rodrigues(T[:3, :3])
        pixels, _ = cv2.projectPoints(points, rvec, T[:3, 3], self.K, self.distortion)
        return pixels.reshape(-1, 2)

    def rays(self, pixels) -> tuple[np.ndarray, np.ndarray]:
        """(origin 3, directions N x 3 unit) in the base frame of the rays through pixels."""
        import cv2

        pixels = np.asarray(pixels, float).reshape(-1, 1, 2)
        normalized = cv2.undistortPoints(pixels, self.K, self.distortion).reshape(-1, 2)
        directions = np.c_[normalized, np.ones(len(normalized))]
        directions = directions @ self.pose[:3, :3].T
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        return self.pose[:3, 3].copy(), directions
