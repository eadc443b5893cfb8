"""Camera input of the kitting cell: frame sources (video file, image folder, a live camera
that fails and comes back, on a fake clock), numpy <-> sensor_msgs conversions, the
intrinsics file, live view selection and the calibrate_camera / camera_driver commands."""

import os
import subprocess
import sys

import cv2
import numpy as np
import pybullet as p
import pytest
from sensor_msgs.msg import CameraInfo, Image

from kitting.calibration import BoardSpec, Intrinsics, write_intrinsics_yaml
from kitting.calibration_views import ViewCollector
from kitting.camera import PinholeCamera
from kitting.frame_source import DeviceSource, FrameSourceError, ImageFolderSource, VideoSource, open_source
from kitting.image_msgs import (
    array_to_image,
    bgr_to_image,
    camera_info_from_intrinsics,
    image_to_bgr,
    intrinsics_from_camera_info,
)
from kitting.intrinsics_file import IntrinsicsFileError, load_camera_info_yaml, resolve_camera_info_url
from kitting.sim_scene import render_board_views
from motion_sensor.devices.device import Backoff

from ..conftest import ROOT

NODES = os.path.join(ROOT, "src", "kitting", "nodes")
PYTHON = os.path.join(ROOT, ".venv", "bin", "python")
if not os.path.exists(PYTHON):  # pragma: no cover - outside the project's venv
    PYTHON = sys.executable
TRUE_F = 600.0
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


class FakeClock:
    """Time that moves only when the code under test sleeps (or the test advances it)."""

    def __init__(self, start=1000.0):
        self.now = start
        self.sleeps = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(round(seconds, 6))
        self.now += seconds


def level_frames(count, size=(64, 48)):
    """Frames of flat grey levels 0, 20, 40, ... (MJPG keeps a flat level within a few)."""
    return [np.full((size[1], size[0], 3), 20 * i, np.uint8) for i in range(count)]


def write_video(path, frames, fps=10.0):
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (width, height))
    assert writer.isOpened(), "OpenCV cannot write MJPG .avi here"
    for frame in frames:
        writer.write(frame)
    writer.release()
    return str(path)


def corrupt_jpeg(path, which):
    """Overwrite the start of the ``which``-th JPEG in an MJPG file (the frame cannot decode)."""
    data = bytearray(open(path, "rb").read())
    starts = [i for i in range(len(data) - 1) if data[i] == 0xFF and data[i + 1] == 0xD8]
    data[starts[which] + 2 : starts[which] + 200] = bytes(198)
    open(path, "wb").write(bytes(data))


def read_all(source, limit=100):
    frames, reasons = [], []
    for _ in range(limit):
        frame, why = source.read()
        if frame is not None:
            frames.append(frame)
        else:
            reasons.append(why)
        if source.finished:
            break
    return frames, reasons


# -- video files ----------------------------------------------------------------------------
def test_video_plays_at_its_own_fps_then_ends(tmp_path):
    path = write_video(tmp_path / "levels.avi", level_frames(10), fps=10.0)
    clock = FakeClock()
    source = VideoSource(path, clock=clock, sleep=clock.sleep)
    assert source.fps == 10.0 and source.frame_count == 10
    frames, reasons = read_all(source)
    assert [round(float(f.image.mean()) / 20) for f in frames] == list(range(10))
    assert all(f.image.shape == (48, 64, 3) and f.image.dtype == np.uint8 for f in frames)
    assert np.allclose(np.diff([f.stamp for f in frames]), 0.1)
    assert [f.media_time for f in frames] == pytest.approx([i / 10 for i in range(10)])
    assert source.finished and reasons == [f"end of {path} (10 frames)"]
    assert source.read() == (None, f"end of {path}")
    assert source.counters["frames"] == 10 and source.counters["late_frames"] == 0


def test_video_loop_replays_and_a_slow_reader_is_counted_late(tmp_path):
    path = write_video(tmp_path / "levels.avi", level_frames(4), fps=10.0)
    clock = FakeClock()
    source = VideoSource(path, loop=True, clock=clock, sleep=clock.sleep)
    levels, notes = [], []
    for _ in range(10):
        frame, why = source.read()
        if frame is None:
            notes.append(why)
            continue
        levels.append(round(float(frame.image.mean()) / 20))
        clock.now += 0.35 if len(levels) == 2 else 0.0  # the reader stalls once
    assert levels == [0, 1, 2, 3, 0, 1, 2, 3]
    assert notes == [f"end of {path}: playing it again"] * 2
    assert not source.finished and source.counters["loops"] == 2 and source.counters["late_frames"] == 1


def test_corrupt_video_frame_is_skipped_with_a_reason(tmp_path):
    path = write_video(tmp_path / "levels.avi", level_frames(10), fps=10.0)
    corrupt_jpeg(path, 4)
    source = VideoSource(path, realtime=False)
    frames, reasons = read_all(source)
    assert [round(float(f.image.mean()) / 20) for f in frames] == [0, 1, 2, 3, 5, 6, 7, 8, 9]
    assert reasons == [f"{path}: frame 4 failed to decode (skipped)", f"end of {path} (9 frames)"]
    assert source.counters["decode_failures"] == 1


def test_unreadable_or_missing_video_is_refused(tmp_path):
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"not a video at all " * 50)
    with pytest.raises(FrameSourceError, match="not a video OpenCV can decode"):
        VideoSource(str(junk))
    with pytest.raises(FrameSourceError, match="not found"):
        VideoSource(str(tmp_path / "missing.avi"))
    with pytest.raises(FrameSourceError, match="not both"):
        open_source(video=str(junk), images=str(tmp_path))


# -- image folders --------------------------------------------------------------------------
def test_image_folder_in_order_with_undecodable_files_skipped(tmp_path):
    frames = level_frames(3)
    for i, frame in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"view_{i}.png"), frame)
    cv2.imwrite(str(tmp_path / "view_3.png"), np.full((48, 64), 200, np.uint8))  # grey
    (tmp_path / "view_1b.png").write_bytes(b"\x89PNG truncated")
    (tmp_path / "notes.txt").write_text("not an image")
    clock = FakeClock()
    source = ImageFolderSource(str(tmp_path), fps=5.0, clock=clock, sleep=clock.sleep)
    got, reasons = read_all(source)
    assert [os.path.basename(f.name) for f in got] == ["view_0.png", "view_1.png", "view_2.png", "view_3.png"]
    assert got[3].image.shape == (48, 64, 3) and int(got[3].image[0, 0, 2]) == 200
    assert np.allclose(np.diff([f.stamp for f in got]), 0.2)
    assert reasons == [
        f"{tmp_path / 'view_1b.png'}: not an image OpenCV can decode (skipped)",
        "end of images (4 frames)",
    ]
    assert source.counters["decode_failures"] == 1
    by_glob = ImageFolderSource(str(tmp_path / "view_?.png"))
    assert len(by_glob.files) == 4
    with pytest.raises(FrameSourceError, match="no images match"):
        ImageFolderSource(str(tmp_path / "*.jpg"))


def test_looping_a_folder_without_one_good_image_ends(tmp_path):
    (tmp_path / "a.png").write_bytes(b"garbage")
    source = ImageFolderSource(str(tmp_path), loop=True)
    _, reasons = read_all(source)
    assert source.finished and "none of the 1 files" in reasons[-1]


# -- a live camera that fails and comes back ------------------------------------------------
class FakeCapture:
    def __init__(self, script):
        self.script = list(script)  # per grab: an image, None (the grab fails) or an exception
        self.released = False
        self.grabbed = None

    def isOpened(self):
        return True

    def get(self, prop):
        return {cv2.CAP_PROP_FRAME_WIDTH: 64, cv2.CAP_PROP_FRAME_HEIGHT: 48, cv2.CAP_PROP_FPS: 30}.get(prop, 0)

    def grab(self):
        item = self.script.pop(0) if self.script else None
        if isinstance(item, Exception):
            raise item
        self.grabbed = item
        return item is not None

    def retrieve(self):
        return (self.grabbed is not None), self.grabbed

    def release(self):
        self.released = True


class ClosedCapture(FakeCapture):
    def isOpened(self):
        return False


def test_lost_camera_is_reopened_with_backoff_on_an_injected_clock():
    good = np.zeros((48, 64, 3), np.uint8)
    sessions = [
        ClosedCapture([]),
        ClosedCapture([]),
        FakeCapture([good, good.astype(np.float32), None, cv2.error("select() timeout"), None]),
        FakeCapture([good]),
    ]
    opened = []

    def open_capture(index, width, height, fps, fourcc):
        opened.append((index, width, height, fps, fourcc))
        return sessions.pop(0)

    clock = FakeClock()
    source = DeviceSource(
        2,
        640,
        480,
        30.0,
        "MJPG",
        max_failures=3,
        backoff=Backoff(0.25, 2.0, 5.0),
        clock=clock,
        sleep=clock.sleep,
        open_capture=open_capture,
    )
    results = [source.read() for _ in range(8)]
    reasons = [why for frame, why in results]
    assert results[0][0] is None and "camera 2 cannot be opened" in reasons[0] and "retrying in 0.25 s" in reasons[0]
    assert "retrying in 0.50 s" in reasons[1]
    assert results[2][0] is not None and results[2][0].image.shape == (48, 64, 3)
    assert "unusable frame: pixel type float32" in reasons[3]
    assert "read failed, 1 in a row" in reasons[4] and "select() timeout" in reasons[5]
    assert "camera 2 lost (3 reads in a row failed); reopening in 0.25 s" == reasons[6]  # backoff reset by a frame
    assert results[7][0] is not None and results[7][0].index == 1
    assert clock.sleeps == [0.25, 0.5, 0.25]
    assert opened[0] == (2, 640, 480, 30.0, "MJPG") and len(opened) == 4
    assert dict(source.counters) == {
        "open_attempts": 4,
        "open_failed": 2,
        "frames": 2,
        "bad_frames": 1,
        "read_failed": 3,
        "disconnects": 1,
    }
    assert source.mode == (64, 48, 30.0)


def test_device_open_raising_is_a_reason_not_a_crash():
    def broken(*_):
        raise cv2.error("VIDEOIO: can't open camera by index")

    clock = FakeClock()
    source = DeviceSource(0, clock=clock, sleep=clock.sleep, open_capture=broken)
    frame, why = source.read()
    assert frame is None and "can't open camera by index" in why and not source.finished


# -- numpy <-> sensor_msgs ------------------------------------------------------------------
def test_image_round_trip_through_the_wire(rng):
    bgr = rng.integers(0, 256, (6, 5, 3), dtype=np.uint8)
    msg = bgr_to_image(bgr, 12.5, "cam")
    assert (msg.encoding, msg.step, msg.width, msg.height, msg.header.frame_id) == ("bgr8", 15, 5, 6, "cam")
    assert msg.header.stamp.to_sec() == 12.5
    from io import BytesIO

    buffer = BytesIO()
    msg.serialize(buffer)
    received = Image()
    received.deserialize(buffer.getvalue())
    back, why = image_to_bgr(received)
    assert why == "" and np.array_equal(back, bgr)
    back[0, 0] = 0  # a writable copy
    rgb, _ = image_to_bgr(array_to_image(bgr[:, :, ::-1], None, "cam", "rgb8"))
    assert np.array_equal(rgb, bgr)
    grey = bgr[:, :, 0].copy()
    mono, _ = image_to_bgr(array_to_image(grey, None, "cam", "mono8"))
    assert mono.shape == (6, 5, 3) and np.array_equal(mono[:, :, 1], grey)


def test_padded_rows_and_list_data_are_decoded(rng):
    bgr = rng.integers(0, 256, (3, 4, 3), dtype=np.uint8)
    padded = np.zeros((3, 16), np.uint8)
    padded[:, :12] = bgr.reshape(3, 12)
    msg = Image(height=3, width=4, encoding="bgr8", step=16, data=padded.tobytes())
    back, why = image_to_bgr(msg)
    assert why == "" and np.array_equal(back, bgr)
    msg.data = [int(v) for v in padded.ravel()]
    assert np.array_equal(image_to_bgr(msg)[0], bgr)


@pytest.mark.parametrize(
    "change, reason",
    [
        (dict(encoding="bgr16"), "unsupported encoding 'bgr16'"),
        (dict(encoding="yuv422"), "unsupported encoding 'yuv422'"),
        (dict(step=11), "step 11 bytes is shorter than a row (4 px x 3 bytes = 12)"),
        (dict(step=13), "data has 36 bytes, expected step 13 x height 3 = 39"),
        (dict(data=bytes(35)), "data has 35 bytes, expected step 12 x height 3 = 36"),
        (dict(height=0, data=b""), "empty image (4 x 0 px)"),
        (dict(data=[300] * 36), "values outside 0..255"),
        (dict(encoding="mono8", step=4), "data has 36 bytes, expected step 4 x height 3 = 12"),
    ],
)
def test_malformed_images_are_refused_with_a_reason(change, reason):
    fields = dict(height=3, width=4, encoding="bgr8", step=12, data=bytes(36))
    fields.update(change)
    array, why = image_to_bgr(Image(**fields))
    assert array is None and reason in why


def test_bad_arrays_cannot_be_published():
    with pytest.raises(ValueError, match="uint8"):
        bgr_to_image(np.zeros((4, 4, 3), np.float32))
    with pytest.raises(ValueError, match="H x W x 3"):
        bgr_to_image(np.zeros((4, 4), np.uint8))
    with pytest.raises(ValueError, match="stamp"):
        bgr_to_image(np.zeros((4, 4, 3), np.uint8), stamp=float("nan"))


def test_camera_info_round_trip_and_refusals():
    K = np.array([[610.0, 0, 322.0], [0, 605.0, 241.0], [0, 0, 1]])
    intrinsics = Intrinsics(K, np.array([0.1, -0.2, 0.001, 0.002, 0.05]), (640, 480), 0.3)
    msg = camera_info_from_intrinsics(intrinsics, 3.0, "cam")
    assert msg.distortion_model == "plumb_bob" and msg.P[2] == 322.0 and msg.P[3] == 0.0 and msg.R[4] == 1.0
    back, why = intrinsics_from_camera_info(msg)
    assert why == "" and np.allclose(back.K, K) and np.allclose(back.distortion, intrinsics.distortion)
    assert back.image_size == (640, 480)
    assert "uncalibrated" in intrinsics_from_camera_info(CameraInfo(width=640, height=480))[1]
    assert "no image size" in intrinsics_from_camera_info(CameraInfo(K=msg.K))[1]
    skewed = CameraInfo(width=640, height=480, K=[610.0, 0, 322, 0, -1.0, 241, 0, 0, 1], distortion_model="plumb_bob")
    assert "not a camera matrix" in intrinsics_from_camera_info(skewed)[1]
    wrong_d = CameraInfo(width=640, height=480, K=msg.K, D=[0.1] * 6, distortion_model="rational_polynomial")
    assert "needs 8 coefficients, got 6" in intrinsics_from_camera_info(wrong_d)[1]
    fisheye = CameraInfo(width=640, height=480, K=msg.K, D=[0.1] * 4, distortion_model="equidistant")
    assert "not supported" in intrinsics_from_camera_info(fisheye)[1]


# -- the intrinsics file --------------------------------------------------------------------
def test_intrinsics_yaml_is_saved_atomically_and_read_back(tmp_path):
    K = np.array([[600.5, 0, 319.0], [0, 601.5, 240.0], [0, 0, 1]])
    path = str(tmp_path / "calib" / "camera.yaml")
    write_intrinsics_yaml(path, Intrinsics(K, np.zeros(5), (640, 480), 0.25), "cam_a")
    assert os.listdir(tmp_path / "calib") == ["camera.yaml"]  # no temporary left
    info = load_camera_info_yaml(path)
    assert (info.width, info.height) == (640, 480) and list(info.K) == list(K.ravel())
    assert list(info.P) == [600.5, 0, 319.0, 0, 0, 601.5, 240.0, 0, 0, 0, 1, 0]
    assert resolve_camera_info_url("file://" + path) == path
    assert (
        resolve_camera_info_url("package://kitting/config/c.yaml", lambda pkg: "/opt/" + pkg)
        == "/opt/kitting/config/c.yaml"
    )
    with pytest.raises(IntrinsicsFileError, match="only file:// and package://"):
        resolve_camera_info_url("http://example.invalid/c.yaml")
    with pytest.raises(IntrinsicsFileError, match="cannot read the intrinsics file.*calibrate_camera"):
        load_camera_info_yaml(str(tmp_path / "missing.yaml"))
    text = open(path).read()
    (tmp_path / "bad.yaml").write_text(text.replace("camera_matrix", "camera_matrx"))
    with pytest.raises(IntrinsicsFileError, match="bad.yaml: 'camera_matrix' is missing"):
        load_camera_info_yaml(str(tmp_path / "bad.yaml"))
    (tmp_path / "binary.yaml").write_bytes(bytes(range(256)))
    with pytest.raises(IntrinsicsFileError, match="binary.yaml: not a text file"):
        load_camera_info_yaml(str(tmp_path / "binary.yaml"))
    (tmp_path / "zero.yaml").write_text(text.replace("image_width: 640", "image_width: 0"))
    with pytest.raises(IntrinsicsFileError, match="'image_width' must be a whole number"):
        load_camera_info_yaml(str(tmp_path / "zero.yaml"))


# -- calibration views and the calibrate_camera command -------------------------------------
@pytest.fixture(scope="module")
def board_views():
    """12 rendered ChArUco shots (RGB) by a camera with fx = fy = 600 px."""
    client = p.connect(p.DIRECT)
    try:
        camera = PinholeCamera(640, 480, np.array([[TRUE_F, 0, 319.5], [0, TRUE_F, 239.5], [0, 0, 1]]))
        return render_board_views(client, BoardSpec(), camera, 12, seed=3)
    finally:
        p.disconnect(client)


def write_views(folder, views):
    os.makedirs(folder, exist_ok=True)
    for i, view in enumerate(views):
        cv2.imwrite(os.path.join(folder, f"board_{i:02d}.png"), cv2.cvtColor(view, cv2.COLOR_RGB2BGR))


def calibrate(*args):
    return subprocess.run(
        [PYTHON, os.path.join(NODES, "calibrate_camera"), *args], capture_output=True, text=True, timeout=120, env=ENV
    )


def test_view_collector_takes_only_moved_boards(board_views):
    views = [cv2.cvtColor(v, cv2.COLOR_RGB2BGR) for v in board_views[:3]]
    collector = ViewCollector(BoardSpec(), count=2, interval=0.5)
    assert collector.offer(np.full((480, 640, 3), 128, np.uint8), 0.0) == (False, "0 ChArUco corners found (need 8)")
    assert collector.offer(views[0], 0.1)[0]
    assert collector.offer(views[1], 0.3) == (False, "too soon after the last view")
    taken, why = collector.offer(views[0], 1.0)
    assert not taken and why.startswith("board moved 0 px")
    assert collector.offer(views[1], 2.0)[0] and collector.done and len(collector.views) == 2


def test_calibrate_camera_from_images_within_one_percent(tmp_path, board_views):
    folder = str(tmp_path / "views")
    write_views(folder, board_views)
    (tmp_path / "views" / "board_99.png").write_bytes(b"broken")
    output = str(tmp_path / "out" / "camera.yaml")
    proc = calibrate("--images", os.path.join(folder, "*.png"), "--output", output, "--camera-name", "test_cam")
    assert proc.returncode == 0, proc.stderr
    assert "board_99.png: not an image OpenCV can decode" in proc.stderr
    assert "RMS reprojection error" in proc.stdout and proc.stdout.count("board_") == 12  # per-view errors
    info = load_camera_info_yaml(output)
    fx, fy = info.K[0], info.K[4]
    assert abs(fx / TRUE_F - 1) < 0.01 and abs(fy / TRUE_F - 1) < 0.01, proc.stdout
    assert f"fx {fx:.2f} px" in proc.stdout
    assert "camera_name: test_cam" in open(output).read()


def test_calibrate_camera_grabs_views_from_a_video_like_a_camera(tmp_path, board_views):
    frames = []
    for view in board_views:  # each pose held for 3 frames
        frames += [cv2.cvtColor(view, cv2.COLOR_RGB2BGR)] * 3
    video = write_video(tmp_path / "board.avi", frames, fps=6.0)
    output = str(tmp_path / "camera.yaml")
    saved = str(tmp_path / "saved")
    proc = calibrate("--video", video, "--count", "10", "--interval", "0.4", "--output", output, "--save-views", saved)
    assert proc.returncode == 0, proc.stderr
    assert "view 10/10" in proc.stderr
    assert sorted(os.listdir(saved)) == [f"view_{i:03d}.png" for i in range(10)]
    info = load_camera_info_yaml(output)
    assert abs(info.K[0] / TRUE_F - 1) < 0.01, proc.stdout


def test_calibrate_camera_fails_clearly_on_too_few_views(tmp_path, board_views):
    folder = str(tmp_path / "few")
    write_views(folder, board_views[:3])
    cv2.imwrite(os.path.join(folder, "blank.png"), np.full((480, 640, 3), 128, np.uint8))
    output = str(tmp_path / "camera.yaml")
    proc = calibrate("--images", folder, "--output", output)
    assert proc.returncode == 1
    assert "blank.png: rejected: 0 ChArUco corners found" in proc.stderr
    assert "only 3 usable views of the board (need 6); nothing written" in proc.stderr
    assert not os.path.exists(output)
    proc = calibrate("--images", str(tmp_path / "nothing" / "*.png"), "--output", output)
    assert proc.returncode == 2 and "no images match" in proc.stderr


def test_commands_have_help():
    proc = calibrate("--help")
    assert proc.returncode == 0 and "--images" in proc.stdout and "--square-size" in proc.stdout
    proc = subprocess.run(
        [PYTHON, os.path.join(NODES, "camera_driver"), "--help"], capture_output=True, text=True, timeout=60, env=ENV
    )
    assert proc.returncode == 0, proc.stderr
    assert "camera_info_url" in proc.stdout and "/kitting/camera/image_raw" in proc.stdout
