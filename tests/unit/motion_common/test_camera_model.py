"""motion_common.camera_model: the one pinhole model (kitting and the camera hand devices
both use it), its CameraInfo checks with typed reasons, and the posed camera's projection."""

import math

import numpy as np
import pytest

from motion_common.camera_model import (
    CameraInfoError,
    Intrinsics,
    PinholeCamera,
    camera_info_fields,
    intrinsics_from_camera_info,
)

K = [[610.0, 0.0, 322.0], [0.0, 605.0, 241.0], [0.0, 0.0, 1.0]]


class MessageLike:
    """A CameraInfo stand-in with attributes (the generated class has the same fields)."""

    def __init__(self, **fields):
        self.width, self.height, self.K, self.D, self.distortion_model = 0, 0, [0.0] * 9, [], ""
        self.__dict__.update(fields)


def test_intrinsics_from_a_matrix_and_back():
    intrinsics = Intrinsics.from_matrix(K, np.array([0.1, -0.2, 0.0, 0.0, 0.05]), (640, 480))
    assert (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy) == (610.0, 605.0, 322.0, 241.0)
    assert intrinsics.image_size == (640, 480) and intrinsics.distortion == (0.1, -0.2, 0.0, 0.0, 0.05)
    np.testing.assert_array_equal(intrinsics.K, K)
    assert intrinsics == Intrinsics(610.0, 605.0, 322.0, 241.0, 640, 480, [0.1, -0.2, 0.0, 0.0, 0.05])
    assert len({intrinsics, Intrinsics.from_matrix(K, (0.1, -0.2, 0.0, 0.0, 0.05), (640, 480))}) == 1
    with pytest.raises(AttributeError):
        intrinsics.fx = 1.0  # a value: frozen


def test_field_of_view_and_scaling():
    webcam = Intrinsics.from_fov(640, 480, 90.0)
    assert webcam.fx == pytest.approx(320.0) and (webcam.cx, webcam.cy) == (320.0, 240.0)
    assert webcam.distortion == () and webcam.skew == 0.0
    half = Intrinsics.from_matrix(K, (), (640, 480)).scaled(320, 240)
    assert (half.fx, half.fy, half.width, half.height) == (305.0, 302.5, 320, 240)
    assert (half.cx, half.cy) == ((322.0 + 0.5) / 2 - 0.5, (241.0 + 0.5) / 2 - 0.5)  # pixel edges scale


def test_camera_info_from_a_mapping_or_a_message():
    fields = camera_info_fields(Intrinsics.from_matrix(K, [0.1, -0.2, 0.001, 0.002, 0.05], (640, 480)))
    assert fields["distortion_model"] == "plumb_bob" and fields["P"][2] == 322.0 and fields["P"][3] == 0.0
    back = intrinsics_from_camera_info(fields)
    assert back == Intrinsics.from_matrix(K, [0.1, -0.2, 0.001, 0.002, 0.05], (640, 480))
    assert intrinsics_from_camera_info(MessageLike(**fields)) == back
    # No distortion at all: five zero coefficients, which project as none do.
    bare = intrinsics_from_camera_info({"K": np.ravel(K), "width": 640, "height": 480})
    assert bare.distortion == (0.0,) * 5
    assert (
        camera_info_fields(Intrinsics.from_matrix(K, [0.0] * 8, (640, 480)))["distortion_model"]
        == "rational_polynomial"
    )
    with pytest.raises(ValueError, match="6 distortion coefficients"):
        camera_info_fields(Intrinsics.from_matrix(K, [0.0] * 6, (640, 480)))


@pytest.mark.parametrize(
    "fields, reason, words",
    [
        ({"K": np.ravel(K)}, "no_image_size", "no image size"),
        ({"K": [1, 2, 3], "width": 640, "height": 480}, "bad_matrix", "9 finite numbers"),
        ({"K": [math.nan] * 9, "width": 640, "height": 480}, "bad_matrix", "9 finite numbers"),
        ({"K": ["a"] * 9, "width": 640, "height": 480}, "bad_matrix", "9 finite numbers"),
        ({"K": [0.0] * 9, "width": 640, "height": 480}, "uncalibrated", "uncalibrated"),
        (
            {"K": [610.0, 0, 322, 0, -1.0, 241, 0, 0, 1], "width": 640, "height": 480},
            "bad_matrix",
            "not a camera matrix",
        ),
        (
            {"K": [610.0, 0, 322, 0, 605, 241, 0, 0, 2], "width": 640, "height": 480},
            "bad_matrix",
            "not a camera matrix",
        ),
        (
            {"K": np.ravel(K), "width": 640, "height": 480, "D": [math.inf] * 5, "distortion_model": "plumb_bob"},
            "bad_distortion",
            "non-finite",
        ),
        (
            {"K": np.ravel(K), "width": 640, "height": 480, "D": [0.1] * 6, "distortion_model": "rational_polynomial"},
            "bad_distortion",
            "needs 8 coefficients, got 6",
        ),
        (
            {"K": np.ravel(K), "width": 640, "height": 480, "D": [0.1] * 4, "distortion_model": "equidistant"},
            "bad_distortion",
            "not supported",
        ),
    ],
)
def test_unusable_camera_info_raises_a_typed_error(fields, reason, words):
    with pytest.raises(CameraInfoError, match=words) as info:
        intrinsics_from_camera_info(fields)
    assert info.value.reason == reason and isinstance(info.value, ValueError)


def test_pinhole_camera_projects_and_casts_rays_consistently():
    pose = np.eye(4)
    pose[:3, :3] = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]  # looking down
    pose[:3, 3] = [0.1, 0.0, 0.6]
    camera = PinholeCamera.from_intrinsics(Intrinsics.from_matrix(K, [0.05, -0.02, 0.0, 0.0, 0.0], (640, 480)), pose)
    points = np.array([[0.1, 0.0, 0.0], [0.2, -0.1, 0.05], [-0.05, 0.12, 0.01]])
    pixels = camera.project(points)
    np.testing.assert_allclose(pixels[0], [322.0, 241.0], atol=1e-9)  # the nadir is the principal point
    origin, directions = camera.rays(pixels)
    for point, direction in zip(points, directions):
        along = (point - origin) / np.linalg.norm(point - origin)
        np.testing.assert_allclose(direction, along, atol=1e-6)
    assert camera.intrinsics == Intrinsics.from_matrix(K, [0.05, -0.02, 0.0, 0.0, 0.0], (640, 480))
    small = camera.scaled(320, 240)
    np.testing.assert_allclose(small.project(points), (pixels + 0.5) / 2 - 0.5, atol=1e-6)
