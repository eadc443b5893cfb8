"""Camera frames from OpenCV, without ROS: a live device, a video file or a folder of images.

Every source has one call, ``read() -> (Frame, "")`` or ``(None, reason)``; it never raises
for bad input. A frame is a BGR uint8 image (grey and BGRA frames are converted) with its
stamp (the injected clock's time when it was delivered), a sequence number, a name (file or
frame number) and its media time (s since the start of the stream; a video's own timeline).
What went wrong is counted in ``counters`` (a ``collections.Counter``) and ``finished`` says
when a finite source is done.

- ``DeviceSource`` (``cv2.VideoCapture(index)``): requests width/height/fps (and a FOURCC
  such as MJPG); a read that fails is counted, and ``max_failures`` failures in a row mean
  the camera is gone: it is released and reopened with exponential backoff
  (``motion_sensor.device.Backoff``), as is a camera that cannot be opened at all. The
  backoff waits happen inside ``read`` through the injected ``sleep``.
- ``VideoSource`` (a video FILE): played at the file's own frame rate when ``realtime``
  (paced with the injected clock/sleep; a reader that falls behind is counted as ``late``
  and does not try to catch up), as fast as it is read otherwise; ``loop`` replays it. A
  frame that fails to decode is counted and skipped (OpenCV does not advance past it, so
  the frames tried are counted against the file's frame count to tell it from the end).
- ``ImageFolderSource`` (a folder or a glob such as ``'views/*.png'``): the files in sorted
  order at ``fps`` (0: as fast as read); a file OpenCV cannot decode is counted and skipped.

A missing or undecodable video file and a glob without matches raise ``FrameSourceError``
at construction (a configuration error the user must fix); everything later is a reason.
The clock (``time.time``) and sleep (``time.sleep``) are injected so tests run on a fake
clock without sleeping; a node passes a sleep that wakes up on shutdown.
"""
import abc
import glob
import math
import os
import time
from collections import Counter
from dataclasses import dataclass
from typing import Callable, List, Optional, Tuple

import cv2
import numpy as np

from motion_sensor.device import Backoff

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm", ".pnm", ".webp")
# A video whose frame rate cannot be read (or is absurd) plays at the fallback rate.
MAX_PLAUSIBLE_FPS = 1000.0
# Without a frame count, this many undecodable frames in a row are taken as the end.
MAX_CONSECUTIVE_DECODE_FAILURES = 25


class FrameSourceError(Exception):
    """A source that cannot work at all (missing file, nothing matches); the message says
    what to do."""


@dataclass
class Frame:
    stamp: float            # s, the clock's time when the frame was delivered
    image: np.ndarray       # H x W x 3 uint8, BGR
    index: int              # 0, 1, 2, ... frames delivered by this source
    name: str               # the file, or "frame N" of a device or video
    media_time: float       # s since the start of the stream (a video's own timeline)


ReadResult = Tuple[Optional[Frame], str]


def as_bgr(image) -> Tuple[Optional[np.ndarray], str]:
    """(H x W x 3 uint8 BGR image, "") from what a capture returned, or (None, reason)."""
    if image is None:
        return None, "no image data"
    image = np.asarray(image)
    if image.size == 0:
        return None, "empty image"
    if image.dtype != np.uint8:
        return None, f"pixel type {image.dtype} (expected 8-bit)"
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR), ""
    if image.ndim == 3 and image.shape[2] == 3:
        return image, ""
    if image.ndim == 3 and image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2BGR), ""
    if image.ndim == 3 and image.shape[2] == 1:
        return cv2.cvtColor(image[:, :, 0], cv2.COLOR_GRAY2BGR), ""
    return None, f"image of shape {image.shape} (expected H x W, H x W x 3 or H x W x 4)"


class _Pacer:
    """Releases frames ``1/fps`` s apart on the injected clock (fps <= 0: no pacing)."""

    def __init__(self, fps: float, clock: Callable[[], float], sleep: Callable[[float], object]):
        self.period = 1.0 / fps if fps > 0 else 0.0
        self.clock, self.sleep = clock, sleep
        self.due: Optional[float] = None

    def wait(self) -> bool:
        """Wait until the next frame is due; False when the reader is more than a frame late
        (the schedule restarts from now: no burst to catch up)."""
        if self.period <= 0:
            return True
        now = self.clock()
        if self.due is None:
            self.due = now
        on_time = True
        if now < self.due:
            self.sleep(self.due - now)
        elif now - self.due > self.period:
            self.due, on_time = now, False
        self.due += self.period
        return on_time

    def restart(self):
        self.due = None


class FrameSource(abc.ABC):
    """One of the sources above: ``read()``, ``finished``, ``counters``, ``close()``."""

    def __init__(self, clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep):
        self.clock, self.sleep = clock, sleep
        self.counters: Counter = Counter()
        self.finished = False
        self._delivered = 0

    @abc.abstractmethod
    def read(self) -> ReadResult:
        """The next frame, or (None, why there is none now)."""

    @abc.abstractmethod
    def describe(self) -> str:
        """One line for logs: what the source reads and at what rate."""

    def close(self) -> None:
        """Release the device or file (a closed source may be read again: it reopens)."""

    def _frame(self, image: np.ndarray, name: str, media_time: float, stamp: Optional[float] = None) -> Frame:
        frame = Frame(self.clock() if stamp is None else stamp, image, self._delivered, name, media_time)
        self._delivered += 1
        self.counters["frames"] += 1
        return frame

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_camera(index: int, width: int = 0, height: int = 0, fps: float = 0.0, fourcc: str = ""):
    """``cv2.VideoCapture`` of camera ``index`` with the requested mode (0 / "": the
    driver's default). Returns the capture even when it did not open (check isOpened)."""
    capture = cv2.VideoCapture(index)
    if capture.isOpened():
        if fourcc:
            capture.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter_fourcc(*fourcc))
        if width:
            capture.set(cv2.CAP_PROP_FRAME_WIDTH, width)
        if height:
            capture.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
        if fps:
            capture.set(cv2.CAP_PROP_FPS, fps)
    return capture


class DeviceSource(FrameSource):
    """A live camera; reopened with backoff when it cannot be opened or stops delivering."""

    def __init__(self, index: int, width: int = 0, height: int = 0, fps: float = 0.0, fourcc: str = "",
                 max_failures: int = 5, backoff: Optional[Backoff] = None,
                 clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep,
                 open_capture: Callable = open_camera):
        super().__init__(clock, sleep)
        if max_failures < 1:
            raise FrameSourceError("max_failures must be at least 1")
        if fourcc and len(fourcc) != 4:
            raise FrameSourceError(f"fourcc {fourcc!r} must have 4 characters (e.g. MJPG, YUYV) or be empty")
        self.index, self.width, self.height, self.fps, self.fourcc = index, width, height, fps, fourcc
        self.max_failures = max_failures
        self.backoff = backoff or Backoff()
        self.open_capture = open_capture
        self.capture = None
        self.retry_at: Optional[float] = None      # when to try to open again
        self.failures_in_row = 0
        self.first_stamp: Optional[float] = None
        self.mode: Tuple[int, int, float] = (0, 0, 0.0)   # what the camera actually delivers

    def describe(self) -> str:
        if not (self.width or self.height or self.fps or self.fourcc):
            return f"camera {self.index} (its default mode)"
        want = f"{self.width or 'default'} x {self.height or 'default'} px @ {f'{self.fps:g}' if self.fps else 'default'} fps"
        return f"camera {self.index} (requested {want}{' ' + self.fourcc if self.fourcc else ''})"

    def _schedule_retry(self) -> float:
        delay = self.backoff.next()
        self.retry_at = self.clock() + delay
        return delay

    def _open(self) -> str:
        """"" when the camera is open, else why not (a retry is scheduled)."""
        if self.retry_at is not None:
            wait = self.retry_at - self.clock()
            if wait > 0:
                self.sleep(wait)
        self.counters["open_attempts"] += 1
        try:
            capture = self.open_capture(self.index, self.width, self.height, self.fps, self.fourcc)
            opened = capture is not None and capture.isOpened()
            why = "" if opened else "no such device, or it is busy"
        except (cv2.error, OSError) as exc:
            capture, opened, why = None, False, str(exc).strip().splitlines()[-1] if str(exc).strip() else repr(exc)
        if not opened:
            if capture is not None:
                capture.release()
            self.counters["open_failed"] += 1
            delay = self._schedule_retry()
            return (f"camera {self.index} cannot be opened ({why}); retrying in {delay:.2f} s "
                    f"(check the cable and /dev/video*, and that no other program uses it)")
        self.capture, self.retry_at, self.failures_in_row = capture, None, 0
        self.mode = (int(capture.get(cv2.CAP_PROP_FRAME_WIDTH) or 0), int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0),
                     float(capture.get(cv2.CAP_PROP_FPS) or 0.0))
        return ""

    def _lost(self, why: str) -> str:
        self.close()
        self.counters["disconnects"] += 1
        delay = self._schedule_retry()
        return f"camera {self.index} lost ({why}); reopening in {delay:.2f} s"

    def read(self) -> ReadResult:
        if self.capture is None:
            why = self._open()
            if why:
                return None, why
        try:
            ok, image = self.capture.read()
            error = ""
        except cv2.error as exc:
            ok, image, error = False, None, str(exc).strip()
        stamp = self.clock()
        if not ok or image is None:
            self.counters["read_failed"] += 1
            self.failures_in_row += 1
            if self.failures_in_row >= self.max_failures:
                return None, self._lost(f"{self.failures_in_row} reads in a row failed")
            return None, f"camera {self.index}: no frame ({error or 'read failed'}, {self.failures_in_row} in a row)"
        image, why = as_bgr(image)
        if image is None:
            self.counters["bad_frames"] += 1
            return None, f"camera {self.index}: unusable frame: {why}"
        self.failures_in_row = 0
        self.backoff.reset()
        if self.first_stamp is None:
            self.first_stamp = stamp
        return self._frame(image, f"frame {self._delivered}", stamp - self.first_stamp, stamp), ""

    def close(self) -> None:
        if self.capture is not None:
            self.capture.release()
            self.capture = None


class VideoSource(FrameSource):
    """A video file, at its own frame rate (``realtime``) or as fast as it decodes."""

    def __init__(self, path: str, loop: bool = False, realtime: bool = True, fallback_fps: float = 30.0,
                 clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep,
                 open_capture: Callable[[str], object] = cv2.VideoCapture):
        super().__init__(clock, sleep)
        self.path, self.loop, self.open_capture = path, loop, open_capture
        if not os.path.isfile(path):
            raise FrameSourceError(f"video file {path!r} not found (give the path of a video file, "
                                   "e.g. an .avi or .mp4)")
        self.capture = None
        self._reopen()
        fps = float(self.capture.get(cv2.CAP_PROP_FPS) or 0.0)
        self.fps_from_file = math.isfinite(fps) and 0 < fps <= MAX_PLAUSIBLE_FPS
        self.fps = fps if self.fps_from_file else float(fallback_fps)
        count = self.capture.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(count) if count and math.isfinite(count) and count > 0 else 0
        self.pacer = _Pacer(self.fps if realtime else 0.0, clock, sleep)
        self.tried = 0              # frames tried in this pass (decoded or not)
        self.failures_in_row = 0
        self.passes = 0
        self.good_this_pass = 0     # a loop over a file without one good frame would spin

    def _reopen(self):
        self.close()
        capture = self.open_capture(self.path)
        if capture is None or not capture.isOpened():
            if capture is not None:
                capture.release()
            raise FrameSourceError(f"cannot open video {self.path!r}: not a video OpenCV can decode "
                                   "(convert it, e.g. ffmpeg -i IN -c:v mjpeg OUT.avi)")
        self.capture = capture

    def describe(self) -> str:
        rate = f"{self.fps:g} fps" + ("" if self.fps_from_file else " (the file gives no frame rate)")
        count = f"{self.frame_count} frames" if self.frame_count else "unknown length"
        return f"video {self.path} ({count}, {rate}{', looped' if self.loop else ''})"

    def _end(self) -> ReadResult:
        if self.loop and self.good_this_pass > 0:
            self.passes += 1
            self.counters["loops"] += 1
            self.good_this_pass = 0
            self.tried = self.failures_in_row = 0
            try:
                self._reopen()
            except FrameSourceError as exc:      # the file vanished or changed meanwhile
                self.finished = True
                return None, str(exc)
            return None, f"end of {self.path}: playing it again"
        self.finished = True
        self.close()
        if self.counters["frames"] == 0:
            return None, f"no frame of {self.path} could be decoded"
        return None, f"end of {self.path} ({self.counters['frames']} frames)"

    def read(self) -> ReadResult:
        if self.finished:
            return None, f"end of {self.path}"
        if self.capture is None:
            try:
                self._reopen()
            except FrameSourceError as exc:
                self.finished = True
                return None, str(exc)
        try:
            ok, image = self.capture.read()
        except cv2.error:
            ok, image = False, None
        if not ok or image is None:
            if self.frame_count and self.tried >= self.frame_count:
                return self._end()
            self.failures_in_row += 1
            if self.failures_in_row >= MAX_CONSECUTIVE_DECODE_FAILURES:
                return self._end()
            self.tried += 1
            self.counters["decode_failed"] += 1
            return None, f"{self.path}: frame {self.tried - 1} failed to decode (skipped)"
        image, why = as_bgr(image)
        position = self.tried
        self.tried += 1
        self.failures_in_row = 0
        if image is None:
            self.counters["bad_frames"] += 1
            return None, f"{self.path}: frame {position} unusable: {why}"
        if not self.pacer.wait():
            self.counters["late"] += 1
        self.good_this_pass += 1
        media_time = (self.passes * max(self.frame_count, 1) + position) / self.fps
        return self._frame(image, f"frame {position}", media_time), ""

    def close(self) -> None:
        if self.capture is not None:
            self.capture.release()
            self.capture = None


def list_images(pattern: str) -> List[str]:
    """The image files of a folder (by extension) or matching a glob, sorted."""
    if os.path.isdir(pattern):
        names = [os.path.join(pattern, n) for n in os.listdir(pattern) if n.lower().endswith(IMAGE_EXTENSIONS)]
    else:
        names = [n for n in glob.glob(os.path.expanduser(pattern), recursive=True) if os.path.isfile(n)]
    return sorted(names)


class ImageFolderSource(FrameSource):
    """The images of a folder or glob, in sorted order, at ``fps`` (0: as fast as read)."""

    def __init__(self, pattern: str, fps: float = 0.0, loop: bool = False,
                 clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep):
        super().__init__(clock, sleep)
        self.pattern, self.fps, self.loop = pattern, fps, loop
        self.files = list_images(pattern)
        if not self.files:
            raise FrameSourceError(f"no images match {pattern!r} (give a folder, or a quoted glob such as "
                                   f"'views/*.png'; image types: {', '.join(IMAGE_EXTENSIONS)})")
        self.position = 0
        self.good_this_pass = 0
        self.pacer = _Pacer(fps, clock, sleep)

    def describe(self) -> str:
        rate = f"{self.fps:g} fps" if self.fps > 0 else "as fast as read"
        return f"{len(self.files)} images from {self.pattern} ({rate}{', looped' if self.loop else ''})"

    def read(self) -> ReadResult:
        if self.position >= len(self.files):
            if not self.loop or self.good_this_pass == 0:
                self.finished = True
                if self.counters["frames"] == 0:
                    return None, f"none of the {len(self.files)} files of {self.pattern} is a decodable image"
                return None, f"end of images ({self.counters['frames']} frames)"
            self.position, self.good_this_pass = 0, 0
            self.counters["loops"] += 1
        path = self.files[self.position]
        index = self.position
        self.position += 1
        image = cv2.imread(path, cv2.IMREAD_COLOR)
        if image is None:
            self.counters["decode_failed"] += 1
            return None, f"{path}: not an image OpenCV can decode (skipped)"
        if not self.pacer.wait():
            self.counters["late"] += 1
        self.good_this_pass += 1
        media_time = index / self.fps if self.fps > 0 else float(index)
        return self._frame(image, path, media_time), ""


def open_source(device: Optional[int] = None, video: str = "", images: str = "", width: int = 0, height: int = 0,
                fps: float = 0.0, loop: bool = False, realtime: bool = True, fourcc: str = "",
                max_failures: int = 5, backoff: Optional[Backoff] = None,
                clock: Callable[[], float] = time.time, sleep: Callable[[float], object] = time.sleep) -> FrameSource:
    """The source for a node's or a tool's options: a video file or images when given (not
    both), else the camera ``device``. A video plays at its own rate (``fps`` only when the
    file has none); images play at ``fps`` (when ``realtime``)."""
    if video and images:
        raise FrameSourceError(f"give a video ({video!r}) or images ({images!r}), not both")
    if video:
        return VideoSource(video, loop, realtime, fps or 30.0, clock, sleep)
    if images:
        return ImageFolderSource(images, fps if realtime else 0.0, loop, clock, sleep)
    if device is None:
        raise FrameSourceError("no source: give a camera device index, a video file or images")
    return DeviceSource(device, width, height, fps, fourcc, max_failures, backoff, clock, sleep)
