"""Draws docs/architecture.png: the packages by layer and the path a hand frame takes to the
robot. The boxes and labels are listed below; edit them here, then run this script.

Usage: .venv/bin/python scripts/gen_architecture.py [--check] [--output PNG]
  --check   draw and compare with the committed file instead of writing it (exit 1 when stale)
  --output  write there instead of docs/architecture.png
"""

import argparse
import io
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))
PNG = os.path.join(ROOT, "docs", "architecture.png")

# Each box: position and size (x, y, width, height) on an 18 x 9 canvas, colour, title, lines.
APPS = "#f6e3c6"
CHAIN = "#d5e6f5"
ROBOT = "#dddddd"
BASE = "#dcefd8"
BOXES = {
    "device": (
        (0.3, 3.6, 2.8, 2.0), ROBOT, "hand device",
        "Leap Motion, SpaceMouse,|webcam, depth camera,|Kinect, recording",
    ),
    "sensor": (
        (4.5, 3.3, 3.4, 2.6), CHAIN, "motion_sensor",
        "devices (HandDevice)|sequencer: checks, filter|gestures|registration (DTW)",
    ),
    "core": (
        (9.6, 3.3, 3.6, 2.6), CHAIN, "motion_commander",
        "core: teleop mapping, clutch|IK (pinocchio), safety|manipulation API|taught programs",
    ),
    "hw": (
        (14.6, 3.3, 3.1, 2.6), CHAIN, "hw_interface",
        "commander.srv server|(motion_controller_server)|drivers: pybullet, ur_rtde,|your RobotDriver",
    ),
    "robot": (
        (14.85, 0.35, 2.6, 1.6), ROBOT, "robot",
        "simulated (pybullet)|or a real arm",
    ),
    "teach": (
        (4.5, 7.0, 3.4, 1.6), APPS, "motion_apps",
        "teach by gesture,|replay programs",
    ),
    "kitting": (
        (9.6, 7.0, 3.6, 1.6), APPS, "kitting",
        "camera, vision, belt,|intercept pick",
    ),
    "dashboard": (
        (14.6, 7.0, 3.1, 1.6), APPS, "dashboard",
        "operator console|(web page)",
    ),
    "common": (
        (4.5, 0.35, 8.7, 1.6), BASE, "motion_common",
        "robot model (URDF, FK/IK), parameter validator,|node declarations: used by every package above",
    ),
}  # fmt: skip
# (from, to, label, from side, to side)
ARROWS = [
    ("device", "sensor", "raw hand", "right", "left"),
    ("sensor", "core", "/motion_states_stamped", "right", "left"),
    ("core", "hw", "commander.srv", "right", "left"),
    ("hw", "robot", "joint targets", "bottom", "top"),
    ("teach", "core", "", "bottom", "top"),
    ("kitting", "core", "pick / place", "bottom", "top"),
    ("dashboard", "hw", "STOP, status", "bottom", "top"),
]
LAYERS = [
    (8.3, "applications"),
    (5.95, "sensing, core, hardware"),
    (1.95, "foundation"),
]


def _anchor(box, side):
    x, y, w, h = box[0]
    return {
        "left": (x, y + h / 2),
        "right": (x + w, y + h / 2),
        "top": (x + w / 2, y + h),
        "bottom": (x + w / 2, y),
    }[side]


def draw() -> bytes:
    """The PNG's bytes (no timestamp or version in its metadata: the same drawing gives the
    same bytes)."""
    fig, ax = plt.subplots(figsize=(18, 9), dpi=80)
    ax.set_xlim(0, 18)
    ax.set_ylim(0, 9)
    ax.axis("off")
    for y, label in LAYERS:
        ax.text(0.3, y, label, fontsize=11, color="#555555", style="italic")
    for (x, y, w, h), colour, title, lines in BOXES.values():
        ax.add_patch(
            FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05,rounding_size=0.15", fc=colour, ec="#333333", lw=1.2)
        )
        ax.text(x + w / 2, y + h - 0.35, title, ha="center", va="center", fontsize=14, weight="bold")
        ax.text(
            x + w / 2,
            y + (h - 0.6) / 2,
            lines.replace("|", "\n"),
            ha="center",
            va="center",
            fontsize=10.5,
            linespacing=1.4,
        )
    for start, end, label, side_a, side_b in ARROWS:
        a = _anchor(BOXES[start], side_a)
        b = _anchor(BOXES[end], side_b)
        ax.add_patch(FancyArrowPatch(a, b, arrowstyle="-|>", mutation_scale=18, lw=1.6, color="#1f4e79"))
        middle = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
        vertical = side_a in ("top", "bottom")
        ax.text(
            middle[0] + (0.1 if vertical else 0),
            middle[1] + (0 if vertical else 0.15),
            label,
            ha="left" if vertical else "center",
            va="center" if vertical else "bottom",
            fontsize=9,
            color="#1f4e79",
        )
    ax.set_title("Motion-sensing teleoperation: packages and the path of a hand frame", fontsize=15)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    plt.close(fig)
    return buffer.getvalue()


def main(argv) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when the committed PNG is stale")
    parser.add_argument("--output", default=PNG, help="PNG to write (default: docs/architecture.png)")
    args = parser.parse_args(argv)
    image = draw()
    if args.check:
        try:
            with open(args.output, "rb") as stream:
                stale = stream.read() != image
        except FileNotFoundError:
            stale = True
        if stale:
            print(f"{args.output} is stale: run .venv/bin/python scripts/gen_architecture.py", file=sys.stderr)
        return 1 if stale else 0
    from motion_common.atomic_file import write_atomic

    print(f"wrote {write_atomic(args.output, image)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
