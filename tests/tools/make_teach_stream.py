#!/usr/bin/env python3
"""Builds the teach demo's hand stream (src/motion_apps/data/teach_demo.jsonl.gz) from real
Leap Motion frames.

The stream is a Leap v6 recording (what a Leap service sends) of an operator teaching a
pick-and-place by gesture, for the cell of src/motion_apps/config/teach_scene.yaml:
hold still over the start, move above the part, hold, descend, hold, make a FIST (grip),
lift, hold, carry to above the place, hold, descend, hold, OPEN the hand (release), lift,
hold, rise clear of the cell, then PINCH and draw a CIRCLE (save), and leave.

Every frame is a real frame of tests/data/{grab,pinch,Waiting-110fps}.jsonl.gz (Leap
Motion's leapjs-playback recordings, Apache-2.0, see tests/data/README.md): its hand
shape (grabStrength, pinchStrength, palm normal and direction, fingers, confidence) is
kept as recorded, closing and opening sequences play in recorded order, a held fist or
pinch goes back and forth through the recording's fully closed frames (a shape held again
goes on where it stopped). Only the palm's slow path is
replaced: palmPosition = the designed path + the source frame's own tremor (its palm
minus its 0.3 s moving average), and every finger position moves with the palm. The hand
id is made constant (one hand throughout) and frames are re-stamped at 110 fps.

Where two frames that follow each other in the stream are not neighbours in their
recording (a pool made of two stretches, a shape starting), their tremors differ by up to
14 mm: a palm that teleports in 9 ms, which no hand does and which the core turned into a
jumping command. There the tremor continues from the frame before and the difference
fades out over ``SEAM_S`` (a minimum-jerk ease), so the palm's path stays one a hand can
make. A pool is not cycled round (its last frame to its first: the 14 mm seams were
those) but played back and forth, so that a held hand stays as still as it was recorded.

Run: .venv/bin/python tests/tools/make_teach_stream.py [--output PATH] (deterministic).
"""

import argparse
import gzip
import json
import os

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DATA = os.path.join(ROOT, "tests", "data")
OUTPUT = os.path.join(ROOT, "src", "motion_apps", "data", "teach_demo.jsonl.gz")
FPS = 110.0
# REP 103 (x forward, y left, z up) -> Leap (x right, y up, z toward the operator), mm.
REP103_TO_LEAP = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]]) * 1000.0
HAND_ORIGIN_LEAP = np.array([0.0, 200.0, 0.0])  # mm, where the palm starts above the device
POINT_KEYS = (
    "tipPosition",
    "dipPosition",
    "pipPosition",
    "mcpPosition",
    "btipPosition",
    "carpPosition",
    "stabilizedTipPosition",
)
HAND_KEYS = ("palmPosition", "stabilizedPalmPosition", "sphereCenter")

# Tool displacements from the engage pose (m, robot base = device axes, speed_ratio 1):
# the tool starts at the UR5e home (-0.492, -0.133, 0.488); the part's top is at z 0.23
# at (-0.50, -0.20); the place is (-0.45, 0.10) on the same table.
START = np.array([-0.492, -0.133, 0.488])
ABOVE_PART = np.array([-0.50, -0.20, 0.33]) - START
AT_PART = np.array([-0.50, -0.20, 0.238]) - START
ABOVE_PLACE = np.array([-0.45, 0.10, 0.33]) - START
AT_PLACE = np.array([-0.45, 0.10, 0.240]) - START
SAVE_POINT = np.array([-0.45, 0.10, 0.46]) - START  # clear above the cell: the circle stays off the table

# (shape, seconds, displacement at the end of the segment or None to stay).
# Shapes: open, fist, closing, opening, pinch, pinching, unpinching.
SCRIPT = [
    ("open", 2.0, None),  # enter, engage, hold still: waypoint at the start
    ("open", 1.6, ABOVE_PART),
    ("open", 1.6, None),  # hold: waypoint above the part
    ("open", 1.4, AT_PART),
    ("open", 1.6, None),  # hold: waypoint at the part
    ("closing", None, None),  # the grab recording's hand closing
    ("fist", 0.8, None),  # fist held: grip
    ("fist", 1.2, ABOVE_PART),
    ("fist", 1.6, None),  # hold: waypoint (lifted)
    ("fist", 1.8, ABOVE_PLACE),
    ("fist", 1.6, None),  # hold: waypoint above the place
    ("fist", 1.4, AT_PLACE),
    ("fist", 1.4, None),  # hold: waypoint at the place
    ("opening", None, None),  # the grab recording's hand opening
    ("open", 1.2, None),  # open palm held: release
    ("open", 1.2, ABOVE_PLACE),
    ("open", 1.6, None),  # hold: waypoint (retreat)
    ("open", 1.2, SAVE_POINT),  # up and clear of the cell before drawing
    ("pinching", None, None),  # the pinch recording's fingers closing
    ("circle", 1.1, None),  # pinch held while drawing a circle: save
    ("unpinching", None, None),
    ("open", 0.3, None),  # and the hand leaves
]
CIRCLE_RADIUS = 0.06  # m
# s over which a seam's tremor difference fades: the largest, 14 mm, moves the palm at
# 0.09 m/s at most (minimum jerk), a change of its per-frame move of 0.2 mm at most
SEAM_S = 0.3
SEAM_FRAMES = int(round(SEAM_S * FPS))


def read_frames(name):
    """The hand frames of a tests/data recording (first hand of each)."""
    frames = []
    with gzip.open(os.path.join(DATA, name), "rt", encoding="utf-8") as stream:
        for line in stream:
            obj = json.loads(line)
            if obj.get("hands"):
                frames.append(obj)
    return frames


def tremor(frames, window_s=0.3):
    """Each frame's palm minus its moving average (mm): the hand's real jitter, no drift."""
    palms = np.array([f["hands"][0]["palmPosition"] for f in frames], dtype=float)
    half = max(1, int(window_s * FPS / 2))
    smooth = np.array([palms[max(0, i - half) : i + half + 1].mean(axis=0) for i in range(len(palms))])
    return palms - smooth


def select(frames, keep, margin=int(0.3 * FPS / 2)):
    """The frames whose hand ``keep`` takes, but those within half the tremor's window of
    the recording's ends, where the moving average is cut short and the "tremor" is the
    hand's motion (up to 13 mm)."""
    return [i for i, f in enumerate(frames) if margin <= i < len(frames) - margin and keep(f["hands"][0])]


def min_jerk(fraction):
    f = np.clip(fraction, 0.0, 1.0)
    return 10 * f**3 - 15 * f**4 + 6 * f**5


class Sources:
    """Pools of real frames by hand shape, with their tremor."""

    def __init__(self):
        self.recordings = {name: read_frames(name + ".jsonl.gz") for name in ("grab", "pinch", "Waiting-110fps")}
        self.tremors = {name: tremor(frames) for name, frames in self.recordings.items()}
        grab, pinch = self.recordings["grab"], self.recordings["pinch"]
        grab_t = np.array([f["timestamp"] for f in grab]) * 1e-6
        grab_t -= grab_t[0]
        pinch_t = np.array([f["timestamp"] for f in pinch]) * 1e-6
        pinch_t -= pinch_t[0]
        span = lambda t, a, b: [i for i in range(len(t)) if a <= t[i] <= b]  # noqa: E731
        self.pools = {
            "open": [
                ("grab", i) for i in select(grab, lambda h: h["grabStrength"] <= 0.02 and h["pinchStrength"] <= 0.02)
            ],
            "fist": [("grab", i) for i in select(grab, lambda h: h["grabStrength"] >= 0.98)],
            "closing": [("grab", i) for i in span(grab_t, 0.25, 0.63)],
            "opening": [("grab", i) for i in span(grab_t, 1.08, 1.49)],
            "pinching": [("pinch", i) for i in span(pinch_t, 0.60, 1.40)],
            "circle": [("pinch", i) for i in select(pinch, lambda h: h["pinchStrength"] >= 0.98)],
            "unpinching": [("pinch", i) for i in span(pinch_t, 1.94, 2.46)],
        }
        for name, pool in self.pools.items():
            if not pool:
                raise SystemExit(f"no source frames for shape {name!r}")

    def frame(self, shape, k):
        """The k-th frame of a shape's pool, its tremor (mm) and where it comes from,
        (recording, index). A pool played longer than it lasts goes back and forth through
        it (the frame after its last is the one before its last, a neighbour), not round
        to its first."""
        pool = self.pools[shape]
        turn = max(1, 2 * (len(pool) - 1))
        k %= turn
        recording, index = pool[k if k < len(pool) else turn - k]
        return self.recordings[recording][index], self.tremors[recording][index], (recording, index)


class SeamlessTremor:
    """The tremors of a sequence of source frames, continuous where consecutive frames are
    not neighbours in their recording: there the tremor goes on from the frame before and
    the difference fades out over ``SEAM_S`` (see the module's docstring)."""

    def __init__(self, fade_frames=SEAM_FRAMES):
        self.fade_frames = fade_frames
        self.previous = None  # (recording, index) of the previous frame
        self.last = np.zeros(3)  # the previous frame's tremor as sent
        self.carry = np.zeros(3)  # what the seam's difference adds, before its fade
        self.since = fade_frames  # frames since the last seam

    def __call__(self, jitter, origin):
        recording, index = origin
        if self.previous is not None and self.previous not in ((recording, index - 1), (recording, index + 1)):
            self.carry, self.since = self.last - jitter, 0
        fade = 1.0 - min_jerk(self.since / self.fade_frames)
        self.last = jitter + self.carry * fade
        self.previous, self.since = origin, self.since + 1
        return self.last


def build():
    """The stream's JSON lines (handshake first)."""
    sources = Sources()
    seamless = SeamlessTremor()
    played = dict.fromkeys(sources.pools, 0)  # frames of each pool played so far: a shape held again goes on
    lines = [json.dumps({"version": 6})]
    position = np.zeros(3)
    stamp_us, frame_id = 1_000_000.0, 1
    for shape, seconds, target in SCRIPT:
        count = len(sources.pools[shape]) if seconds is None else int(round(seconds * FPS))
        start = position.copy()
        for k in range(count):
            fraction = (k + 1) / count
            if target is not None:
                position = start + min_jerk(fraction) * (target - start)
            offset = position.copy()
            if shape == "circle":
                # Clockwise as the operator sees it, from the top, in the vertical y-z plane
                # (as the shipped circle templates): "right" is -y, "up" is +z.
                angle = np.pi / 2 - 2 * np.pi * min_jerk(fraction)
                offset = offset + CIRCLE_RADIUS * np.array([0.0, -np.cos(angle), np.sin(angle) - 1.0])
            source, jitter, origin = sources.frame(shape, played[shape])
            played[shape] += 1
            jitter = seamless(jitter, origin)
            lines.append(
                json.dumps(relocate(source, HAND_ORIGIN_LEAP + REP103_TO_LEAP @ offset + jitter, stamp_us, frame_id))
            )
            stamp_us += 1e6 / FPS
            frame_id += 1
    return lines


def relocate(frame, palm, stamp_us, frame_id):
    """A copy of ``frame`` with its first hand's palm at ``palm`` (mm), fingers moved along,
    hand id 1, and the given timestamp and frame id."""
    hand = json.loads(json.dumps(frame["hands"][0]))
    shift = palm - np.array(hand["palmPosition"], dtype=float)
    for key in HAND_KEYS:
        if key in hand:
            hand[key] = [round(float(v), 4) for v in np.array(hand[key], dtype=float) + shift]
    source_id, hand["id"], hand["type"] = hand["id"], 1, "right"
    pointables = []
    for pointable in frame.get("pointables", []):
        if pointable.get("handId") != source_id:
            continue
        pointable = dict(pointable, handId=1)
        for key in POINT_KEYS:
            if key in pointable:
                pointable[key] = [round(float(v), 4) for v in np.array(pointable[key], dtype=float) + shift]
        pointables.append(pointable)
    return {
        "id": frame_id,
        "timestamp": int(stamp_us),
        "currentFrameRate": FPS,
        "hands": [hand],
        "pointables": pointables,
        "gestures": [],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output", default=OUTPUT, help="where to write the .jsonl.gz (default: %(default)s)")
    args = parser.parse_args()
    lines = build()
    os.makedirs(os.path.dirname(args.output), exist_ok=True)
    with gzip.GzipFile(args.output, "wb", mtime=0) as stream:  # mtime 0: byte-identical reruns
        stream.write(("\n".join(lines) + "\n").encode("utf-8"))
    print(f"wrote {len(lines) - 1} frames ({(len(lines) - 1) / FPS:.1f} s) to {args.output}")


if __name__ == "__main__":
    main()
