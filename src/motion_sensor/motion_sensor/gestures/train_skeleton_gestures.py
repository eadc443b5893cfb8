"""Train the skeleton gesture network: the user-independent estimate, then the shipped
model (``rosrun motion_sensor train_skeleton_gestures``; needs requirements-train.txt).

Subjects are split into ``--folds`` groups by their id order (subject k of the sorted
list goes to group k mod folds). ``--eval-folds`` lists the groups held out one at a
time: a model is trained on the other subjects only and tested on the held-out ones;
the estimate pools every held-out sequence. ``--out`` then trains on every subject and
writes the ONNX model, with a JSON report beside it (``.json``: settings, the estimate,
the held-out subjects, training time). Nothing is written when a step fails; files are
replaced atomically.

With ``--reject-share`` above 0 the network also learns to reject motion that is no
gesture (``skeleton_negatives``): transitions between the training subjects' own gestures,
and the real Leap recordings given with ``--negatives`` (keep the recordings that measure
false positives out of this list).

Example (the shipped model)::

    train_skeleton_gestures --data ../shared/data/shrec17_train/shrec17_train.npz \\
        --eval-folds 4 --out src/motion_sensor/data/skeleton_gestures.onnx
"""

import argparse
import json
import os
import sys
import time

import numpy as np

from motion_sensor.errors import MotionSensorError
from motion_sensor.gestures.skeleton_dataset import load_skeleton_dataset
from motion_sensor.gestures.skeleton_negatives import NegativeSource, leap_motion
from motion_sensor.gestures.skeleton_training import TrainConfig, export_onnx, predict, train_model

__all__ = ["subject_folds", "negatives_for", "holdout_estimate", "main"]


def log(message):
    print(f"train_skeleton_gestures: {message}", file=sys.stderr, flush=True)


def subject_folds(subjects, folds):
    """{subject id: group} with the sorted subjects dealt round-robin into ``folds`` groups."""
    return {int(s): i % folds for i, s in enumerate(sorted({int(s) for s in subjects}))}


def negatives_for(dataset, config, runs):
    """The ``NegativeSource`` of a training set (None when rejection is off)."""
    if config.reject_share <= 0.0:
        return None
    return NegativeSource(runs, dataset.sequences, dataset.subject)


def holdout_estimate(dataset, config, folds, eval_folds, log=None, fold_models=None, runs=()):
    """Pooled accuracy (14 and 28 classes) over the held-out groups, and the details;
    with ``fold_models`` (a folder) each fold's model is exported there as
    ``fold<k>.onnx`` (the spotting benchmark runs it on its held-out subjects). ``runs``:
    real non-gesture motion (``skeleton_negatives.leap_motion``) when rejection is on."""
    groups = subject_folds(dataset.subject, folds)
    group_of = np.array([groups[int(s)] for s in dataset.subject])
    right14 = right28 = count = 0
    details = []
    for fold in eval_folds:
        test = group_of == fold
        if not test.any():
            raise MotionSensorError(f"fold {fold} of {folds} holds no subject")
        started = time.monotonic()
        train = dataset.subset(~test)
        model = train_model(train, config, log, negatives_for(train, config, runs))
        held = dataset.subset(test)
        prob14, prob28 = predict(model, held.sequences)
        ok14 = int(np.sum(prob14.argmax(1) == held.label14))
        ok28 = int(np.sum(prob28.argmax(1) == held.label28))
        right14, right28, count = right14 + ok14, right28 + ok28, count + len(held)
        details.append(
            {
                "fold": fold,
                "held_out_subjects": sorted(int(s) for s in set(held.subject.tolist())),
                "n_test": len(held),
                "accuracy14": round(ok14 / len(held), 4),
                "accuracy28": round(ok28 / len(held), 4),
                "train_s": round(time.monotonic() - started, 1),
            }
        )
        if fold_models:
            os.makedirs(fold_models, exist_ok=True)
            held_subjects = details[-1]["held_out_subjects"]
            export_onnx(model, os.path.join(fold_models, f"fold{fold}.onnx"), {"held_out_subjects": held_subjects})
        if log:
            log(f"fold {fold}: {details[-1]}")
    return {"accuracy14": round(right14 / count, 4), "accuracy28": round(right28 / count, 4), "n_test": count}, details


def parse_args(argv=None):
    parser = argparse.ArgumentParser(
        prog="train_skeleton_gestures", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--data", required=True, help="SHREC'17-layout .npz (joints, offsets, label14, label28, subject)"
    )
    parser.add_argument("--out", help="write the model trained on every subject here (.onnx)")
    parser.add_argument("--folds", type=int, default=5, help="subject groups (%(default)s)")
    parser.add_argument(
        "--eval-folds", type=int, nargs="*", default=[], help="groups held out one at a time for the estimate"
    )
    parser.add_argument("--fold-models", metavar="DIR", help="also export each held-out fold's model here")
    parser.add_argument(
        "--negatives",
        nargs="*",
        default=[],
        metavar="RECORDING",
        help="Leap v6 recordings (.jsonl.gz) of motion that is no gesture, rejected when --reject-share > 0",
    )
    defaults = TrainConfig()
    for name, value in defaults.as_dict().items():
        parser.add_argument(f"--{name.replace('_', '-')}", type=type(value), default=value, help="(%(default)s)")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    config = TrainConfig(**{name: getattr(args, name) for name in TrainConfig().as_dict()})
    if any(not 0 <= f < args.folds for f in args.eval_folds):
        log(f"--eval-folds must be groups 0-{args.folds - 1}, got {args.eval_folds}")
        return 2
    try:
        dataset = load_skeleton_dataset(args.data)
    except MotionSensorError as exc:
        log(str(exc))
        return 2
    try:
        runs = leap_motion(args.negatives) if config.reject_share > 0.0 else []
    except MotionSensorError as exc:
        log(str(exc))
        return 2
    log(f"{len(dataset)} sequences, {len(set(dataset.subject.tolist()))} subjects; settings {config.as_dict()}")
    report = {"data": os.path.basename(args.data), "config": config.as_dict(), "folds": args.folds}
    if runs:
        report["negatives"] = sorted(os.path.basename(p) for p in args.negatives)
    if args.eval_folds:
        estimate, details = holdout_estimate(dataset, config, args.folds, args.eval_folds, log, args.fold_models, runs)
        report.update(estimate=estimate, held_out=details)
        log(f"user-independent estimate: {estimate}")
    if args.out:
        started = time.monotonic()
        model = train_model(dataset, config, log, negatives_for(dataset, config, runs))
        report["final_train_s"] = round(time.monotonic() - started, 1)
        report["parameters"] = int(sum(p.numel() for p in model.parameters()))
        export_onnx(model, args.out, {"config": json.dumps(config.as_dict()), "trained_on": args.data})
        report["model_bytes"] = os.path.getsize(args.out)
        tmp = f"{os.path.splitext(args.out)[0]}.json.tmp"
        with open(tmp, "w", encoding="utf-8") as handle:
            json.dump(report, handle, indent=1)
            handle.write("\n")
        os.replace(tmp, f"{os.path.splitext(args.out)[0]}.json")
        log(f"wrote {args.out} ({report['model_bytes']} bytes)")
    print(json.dumps(report, separators=(",", ":")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
