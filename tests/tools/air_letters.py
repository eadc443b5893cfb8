"""Synthetic air-written letters, a HARD user-independent set: 26 single-stroke letters
(A-Z) written in the air with the index fingertip, as a Leap Motion reports it (x right,
y up, z toward the user; millimetres; times in ms). Seeded: same seed, same data.

Glyph set (``LETTERS``): one unistroke control polyline per letter in a unit box, y up,
in the spirit of Palm Graffiti / air-writing unistrokes: letters needing several strokes
are written as one continuous path that retraces or jumps through the air (E, F, H, K,
T, X, Y retrace; A adds the bar after the right leg, B/P/R start at the bottom of the
stem, D/O/Q close on themselves). Several pairs are close on purpose (O/Q/D, U/V, P/R/B,
C/G, M/W upside down, N/Z mirrored, E/F, I/L/T).

Variation, per subject (the writer's style) and per repetition (how they wrote it that
time); a subject also keeps a personal version of each letter (persistent control-point
offsets), which is what makes the set user-independent rather than just noisy:

* glyph: control-point jitter, a smooth random warp of the whole glyph (sum of
  low-frequency sinusoidal displacement fields), corner rounding (moving average);
* writing style: size 40-180 mm, aspect 0.7-1.4, slant (shear) +-0.35, rotation in the
  writing plane +-14 deg;
* writing plane: tilted in 3-D (pitch +-35 deg, yaw +-35 deg per subject, +-8 deg per
  repetition), bowed (the fingertip moves on an arc about the elbow), depth drift;
* motion: speed profile that slows at corners (curvature-dependent) plus a smooth random
  time warp, pauses at some corners, lead-in and lead-out hooks (the finger arrives at
  the start and leaves the end with a short curl, partly in depth), physiological tremor
  (8-12 Hz) and tracking noise;
* sampling: 50-120 Hz per subject, frame-time jitter, dropped frames (isolated and bursts).

``difficulty`` (default 1.0) scales the per-subject and per-repetition variation; at 1.0
the plain baseline (centred and scaled 3-D DTW 1-NN, dtaidistance, no resampling, no
window) scores about 93-97 % on 10 train / 10 test subjects, 1 repetition each (see
bench/results/gesture_bench.json). Not real data: a harder stand-in, still synthetic.
"""

import numpy as np

# Unistroke control points (x, y) in [0, 1]^2, y up; one stroke per letter.
LETTERS = {
    "A": [(0, 0), (0.5, 1), (1, 0), (0.75, 0.5), (0.25, 0.5)],
    "B": [(0, 0), (0, 1), (0.7, 0.95), (0.75, 0.6), (0, 0.5), (0.85, 0.4), (0.8, 0.05), (0, 0)],
    "C": [(1, 0.9), (0.5, 1), (0.05, 0.7), (0.05, 0.3), (0.5, 0), (1, 0.1)],
    "D": [(0, 0), (0, 1), (0.6, 0.95), (1, 0.5), (0.6, 0.05), (0, 0)],
    "E": [(1, 1), (0, 1), (0, 0.5), (0.7, 0.5), (0, 0.5), (0, 0), (1, 0)],
    "F": [(1, 1), (0, 1), (0, 0.5), (0.7, 0.5), (0, 0.5), (0, 0)],
    "G": [(1, 0.9), (0.5, 1), (0.05, 0.6), (0.3, 0.05), (0.9, 0.1), (1, 0.45), (0.55, 0.45)],
    "H": [(0, 1), (0, 0), (0, 0.5), (1, 0.5), (1, 1), (1, 0)],
    "I": [(0.5, 1), (0.5, 0)],
    "J": [(1, 1), (1, 0.2), (0.6, 0), (0.2, 0.05), (0, 0.3)],
    "K": [(0, 1), (0, 0), (0, 0.45), (1, 1), (0.2, 0.55), (1, 0)],
    "L": [(0, 1), (0, 0), (1, 0)],
    "M": [(0, 0), (0, 1), (0.5, 0.4), (1, 1), (1, 0)],
    "N": [(0, 0), (0, 1), (1, 0), (1, 1)],
    "O": [(0.5, 1), (0.05, 0.75), (0.05, 0.25), (0.5, 0), (0.95, 0.25), (0.95, 0.75), (0.5, 1)],
    "P": [(0, 0), (0, 1), (0.7, 0.95), (0.9, 0.75), (0.7, 0.5), (0, 0.5)],
    "Q": [(0.5, 1), (0.05, 0.7), (0.2, 0.05), (0.8, 0.05), (0.95, 0.7), (0.5, 1), (0.4, 0.4), (1, 0)],
    "R": [(0, 0), (0, 1), (0.7, 0.95), (0.9, 0.75), (0.7, 0.5), (0, 0.5), (1, 0)],
    "S": [(1, 0.9), (0.5, 1), (0.05, 0.8), (0.5, 0.5), (0.95, 0.2), (0.5, 0), (0, 0.1)],
    "T": [(0, 1), (1, 1), (0.5, 1), (0.5, 0)],
    "U": [(0, 1), (0, 0.3), (0.3, 0), (0.7, 0), (1, 0.3), (1, 1)],
    "V": [(0, 1), (0.5, 0), (1, 1)],
    "W": [(0, 1), (0.25, 0), (0.5, 0.6), (0.75, 0), (1, 1)],
    "X": [(0, 1), (1, 0), (1, 1), (0, 0)],
    "Y": [(0, 1), (0.5, 0.5), (1, 1), (0.5, 0.5), (0.5, 0)],
    "Z": [(0, 1), (1, 1), (0, 0), (1, 0)],
}


def _polyline(points, count):
    """``count`` points evenly spaced along a polyline."""
    points = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    axis = np.concatenate([[0.0], np.cumsum(seg)])
    target = np.linspace(0, axis[-1], count)
    return np.column_stack([np.interp(target, axis, points[:, i]) for i in range(points.shape[1])])


def _smooth(points, width):
    if width <= 1:
        return points
    padded = np.pad(points, ((width // 2, width // 2), (0, 0)), mode="edge")
    kernel = np.ones(width) / width
    return np.column_stack([np.convolve(padded[:, i], kernel, "valid") for i in range(points.shape[1])])


def _rotation(pitch, yaw, roll=0.0):
    rx = np.array([[1, 0, 0], [0, np.cos(pitch), -np.sin(pitch)], [0, np.sin(pitch), np.cos(pitch)]])
    ry = np.array([[np.cos(yaw), 0, np.sin(yaw)], [0, 1, 0], [-np.sin(yaw), 0, np.cos(yaw)]])
    rz = np.array([[np.cos(roll), -np.sin(roll), 0], [np.sin(roll), np.cos(roll), 0], [0, 0, 1]])
    return ry @ rx @ rz


def _warp_field(rng, amplitude, terms=3):
    """A smooth random displacement field on the unit square (sum of sinusoids)."""
    freq = rng.uniform(0.5, 1.6, (terms, 2, 2))
    phase = rng.uniform(0, 2 * np.pi, (terms, 2))
    amp = rng.normal(0, amplitude / np.sqrt(terms), (terms, 2))

    def warp(xy):
        out = xy.copy()
        for k in range(terms):
            for axis in range(2):
                arg = np.pi * (freq[k, axis, 0] * xy[:, 0] + freq[k, axis, 1] * xy[:, 1]) + phase[k, axis]
                out[:, axis] += amp[k, axis] * np.sin(arg)
        return out

    return warp


# Internal scale of the variation at difficulty 1.0: chosen so that the plain baseline lands
# at 93-97 % (measured with difficulty 0.6 / 0.65 / 0.72 / 0.8 / 1.0 on seed 2026, 10 vs 10
# subjects, 1 repetition: baseline 96.5 / 94 / 94 / 85 / 81 %).
CALIBRATION = 0.65


def subject_style(rng, difficulty=1.0):
    """One synthetic writer's style (see the module docstring)."""
    d = difficulty * CALIBRATION
    return {
        "size": rng.uniform(40, 180),
        "aspect": np.exp(rng.uniform(-0.35, 0.35) * d),
        "slant": rng.uniform(-0.35, 0.35) * d,
        "roll": rng.uniform(-0.25, 0.25) * d,
        "pitch": rng.uniform(-0.6, 0.6) * d,
        "yaw": rng.uniform(-0.6, 0.6) * d,
        "bow": rng.uniform(0.0, 0.004) * d,
        "speed": rng.uniform(0.2, 0.7),
        "corner_slow": rng.uniform(0.5, 4.0),
        "pause_prob": rng.uniform(0.0, 0.4),
        "pause_ms": rng.uniform(60, 250),
        "rounding": int(rng.integers(2, 12)),
        "jitter": rng.uniform(0.02, 0.05) * d,
        "warp": rng.uniform(0.03, 0.09) * d,
        "hook": rng.uniform(0.0, 0.25) * d,
        "tremor": rng.uniform(0.2, 1.2),
        "rate": rng.uniform(50, 120),
        "drop": rng.uniform(0.0, 0.06),
        "personal": {},  # per-letter persistent control-point offsets, filled lazily
        "personal_scale": rng.uniform(0.02, 0.06) * d,
    }


def _personal(letter, style, rng_subject):
    if letter not in style["personal"]:
        n = len(LETTERS[letter])
        style["personal"][letter] = (
            rng_subject.normal(0, style["personal_scale"], (n, 2)),
            _warp_field(rng_subject, style["warp"]),
        )
    return style["personal"][letter]


def perform(letter, style, rng, rate_hz=None, difficulty=1.0, personal=None):
    """One performance: (points n x 3 mm in Leap axes, times n ms)."""
    d = difficulty * CALIBRATION
    offsets, personal_warp = personal if personal is not None else (0.0, lambda xy: xy)
    ctrl = np.array(LETTERS[letter], dtype=float) + offsets
    ctrl = ctrl + rng.normal(0, style["jitter"], ctrl.shape)
    dense = _polyline(ctrl, 240)
    dense = personal_warp(dense)
    dense = _warp_field(rng, 0.5 * style["warp"])(dense)
    dense = _smooth(dense, 2 * max(1, style["rounding"] + int(rng.integers(-1, 2))) + 1)
    # Lead-in / lead-out hooks: the finger curls into the first point and out of the last.
    scale = style["hook"] * rng.uniform(0.3, 1.2)
    parts = [dense]
    hook_depth = []
    for end in (0, 1):
        if rng.random() < 0.8 and scale > 0.01:
            m = int(20 + 40 * scale)
            ang = rng.uniform(0, 2 * np.pi)
            tip = dense[-1] if end else dense[0]
            arc = np.linspace(0, 1, m)[:, None]
            curl = np.column_stack([np.cos(ang + 1.5 * arc[:, 0]), np.sin(ang + 1.5 * arc[:, 0])])
            hook = tip + scale * arc * curl
            hook = hook[::-1] if end == 0 else hook
            parts = [hook[:-1]] + parts if end == 0 else parts + [hook[1:]]
            hook_depth.append((end, m - 1, rng.normal(0, 0.6) * scale))
    xy = np.vstack(parts)
    depth = np.zeros(len(xy))
    for end, m, dz in hook_depth:  # hooks also move toward/away from the user
        ramp = np.linspace(1, 0, m) if end == 0 else np.linspace(0, 1, m)
        if end == 0:
            depth[:m] += dz * ramp
        else:
            depth[-m:] += dz * ramp
    # Writing style in the plane: aspect, slant, rotation, size.
    x = (xy[:, 0] - 0.5) * style["aspect"] + style["slant"] * (xy[:, 1] - 0.5)
    y = xy[:, 1] - 0.5
    size = style["size"] * rng.uniform(0.8, 1.2)
    xyz = np.column_stack([x, y, depth]) * size
    # Writing plane: tilted per subject and per repetition, bowed, drifting in depth.
    rot = _rotation(
        style["pitch"] + rng.normal(0, 0.14 * d),
        style["yaw"] + rng.normal(0, 0.14 * d),
        style["roll"] + rng.normal(0, 0.08 * d),
    )
    xyz = xyz @ rot.T
    xyz[:, 2] -= style["bow"] * (xyz[:, 0] ** 2 + 0.5 * xyz[:, 1] ** 2)
    drift = np.linspace(0, 1, len(xyz))
    xyz[:, 2] += rng.normal(0, 12 * d) * drift + rng.normal(0, 8 * d) * drift**2
    xyz[:, 1] += rng.normal(0, 5 * d) * drift
    # Speed along the stroke: slower at corners, smooth random time warp, corner pauses.
    step = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    direction = np.diff(xyz, axis=0) / np.maximum(step[:, None], 1e-9)
    turn = np.concatenate([[0.0], np.arccos(np.clip(np.sum(direction[1:] * direction[:-1], axis=1), -1, 1)), [0.0]])
    turn = _smooth(turn[:, None], 9)[:, 0]
    u = np.linspace(0, 1, len(xyz))
    warp = np.exp(
        0.5 * d * sum(rng.normal(0, 0.5) * np.sin((k + 1) * np.pi * u + rng.uniform(0, 6.3)) for k in range(3))
    )
    speed = style["speed"] * rng.uniform(0.75, 1.3) * warp / (1.0 + style["corner_slow"] * turn * 8.0)
    speed *= np.clip(np.minimum(u, 1 - u) * 12 + 0.3, 0.3, 1.0)  # accelerate / decelerate
    seg_speed = 0.5 * (speed[1:] + speed[:-1])
    dt = step / np.maximum(seg_speed, 1e-3)  # ms
    corners = np.where(turn[1:] > 0.15)[0]
    for c in corners:
        if rng.random() < style["pause_prob"] * 0.15:
            dt[c] += style["pause_ms"] * rng.uniform(0.3, 1.0)
    t_curve = np.concatenate([[0.0], np.cumsum(dt)])
    # Sampling: the device's rate, frame-time jitter, dropped frames.
    rate = rate_hz or style["rate"] * rng.uniform(0.95, 1.05)
    period = 1000.0 / rate
    n = max(12, int(t_curve[-1] / period))
    times = np.arange(n) * period + rng.uniform(-0.15, 0.15, n) * period
    times = np.clip(np.sort(times), 0, t_curve[-1])
    path = np.column_stack([np.interp(times, t_curve, xyz[:, i]) for i in range(3)])
    # Tremor (8-12 Hz, a random direction per axis) and tracking noise.
    f = rng.uniform(8, 12)
    tremor = np.sin(2 * np.pi * f * times[:, None] / 1000.0 + rng.uniform(0, 6.3, 3)) * rng.normal(0, 1, 3)
    path += style["tremor"] * tremor + rng.normal(0, 0.4, path.shape)
    keep = rng.random(n) >= style["drop"]
    if rng.random() < 0.3 * d and n > 30:  # a burst of lost frames
        start = int(rng.integers(5, n - 10))
        keep[start : start + int(rng.integers(2, 6))] = False
    keep[[0, -1]] = True
    path, times = path[keep], times[keep]
    offset = rng.uniform([-80, 150, -60], [80, 300, 60])
    return path + offset, times - times[0]


def dataset(subjects, repetitions=1, seed=0, letters=None, difficulty=1.0):
    """{subject id: [(label, points, times), ...]} for subject ids in ``subjects``,
    ``repetitions`` performances of each letter per subject."""
    letters = letters or sorted(LETTERS)
    out = {}
    for subject in subjects:
        rng = np.random.default_rng([seed, subject])
        style = subject_style(rng, difficulty)
        rng_personal = np.random.default_rng([seed, subject, 1])
        items = []
        for letter in letters:
            personal = _personal(letter, style, rng_personal)
            for _ in range(repetitions):
                items.append((letter, *perform(letter, style, rng, difficulty=difficulty, personal=personal)))
        out[subject] = items
    return out
