"""A learned correction of the depth tracker's palm centre: a small convolutional network,
shipped as ONNX and run by onnxruntime, looks at a normalised depth crop around the
tracker's estimate and says where the palm centre lies relative to it.

The tracker's estimate (distance transform, palm core; ``depth_hand``) leans on the
silhouette's widest part, which a palm tilted away from the camera or fingers held together
move by centimetres. The network sees the whole hand in 3-D instead:

- **Input** (``palm_crop``): a square of ``CROP_M`` on a side, centred on the pixel of the
  estimate, at the estimate's depth, resampled to ``CROP_PX`` x ``CROP_PX`` cells (area
  averaging): channel 0 the blob's mean depth in the cell relative to the estimate's, over
  ``DEPTH_SCALE_M`` and clipped to +-1 (1 where the cell holds no blob), channel 1 the
  fraction of the cell the blob covers. Only the tracked blob is seen, so a second hand or
  the body does not enter it.
- **Output**: the palm centre minus the crop's centre point (the ray through the crop's
  middle pixel at the estimate's depth), optical frame, in units of ``OFFSET_SCALE_M``.
- **Applied**: ``weight`` of the way from the estimate to the network's palm centre. The
  network is right on average but noisy from frame to frame on hands it was not trained
  on; part of the way gave a smaller error on left-out tuning subjects than all of it.
- **Fallback** (``PalmModel.correct`` returns None): a crop whose centre lies outside the
  image or with too little of the blob in it, or an output that is not finite or further
  than ``max_offset_m`` from the estimate; the tracker then keeps its own estimate.

The shipped model (``data/depth_palm.onnx``) and how it was trained are described in
``src/motion_sensor/data/README.md``; ``bench/train_depth_palm.py`` trains it again.
"""

import os

import cv2
import numpy as np

from motion_sensor.devices.camera_intrinsics import Intrinsics
from motion_sensor.errors import MotionSensorError
from motion_sensor.onnx_session import cpu_session

__all__ = [
    "CROP_M",
    "CROP_PX",
    "DEPTH_SCALE_M",
    "OFFSET_SCALE_M",
    "MAX_OFFSET_M",
    "DEFAULT_MODEL",
    "PalmCrop",
    "crop_window",
    "crop_channels",
    "palm_crop",
    "corrected",
    "PalmModel",
]

CROP_M = 0.24  # a hand with its fingers spread and a little of the forearm
CROP_PX = 32
DEPTH_SCALE_M = 0.1
OFFSET_SCALE_M = 0.05
#: The farthest (m) a network's palm may be from the estimate and still be used: the
#: crop's half side (a palm outside the crop the network saw is no answer of it).
MAX_OFFSET_M = CROP_M / 2
# A crop the blob covers less than this fraction of is no hand to correct (a hand at the
# image's edge, mostly outside it).
_MIN_COVER = 0.04
DEFAULT_MODEL = os.path.join(os.path.dirname(__file__), "..", "..", "data", "depth_palm.onnx")


class PalmCrop:
    """The network's input for one frame: ``image`` (2, CROP_PX, CROP_PX) float32 and the
    crop's centre point ``origin`` (optical, m) its output is relative to."""

    __slots__ = ("image", "origin")

    def __init__(self, image: np.ndarray, origin: np.ndarray):
        self.image = image
        self.origin = origin


def crop_window(
    z: np.ndarray, top: int, left: int, estimate: np.ndarray, intr: Intrinsics, cells: int = CROP_PX
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(depth relative to the estimate's (m, NaN where no blob), blob cover, centre point) of
    a crop of ``cells`` cells of ``CROP_M / CROP_PX`` around ``estimate`` (optical, m) in the
    blob's depth ``z`` (m, 0 off the blob), a window of the image whose first row and column
    are ``top`` and ``left``; None when the estimate is not in front of the camera or in the
    image. The training script takes wider crops than the network's to shift them."""
    zc = float(estimate[2])
    if not np.isfinite(zc) or zc <= 0:
        return None
    u = intr.fx * float(estimate[0]) / zc + intr.cx
    v = intr.fy * float(estimate[1]) / zc + intr.cy
    if not (0 <= u < intr.width and 0 <= v < intr.height):
        return None
    ui, vi = int(round(u)), int(round(v))
    side = max(cells, int(round(CROP_M * cells / CROP_PX * intr.fx / zc)))
    u0, v0 = ui - side // 2, vi - side // 2
    window = np.zeros((side, side), np.float32)
    # The part of the window that overlaps z (the rest stays 0: no blob).
    r0, r1 = max(v0, top), min(v0 + side, top + z.shape[0])
    c0, c1 = max(u0, left), min(u0 + side, left + z.shape[1])
    if r1 > r0 and c1 > c0:
        window[r0 - v0 : r1 - v0, c0 - u0 : c1 - u0] = z[r0 - top : r1 - top, c0 - left : c1 - left]
    cover = cv2.resize((window > 0).astype(np.float32), (cells, cells), interpolation=cv2.INTER_AREA)
    depth_sum = cv2.resize(window, (cells, cells), interpolation=cv2.INTER_AREA)
    relative = np.full((cells, cells), np.nan, np.float32)
    seen = cover > 1e-6
    relative[seen] = depth_sum[seen] / cover[seen] - zc
    # The crop's centre pixel's ray at the estimate's depth (the window's middle: an even
    # side puts it between pixels).
    uc, vc = u0 + (side - 1) / 2.0, v0 + (side - 1) / 2.0
    origin = np.array([(uc - intr.cx) / intr.fx * zc, (vc - intr.cy) / intr.fy * zc, zc])
    return relative, cover, origin


def crop_channels(relative: np.ndarray, cover: np.ndarray) -> np.ndarray:
    """The network's input channels from ``crop_window``'s depth and cover (..., cells, cells):
    the depth over DEPTH_SCALE_M clipped to +-1 (1 where no blob), and the cover."""
    depth = np.where(np.isnan(relative), 1.0, np.clip(relative / DEPTH_SCALE_M, -1.0, 1.0))
    return np.stack((depth, cover), axis=-3).astype(np.float32)


def palm_crop(z: np.ndarray, top: int, left: int, estimate: np.ndarray, intr: Intrinsics) -> PalmCrop | None:
    """The network's input around ``estimate`` (see ``crop_window``), or None where
    ``crop_window`` gives none or the blob covers too little of the crop."""
    window = crop_window(z, top, left, estimate, intr)
    if window is None or float(window[1].mean()) < _MIN_COVER:
        return None
    return PalmCrop(crop_channels(window[0], window[1]), window[2])


def corrected(estimate, origin, offset, max_offset_m: float, weight: float):
    """(palm centres, fell back) for estimates ``estimate`` (..., 3), their crops' centre
    points ``origin`` and the network's ``offset`` (m): ``weight`` of the way from each
    estimate to ``origin + offset``; the estimate itself where that correction is not finite
    or further than ``max_offset_m``."""
    correction = np.asarray(origin, dtype=float) + np.asarray(offset, dtype=float) - estimate
    fell_back = ~np.all(np.isfinite(correction), axis=-1) | (np.linalg.norm(correction, axis=-1) > max_offset_m)
    correction = np.where(fell_back[..., None], 0.0, correction)
    return estimate + weight * correction, fell_back


class PalmModel:
    """The exported network (input ``crop`` (n, 2, CROP_PX, CROP_PX), output ``offset``
    (n, 3)), single-threaded on the CPU."""

    def __init__(self, model_path: str | None = None, max_offset_m: float = MAX_OFFSET_M, weight: float = 1.0):
        self.model_path = os.path.normpath(model_path or DEFAULT_MODEL)
        self.max_offset_m = float(max_offset_m)
        self.weight = float(weight)
        if not os.path.isfile(self.model_path):
            raise MotionSensorError(f"depth palm model {self.model_path} not found (bench/train_depth_palm.py)")
        self._session = cpu_session(self.model_path, "depth palm model")
        inputs = self._session.get_inputs()
        if [i.name for i in inputs] != ["crop"] or list(inputs[0].shape[1:]) != [2, CROP_PX, CROP_PX]:
            raise MotionSensorError(
                f"{self.model_path}: expected one input 'crop' of shape (n, 2, {CROP_PX}, {CROP_PX}), "
                f"got {[(i.name, i.shape) for i in inputs]}"
            )

    def offsets(self, images: np.ndarray) -> np.ndarray:
        """Raw outputs (n, 3), metres, for crops ``images`` (n, 2, CROP_PX, CROP_PX)."""
        (out,) = self._session.run(["offset"], {"crop": np.ascontiguousarray(images, np.float32)})
        return out.astype(float) * OFFSET_SCALE_M

    def correct(self, z: np.ndarray, top: int, left: int, estimate: np.ndarray, intr: Intrinsics) -> np.ndarray | None:
        """The corrected palm centre (optical, m), or None to keep ``estimate`` (see the
        module's fallback)."""
        crop = palm_crop(z, top, left, estimate, intr)
        if crop is None:
            return None
        palm, fell_back = corrected(
            estimate, crop.origin, self.offsets(crop.image[None])[0], self.max_offset_m, self.weight
        )
        return None if fell_back else palm
