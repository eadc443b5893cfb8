"""Kinect v1 as a hand device through Debian's libfreenect, by ctypes (node ``kinect_driver``).

Why ctypes against ``libfreenect_sync`` and not the PyPI ``freenect`` binding: that
binding is a Cython extension with no wheels, built from source against the installed
libfreenect; ``scripts/setup`` installs wheels only (``--only-binary=:all:``), so it would
need its own build step (Cython, headers, a compiler) for three calls. The synchronous API
is three C functions (``freenect_sync_get_depth``, ``freenect_sync_stop``), the frame a
640x480 uint16 buffer that numpy copies directly.

``depth_format``: ``mm`` asks libfreenect for depth in millimetres (it converts with the
device's own factory registration data: use it with a real Kinect); ``11bit`` takes the raw
disparity and converts it with Magnenat's fit (``fakenect.raw11_to_m``): needed under
fakenect, which in Debian's 0.5.3 only plays raw dumps. Frames are stamped on arrival
(the Kinect's timestamp counts device ticks, not time). ``fakenect_dump`` plays a fakenect
dump instead of the device (``FakenectKinectDevice``: finite, ends before the dump does).
"""

import ctypes
import os

import numpy as np

import motion_sensor.devices.fakenect as fakenect
from motion_common.params import Param, ParamSchema
from motion_sensor.devices.camera_intrinsics import Intrinsics
from motion_sensor.devices.depth_device import IMAGE_CHECK_PARAMS, DepthHandDevice
from motion_sensor.devices.depth_hand import TRACKER_PARAMS
from motion_sensor.errors import DeviceUnavailable, EndOfStream, MotionSensorError
from motion_sensor.hand_sample import HandSample

FREENECT_DEPTH_11BIT = 0
FREENECT_DEPTH_MM = 5
WIDTH, HEIGHT = 640, 480

# One process can hold the real libfreenect or fakenect's, never both: (kind, sync library).
_LOADED = {}


def load_sync_library(fake: bool, stub_dir: str = "") -> ctypes.CDLL:
    """libfreenect_sync bound to the real libfreenect or to fakenect's (plus a stub for its missing camera_to_world)."""
    kind = "fakenect" if fake else "device"
    if _LOADED and kind not in _LOADED:
        raise MotionSensorError(
            f"libfreenect already loaded for the {next(iter(_LOADED))} in this process; "
            "the real device and fakenect need separate processes"
        )
    if kind not in _LOADED:
        try:
            if fake:
                scope = os.RTLD_GLOBAL | os.RTLD_NOW
                ctypes.CDLL(fakenect.build_stub(stub_dir or None), mode=scope)
                ctypes.CDLL(fakenect.fakenect_library(), mode=scope)
            lib = ctypes.CDLL("libfreenect_sync.so.0.5")
        except OSError as exc:
            raise MotionSensorError(
                f"cannot load libfreenect_sync: {exc}; apt-get install libfreenect0.5 (scripts/setup does)"
            ) from None
        lib.freenect_sync_get_depth.argtypes = [
            ctypes.POINTER(ctypes.c_void_p),
            ctypes.POINTER(ctypes.c_uint32),
            ctypes.c_int,
            ctypes.c_int,
        ]
        lib.freenect_sync_get_depth.restype = ctypes.c_int
        lib.freenect_sync_stop.argtypes = []
        lib.freenect_sync_stop.restype = None
        _LOADED[kind] = lib
    return _LOADED[kind]


class KinectDevice(DepthHandDevice):
    """Hands from a Kinect v1's depth stream (blocking reads at the camera's 30 Hz)."""

    name = "kinect"
    params = TRACKER_PARAMS.merged(IMAGE_CHECK_PARAMS).merged(
        ParamSchema(
            [
                Param("device_index", 0, low=0, doc="which Kinect, when several are plugged in"),
                Param(
                    "depth_format",
                    "mm",
                    choices=("mm", "11bit"),
                    doc=(
                        "mm: libfreenect's calibrated conversion (a real Kinect); 11bit: raw, converted here (fakenect)"
                    ),
                ),
                Param(
                    "intrinsics_px",
                    [594.21, 591.04, 339.31, 242.74],
                    unit="px",
                    length=4,
                    doc="depth camera fx, fy, cx, cy (typical Kinect v1 values; calibrate yours)",
                ),
                Param("fakenect_dump", "", doc="play this fakenect dump directory instead of the device"),
                Param(
                    "fakenect_stub_dir",
                    "",
                    doc="where the fakenect camera_to_world stub is built (empty: ~/.cache/motion_sensor)",
                ),
            ],
            ignore=("image_topic", "camera_info_topic", "wait_s"),
        )
    )

    def __init__(self, config: dict, **kw):
        super().__init__(config, **kw)
        fx, fy, cx, cy = self.config["intrinsics_px"]
        if fx <= 0 or fy <= 0:
            raise MotionSensorError("kinect: intrinsics_px fx and fy must be positive")
        self.intrinsics = Intrinsics(fx, fy, cx, cy, WIDTH, HEIGHT)
        self.fake = bool(self.config["fakenect_dump"])
        if self.fake and self.config["depth_format"] != "11bit":
            raise MotionSensorError(
                "kinect: fakenect (libfreenect 0.5.3) plays raw dumps only: set depth_format: 11bit with fakenect_dump"
            )
        self.lib = None

    def describe(self) -> str:
        if self.fake:
            return f"fakenect dump {self.config['fakenect_dump']}"
        return f"Kinect #{self.config['device_index']}"

    def open(self) -> None:
        if self.fake:
            os.environ["FAKENECT_PATH"] = os.path.abspath(self.config["fakenect_dump"])
        self.lib = load_sync_library(self.fake, self.config["fakenect_stub_dir"])
        self.tracker.reset()

    def grab(self) -> np.ndarray:
        """The next depth frame in metres (blocks until the camera delivers it)."""
        pointer, timestamp = ctypes.c_void_p(), ctypes.c_uint32()
        mm = self.config["depth_format"] == "mm"
        status = self.lib.freenect_sync_get_depth(
            ctypes.byref(pointer),
            ctypes.byref(timestamp),
            self.config["device_index"],
            FREENECT_DEPTH_MM if mm else FREENECT_DEPTH_11BIT,
        )
        if status != 0 or not pointer.value:
            raise DeviceUnavailable(
                f"no Kinect #{self.config['device_index']} (libfreenect status {status}): "
                "plugged in, powered, and in the plugdev group?"
            )
        raw = np.ctypeslib.as_array(ctypes.cast(pointer, ctypes.POINTER(ctypes.c_uint16)), shape=(HEIGHT, WIDTH))
        return raw.astype(np.float32) * np.float32(0.001) if mm else fakenect.raw11_to_m(raw)

    def read(self, now: float) -> HandSample | None:
        depth = self.grab()
        stamp = self.clock()  # on arrival: the device's own timestamp is not a time
        measured = np.count_nonzero(depth)
        if measured < self.config["min_valid_fraction"] * depth.size:
            self.reject("empty_depth", f"{measured} measured pixels of {depth.size}: lens covered?")
            return None
        return self.hand_sample(depth, self.intrinsics, stamp)

    def close(self) -> None:
        if self.lib is not None:
            self.lib.freenect_sync_stop()


class FakenectKinectDevice(KinectDevice):
    """A fakenect dump played as the Kinect: finite, it ends one frame before the dump does
    (Debian's fakenect crashes when its index runs out)."""

    finite = True
    wrapper_defaults = {"min_subscribers": 1}  # never play to nobody

    def __init__(self, config: dict, **kw):
        super().__init__(config, **kw)
        if not self.fake:
            raise MotionSensorError("kinect: fakenect_dump must name a dump directory")
        self.frames_left = fakenect.depth_frame_count(self.config["fakenect_dump"]) - 1
        if self.frames_left < 1:
            raise MotionSensorError(f"fakenect dump {self.config['fakenect_dump']} holds fewer than 2 depth frames")

    def read(self, now: float) -> HandSample | None:
        if self.frames_left <= 0:
            raise EndOfStream()
        self.frames_left -= 1
        return super().read(now)
