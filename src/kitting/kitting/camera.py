"""Rendering a simulated camera with pybullet (simulation only: the vision pipeline never
imports this module, so a real cell runs without pybullet).

The camera is a ``motion_common.camera_model.PinholeCamera`` (re-exported here for the
simulation's callers): intrinsics K, distortion and the pose of the optical frame (z
forward, x right, y down) in the robot base frame. Its pybullet view and projection
matrices (``view_matrix``, ``projection_matrix``) are derived from K so that a rendered
point lands on the pixel ``cv2.projectPoints`` gives (OpenCV puts pixel centres at integer
coordinates, OpenGL at half-integers: the projection matrix carries that half pixel). The
renderer draws no lens distortion: a simulated camera has zero distortion, a real one is
undistorted first.

``render(client, camera)`` renders with pybullet's CPU TinyRenderer (works in DIRECT mode,
no display). It costs ~100 ms per 640x480 image and holds the interpreter while it runs:
a node renders in its own process (``kitting.render_worker``), never in the physics thread.
"""

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from motion_common.camera_model import PinholeCamera
from motion_common.quiet_pybullet import pybullet as p

__all__ = ["PinholeCamera", "Lighting", "render", "view_matrix", "projection_matrix", "depth_from_buffer"]

# OpenCV optical frame -> OpenGL camera frame (y up, looking down -z).
_CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


def view_matrix(camera: PinholeCamera) -> Sequence[float]:
    """pybullet (OpenGL, column-major) view matrix of the camera's pose."""
    return tuple((_CV_TO_GL @ camera.world_to_camera()).T.ravel())


def projection_matrix(camera: PinholeCamera) -> Sequence[float]:
    """pybullet (OpenGL, column-major) projection matrix that reproduces K exactly, with
    the camera's near and far planes.

    The principal point terms are set by measurement rather than by the textbook pixel-centre
    convention: with cx and cy + 1, the ArUco corners TinyRenderer draws land where K projects
    them, and a round part's centroid where K projects its centre (mean residual under
    0.07 px at 1x and 2x supersampling; tests/unit/kitting/test_kitting_belt_edge.py). The
    textbook cx + 0.5, cy + 0.5 put everything 0.5 px right and 0.5 px up, a bias the marker
    registration only partly absorbs."""
    w, h, n, f = camera.width, camera.height, camera.near, camera.far
    fx, fy, cx, cy = camera.K[0, 0], camera.K[1, 1], camera.K[0, 2], camera.K[1, 2]
    M = np.array(
        [
            [2 * fx / w, 0.0, 1.0 - 2 * cx / w, 0.0],
            [0.0, 2 * fy / h, 2 * (cy + 1.0) / h - 1.0, 0.0],
            [0.0, 0.0, -(f + n) / (f - n), -2 * f * n / (f - n)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )
    return tuple(M.T.ravel())


def depth_from_buffer(camera: PinholeCamera, buffer) -> np.ndarray:
    """Metric depth (m, along the optical axis) from pybullet's [0, 1] depth buffer."""
    buffer = np.asarray(buffer, float)
    return camera.far * camera.near / (camera.far - (camera.far - camera.near) * buffer)


@dataclass(frozen=True)
class Lighting:
    """TinyRenderer light: direction (towards the light, base frame) and coefficients."""

    direction: tuple[float, float, float] = (0.2, -0.3, 1.0)
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    ambient: float = 0.6
    diffuse: float = 0.45
    specular: float = 0.0


def render(
    client: int,
    camera: PinholeCamera,
    lighting: Lighting | None = None,
    depth: bool = False,
    supersample: int = 1,
    segmentation: bool = False,
):
    """Render the scene of pybullet client ``client`` as seen by ``camera`` with the CPU
    TinyRenderer. Returns an RGB uint8 image (height x width x 3), and with ``depth`` also
    the metric depth image (m, float32).

    TinyRenderer does not anti-alias: an edge lands on a pixel boundary, up to half a pixel
    from where a real sensor (which integrates over each pixel) would put it. With
    ``supersample`` = s the scene is rendered at s times the size and area-averaged down,
    as a sensor does (s² times the cost): use it where sub-pixel edges matter (the
    calibration images); the detector does not need it.

    With ``segmentation`` (not with ``depth``) it returns (RGB, the body id of each pixel,
    -1 where none: int32, height x width; sampled, not averaged, when supersampled)."""
    lighting = lighting or Lighting()
    if segmentation and depth:
        raise ValueError("render: depth and segmentation together are not supported")
    if supersample > 1:
        big = render(
            client,
            camera.scaled(camera.width * supersample, camera.height * supersample),
            lighting,
            depth,
            segmentation=segmentation,
        )
        size = (camera.width, camera.height)
        if segmentation:
            return cv2.resize(big[0], size, interpolation=cv2.INTER_AREA), big[1][::supersample, ::supersample].copy()
        if not depth:
            return cv2.resize(big, size, interpolation=cv2.INTER_AREA)
        return (
            cv2.resize(big[0], size, interpolation=cv2.INTER_AREA),
            cv2.resize(big[1], size, interpolation=cv2.INTER_AREA),
        )
    _, _, rgba, buffer, seg = p.getCameraImage(
        camera.width,
        camera.height,
        viewMatrix=view_matrix(camera),
        projectionMatrix=projection_matrix(camera),
        renderer=p.ER_TINY_RENDERER,
        shadow=0,
        lightDirection=list(lighting.direction),
        lightColor=list(lighting.color),
        lightAmbientCoeff=lighting.ambient,
        lightDiffuseCoeff=lighting.diffuse,
        lightSpecularCoeff=lighting.specular,
        flags=0 if segmentation else p.ER_NO_SEGMENTATION_MASK,
        physicsClientId=client,
    )
    rgb = np.asarray(rgba, np.uint8).reshape(camera.height, camera.width, 4)[:, :, :3].copy()
    if segmentation:
        # pybullet packs the link index into the high bits (objectUniqueId + (linkIndex + 1) << 24)
        ids = np.asarray(seg, np.int64).reshape(camera.height, camera.width)
        return rgb, np.where(ids < 0, -1, ids & ((1 << 24) - 1)).astype(np.int32)
    if not depth:
        return rgb
    buffer = np.asarray(buffer, np.float32).reshape(camera.height, camera.width)
    return rgb, depth_from_buffer(camera, buffer).astype(np.float32)
