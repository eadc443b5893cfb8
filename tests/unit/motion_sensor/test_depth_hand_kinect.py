"""The Kinect source through Debian's libfreenect, without a Kinect: a synthetic fakenect
dump (INDEX.txt + d-*.pgm of a rendered hand moving along a path) played by fakenect's
libfreenect under KinectDevice, in a subprocess (one process holds one libfreenect, and
fakenect 0.5.3 can crash the process that reads past a dump's end)."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from motion_sensor.devices import fakenect
from motion_sensor.devices.depth_hand import OPTICAL_TO_BODY
from motion_sensor.devices.kinect import FakenectKinectDevice, KinectDevice
from motion_sensor.errors import MotionSensorError
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR
from motion_sensor.testing.synthetic_depth import hand_path, render_hand

from ..conftest import ROOT

PYTHONPATH = os.pathsep.join(os.path.join(ROOT, "src", p) for p in ("motion_sensor", "motion_common"))

PLAY = """
import json, sys
from motion_sensor.devices.kinect import FakenectKinectDevice
from motion_sensor.errors import EndOfStream
config = dict(FakenectKinectDevice.params.defaults(), **json.loads(sys.argv[1]))
device = FakenectKinectDevice(config, clock=lambda: 0.0, sleep=lambda s: None)
device.open()
out = []
try:
    while True:
        sample = device.read(0.0)
        out.append(None if sample is None else [sample.hands_num] + list(map(float, sample.position)))
except EndOfStream:
    pass
device.close()
print(json.dumps({"samples": out, "counters": dict(device.counters)}))
"""


def run_python(code, *args, env=None):
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ, PYTHONPATH=PYTHONPATH, **(env or {})),
    )


def test_raw11_conversion_round_trips_within_quantisation():
    depth = np.linspace(0.4, 1.3, 50)
    back = fakenect.raw11_to_m(fakenect.m_to_raw11(depth))
    step = fakenect.raw11_to_m(fakenect.m_to_raw11(depth) + 1) - back  # one raw unit at that depth
    assert np.all(np.abs(back - depth) <= step * 0.51 + 1e-6)
    assert np.all(step < 0.005) and step[0] < 0.001  # Kinect: < 1 mm at 0.4 m, < 5 mm at 1.3 m
    assert fakenect.raw11_to_m(np.array([fakenect.RAW_NO_VALUE]))[0] == 0.0
    assert fakenect.m_to_raw11(np.array([0.0]))[0] == fakenect.RAW_NO_VALUE


def test_python_needs_the_stub_under_fakenect(tmp_path):
    """fakenect lacks camera_to_world (OpenKinect/libfreenect#509): without the stub, libfreenect_sync cannot load."""
    code = (
        "import ctypes, os\n"
        "ctypes.CDLL(os.environ['FAKE_LIB'], mode=os.RTLD_GLOBAL | os.RTLD_NOW)\n"
        "ctypes.CDLL('libfreenect_sync.so.0.5')\n"
    )
    result = run_python(code, env={"FAKE_LIB": fakenect.fakenect_library()})
    assert result.returncode != 0 and "freenect_camera_to_world" in result.stderr
    stub = fakenect.build_stub(str(tmp_path))
    with_stub = run_python(
        f"import ctypes, os; ctypes.CDLL({stub!r}, mode=os.RTLD_GLOBAL)\n" + code.split("\n", 1)[1],
        env={"FAKE_LIB": fakenect.fakenect_library()},
    )
    assert with_stub.returncode == 0, with_stub.stderr
    assert fakenect.build_stub(str(tmp_path)) == stub  # cached: built once


def test_kinect_device_tracks_a_hand_in_a_fakenect_dump(tmp_path):
    poses = hand_path(12, seed=5)
    rng = np.random.default_rng(2)
    frames = [fakenect.m_to_raw11(render_hand(p, noise_per_m2=0.0015, rng=rng)) for p in poses]
    frames.append(fakenect.m_to_raw11(np.full((480, 640), 2.5)))  # the last frame is never read
    dump = tmp_path / "dump"
    assert fakenect.write_dump(str(dump), frames) == 13
    config = {
        "fakenect_dump": str(dump),
        "depth_format": "11bit",
        "fakenect_stub_dir": str(tmp_path / "stub"),
        "intrinsics_px": [INTR.fx, INTR.fy, INTR.cx, INTR.cy],
    }
    result = run_python(PLAY, json.dumps(config))
    assert result.returncode == 0, result.stderr[-2000:]
    report = json.loads(result.stdout.strip().splitlines()[-1])
    samples = report["samples"]
    assert len(samples) == 12 and report["counters"]["frames"] == 12  # stopped one frame before the dump's end
    assert all(s is not None and s[0] == 1 for s in samples), samples
    seen = np.array([s[1:] for s in samples])
    truth = np.array([OPTICAL_TO_BODY @ p.position for p in poses])
    errors = seen - truth
    rms = float(np.sqrt(np.mean(np.sum((errors - errors.mean(axis=0)) ** 2, axis=1))))
    assert rms < 0.012, f"{rms * 1000:.1f} mm RMS through fakenect"


def test_kinect_config_checks():
    defaults = KinectDevice.params.defaults()
    with pytest.raises(MotionSensorError, match="11bit"):
        KinectDevice(dict(defaults, fakenect_dump="/tmp/x"))
    with pytest.raises(MotionSensorError, match="dump directory"):
        FakenectKinectDevice(dict(defaults, depth_format="11bit"))
    with pytest.raises(MotionSensorError, match="INDEX.txt"):
        FakenectKinectDevice(dict(defaults, depth_format="11bit", fakenect_dump="/nonexistent"))
