"""Cut tests/data/shrec17_slice.npz from the shared SHREC'17 training split: a few real
sequences of the gestures the teach commands use (grab, tap, expand, swipe left, shake),
whole hand, two repetitions each of four subjects, joints stored as float16 (the file
stays small; a few tenths of a millimetre of rounding). Same array layout as the shared
file. Attribution: tests/data/README.md.

Run: .venv/bin/python tests/tools/make_skeleton_slice.py [path/to/shrec17_train.npz]
"""

import os
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SOURCE = os.path.join(ROOT, "..", "shared", "data", "shrec17_train", "shrec17_train.npz")
OUT = os.path.join(ROOT, "tests", "data", "shrec17_slice.npz")
GESTURES = (1, 2, 3, 8, 14)  # grab, tap, expand, swipe left, shake
SUBJECTS = (2, 10, 19, 22)
PER_CELL = 2


def main(source=SOURCE):
    data = np.load(source)
    offsets = data["offsets"]
    keep = []
    for subject in SUBJECTS:
        for gesture in GESTURES:
            rows = np.flatnonzero((data["subject"] == subject) & (data["gesture"] == gesture) & (data["finger"] == 2))
            keep.extend(sorted(rows.tolist())[:PER_CELL])
    joints = [data["joints"][offsets[i] : offsets[i + 1]].astype(np.float16) for i in keep]
    new_offsets = np.concatenate([[0], np.cumsum([len(j) for j in joints])]).astype(np.int64)
    tmp = OUT + ".tmp.npz"
    np.savez_compressed(
        tmp,
        joints=np.concatenate(joints),
        offsets=new_offsets,
        **{name: data[name][keep] for name in ("gesture", "finger", "subject", "essai", "label14", "label28")},
    )
    os.replace(tmp, OUT)
    print(f"{OUT}: {len(keep)} sequences, {new_offsets[-1]} frames, {os.path.getsize(OUT)} bytes")


if __name__ == "__main__":
    main(*sys.argv[1:])
