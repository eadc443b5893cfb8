"""Camera calibration with cv2.aruco.

Intrinsics: ``calibrate_intrinsics`` takes images of a ChArUco board, finds its corners
with ``cv2.aruco.CharucoDetector.detectBoard``, pairs them with the board's 3-D corners
(``CharucoBoard.matchImagePoints``) and runs ``cv2.calibrateCamera``; the result
(``CalibrationResult``) carries the camera (``motion_common.camera_model.Intrinsics``), the
RMS reprojection error (px) and the per-view errors. ``write_intrinsics_yaml`` writes a
ROS camera_info-style YAML.

Extrinsics: ``extrinsics_from_marker`` detects the cell's ArUco marker
(``cv2.aruco.ArucoDetector``, sub-pixel corners), solves its pose in the camera with
``cv2.solvePnP(..., SOLVEPNP_IPPE_SQUARE)`` (the replacement of the removed
``estimatePoseSingleMarkers``), and chains it with the marker's known pose in the robot base
frame (cell YAML): T_base_cam = T_base_marker * inv(T_cam_marker). A missing marker, a wrong
id or a marker partly outside the image is refused with a reason, never guessed.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from motion_common.camera_model import Intrinsics as CameraIntrinsics

from .cell import Marker


# -- ChArUco board --------------------------------------------------------------------------
@dataclass(frozen=True)
class BoardSpec:
    squares: tuple[int, int] = (7, 5)  # squares along x, y
    square: float = 0.04  # m
    marker: float = 0.03  # m
    dictionary: str = "DICT_5X5_100"

    def board(self):
        aruco_dict = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        return cv2.aruco.CharucoBoard(self.squares, self.square, self.marker, aruco_dict)

    @property
    def size(self) -> tuple[float, float]:
        """m, the board's chessboard area (x, y)."""
        return self.squares[0] * self.square, self.squares[1] * self.square

    def image(self, pixels_per_square: int = 80, margin_squares: float = 0.5) -> tuple[np.ndarray, tuple[float, float]]:
        """(printable grey image with a white margin, its physical size in m (x, y))."""
        w, h = (n * pixels_per_square for n in self.squares)
        image = self.board().generateImage((w, h), marginSize=0, borderBits=1)
        pad = int(round(margin_squares * pixels_per_square))
        image = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
        scale = self.square / pixels_per_square
        return image, (image.shape[1] * scale, image.shape[0] * scale)


@dataclass
class CalibrationResult:
    """What ``calibrate_intrinsics`` measured: the camera's ``intrinsics`` (the framework's
    one pinhole model), the RMS reprojection error (px) overall and per view used, and the
    views rejected with the reason. K, distortion, image_size, fx and fy read through to
    the intrinsics."""

    intrinsics: CameraIntrinsics
    rms: float = float("nan")  # px, overall RMS reprojection error
    per_view_rms: list[float] = field(default_factory=list)
    views_used: int = 0
    views_rejected: list[tuple[int, str]] = field(default_factory=list)

    @property
    def K(self) -> np.ndarray:
        return self.intrinsics.K

    @property
    def distortion(self) -> np.ndarray:
        return np.array(self.intrinsics.distortion)

    @property
    def image_size(self) -> tuple[int, int]:
        return self.intrinsics.image_size

    @property
    def fx(self) -> float:
        return self.intrinsics.fx

    @property
    def fy(self) -> float:
        return self.intrinsics.fy


def Intrinsics(K, distortion, image_size: tuple[int, int], rms: float = float("nan")) -> CalibrationResult:  # noqa: N802
    """A CalibrationResult of camera matrix ``K``, ``distortion`` and ``image_size`` (width,
    height) with RMS error ``rms``: the constructor of the calibration result under its
    former name, for the callers written against it (nodes/kitting_cell_sim)."""
    return CalibrationResult(CameraIntrinsics.from_matrix(K, distortion, image_size), float(rms))


def _grey(image) -> np.ndarray:
    image = np.asarray(image)
    return cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image


def detect_board(image, spec: BoardSpec, min_corners: int = 8):
    """(object points N x 3, image points N x 2) of the board's ChArUco corners in an image,
    or (None, reason)."""
    board = spec.board()
    detector = cv2.aruco.CharucoDetector(board)
    corners, ids, _, _ = detector.detectBoard(_grey(image))
    if ids is None or len(ids) < min_corners:
        return None, f"{0 if ids is None else len(ids)} ChArUco corners found (need {min_corners})"
    objects, pixels = board.matchImagePoints(corners, ids)
    return (np.asarray(objects, np.float32).reshape(-1, 3), np.asarray(pixels, np.float32).reshape(-1, 2)), ""


def calibrate_intrinsics(
    images: Sequence[np.ndarray],
    spec: BoardSpec = BoardSpec(),
    flags: int = 0,
    min_corners: int = 8,
    min_views: int = 4,
) -> CalibrationResult:
    """Intrinsics from ChArUco board images (all of the same size). ValueError when fewer
    than ``min_views`` images show enough of the board."""
    objects, pixels, rejected, size = [], [], [], None
    for index, image in enumerate(images):
        image = np.asarray(image)
        shape = (image.shape[1], image.shape[0])
        if size is None:
            size = shape
        elif shape != size:
            rejected.append((index, f"size {shape} differs from {size}"))
            continue
        found, reason = detect_board(image, spec, min_corners)
        if found is None:
            rejected.append((index, reason))
            continue
        objects.append(found[0])
        pixels.append(found[1])
    if len(objects) < min_views:
        raise ValueError(f"only {len(objects)} usable board views (need {min_views}); rejected: {rejected}")
    rms, K, dist, _, _, _, _, per_view = cv2.calibrateCameraExtended(objects, pixels, size, None, None, flags=flags)
    return CalibrationResult(
        CameraIntrinsics.from_matrix(K, dist.ravel(), size),
        float(rms),
        [float(e) for e in np.ravel(per_view)],
        len(objects),
        rejected,
    )


def write_intrinsics_yaml(path: str, intrinsics: CalibrationResult, camera_name: str = "kitting_camera") -> str:
    """A ROS camera_info-style YAML (camera_calibration_parsers' format) of a calibration
    result, written atomically; returns the absolute path."""
    import yaml

    from motion_common.atomic_file import write_atomic

    w, h = intrinsics.image_size
    K = intrinsics.K
    P = np.c_[K, np.zeros(3)]
    data = {
        "image_width": int(w),
        "image_height": int(h),
        "camera_name": camera_name,
        "camera_matrix": {"rows": 3, "cols": 3, "data": [float(v) for v in K.ravel()]},
        "distortion_model": "plumb_bob",
        "distortion_coefficients": {
            "rows": 1,
            "cols": len(intrinsics.distortion),
            "data": [float(v) for v in intrinsics.distortion],
        },
        "rectification_matrix": {"rows": 3, "cols": 3, "data": [float(v) for v in np.eye(3).ravel()]},
        "projection_matrix": {"rows": 3, "cols": 4, "data": [float(v) for v in P.ravel()]},
        "reprojection_error_px": float(intrinsics.rms),
    }
    return write_atomic(path, yaml.safe_dump(data, sort_keys=False))


# -- marker extrinsics ----------------------------------------------------------------------
@dataclass
class MarkerObservation:
    """The cell marker seen in one image: its corners (4 x 2 px, ArUco order), its pose in
    the camera (4x4), the reprojection error (px), or a reason it is unusable;
    ``partly_outside``: it was found but reaches the image border (partly hidden)."""

    ok: bool
    reason: str = ""
    corners: np.ndarray | None = None
    T_cam_marker: np.ndarray | None = None
    reprojection_px: float = float("nan")
    partly_outside: bool = False


def marker_detector(dictionary: str):
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    aruco_dict = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    return cv2.aruco.ArucoDetector(aruco_dict, params)


def observe_marker(image, marker: Marker, K, distortion, edge_margin_px: float = 3.0) -> MarkerObservation:
    """Detect ``marker`` in an image and solve its pose in the camera frame."""
    image = np.asarray(image)
    if image.size == 0 or image.ndim not in (2, 3):
        return MarkerObservation(False, "corrupt image")
    corners, ids, _ = marker_detector(marker.dictionary).detectMarkers(_grey(image))
    if ids is None or marker.id not in np.ravel(ids):
        return MarkerObservation(
            False,
            "no marker"
            if ids is None
            else f"marker {marker.id} not found (saw ids {sorted(int(i) for i in np.ravel(ids))})",
        )
    found = [c.reshape(4, 2) for c, i in zip(corners, np.ravel(ids)) if i == marker.id]
    if len(found) > 1:
        return MarkerObservation(False, f"marker {marker.id} seen {len(found)} times")
    pixels = found[0].astype(np.float64)
    h, w = image.shape[:2]
    if (
        pixels.min() < edge_margin_px
        or pixels[:, 0].max() > w - 1 - edge_margin_px
        or pixels[:, 1].max() > h - 1 - edge_margin_px
    ):
        return MarkerObservation(False, "marker partly outside the image", pixels, partly_outside=True)
    half = marker.size / 2
    objects = np.array([[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]], np.float64)
    ok, rvec, tvec = cv2.solvePnP(objects, pixels, K, distortion, flags=cv2.SOLVEPNP_IPPE_SQUARE)
    if not ok:
        return MarkerObservation(False, "marker pose not solvable", pixels)
    projected, _ = cv2.projectPoints(objects, rvec, tvec, K, distortion)
    error = float(np.sqrt(np.mean(np.sum((projected.reshape(4, 2) - pixels) ** 2, axis=1))))
    T = np.eye(4)
    T[:3, :3], _ = cv2.Rodrigues(rvec)
    T[:3, 3] = tvec.ravel()
    return MarkerObservation(True, "", pixels, T, error)


@dataclass
class Extrinsics:
    """Camera pose in the base frame (or the reason there is none), the RMS reprojection
    error of the marker corners (px), the markers used, those expected but not usable (id,
    reason), and among these the ones seen partly outside the image (``partly_hidden``)."""

    ok: bool
    reason: str = ""
    T_base_cam: np.ndarray | None = None
    reprojection_px: float = float("nan")
    used: list[int] = field(default_factory=list)
    missing: list[tuple[int, str]] = field(default_factory=list)
    partly_hidden: list[int] = field(default_factory=list)
    object_points: np.ndarray | None = None  # N x 3 m, base frame: the corners solved with
    image_points: np.ndarray | None = None  # N x 2 px, where they were seen
    edge_corners: int = 0  # corners of markers at the image border among them


def _inner_corners(image, observation: MarkerObservation, margin_px: float) -> np.ndarray:
    """Which corners of a marker found at the image border lie ``margin_px`` inside it."""
    h, w = np.asarray(image).shape[:2]
    c = observation.corners
    return (
        (c[:, 0] >= margin_px)
        & (c[:, 1] >= margin_px)
        & (c[:, 0] <= w - 1 - margin_px)
        & (c[:, 1] <= h - 1 - margin_px)
    )


def extrinsics_from_marker(
    image, markers, K, distortion, require_all: bool = False, edge_corners: bool = False, occluded=None
) -> Extrinsics:
    """Camera pose in the robot base frame from one image of the cell's marker(s) (a Marker
    or a list). Every visible marker's four corners, in base coordinates from the cell
    YAML, go into one ``cv2.solvePnP``: one marker with SOLVEPNP_IPPE_SQUARE, several with
    SOLVEPNP_IPPE (coplanar points) refined by Levenberg-Marquardt. With ``require_all`` a
    missing or partly hidden marker refuses the calibration. With ``edge_corners`` a
    marker found at the image border still gives its corners that lie inside the image
    (they join the other markers' corners; alone, fewer than four corners fix nothing).
    ``occluded`` (uint8 mask, 255 = covered by the robot arm): a marker whose square comes
    within 3 px of it counts as missing ("hidden by the arm"): a corner the arm's edge
    touches may be found off its place."""
    markers = [markers] if isinstance(markers, Marker) else list(markers)
    objects, pixels, used, missing, hidden, single = [], [], [], [], [], None
    edge_objects, edge_pixels = [], []
    for marker in markers:
        observation = observe_marker(image, marker, K, distortion)
        if observation.ok and occluded is not None and _touches(occluded, observation.corners, 3):
            missing.append((marker.id, "hidden by the arm"))
            continue
        if not observation.ok:
            missing.append((marker.id, observation.reason))
            if observation.partly_outside:
                hidden.append(marker.id)
                if edge_corners and observation.corners is not None:
                    inside = _inner_corners(image, observation, 3.0)
                    edge_objects.append(marker.corners()[inside])
                    edge_pixels.append(observation.corners[inside])
            continue
        objects.append(marker.corners())
        pixels.append(observation.corners)
        used.append(marker.id)
        single = (marker, observation)
    if not used or (require_all and missing):
        reason = "; ".join(f"marker {i}: {why}" for i, why in missing)
        return Extrinsics(False, reason, missing=missing, partly_hidden=hidden)
    edge_count = int(sum(len(e) for e in edge_objects))
    objects, pixels = np.vstack(objects + edge_objects), np.vstack(pixels + edge_pixels)
    if len(used) == 1 and not edge_count:
        marker, observation = single
        T_cam_base = observation.T_cam_marker @ np.linalg.inv(marker.pose)
    else:
        ok, rvec, tvec = cv2.solvePnP(objects, pixels, K, distortion, flags=cv2.SOLVEPNP_IPPE)
        if not ok:
            return Extrinsics(False, "marker pose not solvable", missing=missing, partly_hidden=hidden)
        rvec, tvec = cv2.solvePnPRefineLM(objects, pixels, K, distortion, rvec, tvec)
        T_cam_base = np.eye(4)
        T_cam_base[:3, :3], _ = cv2.Rodrigues(rvec)
        T_cam_base[:3, 3] = np.ravel(tvec)
    rvec, _ = cv2.Rodrigues(T_cam_base[:3, :3])
    projected, _ = cv2.projectPoints(objects, rvec, T_cam_base[:3, 3], K, distortion)
    error = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - pixels) ** 2, axis=1))))
    return Extrinsics(True, "", np.linalg.inv(T_cam_base), error, used, missing, hidden, objects, pixels, edge_count)


def _touches(mask, corners, margin_px: int) -> bool:
    """Whether the quadrilateral ``corners`` (4 x 2 px), grown by ``margin_px``, covers a
    set pixel of ``mask``."""
    quad = np.zeros(mask.shape, np.uint8)
    polygon = np.round(np.asarray(corners, float).reshape(-1, 2)).astype(np.int32)
    cv2.fillConvexPoly(quad, polygon, 255)
    cv2.polylines(quad, [polygon], True, 255, thickness=2 * margin_px + 1)
    return bool(np.any((quad > 0) & (mask > 0)))


def pose_error(T_estimate, T_true) -> tuple[float, float]:
    """(position error m, rotation error deg) between two 4x4 poses."""
    delta = np.linalg.inv(T_true) @ T_estimate
    angle = math.degrees(math.acos(np.clip((np.trace(delta[:3, :3]) - 1) / 2, -1.0, 1.0)))
    return float(np.linalg.norm(T_estimate[:3, 3] - T_true[:3, 3])), angle
