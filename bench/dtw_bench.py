"""DTW registration on synthetic paths with a known transform: a 3D Lissajous hand path,
8-12 Hz tremor of about 0.5 mm, irregular timing (+-30% frame-gap jitter); the robot path
is the same shape, rotated, translated, scaled and performed at a different speed.

Run: bench/run dtw_bench [--trials 20]
Writes bench/results/dtw_bench.json. Goals: error <= 2 mm and <= 1 deg; <= 50 ms at 1000 frames.
"""

import argparse
import os
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from bench_common import write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_sensor"))
from motion_sensor.registration.device_registration import register  # noqa: E402


def shape(u):
    """A 3D Lissajous figure, metres, u in [0, 1]."""
    return np.column_stack(
        [0.10 * np.sin(2 * np.pi * u), 0.07 * np.sin(4 * np.pi * u + 0.5), 0.05 * np.sin(6 * np.pi * u + 1.0)]
    )


def irregular_times(n, duration, rng):
    gaps = rng.uniform(0.7, 1.3, n - 1)
    return np.concatenate([[0.0], np.cumsum(gaps)]) * duration / gaps.sum()


def trial(rng, frames):
    """One synthetic registration; returns (position error m, angle error deg, seconds)."""
    true_rotation = Rotation.random(random_state=rng.integers(1 << 31))
    true_translation = rng.uniform(-0.5, 0.5, 3)
    true_scale = rng.uniform(0.5, 2.0)
    hand_t = irregular_times(frames, 4.0, rng)
    robot_t = irregular_times(int(frames * rng.uniform(0.8, 1.2)), 4.0 * rng.uniform(1.5, 3.0), rng)
    # Speeds differ along the path too: the hand lingers where the robot does not.
    hand_u = (hand_t / hand_t[-1]) ** 1.3
    robot_u = robot_t / robot_t[-1]
    freq = rng.uniform(8, 12)
    tremor = 0.0005 * np.column_stack([np.sin(2 * np.pi * freq * hand_t + p) for p in rng.uniform(0, 6.3, 3)])
    hand = shape(hand_u) + tremor + rng.normal(0, 0.0001, (frames, 3))
    robot = true_scale * true_rotation.apply(shape(robot_u)) + true_translation
    start = time.perf_counter()
    result = register(hand, robot, hand_t, robot_t)
    elapsed = time.perf_counter() - start
    probe = shape(np.linspace(0, 1, 200))
    error = np.linalg.norm(result.apply(probe) - (true_scale * true_rotation.apply(probe) + true_translation), axis=1)
    angle = np.degrees((Rotation.from_matrix(result.rotation) * true_rotation.inv()).magnitude())
    return float(error.max()), float(angle), elapsed, abs(result.scale - true_scale) / true_scale


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--frames", type=int, default=1000)
    args = parser.parse_args()
    rng = np.random.default_rng(2026)
    rows = []
    for index in range(args.trials):
        rows.append(trial(rng, args.frames))
        print(
            f"[{index + 1}/{args.trials}] max error {rows[-1][0] * 1000:.3f} mm, angle {rows[-1][1]:.3f} deg, "
            f"{rows[-1][2] * 1000:.1f} ms",
            flush=True,
        )
    errors, angles, seconds, scale_errors = (np.array(c) for c in zip(*rows))
    results = {
        "frames": args.frames,
        "trials": args.trials,
        "max_position_error_mm": {
            "p50": round(float(np.median(errors)) * 1000, 3),
            "max": round(float(errors.max()) * 1000, 3),
        },
        "rotation_error_deg": {"p50": round(float(np.median(angles)), 4), "max": round(float(angles.max()), 4)},
        "relative_scale_error": {"max": round(float(scale_errors.max()), 5)},
        "time_ms": {
            "p50": round(float(np.median(seconds)) * 1000, 2),
            "p99": round(float(np.percentile(seconds, 99)) * 1000, 2),
        },
        "goals": {"error_mm": 2.0, "angle_deg": 1.0, "time_ms": 50.0},
    }
    write_results("dtw_bench", results)


if __name__ == "__main__":
    main()
