"""The hand detector interface and its MediaPipe Hands implementation.

``HandDetector.detect(rgb)`` returns ``DetectedHand``s (``motion_sensor.devices.hand_landmarks``);
everything after it is plain numpy. MediaPipe is imported only when a ``MediaPipeHandDetector``
is built, so the maths and the device logic are tested with fake detectors without it.
mediapipe 0.10.21 carries its models inside the wheel: nothing is downloaded at run time.
"""

import abc
import os

import numpy as np

from motion_common.native_output import native_output_silenced
from motion_sensor.devices.hand_landmarks import NUM_LANDMARKS, DetectedHand
from motion_sensor.errors import MotionSensorError


class HandDetector(abc.ABC):
    """Finds hands in an RGB image (H x W x 3 uint8, unmirrored: the camera's own view)."""

    @abc.abstractmethod
    def detect(self, rgb: np.ndarray) -> list[DetectedHand]:
        """Every hand seen, best first."""

    def close(self) -> None:
        """Release the detector's resources (optional)."""


def _protobuf_compatibility() -> None:
    """mediapipe 0.10.21 calls ``MessageFactory.GetPrototype``, which protobuf 5 removed in
    favour of ``message_factory.GetMessageClass``; the protobuf pinned here (onnx needs >= 6)
    has only the new name, and every graph start printed an AttributeError. The old name is
    given back, delegating to the new one."""
    from google.protobuf import message_factory

    if not hasattr(message_factory.MessageFactory, "GetPrototype"):
        message_factory.MessageFactory.GetPrototype = lambda self, descriptor: message_factory.GetMessageClass(
            descriptor
        )


class MediaPipeHandDetector(HandDetector):
    """MediaPipe Hands (the ``solutions`` API of mediapipe 0.10.21).

    ``static_image_mode`` False is tracking mode: the palm detector runs only until a hand is
    found, then the landmarks of one frame seed the next (about 15 ms a 640x480 frame here);
    True runs the detector on every frame (independent images, several times slower).
    """

    def __init__(
        self,
        max_num_hands: int = 2,
        model_complexity: int = 1,
        min_detection_confidence: float = 0.5,
        min_tracking_confidence: float = 0.5,
        static_image_mode: bool = False,
    ):
        # Quieten TensorFlow Lite's and glog's start-up chatter on stderr (before the import).
        os.environ.setdefault("GLOG_minloglevel", "2")
        os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "2")
        _protobuf_compatibility()
        try:
            from mediapipe.python.solutions import hands as mp_hands
        except ImportError as exc:
            raise MotionSensorError(
                f"mediapipe is not installed ({exc}); run scripts/setup (it installs requirements-nodeps.txt)"
            ) from None
        # The graph's start-up (TFLite delegate, absl "before InitializeLog" and feedback-tensor
        # notices) and its first frame with a hand (a NORM_RECT notice) print warnings that
        # are no fault, straight to stderr from C++: silenced until the first hand is seen.
        self._warming_up = True
        with native_output_silenced():
            self._hands = mp_hands.Hands(
                static_image_mode=static_image_mode,
                max_num_hands=max_num_hands,
                model_complexity=model_complexity,
                min_detection_confidence=min_detection_confidence,
                min_tracking_confidence=min_tracking_confidence,
            )
            # The graph opens its calculators on threads of its own after Hands() returns,
            # and each TFLite delegate prints a notice then: by the end of one frame they
            # are all open. A blank frame here, still silenced (it seeds no tracking).
            self._hands.process(np.zeros((64, 64, 3), dtype=np.uint8))

    def detect(self, rgb: np.ndarray) -> list[DetectedHand]:
        height, width = rgb.shape[:2]
        if self._warming_up:
            with native_output_silenced():
                result = self._hands.process(np.ascontiguousarray(rgb))
            self._warming_up = not result.multi_hand_landmarks
        else:
            result = self._hands.process(np.ascontiguousarray(rgb))
        if not result.multi_hand_landmarks:
            return []
        hands = []
        for image_lms, world_lms, handedness in zip(
            result.multi_hand_landmarks, result.multi_hand_world_landmarks, result.multi_handedness
        ):
            image = np.array([(lm.x * width, lm.y * height) for lm in image_lms.landmark], dtype=float)
            world = np.array([(lm.x, lm.y, lm.z) for lm in world_lms.landmark], dtype=float)
            if image.shape[0] != NUM_LANDMARKS:
                continue
            label = handedness.classification[0]
            # MediaPipe labels hands as if the image were mirrored (a selfie view); ours is
            # the camera's own view, so its "Left" is the person's right hand.
            person = "right" if label.label == "Left" else "left"
            hands.append(DetectedHand(image=image, world=world, handedness=person, score=float(label.score)))
        hands.sort(key=lambda hand: -hand.score)
        return hands

    def close(self) -> None:
        self._hands.close()
