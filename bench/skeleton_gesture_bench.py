"""Skeleton gesture benchmark: the DD-Net-style recognizer (motion_sensor.gestures.skeleton_*)
user-independently on SHREC'17, its time per classification, and online spotting.

Subjects are dealt round-robin by sorted id into 5 groups (train_skeleton_gestures); group 4
(subjects 8, 13, 20, 27: 380 sequences) is held out. The held-out model is
``--fold-model`` (made by ``train_skeleton_gestures --eval-folds 3 4 --fold-models DIR``,
trained on the other 16 subjects only); the shipped model is trained on all 20.

Splits. The spotter's settings were tuned on the TUNING split only: the streams of group 3
(subjects 7, 12, 19, 26) with that group's own held-out model (``--tuning-model``,
fold3.onnx), and the Leap recordings of LEAP_TRAINING. The figures are on the
EVALUATION split: group 4's streams with fold4.onnx and the Leap recordings of
LEAP_EVALUATION. The models learn to reject non-gesture motion from the LEAP_TRAINING
recordings (``--negatives``) and from transitions between their own training subjects'
gestures, never from group 4 or LEAP_EVALUATION.

(a) classification of the held-out sequences by the held-out model, 14 and 28 classes,
    against the project's DTW path recognizer (DTWClassifier, index-tip paths, templates
    from the same 16 subjects, every ``--dtw-stride``-th test sequence) in the same run;
    confusion matrix PNG (14 classes);
(b) time per classification of the SHIPPED model through onnxruntime, 1 intra-op thread,
    one sequence at a time, features included (p50/p99; and of each sequence's fastest of
    3 runs, which a load spike of the shared machine does not hit);
(c) spotting on continuous streams: the held-out subjects' sequences, one stream per
    subject, concatenated in a seeded random order with idle gaps (the hand comes to rest,
    holds still with 1 mm tremor for 1-3 s, then moves to the next start in 0.5 s), 30 Hz,
    run through SkeletonSpotter with the held-out model; a gesture is detected when an event
    with its label ends inside [start, end + 1 s] of it (one event per gesture); every other
    event is a false positive;
(d) false positives on ordinary hand motion: every real Leap recording of
    ../shared/data/leap_v6 converted to canonical skeletons from its finger joints (Leap
    v6 parser), each hand seen its own stream (as the spotter follows one hand), run
    through the spotter with the SHIPPED model, with its defaults and with the teach
    settings; every event counts as a false positive (some recordings show a real grab or
    pinch: a strict count); the LEAP_EVALUATION figure is the one to quote (LEAP_TRAINING
    was seen in training). With the minutes it has, the 95 % upper bound of the rate
    (Poisson) says what rate those minutes can show at all;
(e) a longer stream of real hand motion that is no command: the held-out subjects'
    gestures that the teach commands do not use (rotations, pinch, swipes other than
    left: 9 of the 14, real SHREC'17 motion), one stream per subject as in (c), through the
    spotter as the teach session runs it (``labels`` = the gestures of
    skeleton_gesture_commands.yaml) with the held-out model: every event is a false
    positive. Played in ``--orders`` seeded orders (different rests and ways between the
    gestures: one order holds only 243 gestures' worth of transitions, and 1 to 5 events),
    with the teach settings before this round (BEFORE_TEACH) and as shipped
    (skeleton_teach_spotter.yaml), in the same run, on the held-out and on the tuning split.
    The orders replay the same gestures, so with the count goes the number of distinct
    gestures behind it.

Run: bench/run skeleton_gesture_bench [--fold-model output/skeleton_folds/fold4.onnx]
[--tuning-model output/skeleton_folds/fold3.onnx]
Writes bench/results/skeleton_gesture_bench.json and skeleton_gesture_confusion.png. Needs
../shared (says so and exits 2 without it).
"""

import argparse
import glob
import os
import re
import sys
import time
from collections import Counter

import numpy as np

from bench_common import RESULTS, ROOT, write_results

sys.path[:0] = [os.path.join(ROOT, "src", "motion_sensor"), os.path.join(ROOT, "src", "motion_common")]
from motion_sensor.devices.leap_v6 import read_recording  # noqa: E402
from motion_sensor.gestures.dtw_classifier import DTWClassifier  # noqa: E402
from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier  # noqa: E402
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, load_skeleton_dataset  # noqa: E402
from motion_sensor.gestures.skeleton_eval import evaluate_skeleton  # noqa: E402
from motion_sensor.gestures.skeleton_spotter import SkeletonSpotter  # noqa: E402
from motion_sensor.gestures.skeleton_stream import build_stream  # noqa: E402
from motion_sensor.gestures.train_skeleton_gestures import subject_folds  # noqa: E402

SHARED = os.path.join(ROOT, "..", "shared", "data")
SHREC = os.path.join(SHARED, "shrec17_train", "shrec17_train.npz")
LEAP = os.path.join(SHARED, "leap_v6")
HELD_OUT_FOLD = 4
TUNING_FOLD = 3
RATE = 30.0
# Leap recordings the models learn to reject (and the spotter was tuned on); the others
# measure false positives. Variants of one recording (resolutions, frame rates) stay together.
LEAP_TRAINING = (
    "HandSplay-110fps",
    "brian",
    "confidence-demo",
    "confidence-demo-half-res",
    "confidence-demo-quarter-res",
    "confidence-demo-eighth-res",
    "flapping",
    "gun",
    "rollAndPitchCropped",
    "rollAndPitchWithEntry",
    "three-claps",
    "wave",
)
TEACH_SPOTTER = os.path.join(ROOT, "src", "motion_apps", "config", "skeleton_teach_spotter.yaml")
# The teach session's spotter settings before this round (pause_s 0.3, the spotter's
# default): the reference of (e).
BEFORE_TEACH = {
    "labels": ["expand", "grab", "shake", "swipe_left", "tap"],
    "min_confidence": 0.6,
    "max_other_probability": 0.05,
}
# Variants of one Leap recording (frame rates, resolutions) show the same motion.
VARIANT_SUFFIX = re.compile(r"-(\d+fps|half-res|quarter-res|eighth-res)$")


def log(message):
    print(f"skeleton_gesture_bench: {message}", file=sys.stderr, flush=True)


def stats(ms):
    return {"p50": round(float(np.percentile(ms, 50)), 4), "p99": round(float(np.percentile(ms, 99)), 4)}


def dtw_baseline(train, test, stride):
    """The project's DTW path recognizer on index-tip paths (REP 103 metres -> mm)."""
    index_tip = 9
    classifier = DTWClassifier()
    classifier.fit(
        [
            (CLASSES_14[label], seq[:, index_tip] * 1000.0, np.arange(len(seq)) * 1000.0 / RATE)
            for seq, label in zip(train.sequences, train.label14, strict=True)
        ]
    )
    right, times = 0, []
    chosen = range(0, len(test), stride)
    for i in chosen:
        seq = test.sequences[i]
        start = time.perf_counter()
        result = classifier.classify(seq[:, index_tip] * 1000.0, np.arange(len(seq)) * 1000.0 / RATE, open_set=False)
        times.append((time.perf_counter() - start) * 1000.0)
        right += result.candidate == CLASSES_14[test.label14[i]]
    return {"accuracy14": round(right / len(chosen), 4), "n_test": len(chosen), "ms": stats(times)}


def best_of_repeats(classifier, sequences, repeats):
    """p50/p99 over sequences of each one's fastest of ``repeats`` classifications: a load
    spike of the shared machine hits one run, not all three."""
    ms = np.full(len(sequences), np.inf)
    for _ in range(repeats):
        for i, sequence in enumerate(sequences):
            start = time.perf_counter()
            classifier.classify(sequence)
            ms[i] = min(ms[i], (time.perf_counter() - start) * 1000.0)
    return stats(ms)


def plot_confusion(path, matrix, accuracy):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 7))
    ax.imshow(matrix, cmap="Blues")
    ax.set_xticks(range(14), CLASSES_14, rotation=90)
    ax.set_yticks(range(14), CLASSES_14)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(f"skeleton gestures, held-out subjects 8/13/20/27: accuracy {accuracy:.3f}")
    for i in range(14):
        for j in range(14):
            if matrix[i][j]:
                ax.text(j, i, str(matrix[i][j]), ha="center", va="center", fontsize=7)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=90)
    plt.close(fig)
    os.replace(tmp, path)


def run_spotter(classifier, stamps, joints, params=None):
    spotter = SkeletonSpotter(classifier, params)
    events, ms = [], []
    for stamp, frame in zip(stamps, joints, strict=True):
        start = time.perf_counter()
        events.extend(spotter.update(stamp, frame))
        ms.append((time.perf_counter() - start) * 1000.0)
    events.extend(spotter.finish())
    return events, ms, spotter.counters


def score_stream(events, truth):
    matched, right_label, false_pos = set(), 0, 0
    for event in events:
        hit = None
        for k, (_label, start, end) in enumerate(truth):
            if k not in matched and start <= event.stamp <= end + 1.0:
                hit = k
                break
        if hit is None:
            false_pos += 1
            continue
        matched.add(hit)
        if event.name == truth[hit][0]:
            right_label += 1
        else:
            false_pos += 1
    return len(matched), right_label, false_pos


def teach_settings():
    import yaml

    with open(TEACH_SPOTTER, encoding="utf-8") as handle:
        return yaml.safe_load(handle)


def no_command_bench(model, held, seeds, settings):
    """(e): streams of the split's gestures that are no teach command, spotted for commands
    with ``settings``; and, for scale, the commands' own streams; one pass per seed (the
    order of the gestures and the rests between them). The first seed's figures alone too."""
    labels = settings["labels"]
    commands = np.array([CLASSES_14[k] in labels for k in held.label14])
    others, own = held.subset(~commands), held.subset(commands)
    passes = []
    fired = set()  # (subject, sequence) of the gestures behind the false commands
    for seed in seeds:
        rng = np.random.default_rng(seed)
        events, minutes, names = 0, 0.0, []
        for subject in sorted(set(others.subject.tolist())):
            part = others.subset(others.subject == subject)
            stamps, joints, truth = build_stream(part.sequences, list(range(len(part))), rng)
            found, _, _ = run_spotter(model, stamps, joints, settings)
            events += len(found)
            names += [e.name for e in found]
            fired.update((subject, most_overlapped(e, truth)) for e in found)
            minutes += stamps[-1] / 60.0
        detected = total = command_fp = 0
        for subject in sorted(set(own.subject.tolist())):
            part = own.subset(own.subject == subject)
            stamps, joints, truth = build_stream(part.sequences, [CLASSES_14[k] for k in part.label14], rng)
            found, _, _ = run_spotter(model, stamps, joints, settings)
            _, right, false_pos = score_stream(found, truth)
            detected, total, command_fp = detected + right, total + len(truth), command_fp + false_pos
        passes.append((events, minutes, names, detected, total, command_fp))
    events, minutes = sum(p[0] for p in passes), sum(p[1] for p in passes)
    detected, total = sum(p[3] for p in passes), sum(p[4] for p in passes)
    first = passes[0]
    return {
        "settings": settings,
        "orders": len(seeds),
        "gestures_played": len(others) * len(seeds),
        "minutes": round(minutes, 2),
        "false_positives": events,
        "false_positives_per_10_min": round(10.0 * events / minutes, 3),
        "false_positives_per_10_min_upper_95": round(10.0 * poisson_upper(events) / minutes, 3),
        "events": dict(sorted(Counter(name for p in passes for name in p[2]).items())),
        # The orders replay the same gestures: one gesture read as a command in most orders
        # makes most of the count, so the distinct gestures behind it say how many there are.
        "distinct_gestures_fired": len(fired),
        "commands_played": total,
        "commands_detection_rate": round(detected / total, 4),
        "commands_false_positives": sum(p[5] for p in passes),
        "first_order_only": {
            "seed": seeds[0],
            "minutes": round(first[1], 2),
            "false_positives": first[0],
            "false_positives_per_10_min": round(10.0 * first[0] / first[1], 3),
            "commands_detection_rate": round(first[3] / first[4], 4),
        },
    }


def most_overlapped(event, truth):
    """The label (here: the sequence's index) of the truth span ``event`` overlaps most."""
    start, end = event.info["start"], event.info["end"]
    return max(truth, key=lambda t: min(end, t[2]) - max(start, t[1]))[0]


def poisson_upper(events, level=0.95):
    """The upper bound of a Poisson mean at ``level`` after ``events`` counts."""
    from scipy.stats import chi2

    return float(chi2.ppf(level, 2 * events + 2) / 2.0)


def spotting_bench(model, held, seed):
    rng = np.random.default_rng(seed)
    total = {"gestures": 0, "spotted": 0, "detected": 0, "false_positives": 0, "minutes": 0.0}
    per_class = {c: [0, 0] for c in CLASSES_14}
    ms_all = []
    for subject in sorted(set(held.subject.tolist())):
        part = held.subset(held.subject == subject)
        stamps, joints, truth = build_stream(part.sequences, [CLASSES_14[k] for k in part.label14], rng)
        events, ms, _ = run_spotter(model, stamps, joints)
        ms_all.extend(ms)
        spotted, detected, false_pos = score_stream(events, truth)
        for label, start, end in truth:
            per_class[label][0] += 1
            per_class[label][1] += any(
                e.name == label and start <= e.stamp <= end + 1.0 for e in events
            )  # approximate per-class view
        total["gestures"] += len(truth)
        total["spotted"] += spotted
        total["detected"] += detected
        total["false_positives"] += false_pos
        total["minutes"] += stamps[-1] / 60.0
        log(f"stream of subject {subject}: {len(truth)} gestures, {detected} detected, {false_pos} false positives")
    return {
        "streams": len(set(held.subject.tolist())),
        "gestures": total["gestures"],
        "minutes": round(total["minutes"], 2),
        "detection_rate": round(total["detected"] / total["gestures"], 4),
        "spotted_any_label": round(total["spotted"] / total["gestures"], 4),
        "false_positives": total["false_positives"],
        "false_positives_per_min": round(total["false_positives"] / total["minutes"], 3),
        "per_class_detection": {c: round(v[1] / v[0], 3) for c, v in per_class.items() if v[0]},
        "ms_per_frame": stats(ms_all),
    }


def leap_bench(model, names, params=None):
    """Every hand of every recording as its own stream (a spotter per hand type, as the node
    follows one hand); seconds with that hand in view (frame gaps capped at 0.3 s)."""
    files = [os.path.join(LEAP, f"{name}.jsonl.gz") for name in names]
    per_file, total_events, total_minutes, distinct = {}, 0, 0.0, {}
    for path in files:
        recording = read_recording(path)
        spotters, events, seconds, last = {}, [], {}, {}
        for frame in recording.frames:
            for hand in frame.hands:
                if hand.skeleton is None:
                    continue
                key = hand.hand_type or "?"
                if key in last:
                    seconds[key] = seconds.get(key, 0.0) + min(frame.timestamp - last[key], 0.3)
                last[key] = frame.timestamp
                spotter = spotters.setdefault(key, SkeletonSpotter(model, params))
                events.extend(spotter.update(frame.timestamp, hand.skeleton))
        for spotter in spotters.values():
            events.extend(spotter.finish())
        name = os.path.basename(path).replace(".jsonl.gz", "")
        hand_seconds = sum(seconds.values())
        per_file[name] = {
            "hand_seconds": {k: round(v, 2) for k, v in sorted(seconds.items())},
            "events": [f"{e.name}:{e.confidence:.2f}" for e in events],
        }
        total_events += len(events)
        total_minutes += hand_seconds / 60.0
        base = VARIANT_SUFFIX.sub("", name)
        distinct[base] = max(distinct.get(base, 0.0), hand_seconds / 60.0)
    return {
        "recordings": len(files),
        "hand_minutes": round(total_minutes, 2),
        "distinct_hand_minutes": round(sum(distinct.values()), 2),
        "false_positives": total_events,
        "false_positives_per_10_min": round(10.0 * total_events / max(total_minutes, 1e-9), 3),
        "upper_95_per_10_min": round(10.0 * poisson_upper(total_events) / max(total_minutes, 1e-9), 1),
        "minutes_needed_to_show_under_1_per_10_min": round(10.0 * poisson_upper(0), 1),
        "per_recording": per_file,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fold-model", default=os.path.join(ROOT, "output", "skeleton_folds", "fold4.onnx"))
    parser.add_argument("--tuning-model", default=os.path.join(ROOT, "output", "skeleton_folds", "fold3.onnx"))
    parser.add_argument("--dtw-stride", type=int, default=4, help="every N-th held-out sequence for the DTW baseline")
    parser.add_argument("--seed", type=int, default=29)
    parser.add_argument("--orders", type=int, default=8, help="(e): seeded orders of the no-command streams")
    args = parser.parse_args()
    if not os.path.isfile(SHREC) or not os.path.isdir(LEAP):
        log(f"needs {SHREC} and {LEAP} (the shared data); nothing measured")
        return 2
    if not os.path.isfile(args.fold_model):
        log(
            f"no held-out model {args.fold_model}: make it with train_skeleton_gestures --data {SHREC} "
            f"--eval-folds {HELD_OUT_FOLD} --fold-models {os.path.dirname(args.fold_model)}"
        )
        return 2
    data = load_skeleton_dataset(SHREC)
    groups = subject_folds(data.subject, 5)
    test_mask = np.array([groups[int(s)] == HELD_OUT_FOLD for s in data.subject])
    held, train = data.subset(test_mask), data.subset(~test_mask)
    fold_model = SkeletonClassifier(args.fold_model)
    shipped = SkeletonClassifier()
    log(f"(a) held-out subjects {sorted(set(held.subject.tolist()))}: {len(held)} sequences")
    a14 = evaluate_skeleton(fold_model, held, 14)
    a28 = evaluate_skeleton(fold_model, held, 28)
    log("(a) DTW path baseline")
    baseline = dtw_baseline(train, held, args.dtw_stride)
    plot_path = os.path.join(RESULTS, "skeleton_gesture_confusion.png")
    plot_confusion(plot_path, a14["confusion"], a14["accuracy"])
    log("(b) shipped model timing")
    timing = evaluate_skeleton(shipped, held, 14)
    best = best_of_repeats(shipped, held.sequences, 3)
    log("(c) spotting on continuous held-out streams")
    spotting = spotting_bench(fold_model, held, args.seed)
    tuning = tuning_set = tuning_model = None
    if os.path.isfile(args.tuning_model):
        log("(c) the same on the tuning streams (group 3, its own held-out model)")
        tuning_set = data.subset(np.array([groups[int(s)] == TUNING_FOLD for s in data.subject]))
        tuning_model = SkeletonClassifier(args.tuning_model)
        tuning = spotting_bench(tuning_model, tuning_set, args.seed)
    log("(d) false positives on the Leap recordings")
    every = sorted(os.path.basename(p).replace(".jsonl.gz", "") for p in glob.glob(os.path.join(LEAP, "*.jsonl.gz")))
    evaluation_names = [n for n in every if n not in LEAP_TRAINING]
    training_names = [n for n in every if n in LEAP_TRAINING]
    teach = teach_settings()
    leap_eval = leap_bench(shipped, evaluation_names)
    leap_eval_teach = leap_bench(shipped, evaluation_names, teach)
    leap_train = leap_bench(shipped, training_names)
    seeds = [args.seed] + [k for k in range(1, args.orders + 1) if k != args.seed][: args.orders - 1]
    log(f"(e) no-command motion, spotted for the teach commands, {len(seeds)} orders, before and as shipped")
    no_command = {"held_out": {}, "tuning": {}}
    for name, settings in (("before", BEFORE_TEACH), ("shipped", teach)):
        no_command["held_out"][name] = no_command_bench(fold_model, held, seeds, settings)
        if tuning_set is not None:
            no_command["tuning"][name] = no_command_bench(tuning_model, tuning_set, seeds, settings)
        log(
            f"(e) {name}: held-out {no_command['held_out'][name]['false_positives_per_10_min']} per 10 min, "
            f"commands {no_command['held_out'][name]['commands_detection_rate']}"
        )
    results = {
        "held_out_subjects": sorted(int(s) for s in set(held.subject.tolist())),
        "classification": {
            "accuracy14": a14["accuracy"],
            "accuracy28": a28["accuracy"],
            "n_test": a14["n_test"],
            "dtw_baseline_index_tip": baseline,
            "accuracy14_ratio_to_dtw": round(a14["accuracy"] / max(baseline["accuracy14"], 1e-9), 3),
            "confusion_png": os.path.relpath(plot_path, ROOT),
        },
        "timing_shipped_model_ms": {
            "p50": timing["ms_per_classification_p50"],
            "p99": timing["ms_per_classification_p99"],
            "best_of_3_per_sequence": best,
            "dtw_baseline_p50_ratio": round(baseline["ms"]["p50"] / timing["ms_per_classification_p50"], 2),
            "model_bytes": os.path.getsize(shipped.model_path),
        },
        "spotting_held_out_streams": spotting,
        "spotting_tuning_streams": tuning,
        "leap_teleop_false_positives": {
            "evaluation": leap_eval,
            "evaluation_teach_settings": leap_eval_teach,
            "training_seen": leap_train,
        },
        "no_command_streams_false_positives": no_command,
    }
    write_results("skeleton_gesture_bench", results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
