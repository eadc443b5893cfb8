"""One webcam frame to one HandSample: frame checks, the detector, the palm pose of the
primary hand, the skeleton of every hand seen and tracking ids, without ROS or a camera
(``WebcamHandTracker``).

Bad input never produces a pose: a black or saturated frame, a frame without a hand and a
detection whose landmarks give no pose all go out as a frame without a hand (hands_num 0,
as the Leap driver sends when the hand leaves), and each is counted by reason.
"""

from collections import Counter
from dataclasses import dataclass

import numpy as np

from motion_sensor.devices.camera_intrinsics import Intrinsics
from motion_sensor.devices.device import empty_sample
from motion_sensor.devices.hand_landmarks import GestureThresholds, landmark_problem, palm_pose
from motion_sensor.devices.mediapipe_hands import HandDetector
from motion_sensor.hand_sample import HandSample
from motion_sensor.skeleton_joints import mediapipe_to_canonical
from motion_sensor.skeleton_sample import SkeletonSample


@dataclass(frozen=True)
class FrameLimits:
    """When a frame holds no usable picture: mean grey below ``black_level`` (0-255) is
    black; more than ``saturated_fraction`` of its pixels at ``saturated_level`` or above
    is saturated (over-exposed)."""

    black_level: float = 12.0
    saturated_level: int = 250
    saturated_fraction: float = 0.8


def frame_problem(frame, limits: FrameLimits = FrameLimits()) -> tuple[str, str] | None:
    """(counter name, reason) when ``frame`` (BGR uint8 H x W x 3) cannot be used, else None."""
    if (
        not isinstance(frame, np.ndarray)
        or frame.dtype != np.uint8
        or frame.ndim != 3
        or frame.shape[2] != 3
        or frame.shape[0] < 16
        or frame.shape[1] < 16
    ):
        shape = getattr(frame, "shape", None)
        return "bad_frames", f"not a BGR uint8 image of at least 16x16 pixels (shape {shape})"
    sample = frame[::4, ::4]  # every 16th pixel is plenty for a mean and a fraction
    grey = sample.mean(axis=2)
    if float(grey.mean()) < limits.black_level:
        return "black_frames", f"black frame (mean grey {grey.mean():.1f} < {limits.black_level:g}): lens covered?"
    saturated = float(np.mean(sample.min(axis=2) >= limits.saturated_level))
    if saturated > limits.saturated_fraction:
        return "saturated_frames", f"saturated frame ({saturated:.0%} of pixels white): too much light?"
    return None


class WebcamHandTracker:
    """Turns BGR frames into HandSamples of the primary hand, with the skeleton of every
    hand seen (up to the detector's ``max_num_hands``; the primary's first), as the Leap
    driver sends both of its hands.

    ``intrinsics`` None derives them from each frame's size and ``hfov_deg``.
    ``primary_hand`` is right, left or first (the detector's best). Each hand type
    (MediaPipe's handedness) keeps a number while it stays in view and gets a new one when
    it appears after a frame without it, so ``hand_id`` changes when the primary hand's type
    changes or a hand comes back, and the sequencer re-seeds its filter for a new hand. A
    second hand of a type already seen in the frame (a handedness mistake) has no skeleton
    (``duplicate_hands``); one whose landmarks give no pose neither (``bad_landmarks``).
    ``counters`` counts every frame's outcome; ``last_problem`` says why the last frame had
    no pose.
    """

    def __init__(
        self,
        detector: HandDetector,
        frame_id: str = "webcam",
        intrinsics: Intrinsics | None = None,
        hfov_deg: float = 60.0,
        depth_scale: float = 1.0,
        primary_hand: str = "right",
        thresholds: GestureThresholds = GestureThresholds(),
        limits: FrameLimits = FrameLimits(),
        mirrored: bool = False,
    ):
        self.detector = detector
        self.frame_id = frame_id
        self.intrinsics = intrinsics
        self.hfov_deg = hfov_deg
        self.depth_scale = depth_scale
        self.primary_hand = primary_hand
        self.thresholds = thresholds
        self.limits = limits
        self.mirrored = mirrored
        self.counters: Counter = Counter()
        self.last_problem = ""
        self._hand_id = 0  # the last number given
        self._ids: dict[str, int] = {}  # hand type in view -> its number

    def intrinsics_for(self, width: int, height: int) -> Intrinsics:
        """The configured intrinsics, or those of the field of view at this frame size."""
        return self.intrinsics or Intrinsics.from_fov(width, height, self.hfov_deg)

    def _no_hand(self, stamp: float, counter: str, reason: str) -> HandSample:
        self.counters[counter] += 1
        self.last_problem = reason
        self._ids.clear()
        return empty_sample(stamp, self.frame_id, "webcam")

    def process(self, frame: np.ndarray, stamp: float) -> HandSample:
        """The HandSample of one BGR frame taken at ``stamp`` (s)."""
        self.counters["frames"] += 1
        problem = frame_problem(frame, self.limits)
        if problem is not None:
            return self._no_hand(stamp, *problem)
        import cv2

        if self.mirrored:  # a selfie view: give the detector the camera's own view
            frame = cv2.flip(frame, 1)
        hands = self.detector.detect(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
        usable = [hand for hand in hands if landmark_problem(hand) is None]
        if len(usable) < len(hands):
            self.counters["bad_landmarks"] += len(hands) - len(usable)
        if not usable:
            return self._no_hand(stamp, "no_hand", "no hand in view")
        primary = usable[0]
        if self.primary_hand in ("left", "right"):
            primary = next((hand for hand in usable if hand.handedness == self.primary_hand), usable[0])
        height, width = frame.shape[:2]
        try:
            pose = palm_pose(primary, self.intrinsics_for(width, height), self.depth_scale, self.thresholds)
        except ValueError as exc:
            return self._no_hand(stamp, "bad_landmarks", str(exc))
        self._track_ids([primary] + [hand for hand in usable if hand is not primary])
        self.counters["hands"] += 1
        others = [hand.handedness for hand in usable if hand is not primary]
        confidence = float(np.clip(primary.score, 0.0, 1.0))
        skeletons = [self._skeleton(stamp, primary.handedness, pose.landmarks, confidence)]
        for hand in usable:
            if hand is primary:
                continue
            if any(s.hand_type == hand.handedness for s in skeletons):
                self.counters["duplicate_hands"] += 1
                continue
            try:
                landmarks = palm_pose(hand, self.intrinsics_for(width, height), self.depth_scale).landmarks
            except ValueError:
                self.counters["bad_landmarks"] += 1
                continue
            skeletons.append(self._skeleton(stamp, hand.handedness, landmarks, float(np.clip(hand.score, 0.0, 1.0))))
        return HandSample(
            stamp=stamp,
            position=pose.position,
            orientation=pose.orientation,
            hands_num=len(usable),
            hand_types=tuple([primary.handedness] + others),
            frame_id=self.frame_id,
            hand_id=self._ids[primary.handedness],
            device="webcam",
            extra={"raw_depth": pose.raw_depth},
            confidence=confidence,
            grab_strength=pose.grab_strength,
            pinch_strength=pose.pinch_strength,
            index_tip=pose.index_tip,
            skeletons=tuple(skeletons),
        )

    def _track_ids(self, hands) -> None:
        """Keep the number of each hand type still in view; number the ones that appear."""
        seen = {hand.handedness for hand in hands}
        for hand_type in list(self._ids):
            if hand_type not in seen:
                del self._ids[hand_type]
        for hand in hands:
            if hand.handedness not in self._ids:
                self._hand_id += 1
                self._ids[hand.handedness] = self._hand_id

    def _skeleton(self, stamp: float, hand_type: str, landmarks, confidence: float) -> SkeletonSample:
        return SkeletonSample(
            stamp,
            mediapipe_to_canonical(landmarks),
            hand_type,
            self._ids[hand_type],
            confidence,
            self.frame_id,
            "webcam",
        )
