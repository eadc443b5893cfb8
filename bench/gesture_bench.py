"""Gesture recognition benchmark: DTW classifier accuracy and time per classification,
user-independent (whole subjects held out), against the plain baseline (centred and scaled
3-D DTW 1-NN in dtaidistance, no resampling, no window, same run).

(a) SHREC'17 dynamic gestures (../shared/data/shrec17_train, never copied into the
    project) from the palm and the index-tip path: coarse (swipes, shake) and all 14;
    subjects split in two halves (sorted ids), both directions;
(b) static poses from the finger joints: a grab-strength proxy (fingertip-to-palm distance
    over hand size) fed to StaticPoseDetector; "fist" rate on grab vs on swipe sequences;
(c) the gesture_eval CLI on SHREC index-tip paths exported to <subject>/<label>.csv
    (x y z t, mm/ms) in a temp dir, both directions;
(d) HARD synthetic 26-letter air writing (tests/tools/air_letters.py, seed 2026: writer
    styles, tilted planes, warps, hooks, pauses, tremor, 50-120 Hz, dropped frames),
    subjects 1-10 vs 11-20, 260 templates each way, ours vs the baseline both directions;
    the time per classification with 1,040 templates (subjects 21-60); and the
    gesture_eval CLI end to end on the same letters exported as <subject>/<label>.csv
    (x y z t, mm/ms, Leap axes), both directions.

Run: bench/run gesture_bench [--stride 3]   (every STRIDE-th test sequence for (a), to
stay short on 2 shared cores). Writes bench/results/gesture_bench.json. Skips (a)-(c) with
a message when ../shared is absent.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from dtaidistance import dtw_ndim

from bench_common import ROOT, write_results

sys.path[:0] = [
    os.path.join(ROOT, "src", "motion_sensor"),
    os.path.join(ROOT, "src", "motion_common"),
    os.path.join(ROOT, "tests", "tools"),
]
import air_letters  # noqa: E402
from motion_sensor.gestures.dtw_classifier import DTWClassifier  # noqa: E402
from motion_sensor.gestures.gesture_frame import GestureFrame  # noqa: E402
from motion_sensor.gestures.static_poses import StaticPoseDetector  # noqa: E402

SHREC = os.path.join(ROOT, "..", "shared", "data", "shrec17_train", "shrec17_train.npz")
CAMERA_TO_LEAPLIKE = np.array([1.0, -1.0, -1.0])  # y down -> up (a proper rotation about x)


def stats(ms):
    return round(float(np.percentile(ms, 50)), 3), round(float(np.percentile(ms, 99)), 3)


def baseline(train, test):
    def prep(p):
        p = p - p.mean(axis=0)
        return np.ascontiguousarray(p / np.sqrt((p**2).sum(axis=1).mean()))

    templates = [(label, prep(p)) for label, p, _ in train]
    correct, times = 0, []
    for label, p, _ in test:
        start = time.perf_counter()
        q = prep(p)
        d = [dtw_ndim.distance_fast(q, t) for _, t in templates]
        times.append((time.perf_counter() - start) * 1000)
        correct += templates[int(np.argmin(d))][0] == label
    return correct / len(test), times


def ours(train, test, **kw):
    clf = DTWClassifier(**kw).fit(train)
    correct, times = 0, []
    for label, p, t in test:
        start = time.perf_counter()
        result = clf.classify(p, t)
        times.append((time.perf_counter() - start) * 1000)
        correct += result.label == label
    return correct / len(test), times


def compare(train, test, stride, baseline_stride=None):
    acc, ms = ours(train, test[::stride])
    base_acc, base_ms = baseline(train, test[:: baseline_stride or stride])
    p50, p99 = stats(ms)
    b50, b99 = stats(base_ms)
    return {
        "n_train": len(train),
        "n_test": len(test[::stride]),
        "accuracy": round(acc, 4),
        "ms_p50": p50,
        "ms_p99": p99,
        "baseline_accuracy": round(base_acc, 4),
        "baseline_ms_p50": b50,
        "baseline_ms_p99": b99,
        "speedup_p50": round(b50 / p50, 1),
        "speedup_p99": round(b99 / p99, 1),
        "accuracy_gain": round(acc - base_acc, 4),
    }


def export_letters(data, folder):
    """Write {subject: [(label, points, times)]} as folder/s<subject>/<label>.csv (mm, ms)."""
    for subject, items in data.items():
        sub = os.path.join(folder, f"s{subject}")
        os.makedirs(sub, exist_ok=True)
        for label, points, times in items:
            np.savetxt(
                os.path.join(sub, f"{label}.csv"),
                np.column_stack([points, times]),
                fmt="%.2f",
                header="x y z t  (mm, ms; Leap axes: x right, y up, z toward the user)",
            )


def shrec_sequences(data, joint, coarse):
    joints, offsets = data["joints"], data["offsets"]
    out = []
    for i, gesture in enumerate(data["gesture"]):
        if coarse and gesture < 7:
            continue
        points = joints[offsets[i] : offsets[i + 1], joint].astype(float) * CAMERA_TO_LEAPLIKE * 1000.0
        out.append((str(int(gesture)), points, np.arange(len(points)) * 1000.0 / 30.0, int(data["subject"][i])))
    return out


def split(seqs):
    subjects = sorted({s for *_, s in seqs})
    first = set(subjects[: len(subjects) // 2])
    a = [(label, p, t) for label, p, t, s in seqs if s in first]
    b = [(label, p, t) for label, p, t, s in seqs if s not in first]
    return a, b


def grab_proxy(frame):
    """0 (open) .. 1 (closed) from 22 joints: fingertip-to-palm distance over hand size."""
    palm, tips, bases = frame[1], frame[[9, 13, 17, 21]], frame[[6, 10, 14, 18]]
    size = np.linalg.norm(bases - palm, axis=1).mean()
    ratio = np.linalg.norm(tips - palm, axis=1).mean() / max(size, 1e-6)
    return float(np.clip((2.0 - ratio) / 1.0, 0.0, 1.0))


def static_bench(data):
    joints, offsets = data["joints"], data["offsets"]
    fired = {}
    for i, gesture in enumerate(data["gesture"]):
        if data["finger"][i] != 2:
            continue
        kind = "grab" if gesture == 1 else "expand" if gesture == 3 else "swipe" if 7 <= gesture <= 13 else None
        if kind is None:
            continue
        det = StaticPoseDetector({"fist_dwell_s": 0.1})
        names = []
        for k, frame in enumerate(joints[offsets[i] : offsets[i + 1]]):
            names += [
                e.name
                for e in det.update(GestureFrame(k / 30.0, frame[1].astype(float), grab=grab_proxy(frame), pinch=0.0))
            ]
        fired.setdefault(kind, []).append("fist" in names)
    return {kind: {"sequences": len(v), "fist_rate": round(float(np.mean(v)), 3)} for kind, v in fired.items()}


def run_cli(folders):
    out = {}
    for train, test in (("A", "B"), ("B", "A")):
        start = time.perf_counter()
        proc = subprocess.run(
            [
                sys.executable,
                os.path.join(ROOT, "src", "motion_sensor", "nodes", "gesture_eval"),
                "--train",
                folders[train],
                "--test",
                folders[test],
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=600,
        )
        result = json.loads(proc.stdout.strip().splitlines()[-1])
        out[f"{train}->{test}"] = {
            k: result[k]
            for k in ("accuracy", "ms_per_classification_p50", "ms_per_classification_p99", "n_train", "n_test")
        }
        out[f"{train}->{test}"]["wall_s"] = round(time.perf_counter() - start, 1)
        print(f"  CLI {train}->{test}: {out[f'{train}->{test}']}", flush=True)
    return out


def cli_bench(seqs, tmp):
    folders = {}
    subjects = sorted({s for *_, s in seqs})
    for half, group in (("A", subjects[: len(subjects) // 2]), ("B", subjects[len(subjects) // 2 :])):
        folders[half] = os.path.join(tmp, half)
        counts = {}
        for label, points, times, subject in seqs:
            if subject not in group:
                continue
            counts[(subject, label)] = counts.get((subject, label), 0) + 1
            sub = os.path.join(folders[half], f"s{subject}", f"rep{counts[(subject, label)]}")
            os.makedirs(sub, exist_ok=True)
            np.savetxt(os.path.join(sub, f"g{label}.csv"), np.column_stack([points, times]), fmt="%.2f")
    return run_cli(folders)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--stride", type=int, default=3, help="use every STRIDE-th test sequence in (a)")
    args = parser.parse_args()
    results = {
        "goals": {"ms_per_classification": 5.0, "letters_accuracy": 0.97},
        "classifier": {
            "features": vars(DTWClassifier().config),
            "window": DTWClassifier().window_fraction,
            "k": DTWClassifier().k,
        },
        "baseline": "centred, RMS-scaled raw 3-D path, unconstrained DTW 1-NN (dtaidistance dtw_ndim)",
    }

    letters = air_letters.dataset(range(1, 21), 1, seed=2026)
    a = [x for s in range(1, 11) for x in letters[s]]
    b = [x for s in range(11, 21) for x in letters[s]]
    hard = {
        "set": "air_letters.dataset(range(1, 21), 1, seed=2026), difficulty 1.0; A = subjects 1-10, B = 11-20",
        "A->B": compare(a, b, 1),
        "B->A": compare(b, a, 1),
    }
    hard["mean_accuracy"] = round((hard["A->B"]["accuracy"] + hard["B->A"]["accuracy"]) / 2, 4)
    hard["mean_baseline_accuracy"] = round(
        (hard["A->B"]["baseline_accuracy"] + hard["B->A"]["baseline_accuracy"]) / 2, 4
    )
    print("hard synthetic letters:", hard, flush=True)
    many = air_letters.dataset(range(21, 61), 1, seed=2026)
    big = [x for s in many for x in many[s]]
    acc, ms = ours(big, (a + b)[::4])
    hard["templates_1040"] = {
        "n_train": len(big),
        "n_test": len((a + b)[::4]),
        "accuracy": round(acc, 4),
        "ms_p50": stats(ms)[0],
        "ms_p99": stats(ms)[1],
    }
    print("  1,040 templates:", hard["templates_1040"], flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        folders = {"A": os.path.join(tmp, "A"), "B": os.path.join(tmp, "B")}
        export_letters({s: letters[s] for s in range(1, 11)}, folders["A"])
        export_letters({s: letters[s] for s in range(11, 21)}, folders["B"])
        hard["cli"] = run_cli(folders)
    results["hard_synthetic_letters_26"] = hard

    if not os.path.exists(SHREC):
        results["shrec17"] = f"skipped: {os.path.normpath(SHREC)} not found (../shared absent)"
        print(results["shrec17"])
    else:
        data = np.load(SHREC)
        shrec = {}
        for joint_name, joint in (("palm", 1), ("index_tip", 9)):
            for subset, coarse in (("coarse", True), ("all14", False)):
                a, b = split(shrec_sequences(data, joint, coarse))
                key = f"{joint_name}_{subset}"
                shrec[key] = {"A->B": compare(a, b, args.stride), "B->A": compare(b, a, args.stride)}
                print(f"SHREC {key}: {shrec[key]}", flush=True)
        shrec["static_fist_from_joints"] = static_bench(data)
        print("static:", shrec["static_fist_from_joints"], flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            shrec["cli_index_tip_all14"] = cli_bench(shrec_sequences(data, 9, False), tmp)
        results["shrec17"] = shrec
    write_results("gesture_bench", results)


if __name__ == "__main__":
    main()
