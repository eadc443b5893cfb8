"""MediaPipe Hands starts and tracks without printing: no protobuf AttributeError (its
GetPrototype call on a protobuf that renamed it), no TFLite or absl start-up warnings."""

import subprocess
import sys

from ..conftest import DATA, ROOT

SCRIPT = f"""
import sys
sys.path[:0] = [{ROOT + "/src/motion_sensor"!r}, {ROOT + "/src/motion_common"!r}]
import cv2
from motion_sensor.devices.mediapipe_hands import MediaPipeHandDetector
detector = MediaPipeHandDetector()
image = cv2.imread({DATA + "/right04.jpg"!r})[:, :, ::-1]
print(sum(len(detector.detect(image)) for _ in range(3)))
detector.close()
"""


def test_mediapipe_prints_nothing_but_finds_the_hand():
    result = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "3\n" and result.stderr == ""
