"""What a real camera adds to a rendered image: motion blur of the moving belt's parts and
the exposure's gain, offset and gamma (simulation only; the vision pipeline copes with them).

- Motion blur: during the exposure (``exposure_time`` s) a part on the belt moves
  ``exposure_time * belt_speed`` metres along the belt; in the image that is a streak of
  ``blur_length_px`` pixels along the belt's image direction. The scene is drawn at the
  middle of the exposure (the image's stamp), so the streak is centred on the drawn part
  (a real driver that stamps the start of the exposure is half an exposure early). Only the
  pixels the moving parts sweep are blurred: the still tray, markers and arm stay sharp.
  The belt under the parts is a uniform dark surface, so blurring the image there along the
  belt is the moving part averaged over the belt it passes.
- Exposure: ``out = 255 * gain * (in / 255) ** gamma + offset`` (levels 0-255), clipped.
  ``ExposureDrift`` varies the three per frame as a seeded, mean-reverting random walk that
  stays inside declared ranges (an auto-exposure hunting, a lamp flickering slowly).
"""

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["Exposure", "ExposureDrift", "belt_direction_px", "blur_kernel", "motion_blur", "apply_exposure"]


@dataclass(frozen=True)
class Exposure:
    """Per-frame gain (x), offset (levels of 0-255) and gamma; the identity by default."""

    gain: float = 1.0
    offset: float = 0.0
    gamma: float = 1.0

    @property
    def identity(self) -> bool:
        return self.gain == 1.0 and self.offset == 0.0 and self.gamma == 1.0


def apply_exposure(image: np.ndarray, exposure: Exposure) -> np.ndarray:
    """``image`` (uint8) under ``exposure``, through a 256-entry lookup table."""
    if exposure.identity:
        return image
    levels = np.arange(256, dtype=np.float64) / 255.0
    table = 255.0 * exposure.gain * levels**exposure.gamma + exposure.offset
    return cv2.LUT(image, np.clip(np.round(table), 0, 255).astype(np.uint8))


class ExposureDrift:
    """Seeded per-frame exposure inside ``gain_range``, ``offset_range`` and ``gamma_range``
    (each [low, high]): each value reverts to its range's middle with time constant ``tau``
    (s) and is driven by noise that spans the range within about ``tau``; clipped to the range."""

    def __init__(self, gain_range, offset_range, gamma_range, seed: int = 0, tau: float = 2.0):
        self.ranges = np.array([gain_range, offset_range, gamma_range], float)
        if np.any(self.ranges[:, 0] > self.ranges[:, 1]):
            raise ValueError(f"exposure ranges must be [low, high]: {self.ranges.tolist()}")
        self.rng = np.random.default_rng(seed)
        self.tau = float(tau)
        self.middle = self.ranges.mean(axis=1)
        self.half = 0.5 * (self.ranges[:, 1] - self.ranges[:, 0])
        # start anywhere in the ranges: the first frame of a session is not special
        self.value = self.middle + self.half * self.rng.uniform(-1.0, 1.0, 3)

    def step(self, dt: float) -> Exposure:
        """The exposure of a frame ``dt`` s after the previous one."""
        dt = max(0.0, float(dt))
        decay = math.exp(-dt / self.tau)
        # Ornstein-Uhlenbeck with a stationary spread of half the range's half width
        spread = 0.5 * self.half * math.sqrt(1.0 - decay * decay)
        self.value = self.middle + (self.value - self.middle) * decay + spread * self.rng.standard_normal(3)
        self.value = np.clip(self.value, self.ranges[:, 0], self.ranges[:, 1])
        return Exposure(*(float(v) for v in self.value))


def belt_direction_px(camera, belt, step: float = 0.01) -> tuple[np.ndarray, float]:
    """(unit image direction of the belt's +x, pixels per metre along it) at the belt's point
    under the camera."""
    x = float(np.clip(camera.pose[0, 3], belt.x_start, belt.x_end))
    a, b = camera.project(np.array([[x, belt.y, belt.height], [x + step, belt.y, belt.height]]))
    delta = b - a
    length = float(np.linalg.norm(delta))
    return delta / length, length / step


def blur_kernel(length_px: float, direction) -> np.ndarray:
    """Normalised linear motion-blur kernel: a segment of ``length_px`` along ``direction``
    (unit, image x right, y down), centred, sub-pixel (bilinear splats)."""
    direction = np.asarray(direction, float)
    half = int(math.ceil(length_px / 2.0)) + 1
    kernel = np.zeros((2 * half + 1, 2 * half + 1), np.float64)
    samples = max(2, int(math.ceil(4 * length_px)) + 1)
    for t in np.linspace(-length_px / 2.0, length_px / 2.0, samples):
        x, y = half + t * direction[0], half + t * direction[1]
        x0, y0 = int(math.floor(x)), int(math.floor(y))
        fx, fy = x - x0, y - y0
        kernel[y0, x0] += (1 - fx) * (1 - fy)
        kernel[y0, x0 + 1] += fx * (1 - fy)
        kernel[y0 + 1, x0] += (1 - fx) * fy
        kernel[y0 + 1, x0 + 1] += fx * fy
    return (kernel / kernel.sum()).astype(np.float32)


def motion_blur(image: np.ndarray, moving: np.ndarray, length_px: float, direction) -> np.ndarray:
    """``image`` with the pixels of ``moving`` (bool mask: the belt's parts) smeared over
    ``length_px`` along ``direction``; pixels the streaks do not reach are unchanged."""
    if length_px < 0.05 or not np.any(moving):
        return image
    kernel = blur_kernel(length_px, direction)
    reach = cv2.dilate(moving.astype(np.uint8), (kernel > 0).astype(np.uint8)) > 0
    ys, xs = np.nonzero(reach)
    pad = kernel.shape[0]
    y0, y1 = max(0, ys.min() - pad), min(image.shape[0], ys.max() + pad + 1)
    x0, x1 = max(0, xs.min() - pad), min(image.shape[1], xs.max() + pad + 1)
    window = image[y0:y1, x0:x1]
    blurred = cv2.filter2D(window, -1, kernel, borderType=cv2.BORDER_REPLICATE)
    out = image.copy()
    sub = reach[y0:y1, x0:x1]
    out[y0:y1, x0:x1][sub] = blurred[sub]
    return out
