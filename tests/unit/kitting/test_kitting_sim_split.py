"""The real vision pipeline runs without the simulator: the pinhole model is
motion_common.camera_model's, pybullet rendering stays in kitting.camera (simulation only)."""

import json
import os
import subprocess
import sys

from ..conftest import ROOT

PACKAGES = ("motion_common", "motion_sensor", "motion_commander", "hw_interface", "motion_apps", "kitting")


def modules_loaded_by(module):
    """Top-level modules among pybullet/onnxruntime/rospy that importing ``module`` loads, in
    a fresh interpreter with the source tree first on its path (as this suite imports)."""
    paths = [os.path.join(ROOT, "src", package) for package in PACKAGES]
    code = (
        f"import importlib, json, sys\nsys.path[:0] = {paths!r}\nimportlib.import_module({module!r})\n"
        "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules} & {'pybullet', 'onnxruntime', 'rospy'})))"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_vision_pipeline_does_not_import_pybullet():
    assert modules_loaded_by("kitting.vision_pipeline") == []


def test_the_sim_renderer_draws_the_common_pinhole_camera():
    from kitting import camera
    from motion_common.camera_model import PinholeCamera

    assert camera.PinholeCamera is PinholeCamera
    assert modules_loaded_by("kitting.camera") == ["pybullet"]
