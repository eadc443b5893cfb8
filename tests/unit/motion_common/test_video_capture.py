"""motion_common.video_capture: the one OpenCV capture (camera, video file, image folder) of
kitting's camera driver and the webcam hand device, on a fake clock with fake captures.
The kitting tests play real files and the webcam tests run it inside the hand device."""

import cv2
import numpy as np
import pytest

from motion_common.video_capture import DeviceSource, FramePacer, FrameSourceError, VideoSource

# Every counter a source may use (the module docstring's list).
COUNTERS = {
    "frames",
    "decode_failures",
    "bad_frames",
    "late_frames",
    "loops",
    "open_attempts",
    "open_failed",
    "read_failed",
    "disconnects",
}


class FakeClock:
    def __init__(self, start=10.0):
        self.now = start
        self.sleeps = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(round(seconds, 6))
        self.now += seconds


class FakeCapture:
    """cv2.VideoCapture stand-in: ``frames`` (None: grabbed but fails to decode; False: the
    grab fails), ``fps`` and frame count as a file reports them."""

    def __init__(self, frames, fps=20.0, count=None, opened=True):
        self.frames, self.fps, self.opened = list(frames), fps, opened
        self.count = len(self.frames) if count is None else count
        self.position, self.current, self.released = 0, None, False

    def isOpened(self):
        return self.opened

    def get(self, prop):
        return {cv2.CAP_PROP_FPS: self.fps, cv2.CAP_PROP_FRAME_COUNT: self.count}.get(prop, 0.0)

    def set(self, prop, value):
        return True

    def grab(self):
        if self.position >= len(self.frames) or self.frames[self.position] is False:
            self.position += 1
            return False
        self.current = self.frames[self.position]
        self.position += 1
        return True

    def retrieve(self):
        return self.current is not None, self.current

    def release(self):
        self.released = True


def image(level=100):
    return np.full((8, 8, 3), level, np.uint8)


def video(tmp_path, capture, **kw):
    path = tmp_path / "clip.avi"
    path.write_bytes(b"the capture is a fake")
    clock = FakeClock()
    return VideoSource(str(path), clock=clock, sleep=clock.sleep, open_capture=lambda _: capture, **kw), clock


def read_all(source, limit=50):
    frames, reasons = [], []
    for _ in range(limit):
        frame, why = source.read()
        (frames if frame is not None else reasons).append(frame if frame is not None else why)
        if source.finished:
            break
    return frames, reasons


def test_pacer_keeps_the_timeline_and_restarts_it_when_late():
    clock = FakeClock()
    pacer = FramePacer(0.1, clock, clock.sleep)
    assert pacer.wait(0.0) == (10.0, False)
    assert pacer.wait(0.2) == (pytest.approx(10.2), False) and clock.now == pytest.approx(10.2)
    clock.now += 0.05  # late by less than a period: stamped on time
    assert pacer.wait(0.3) == (pytest.approx(10.3), False)
    clock.now = 11.0  # a stall
    assert pacer.wait(0.4) == (11.0, True)
    assert pacer.wait(0.5) == (pytest.approx(11.1), False)  # the timeline restarted from the stall
    assert FramePacer(0.0, clock, clock.sleep).wait(5.0) == (clock.now, False)


def test_a_video_frame_that_fails_to_decode_keeps_its_slot(tmp_path):
    capture = FakeCapture([image(0), None, image(2), False, image(4)])
    source, clock = video(tmp_path, capture)
    frames, reasons = read_all(source)
    assert [f.name for f in frames] == ["frame 0", "frame 2", "frame 4"]
    np.testing.assert_allclose([f.stamp for f in frames], 10.0 + np.array([0, 2, 4]) / 20.0)
    assert [f.media_time for f in frames] == pytest.approx([0.0, 0.1, 0.2])
    assert reasons[:2] == [
        f"{source.path}: frame 1 failed to decode (skipped)",
        f"{source.path}: frame 3 failed to decode (skipped)",
    ]
    assert source.finished and capture.released
    assert dict(source.counters) == {"frames": 3, "decode_failures": 2}


def test_a_video_without_a_frame_rate_plays_at_the_fallback_or_is_refused(tmp_path):
    source, _ = video(tmp_path, FakeCapture([image()], fps=0.0), realtime=False)
    assert source.fps == 30.0 and not source.fps_from_file
    with pytest.raises(FrameSourceError, match="no frame rate"):
        video(tmp_path, FakeCapture([image()], fps=0.0), fallback_fps=None)


def test_camera_without_backoff_reports_lost_and_opens_again_when_asked():
    sessions = [FakeCapture([image(), np.zeros((8, 8, 3), np.float32), None, False, False]), FakeCapture([image()])]
    clock = FakeClock()
    source = DeviceSource(1, max_failures=2, clock=clock, sleep=clock.sleep, open_capture=lambda *mode: sessions.pop(0))
    assert source.open() == "" and source.connected
    first, _ = source.read()
    assert first.stamp == 10.0 and first.image.shape == (8, 8, 3)
    assert "unusable frame" in source.read()[1]
    assert "failed to decode" in source.read()[1]
    assert "1 in a row" in source.read()[1]
    frame, why = source.read()
    assert frame is None and why == "camera 1 lost (2 reads in a row failed)" and not source.connected
    assert source.open() == "" and source.read()[0].index == 1
    assert clock.sleeps == []  # no backoff: the caller decides when
    assert dict(source.counters) == {
        "open_attempts": 2,
        "frames": 2,
        "bad_frames": 1,
        "decode_failures": 1,
        "read_failed": 2,
        "disconnects": 1,
    }
    assert set(source.counters) <= COUNTERS


def test_a_camera_that_cannot_be_opened_says_so():
    clock = FakeClock()
    source = DeviceSource(3, clock=clock, sleep=clock.sleep, open_capture=lambda *mode: FakeCapture([], opened=False))
    frame, why = source.read()
    assert frame is None and why.startswith("camera 3 cannot be opened (no such device, or it is busy)")
    assert dict(source.counters) == {"open_attempts": 1, "open_failed": 1}
