"""Depth-camera hand devices, without ROS: the shared per-image step (DepthHandDevice) and
the device fed by a depth image topic (DepthTopicDevice, node ``depth_hand_driver``).

Every image becomes at most one HandSample stamped with the image's own stamp: a hand
(hands_num 1 or 2), or hands_num 0 when no hand is in the working volume (as the Leap
driver does when the hand leaves). An image that cannot be used (wrong encoding, size not
matching its step, all-zero, all-NaN or saturated depth, no or invalid CameraInfo, size
differing from the CameraInfo's) publishes nothing: it is counted as ``rejected`` and by
reason (``rejected_<reason>``) on /diagnostics and warned about, and the node goes on.
"""

import queue
from dataclasses import dataclass

import numpy as np

from motion_common.interface import Topic
from motion_common.params import Param, ParamSchema
from motion_sensor.devices.camera_intrinsics import Intrinsics
from motion_sensor.devices.depth_hand import TRACKER_PARAMS, DepthHandTracker
from motion_sensor.devices.depth_image import DepthImageError, decode_depth, intrinsics_from_camera_info
from motion_sensor.devices.device import HandDevice, empty_sample
from motion_sensor.hand_sample import HandSample

IMAGE_CHECK_PARAMS = ParamSchema(
    [
        Param(
            "min_valid_fraction",
            0.01,
            low=0,
            high=1,
            doc="an image with fewer measured pixels than this fraction is rejected (lens covered, all NaN)",
        ),
    ]
)


@dataclass
class DepthMessage:
    """The fields of one sensor_msgs/Image, ROS-free."""

    stamp: float
    encoding: str
    width: int
    height: int
    step: int
    data: bytes
    is_bigendian: bool = False


class DepthHandDevice(HandDevice):
    """Base of the depth devices: a tracker and the image -> HandSample step."""

    default_frame_id = "camera_depth_frame"  # REP 103 body frame of the depth camera (openni naming)

    def __init__(self, config: dict, **kw):
        super().__init__(config, **kw)
        self.tracker = DepthHandTracker(self.config)

    def reject(self, reason: str, message: str) -> None:
        """Count and warn about an unusable image."""
        self.counters["rejected"] += 1
        self.counters[f"rejected_{reason}"] += 1
        self.warn(f"{self.name}: image dropped ({reason}): {message}")

    def hand_sample(self, depth: np.ndarray, intrinsics: Intrinsics, stamp: float) -> HandSample:
        """The HandSample of one decoded depth image (hands_num 0 when there is no hand)."""
        self.counters["frames"] += 1
        hand = self.tracker.track(depth, intrinsics)
        if hand is None:
            self.counters["no_hand"] += 1
            return empty_sample(stamp, self.frame_id, self.name)
        return HandSample(
            stamp=stamp,
            position=hand.position,
            orientation=hand.orientation,
            hands_num=hand.hands_num,
            hand_types=hand.hand_types,
            frame_id=self.frame_id,
            hand_id=hand.hand_id,
            device=self.name,
            grab_strength=hand.grab_strength,
        )


class DepthTopicDevice(DepthHandDevice):
    """Hands from a depth image topic (16UC1 mm or 32FC1 m) and its CameraInfo.

    The ROS edge (``motion_sensor.devices.depth_node``) calls ``feed_info`` and ``feed_image`` from
    its subscriber callbacks; ``read`` takes the next image (the newest when the tracker
    falls behind: older ones are dropped and counted as ``skipped``).
    """

    name = "depth"
    # The node subscribes these (launch files remap them to the camera's topics).
    subscribes = (
        Topic("camera/depth/image_raw", "sensor_msgs/Image", "depth image, 16UC1 (mm) or 32FC1 (m)"),
        Topic("camera/depth/camera_info", "sensor_msgs/CameraInfo", "intrinsics of that image"),
    )
    params = TRACKER_PARAMS.merged(IMAGE_CHECK_PARAMS).merged(
        ParamSchema(
            [
                Param("wait_s", 0.2, unit="s", low=0, low_open=True, doc="read() returns empty-handed after this long"),
            ]
        )
    )

    def __init__(self, config: dict, **kw):
        super().__init__(config, **kw)
        self.images: queue.Queue[DepthMessage] = queue.Queue(maxsize=2)
        self.intrinsics: Intrinsics | None = None
        # Why there are no intrinsics: the counter key and the message.
        self.info_reason, self.info_problem = "no_camera_info", "no CameraInfo received yet"

    def describe(self) -> str:
        return "depth camera (camera/depth/image_raw)"

    def feed_info(self, k, width: int, height: int) -> None:
        """A CameraInfo arrived (K row-major, image size)."""
        try:
            self.intrinsics = intrinsics_from_camera_info(k, width, height)
            self.info_problem = ""
        except DepthImageError as exc:
            self.intrinsics = None
            self.info_reason, self.info_problem = exc.reason, str(exc)

    def feed_image(self, message: DepthMessage) -> None:
        """An image arrived; the newest two wait for ``read``."""
        while True:
            try:
                self.images.put_nowait(message)
                return
            except queue.Full:
                try:
                    self.images.get_nowait()
                    self.counters["skipped"] += 1
                except queue.Empty:
                    pass

    def open(self) -> None:
        self.tracker.reset()

    def read(self, now: float) -> HandSample | None:
        try:
            message = self.images.get(timeout=self.config["wait_s"])
        except queue.Empty:
            return None
        return self.process(message)

    def process(self, message: DepthMessage) -> HandSample | None:
        """The HandSample of one image message, or None when it is rejected (counted)."""
        intrinsics = self.intrinsics
        if intrinsics is None:
            self.reject(self.info_reason, self.info_problem + " (on camera/depth/camera_info)")
            return None
        try:
            depth = decode_depth(
                message.encoding,
                message.width,
                message.height,
                message.step,
                message.data,
                message.is_bigendian,
                self.config["min_valid_fraction"],
            )
        except DepthImageError as exc:
            self.reject(exc.reason, str(exc))
            return None
        if (message.width, message.height) != (intrinsics.width, intrinsics.height):
            self.reject(
                "camera_info_size",
                f"image {message.width}x{message.height} but CameraInfo "
                f"{intrinsics.width}x{intrinsics.height}: mismatched topics?",
            )
            return None
        return self.hand_sample(depth, intrinsics, message.stamp)

    def close(self) -> None:
        pass
