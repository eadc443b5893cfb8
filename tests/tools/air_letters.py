"""Synthetic air-written letters: 26 single-stroke letters (A-Z) as control polylines in a
unit box, performed by synthetic "subjects" with their own style (size, slant, aspect,
plane tilt, speed profile, corner rounding) and per-performance variation (control-point
jitter, tremor, depth drift, frame-time jitter). Output like a Leap fingertip: x right,
y up, z toward the user, millimetres, times in ms. Seeded: same seed, same data.

Used by bench/gesture_bench.py (26 classes, 200+ templates, <= 5 ms goal) and the unit
tests. This is not real data: it checks speed and plumbing, not the accuracy one would
get on real air writing.
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


def subject_style(rng):
    """One synthetic writer's style."""
    return {"size": rng.uniform(60, 160), "aspect": rng.uniform(0.75, 1.3), "slant": rng.uniform(-0.25, 0.25),
            "tilt": rng.uniform(-0.35, 0.35), "yaw": rng.uniform(-0.3, 0.3), "speed": rng.uniform(0.25, 0.6),
            "rounding": int(rng.integers(3, 9)), "jitter": rng.uniform(0.02, 0.06)}


def perform(letter, style, rng, rate_hz=None):
    """One performance: (points n x 3 mm in Leap axes, times n ms)."""
    ctrl = np.array(LETTERS[letter], dtype=float)
    ctrl = ctrl + rng.normal(0, style["jitter"], ctrl.shape)
    dense = _polyline(ctrl, 200)
    width = style["rounding"] * 2 + 1  # corner rounding: moving average
    padded = np.pad(dense, ((width // 2, width // 2), (0, 0)), mode="edge")
    dense = np.column_stack([np.convolve(padded[:, i], np.ones(width) / width, "valid") for i in range(2)])
    x = (dense[:, 0] - 0.5) * style["aspect"] + style["slant"] * (dense[:, 1] - 0.5)
    y = dense[:, 1] - 0.5
    size = style["size"] * rng.uniform(0.85, 1.15)
    xyz = np.column_stack([x, y, np.zeros_like(x)]) * size
    # The writing plane is tilted and turned a little, and the finger drifts in depth.
    t, w = style["tilt"] + rng.normal(0, 0.05), style["yaw"] + rng.normal(0, 0.05)
    rx = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    ry = np.array([[np.cos(w), 0, np.sin(w)], [0, 1, 0], [-np.sin(w), 0, np.cos(w)]])
    xyz = xyz @ (ry @ rx).T
    xyz[:, 2] += np.linspace(0, rng.normal(0, 10), len(xyz))
    length = np.sum(np.linalg.norm(np.diff(xyz, axis=0), axis=1))
    duration = length / (style["speed"] * rng.uniform(0.8, 1.25))  # mm / (mm/ms)
    rate = rate_hz or rng.uniform(60, 120)
    n = max(12, int(duration * rate / 1000.0))
    # Uneven speed along the stroke (slow at the ends), frame-time jitter.
    u = np.linspace(0, 1, n)
    u = u + rng.uniform(0.02, 0.08) * np.sin(2 * np.pi * u) / (2 * np.pi)
    u = np.clip((u - u[0]) / (u[-1] - u[0]), 0, 1)
    s = 0.5 - 0.5 * np.cos(np.pi * u)
    index = s * (len(xyz) - 1)
    path = np.column_stack([np.interp(index, np.arange(len(xyz)), xyz[:, i]) for i in range(3)])
    path += rng.normal(0, 0.6, path.shape)  # tracking noise, mm
    times = np.cumsum(np.concatenate([[0.0], rng.uniform(0.7, 1.3, n - 1) * 1000.0 / rate]))
    offset = rng.uniform([-80, 150, -60], [80, 300, 60])
    return path + offset, times


def dataset(subjects, repetitions=1, seed=0, letters=None):
    """{subject id: [(label, points, times), ...]} for subject ids in ``subjects``."""
    letters = letters or sorted(LETTERS)
    out = {}
    for subject in subjects:
        rng = np.random.default_rng([seed, subject])
        style = subject_style(rng)
        out[subject] = [(letter, *perform(letter, style, rng)) for letter in letters for _ in range(repetitions)]
    return out
