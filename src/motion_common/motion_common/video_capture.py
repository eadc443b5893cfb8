"""Frames from OpenCV, without ROS: a live camera, a video file or a folder of images.

Every source has one call, ``read() -> (Frame, "")`` or ``(None, reason)``; it never raises
for bad input. A frame is a BGR uint8 image (grey and BGRA frames are converted) with its
stamp, a sequence number, a name (file or frame number) and its media time (s since the
start of the stream; a video's own timeline). ``finished`` says when a finite source is
done; ``close()`` releases the device or file (a closed source may be read again).

Stamps: a camera frame is stamped with the clock right after it was grabbed (before it is
decoded); a paced video frame with its due time (its time in the file mapped onto the
clock); a paced image with its due time at ``fps``; anything played as fast as it is read
with the clock when it is delivered.

Pacing (``FramePacer``): a video plays at its own frame rate when ``realtime`` (a frame
that fails to decode keeps its slot), images at ``fps``; a reader that falls more than one
frame period behind is counted late and the schedule restarts from now (no burst to catch
up).

What happened is counted in ``counters`` (a ``collections.Counter``), with the same names
for every source:

- ``frames``: frames delivered;
- ``decode_failures``: a frame (or image file) that could not be decoded, skipped;
- ``bad_frames``: a decoded frame that is no 8-bit image of a usable shape, skipped;
- ``late_frames``: the reader fell more than a frame period behind (paced sources);
- ``loops``: a looped video or folder started again;
- ``open_attempts``, ``open_failed``: attempts to open a camera, and those that failed;
- ``read_failed``: a camera grab that gave no frame;
- ``disconnects``: a camera given up as lost after ``max_failures`` failed grabs in a row.

Sources:

- ``DeviceSource`` (``cv2.VideoCapture(index)``): requests width/height/fps (and a FOURCC
  such as MJPG). A camera that cannot be opened, or is lost, is released; with a
  ``backoff`` (``next()`` and ``reset()``, e.g. ``motion_sensor.devices.device.Backoff``) the next
  attempt waits for its delay inside ``read`` through the injected ``sleep``; without one
  the caller decides when to ``open()`` again (a hand device's runner does).
- ``VideoSource`` (a video FILE): paced or as fast as read, ``loop`` replays it. A frame
  that fails to decode is counted and skipped; the frames tried are counted against the
  file's frame count to tell a bad frame from the end.
- ``ImageFolderSource`` (a folder or a glob such as ``'views/*.png'``): the files in sorted
  order at ``fps`` (0: as fast as read).

A missing or undecodable video file, a video without a frame rate when no fallback is
given and a glob without matches raise ``FrameSourceError`` at construction (a
configuration error the user must fix); everything later is a reason. The clock
(``time.time``), the sleep (``time.sleep``) and the capture factories are injected, so
tests run on a fake clock with fake captures.
"""

import abc
import glob
import math
import os
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = [
    "IMAGE_EXTENSIONS",
    "FrameSourceError",
    "Frame",
    "ReadResult",
    "as_bgr",
    "FramePacer",
    "FrameSource",
    "open_camera",
    "DeviceSource",
    "VideoSource",
    "ImageFolderSource",
    "list_images",
    "open_source",
]

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm", ".pnm", ".webp")
# A video whose frame rate cannot be read (or is absurd) has none.
MAX_PLAUSIBLE_FPS = 1000.0
# Without a frame count, this many undecodable frames in a row are taken as the end.
MAX_CONSECUTIVE_DECODE_FAILURES = 25


class FrameSourceError(Exception):
    """A source that cannot work at all (missing file, nothing matches); the message says
    what to do."""


@dataclass
class Frame:
    stamp: float  # s, on the source's clock (see the module docstring)
    image: np.ndarray  # H x W x 3 uint8, BGR
    index: int  # 0, 1, 2, ... frames delivered by this source
    name: str  # the file, or "frame N" of a device or video
    media_time: float  # s since the start of the stream (a video's own timeline)


ReadResult = tuple[Frame | None, str]


def as_bgr(image) -> tuple[np.ndarray | None, str]:
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


class FramePacer:
    """Releases frames at their time on a stream's timeline, mapped onto the injected clock
    (the first frame released at once); a period <= 0 releases everything at once."""

    def __init__(self, period: float, clock: Callable[[], float], sleep: Callable[[float], object]):
        self.period = period if period > 0 else 0.0
        self.clock, self.sleep = clock, sleep
        self.origin: float | None = None  # clock time of the timeline's zero

    def wait(self, offset: float) -> tuple[float, bool]:
        """Wait until the frame at ``offset`` s on the timeline is due; (its stamp: the due
        time, or now when it is late; whether the reader was more than a period late, in
        which case the timeline restarts from now)."""
        now = self.clock()
        if self.period <= 0:
            return now, False
        if self.origin is None:
            self.origin = now - offset
        due = self.origin + offset
        if now < due:
            self.sleep(due - now)
            return due, False
        if now - due > self.period:
            self.origin += now - due
            return now, True
        return due, False

    def restart(self) -> None:
        self.origin = None


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

    def _frame(self, image: np.ndarray, name: str, media_time: float, stamp: float | None = None) -> Frame:
        frame = Frame(self.clock() if stamp is None else stamp, image, self._delivered, name, media_time)
        self._delivered += 1
        self.counters["frames"] += 1
        return frame

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_camera(
    index: int, width: int = 0, height: int = 0, fps: float = 0.0, fourcc: str = "", factory: Callable | None = None
):
    """``cv2.VideoCapture`` (or ``factory``) of camera ``index`` with the requested mode (0 /
    "": the driver's default). Returns the capture even when it did not open (check
    isOpened)."""
    capture = (factory or cv2.VideoCapture)(index)
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


def _last_line(exc: BaseException) -> str:
    """The last line of an OpenCV error (its message; the lines before are the location)."""
    text = str(exc).strip()
    return text.splitlines()[-1] if text else repr(exc)


class DeviceSource(FrameSource):
    """A live camera. ``max_failures`` failed grabs in a row mean it is lost: it is released
    (and, with a ``backoff``, reopened after the next delay)."""

    def __init__(
        self,
        index: int,
        width: int = 0,
        height: int = 0,
        fps: float = 0.0,
        fourcc: str = "",
        max_failures: int = 5,
        backoff=None,
        clock: Callable[[], float] = time.time,
        sleep: Callable[[float], object] = time.sleep,
        open_capture: Callable = open_camera,
    ):
        super().__init__(clock, sleep)
        if max_failures < 1:
            raise FrameSourceError("max_failures must be at least 1")
        if fourcc and len(fourcc) != 4:
            raise FrameSourceError(f"fourcc {fourcc!r} must have 4 characters (e.g. MJPG, YUYV) or be empty")
        self.index, self.width, self.height, self.fps, self.fourcc = index, width, height, fps, fourcc
        self.max_failures = max_failures
        self.backoff = backoff
        self.open_capture = open_capture
        self.capture = None
        self.retry_at: float | None = None  # when to try to open again
        self.failures_in_row = 0
        self.first_stamp: float | None = None
        self.mode: tuple[int, int, float] = (0, 0, 0.0)  # what the camera actually delivers

    @property
    def connected(self) -> bool:
        """True while the camera is open."""
        return self.capture is not None

    def describe(self) -> str:
        if not (self.width or self.height or self.fps or self.fourcc):
            return f"camera {self.index} (its default mode)"
        fps = f"{self.fps:g}" if self.fps else "default"
        want = f"{self.width or 'default'} x {self.height or 'default'} px @ {fps} fps"
        return f"camera {self.index} (requested {want}{' ' + self.fourcc if self.fourcc else ''})"

    def _schedule_retry(self) -> float | None:
        """With a backoff: the delay before the next attempt to open, now scheduled."""
        if self.backoff is None:
            return None
        delay = self.backoff.next()
        self.retry_at = self.clock() + delay
        return delay

    def open(self) -> str:
        """Open the camera (after waiting for a scheduled retry): "" when it is open, else
        why not."""
        if self.capture is not None:
            return ""
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
            capture, opened, why = None, False, _last_line(exc)
        if not opened:
            if capture is not None:
                capture.release()
            self.counters["open_failed"] += 1
            delay = self._schedule_retry()
            retry = "" if delay is None else f"; retrying in {delay:.2f} s"
            return (
                f"camera {self.index} cannot be opened ({why}){retry} "
                f"(check the cable and /dev/video*, and that no other program uses it)"
            )
        self.capture, self.retry_at, self.failures_in_row = capture, None, 0
        self.mode = (
            int(capture.get(cv2.CAP_PROP_FRAME_WIDTH) or 0),
            int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0),
            float(capture.get(cv2.CAP_PROP_FPS) or 0.0),
        )
        return ""

    def _lost(self, why: str) -> str:
        self.close()
        self.counters["disconnects"] += 1
        delay = self._schedule_retry()
        return f"camera {self.index} lost ({why})" + ("" if delay is None else f"; reopening in {delay:.2f} s")

    def read(self) -> ReadResult:
        if self.capture is None:
            why = self.open()
            if why:
                return None, why
        try:
            grabbed, error = bool(self.capture.grab()), ""
        except cv2.error as exc:
            grabbed, error = False, str(exc).strip()
        stamp = self.clock()  # the frame has just arrived: its grab time
        if not grabbed:
            self.counters["read_failed"] += 1
            self.failures_in_row += 1
            if self.failures_in_row >= self.max_failures:
                reads = "reads in a row" if self.failures_in_row > 1 else "read"
                return None, self._lost(f"{self.failures_in_row} {reads} failed")
            return None, f"camera {self.index}: no frame ({error or 'read failed'}, {self.failures_in_row} in a row)"
        self.failures_in_row = 0
        if self.backoff is not None:
            self.backoff.reset()
        try:
            decoded, image = self.capture.retrieve()
        except cv2.error:
            decoded, image = False, None
        if not decoded or image is None:
            self.counters["decode_failures"] += 1
            return None, f"camera {self.index}: a frame failed to decode (skipped)"
        image, why = as_bgr(image)
        if image is None:
            self.counters["bad_frames"] += 1
            return None, f"camera {self.index}: unusable frame: {why}"
        if self.first_stamp is None:
            self.first_stamp = stamp
        return self._frame(image, f"frame {self._delivered}", stamp - self.first_stamp, stamp), ""

    def close(self) -> None:
        if self.capture is not None:
            self.capture.release()
            self.capture = None


class VideoSource(FrameSource):
    """A video file, at its own frame rate (``realtime``) or as fast as it decodes. A file
    without a plausible frame rate plays at ``fallback_fps``, or is refused when that is
    None."""

    def __init__(
        self,
        path: str,
        loop: bool = False,
        realtime: bool = True,
        fallback_fps: float | None = 30.0,
        clock: Callable[[], float] = time.time,
        sleep: Callable[[float], object] = time.sleep,
        open_capture: Callable[[str], object] = cv2.VideoCapture,
    ):
        super().__init__(clock, sleep)
        self.path, self.loop, self.open_capture = path, loop, open_capture
        if not os.path.isfile(path):
            raise FrameSourceError(
                f"video file {path!r} not found (give the path of a video file, e.g. an .avi or .mp4)"
            )
        self.capture = None
        self._reopen()
        fps = float(self.capture.get(cv2.CAP_PROP_FPS) or 0.0)
        self.fps_from_file = math.isfinite(fps) and 0 < fps <= MAX_PLAUSIBLE_FPS
        if not self.fps_from_file and fallback_fps is None:
            self.close()
            raise FrameSourceError(
                f"video {path!r} has no frame rate: re-encode it with one (e.g. ffmpeg -i IN -r 30 OUT)"
            )
        self.fps = fps if self.fps_from_file else float(fallback_fps)
        count = self.capture.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(count) if count and math.isfinite(count) and count > 0 else 0
        self.pacer = FramePacer(1.0 / self.fps if realtime else 0.0, clock, sleep)
        self.tried = 0  # frames tried in this pass (decoded or not)
        self.failures_in_row = 0
        self.passes = 0
        self.good_this_pass = 0  # a loop over a file without one good frame would spin

    def _reopen(self):
        self.close()
        capture = self.open_capture(self.path)
        if capture is None or not capture.isOpened():
            if capture is not None:
                capture.release()
            raise FrameSourceError(
                f"cannot open video {self.path!r}: not a video OpenCV can decode "
                "(convert it, e.g. ffmpeg -i IN -c:v mjpeg OUT.avi)"
            )
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
            except FrameSourceError as exc:  # the file vanished or changed meanwhile
                self.finished = True
                return None, str(exc)
            return None, f"end of {self.path}: playing it again"
        self.finished = True
        self.close()
        if self.counters["frames"] == 0:
            return None, f"no frame of {self.path} could be decoded"
        return None, f"end of {self.path} ({self.counters['frames']} frames)"

    def _failed(self, position: int) -> ReadResult:
        """A frame that did not decode: counted and skipped, or the end after too many."""
        self.failures_in_row += 1
        if self.failures_in_row >= MAX_CONSECUTIVE_DECODE_FAILURES:
            return self._end()
        self.counters["decode_failures"] += 1
        return None, f"{self.path}: frame {position} failed to decode (skipped)"

    def read(self) -> ReadResult:
        if self.finished:
            return None, f"end of {self.path}"
        if self.capture is None:
            try:
                self._reopen()
            except FrameSourceError as exc:
                self.finished = True
                return None, str(exc)
        position = self.tried
        try:
            grabbed = bool(self.capture.grab())
        except cv2.error:
            grabbed = False
        if not grabbed and self.frame_count and position >= self.frame_count:
            return self._end()
        self.tried += 1
        if not grabbed:
            return self._failed(position)
        try:
            decoded, image = self.capture.retrieve()
        except cv2.error:
            decoded, image = False, None
        if not decoded or image is None:
            return self._failed(position)
        self.failures_in_row = 0
        image, why = as_bgr(image)
        if image is None:
            self.counters["bad_frames"] += 1
            return None, f"{self.path}: frame {position} unusable: {why}"
        media_time = (self.passes * max(self.frame_count, 1) + position) / self.fps
        stamp, late = self.pacer.wait(media_time)
        if late:
            self.counters["late_frames"] += 1
        self.good_this_pass += 1
        return self._frame(image, f"frame {position}", media_time, stamp), ""

    def close(self) -> None:
        if self.capture is not None:
            self.capture.release()
            self.capture = None


def list_images(pattern: str) -> list[str]:
    """The image files of a folder (by extension) or matching a glob, sorted."""
    if os.path.isdir(pattern):
        names = [os.path.join(pattern, n) for n in os.listdir(pattern) if n.lower().endswith(IMAGE_EXTENSIONS)]
    else:
        names = [n for n in glob.glob(os.path.expanduser(pattern), recursive=True) if os.path.isfile(n)]
    return sorted(names)


class ImageFolderSource(FrameSource):
    """The images of a folder or glob, in sorted order, at ``fps`` (0: as fast as read)."""

    def __init__(
        self,
        pattern: str,
        fps: float = 0.0,
        loop: bool = False,
        clock: Callable[[], float] = time.time,
        sleep: Callable[[float], object] = time.sleep,
    ):
        super().__init__(clock, sleep)
        self.pattern, self.fps, self.loop = pattern, fps, loop
        self.files = list_images(pattern)
        if not self.files:
            raise FrameSourceError(
                f"no images match {pattern!r} (give a folder, or a quoted glob such as "
                f"'views/*.png'; image types: {', '.join(IMAGE_EXTENSIONS)})"
            )
        self.position = 0
        self.good_this_pass = 0
        self.pacer = FramePacer(1.0 / fps if fps > 0 else 0.0, clock, sleep)

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
            self.counters["decode_failures"] += 1
            return None, f"{path}: not an image OpenCV can decode (skipped)"
        # An image's slot is one period after the previous good one: a file that does not
        # decode leaves no gap.
        stamp, late = self.pacer.wait(self._delivered / self.fps if self.fps > 0 else 0.0)
        if late:
            self.counters["late_frames"] += 1
        self.good_this_pass += 1
        media_time = index / self.fps if self.fps > 0 else float(index)
        return self._frame(image, path, media_time, stamp), ""


def open_source(
    device: int | None = None,
    video: str = "",
    images: str = "",
    width: int = 0,
    height: int = 0,
    fps: float = 0.0,
    loop: bool = False,
    realtime: bool = True,
    fourcc: str = "",
    max_failures: int = 5,
    backoff=None,
    clock: Callable[[], float] = time.time,
    sleep: Callable[[float], object] = time.sleep,
) -> FrameSource:
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
