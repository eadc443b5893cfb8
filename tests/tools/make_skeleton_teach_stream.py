#!/usr/bin/env python3
"""Builds the skeleton teach demo's operator stream (src/motion_apps/data/skeleton_teach_demo.npz)
from real SHREC'17 training-split frames.

The file is a SHREC'17-layout .npz (what shrec_stream_driver plays): real sequences of
tests/data/shrec17_slice.npz (SHREC'17, see tests/data/README.md), in the order an operator
teaches the pick-and-place of src/motion_apps/config/teach_scene.yaml with the commands of
src/motion_apps/config/skeleton_gesture_commands.yaml: tap where the hand engages (the
first waypoint; the stream starts there), tap above the part, GRAB at the part (grip), tap
lifted, tap above the place, EXPAND at the place (release), SHAKE clear above the cell
(stop: the program is saved). Every frame is a real frame, as recorded; each sequence is only translated so that
its palm ends where the arm must be when its command is taken (the tool follows the palm's
displacement, speed_ratio 1, from the pose where the hand engaged). The driver plays them
with a rest after each and a 0.5 s move to the next one's first pose: the moves carry the
arm. The sequences at the part and the place are ones whose palm never dips below their
last frame, so the tool does not press into the part or the table while the gesture is
made.

Run: .venv/bin/python tests/tools/make_skeleton_teach_stream.py [--output PATH] (deterministic).
"""

import argparse
import os
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path[:0] = [os.path.join(ROOT, "src", "motion_sensor"), os.path.join(ROOT, "src", "motion_common")]
from motion_sensor.gestures.skeleton_dataset import load_skeleton_dataset, save_skeleton_npz  # noqa: E402
from motion_sensor.skeleton_joints import SHREC_TO_REP103  # noqa: E402

SLICE = os.path.join(ROOT, "tests", "data", "shrec17_slice.npz")
OUTPUT = os.path.join(ROOT, "src", "motion_apps", "data", "skeleton_teach_demo.npz")

# Tool poses of the teach cell (m, robot base; make_teach_stream.py's): the tool starts at
# the UR5e home; the part's top is at z 0.23 at (-0.50, -0.20), the place at (-0.45, 0.10).
START = np.array([-0.492, -0.133, 0.488])
ABOVE_PART = np.array([-0.50, -0.20, 0.33])
AT_PART = np.array([-0.50, -0.20, 0.238])
ABOVE_PLACE = np.array([-0.45, 0.10, 0.33])
AT_PLACE = np.array([-0.45, 0.10, 0.240])
SAVE_POINT = np.array([-0.45, 0.10, 0.46])

# (index in the slice, gesture checked, where the tool is when the command is taken)
SCRIPT = [
    (22, "tap", None),  # subject 19, where the hand engages: the stream starts with its first frame
    (12, "tap", ABOVE_PART),  # subject 10
    (31, "grab", AT_PART),  # subject 22: the palm never dips below its end
    (32, "tap", ABOVE_PART),  # subject 22, lifted with the part
    (22, "tap", ABOVE_PLACE),  # subject 19
    (24, "expand", AT_PLACE),  # subject 19: the palm never dips below its end
    (18, "shake", SAVE_POINT),  # subject 10
]


def build():
    """(joints per sequence in the SHREC file frame, label14, label28, subject)."""
    data = load_skeleton_dataset(SLICE)
    names = {"grab": 0, "tap": 1, "expand": 2, "shake": 13}
    origin = np.zeros(3)  # the palm where the hand engages (the tool at START)
    joints, rows = [], []
    for index, label, tool in SCRIPT:
        if data.label14[index] != names[label]:
            raise SystemExit(f"slice sequence {index} is not a {label}")
        seq = data.sequences[index]
        if tool is None:
            moved = seq - seq[0, 1] + origin
        else:
            moved = seq - seq[-1, 1] + origin + (tool - START)
        joints.append(moved @ SHREC_TO_REP103)  # back to the file's (camera) frame
        rows.append(index)
    label14 = [int(data.label14[i]) + 1 for i in rows]  # the file counts classes from 1
    label28 = [int(data.label28[i]) + 1 for i in rows]
    return joints, label14, label28, [int(data.subject[i]) for i in rows]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output", default=OUTPUT)
    args = parser.parse_args(argv)
    joints, label14, label28, subject = build()
    save_skeleton_npz(args.output, joints, label14, label28, subject)
    print(f"wrote {args.output}: {len(joints)} sequences, {sum(len(j) for j in joints)} frames")
    return 0


if __name__ == "__main__":
    sys.exit(main())
