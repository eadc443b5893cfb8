"""A webcam (or a video file) with MediaPipe Hands as a HandDevice (nodes/webcam_hand_driver).

The frames come from ``motion_common.video_capture`` (its counters join the device's on
/diagnostics, with the same names as every frame source's):

- ``camera`` >= 0 opens that OpenCV VideoCapture device and streams in tracking mode; a
  camera that cannot be opened or stops delivering is reopened with backoff (by the device
  runner). Each message carries the time its frame was grabbed.
- ``video`` = FILE plays the file once at its own frame rate, one message per frame, each
  stamped with its frame's time in the file mapped onto the clock (a reader more than a
  frame late plays on from now: ``late_frames``); at the end it raises EndOfStream, so the
  node reports ~finished and exits, as the replay does.

Frames that fail to decode are counted (``decode_failures``) and skipped. Frames that
decode but show nothing usable (black, saturated, no hand) go out as hands_num 0 (see
``motion_sensor.devices.webcam_hand``).
"""

import functools
import os
from collections import Counter
from collections.abc import Callable

import numpy as np

from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema, read_yaml_file
from motion_sensor.devices.camera_intrinsics import Intrinsics
from motion_sensor.devices.device import HandDevice
from motion_sensor.devices.hand_landmarks import GestureThresholds
from motion_sensor.devices.webcam_hand import FrameLimits, WebcamHandTracker
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError
from motion_sensor.hand_sample import HandSample


def load_depth_scale(path: str) -> float:
    """``depth_scale`` from a calibration YAML written by webcam_hand_calibrate; raises
    MotionSensorError naming the file when it cannot be used."""
    try:
        data = read_yaml_file(path)
    except ParameterError as exc:
        raise MotionSensorError(
            f"webcam calibration {exc}; run webcam_hand_calibrate or leave calibration_file empty"
        ) from None
    value = data.get("depth_scale") if isinstance(data, dict) else None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.05 <= value <= 20:
        raise MotionSensorError(f"{path}: depth_scale must be a number in [0.05, 20], got {value!r}")
    return float(value)


class WebcamHandDevice(HandDevice):
    """A webcam or a video file, hands found by a detector (MediaPipe Hands by default)."""

    name = "webcam"
    publishes_skeletons = True  # whole-hand skeletons on motion_sensor/raw_hand_skeleton
    default_frame_id = "webcam"
    finite = True  # a video file ends (EndOfStream); a camera never does
    params = ParamSchema(
        [
            Param("camera", 0, low=-1, doc="OpenCV camera index; -1 none (then video must be set)"),
            Param("video", "", doc="play this video file once instead of a camera"),
            Param("width", 640, unit="px", low=0, doc="requested camera frame width (0: the camera's default)"),
            Param("height", 480, unit="px", low=0, doc="requested camera frame height (0: the camera's default)"),
            Param("fps", 30.0, unit="Hz", low=0, doc="requested camera frame rate (0: the camera's default)"),
            Param("hfov_deg", 60.0, unit="deg", low=10, high=170, doc="horizontal field of view, used when fx is 0"),
            Param("fx", 0.0, unit="px", low=0, doc="focal length x; 0: from hfov_deg and the frame width"),
            Param("fy", 0.0, unit="px", low=0, doc="focal length y; 0: equal to fx"),
            Param("cx", 0.0, unit="px", low=0, doc="principal point x; 0: the image centre"),
            Param("cy", 0.0, unit="px", low=0, doc="principal point y; 0: the image centre"),
            Param("depth_scale", 1.0, low=0.05, high=20, doc="true / estimated depth (one-time calibration)"),
            Param("calibration_file", "", doc="YAML with depth_scale (webcam_hand_calibrate); overrides depth_scale"),
            Param("mirrored", False, doc="frames are a mirror (selfie) view; they are flipped back before detection"),
            Param(
                "primary_hand", "right", choices=("right", "left", "first"), doc="hand that steers when two are seen"
            ),
            Param(
                "max_num_hands", 2, low=1, high=4, doc="hands MediaPipe looks for (2: engage:=gesture needs a second)"
            ),
            Param("model_complexity", 1, low=0, high=1, doc="MediaPipe landmark model: 0 lite, 1 full"),
            Param("min_detection_confidence", 0.5, low=0, high=1, doc="MediaPipe palm detection threshold"),
            Param("min_tracking_confidence", 0.5, low=0, high=1, doc="MediaPipe landmark tracking threshold"),
            Param("static_image_mode", False, doc="detect on every frame instead of tracking (several times slower)"),
            Param("black_level", 12.0, low=0, high=255, doc="mean grey (0-255) below which a frame is black"),
            Param(
                "saturated_fraction",
                0.8,
                low=0,
                high=1,
                doc="fraction of white pixels above which a frame is saturated",
            ),
            Param(
                "curl_open_deg",
                60.0,
                unit="deg",
                low=0,
                high=270,
                doc="finger curl (sum of its joint bends) counted as open (grab 0)",
            ),
            Param("curl_fist_deg", 230.0, unit="deg", low=0, high=270, doc="finger curl counted as closed (grab 1)"),
            Param(
                "pinch_touch_m", 0.02, unit="m", low=0, doc="thumb-finger tip distance counted as touching (pinch 1)"
            ),
            Param(
                "pinch_open_m",
                0.07,
                unit="m",
                low=0,
                low_open=True,
                doc="thumb-finger tip distance counted as apart (pinch 0)",
            ),
        ]
    )

    def __init__(
        self, config, detector_factory: Callable[[dict], object] = None, capture_factory: Callable = None, **kw
    ):
        super().__init__(config, **kw)
        cfg = self.config
        if not cfg["video"] and cfg["camera"] < 0:
            raise MotionSensorError("give a camera index (camera >= 0) or a video file (video:=FILE)")
        if cfg["video"] and not os.path.isfile(cfg["video"]):
            raise MotionSensorError(f"video file {cfg['video']} does not exist")
        if cfg["curl_fist_deg"] <= cfg["curl_open_deg"] or cfg["pinch_open_m"] <= cfg["pinch_touch_m"]:
            raise MotionSensorError("need curl_fist_deg > curl_open_deg and pinch_open_m > pinch_touch_m")
        depth_scale = load_depth_scale(cfg["calibration_file"]) if cfg["calibration_file"] else cfg["depth_scale"]
        self._detector_factory = detector_factory or _mediapipe_factory
        self._capture_factory = capture_factory
        self.tracker = WebcamHandTracker(
            detector=None,
            frame_id=self.frame_id,
            intrinsics=self._intrinsics(),
            hfov_deg=cfg["hfov_deg"],
            depth_scale=depth_scale,
            primary_hand=cfg["primary_hand"],
            thresholds=GestureThresholds(
                cfg["curl_open_deg"], cfg["curl_fist_deg"], cfg["pinch_touch_m"], cfg["pinch_open_m"]
            ),
            limits=FrameLimits(black_level=cfg["black_level"], saturated_fraction=cfg["saturated_fraction"]),
            mirrored=cfg["mirrored"],
        )
        self.tracker.counters = self.counters  # one set of counters on /diagnostics
        self._source = None  # the camera or video, kept across reconnects
        self._synced: Counter = Counter()  # its counters already added to ours

    def _intrinsics(self) -> Intrinsics | None:
        cfg = self.config
        if cfg["fx"] <= 0:
            return None
        if cfg["cx"] <= 0 or cfg["cy"] <= 0:
            raise MotionSensorError("with fx set, give cx and cy too (pixels), or leave fx 0 to use hfov_deg")
        return Intrinsics(cfg["fx"], cfg["fy"] or cfg["fx"], cfg["cx"], cfg["cy"])

    def describe(self) -> str:
        return f"webcam video {self.config['video']}" if self.config["video"] else f"webcam {self.config['camera']}"

    def open(self) -> None:
        if self.tracker.detector is None:  # built once, kept across reconnects (loading takes ~0.5 s)
            self.tracker.detector = self._detector_factory(self.config)
            # The first inference initialises the graph (~0.5 s): do it now, so that the
            # first real frame is not late (the sequencer would drop it as stale).
            self.tracker.detector.detect(np.zeros((480, 640, 3), np.uint8))
        if self._source is None:
            self._source = self._new_source()
        if not self.config["video"]:
            why = self._source.open()
            self._sync_counters()
            if why:
                raise DeviceUnavailable(why)

    def _new_source(self):
        """The frame source (motion_common.video_capture) of the camera or the video file."""
        import cv2

        from motion_common import video_capture

        cfg = self.config
        if cfg["video"]:
            try:
                source = video_capture.VideoSource(
                    cfg["video"],
                    fallback_fps=None,
                    clock=self.clock,
                    sleep=self.sleep,
                    open_capture=self._capture_factory or cv2.VideoCapture,
                )
            except video_capture.FrameSourceError as exc:  # a file OpenCV cannot play will not heal: stop
                raise MotionSensorError(str(exc)) from None
            self.info(f"playing {cfg['video']}: {source.frame_count} frames at {source.fps:.2f} fps")
            return source
        # One failed grab and the camera counts as lost: the device runner closes it and
        # opens it again with its backoff.
        return video_capture.DeviceSource(
            cfg["camera"],
            cfg["width"],
            cfg["height"],
            cfg["fps"],
            max_failures=1,
            clock=self.clock,
            sleep=self.sleep,
            open_capture=functools.partial(video_capture.open_camera, factory=self._capture_factory),
        )

    def _sync_counters(self) -> None:
        """Add what the frame source counted since the last call to the device's counters,
        except its ``frames``: the tracker counts every frame it is given."""
        for key, value in self._source.counters.items():
            if key != "frames" and value != self._synced[key]:
                self.counters[key] += value - self._synced[key]
                self._synced[key] = value

    def read(self, now: float) -> HandSample | None:
        frame, why = self._source.read()
        self._sync_counters()
        if frame is None:
            if self._source.finished:
                raise EndOfStream()
            if not self.config["video"] and not self._source.connected:
                raise DeviceUnavailable(why)
            self.warn(f"{self.describe()}: {why}")
            return None
        return self.tracker.process(frame.image, frame.stamp)

    def close(self) -> None:
        if self._source is not None:
            self._source.close()

    def shutdown(self) -> None:
        if self.tracker.detector is not None:
            self.tracker.detector.close()


def _mediapipe_factory(config: dict):
    from motion_sensor.devices.mediapipe_hands import MediaPipeHandDetector

    return MediaPipeHandDetector(
        max_num_hands=config["max_num_hands"],
        model_complexity=config["model_complexity"],
        min_detection_confidence=config["min_detection_confidence"],
        min_tracking_confidence=config["min_tracking_confidence"],
        static_image_mode=config["static_image_mode"],
    )
