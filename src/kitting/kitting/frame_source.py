"""Camera frames for the kitting cell: the framework's frame sources
(``motion_common.video_capture``: a live camera, a video file or a folder of images, each
``read() -> (Frame, "")`` or ``(None, reason)`` with the same counters), with the cell's
default for a camera that cannot be opened or is lost: it is reopened with exponential
backoff (``motion_sensor.devices.device.Backoff``), the waits inside ``read`` through the injected
``sleep``."""

from motion_common import video_capture
from motion_common.video_capture import (
    IMAGE_EXTENSIONS,
    Frame,
    FrameSource,
    FrameSourceError,
    ImageFolderSource,
    ReadResult,
    VideoSource,
    as_bgr,
    list_images,
    open_camera,
)
from motion_sensor.devices.device import Backoff

__all__ = [
    "IMAGE_EXTENSIONS",
    "Frame",
    "FrameSource",
    "FrameSourceError",
    "ImageFolderSource",
    "ReadResult",
    "VideoSource",
    "DeviceSource",
    "as_bgr",
    "list_images",
    "open_camera",
    "open_source",
]


class DeviceSource(video_capture.DeviceSource):
    """A live camera (``motion_common.video_capture.DeviceSource``), reopened with backoff:
    ``backoff`` defaults to ``motion_sensor.devices.device.Backoff()``."""

    def __init__(self, *args, backoff=None, **kwargs):
        super().__init__(*args, backoff=backoff or Backoff(), **kwargs)


def open_source(*args, backoff=None, **kwargs) -> FrameSource:
    """``motion_common.video_capture.open_source`` with a camera reopened with backoff
    (``backoff`` defaults to ``motion_sensor.devices.device.Backoff()``)."""
    return video_capture.open_source(*args, backoff=backoff or Backoff(), **kwargs)
