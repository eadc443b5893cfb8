"""fakenect: libfreenect's recorded-dump player, usable from Python without a Kinect.

Debian's ``libfreenect0.5`` ships a second ``libfreenect.so.0.5`` under
``/usr/lib/<arch>/fakenect/`` that plays a dump directory (``FAKENECT_PATH``) instead of
talking to a device. Two things stand between it and Python:

- ``libfreenect_sync.so`` (the synchronous API used through ctypes) needs
  ``freenect_camera_to_world``, which fakenect does not define (OpenKinect/libfreenect#509),
  so loading it fails with "undefined symbol". ``build_stub`` compiles a one-function
  shared library defining that symbol with the system's gcc (cached by source hash).
- The usual cure is ``LD_PRELOAD``, which must be set before the interpreter starts. We
  load instead, in this order and ``RTLD_GLOBAL``: the stub, fakenect's libfreenect, then
  libfreenect_sync; the dynamic loader then binds libfreenect_sync's libfreenect.so.0.5 to
  the already-loaded fakenect library (same soname) and the missing symbol to the stub.
  (``motion_sensor.devices.kinect`` does this; one process can hold only one of real or fake.)

Dump format (fakenect's ``record``): ``INDEX.txt`` lists one file name per line;
``d-<seconds>-<timestamp>.pgm`` is a depth frame: a one-line ``P5 640 480 65535`` header
followed by the raw 640x480 11-bit values as the host's uint16 (little-endian here, not
PGM's big-endian). Debian's fakenect (0.5.3) plays only ``FREENECT_DEPTH_11BIT`` (it
aborts on the mm format), sleeps to reproduce the recorded spacing, and crashes when the
index runs out, so a reader stops one frame before the end (``depth_frame_count``).
"""

import glob
import hashlib
import os
import subprocess
from collections.abc import Iterable

import numpy as np

from motion_sensor.errors import MotionSensorError

STUB_SOURCE = """\
/* freenect_camera_to_world for fakenect, which lacks it (OpenKinect/libfreenect#509):
   libfreenect_sync references it; nothing here calls it. */
void freenect_camera_to_world(void *dev, int cx, int cy, int wz, double *wx, double *wy)
{
    (void)dev; (void)wz;
    *wx = cx;
    *wy = cy;
}
"""

# Raw 11-bit disparity to metres (Magnenat's fit, OpenKinect wiki "Imaging Information").
RAW_A, RAW_B, RAW_C = 0.1236, 2842.5, 1.1863
RAW_NO_VALUE = 2047


def raw11_to_m(raw: np.ndarray) -> np.ndarray:
    """Metres (float32, 0 where the Kinect measured nothing) of raw 11-bit depth values."""
    raw = np.asarray(raw)
    depth = (RAW_A * np.tan(raw.astype(np.float32) / np.float32(RAW_B) + np.float32(RAW_C))).astype(np.float32)
    depth[(raw >= RAW_NO_VALUE) | (depth <= 0)] = 0.0
    return depth


def m_to_raw11(depth_m: np.ndarray) -> np.ndarray:
    """Raw 11-bit values (uint16) of depths in metres; 0 m becomes 2047 (no measurement)."""
    depth = np.asarray(depth_m, dtype=float)
    raw = np.rint((np.arctan(np.maximum(depth, 1e-6) / RAW_A) - RAW_C) * RAW_B)
    raw = np.clip(raw, 0, RAW_NO_VALUE - 1)
    raw[depth <= 0] = RAW_NO_VALUE
    return raw.astype(np.uint16)


def fakenect_library() -> str:
    """Path of Debian's fakenect libfreenect.so.0.5; MotionSensorError if not installed."""
    found = sorted(glob.glob("/usr/lib/*/fakenect/libfreenect.so.0.5")) + sorted(
        glob.glob("/usr/lib/fakenect/libfreenect.so.0.5")
    )
    if not found:
        raise MotionSensorError("fakenect is not installed: apt-get install libfreenect0.5 (scripts/setup does)")
    return found[0]


def build_stub(cache_dir: str | None = None, compiler: str = "gcc") -> str:
    """Path of the compiled stub library (built once per source version into ``cache_dir``,
    default ~/.cache/motion_sensor); MotionSensorError naming the fix if gcc fails."""
    cache_dir = cache_dir or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "motion_sensor"
    )
    digest = hashlib.sha256(STUB_SOURCE.encode()).hexdigest()[:12]
    target = os.path.join(cache_dir, f"fakenect_stub-{digest}.so")
    if os.path.exists(target):
        return target
    os.makedirs(cache_dir, exist_ok=True)
    source = os.path.join(cache_dir, f"fakenect_stub-{digest}.c")
    with open(source, "w", encoding="utf-8") as stream:
        stream.write(STUB_SOURCE)
    partial = f"{target}.{os.getpid()}.tmp"
    try:
        subprocess.run(
            [compiler, "-shared", "-fPIC", "-O2", "-o", partial, source],
            check=True,
            capture_output=True,
            text=True,
            timeout=60,
        )
    except FileNotFoundError:
        raise MotionSensorError(f"cannot build the fakenect stub: {compiler} not found (apt-get install gcc)") from None
    except subprocess.CalledProcessError as exc:
        raise MotionSensorError(f"cannot build the fakenect stub: {exc.stderr.strip()}") from None
    os.replace(partial, target)  # atomic: a concurrent build never sees half a library
    return target


def write_dump(directory: str, frames_raw: Iterable[np.ndarray], fps: float = 30.0, start_s: float = 1.0) -> int:
    """Write a fakenect dump of 640x480 raw 11-bit depth frames (INDEX.txt + d-*.pgm);
    returns the number of frames."""
    os.makedirs(directory, exist_ok=True)
    names = []
    for index, raw in enumerate(frames_raw):
        raw = np.asarray(raw, dtype="<u2")
        if raw.shape != (480, 640):
            raise MotionSensorError(f"fakenect frames are 640x480, got {raw.shape}")
        name = f"d-{start_s + index / fps:.6f}-{index * int(60e6 / fps)}.pgm"
        with open(os.path.join(directory, name), "wb") as stream:
            stream.write(b"P5 640 480 65535\n")
            stream.write(raw.tobytes())
        names.append(name)
    with open(os.path.join(directory, "INDEX.txt"), "w", encoding="utf-8") as stream:
        stream.write("".join(f"{name}\n" for name in names))
    return len(names)


def depth_frame_count(directory: str) -> int:
    """Depth frames listed in a dump's INDEX.txt; MotionSensorError if it cannot be read."""
    try:
        with open(os.path.join(directory, "INDEX.txt"), encoding="utf-8") as stream:
            return sum(1 for line in stream if line.startswith("d-"))
    except OSError as exc:
        raise MotionSensorError(f"fakenect dump {directory}: cannot read INDEX.txt: {exc.strerror}") from None
