"""gesture_eval and record_gesture end to end, as subprocesses of the project's python."""

import json
import os
import subprocess
import sys

import numpy as np

from ..conftest import DATA, ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import air_letters  # noqa: E402

NODES = os.path.join(ROOT, "src", "motion_sensor", "nodes")
PYTHON = os.path.join(ROOT, ".venv", "bin", "python")
if not os.path.exists(PYTHON):  # pragma: no cover - outside the project's venv
    PYTHON = sys.executable
LETTERS = ["C", "L", "O", "S", "V", "Z"]


def write_dataset(folder, subjects, nested=False):
    data = air_letters.dataset(subjects, 1, seed=11, letters=LETTERS)
    for subject, items in data.items():
        for label, points, times in items:
            sub = os.path.join(folder, f"s{subject}", "session1" if nested else "")
            os.makedirs(sub, exist_ok=True)
            np.savetxt(os.path.join(sub, f"{label}.csv"), np.column_stack([points, times]), fmt="%.3f")


def test_gesture_eval_end_to_end(tmp_path):
    train, test = str(tmp_path / "train"), str(tmp_path / "test")
    write_dataset(train, [1, 2, 3])
    write_dataset(test, [4, 5], nested=True)
    with open(os.path.join(test, "s4", "session1", "S.csv"), "a") as fh:
        fh.write("1 2 oops 4\n")
    with open(os.path.join(test, "s5", "junk.csv"), "w") as fh:
        fh.write("nothing here\n")
    header_file = os.path.join(test, "s5", "session1", "O.csv")  # a header row and comments are fine
    with open(header_file) as fh:
        body = fh.read()
    with open(header_file, "w") as fh:
        fh.write("# recorded by a Leap, mm / ms\nx y z t\n" + body)
    plot = str(tmp_path / "confusion.png")
    proc = subprocess.run(
        [
            PYTHON,
            os.path.join(NODES, "gesture_eval"),
            "--train",
            train,
            "--test",
            test,
            "--json",
            "--plot",
            plot,
            "--reject",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"},
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["n_train"] == 18 and result["n_test"] == 12  # junk.csv left out
    assert result["classes"] == sorted(LETTERS)
    assert result["accuracy"] >= 0.9
    assert 0 < result["ms_per_classification_p50"] <= result["ms_per_classification_p99"] < 50
    assert "open_set" in result
    assert "not numbers" in proc.stderr and "junk.csv" in proc.stderr
    assert os.path.getsize(plot) > 1000


def test_gesture_eval_help_and_bad_folder(tmp_path):
    proc = subprocess.run(
        [PYTHON, os.path.join(NODES, "gesture_eval"), "--help"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 0 and "--train" in proc.stdout and "x y z t" in proc.stdout
    proc = subprocess.run(
        [PYTHON, os.path.join(NODES, "gesture_eval"), "--train", str(tmp_path / "none"), "--test", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2 and "does not exist" in proc.stderr


def test_gesture_eval_imports_no_rospy():
    with open(os.path.join(NODES, "gesture_eval")) as fh:
        text = fh.read()
    assert text.startswith("#!/usr/bin/env python3") and "rospy" not in text


def test_record_gesture_cuts_a_segment_from_a_recording(tmp_path):
    out = str(tmp_path / "gestures")
    cmd = [
        PYTHON,
        os.path.join(NODES, "record_gesture"),
        "roll",
        "--from",
        os.path.join(DATA, "rollAndPitchCropped.jsonl.gz"),
        "--dir",
        out,
        "--source",
        "index",
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    written = os.path.join(out, "roll", "001.csv")
    rows = np.loadtxt(written)
    assert rows.shape[1] == 4 and len(rows) > 20 and np.all(np.diff(rows[:, 3]) > 0)
    assert np.linalg.norm(np.ptp(rows[:, :3], axis=0)) > 60  # mm
    proc = subprocess.run(
        cmd[:4] + [os.path.join(DATA, "wave.jsonl.gz"), "--dir", out], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 1 and "no gesture spotted" in proc.stderr
    assert sorted(os.listdir(os.path.join(out, "roll"))) == ["001.csv"]
