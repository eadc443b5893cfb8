#!/usr/bin/env python3
"""Webcam hand driver benchmark: MediaPipe Hands through WebcamHandTracker on moving
sequences made from real hand photos (tests/tools/hand_warp.py: handSrc.jpg and
Back_Projection_Theory0.jpg from Debian's opencv-doc, warped along seeded paths).

Per frame cost (BGR frame in, HandSample out: colour conversion, MediaPipe, palm maths),
p50/p99, in tracking mode (what the driver runs) and in static-image mode (detection on
every frame) measured in the same run as the baseline; detection rate; how well the palm
path follows the image motion (correlation of the reprojected palm pixel with the warp's
ground truth in x and y, RMS pixel error) and the depth from apparent size against
1/scale. Writes bench/results/webcam_hand_bench.json and webcam_hand_bench.png.

Run: bench/run webcam_hand_bench [--frames 150] [--seed 1]
"""

import argparse
import os
import sys
import time

import numpy as np

from bench_common import RESULTS, ROOT, write_results

for path in ("src/motion_common", "src/motion_sensor", "tests/tools"):
    sys.path.insert(0, os.path.join(ROOT, path))

from hand_warp import HEIGHT, PHOTOS, WIDTH, warped_sequence  # noqa: E402
from motion_sensor.devices.mediapipe_hands import MediaPipeHandDetector  # noqa: E402
from motion_sensor.devices.webcam_hand import WebcamHandTracker  # noqa: E402

FOCAL = 0.5 * WIDTH / np.tan(np.radians(60.0) / 2)  # the tracker's default hfov_deg


def run(sequence, static: bool):
    """Per-frame costs (ms), reprojected palm pixels (NaN without a hand), depths (m)."""
    tracker = WebcamHandTracker(MediaPipeHandDetector(static_image_mode=static))
    # Load both models outside the timing (tracking then starts from the first frame's hand,
    # as a live tracker would after its first frame).
    tracker.process(sequence.frames[0], 0.0)
    costs, pixels, depths = [], np.full((len(sequence.frames), 2), np.nan), np.full(len(sequence.frames), np.nan)
    for i, frame in enumerate(sequence.frames):
        start = time.perf_counter()
        sample = tracker.process(frame, i / 30.0)
        costs.append((time.perf_counter() - start) * 1e3)
        if sample.hands_num:
            x, y, z = sample.position
            pixels[i] = (WIDTH / 2 - FOCAL * y / x, HEIGHT / 2 - FOCAL * z / x)
            depths[i] = x
    return np.array(costs), pixels, depths


def path_figures(sequence, pixels, depths):
    """Detection rate and how the palm path follows the warp's ground truth."""
    found = np.isfinite(depths)
    if found.sum() < 3:
        return {"detection_rate": float(found.mean())}, None
    first = int(np.argmax(found))
    affine = np.vstack([sequence.transforms[first], [0, 0, 1]])
    truth = sequence.image_point(np.linalg.solve(affine, [*pixels[first], 1.0])[:2])
    product = depths[found] * sequence.scales[found]
    figures = {
        "detection_rate": round(float(found.mean()), 4),
        "corr_x": round(float(np.corrcoef(pixels[found, 0], truth[found, 0])[0, 1]), 4),
        "corr_y": round(float(np.corrcoef(pixels[found, 1], truth[found, 1])[0, 1]), 4),
        "rms_px": round(float(np.sqrt(np.mean(np.sum((pixels[found] - truth[found]) ** 2, axis=1)))), 2),
        "corr_depth_inverse_scale": round(float(np.corrcoef(depths[found], 1 / sequence.scales[found])[0, 1]), 4),
        "depth_times_scale_cv": round(float(np.std(product) / np.mean(product)), 4),
    }
    return figures, truth


def plot(panels, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(panels), 3, figsize=(13, 3.4 * len(panels)), squeeze=False)
    for row, (name, sequence, pixels, depths, truth) in enumerate(panels):
        frames = np.arange(len(depths))
        for col, label in enumerate(("x (px)", "y (px)")):
            ax = axes[row, col]
            ax.plot(frames, truth[:, col], "k-", lw=2, alpha=0.4, label="image motion (warp)")
            ax.plot(frames, pixels[:, col], "r.", ms=3, label="palm (reprojected)")
            ax.set_title(f"{name}: palm {label}")
            ax.set_xlabel("frame")
            ax.legend(fontsize=7)
        ax = axes[row, 2]
        found = np.isfinite(depths)
        reference = np.median(depths[found] * sequence.scales[found])
        ax.plot(frames, reference / sequence.scales, "k-", lw=2, alpha=0.4, label="median(depth*scale) / scale")
        ax.plot(frames, depths, "b.", ms=3, label="depth from apparent size")
        ax.set_title(f"{name}: depth (m, uncalibrated)")
        ax.set_xlabel("frame")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=150, help="frames per sequence (default 150)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the warp paths (default 1)")
    args = parser.parse_args()
    results = {"frames_per_sequence": args.frames, "seed": args.seed, "frame_size": [WIDTH, HEIGHT], "sequences": {}}
    costs = {"tracking": [], "static": []}
    panels = []
    for k, name in enumerate(PHOTOS):
        sequence = warped_sequence(name, frames=args.frames, seed=args.seed + k, period_frames=args.frames / 2)
        entry = {}
        for mode in ("tracking", "static"):
            cost, pixels, depths = run(sequence, static=(mode == "static"))
            costs[mode].append(cost)
            figures, truth = path_figures(sequence, pixels, depths)
            entry[mode] = {
                "cost_ms_p50": round(float(np.percentile(cost, 50)), 2),
                "cost_ms_p99": round(float(np.percentile(cost, 99)), 2),
                **figures,
            }
            if mode == "tracking" and truth is not None:
                panels.append((name, sequence, pixels, depths, truth))
            print(
                f"{name:24s} {mode:8s} cost p50 {entry[mode]['cost_ms_p50']:6.2f} ms  p99 "
                f"{entry[mode]['cost_ms_p99']:6.2f} ms  found {figures['detection_rate']:.1%}  "
                f"corr x/y {figures.get('corr_x', float('nan')):.3f}/{figures.get('corr_y', float('nan')):.3f}  "
                f"rms {figures.get('rms_px', float('nan')):.1f} px  depth corr "
                f"{figures.get('corr_depth_inverse_scale', float('nan')):.3f}"
            )
        results["sequences"][name] = entry
    for mode in costs:
        all_costs = np.concatenate(costs[mode])
        results[f"{mode}_cost_ms_p50"] = round(float(np.percentile(all_costs, 50)), 2)
        results[f"{mode}_cost_ms_p99"] = round(float(np.percentile(all_costs, 99)), 2)
    results["static_over_tracking_p50"] = round(results["static_cost_ms_p50"] / results["tracking_cost_ms_p50"], 2)
    png = os.path.join(RESULTS, "webcam_hand_bench.png")
    os.makedirs(RESULTS, exist_ok=True)
    plot(panels, png)
    results["plot"] = os.path.relpath(png, ROOT)
    write_results("webcam_hand_bench", results, show=False)
    print(f"=== webcam hand bench ({args.frames} frames x {len(PHOTOS)} sequences, 640x480) ===")
    print(f"tracking mode  p50 / p99 : {results['tracking_cost_ms_p50']} / {results['tracking_cost_ms_p99']} ms")
    print(
        f"static mode    p50 / p99 : {results['static_cost_ms_p50']} / {results['static_cost_ms_p99']} ms "
        f"(x{results['static_over_tracking_p50']} of tracking, same run)"
    )
    print(f"plot                     : {png}")


if __name__ == "__main__":
    main()
