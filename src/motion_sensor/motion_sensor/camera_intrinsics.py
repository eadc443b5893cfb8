"""Pinhole camera intrinsics and the optical-to-REP 103 rotation, shared by the camera hand
devices (depth camera, Kinect, webcam)."""
from dataclasses import dataclass

import numpy as np

# Optical axes (x right, y down, z forward) to REP 103 body axes (x forward, y left, z up).
OPTICAL_TO_REP103 = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels: focal lengths, principal point, and the image size the
    values belong to (0 when a device does not know it, e.g. before its first frame)."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int = 0
    height: int = 0

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_deg: float) -> "Intrinsics":
        """Square pixels, centred principal point, focal length from the horizontal field of
        view (a webcam's data sheet value when it was never calibrated)."""
        fx = 0.5 * width / np.tan(np.radians(hfov_deg) / 2.0)
        return cls(fx, fx, 0.5 * width, 0.5 * height, int(width), int(height))
