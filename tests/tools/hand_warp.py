"""Moving webcam sequences made from one real hand photo (tests/data, from Debian's
opencv-doc; see tests/data/README.md): each frame is the photo translated, scaled and
rotated about its centre with cv2.warpAffine on a 640x480 canvas, along a smooth seeded
path. The known affine transform of every frame is the ground truth of the image motion:
a point of the photo moves to ``transforms[i] @ (x, y, 1)``, and the hand's apparent size
is proportional to ``scales[i]`` (so its depth to 1 / scales[i]).

Used by tests/unit/motion_sensor/test_webcam_hand_images.py and bench/webcam_hand_bench.py.
"""

import os
from dataclasses import dataclass

import cv2
import numpy as np

DATA = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "data"))
WIDTH, HEIGHT = 640, 480

# Per photo: the scale at which it fills the canvas sensibly, the travel of the path.
PHOTOS = {
    "handSrc": dict(file="handSrc.jpg", base_scale=0.6, travel_px=(90, 45), scale_range=0.25, turn_deg=12.0),
    "Back_Projection_Theory0": dict(
        file="Back_Projection_Theory0.jpg", base_scale=1.6, travel_px=(140, 70), scale_range=0.25, turn_deg=12.0
    ),
}


@dataclass
class WarpedSequence:
    """Frames (BGR, 480x640) and their ground truth: 2x3 affine ``transforms`` from photo
    pixels to frame pixels, ``scales``, ``angles_deg``."""

    name: str
    frames: list[np.ndarray]
    transforms: np.ndarray
    scales: np.ndarray
    angles_deg: np.ndarray

    def image_point(self, photo_xy) -> np.ndarray:
        """Where a photo pixel is in every frame (N x 2)."""
        x, y = photo_xy
        return self.transforms @ np.array([x, y, 1.0])


def load_photo(name: str) -> np.ndarray:
    """The photo (BGR) of ``PHOTOS[name]``."""
    path = os.path.join(DATA, PHOTOS[name]["file"])
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        raise FileNotFoundError(f"cannot read {path}")
    return image


def _border_colour(image: np.ndarray) -> tuple:
    """The photo's median edge colour, so the canvas around it looks like its background."""
    edge = np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])
    return tuple(int(c) for c in np.median(edge, axis=0))


def warped_sequence(name: str, frames: int = 60, seed: int = 0, period_frames: float = 60.0) -> WarpedSequence:
    """``frames`` frames of the photo moving along a seeded smooth path: a Lissajous-like
    translation, a scale oscillating by +-scale_range around base_scale and a turn of
    +-turn_deg, with random phases and amplitude factors from ``seed``."""
    spec = PHOTOS[name]
    photo = load_photo(name)
    rng = np.random.default_rng(seed)
    phases = rng.uniform(0, 2 * np.pi, 4)
    amplitude = rng.uniform(0.7, 1.0, 4)
    t = np.arange(frames) * 2 * np.pi / period_frames
    tx = spec["travel_px"][0] * amplitude[0] * np.sin(t + phases[0])
    ty = spec["travel_px"][1] * amplitude[1] * np.sin(1.5 * t + phases[1])
    scales = spec["base_scale"] * (1.0 + spec["scale_range"] * amplitude[2] * np.sin(0.75 * t + phases[2]))
    angles = spec["turn_deg"] * amplitude[3] * np.sin(0.5 * t + phases[3])
    h, w = photo.shape[:2]
    border = _border_colour(photo)
    images, transforms = [], []
    for i in range(frames):
        matrix = cv2.getRotationMatrix2D((w / 2.0, h / 2.0), angles[i], scales[i])
        # Photo centre to canvas centre, then the path's translation.
        matrix[:, 2] += np.array([WIDTH / 2.0 - w / 2.0 + tx[i], HEIGHT / 2.0 - h / 2.0 + ty[i]])
        images.append(
            cv2.warpAffine(
                photo,
                matrix,
                (WIDTH, HEIGHT),
                flags=cv2.INTER_LINEAR,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=border,
            )
        )
        transforms.append(matrix)
    return WarpedSequence(name=name, frames=images, transforms=np.array(transforms), scales=scales, angles_deg=angles)
