"""Palm pose, depth and gesture strengths from the 21 hand landmarks of MediaPipe Hands,
without MediaPipe (plain numpy, so it is unit-tested on synthetic hands).

A detected hand (``DetectedHand``) has the landmarks twice:

- ``image``: 21 x 2 pixel coordinates (u right, v down);
- ``world``: 21 x 3 metric coordinates (m) in the camera's optical axes (x right, y down,
  z away from the camera) around the hand's own centre. Their size is the model's idea of a
  hand, not the user's; their directions follow the hand as the camera sees it.

Depth from one camera: the world landmarks give the hand's metric shape in the camera's
axes, the image landmarks where it appears; the translation that projects the one onto the
other (``hand_translation``, linear least squares under full perspective) puts the hand at
the distance where its metric size has its apparent (pixel) size. The world landmarks'
size is the model's idea of a hand, not the user's, so the result is as large as the model's
hand is to the user's; a one-time calibration at a known distance stores the ratio as
``depth_scale`` (``calibrate_depth_scale``), which scales the whole hand and its position.
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motion_common.rotations import matrix_to_quaternion, with_positive_w
from motion_sensor.devices.camera_intrinsics import OPTICAL_TO_REP103, Intrinsics

WRIST = 0
THUMB_TIP = 4
INDEX_MCP, INDEX_TIP = 5, 8
MIDDLE_MCP, MIDDLE_TIP = 9, 12
RING_MCP, RING_TIP = 13, 16
PINKY_MCP, PINKY_TIP = 17, 20
NUM_LANDMARKS = 21
#: The palm's landmarks: the wrist and the four finger bases (rigid; fingers move).
PALM = (WRIST, INDEX_MCP, MIDDLE_MCP, RING_MCP, PINKY_MCP)
#: (MCP, PIP, DIP, TIP) of the four fingers.
FINGERS = tuple((base, base + 1, base + 2, base + 3) for base in (INDEX_MCP, MIDDLE_MCP, RING_MCP, PINKY_MCP))


@dataclass
class DetectedHand:
    """One hand as a detector sees it: landmarks (see the module docstring), ``handedness``
    ("left"/"right", the person's hand, already corrected for a mirrored view) and its
    classification ``score`` (0-1)."""

    image: np.ndarray
    world: np.ndarray
    handedness: str
    score: float


@dataclass(frozen=True)
class GestureThresholds:
    """Where grab and pinch strength reach 0 and 1.

    A finger's curl is the sum of its three joints' bends (``finger_curls``):
    ``curl_open_deg`` or less counts as straight (0), ``curl_fist_deg`` or more as closed
    (1); grab strength is the mean over the four fingers.
    Pinch strength is 1 when the thumb tip is ``pinch_touch_m`` or closer to the nearest
    finger tip, 0 at ``pinch_open_m`` or more (metric world landmarks).
    """

    curl_open_deg: float = 60.0
    curl_fist_deg: float = 230.0
    pinch_touch_m: float = 0.02
    pinch_open_m: float = 0.07


def landmark_problem(hand: DetectedHand) -> str | None:
    """Why a detection cannot be used (wrong shapes, non-finite values), or None."""
    image = np.asarray(hand.image, dtype=float)
    world = np.asarray(hand.world, dtype=float)
    if image.shape != (NUM_LANDMARKS, 2) or world.shape != (NUM_LANDMARKS, 3):
        return f"landmark arrays of shape {image.shape} and {world.shape}, expected (21, 2) and (21, 3)"
    if not (np.all(np.isfinite(image)) and np.all(np.isfinite(world))):
        return "non-finite landmark"
    if hand.handedness not in ("left", "right"):
        return f"handedness {hand.handedness!r} is not left or right"
    return None


def hand_translation(
    image: np.ndarray, world: np.ndarray, intrinsics: Intrinsics, indices: Sequence[int] = PALM
) -> np.ndarray:
    """Position (m, optical frame) of the world landmarks' origin that projects them onto
    their pixels, before calibration; NaNs when the landmarks have no consistent size.

    The rotation is known (world landmarks are in the camera's axes), so perspective
    projection is linear in the translation t: with normalised pixels x = (u - cx) / fx,
    x (t_z + Z_i) = t_x + X_i, and the same for y. Least squares over ``indices`` (the palm,
    which is rigid) gives t; the depth comes from the spread of the pixels against the metric
    spread, i.e. from the hand's apparent size.
    """
    pixels = np.asarray(image, dtype=float)[list(indices)]
    metric = np.asarray(world, dtype=float)[list(indices)]
    x = (pixels[:, 0] - intrinsics.cx) / intrinsics.fx
    y = (pixels[:, 1] - intrinsics.cy) / intrinsics.fy
    n = len(indices)
    # Unknowns (t_x, t_y, t_z): rows x_i t_z - t_x = X_i - x_i Z_i and y_i t_z - t_y = Y_i - y_i Z_i.
    matrix = np.zeros((2 * n, 3))
    matrix[:n, 0] = -1.0
    matrix[n:, 1] = -1.0
    matrix[:n, 2] = x
    matrix[n:, 2] = y
    rhs = np.concatenate([metric[:, 0] - x * metric[:, 2], metric[:, 1] - y * metric[:, 2]])
    solution, _, rank, _ = np.linalg.lstsq(matrix, rhs, rcond=None)
    if rank < 3 or not solution[2] > 1e-3:  # no spread, or behind the camera: landmarks disagree
        return np.full(3, np.nan)
    return solution


def estimate_depth(image: np.ndarray, world: np.ndarray, intrinsics: Intrinsics) -> float:
    """Depth (m, along the optical axis) of the palm centre before calibration; NaN when the
    landmarks give none (see ``hand_translation``)."""
    palm = np.asarray(world, dtype=float)[list(PALM)].mean(axis=0)
    return float(hand_translation(image, world, intrinsics)[2] + palm[2])


def _unit(vector: np.ndarray) -> np.ndarray:
    norm = float(np.linalg.norm(vector))
    if norm < 1e-9:
        raise ValueError("degenerate hand: zero-length palm vector")
    return vector / norm


def palm_rotation(world: np.ndarray, handedness: str) -> np.ndarray:
    """Rotation matrix (columns: the hand's x, y, z axes in the optical frame) of hand.msg's
    hand frame: x along the fingers (wrist to the middle finger's base), z out of the back of
    the hand, y completing a right-handed frame. Raises ValueError for a degenerate palm.

    The palm normal is the cross product of the wrist-to-index-base and wrist-to-pinky-base
    vectors; which side of the palm it points to depends on the hand (a left hand is a
    mirror image), hence ``handedness``."""
    world = np.asarray(world, dtype=float)
    wrist = world[WRIST]
    x_axis = _unit(world[MIDDLE_MCP] - wrist)
    # For a right hand (index - wrist) x (pinky - wrist) points out of the palm.
    normal = np.cross(world[INDEX_MCP] - wrist, world[PINKY_MCP] - wrist)
    back = -normal if handedness == "right" else normal
    z_axis = _unit(back - np.dot(back, x_axis) * x_axis)
    y_axis = np.cross(z_axis, x_axis)
    return np.column_stack([x_axis, y_axis, z_axis])


def finger_curls(world: np.ndarray) -> np.ndarray:
    """The four fingers' curl (degrees): the sum of the bends at their three joints (wrist-
    to-base against base-to-middle joint, and so on to the tip); about 0 for a straight
    finger, 250 in a fist. Monotonic as a finger closes, unlike the tip's direction, which
    comes back towards the palm."""
    world = np.asarray(world, dtype=float)
    curls = []
    for chain in FINGERS:
        points = world[[WRIST, *chain]]
        segments = np.diff(points, axis=0)
        total = 0.0
        for first, second in zip(segments[:-1], segments[1:]):
            cosine = np.dot(first, second) / max(np.linalg.norm(first) * np.linalg.norm(second), 1e-12)
            total += np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
        curls.append(total)
    return np.array(curls)


def _ramp(value: float, zero_at: float, one_at: float) -> float:
    """0 at ``zero_at``, 1 at ``one_at``, linear between, clipped."""
    return float(np.clip((value - zero_at) / (one_at - zero_at), 0.0, 1.0))


def grab_strength(world: np.ndarray, thresholds: GestureThresholds = GestureThresholds()) -> float:
    """0 for an open flat hand, 1 for a fist (as Leap's grabStrength): mean finger curl."""
    curls = finger_curls(world)
    return float(np.mean([_ramp(c, thresholds.curl_open_deg, thresholds.curl_fist_deg) for c in curls]))


def pinch_strength(world: np.ndarray, thresholds: GestureThresholds = GestureThresholds()) -> float:
    """1 when the thumb tip touches the nearest finger tip, 0 when they are apart."""
    world = np.asarray(world, dtype=float)
    tips = world[[INDEX_TIP, MIDDLE_TIP, RING_TIP, PINKY_TIP]]
    distance = float(np.min(np.linalg.norm(tips - world[THUMB_TIP], axis=1)))
    return _ramp(distance, thresholds.pinch_open_m, thresholds.pinch_touch_m)


@dataclass
class PalmPose:
    """A hand's pose in the device frame (REP 103 axes, m): palm centre, unit quaternion
    (x, y, z, w), index tip; plus the gesture strengths, the raw (uncalibrated) depth and
    all 21 landmarks placed the same way (``landmarks`` (21, 3), metric as far as the depth
    estimate is; ``motion_sensor.skeleton_joints.mediapipe_to_canonical`` maps them)."""

    position: np.ndarray
    orientation: np.ndarray
    index_tip: np.ndarray
    grab_strength: float
    pinch_strength: float
    raw_depth: float
    landmarks: np.ndarray | None = None


def palm_pose(
    hand: DetectedHand,
    intrinsics: Intrinsics,
    depth_scale: float = 1.0,
    thresholds: GestureThresholds = GestureThresholds(),
) -> PalmPose:
    """The palm pose of one detected hand in the camera's REP 103 frame (x forward along the
    optical axis, y left, z up). ``depth_scale`` is the calibrated ratio of true to estimated
    depth; it also scales the model's metric hand to the user's. Raises ValueError for a
    detection that gives no pose (check ``landmark_problem`` first)."""
    image = np.asarray(hand.image, dtype=float)
    world = np.asarray(hand.world, dtype=float)
    translation = hand_translation(image, world, intrinsics)
    if not np.all(np.isfinite(translation)):
        raise ValueError("no depth: the palm landmarks have no consistent size")
    # Scaling the model's hand and its translation together keeps every projection: the
    # calibrated hand is the same picture of a hand depth_scale times the model's size.
    raw_centre = translation + world[list(PALM)].mean(axis=0)
    centre = depth_scale * raw_centre
    index_tip = depth_scale * (translation + world[INDEX_TIP])
    raw_depth = float(raw_centre[2])
    rotation = palm_rotation(world, hand.handedness)
    return PalmPose(
        position=OPTICAL_TO_REP103 @ centre,
        orientation=with_positive_w(matrix_to_quaternion(OPTICAL_TO_REP103 @ rotation)),
        index_tip=OPTICAL_TO_REP103 @ index_tip,
        grab_strength=grab_strength(world, thresholds),
        pinch_strength=pinch_strength(world, thresholds),
        raw_depth=raw_depth,
        landmarks=(depth_scale * (translation + world)) @ OPTICAL_TO_REP103.T,
    )


def calibrate_depth_scale(raw_depths: Sequence[float], true_depth_m: float) -> float:
    """The ``depth_scale`` that maps the median raw depth of a hand held at a measured
    distance (m, camera to palm along the optical axis) onto that distance. Raises
    ValueError without usable estimates."""
    values = np.asarray([d for d in raw_depths if np.isfinite(d) and d > 0], dtype=float)
    if values.size == 0:
        raise ValueError("no usable depth estimate: show the open hand to the camera")
    if not true_depth_m > 0:
        raise ValueError(f"the measured distance must be positive, got {true_depth_m}")
    return float(true_depth_m / np.median(values))
