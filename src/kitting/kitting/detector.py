"""The default part detector: classical OpenCV, colour + shape.

1. Sanity: an image that is not an H x W x 3 uint8 array, is empty or is blank (no contrast)
   is rejected as a whole ("corrupt image").
2. Foreground: inside the belt's image region (``belt_mask``), pixels that differ from the
   dark belt: bright (V) or saturated (S) in HSV.
3. Blobs: external contours with their holes (``RETR_CCOMP``). A blob within ``edge_px`` of
   the image border or of the belt region's border is rejected ("edge": only part of it is
   seen, or it lies on the belt's edge).
4. Colour: yellow = hue in [15, 40] (OpenCV's 0-180 scale) and saturated; silver = low
   saturation and bright. A blob whose pixels are neither, or a mix, is an unknown object.
5. Shape, measured in millimetres on the belt plane (the contour is mapped through
   ``to_plane``, so sizes do not depend on where the part lies in the image):
   bolt = elongated (min-area-rectangle aspect > 2.2); washer = round with a hole (hole area
   > 12 % of the outline); nut = compact, filled, hexagonal (6-ish polygon vertices). The
   footprint area must match the class's (``parts.PartClass.footprint_area``) within
   ``area_tolerance`` (50 %: oblique views add the side faces); otherwise the blob is an unknown object.

Each detection has a class, the pixel centroid, an image orientation (rad; the bolt's
axis, the nut's flat direction mod 60°, 0 for a washer) and a confidence in [0, 1] from the
colour purity and how well the shape features match.
"""
import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Tuple

import cv2
import numpy as np

from motion_common.params import Param, ParamSchema

from .parts import PART_CLASSES

DETECTOR_SCHEMA = ParamSchema([
    Param("value_min", 95, "0-255", "V above which a grey pixel is foreground (silver)", low=0, high=255),
    Param("saturation_min", 90, "0-255", "S above which a pixel is coloured", low=0, high=255),
    Param("hue_yellow", [12.0, 40.0], "OpenCV hue 0-180", "yellow hue range", length=2, low=0.0, high=180.0),
    Param("min_area_px", 25, "px", "smaller blobs are noise", low=1, high=100000),
    Param("edge_px", 2, "px", "blobs this close to the image or belt border are 'edge'", low=0, high=100),
    Param("colour_purity_min", 0.75, "", "fraction of a blob's pixels of one colour", low=0.0, high=1.0),
    Param("area_tolerance", 0.5, "", "relative footprint area error accepted", low=0.01, high=2.0),
    Param("bolt_aspect_min", 2.2, "", "length/width above which a blob is a bolt", low=1.0, high=20.0),
    Param("hole_ratio_min", 0.12, "", "hole/outline area above which a blob is a washer", low=0.0, high=1.0),
])


@dataclass
class Detection:
    class_name: str
    pixel: Tuple[float, float]        # px, centroid
    angle: float                      # rad, image orientation (x towards y)
    confidence: float                 # 0-1
    features: dict = field(default_factory=dict)


@dataclass
class Rejection:
    reason: str                       # "corrupt image" | "edge" | "unknown object"
    pixel: Optional[Tuple[float, float]] = None
    detail: str = ""


@dataclass
class DetectionResult:
    detections: List[Detection] = field(default_factory=list)
    rejections: List[Rejection] = field(default_factory=list)

    @property
    def corrupt(self) -> bool:
        return any(r.reason == "corrupt image" for r in self.rejections)


def check_image(image) -> str:
    """'' for a usable image, else why not."""
    if image is None:
        return "no image"
    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        return f"not an H x W x 3 uint8 image (shape {image.shape}, dtype {image.dtype})"
    if image.shape[0] < 8 or image.shape[1] < 8:
        return f"image too small {image.shape[:2]}"
    if float(image.std()) < 1.0:
        return "blank image (no contrast)"
    return ""


class ClassicalDetector:
    """Colour + shape detector. ``belt_mask``: uint8 mask (255 = belt) of the image size, or
    None for the whole image. ``to_plane(pixels N x 2) -> N x 2 metres`` on the belt plane
    (default: ``mm_per_px`` scale)."""

    name = "classical"

    def __init__(self, belt_mask: Optional[np.ndarray] = None,
                 to_plane: Optional[Callable[[np.ndarray], np.ndarray]] = None,
                 mm_per_px: float = 1.0, params: Optional[dict] = None):
        self.params = DETECTOR_SCHEMA.validate(params or {}, "detector")
        self.belt_mask = belt_mask
        self.to_plane = to_plane or (lambda px: np.asarray(px, float) * mm_per_px / 1000.0)

    def detect(self, image) -> DetectionResult:
        result = DetectionResult()
        problem = check_image(image)
        if problem:
            result.rejections.append(Rejection("corrupt image", detail=problem))
            return result
        P = self.params
        h, w = image.shape[:2]
        hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)
        hue, sat, val = hsv[:, :, 0], hsv[:, :, 1], hsv[:, :, 2]
        yellow = (sat >= P["saturation_min"]) & (hue >= P["hue_yellow"][0]) & (hue <= P["hue_yellow"][1]) & (val >= 60)
        silver = (sat < P["saturation_min"] * 0.5) & (val >= P["value_min"])
        foreground = (val >= P["value_min"]) | (sat >= P["saturation_min"])
        region = np.full((h, w), 255, np.uint8) if self.belt_mask is None else self.belt_mask
        if region.shape != (h, w):
            result.rejections.append(Rejection("corrupt image", detail=f"image size {w}x{h} does not match the belt mask"))
            return result
        mask = np.where(foreground & (region > 0), 255, 0).astype(np.uint8)
        # Edge zone: the image border and the belt region's border.
        edge = P["edge_px"] + 1
        inner = cv2.erode(region, np.ones((2 * edge + 1, 2 * edge + 1), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0)
        contours, hierarchy = cv2.findContours(mask, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
        if hierarchy is None:
            return result
        hierarchy = hierarchy[0]
        for index, contour in enumerate(contours):
            if hierarchy[index][3] != -1:
                continue  # a hole; handled with its outline
            area_px = cv2.contourArea(contour)
            if area_px < P["min_area_px"]:
                continue
            moments = cv2.moments(contour)
            centroid = (moments["m10"] / moments["m00"], moments["m01"] / moments["m00"])
            points = contour.reshape(-1, 2)
            if np.any(inner[points[:, 1], points[:, 0]] == 0):
                result.rejections.append(Rejection("edge", centroid, "touches the image or belt border"))
                continue
            holes = []
            child = hierarchy[index][2]
            while child != -1:
                holes.append(contours[child])
                child = hierarchy[child][0]
            self._classify(contour, holes, centroid, yellow, silver, result)
        return result

    def _classify(self, contour, holes, centroid, yellow, silver, result):
        P = self.params
        blob = np.zeros(yellow.shape, np.uint8)
        cv2.drawContours(blob, [contour], -1, 255, cv2.FILLED)
        for hole in holes:
            cv2.drawContours(blob, [hole], -1, 0, cv2.FILLED)
        inside = blob > 0
        count = max(int(inside.sum()), 1)
        fractions = {"yellow": float(yellow[inside].sum()) / count, "silver": float(silver[inside].sum()) / count}
        colour = max(fractions, key=fractions.get)
        purity = fractions[colour]
        # Shape in millimetres on the belt plane.
        outline = self.to_plane(contour.reshape(-1, 2).astype(float)) * 1000.0
        outline_area = abs(cv2.contourArea(outline.astype(np.float32)))
        hole_area = sum(abs(cv2.contourArea((self.to_plane(h.reshape(-1, 2).astype(float)) * 1000.0).astype(np.float32)))
                        for h in holes)
        (_, _), (rw, rh), _ = cv2.minAreaRect(outline.astype(np.float32))
        aspect = max(rw, rh) / max(min(rw, rh), 1e-6)
        hole_ratio = hole_area / max(outline_area, 1e-6)
        hull = cv2.convexHull(outline.astype(np.float32))
        perimeter = cv2.arcLength(hull, True)
        vertices = len(cv2.approxPolyDP(hull, 0.06 * perimeter / 6, True))
        features = {"area_mm2": outline_area - hole_area, "aspect": aspect, "hole_ratio": hole_ratio,
                    "vertices": vertices, "purity": purity, "colour": colour}
        if purity < P["colour_purity_min"]:
            result.rejections.append(Rejection("unknown object", centroid, f"colour: {fractions}"))
            return
        if aspect >= P["bolt_aspect_min"]:
            kind = "bolt"
        elif hole_ratio >= P["hole_ratio_min"]:
            kind = "washer"
        elif aspect < 1.35 and 5 <= vertices <= 10:
            kind = "nut"
        else:
            result.rejections.append(Rejection("unknown object", centroid, f"shape: {features}"))
            return
        part = PART_CLASSES[f"{kind}_{colour}"]
        expected = part.footprint_area * 1e6
        area_error = abs(features["area_mm2"] - expected) / expected
        if area_error > P["area_tolerance"]:
            result.rejections.append(Rejection("unknown object", centroid,
                                               f"{kind}-like but area {features['area_mm2']:.0f} mm² (expected {expected:.0f})"))
            return
        angle = self._angle(contour, kind)
        confidence = purity * math.exp(-area_error)
        if kind == "nut":
            confidence *= 1.0 if vertices == 6 else 0.8
        result.detections.append(Detection(part.name, centroid, angle, float(confidence), features))

    @staticmethod
    def _angle(contour, kind) -> float:
        if kind == "washer":
            return 0.0
        (_, _), (w, h), angle = cv2.minAreaRect(contour)
        angle = math.radians(angle)
        if kind == "bolt":
            return angle if w >= h else angle + math.pi / 2
        return angle % (math.pi / 3)


def belt_mask_for(camera, belt, shrink: float = 0.0) -> np.ndarray:
    """uint8 mask (255 = belt) of the belt's top surface in the camera image."""
    y0, y1 = belt.y - belt.width / 2 + shrink, belt.y + belt.width / 2 - shrink
    corners = np.array([[belt.x_start, y0, belt.height], [belt.x_end, y0, belt.height],
                        [belt.x_end, y1, belt.height], [belt.x_start, y1, belt.height]])
    # Clip the long belt to the part in front of the camera before projecting.
    cx = camera.pose[0, 3]
    reach = 3.0 * camera.pose[2, 3]
    corners[:, 0] = np.clip(corners[:, 0], cx - reach, cx + reach)
    pixels = camera.project(corners)
    mask = np.zeros((camera.height, camera.width), np.uint8)
    cv2.fillConvexPoly(mask, np.round(pixels).astype(np.int32), 255)
    return mask
