"""Depth hand tracker: per-frame cost at 640x480 and palm position error on rendered depth
images of a hand with its forearm moving along a known 3-D path (motion_sensor.
synthetic_depth, Kinect-like noise sigma = 1.5 mm * z^2, millimetre quantisation).

Per frame = what depth_hand_driver does with one image: decode the 16UC1 bytes to metres
and track (blob, distance transform, back-projection, axes). Baseline in the same run:
cv2.distanceTransform alone on the full 640x480 in-volume mask of the same images (the one
image-wide operation the method cannot do without). Position error: RMS distance between
the tracked palm and the true palm centre after removing their mean difference (the seen
palm surface lies a constant half palm thickness in front of the centre).

Real hand motion (``real_motion`` in the results; skipped without ../shared): the SHREC'17
training skeletons of a fixed, seeded subset (bench/shrec_hands.py: subjects split in half,
a tuning set and a held-out evaluation set, two sequences of different gestures per subject)
rendered by an independent hand model built from each skeleton
(motion_sensor.testing.skeleton_depth: capsules, a palm slab, a forearm, Kinect-like noise,
quantisation and dropout at silhouettes) and tracked frame by frame, the tracker reset at
each sequence. Truth: SHREC's palm centre joint. Errors are given three ways: per sequence
after removing that sequence's mean difference (the goal's figure: a rigid alignment, as a
teleoperation clutch makes every motion relative), after removing one offset over all
frames, and raw. A hand frame is one whose palm centre lies in the image and the working
volume; found = tracked in such a frame. For scale, a naive nearest-blob tracker on the same
frames: the 3-D centroid of the pixels within 10 cm behind the 4th nearest one.
``--reference FILE`` also runs another version of depth_hand.py (e.g. the one before a
change, ``git show REV:src/motion_sensor/motion_sensor/devices/depth_hand.py > FILE``) on
every frame of both parts, timed alongside, for before/after figures from one run.

Run: bench/run depth_hand_bench [--frames 300] [--seed 1] [--noise 0.0015] [--reference FILE]
Writes bench/results/depth_hand_bench.json and depth_hand_path.png.
"""

import argparse
import importlib.util
import os
import sys
import time

import numpy as np

import shrec_hands
from bench_common import RESULTS, ROOT, write_results

for package in ("motion_sensor", "motion_common"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))

import cv2  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from motion_sensor.devices.depth_hand import OPTICAL_TO_BODY, TRACKER_PARAMS, DepthHandTracker  # noqa: E402
from motion_sensor.devices.depth_image import decode_depth, encode_depth_mm  # noqa: E402
from motion_sensor.testing.skeleton_depth import PALM, render_skeleton  # noqa: E402
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR  # noqa: E402
from motion_sensor.testing.synthetic_depth import hand_path, render_hand  # noqa: E402

TRACKER_DEFAULTS = TRACKER_PARAMS.defaults()
NEAREST_BAND_M = 0.10  # the nearest-blob baseline's band behind the nearest pixel


def stats_ms(samples):
    ms = np.asarray(samples) * 1e3
    return {
        "p50_ms": round(float(np.percentile(ms, 50)), 3),
        "p99_ms": round(float(np.percentile(ms, 99)), 3),
        "max_ms": round(float(ms.max()), 3),
    }


def load_reference(path):
    """DepthHandTracker from another version of depth_hand.py, or None."""
    if not path:
        return None
    spec = importlib.util.spec_from_file_location("reference_depth_hand", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.DepthHandTracker


def nearest_blob(depth, tracker_config):
    """The naive baseline's palm (optical, m): centroid of the pixels near the nearest one."""
    inside = (depth > tracker_config["min_depth_m"]) & (depth < tracker_config["max_depth_m"])
    values = depth[inside]
    if values.size < 4:
        return None
    near = float(np.partition(values, 3)[3])
    v, u = np.nonzero(inside & (depth < near + NEAREST_BAND_M))
    z = depth[v, u].astype(float)
    return np.array([np.mean((u - INTR.cx) / INTR.fx * z), np.mean((v - INTR.cy) / INTR.fy * z), np.mean(z)])


def path_errors(seen, truth, sequence, hand):
    """Palm error figures (mm) of one tracker over frames: found fraction of hand frames and
    RMS/p95/max per sequence aligned, globally aligned and raw."""
    found = ~np.isnan(seen[:, 0])
    ok = found & hand
    error = seen - truth
    aligned = np.full(len(error), np.nan)
    for s in np.unique(sequence[ok]):
        mine = ok & (sequence == s)
        aligned[mine] = np.linalg.norm(error[mine] - error[mine].mean(axis=0), axis=1)
    offset = error[ok].mean(axis=0)
    global_aligned = np.linalg.norm(error[ok] - offset, axis=1)
    raw = np.linalg.norm(error[ok], axis=1)

    def figures(values):
        values = np.asarray(values) * 1000
        return {
            "rms_mm": round(float(np.sqrt(np.mean(values**2))), 2),
            "p95_mm": round(float(np.percentile(values, 95)), 2),
            "max_mm": round(float(values.max()), 2),
        }

    return {
        "found_fraction": round(float(ok.sum() / max(hand.sum(), 1)), 4),
        "per_sequence_aligned": figures(aligned[ok]),
        "globally_aligned": dict(figures(global_aligned), offset_mm=[round(float(v) * 1000, 2) for v in offset]),
        "raw": figures(raw),
    }


# SHREC joints the hand's axes come from: wrist, palm centre, index, middle and little
# finger bases.
HAND_AXES_JOINTS = (0, 1, 6, 10, 18)
TILT_BINS_DEG = (0, 25, 50, 70, 90)


def hand_axes_errors(seen, skeletons, sequence, hand):
    """Where the per-sequence aligned palm error lies: RMS (mm) along the hand (wrist to
    middle finger base), across it and along the palm normal, and by the palm's tilt (the
    angle between its normal and the line of sight): share of frames, RMS, share of the
    squared error."""
    ok = ~np.isnan(seen[:, 0]) & hand
    error = seen - skeletons[:, 1]
    aligned = np.zeros_like(error)
    for s in np.unique(sequence[ok]):
        mine = ok & (sequence == s)
        aligned[mine] = error[mine] - error[mine].mean(axis=0)
    along = skeletons[:, 3] - skeletons[:, 0]
    along /= np.linalg.norm(along, axis=1, keepdims=True)
    normal = np.cross(skeletons[:, 2] - skeletons[:, 0], skeletons[:, 4] - skeletons[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    across = np.cross(normal, along)
    parts = {
        name: float(np.sqrt(np.mean(np.einsum("ij,ij->i", aligned[ok], axis[ok]) ** 2)) * 1000)
        for name, axis in (("along_hand", along), ("across_hand", across), ("palm_normal", normal))
    }
    squared = np.einsum("ij,ij->i", aligned[ok], aligned[ok]) * 1e6
    tilt = np.degrees(np.arccos(np.clip(np.abs(normal[ok, 2]), 0.0, 1.0)))
    bins = []
    for low, high in zip(TILT_BINS_DEG[:-1], TILT_BINS_DEG[1:]):
        mine = (tilt >= low) & (tilt < high) if high < 90 else (tilt >= low)
        bins.append(
            {
                "tilt_deg": [low, high],
                "frames_fraction": round(float(mine.mean()), 3),
                "rms_mm": round(float(np.sqrt(squared[mine].mean())), 2) if mine.any() else None,
                "squared_error_share": round(float(squared[mine].sum() / squared.sum()), 3),
            }
        )
    return {"rms_mm": {k: round(v, 2) for k, v in parts.items()}, "by_tilt": bins}


def real_motion(args, reference):
    """The real-motion part (see the module), or a 'skipped' string."""
    data = shrec_hands.load()
    if data is None:
        return f"skipped: {shrec_hands.SHREC} not found (../shared absent)"
    tune, held_out = shrec_hands.select(data, seed=args.shrec_seed, per_subject=args.per_subject)
    rng = np.random.default_rng(args.seed)
    config = TRACKER_DEFAULTS
    out = {
        "source": "SHREC'17 training split (../shared/data/shrec17_train), skeletons rendered by "
        "motion_sensor.testing.skeleton_depth with its default hand model and sensor noise",
        "selection_seed": args.shrec_seed,
        "sequences_per_subject": args.per_subject,
        "truth": "SHREC joint 1 (palm centre), on the rendered palm slab's mid-plane",
    }
    total = sum(len(s.joints) for s in tune + held_out)
    done = 0
    for name, sequences in (("tuning_set", tune), ("evaluation_set", held_out)):
        truth, seqs, hand, skeletons = [], [], [], []
        seen = {"tracker": [], "nearest_blob": [], "reference": []}
        costs = {"tracker": [], "reference": []}
        for index, sequence in enumerate(sequences):
            tracker = DepthHandTracker({})
            before = reference({}) if reference else None
            for joints in shrec_hands.place(sequence.joints):
                data16 = encode_depth_mm(render_skeleton(joints, INTR, rng=rng))
                palm = joints[PALM]
                u = INTR.cx + INTR.fx * palm[0] / palm[2]
                v = INTR.cy + INTR.fy * palm[1] / palm[2]
                hand.append(
                    0 <= u < INTR.width
                    and 0 <= v < INTR.height
                    and config["min_depth_m"] < palm[2] < config["max_depth_m"]
                )
                truth.append(palm)
                skeletons.append(joints[list(HAND_AXES_JOINTS)])
                seqs.append(index)
                for key, which in (("tracker", tracker), ("reference", before)):
                    if which is None:
                        continue
                    start = time.perf_counter()
                    depth = decode_depth("16UC1", INTR.width, INTR.height, INTR.width * 2, data16)
                    result = which.track(depth, INTR)
                    costs[key].append(time.perf_counter() - start)
                    seen[key].append(OPTICAL_TO_BODY.T @ result.position if result is not None else [np.nan] * 3)
                depth = decode_depth("16UC1", INTR.width, INTR.height, INTR.width * 2, data16)
                blob = nearest_blob(depth, config)
                seen["nearest_blob"].append(blob if blob is not None else [np.nan] * 3)
                done += 1
            print(f"  real motion: {done}/{total} frames", flush=True)
        truth, seqs, hand = np.array(truth), np.array(seqs), np.array(hand, bool)
        skeletons = np.array(skeletons)
        part = {
            "sequences": [s.describe() for s in sequences],
            "subjects": sorted({s.subject for s in sequences}),
            "frames": len(truth),
            "hand_frames": int(hand.sum()),
            "tracker": path_errors(np.array(seen["tracker"], float), truth, seqs, hand),
            "nearest_blob_baseline": path_errors(np.array(seen["nearest_blob"], float), truth, seqs, hand),
        }
        part["tracker"]["per_frame_decode_and_track"] = stats_ms(costs["tracker"])
        part["tracker"]["by_hand_axes"] = hand_axes_errors(np.array(seen["tracker"], float), skeletons, seqs, hand)
        if reference:
            part["reference"] = path_errors(np.array(seen["reference"], float), truth, seqs, hand)
            part["reference"]["by_hand_axes"] = hand_axes_errors(
                np.array(seen["reference"], float), skeletons, seqs, hand
            )
            part["reference"]["per_frame_decode_and_track"] = stats_ms(costs["reference"])
        out[name] = part
    goals = {"per_sequence_rms_mm_max": 6.0, "per_sequence_p95_mm_max": 12.0, "found_fraction_min": 0.95}
    out["goals"] = goals
    out["goals_met"] = {
        name: bool(
            out[name]["tracker"]["per_sequence_aligned"]["rms_mm"] <= goals["per_sequence_rms_mm_max"]
            and out[name]["tracker"]["per_sequence_aligned"]["p95_mm"] <= goals["per_sequence_p95_mm_max"]
            and out[name]["tracker"]["found_fraction"] >= goals["found_fraction_min"]
        )
        for name in ("tuning_set", "evaluation_set")
    }
    return out


def plot(truth, seen, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(16, 4))
    frames = np.arange(len(truth))
    for i, name in enumerate("xyz"):
        axes[i].plot(frames, truth[:, i] * 1000, label="true palm centre")
        axes[i].plot(frames, seen[:, i] * 1000, ".", markersize=3, label="tracked (offset removed)")
        axes[i].set_title(f"{name} (camera frame, REP 103)")
        axes[i].set_xlabel("frame")
        axes[i].set_ylabel("mm")
    axes[3].plot(truth[:, 1] * 1000, truth[:, 0] * 1000, label="true palm centre")
    axes[3].plot(seen[:, 1] * 1000, seen[:, 0] * 1000, ".", markersize=3, label="tracked (offset removed)")
    axes[3].set_title("top view")
    axes[3].set_xlabel("y (left) mm")
    axes[3].set_ylabel("x (depth) mm")
    axes[3].invert_xaxis()
    axes[3].legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=300, help="frames along the path (default 300: 10 s at 30 Hz)")
    parser.add_argument("--seed", type=int, default=1, help="path and noise seed")
    parser.add_argument("--noise", type=float, default=0.0015, help="depth noise sigma per z^2 (m/m^2)")
    parser.add_argument(
        "--repeats", type=int, default=3, help="timing passes over the frames (the best of each is kept)"
    )
    parser.add_argument("--shrec-seed", type=int, default=28, help="seed of the real-motion subset")
    parser.add_argument("--per-subject", type=int, default=2, help="real-motion sequences per subject")
    parser.add_argument("--reference", help="another depth_hand.py to run alongside (before/after)")
    parser.add_argument("--skip-real", action="store_true", help="only the synthetic part")
    args = parser.parse_args()
    reference = load_reference(args.reference)

    poses = hand_path(args.frames, seed=args.seed)
    rng = np.random.default_rng(args.seed)
    print(f"rendering {args.frames} frames of 640x480 ...", flush=True)
    t0 = time.perf_counter()
    images = [encode_depth_mm(render_hand(p, noise_per_m2=args.noise, rng=rng)) for p in poses]
    render_s = time.perf_counter() - t0

    def frame(data, tracker):
        depth = decode_depth("16UC1", INTR.width, INTR.height, INTR.width * 2, data)
        return tracker.track(depth, INTR)

    costs = np.full(args.frames, np.inf)
    baseline = np.full(args.frames, np.inf)
    reference_costs = np.full(args.frames, np.inf)
    results_per_frame = reference_per_frame = None
    for _ in range(args.repeats):
        tracker = DepthHandTracker({})
        before = reference({}) if reference else None
        out, out_before = [], []
        for i, data in enumerate(images):
            start = time.perf_counter()
            out.append(frame(data, tracker))
            costs[i] = min(costs[i], time.perf_counter() - start)
            if before is not None:
                start = time.perf_counter()
                out_before.append(frame(data, before))
                reference_costs[i] = min(reference_costs[i], time.perf_counter() - start)
        results_per_frame, reference_per_frame = out, out_before
        for i, data in enumerate(images):
            depth = decode_depth("16UC1", INTR.width, INTR.height, INTR.width * 2, data)
            mask = ((depth > 0.35) & (depth < 1.3)).view(np.uint8)
            start = time.perf_counter()
            cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
            baseline[i] = min(baseline[i], time.perf_counter() - start)

    found = [r is not None for r in results_per_frame]
    truth = np.array([OPTICAL_TO_BODY @ p.position for p in poses])
    seen = np.array([r.position if r is not None else [np.nan] * 3 for r in results_per_frame])
    ok = np.array(found)
    offset = np.mean(seen[ok] - truth[ok], axis=0)
    residual = np.linalg.norm(seen[ok] - offset - truth[ok], axis=1)
    finger_err, normal_err = [], []
    for pose, result in zip(poses, results_per_frame):
        if result is None:
            continue
        r_seen = Rotation.from_quat(result.orientation).as_matrix()
        r_true = OPTICAL_TO_BODY @ pose.rotation
        finger_err.append(np.degrees(np.arccos(np.clip(r_seen[:, 0] @ r_true[:, 0], -1, 1))))
        normal_err.append(np.degrees(np.arccos(np.clip(r_seen[:, 2] @ r_true[:, 2], -1, 1))))

    png = os.path.join(RESULTS, "depth_hand_path.png")
    os.makedirs(RESULTS, exist_ok=True)
    plot(truth, seen - offset, png)
    cost, base = stats_ms(costs), stats_ms(baseline)
    results = {
        "frames": args.frames,
        "image": "640x480 16UC1",
        "seed": args.seed,
        "noise_sigma_per_m2": args.noise,
        "found_fraction": round(float(np.mean(found)), 4),
        "per_frame_decode_and_track": cost,
        "baseline_distance_transform_full_image": base,
        "ratio_p50_vs_baseline": round(cost["p50_ms"] / base["p50_ms"], 2),
        "ratio_p99_vs_baseline": round(cost["p99_ms"] / base["p99_ms"], 2),
        "position_rms_mm": round(float(np.sqrt(np.mean(residual**2))) * 1000, 2),
        "position_p95_mm": round(float(np.percentile(residual, 95)) * 1000, 2),
        "position_max_mm": round(float(residual.max()) * 1000, 2),
        "constant_offset_mm": [round(float(v) * 1000, 2) for v in offset],
        "fingers_axis_error_deg_mean_max": [round(float(np.mean(finger_err)), 2), round(float(np.max(finger_err)), 2)],
        "palm_normal_error_deg_mean_max": [round(float(np.mean(normal_err)), 2), round(float(np.max(normal_err)), 2)],
        "render_s_per_frame": round(render_s / args.frames, 4),
        "goals": {"p99_ms_max": 10.0, "position_rms_mm_max": 10.0},
        "plot": png,
    }
    results["goals_met"] = bool(cost["p99_ms"] <= 10.0 and results["position_rms_mm"] <= 10.0)
    if reference:
        ok_before = np.array([r is not None for r in reference_per_frame])
        seen_before = np.array([r.position if r is not None else [np.nan] * 3 for r in reference_per_frame])
        diff = seen_before[ok_before] - truth[ok_before]
        residual_before = np.linalg.norm(diff - diff.mean(axis=0), axis=1)
        results["reference"] = {
            "file": args.reference,
            "found_fraction": round(float(ok_before.mean()), 4),
            "position_rms_mm": round(float(np.sqrt(np.mean(residual_before**2))) * 1000, 2),
            "position_p95_mm": round(float(np.percentile(residual_before, 95)) * 1000, 2),
            "per_frame_decode_and_track": stats_ms(reference_costs),
        }
    if not args.skip_real:
        print("real hand motion (SHREC'17 skeletons) ...", flush=True)
        results["real_motion"] = real_motion(args, reference)
    write_results("depth_hand_bench", results, show=False)
    print("=== depth hand bench ===")
    print(f"frames                    : {args.frames} (hand found in {results['found_fraction'] * 100:.1f} %)")
    print(f"per frame (decode+track)  : p50 {cost['p50_ms']} ms, p99 {cost['p99_ms']} ms (goal p99 <= 10 ms)")
    print(
        f"baseline (bare dist. tr.) : p50 {base['p50_ms']} ms, p99 {base['p99_ms']} ms; "
        f"ratio p50 {results['ratio_p50_vs_baseline']}, p99 {results['ratio_p99_vs_baseline']}"
    )
    print(
        f"palm position error       : RMS {results['position_rms_mm']} mm, p95 {results['position_p95_mm']} mm, "
        f"max {results['position_max_mm']} mm (goal RMS <= 10 mm), constant offset {results['constant_offset_mm']} mm"
    )
    print(
        f"orientation error         : fingers mean/max {results['fingers_axis_error_deg_mean_max']} deg, "
        f"palm normal {results['palm_normal_error_deg_mean_max']} deg"
    )
    if reference:
        before = results["reference"]
        print(
            f"reference tracker         : p50 {before['per_frame_decode_and_track']['p50_ms']} ms, "
            f"p99 {before['per_frame_decode_and_track']['p99_ms']} ms; palm RMS {before['position_rms_mm']} mm"
        )
    real = results.get("real_motion")
    if isinstance(real, dict):
        for name in ("tuning_set", "evaluation_set"):
            part = real[name]
            rows = [("tracker", part["tracker"]), ("nearest blob", part["nearest_blob_baseline"])]
            if "reference" in part:
                rows.append(("reference", part["reference"]))
            print(f"real motion, {name} ({part['frames']} frames, subjects {part['subjects']}):")
            for label, figures in rows:
                cost_text = ""
                if "per_frame_decode_and_track" in figures:
                    c = figures["per_frame_decode_and_track"]
                    cost_text = f"; p50 {c['p50_ms']} ms, p99 {c['p99_ms']} ms"
                print(
                    f"  {label:13}: found {figures['found_fraction'] * 100:.1f} %, per sequence RMS "
                    f"{figures['per_sequence_aligned']['rms_mm']} mm, p95 {figures['per_sequence_aligned']['p95_mm']} "
                    f"mm; one offset RMS {figures['globally_aligned']['rms_mm']} mm; raw RMS "
                    f"{figures['raw']['rms_mm']} mm{cost_text}"
                )
                if "by_hand_axes" in figures:
                    axes = figures["by_hand_axes"]
                    print(
                        f"  {'':13}  RMS along the hand / across / palm normal "
                        + " / ".join(f"{v}" for v in axes["rms_mm"].values())
                        + " mm; by tilt "
                        + ", ".join(
                            f"{b['tilt_deg'][0]}-{b['tilt_deg'][1]} deg: {b['rms_mm']} mm "
                            f"({100 * b['frames_fraction']:.0f} % of frames)"
                            for b in axes["by_tilt"]
                        )
                    )
        print(f"real-motion goals met      : {real['goals_met']}")
    elif real:
        print(real)
    print(f"plot                      : {png}")
    print(f"goals met                 : {results['goals_met']}")
    return 0 if results["goals_met"] else 1


if __name__ == "__main__":
    sys.exit(main())
