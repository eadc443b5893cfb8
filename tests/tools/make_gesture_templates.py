#!/usr/bin/env python3
"""Writes the default dynamic gesture templates of motion_sensor: swipe_right,
swipe_left, swipe_up, swipe_down and circle, as parametric palm paths with seeded
per-template variation (length, arc, tilt, speed profile, tracking noise, frame rate).

Run: .venv/bin/python tests/tools/make_gesture_templates.py [--out DIR] [--count 8] [--seed 17]
(default DIR: src/motion_sensor/config/gestures). A unit test checks the shipped files are
what this script writes. Axes are the hand message's (REP 103: x forward, y left, z up),
as seen by an operator facing forward: "right" is -y, "up" is +z; the circle is drawn
clockwise as the operator sees it, in the vertical y-z plane. Files: <DIR>/<label>/<n>.csv
with rows "x y z t" (mm, ms), see motion_sensor.gestures.gesture_templates.
"""

import argparse
import os
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_sensor"))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))
from motion_sensor.gestures.gesture_templates import format_path, write_atomic  # noqa: E402

LABELS = ("swipe_right", "swipe_left", "swipe_up", "swipe_down", "circle")
DIRECTIONS = {"swipe_right": (0, -1, 0), "swipe_left": (0, 1, 0), "swipe_up": (0, 0, 1), "swipe_down": (0, 0, -1)}


def gesture_path(label, rng, rate_hz=None):
    """One performance of ``label``: (points n x 3 in metres, times n in seconds)."""
    rate = rate_hz or rng.uniform(60, 110)
    if label == "circle":
        radius = rng.uniform(0.05, 0.09)
        duration = rng.uniform(0.7, 1.2)
        start = rng.uniform(-0.3, 0.3) + np.pi / 2
        n = int(duration * rate)
        s = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0, 1, n))
        angle = start - 2 * np.pi * rng.uniform(0.95, 1.08) * s  # clockwise seen from behind (-x)
        ry = radius * rng.uniform(0.85, 1.15)
        path = np.column_stack([rng.normal(0, 0.01) * np.sin(angle), -ry * np.cos(angle), radius * np.sin(angle)])
    else:
        direction = np.array(DIRECTIONS[label], dtype=float)
        length = rng.uniform(0.15, 0.3)
        duration = length / rng.uniform(0.35, 0.7)
        n = int(duration * rate)
        s = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0, 1, n))
        side = np.cross(direction, [1.0, 0.0, 0.0])  # in the vertical plane, across the swipe
        arc = rng.normal(0, 0.08) * length * np.sin(np.pi * s)
        depth = rng.normal(0, 0.05) * length * s
        path = np.outer(s * length, direction) + np.outer(arc, side) + np.outer(depth, [1.0, 0.0, 0.0])
    path = path + rng.normal(0, 0.0005, path.shape) + rng.uniform([0.0, -0.1, 0.15], [0.1, 0.1, 0.3])
    times = np.arange(len(path)) / rate
    return path, times


def write_templates(out, count=8, seed=17):
    """Write ``count`` templates per label into ``out``; return the paths written."""
    written = []
    for li, label in enumerate(LABELS):
        for i in range(count):
            rng = np.random.default_rng([seed, li, i])
            path, times = gesture_path(label, rng)
            target = os.path.join(out, label, f"{i + 1:03d}.csv")
            write_atomic(
                target,
                format_path(
                    path * 1000.0,
                    times * 1000.0,
                    f"gesture {label}; synthetic, tests/tools/make_gesture_templates.py "
                    f"seed {seed}\naxes REP 103 (x forward, y left, z up), palm",
                ),
            )
            written.append(target)
    return written


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=os.path.join(ROOT, "src", "motion_sensor", "config", "gestures"))
    parser.add_argument("--count", type=int, default=8)
    parser.add_argument("--seed", type=int, default=17)
    args = parser.parse_args()
    written = write_templates(args.out, args.count, args.seed)
    print(f"wrote {len(written)} templates to {args.out}")


if __name__ == "__main__":
    main()
