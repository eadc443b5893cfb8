#!/usr/bin/env python3
"""Writes tests/data/webcam_hand_sweep.avi, the video of the webcam_session rostest: the
real open-hand photo handSrc.jpg (tests/data/README.md) moved along a seeded path by
tests/tools/hand_warp.py, 60 frames at 15 fps (4 s), MJPG in AVI.

Run: .venv/bin/python tests/tools/make_webcam_video.py [--output FILE]
"""

import argparse
import os

import cv2

from hand_warp import DATA, HEIGHT, WIDTH, warped_sequence

FRAMES, FPS, SEED = 60, 15.0, 11


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output", default=os.path.join(DATA, "webcam_hand_sweep.avi"))
    args = parser.parse_args()
    sequence = warped_sequence("handSrc", frames=FRAMES, seed=SEED, period_frames=FRAMES)
    writer = cv2.VideoWriter(args.output, cv2.VideoWriter_fourcc(*"MJPG"), FPS, (WIDTH, HEIGHT))
    writer.set(cv2.VIDEOWRITER_PROP_QUALITY, 70)
    for frame in sequence.frames:
        writer.write(frame)
    writer.release()
    print(f"{args.output}: {FRAMES} frames at {FPS:g} fps, {os.path.getsize(args.output) / 1024:.0f} KiB")


if __name__ == "__main__":
    main()
