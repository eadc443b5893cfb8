"""One camera image in, the parts on the belt out (what the vision node runs per image).

1. Registration: the camera pose in the robot base frame from whatever cell ArUco markers
   the image shows (``calibration.extrinsics_from_marker``; a marker at the image border
   gives the corners that lie inside it), averaged over the last ``registration_window``
   full registrations (per-image PnP noise is ~0.6 mm / 0.09°). A registration that
   differs from the average by more than ``moved_mm`` / ``moved_deg`` means the camera was
   moved: the average restarts from it (re-registration, no restart needed). The markers
   lie on one line, which leaves the camera's tilt about it loose (0.3 px of corner
   quantisation tilts it by up to ~0.8°): the belt's far edge, found along its length near
   where the markers' pose puts it, joins their corners in one solve
   (``kitting.belt_edge``; ``belt_edge_registration``), unless it is seen in fewer than
   ``belt_edge_min_points`` columns or moves the pose implausibly far.
2. Fewer markers than the cell has (one hidden, cut by the border): the pose prior (the
   last good registration, else the calibrated pose given as ``prior_pose``) is checked
   against them. When it reprojects their corners within ``prior_agreement_px`` it is
   confirmed and held (its age restarts); otherwise the camera moved, and the pose is
   solved from the seen corners starting at the prior (Levenberg-Marquardt: one marker's
   weak tilt is pulled towards the prior instead of a mirror solution).
3. A frame with no usable marker keeps the last registration while it is younger than
   ``registration_max_age`` s, and is counted; with no registration at all, or an older
   one, no part is published (nothing is picked from an unregistered camera).
4. Detection (classical colour + shape, or an ONNX model) and the exact ray-plane
   intersection (``kitting.vision.BeltVision``).

The robot arm works between the camera and the belt. Given the robot's joint states
around the image's stamp (``process(..., joints=)``: one (names, positions) or a list),
the pipeline projects the arm and magnet at each (``kitting.robot_silhouette``, grown by
``robot_mask_margin_px``) with the held camera pose and masks their union: the arm moves
during the exposure and the image's stamp and the joint states' are not taken at the same
instant (at 0.5 m/s near the camera, 10 ms is 10 px). a marker the silhouette touches is left out of the
registration (step 2 then registers from the others), the covered pixels are never
foreground, and a part blob that touches them is rejected as "hidden by the arm" (the
detector module explains why masking beats guessing a half-seen part). Without joints
(``joints=None``, e.g. no joint state near the stamp) nothing is masked and the image is
counted ("arm not masked: no joints").

Every rejected image or object is counted by reason (``counts``) and kept in the result;
``registration`` says how the current image was registered.
"""

import math
from collections import Counter, deque
from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.camera_model import PinholeCamera
from motion_common.params import Param, ParamSchema

from .belt_edge import far_edge, measure_line, refine_with_lines
from .calibration import extrinsics_from_marker
from .cell import Cell
from .detector import ClassicalDetector, DetectionResult, Rejection, belt_mask_for, check_image
from .geometry import pixels_to_plane
from .robot_silhouette import RobotSilhouette, robot_urdf
from .vision import BeltVision, PartObservation

VISION_SCHEMA = ParamSchema(
    [
        Param("detector", "classical", "", "part detector", choices=("classical", "onnx")),
        Param("onnx_model", "", "", "ONNX model file (detector: onnx)"),
        Param("registration_window", 10, "images", "registrations averaged for the camera pose", low=1, high=1000),
        Param(
            "registration_max_age",
            5.0,
            "s",
            "how long a registration serves frames whose markers are hidden",
            low=0.0,
            high=3600.0,
        ),
        Param("moved_mm", 3.0, "mm", "registration change that means the camera moved", low=0.1, high=1000.0),
        Param("moved_deg", 0.5, "deg", "rotation change that means the camera moved", low=0.01, high=180.0),
        Param("max_reprojection_px", 2.0, "px", "largest marker reprojection error accepted", low=0.01, high=100.0),
        Param(
            "prior_agreement_px",
            2.0,
            "px",
            "largest RMS reprojection of the seen markers under the held registration that confirms it",
            low=0.01,
            high=100.0,
        ),
        Param("belt_edge_margin", 0.0, "m", "strip along the belt's edges treated as 'edge'", low=0.0, high=0.2),
        Param(
            "belt_edge_registration",
            True,
            "",
            "solve the camera pose from the marker corners and the belt's far edge together (pins the tilt "
            "about the markers' line)",
        ),
        Param(
            "belt_edge_max_shift_mm",
            25.0,
            "mm",
            "largest camera move the belt edge may make to the markers' registration (16 mm seen on the simulated "
            "cell's perturbed poses)",
            low=0.0,
            high=1000.0,
        ),
        Param(
            "belt_edge_max_turn_deg",
            2.0,
            "deg",
            "largest camera turn the belt edge may make to the markers' registration (1.6 degrees seen on the "
            "simulated cell's perturbed poses)",
            low=0.0,
            high=180.0,
        ),
        Param(
            "belt_edge_min_points",
            20,
            "columns",
            "fewest image columns where the far edge must be found for it to join the registration",
            low=3,
            high=10000,
        ),
        Param("robot_mask", True, "", "mask the robot arm and gripper, projected from the joints, out of the image"),
        Param(
            "robot_mask_margin_px",
            6.0,
            "px",
            "growth of the projected arm (the joint sample's age: 5 ms at 0.5 m/s is 3 px)",
            low=0.0,
            high=100.0,
        ),
        Param("robot_urdf", "", "", "URDF of the arm for the mask; empty: motion_common's of the cell's robot"),
    ],
    ignore=("detector_params",),
)


@dataclass
class VisionResult:
    """Parts located in one image, or why none could be; rejections by reason."""

    ok: bool
    reason: str = ""
    parts: list[PartObservation] = field(default_factory=list)
    rejections: list[Rejection] = field(default_factory=list)
    camera_pose: np.ndarray | None = None
    registration: str = ""  # full | confirmed | partial | held | none


class VisionPipeline:
    """Registration + detection + geometry for one camera (intrinsics ``K``, ``distortion``,
    image size) over the cell's belt."""

    def __init__(
        self,
        cell: Cell,
        K,
        distortion,
        width: int,
        height: int,
        params: dict | None = None,
        detector_params: dict | None = None,
        source: str = "vision parameters",
        prior_pose=None,
    ):
        self.params = VISION_SCHEMA.validate(params or {}, source)
        self.cell = cell
        self.camera = PinholeCamera(int(width), int(height), np.asarray(K, float), np.asarray(distortion, float))
        # The detector and BeltVision are built once; a new registration only gives them
        # the camera pose and the belt mask it implies (_set_pose).
        if self.params["detector"] == "onnx":
            from .onnx_detector import OnnxDetector  # onnxruntime only when asked for

            if not self.params["onnx_model"]:
                raise ValueError(f"{source}: detector is 'onnx' but onnx_model is empty: give the model's path")
            detector = OnnxDetector(self.params["onnx_model"])
        else:
            detector = ClassicalDetector(
                params=detector_params,
                to_plane=lambda px: pixels_to_plane(self._vision.camera, px, cell.belt.height)[:, :2],
            )
        self._vision = BeltVision(self.camera, cell.belt, detector=detector)
        self._registrations = deque(maxlen=self.params["registration_window"])
        self.registration_time: float | None = None
        self.camera_pose: np.ndarray | None = None
        # The calibrated pose (4x4, base frame), only a starting point for a partial view.
        self.prior_pose = None if prior_pose is None else np.asarray(prior_pose, float)
        self.registration = "none"
        self.counts = Counter()
        self.silhouette = None
        if self.params["robot_mask"]:
            urdf = self.params["robot_urdf"] or robot_urdf(cell.robot)
            self.silhouette = RobotSilhouette(urdf, cell.gripper.tcp_length)
        self.robot_mask: np.ndarray | None = None  # the last image's (uint8, 255 = arm)
        # (marker ids, corner pixels, pose) of the last registration refined with the belt edge:
        # the same corners give the same pose, so a still camera does not solve it again.
        self._edge_cache = None

    # -- registration ------------------------------------------------------------------------
    def _register(self, image, stamp: float, occluded=None) -> str:
        """Update the camera pose from the markers; '' or why this image gave none."""
        found = extrinsics_from_marker(
            image, self.cell.markers, self.camera.K, self.camera.distortion, edge_corners=True, occluded=occluded
        )
        if any(why == "hidden by the arm" for _, why in found.missing):
            self.counts["marker hidden by the arm"] += 1
        if not found.ok:
            return "marker partly hidden" if found.partly_hidden else "no marker"
        if found.reprojection_px > self.params["max_reprojection_px"]:
            return f"marker reprojection {found.reprojection_px:.2f} px too large"
        if found.missing:
            return self._register_partial(found, stamp, image, occluded)
        self.counts["registered: every marker"] += 1
        self.registration = "full"
        self._add_registration(self._with_far_edge(found.T_base_cam, found, image, occluded), stamp)
        return ""

    def _with_far_edge(self, pose, found, image, occluded) -> np.ndarray:
        """``pose`` solved again from the marker corners and the belt's far edge together
        (kitting.belt_edge), or ``pose`` unchanged when the edge is not seen well enough or
        disagrees with the markers."""
        if not self.params["belt_edge_registration"]:
            return pose
        cache = self._edge_cache
        if (
            cache is not None
            and cache[0] == tuple(found.used)
            and cache[1].shape == found.image_points.shape
            and np.max(np.abs(cache[1] - found.image_points)) <= 0.25
        ):
            return cache[2]
        edge = far_edge(self.cell.belt, pose[1, 3])
        points = measure_line(image, self.camera.with_pose(pose), edge, occluded)
        if len(points) < self.params["belt_edge_min_points"]:
            self.counts["belt edge not seen: markers only"] += 1
            return pose
        refined, corner_rms, edge_median = refine_with_lines(
            pose, found.object_points, found.image_points, [(edge, points)], self.camera.K, self.camera.distortion
        )
        shift_mm = 1000.0 * np.linalg.norm(refined[:3, 3] - pose[:3, 3])
        turn_deg = math.degrees(Rotation.from_matrix(pose[:3, :3].T @ refined[:3, :3]).magnitude())
        if (
            corner_rms > self.params["max_reprojection_px"]
            or edge_median > 1.0
            or shift_mm > self.params["belt_edge_max_shift_mm"]
            or turn_deg > self.params["belt_edge_max_turn_deg"]
        ):
            # No pose explains both, or one further from the markers' than their corners'
            # quantisation leaves it: something else was taken for the edge, or the belt is
            # not where the cell says.
            self.counts["belt edge disagrees with the markers: markers only"] += 1
            return pose
        self.counts["registered with the belt edge"] += 1
        self._edge_cache = (tuple(found.used), found.image_points.copy(), refined)
        return refined

    def _register_partial(self, found, stamp: float, image, occluded) -> str:
        """Some markers seen: confirm the prior, or solve from them starting at the prior."""
        prior = self.camera_pose if self.camera_pose is not None else self.prior_pose
        seen = ", ".join(str(i) for i in found.used) or "edge corners"
        if prior is None:
            pose = found.T_base_cam
        elif self._reprojection(prior, found) <= self.params["prior_agreement_px"]:
            if self.camera_pose is not None:
                # The markers seen are where the held registration puts them: it still holds.
                self.counts["registration confirmed by part of the markers"] += 1
                self.registration = "confirmed"
                self.registration_time = stamp
                return ""
            # The calibrated prior already explains the seen markers: a solve from fewer
            # markers could only move it along the directions they leave loose (one
            # marker's tilt), so the prior is taken as it is.
            pose = prior
        else:
            pose = self._refine_from(prior, found)
        if self._reprojection(pose, found) > self.params["max_reprojection_px"]:
            return f"marker(s) {seen}: no pose near the prior explains them"
        self.counts["registered: part of the markers"] += 1
        self.registration = "partial"
        self._add_registration(self._with_far_edge(pose, found, image, occluded), stamp)
        return ""

    def _reprojection(self, T_base_cam, found) -> float:
        T_cam_base = np.linalg.inv(T_base_cam)
        rvec, _ = cv2.Rodrigues(T_cam_base[:3, :3])
        projected, _ = cv2.projectPoints(
            found.object_points, rvec, T_cam_base[:3, 3], self.camera.K, self.camera.distortion
        )
        return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - found.image_points) ** 2, axis=1))))

    def _refine_from(self, T_base_cam, found) -> np.ndarray:
        T_cam_base = np.linalg.inv(T_base_cam)
        rvec, _ = cv2.Rodrigues(T_cam_base[:3, :3])
        tvec = T_cam_base[:3, 3].reshape(3, 1).copy()
        rvec, tvec = cv2.solvePnPRefineLM(
            found.object_points, found.image_points, self.camera.K, self.camera.distortion, rvec, tvec
        )
        refined = np.eye(4)
        refined[:3, :3], _ = cv2.Rodrigues(rvec)
        refined[:3, 3] = np.ravel(tvec)
        return np.linalg.inv(refined)

    def _add_registration(self, pose, stamp: float):
        if self._registrations:
            mean = self._mean_pose()
            moved_mm = 1000.0 * np.linalg.norm(pose[:3, 3] - mean[:3, 3])
            moved_deg = math.degrees(
                (Rotation.from_matrix(mean[:3, :3]).inv() * Rotation.from_matrix(pose[:3, :3])).magnitude()
            )
            if moved_mm > self.params["moved_mm"] or moved_deg > self.params["moved_deg"]:
                self.counts["camera moved: re-registered"] += 1
                self._registrations.clear()
        self._registrations.append(pose)
        self.registration_time = stamp
        self._set_pose(self._mean_pose())

    def _mean_pose(self) -> np.ndarray:
        poses = list(self._registrations)
        mean = np.eye(4)
        mean[:3, 3] = np.mean([p[:3, 3] for p in poses], axis=0)
        mean[:3, :3] = Rotation.from_matrix([p[:3, :3] for p in poses]).mean().as_matrix()
        return mean

    def _set_pose(self, pose):
        self.camera_pose = pose
        camera = self.camera.with_pose(pose)
        self._vision.camera = camera
        self._vision.detector.belt_mask = belt_mask_for(camera, self.cell.belt, self.params["belt_edge_margin"])

    @staticmethod
    def _moved(before, after) -> bool:
        """Did the registration move the camera by more than 2 mm or 0.2°?"""
        if before is None or after is None:
            return True
        turn = Rotation.from_matrix(before[:3, :3].T @ after[:3, :3]).magnitude()
        return bool(np.linalg.norm(after[:3, 3] - before[:3, 3]) > 0.002 or math.degrees(turn) > 0.2)

    def _mask(self, pose, configurations) -> np.ndarray:
        """Union of the arm's silhouettes at ``configurations`` in the camera at ``pose``."""
        camera = self.camera.with_pose(pose)
        mask = None
        for q in configurations:
            one = self.silhouette.mask(camera, q, self.params["robot_mask_margin_px"])
            mask = one if mask is None else np.maximum(mask, one)
        return mask

    # -- per image ---------------------------------------------------------------------------
    def process(self, image_rgb, stamp: float, joints=None) -> VisionResult:
        """Parts in one RGB image taken at ``stamp`` (s); ``joints``: (names, positions) of
        the robot at ``stamp``, or a list of them around it (the arm is masked out), None
        when unknown."""
        problem = check_image(image_rgb)
        if not problem and image_rgb.shape[:2] != (self.camera.height, self.camera.width):
            problem = (
                f"image is {image_rgb.shape[1]}x{image_rgb.shape[0]}, the camera info says "
                f"{self.camera.width}x{self.camera.height}"
            )
        if problem:
            self.counts["corrupt image"] += 1
            return VisionResult(False, f"corrupt image: {problem}")
        configurations = []
        if self.silhouette is not None:
            samples = [] if joints is None else [joints] if isinstance(joints[0][0], str) else list(joints)
            for sample in samples:
                try:
                    configurations.append(self.silhouette.configuration(*sample))
                except ValueError:
                    self.counts["arm not masked: joints not the robot's"] += 1
            if not samples:
                self.counts["arm not masked: no joints"] += 1
        # The held pose (or the calibrated one) places the arm for the markers and the parts:
        # a registration moves it by a fraction of a pixel, far less than the margin.
        pose = self.camera_pose if self.camera_pose is not None else self.prior_pose
        occluded = self._mask(pose, configurations) if configurations and pose is not None else None
        why = self._register(cv2.cvtColor(image_rgb, cv2.COLOR_RGB2GRAY), stamp, occluded)
        if why:
            self.counts[why] += 1
            self.registration = "held"
            age = math.inf if self.registration_time is None else stamp - self.registration_time
            if age > self.params["registration_max_age"]:
                self.registration = "none"
                self.counts["no registration: parts not published"] += 1
                return VisionResult(
                    False,
                    f"{why}; no camera registration younger than "
                    f"{self.params['registration_max_age']:g} s: check the markers are visible",
                    registration="none",
                )
        if configurations and (occluded is None or self._moved(pose, self.camera_pose)):
            occluded = self._mask(self.camera_pose, configurations)  # a first or a new registration
        self.robot_mask = occluded
        self._vision.detector.occluded = self.robot_mask
        observations, detected = self._vision.observe(image_rgb)
        detected: DetectionResult
        for rejection in detected.rejections:
            self.counts[rejection.reason] += 1
        self.counts["parts"] += len(observations)
        return VisionResult(True, why, observations, detected.rejections, self.camera_pose, self.registration)
