"""From pixels to parts on the belt: the detector's output turned into belt-plane poses in
the robot base frame with the calibrated camera (``kitting.geometry``)."""

import math
from dataclasses import dataclass

import cv2
import numpy as np

from motion_common.camera_model import PinholeCamera

from .cell import Belt
from .detector import ClassicalDetector, Detection, DetectionResult, belt_mask_for
from .geometry import image_angle_to_belt_yaw, pixel_to_belt, pixels_to_plane
from .parts import BOLT_HEAD, BOLT_SHAFT, PART_CLASSES


def bolt_boxes(part) -> list[np.ndarray]:
    """The bolt's head and shaft as 8 x 3 box corners in its own frame (origin: footprint
    centroid on the belt, +x from the head to the shaft's end), as ``kitting.meshes`` builds it."""
    head_len, head_w = BOLT_HEAD
    diameter, lift = BOLT_SHAFT
    shaft_len = part.length - head_len
    head_area, shaft_area = head_len * head_w, shaft_len * diameter
    x0 = -(head_area * head_len / 2 + shaft_area * (head_len + shaft_len / 2)) / (head_area + shaft_area)

    def box(xa, xb, half_y, za, zb):
        return np.array([[x, y, z] for x in (xa, xb) for y in (-half_y, half_y) for z in (za, zb)])

    return [
        box(x0, x0 + head_len, head_w / 2, 0.0, part.height),
        box(x0 + head_len, x0 + part.length, diameter / 2, lift, lift + diameter),
    ]


def bolt_silhouette_centroid(camera, part, x, y, yaw, belt_height, supersample: int = 8):
    """Pixel centroid of the bolt's silhouette at (x, y, yaw) on the belt: the union of its
    two boxes' projected convex hulls, rasterised at ``supersample`` x; None off-image."""
    c, s = math.cos(yaw), math.sin(yaw)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    hulls = [camera.project(corners @ rotation.T + (x, y, belt_height)) for corners in bolt_boxes(part)]
    points = np.vstack(hulls)
    if not np.all(np.isfinite(points)):
        return None
    origin = np.floor(points.min(axis=0)) - 1.0
    size = np.ceil((points.max(axis=0) - origin + 2.0) * supersample).astype(int)
    mask = np.zeros((size[1], size[0]), np.uint8)
    for hull in hulls:
        grid = (hull - origin) * supersample - 0.5
        polygon = cv2.convexHull(np.round(grid * 16).astype(np.int32))
        cv2.fillConvexPoly(mask, polygon, 1, lineType=cv2.LINE_8, shift=4)
    moments = cv2.moments(mask, binaryImage=True)
    if moments["m00"] <= 0:
        return None
    centre = np.array([moments["m10"], moments["m01"]]) / moments["m00"]
    return origin + (centre + 0.5) / supersample


@dataclass
class PartObservation:
    class_name: str
    x: float  # m, base frame, on the belt plane
    y: float
    yaw: float  # rad (bolt: its axis from the head to the shaft end; nut: mod pi/3; washer: 0)
    confidence: float
    pixel: tuple


class BeltVision:
    """Detector + geometry for one calibrated camera over the belt."""

    def __init__(self, camera: PinholeCamera, belt: Belt, detector=None, detector_params: dict | None = None):
        self.camera, self.belt = camera, belt
        if detector is None:
            mask = belt_mask_for(camera, belt)
            detector = ClassicalDetector(
                belt_mask=mask,
                params=detector_params,
                to_plane=lambda px: pixels_to_plane(camera, px, belt.height)[:, :2],
            )
        self.detector = detector

    def locate(self, detection: Detection) -> PartObservation:
        part = PART_CLASSES[detection.class_name]
        x, y, _ = pixel_to_belt(self.camera, detection.pixel, self.belt.height, part.centroid_height)
        yaw = image_angle_to_belt_yaw(
            self.camera, detection.pixel, detection.angle, self.belt.height + part.centroid_height
        )
        head = (detection.features or {}).get("head_px") if part.kind == "bolt" else None
        if head is not None:
            x, y, yaw = self._locate_bolt(part, detection.pixel, head, x, y, yaw)
        return PartObservation(
            detection.class_name, float(x), float(y), yaw, detection.confidence, tuple(detection.pixel)
        )

    def _locate_bolt(self, part, pixel, head_px, x, y, yaw, iterations: int = 3):
        """A bolt's footprint centroid from its silhouette's centroid: the head is taller than
        the shaft and at one end, so the silhouette's centroid is not over the footprint's.
        The bolt model (head and shaft boxes, ``kitting.parts``) is placed at the estimate,
        its silhouette's centroid predicted, and the estimate moved by the difference."""
        head = pixel_to_belt(self.camera, head_px, self.belt.height, part.centroid_height)
        # The head lies at the bolt's -x end (kitting.meshes): turn the yaw (known mod pi) to it.
        if math.cos(yaw) * (head[0] - x) + math.sin(yaw) * (head[1] - y) > 0:
            yaw += math.pi
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        measured = np.asarray(pixel, float)
        for _ in range(iterations):
            predicted = bolt_silhouette_centroid(self.camera, part, x, y, yaw, self.belt.height)
            if predicted is None:
                break
            a, b = pixels_to_plane(
                self.camera, np.vstack([predicted, measured]), self.belt.height + part.centroid_height
            )
            x, y = x + (b[0] - a[0]), y + (b[1] - a[1])
        return x, y, yaw

    def observe(self, image):
        """(observations, DetectionResult) of one image."""
        result: DetectionResult = self.detector.detect(image)
        return [self.locate(d) for d in result.detections], result
