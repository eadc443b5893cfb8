"""The default part detector: classical OpenCV, colour + shape.

1. Sanity: an image that is not an H x W x 3 uint8 array, is empty or is blank (no contrast)
   is rejected as a whole ("corrupt image").
2. Foreground: inside the belt's image region (``belt_mask``), pixels that differ from the
   dark belt: bright (V) or saturated (S) in HSV. The brightness threshold follows the
   exposure (``belt_value``): a camera's gain, offset and gamma, and the lighting, move the
   belt's and the parts' levels together, so the threshold is set from the belt's median
   V in this image B: ``B + (value_min - belt_value) * (B / belt_value) ** 0.75``, at least
   ``value_margin_min`` above B (exactly ``value_min`` at the nominal exposure). The
   exponent sits between a pure gain (1: the margin scales with the belt) and a pure
   offset (0: it does not): over the cell's perturbation ranges (light x0.7-1.2, gain
   0.8-1.2, offset -12..12, gamma 0.85-1.2) the belt reads 5-95 and a silver part's
   darkest face 44-205, and the threshold stays between them. Yellow needs V above the
   same threshold scaled by 60/95 (a dark, saturated belt pixel is not yellow).
3. Blobs: external contours with their holes (``RETR_CCOMP``). A blob within ``edge_px`` of
   the image border or of the belt region's border is rejected ("edge": only part of it is
   seen, or it lies on the belt's edge).
4. Colour: yellow = hue in [15, 40] (OpenCV's 0-180 scale) and saturated; silver = low
   saturation and bright. A blob whose pixels are neither, or a mix, is an unknown object.
5. Shape, measured in millimetres on the belt plane (the contour is mapped through
   ``to_plane``, so sizes do not depend on where the part lies in the image): a blob with a
   hole (hole area > 12 % of the outline) is a washer candidate, any other a bolt or nut
   candidate. Its convex hull's narrowest and widest widths and its area must lie in the
   class's envelope (``shape_envelope``), computed from the part's real dimensions
   (``kitting.parts``: bolt 13 mm head across, 8 mm shaft, 45.3 mm long, 13 mm high; nut
   M12 18 mm across flats, 20.8 mm across corners, 10.8 mm high; washer 20 mm outside,
   10.5 mm bore, 2 mm high) widened by two effects that are not errors:

   - parallax: ``to_plane`` maps every pixel onto the belt plane, but a part's top face lies
     ``height`` above it, so the top face lands ``height * slope`` further from the
     camera's nadir (slope = horizontal distance from the nadir / camera height above the
     top, at most ``view_slope_max``). The silhouette on the plane is the footprint swept
     by up to 8.6 mm (nut) or 10.4 mm (bolt): a width grows by at most the sweep, the
     narrowest width stays between the footprint's narrowest and its width across the
     sweep, the area grows by at most sweep x the footprint's diameter, and corners only
     open (a convex outline swept along a segment keeps its corners or splits them in two).
     The old fixed test "aspect < 1.35" rejected nuts swept by more than ~3.5 mm (parts
     more than ~0.17 m from the nadir, at the yaws where a corner points along the sweep);
   - pixels: every silhouette edge lies within ``edge_tolerance_px`` of the true outline
     (binarisation of an image without anti-aliasing), converted to mm at the blob.
     findContours runs through the boundary pixels' centres, half a pixel inside the
     edge: the widths get one pixel back and the area is the blob's pixel count times the
     pixel's area on the plane.

   A nut's hull must moreover simplify to 5-10 vertices (a swept hexagon has 6-8) whose
   smallest corner is at least ``nut_corner_min`` (hexagon 120°, box 90°); a bolt's head must
   stand out of its shaft by 13 - 8 = 5 mm (``head_step``; a bar of a bolt's size has no
   step). A blob that fits no envelope is an unknown object; the reason names each
   candidate and the measures that failed.

Each detection has a class, the pixel centroid, an image orientation (rad; the bolt's
axis, the nut's flat direction mod 60°, 0 for a washer) and a confidence in [0, 1] from the
colour purity and how well the shape features match.

``PartDetector`` is the base of this detector and of the ONNX one (``onnx_detector``):
the image check of step 1, the belt mask, its eroded inner region, and the records.

Occlusion: ``occluded`` (set per image by the vision pipeline from the robot's joints,
``kitting.robot_silhouette``) marks the pixels the arm and gripper cover. They are never
foreground (the light grey arm would pass for a silver part), and a blob that touches them
(within ``edge_px``) is rejected as "hidden by the arm": only part of it is seen, so its
centroid and shape would be wrong. The tracker then gets no sighting of the part: it holds
its prediction, or drops the track, instead of jumping to a half-part's centroid. A
detector that finds no blobs (ONNX) drops every detection whose centre lies within
``OCCLUSION_REACH_PX`` of the covered pixels.
"""

import abc
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np

from motion_common.params import Param, ParamSchema

from .parts import BOLT_HEAD, BOLT_SHAFT, PART_CLASSES

DETECTOR_SCHEMA = ParamSchema(
    [
        Param(
            "value_min",
            95,
            "0-255",
            "V above which a grey pixel is foreground (silver), at belt_value",
            low=0,
            high=255,
        ),
        Param(
            "belt_value",
            46,
            "0-255",
            "the belt's V at the nominal exposure: value_min follows the belt's level in each image (0: fixed)",
            low=0,
            high=255,
        ),
        Param("value_margin_min", 12, "0-255", "least V above the belt's that is foreground", low=1, high=255),
        Param("saturation_min", 90, "0-255", "S above which a pixel is coloured", low=0, high=255),
        Param("hue_yellow", [12.0, 40.0], "OpenCV hue 0-180", "yellow hue range", length=2, low=0.0, high=180.0),
        Param("min_area_px", 25, "px", "smaller blobs are noise", low=1, high=100000),
        Param("edge_px", 2, "px", "blobs this close to the image or belt border are 'edge'", low=0, high=100),
        Param("colour_purity_min", 0.75, "", "fraction of a blob's pixels of one colour", low=0.0, high=1.0),
        # A pixel is drawn when its centre is inside the part: an edge is within half a pixel,
        # plus margin for the pixel's shape on the plane. A width may be off by 2 x this (one
        # edge per side), an area by perimeter x this.
        Param(
            "edge_tolerance_px",
            0.75,
            "px",
            "how far a silhouette edge may lie from the part's true outline",
            low=0.0,
            high=10.0,
        ),
        # The cell's camera (config/cell.yaml) is 0.55 m above the belt; the visible belt reaches
        # 0.42 m from its nadir: slope 0.42 / (0.55 - 0.013) = 0.79.
        Param(
            "view_slope_max",
            0.8,
            "",
            "largest horizontal distance of a part from the camera's nadir "
            "/ camera height above the part's top, over the belt in view (parallax bound)",
            low=0.0,
            high=5.0,
        ),
        Param(
            "area_tolerance",
            0.1,
            "",
            "relative footprint area error accepted beyond the parallax and pixel bounds",
            low=0.0,
            high=2.0,
        ),
        # A hexagon's corners are 120°, a box's 90°; parallax only opens corners (module docstring,
        # 5.), pixels blur them: at 640x480 nuts measure >= 106°, boxes <= 94° (at 320x240 ~1 % of
        # nuts fall below 100° and boxes reach 97°: the two are no longer told apart reliably).
        Param("nut_corner_min", 100.0, "deg", "smallest corner of a nut's simplified outline", low=0.0, high=180.0),
        Param("hole_ratio_min", 0.12, "", "hole/outline area above which a blob is a washer", low=0.0, high=1.0),
    ]
)

# A nut's hull is simplified to within a tenth of its width across flats (1.8 mm): above the
# pixel staircase (about 1 px = 0.9 mm at 640x480, 1.8 mm at 320x240), below the 5.2 mm by
# which each corner of the hexagon stands out of the chord between its neighbours.
NUT_POLYGON_EPSILON_MM = 0.1 * 1000.0 * PART_CLASSES["nut_yellow"].width
# A bolt's half length in pixels at the cell camera's scale (~1.1 px/mm): a box detector's
# detection centred this close to the arm may be a part the arm half hides.
OCCLUSION_REACH_PX = 25
HIDDEN = "hidden by the arm"


@dataclass
class Detection:
    class_name: str
    pixel: tuple[float, float]  # px, centroid
    angle: float  # rad, image orientation (x towards y)
    confidence: float  # 0-1
    features: dict = field(default_factory=dict)


@dataclass
class Rejection:
    reason: str  # "corrupt image" | "edge" | "unknown object" | "hidden by the arm"
    pixel: tuple[float, float] | None = None
    detail: str = ""


@dataclass
class DetectionResult:
    detections: list[Detection] = field(default_factory=list)
    rejections: list[Rejection] = field(default_factory=list)

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


class BeltInner:
    """The belt region less an edge zone of ``edge`` px (the image border counts as an
    edge), eroded once per belt mask: the vision pipeline replaces the mask at each
    (re-)registration, frames in between reuse it."""

    def __init__(self):
        self._mask, self._key, self._inner = None, None, None

    def get(self, belt_mask: np.ndarray | None, shape, edge: int) -> np.ndarray:
        """The eroded region for ``belt_mask`` (None: the whole image of ``shape``)."""
        key = (tuple(shape), int(edge))
        if self._inner is None or belt_mask is not self._mask or key != self._key:
            region = np.full(key[0], 255, np.uint8) if belt_mask is None else belt_mask
            kernel = np.ones((2 * edge + 1, 2 * edge + 1), np.uint8)
            self._inner = cv2.erode(region, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0)
            self._mask, self._key = belt_mask, key  # holding the mask keeps its identity unique
        return self._inner


def input_problem(image, belt_mask=None) -> str:
    """'' when a detector can use ``image`` with ``belt_mask`` (or None), else why not."""
    problem = check_image(image)
    if not problem and belt_mask is not None and belt_mask.shape != image.shape[:2]:
        problem = f"image size {image.shape[1]}x{image.shape[0]} does not match the belt mask"
    return problem


class PartDetector(abc.ABC):
    """The part detector ``BeltVision`` runs: ``detect(image) -> DetectionResult``, the same
    ``Detection`` / ``Rejection`` records whatever finds them (``ClassicalDetector``,
    ``onnx_detector.OnnxDetector``).

    ``belt_mask``: uint8 mask (255 = belt) of the image size, or None for the whole image;
    the vision pipeline replaces it at each camera registration. ``detect`` checks the
    image first (one "corrupt image" rejection for an image no detector can use, or one
    that does not fit the mask) and hands a usable one to the subclass's ``_detect``.
    ``belt_inner(shape, edge)`` is the belt region less an edge zone, computed once per mask.
    """

    name = "detector"

    handles_occlusion = False  # True: _detect itself rejects blobs touching ``occluded``

    def __init__(self, belt_mask: np.ndarray | None = None):
        self.belt_mask = belt_mask
        self.occluded: np.ndarray | None = None  # uint8, 255 = the arm covers it (this image)
        self._belt_inner = BeltInner()

    def detect(self, image) -> DetectionResult:
        """The parts in an RGB uint8 image (H x W x 3), and what was rejected and why."""
        result = DetectionResult()
        problem = input_problem(image, self.belt_mask)
        if not problem and self.occluded is not None and self.occluded.shape != image.shape[:2]:
            problem = f"image size {image.shape[1]}x{image.shape[0]} does not match the occlusion mask"
        if problem:
            result.rejections.append(Rejection("corrupt image", detail=problem))
            return result
        self._detect(image, result)
        if self.occluded is not None and not self.handles_occlusion and self.occluded.any():
            size = 2 * OCCLUSION_REACH_PX + 1
            near = cv2.dilate(self.occluded, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size)))
            h, w = near.shape
            kept = []
            for detection in result.detections:
                x, y = (int(round(v)) for v in detection.pixel)
                if 0 <= x < w and 0 <= y < h and near[y, x]:
                    result.rejections.append(Rejection(HIDDEN, detection.pixel, "next to the arm"))
                else:
                    kept.append(detection)
            result.detections = kept
        return result

    @abc.abstractmethod
    def _detect(self, image: np.ndarray, result: DetectionResult) -> None:
        """Add the detections and rejections of a checked image to ``result``."""

    def belt_inner(self, shape, edge: int) -> np.ndarray:
        """The belt region (the whole image of ``shape`` without a mask) less ``edge`` px."""
        return self._belt_inner.get(self.belt_mask, shape, edge)


class ClassicalDetector(PartDetector):
    """Colour + shape detector (``PartDetector``). ``to_plane(pixels N x 2) -> N x 2
    metres`` on the belt plane (default: ``mm_per_px`` scale)."""

    name = "classical"
    handles_occlusion = True

    def __init__(
        self,
        belt_mask: np.ndarray | None = None,
        to_plane: Callable[[np.ndarray], np.ndarray] | None = None,
        mm_per_px: float = 1.0,
        params: dict | None = None,
    ):
        super().__init__(belt_mask)
        self.params = DETECTOR_SCHEMA.validate(params or {}, "detector")
        self.last_value_threshold = float(self.params["value_min"])  # of the last image (diagnostics)
        self.to_plane = to_plane or (lambda px: np.asarray(px, float) * mm_per_px / 1000.0)

    def _detect(self, image, result):
        P = self.params
        h, w = image.shape[:2]
        hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)
        hue, sat, val = hsv[:, :, 0], hsv[:, :, 1], hsv[:, :, 2]
        region = np.full((h, w), 255, np.uint8) if self.belt_mask is None else self.belt_mask
        visible = region > 0
        near_arm = None
        edge = P["edge_px"] + 1
        if self.occluded is not None and self.occluded.any():
            visible &= self.occluded == 0
            size = 2 * edge + 1
            near_arm = cv2.dilate(self.occluded, np.ones((size, size), np.uint8))
        value_min = self.value_threshold(val, visible)
        bright = val >= value_min
        coloured = (sat >= P["saturation_min"]) & (val >= value_min * (60.0 / 95.0))
        yellow = coloured & (hue >= P["hue_yellow"][0]) & (hue <= P["hue_yellow"][1])
        silver = (sat < P["saturation_min"] * 0.5) & bright
        foreground = bright | coloured
        mask = np.where(foreground & visible, 255, 0).astype(np.uint8)
        # Edge zone: the image border and the belt region's border.
        inner = self.belt_inner((h, w), edge)
        contours, hierarchy = cv2.findContours(mask, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
        if hierarchy is None:
            return
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
            if near_arm is not None and np.any(near_arm[points[:, 1], points[:, 0]]):
                result.rejections.append(Rejection(HIDDEN, centroid, "touches the arm's silhouette"))
                continue
            if np.any(inner[points[:, 1], points[:, 0]] == 0):
                result.rejections.append(Rejection("edge", centroid, "touches the image or belt border"))
                continue
            holes = []
            child = hierarchy[index][2]
            while child != -1:
                holes.append(contours[child])
                child = hierarchy[child][0]
            self._classify(contour, holes, centroid, yellow, silver, result)

    def value_threshold(self, val: np.ndarray, visible: np.ndarray) -> float:
        """The V threshold of this image (module docstring, 2.)."""
        P = self.params
        nominal = P["belt_value"]
        if not nominal:
            return float(P["value_min"])
        sample = val[visible][::7]  # the belt, a few parts: the median is the belt's
        if sample.size < 100:
            return float(P["value_min"])
        belt = float(np.median(sample))
        threshold = belt + (P["value_min"] - nominal) * (max(belt, 1.0) / nominal) ** 0.75
        self.last_value_threshold = max(threshold, belt + P["value_margin_min"])
        return self.last_value_threshold

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
        if purity < P["colour_purity_min"]:
            result.rejections.append(Rejection("unknown object", centroid, f"colour: {fractions}"))
            return
        # Shape in millimetres on the belt plane. findContours traces the centres of the
        # blob's boundary pixels, half a pixel inside its edge (outline and holes alike):
        # widths get that pixel back, and the area is the blob's pixel count (a pixel is
        # drawn when its centre is inside the part) times the pixel's area on the plane.
        outline = (self.to_plane(contour.reshape(-1, 2).astype(float)) * 1000.0).astype(np.float32)
        outline_area = abs(cv2.contourArea(outline))
        hole_area = sum(
            abs(cv2.contourArea((self.to_plane(h.reshape(-1, 2).astype(float)) * 1000.0).astype(np.float32)))
            for h in holes
        )
        pixel_mm, pixel_mm2, pixel_mm_max = self._pixel_size(centroid)
        hull = cv2.convexHull(outline)
        width_min, width_max = hull_widths(hull.reshape(-1, 2))
        polygon = cv2.approxPolyDP(hull, NUT_POLYGON_EPSILON_MM, True).reshape(-1, 2)
        # How far a width may be off: an edge per side, in mm at the blob (the pixel's longer side).
        tolerance = P["edge_tolerance_px"] * pixel_mm_max
        features = {
            "area_mm2": count * pixel_mm2,
            "width_min_mm": width_min + pixel_mm,
            "width_max_mm": width_max + pixel_mm,
            "head_step_mm": head_step(outline),
            "hole_ratio": hole_area / max(outline_area, 1e-6),
            "vertices": len(polygon),
            "corner_min_deg": smallest_corner(polygon),
            "tolerance_mm": tolerance,
            "purity": purity,
            "colour": colour,
        }
        kinds = ("washer",) if features["hole_ratio"] >= P["hole_ratio_min"] else ("bolt", "nut")
        mismatches = []
        for kind in kinds:
            part = PART_CLASSES[f"{kind}_{colour}"]
            misfit, excess = self._misfit(part, features, tolerance)
            if not misfit:
                break
            mismatches.append(f"not a {kind}: {misfit}")
        else:
            result.rejections.append(Rejection("unknown object", centroid, "; ".join(mismatches)))
            return
        angle = self._angle(contour, kind)
        if kind == "bolt":
            # Which end is the head: the bolt's pose is found from a model of its silhouette.
            features["head_px"] = head_end(contour.reshape(-1, 2).astype(float), angle)
        confidence = purity * math.exp(-0.5 * excess)
        if kind == "nut":
            confidence *= 1.0 if features["vertices"] == 6 else 0.8
        result.detections.append(Detection(part.name, centroid, angle, float(confidence), features))

    def _misfit(self, part, features, tolerance) -> tuple[str, float]:
        """('', excess) if the blob's features fit ``part``'s envelope (module docstring, 5.),
        else (which measures fail, excess). ``excess``: the worst feature's distance beyond
        the parallax-only envelope, in units of its pixel tolerance (0: inside, <= 1: fits)."""
        P = self.params
        envelope = shape_envelope(part, P["view_slope_max"])
        misfits, excess = [], 0.0
        for name, bounds in envelope.items():
            if name == "perimeter_mm":
                continue
            low, high = bounds
            if name == "area_mm2":  # a band along the outline, plus the relative tolerance
                slack = envelope["perimeter_mm"] * tolerance + P["area_tolerance"] * low
            else:  # a width, or the difference of two: one edge on each side
                slack = 2.0 * tolerance
            value = features[name]
            beyond = max(low - value, value - high, 0.0) / max(slack, 1e-9)
            excess = max(excess, beyond)
            if beyond > 1.0:
                misfits.append(f"{name.rsplit('_', 1)[0]} {value:.1f} outside [{low - slack:.1f}, {high + slack:.1f}]")
        if part.kind == "nut" and not 5 <= features["vertices"] <= 10:
            misfits.append(f"{features['vertices']} vertices (hexagon: 6-8)")
        if part.kind == "nut" and features["corner_min_deg"] < P["nut_corner_min"]:
            misfits.append(f"a {features['corner_min_deg']:.0f}° corner (hexagon: 120°)")
        return ", ".join(misfits), excess

    def _pixel_size(self, pixel) -> tuple[float, float, float]:
        """A pixel at ``pixel`` on the belt plane: (mean side mm, area mm², longer side mm)."""
        pixel = np.asarray(pixel, float)
        a, bx, by = self.to_plane(np.vstack([pixel, pixel + (1.0, 0.0), pixel + (0.0, 1.0)])) * 1000.0
        (ux, uy), (vx, vy) = bx - a, by - a
        area = abs(float(ux * vy - uy * vx))
        return math.sqrt(area), area, float(max(np.linalg.norm(bx - a), np.linalg.norm(by - a)))

    @staticmethod
    def _angle(contour, kind) -> float:
        if kind == "washer":
            return 0.0
        (_, _), (w, h), angle = cv2.minAreaRect(contour)
        angle = math.radians(angle)
        if kind == "bolt":
            return angle if w >= h else angle + math.pi / 2
        return angle % (math.pi / 3)


def hull_widths(hull: np.ndarray) -> tuple[float, float]:
    """(narrowest, widest) width of a convex polygon (N x 2, in order): the narrowest is
    across one of its edges (rotating calipers), the widest its diameter."""
    hull = np.asarray(hull, float).reshape(-1, 2)
    if len(hull) < 3:
        extent = float(np.ptp(hull, axis=0).max()) if len(hull) else 0.0
        return 0.0, extent
    edges = np.roll(hull, -1, axis=0) - hull
    lengths = np.linalg.norm(edges, axis=1)
    keep = lengths > 1e-9
    normals = np.c_[edges[keep, 1], -edges[keep, 0]] / lengths[keep, None]
    projections = hull @ normals.T
    narrowest = float((projections.max(axis=0) - projections.min(axis=0)).min())
    widest = float(np.sqrt(((hull[:, None, :] - hull[None, :, :]) ** 2).sum(axis=2).max()))
    return narrowest, widest


def smallest_corner(polygon: np.ndarray) -> float:
    """Degrees, the smallest interior angle of a convex polygon (N x 2; 180 below 3 vertices)."""
    polygon = np.asarray(polygon, float).reshape(-1, 2)
    if len(polygon) < 3:
        return 180.0
    before, after = np.roll(polygon, 1, axis=0) - polygon, np.roll(polygon, -1, axis=0) - polygon
    cosine = (before * after).sum(axis=1) / np.maximum(
        np.linalg.norm(before, axis=1) * np.linalg.norm(after, axis=1), 1e-12
    )
    return float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))).min())


def head_step(outline: np.ndarray, bins: int = 20) -> float:
    """mm by which the wider end of an elongated blob (N x 2 outline, mm) stands out of its
    middle: the widest of the end fifths' cross-widths minus the median cross-width of the
    far 40-90 % of its length, along its min-area rectangle's long axis. A bolt's head is
    5 mm wider than its shaft; a bar of its size has none."""
    outline = np.asarray(outline, float).reshape(-1, 2)
    (cx, cy), (w, h), angle = cv2.minAreaRect(outline.astype(np.float32))
    angle = math.radians(angle if w >= h else angle + 90.0)
    axis = np.array([math.cos(angle), math.sin(angle)])
    along = (outline - (cx, cy)) @ axis
    across = (outline - (cx, cy)) @ np.array([-axis[1], axis[0]])
    span = along.max() - along.min()
    if span <= 0:
        return 0.0
    index = np.minimum(((along - along.min()) / span * bins).astype(int), bins - 1)
    top, bottom = np.full(bins, -np.inf), np.full(bins, np.inf)
    np.maximum.at(top, index, across)
    np.minimum.at(bottom, index, across)
    profile = np.where(np.isfinite(top), top - bottom, np.nan)
    end = bins // 5
    if np.isnan(profile[:end]).all() or np.isnan(profile[-end:]).all():
        return 0.0
    if np.nanmax(profile[:end]) < np.nanmax(profile[-end:]):
        profile = profile[::-1]
    middle = profile[int(0.4 * bins) : int(0.9 * bins)]
    if np.isnan(middle).all():
        return 0.0
    return float(np.nanmax(profile[:end]) - np.nanmedian(middle))


def head_end(outline_px: np.ndarray, angle: float, bins: int = 20) -> tuple[float, float]:
    """Pixel at the wider end of an elongated blob (its outline, N x 2 px) along the image
    direction ``angle`` (rad): a bolt's head end."""
    axis = np.array([math.cos(angle), math.sin(angle)])
    centre = outline_px.mean(axis=0)
    along = (outline_px - centre) @ axis
    across = (outline_px - centre) @ np.array([-axis[1], axis[0]])
    low, high = along.min(), along.max()
    span = max(high - low, 1e-9)
    index = np.minimum(((along - low) / span * bins).astype(int), bins - 1)
    top, bottom = np.full(bins, -np.inf), np.full(bins, np.inf)
    np.maximum.at(top, index, across)
    np.minimum.at(bottom, index, across)
    width = np.where(np.isfinite(top), top - bottom, np.nan)
    end = max(1, bins // 5)
    head_low = np.nanmax(width[:end]) if not np.isnan(width[:end]).all() else 0.0
    head_high = np.nanmax(width[-end:]) if not np.isnan(width[-end:]).all() else 0.0
    tip = low if head_low >= head_high else high
    point = centre + axis * tip
    return float(point[0]), float(point[1])


def shape_envelope(part, view_slope_max: float) -> dict:
    """What a part's silhouette, mapped onto the belt plane, measures when the part lies
    flat anywhere in a view whose slope is at most ``view_slope_max`` (module docstring,
    5.), before pixel tolerances: {feature: (low, high)} for "width_min_mm",
    "width_max_mm", "area_mm2" (and the bolt's "head_step_mm"), and "perimeter_mm" (the
    footprint's, for the area's pixel band). All from ``kitting.parts``'s dimensions."""
    sweep = 1000.0 * part.height * view_slope_max  # mm, the top face's largest displacement
    area = 1e6 * part.footprint_area
    if part.kind == "nut":
        across_flats = 1000.0 * part.width  # 18 mm (ISO 4032 M12)
        across_corners = across_flats * 2.0 / math.sqrt(3)  # 20.8 mm: also the diameter
        return {
            "width_min_mm": (across_flats, across_corners),
            "width_max_mm": (across_corners, across_corners + sweep),
            "area_mm2": (area, area + sweep * across_corners),
            "perimeter_mm": 3.0 * across_corners,
        }
    if part.kind == "washer":
        diameter, bore = 1000.0 * part.width, 1000.0 * part.bore  # 20 / 10.5 mm (ISO 7089 M10)
        # The sweep also narrows the see-through bore (where the top and bottom openings overlap).
        return {
            "width_min_mm": (diameter, diameter),
            "width_max_mm": (diameter, diameter + sweep),
            "area_mm2": (area, area + sweep * (diameter + bore)),
            "perimeter_mm": math.pi * (diameter + bore),
        }
    head = 1000.0 * BOLT_HEAD[1]  # 13 mm head across flats (ISO 4017 M8)
    shaft = 1000.0 * BOLT_SHAFT[0]  # 8 mm
    length = 1000.0 * part.length  # 45.3 mm head + shaft
    diameter = math.hypot(length, (head + shaft) / 2.0)  # a head corner to the shaft end's far corner
    # The head (13 mm high) sweeps further than the shaft's top (10.5 mm): the step can only grow.
    # Its upper end is left open: a head swept along the shaft widens the head end further.
    return {
        "width_min_mm": (head, head + sweep),
        "width_max_mm": (diameter, diameter + sweep),
        "area_mm2": (area, area + sweep * diameter),
        "head_step_mm": (head - shaft, math.inf),
        "perimeter_mm": 2.0 * (length + head),
    }


def belt_mask_for(camera, belt, shrink: float = 0.0) -> np.ndarray:
    """uint8 mask (255 = belt) of the belt's top surface in the camera image."""
    y0, y1 = belt.y - belt.width / 2 + shrink, belt.y + belt.width / 2 - shrink
    corners = np.array(
        [
            [belt.x_start, y0, belt.height],
            [belt.x_end, y0, belt.height],
            [belt.x_end, y1, belt.height],
            [belt.x_start, y1, belt.height],
        ]
    )
    # Clip the long belt to the part in front of the camera before projecting.
    cx = camera.pose[0, 3]
    reach = 3.0 * camera.pose[2, 3]
    corners[:, 0] = np.clip(corners[:, 0], cx - reach, cx + reach)
    pixels = camera.project(corners)
    mask = np.zeros((camera.height, camera.width), np.uint8)
    cv2.fillConvexPoly(mask, np.round(pixels).astype(np.int32), 255)
    return mask
