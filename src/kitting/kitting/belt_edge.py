"""The belt's far edge as a registration feature.

The cell's markers lie on one line beside the belt. Their corners fix the camera well
except for its tilt about that line: each marker spans only ~66 px across it, so the
corners' quantisation (0.3 px RMS on the simulated camera, which does not anti-alias)
leaves the camera tilted by up to ~0.8°, i.e. several mm on the far side of the belt and
1-3 mm at the parts. The belt's far edge is a long straight line at a known place in the
base frame (the cell YAML's belt), ~250 px from the markers across that line: measured
along its whole length in the image and added to the marker corners, it pins that tilt.

``measure_line`` finds an edge near where a registration predicts it, column by column
(a step from the background to the belt, located at its half-way level);
``refine_with_lines`` solves the camera pose from the marker corners and those points
together (scipy's least squares, a robust loss so that a part or a shadow at the edge
does not pull it).
"""

import cv2
import numpy as np
from scipy.optimize import least_squares

__all__ = ["BeltLine", "far_edge", "measure_line", "refine_with_lines"]


class BeltLine:
    """A straight edge of the belt along its run: the line y = ``y``, z = ``height`` (base
    frame, m) for x in [``x_start``, ``x_end``]; ``belt_side`` is +1 when the belt lies at
    larger y than the edge, -1 when smaller."""

    def __init__(self, y: float, height: float, x_start: float, x_end: float, belt_side: int):
        self.y, self.height, self.x_start, self.x_end, self.belt_side = y, height, x_start, x_end, belt_side


def far_edge(belt, camera_y: float) -> BeltLine:
    """The edge of ``belt`` (kitting.cell.Belt) farther from a camera at base y ``camera_y``:
    the top hides the belt's side there, so the image shows a clean step from the
    background to the belt. (The near side was tried as a second line and made the
    registration worse: the top's near edge is a faint step onto the side, and the marker
    plates hide the side's foot.)"""
    near, far = belt.y - belt.width / 2, belt.y + belt.width / 2
    if abs(near - camera_y) > abs(far - camera_y):
        near, far = far, near
    return BeltLine(far, belt.height, belt.x_start, belt.x_end, 1 if near > far else -1)


def measure_line(
    gray,
    camera,
    edge: BeltLine,
    occluded=None,
    step_px: int = 8,
    search_px: int = 12,
    min_step: float = 20.0,
    flat: float = 6.0,
) -> np.ndarray:
    """Points (N x 2, px) of ``edge`` in the grey image ``gray``, searched within
    ``search_px`` of where ``camera`` (a PinholeCamera with a pose) projects it, one per
    ``step_px`` columns. A column counts when the image steps by at least ``min_step``
    levels toward the belt's side and is flat (within ``flat`` levels) for two pixels on
    each side of the step: a part, a marker or the arm at the edge breaks that and the
    column is left out, as is any column ``occluded`` (uint8 mask, 255 = arm) covers."""
    height, width = gray.shape[:2]
    xs = np.linspace(edge.x_start, edge.x_end, 4 * width)
    points3d = np.column_stack([xs, np.full_like(xs, edge.y), np.full_like(xs, edge.height)])
    in_front = (np.linalg.inv(camera.pose) @ np.c_[points3d, np.ones(len(xs))].T)[2] > 0.0
    points3d = points3d[in_front]
    if not len(points3d):
        return np.zeros((0, 2))
    pixels = camera.project(points3d)
    margin = search_px + 3
    columns = np.round(pixels[:, 0]).astype(int)
    inside = (
        (columns >= margin) & (columns < width - margin) & (pixels[:, 1] >= margin) & (pixels[:, 1] < height - margin)
    )
    if not np.any(inside):
        return np.zeros((0, 2))
    # One sample per step_px columns: the first point projected into each band.
    _, first = np.unique(columns[inside] // step_px, return_index=True)
    chosen = np.flatnonzero(inside)[first]
    belt_rows = camera.project(points3d[chosen] + [0.0, 0.02 * edge.belt_side, 0.0])[:, 1]
    found = []
    for (u, v), v_belt in zip(pixels[chosen], belt_rows):
        column = int(round(u))
        top = int(round(v)) - search_px
        if occluded is not None and np.any(occluded[top : top + 2 * search_px + 1, column]):
            continue
        profile = gray[top : top + 2 * search_px + 1, column].astype(float)
        sign = 1.0 if v_belt > v else -1.0  # rows toward the belt: +1 down the image
        steps = np.diff(profile) * sign  # background -> belt, signed so the belt side is darker
        k = int(np.argmin(steps))  # the steepest fall toward the belt
        if -steps[k] < min_step or k < 2 or k + 3 >= len(profile):
            continue
        before, after = profile[k - 1 : k + 1], profile[k + 1 : k + 3]
        if np.ptp(before) > flat or np.ptp(after) > flat:
            continue
        middle = (before.mean() + after.mean()) / 2
        # Where the profile crosses half-way between the two levels, between pixel centres:
        # k + 0.5 for a sharp step (a sensor that integrates gives the true sub-pixel place).
        a, b = profile[k], profile[k + 1]
        fraction = 0.5 if a == b else float(np.clip((a - middle) / (a - b), 0.0, 1.0))
        row = top + k + fraction
        found.append((float(u), float(row)))
    return np.array(found, float).reshape(-1, 2)


def refine_with_lines(T_base_cam, object_points, image_points, measured, K, distortion):
    """The camera pose (4x4, base frame) that best explains the marker corners
    (``object_points`` in the base frame, ``image_points`` in px) and the belt's edges
    together, starting from ``T_base_cam``; ``measured``: (BeltLine, points N x 2 px) pairs.
    The edges together count as much as all the corners; residuals are in pixels.

    Returns (pose, the corners' RMS reprojection px, the edge points' median distance px
    from their line): a fit that agrees with both leaves each within a pixel or so."""
    K = np.asarray(K, float)
    distortion = np.asarray(distortion, float)
    object_points = np.asarray(object_points, float).reshape(-1, 3)
    image_points = np.asarray(image_points, float).reshape(-1, 2)
    lines = [(line, points) for line, points in measured if len(points)]
    points = np.vstack([points for _, points in lines]).reshape(-1, 1, 2) if lines else np.zeros((0, 1, 2))
    rays = cv2.undistortPoints(points.astype(float), K, distortion).reshape(-1, 2) if len(points) else np.zeros((0, 2))
    rays = np.c_[rays, np.ones(len(rays))]  # camera frame, depth 1
    line_y = np.concatenate([np.full(len(p), line.y) for line, p in lines]) if lines else np.zeros(0)
    line_z = np.concatenate([np.full(len(p), line.height) for line, p in lines]) if lines else np.zeros(0)
    weight = np.sqrt(image_points.size / max(len(rays), 1))
    focal = float(K[0, 0])

    def pose_of(x):
        T = np.eye(4)
        T[:3, :3] = cv2.Rodrigues(x[:3])[0]
        T[:3, 3] = x[3:]
        return T  # camera <- base

    def residuals(x):
        projected, _ = cv2.projectPoints(object_points, x[:3], x[3:], K, distortion)
        corners = (projected.reshape(-1, 2) - image_points).ravel()
        T_base = np.linalg.inv(pose_of(x))
        directions = rays @ T_base[:3, :3].T
        origin = T_base[:3, 3]
        depth = (line_z - origin[2]) / directions[:, 2]  # camera-frame depth of each hit
        hits_y = origin[1] + depth * directions[:, 1]
        return np.r_[corners, weight * (hits_y - line_y) * focal / np.abs(depth)]

    T_cam_base = np.linalg.inv(np.asarray(T_base_cam, float))
    start = np.r_[cv2.Rodrigues(T_cam_base[:3, :3])[0].ravel(), T_cam_base[:3, 3]]
    solution = least_squares(residuals, start, loss="soft_l1", f_scale=1.0, x_scale="jac")
    final = residuals(solution.x)
    corners = final[: image_points.size].reshape(-1, 2)
    corner_rms = float(np.sqrt(np.mean(np.sum(corners**2, axis=1))))
    edge_median = float(np.median(np.abs(final[image_points.size :]) / weight)) if len(rays) else 0.0
    return np.linalg.inv(pose_of(solution.x)), corner_rms, edge_median
