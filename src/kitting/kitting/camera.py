"""Pinhole camera model (OpenCV conventions) and its pybullet rendering.

``PinholeCamera`` holds the intrinsics K, the distortion coefficients and the pose of the
optical frame (z forward, x right, y down) in the robot base frame. Its pybullet view and
projection matrices are derived from K so that a rendered point lands on the pixel
``cv2.projectPoints`` gives (OpenCV puts pixel centres at integer coordinates, OpenGL at
half-integers: the projection matrix carries that half pixel). The renderer draws no lens
distortion: a simulated camera has zero distortion, a real one is undistorted first.

``render(client, camera)`` renders with pybullet's CPU TinyRenderer (works in DIRECT mode,
no display). It costs ~100 ms per 640x480 image and holds the interpreter while it runs:
a node renders in its own process (``kitting.render_worker``), never in the physics thread.
"""
from dataclasses import dataclass, field, replace
from typing import Optional, Sequence, Tuple

import cv2
import numpy as np
import pybullet as p

# OpenCV optical frame -> OpenGL camera frame (y up, looking down -z).
_CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


@dataclass
class PinholeCamera:
    width: int
    height: int
    K: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))   # optical frame in base
    near: float = 0.05
    far: float = 2.0

    @classmethod
    def from_spec(cls, spec) -> "PinholeCamera":
        """From a ``kitting.cell.CameraSpec``."""
        return cls(spec.width, spec.height, np.array(spec.K, float), np.array(spec.distortion, float),
                   np.array(spec.pose, float), spec.near, spec.far)

    @property
    def fx(self) -> float:
        return float(self.K[0, 0])

    @property
    def fy(self) -> float:
        return float(self.K[1, 1])

    def scaled(self, width: int, height: int) -> "PinholeCamera":
        """The same camera at another resolution (K scaled; pixel centres kept consistent)."""
        sx, sy = width / self.width, height / self.height
        K = self.K.copy()
        K[0, 0] *= sx
        K[1, 1] *= sy
        K[0, 2] = (self.K[0, 2] + 0.5) * sx - 0.5
        K[1, 2] = (self.K[1, 2] + 0.5) * sy - 0.5
        return replace(self, width=width, height=height, K=K)

    def with_pose(self, pose) -> "PinholeCamera":
        return replace(self, pose=np.array(pose, float))

    # -- projection ---------------------------------------------------------------------
    def world_to_camera(self) -> np.ndarray:
        """4x4 transform from base coordinates to optical-frame coordinates."""
        return np.linalg.inv(self.pose)

    def project(self, points) -> np.ndarray:
        """N x 2 pixels of N x 3 base-frame points (with the distortion model)."""
        points = np.asarray(points, float).reshape(-1, 3)
        T = self.world_to_camera()
        rvec, _ = cv2.Rodrigues(T[:3, :3])
        pixels, _ = cv2.projectPoints(points, rvec, T[:3, 3], self.K, self.distortion)
        return pixels.reshape(-1, 2)

    def rays(self, pixels) -> Tuple[np.ndarray, np.ndarray]:
        """(origin 3, directions N x 3 unit) in the base frame of the rays through pixels."""
        pixels = np.asarray(pixels, float).reshape(-1, 1, 2)
        normalized = cv2.undistortPoints(pixels, self.K, self.distortion).reshape(-1, 2)
        directions = np.c_[normalized, np.ones(len(normalized))]
        directions = directions @ self.pose[:3, :3].T
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        return self.pose[:3, 3].copy(), directions

    # -- pybullet -----------------------------------------------------------------------
    def view_matrix(self) -> Sequence[float]:
        """pybullet (OpenGL, column-major) view matrix of this pose."""
        return tuple((_CV_TO_GL @ self.world_to_camera()).T.ravel())

    def projection_matrix(self) -> Sequence[float]:
        """pybullet (OpenGL, column-major) projection matrix that reproduces K exactly."""
        w, h, n, f = self.width, self.height, self.near, self.far
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        M = np.array([
            [2 * fx / w, 0.0, 1.0 - 2 * (cx + 0.5) / w, 0.0],
            [0.0, 2 * fy / h, 2 * (cy + 0.5) / h - 1.0, 0.0],
            [0.0, 0.0, -(f + n) / (f - n), -2 * f * n / (f - n)],
            [0.0, 0.0, -1.0, 0.0]])
        return tuple(M.T.ravel())

    def depth_from_buffer(self, buffer) -> np.ndarray:
        """Metric depth (m, along the optical axis) from pybullet's [0, 1] depth buffer."""
        buffer = np.asarray(buffer, float)
        return self.far * self.near / (self.far - (self.far - self.near) * buffer)


@dataclass(frozen=True)
class Lighting:
    """TinyRenderer light: direction (towards the light, base frame) and coefficients."""

    direction: Tuple[float, float, float] = (0.2, -0.3, 1.0)
    color: Tuple[float, float, float] = (1.0, 1.0, 1.0)
    ambient: float = 0.6
    diffuse: float = 0.45
    specular: float = 0.0


def render(client: int, camera: PinholeCamera, lighting: Optional[Lighting] = None,
           depth: bool = False, supersample: int = 1):
    """Render the scene of pybullet client ``client`` as seen by ``camera`` with the CPU
    TinyRenderer. Returns an RGB uint8 image (height x width x 3), and with ``depth`` also
    the metric depth image (m, float32).

    TinyRenderer does not anti-alias: an edge lands on a pixel boundary, up to half a pixel
    from where a real sensor (which integrates over each pixel) would put it. With
    ``supersample`` = s the scene is rendered at s times the size and area-averaged down,
    as a sensor does (s² times the cost): use it where sub-pixel edges matter (the
    calibration images); the detector does not need it."""
    lighting = lighting or Lighting()
    if supersample > 1:
        big = render(client, camera.scaled(camera.width * supersample, camera.height * supersample),
                     lighting, depth)
        size = (camera.width, camera.height)
        if not depth:
            return cv2.resize(big, size, interpolation=cv2.INTER_AREA)
        return (cv2.resize(big[0], size, interpolation=cv2.INTER_AREA),
                cv2.resize(big[1], size, interpolation=cv2.INTER_AREA))
    _, _, rgba, buffer, _ = p.getCameraImage(
        camera.width, camera.height, viewMatrix=camera.view_matrix(),
        projectionMatrix=camera.projection_matrix(), renderer=p.ER_TINY_RENDERER,
        shadow=0, lightDirection=list(lighting.direction), lightColor=list(lighting.color),
        lightAmbientCoeff=lighting.ambient, lightDiffuseCoeff=lighting.diffuse,
        lightSpecularCoeff=lighting.specular, flags=p.ER_NO_SEGMENTATION_MASK,
        physicsClientId=client)
    rgb = np.asarray(rgba, np.uint8).reshape(camera.height, camera.width, 4)[:, :, :3].copy()
    if not depth:
        return rgb
    buffer = np.asarray(buffer, np.float32).reshape(camera.height, camera.width)
    return rgb, camera.depth_from_buffer(buffer).astype(np.float32)
