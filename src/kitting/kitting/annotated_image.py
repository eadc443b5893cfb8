"""The cell camera's image with what vision made of it drawn on top, for people (the
operator's dashboard): each located part with its class and confidence, each rejection
with its reason, and a status line. JPEG-compressed, at a low rate, off the control path
(vision_node publishes it after publishing the poses). No ROS import.
"""

import cv2
import numpy as np

__all__ = ["AnnotationThrottle", "annotate", "encode_jpeg"]

PART_BGR = (60, 200, 60)
REJECTED_BGR = (0, 140, 255)
TEXT_BGR = (255, 255, 255)


class AnnotationThrottle:
    """At most one annotated frame per ``period_s`` (stamps in s; the first one passes)."""

    def __init__(self, period_s: float = 0.5):
        if not period_s > 0:
            raise ValueError(f"period_s must be > 0 s, got {period_s!r}")
        self.period_s = float(period_s)
        self._last = None

    def due(self, now: float) -> bool:
        """True when a frame is due at ``now`` (and counts it as sent)."""
        if self._last is not None and 0.0 <= now - self._last < self.period_s:
            return False
        self._last = now
        return True


def _label(image, text, origin, colour):
    x, y = int(origin[0]), int(origin[1])
    (w, h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.45, 1)
    y = max(y, h + 2)
    cv2.rectangle(image, (x, y - h - 2), (x + w + 2, y + base), colour, cv2.FILLED)
    cv2.putText(image, text, (x + 1, y - 1), cv2.FONT_HERSHEY_SIMPLEX, 0.45, TEXT_BGR, 1, cv2.LINE_AA)


def annotate(bgr, parts=(), rejections=(), status: str = "") -> np.ndarray:
    """A copy of ``bgr`` (H x W x 3 uint8) with ``parts`` (objects with ``pixel``,
    ``class_name``, ``confidence``), ``rejections`` (``pixel`` or None, ``reason``) and a
    ``status`` line drawn on it."""
    image = np.ascontiguousarray(bgr, dtype=np.uint8).copy()
    for part in parts:
        u, v = (int(round(c)) for c in part.pixel)
        cv2.circle(image, (u, v), 14, PART_BGR, 2, cv2.LINE_AA)
        cv2.drawMarker(image, (u, v), PART_BGR, cv2.MARKER_CROSS, 8, 1)
        _label(image, f"{part.class_name} {float(part.confidence):.2f}", (u + 16, v - 8), PART_BGR)
    for rejection in rejections:
        if rejection.pixel is None:
            continue
        u, v = (int(round(c)) for c in rejection.pixel)
        cv2.drawMarker(image, (u, v), REJECTED_BGR, cv2.MARKER_TILTED_CROSS, 16, 2)
        _label(image, rejection.reason, (u + 10, v + 18), REJECTED_BGR)
    if status:
        _label(image, status, (4, 16), (40, 40, 40))
    return image


def encode_jpeg(bgr, quality: int = 70) -> bytes:
    """JPEG bytes of a BGR image (ValueError when OpenCV cannot encode it)."""
    ok, buffer = cv2.imencode(".jpg", np.asarray(bgr), [int(cv2.IMWRITE_JPEG_QUALITY), int(quality)])
    if not ok:
        raise ValueError("JPEG encoding failed")
    return buffer.tobytes()
