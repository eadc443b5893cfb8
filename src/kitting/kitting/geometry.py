"""Pixel to belt plane: exact ray-plane intersection with the calibrated camera.

A pixel is undistorted (``cv2.undistortPoints``) into a viewing ray in the camera's
optical frame, rotated and placed into the robot base frame with the camera's pose (from
the marker calibration), and intersected with the plane z = belt height (+ the part's
centroid height). This is exact for any camera position and tilt and for lens
distortion. The paper's equations (1)-(3) scale pixel offsets from the image centre by a
constant metres-per-pixel, which holds only for a camera looking straight down at a known
height with no distortion: with our ~10 degree tilt the scale changes across the image by
several percent (tens of millimetres at the image edge), far beyond the 2 mm goal.
"""

import numpy as np

from motion_common.camera_model import PinholeCamera


def intersect_plane(origin, directions, plane_point, plane_normal) -> np.ndarray:
    """N x 3 intersections of rays (origin 3, directions N x 3) with a plane; NaN rows for
    rays parallel to the plane or pointing away from it."""
    directions = np.asarray(directions, float).reshape(-1, 3)
    normal = np.asarray(plane_normal, float)
    denominator = directions @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((np.asarray(plane_point, float) - origin) @ normal) / denominator
    t = np.where((np.abs(denominator) < 1e-12) | (t <= 0), np.nan, t)
    return origin + t[:, None] * directions


def pixels_to_plane(camera: PinholeCamera, pixels, height: float) -> np.ndarray:
    """N x 3 base-frame points where the rays through ``pixels`` (N x 2) meet z = height."""
    origin, directions = camera.rays(pixels)
    return intersect_plane(origin, directions, (0.0, 0.0, height), (0.0, 0.0, 1.0))


def pixel_to_belt(camera: PinholeCamera, pixel, belt_height: float, above: float = 0.0) -> np.ndarray:
    """(x, y, z) on the belt plane under a pixel; ``above`` lifts the plane to where the
    observed point really is (a part's centroid height), the result is dropped back onto the
    belt plane (z = belt_height)."""
    point = pixels_to_plane(camera, np.reshape(pixel, (1, 2)), belt_height + above)[0]
    return np.array([point[0], point[1], belt_height])


def image_angle_to_belt_yaw(camera: PinholeCamera, pixel, angle: float, height: float, step_px: float = 10.0) -> float:
    """Yaw (rad, base frame) of the belt-plane direction seen at ``pixel`` along the image
    direction ``angle`` (rad, image x towards image y)."""
    pixel = np.asarray(pixel, float)
    tip = pixel + step_px * np.array([np.cos(angle), np.sin(angle)])
    a, b = pixels_to_plane(camera, np.vstack([pixel, tip]), height)
    return float(np.arctan2(b[1] - a[1], b[0] - a[0]))


def plane_to_pixel(camera: PinholeCamera, points) -> np.ndarray:
    """N x 2 pixels of base-frame points (the inverse direction, with distortion)."""
    return camera.project(points)


def footprint_scale(camera: PinholeCamera, pixel, height: float) -> tuple[float, float]:
    """Metres per pixel along image x and y at ``pixel`` on the plane z = height."""
    pixel = np.asarray(pixel, float)
    a, bx, by = pixels_to_plane(camera, np.vstack([pixel, pixel + (1, 0), pixel + (0, 1)]), height)
    return float(np.linalg.norm(bx - a)), float(np.linalg.norm(by - a))
