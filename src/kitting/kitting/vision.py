"""From pixels to parts on the belt: the detector's output turned into belt-plane poses in
the robot base frame with the calibrated camera (``kitting.geometry``)."""

from dataclasses import dataclass

from motion_common.camera_model import PinholeCamera

from .cell import Belt
from .detector import ClassicalDetector, Detection, DetectionResult, belt_mask_for
from .geometry import image_angle_to_belt_yaw, pixel_to_belt, pixels_to_plane
from .parts import PART_CLASSES


@dataclass
class PartObservation:
    class_name: str
    x: float  # m, base frame, on the belt plane
    y: float
    yaw: float  # rad (bolt: axis mod pi; nut: mod pi/3; washer: 0)
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
        return PartObservation(
            detection.class_name, float(x), float(y), yaw, detection.confidence, tuple(detection.pixel)
        )

    def observe(self, image):
        """(observations, DetectionResult) of one image."""
        result: DetectionResult = self.detector.detect(image)
        return [self.locate(d) for d in result.detections], result
