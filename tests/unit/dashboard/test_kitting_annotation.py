"""The kitting camera frame the dashboard shows (kitting.annotated_image, published by
vision_node): detections and rejections drawn, JPEG-encoded, at a low rate."""

from dataclasses import dataclass

import cv2
import numpy as np
import pytest

from kitting.annotated_image import AnnotationThrottle, annotate, encode_jpeg


@dataclass
class Part:
    class_name: str
    confidence: float
    pixel: tuple


@dataclass
class Rejection:
    reason: str
    pixel: tuple | None


def test_parts_and_rejections_are_drawn_on_a_copy():
    image = np.full((120, 160, 3), 90, np.uint8)
    out = annotate(image, [Part("nut_yellow", 0.93, (40.0, 60.0))], [Rejection("edge", (120, 30))], "1 part(s)")
    assert (image == 90).all()  # the input is untouched
    assert out.shape == image.shape and out.dtype == np.uint8
    assert (out[60, 40 - 14 : 40 + 15] != 90).any()  # the ring around the part
    assert (out[25:35, 115:125] != 90).any()  # the rejection's cross
    assert (out[2:14, 4:40] != 90).any()  # the status line


def test_a_rejection_without_a_pixel_is_skipped():
    image = np.zeros((40, 40, 3), np.uint8)
    assert (annotate(image, [], [Rejection("corrupt image", None)]) == 0).all()


def test_jpeg_round_trip():
    image = np.zeros((48, 64, 3), np.uint8)
    image[:, 32:] = (0, 0, 255)
    data = encode_jpeg(image, quality=90)
    assert data[:2] == b"\xff\xd8"
    decoded = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape == image.shape and decoded[24, 50, 2] > 200


def test_throttle_passes_at_most_one_frame_per_period():
    due = AnnotationThrottle(0.5)
    assert [due.due(t) for t in (0.0, 0.2, 0.49, 0.5, 0.6, 1.2)] == [True, False, False, True, False, True]
    assert due.due(0.1)  # time went back (a restarted clock): send rather than stall
    with pytest.raises(ValueError):
        AnnotationThrottle(0.0)
