"""Design study for the DTW gesture classifier defaults (one process, sequential).

For every variant (DTWClassifier keyword arguments) and every user-independent dataset
(hard synthetic letters, tests/tools/air_letters.py, subjects 1-10 vs 11-20; SHREC'17
index tip and palm, coarse and all 14, subjects split in sorted halves):

* ``inner``: leave-subjects-out INSIDE each training half (its subjects split in two,
  both directions), averaged over both halves: the figure used to choose defaults;
* ``outer``: train on one half, test on the other, both directions: reported only.

Selection score = mean(letters inner, mean of the SHREC inner figures).
Run: .venv/bin/python bench/gesture_explore.py [--stride 2] [--out FILE]
"""

import argparse
import json
import os
import sys
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path[:0] = [
    os.path.join(ROOT, "src", "motion_sensor"),
    os.path.join(ROOT, "src", "motion_common"),
    os.path.join(ROOT, "tests", "tools"),
    os.path.join(ROOT, "bench"),
]
import air_letters  # noqa: E402
from motion_sensor.gestures.dtw_classifier import DTWClassifier  # noqa: E402
from motion_sensor.gestures.gesture_features import FeatureConfig  # noqa: E402

SHREC = os.path.join(ROOT, "..", "shared", "data", "shrec17_train", "shrec17_train.npz")
CAMERA_TO_LEAPLIKE = np.array([1.0, -1.0, -1.0])


def make(spec):
    spec = dict(spec)
    clf_keys = {"window", "k", "weighted"}
    clf = {k: spec.pop(k) for k in list(spec) if k in clf_keys}
    if "axis_weights" in spec:
        spec["axis_weights"] = tuple(spec["axis_weights"])
    return DTWClassifier(FeatureConfig(**spec), **clf)


def accuracy(spec, train, test, stride):
    clf = make(spec).fit([(label, p, t) for label, p, t, _ in train])
    test = test[::stride]
    return float(np.mean([clf.classify(p, t).label == label for label, p, t, _ in test]))


def halves(seqs):
    subjects = sorted({s for *_, s in seqs})
    first = set(subjects[: len(subjects) // 2])
    return [x for x in seqs if x[3] in first], [x for x in seqs if x[3] not in first]


def evaluate(spec, seqs, stride):
    a, b = halves(seqs)
    outer = [accuracy(spec, a, b, stride), accuracy(spec, b, a, stride)]
    inner = []
    for half in (a, b):
        x, y = halves(half)
        inner += [accuracy(spec, x, y, stride), accuracy(spec, y, x, stride)]
    return {"inner": round(float(np.mean(inner)), 4), "outer": [round(v, 4) for v in outer]}


def datasets():
    letters = air_letters.dataset(range(1, 21), 1, seed=2026)
    out = {"letters": [(label, p, t, s) for s in letters for label, p, t in letters[s]]}
    if os.path.exists(SHREC):
        data = np.load(SHREC)
        joints, offsets = data["joints"], data["offsets"]
        for name, joint in (("index_tip", 9), ("palm", 1)):
            for subset, coarse in (("coarse", True), ("all14", False)):
                seqs = []
                for i, g in enumerate(data["gesture"]):
                    if coarse and g < 7:
                        continue
                    p = joints[offsets[i] : offsets[i + 1], joint].astype(float) * CAMERA_TO_LEAPLIKE * 1000.0
                    seqs.append((str(int(g)), p, np.arange(len(p)) * 1000.0 / 30.0, int(data["subject"][i])))
                out[f"shrec_{name}_{subset}"] = seqs
    return out


VARIANTS = {
    "default": {},
    "plane_align": {"plane": "align"},
    "plane_align_z0.5": {"plane": "align", "axis_weights": (1, 1, 0.5)},
    "z0.5": {"axis_weights": (1, 1, 0.5)},
    "dir0.3": {"direction_weight": 0.3},
    "dir1.0": {"direction_weight": 1.0},
    "curv0.3": {"curvature_weight": 0.3},
    "len48": {"length": 48},
    "len24": {"length": 24},
    "win0.08": {"window": 0.08},
    "win0.25": {"window": 0.25},
    "k3": {"k": 3},
    "bbox": {"scale": "bbox"},
    "smooth5": {"smooth": 5},
}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--stride", type=int, default=2)
    parser.add_argument("--variants", default="", help="comma-separated names (default all) or JSON dict")
    parser.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "gesture_explore.json"))
    args = parser.parse_args()
    variants = VARIANTS
    if args.variants.startswith("{"):
        variants = json.loads(args.variants)
    elif args.variants:
        variants = {k: VARIANTS[k] for k in args.variants.split(",")}
    data = datasets()
    results = {}
    for name, spec in variants.items():
        start = time.perf_counter()
        row = {key: evaluate(spec, seqs, 1 if key == "letters" else args.stride) for key, seqs in data.items()}
        shrec = [v["inner"] for k, v in row.items() if k.startswith("shrec")]
        row["score_inner"] = round(float(np.mean([row["letters"]["inner"], np.mean(shrec) if shrec else 0])), 4)
        row["spec"] = spec
        results[name] = row
        print(
            f"{name:18s} score {row['score_inner']:.4f} "
            + " ".join(
                f"{k}:{v['inner']:.3f}/{v['outer'][0]:.3f}/{v['outer'][1]:.3f}"
                for k, v in row.items()
                if isinstance(v, dict) and "inner" in v
            )
            + f" ({time.perf_counter() - start:.0f} s)",
            flush=True,
        )
    with open(args.out, "w") as fh:
        json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
