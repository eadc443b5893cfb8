"""The camera hand devices' (depth camera, Kinect, webcam) camera model: the pinhole
intrinsics, which are ``motion_common.camera_model.Intrinsics`` (one model for every camera
of the framework), and the rotation from a camera's optical axes to REP 103 body axes."""

import numpy as np

from motion_common.camera_model import Intrinsics

__all__ = ["Intrinsics", "OPTICAL_TO_REP103"]

# Optical axes (x right, y down, z forward) to REP 103 body axes (x forward, y left, z up).
OPTICAL_TO_REP103 = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
