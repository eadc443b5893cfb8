"""Gesture recognition: static poses (hysteresis, dwell, hold-still), DTW classification
and rejection, spotting, no false positives on the real recordings, template files."""

import glob
import os
import sys

import numpy as np
import pytest

from motion_common.errors import ParameterError
from motion_sensor.gestures.dtw_classifier import DTWClassifier
from motion_sensor.gestures.gesture_features import FeatureConfig, features
from motion_sensor.gestures.gesture_frame import GestureFrame, frames_from_recording
from motion_sensor.gestures.gesture_recognizer import DEFAULT_TEMPLATES, GestureRecognizer, load_classifier
from motion_sensor.gestures.gesture_spotter import GestureSpotter
from motion_sensor.gestures.gesture_templates import load_templates, read_path, save_template, write_atomic
from motion_sensor.gestures.static_poses import StaticPoseDetector

from ..conftest import DATA, ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import air_letters  # noqa: E402
import make_gesture_templates  # noqa: E402

RATE = 100.0


def stream(values, start=0.0, palm=None, **fixed):
    """GestureFrames at RATE Hz: ``values`` is a list of dicts of per-frame fields."""
    frames = []
    for i, v in enumerate(values):
        fields = dict(fixed)
        fields.update(v)
        position = fields.pop("palm", np.zeros(3) if palm is None else palm)
        frames.append(GestureFrame(start + i / RATE, np.asarray(position, dtype=float), **fields))
    return frames


def run(detector, frames):
    events = []
    for frame in frames:
        events.extend((e.name, round(e.stamp, 4)) for e in detector.update(frame))
    return events


# ---------------------------------------------------------------- static poses


def test_fist_fires_after_dwell_once_and_ends_with_hysteresis():
    det = StaticPoseDetector({"fist_dwell_s": 0.2, "grab_on": 0.8, "grab_off": 0.5})
    grab = [0.0] * 10 + [0.9] * 40 + [0.7] * 20 + [0.3] * 10  # 0.7 is inside the band: still a fist
    events = [e for e in run(det, stream([{"grab": g, "pinch": 0.0} for g in grab])) if "fist" in e[0]]
    assert events == [("fist", pytest.approx(0.30)), ("fist_end", pytest.approx(0.70))]


def test_fist_shorter_than_dwell_is_no_event():
    det = StaticPoseDetector({"fist_dwell_s": 0.3})
    grab = [0.0] * 10 + [0.95] * 20 + [0.0] * 10 + [0.95] * 20
    assert not [e for e in run(det, stream([{"grab": g, "pinch": 0.0} for g in grab])) if "fist" in e[0]]


def test_chattering_grab_at_threshold_gives_one_fist():
    det = StaticPoseDetector({"fist_dwell_s": 0.1})
    grab = [0.0] * 5 + [0.85] * 20 + [0.75, 0.82] * 30 + [0.1] * 5
    names = [e[0] for e in run(det, stream([{"grab": g, "pinch": 0.0} for g in grab])) if "fist" in e[0]]
    assert names == ["fist", "fist_end"]


def test_pinch_but_not_when_fist():
    det = StaticPoseDetector({"pinch_dwell_s": 0.1, "fist_dwell_s": 0.1})
    values = (
        [{"grab": 0.1, "pinch": 0.95}] * 30 + [{"grab": 0.1, "pinch": 0.2}] * 10 + [{"grab": 0.95, "pinch": 0.95}] * 30
    )
    names = [e[0] for e in run(det, stream(values))]
    assert names.count("pinch") == 1 and names.count("pinch_end") == 1 and "fist" in names
    assert names.index("pinch_end") < names.index("fist")


def test_open_palm_and_unknown_strength_is_no_evidence():
    det = StaticPoseDetector({"open_dwell_s": 0.3})
    values = (
        [{"grab": 0.0, "pinch": 0.0}] * 20 + [{"grab": -1.0, "pinch": -1.0}] * 5 + [{"grab": 0.0, "pinch": 0.0}] * 20
    )
    names = [e[0] for e in run(det, stream(values)) if "open" in e[0]]
    assert names == []  # 0.19 s, then unknown restarts the dwell, then 0.19 s
    names = [e[0] for e in run(det, stream([{"grab": 0.0, "pinch": 0.05}] * 40, start=5.0)) if "open" in e[0]]
    assert names == ["open_palm"]


def test_palm_only_device_never_reports_hand_poses():
    det = StaticPoseDetector()
    names = [e[0] for e in run(det, stream([{}] * 300))]
    assert "fist" not in names and "pinch" not in names and "open_palm" not in names


def test_second_hand_with_dwell_and_end():
    det = StaticPoseDetector({"second_hand_dwell_s": 0.2})
    values = (
        [{"hands_num": 1}] * 10
        + [{"hands_num": 2}] * 10
        + [{"hands_num": 1}] * 5
        + [{"hands_num": 2}] * 30
        + [{"hands_num": 1}] * 5
    )
    events = [e for e in run(det, stream(values)) if "second" in e[0]]
    assert events == [("second_hand", pytest.approx(0.45)), ("second_hand_end", pytest.approx(0.55))]


def test_hold_still_after_the_set_time_with_jitter_and_release(rng):
    det = StaticPoseDetector({"still_time_s": 1.0})
    moving = [{"palm": [0.0, 0.1 * i / RATE, 0.2]} for i in range(50)]  # 0.1 m/s
    still = [{"palm": [0.0, 0.05, 0.2] + rng.normal(0, 0.0003, 3)} for _ in range(150)]  # Leap-like jitter
    moving2 = [{"palm": [0.0, 0.05 + 0.2 * i / RATE, 0.2]} for i in range(30)]
    events = [e for e in run(det, stream(moving + still + moving2)) if "still" in e[0]]
    assert [e[0] for e in events] == ["hold_still", "hold_still_end"]
    assert 1.55 <= events[0][1] <= 1.8  # still from 0.5 s (+ part of the speed window), held 1 s
    assert 2.0 <= events[1][1] <= 2.25


def test_slow_drift_is_not_still_and_gap_resets():
    det = StaticPoseDetector({"still_time_s": 0.5})
    drift = [{"palm": [0.0, 0.08 * i / RATE, 0.2]} for i in range(200)]  # 80 mm/s: slow, not still
    assert not run(det, stream(drift))
    det = StaticPoseDetector({"still_time_s": 0.5})
    before = stream([{}] * 40)
    after = stream([{}] * 40, start=1.0)  # 0.6 s gap: hand lost, the timer restarts
    assert [e[0] for e in run(det, before + after)] == []


def test_static_parameters_are_checked():
    with pytest.raises(ParameterError, match="still_speed"):
        StaticPoseDetector({"still_speed": -1.0})
    with pytest.raises(ParameterError, match="unknown parameter"):
        StaticPoseDetector({"grab_onn": 0.5})


def test_real_grab_recording_gives_fist_then_release():
    det = StaticPoseDetector()
    names = [e.name for f in frames_from_recording(os.path.join(DATA, "grab.jsonl.gz")) for e in det.update(f)]
    assert "fist" in names and names.index("fist") < names.index("fist_end")
    det = StaticPoseDetector()
    names = [
        e.name for f in frames_from_recording(os.path.join(DATA, "Waiting-110fps.jsonl.gz")) for e in det.update(f)
    ]
    assert "hold_still" in names and "fist" not in names


# ---------------------------------------------------------------- DTW classification


def _letters(subjects, seed=7):
    data = air_letters.dataset(subjects, 1, seed=seed)
    return [item for s in subjects for item in data[s]]


def test_features_are_invariant_to_position_scale_and_speed(rng):
    t = np.linspace(0, 1, 400)
    path = np.column_stack([np.cos(3 * t), np.sin(5 * t), t])
    slow = np.column_stack([np.cos(3 * t**2), np.sin(5 * t**2), t**2])
    a = features(path)
    assert a.shape == (48, 6) and a.flags["C_CONTIGUOUS"]
    assert np.allclose(features(path * 7 + [1, 2, 3]), a, atol=1e-9)
    assert np.abs(features(slow) - a).max() < 0.05  # arc-length resampling removes speed
    assert features(path, config=FeatureConfig(direction_weight=0)).shape == (48, 3)


def test_plane_alignment_undoes_a_tilted_writing_plane():
    letter = air_letters._polyline(air_letters.LETTERS["R"], 200)
    flat = np.column_stack([letter, np.zeros(len(letter))]) * 100.0
    tilted = flat @ air_letters._rotation(0.5, -0.4).T
    config = FeatureConfig(plane="align", axis_weights=(1.0, 1.0, 1.0))
    plain = FeatureConfig(axis_weights=(1.0, 1.0, 1.0))
    assert np.abs(features(tilted, config=config) - features(flat, config=config)).max() < 0.2
    assert np.abs(features(tilted, config=plain) - features(flat, config=plain)).max() > 0.3
    line = np.column_stack([np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)])
    assert np.allclose(
        features(line @ air_letters._rotation(0.3, 0.2).T, config=config),
        features(line @ air_letters._rotation(0.3, 0.2).T, config=plain),
    )  # no plane: untouched


@pytest.mark.parametrize("kwargs", [{}, {"k": 3}, {"config": FeatureConfig(plane="align", length=32)}])
def test_dtw_cascade_equals_full_scan(kwargs):
    train, test = _letters(range(1, 4)), _letters(range(4, 6))
    clf = DTWClassifier(**kwargs).fit(train)
    calls = []
    for _label, points, times in test[:30]:
        q = clf.features(points, times)
        result = clf.classify_features(q)
        full = np.array([clf.dtw(q, t) for t in clf._data])
        order = np.argsort(full, kind="stable")[: clf.k]
        if clf.k == 1:
            assert result.candidate == clf.labels[order[0]]
        else:  # the same k nearest as a full scan, so the same vote
            best, _, _ = clf.scan(q, clf.k)
            assert [d for d, _ in best] == pytest.approx(list(full[order]))
        assert result.distance == pytest.approx(
            full[[i for i, lab in enumerate(clf.labels) if lab == result.candidate]].min() / np.sqrt(clf.config.length)
        )
        calls.append(result.dtw_calls)
    assert np.mean(calls) < len(clf)  # the lower bounds pruned something


def _baseline_accuracy(train, test):
    """The plain reference: centred, RMS-scaled raw 3-D path, unconstrained DTW 1-NN."""
    from dtaidistance import dtw_ndim

    def prep(p):
        p = p - p.mean(axis=0)
        return np.ascontiguousarray(p / np.sqrt((p**2).sum(axis=1).mean()))

    templates = [(label, prep(p)) for label, p, _ in train]
    correct = 0
    for label, p, _ in test:
        q = prep(p)
        correct += templates[int(np.argmin([dtw_ndim.distance_fast(q, t) for _, t in templates]))][0] == label
    return correct / len(test)


def test_held_out_hard_letters_beat_the_plain_baseline():
    train, test = _letters(range(1, 6), seed=2026), _letters(range(11, 14), seed=2026)
    ours = np.mean([DTWClassifier().fit(train).classify(p, t).label == label for label, p, t in test])
    base = _baseline_accuracy(train, test)
    assert base < 0.99  # the set is hard enough that the baseline is not perfect
    assert ours > base and ours >= 0.95


def test_dtw_classifies_held_out_letters():
    train, test = _letters(range(1, 7)), _letters(range(7, 10))
    clf = DTWClassifier().fit(train)
    correct = sum(clf.classify(p, t).label == label for label, p, t in test)
    assert correct / len(test) >= 0.93
    clf3 = DTWClassifier(k=3).fit(train)
    assert sum(clf3.classify(p, t).label == label for label, p, t in test) / len(test) >= 0.9


def test_open_set_rejects_non_gestures_closed_set_does_not(rng):
    clf = DTWClassifier().fit(_letters(range(1, 6)))
    threshold = clf.calibrate_rejection()
    assert threshold > 0
    label, points, times = _letters([8])[3]
    assert clf.classify(points, times).label == label  # open set now, still accepted
    scribble = np.cumsum(rng.normal(0, 5, (120, 3)), axis=0)  # random walk, not a letter
    result = clf.classify(scribble)
    assert result.rejected and result.label is None and result.candidate
    assert clf.classify(scribble, open_set=False).label == result.candidate


# ---------------------------------------------------------------- spotting


def _with_pauses(path, rng, rest=60):
    rest_a = np.repeat(path[:1], rest, axis=0) + rng.normal(0, 0.0003, (rest, 3))
    rest_b = np.repeat(path[-1:], rest, axis=0) + rng.normal(0, 0.0003, (rest, 3))
    points = np.vstack([rest_a, path, rest_b])
    return [GestureFrame(i / 90.0, p) for i, p in enumerate(points)]


def test_spotter_finds_each_default_gesture_in_a_stream():
    classifier = load_classifier(DEFAULT_TEMPLATES)
    assert classifier.classes == sorted(make_gesture_templates.LABELS)
    for li, label in enumerate(make_gesture_templates.LABELS):
        rng = np.random.default_rng([5, li])
        path, _ = make_gesture_templates.gesture_path(label, rng, 90.0)
        spotter = GestureSpotter(classifier)
        events = [e for f in _with_pauses(path, rng) for e in spotter.update(f)]
        assert [e.name for e in events] == [label]
        assert 0 < events[0].confidence <= 1 and events[0].info["duration_s"] > 0.2


def test_spotter_needs_a_pause_first_and_abandons_endless_motion(rng):
    classifier = load_classifier(DEFAULT_TEMPLATES)
    spotter = GestureSpotter(classifier, {"max_duration_s": 2.0})
    t = np.arange(0, 6, 1 / 90.0)
    circling = np.column_stack([0.1 + 0 * t, 0.08 * np.cos(4 * t), 0.2 + 0.08 * np.sin(4 * t)])
    assert not [e for i, p in enumerate(circling) for e in spotter.update(GestureFrame(t[i], p))]


def test_clutch_mode_segments_while_pinched():
    classifier = load_classifier(DEFAULT_TEMPLATES)
    rng = np.random.default_rng(3)
    path, _ = make_gesture_templates.gesture_path("swipe_up", rng, 90.0)
    frames = [GestureFrame(i / 90.0, p, pinch=0.95 if 5 <= i < len(path) - 5 else 0.1) for i, p in enumerate(path)]
    spotter = GestureSpotter(classifier, {"mode": "clutch"})
    assert [e.name for f in frames for e in spotter.update(f)] == ["swipe_up"]


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(DATA, "*.jsonl.gz"))), ids=os.path.basename)
def test_no_false_gestures_on_real_recordings(path):
    """None of the shipped recordings performs a default gesture: no dynamic event."""
    recognizer = GestureRecognizer.from_params({})
    recognizer_index = GestureRecognizer.from_params({"spotter": {"source": "index"}})
    frames = frames_from_recording(path)
    dynamic = set(make_gesture_templates.LABELS)
    for rec in (recognizer, recognizer_index):
        events = [e.name for f in frames for e in rec.update(f)]
        assert not dynamic & set(events), events


# ---------------------------------------------------------------- template files


def test_shipped_templates_match_the_generator(tmp_path):
    make_gesture_templates.write_templates(str(tmp_path))
    shipped = sorted(glob.glob(os.path.join(DEFAULT_TEMPLATES, "*", "*.csv")))
    generated = sorted(glob.glob(os.path.join(str(tmp_path), "*", "*.csv")))
    assert [os.path.relpath(p, DEFAULT_TEMPLATES) for p in shipped] == [
        os.path.relpath(p, str(tmp_path)) for p in generated
    ]
    for a, b in zip(shipped, generated):
        with open(a) as fa, open(b) as fb:
            assert fa.read() == fb.read(), a


def test_save_template_numbers_files_and_round_trips(tmp_path):
    points = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.5], [7.0, 8.0, 9.0]] * 3)
    times = np.arange(9) * 10.0
    first = save_template(str(tmp_path), "wave_hi", points, times)
    second = save_template(str(tmp_path), "wave_hi", points, times)
    assert os.path.basename(first) == "001.csv" and os.path.basename(second) == "002.csv"
    item = read_path(first)
    assert np.allclose(item.points, points) and np.allclose(item.times, times)
    files, problems = load_templates(str(tmp_path))
    assert [f.label for f in files] == ["wave_hi", "wave_hi"] and not problems
    assert not [n for n in os.listdir(os.path.join(str(tmp_path), "wave_hi")) if n.endswith(".tmp")]


def test_atomic_write_leaves_the_old_file_when_writing_fails(tmp_path, monkeypatch):
    target = tmp_path / "g" / "001.csv"
    write_atomic(str(target), "old\n")

    def broken_fsync(fd):
        raise OSError("disk full")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(OSError):
        write_atomic(str(target), "new\n")
    assert target.read_text() == "old\n"
    assert os.listdir(str(tmp_path / "g")) == ["001.csv"]


def test_malformed_rows_are_skipped_with_a_reason(tmp_path):
    path = tmp_path / "A.csv"
    path.write_text("# comment\n1 2 3 0\n1 2 x 4\n1 2 3\n4,5,6,10\nnan 1 1 1\n")
    item = read_path(str(path))
    assert len(item.points) == 2 and len(item.skipped) == 3
    assert any("not numbers" in s for s in item.skipped) and any("3 values" in s for s in item.skipped)


def test_a_fist_is_not_a_pinch_clutch():
    """Leap reports a closed fist as pinched too: carrying a part must draw no gesture."""
    classifier = load_classifier(DEFAULT_TEMPLATES)
    rng = np.random.default_rng(3)
    path, _ = make_gesture_templates.gesture_path("swipe_up", rng, 90.0)
    frames = [
        GestureFrame(i / 90.0, p, pinch=1.0, grab=1.0 if 5 <= i < len(path) - 5 else 0.0) for i, p in enumerate(path)
    ]
    spotter = GestureSpotter(classifier, {"mode": "clutch"})
    assert [e.name for f in frames for e in spotter.update(f)] == []
    assert any(s.reason == "a fist, not a pinch" for s in spotter.segments)


def test_inverted_hysteresis_thresholds_are_refused_at_start_up():
    with pytest.raises(ParameterError, match="grab_off.*grab_on"):
        StaticPoseDetector({"grab_on": 0.5, "grab_off": 0.8}, "teach_gestures.yaml")
    with pytest.raises(ParameterError, match="clutch_off"):
        GestureSpotter(None, {"clutch_on": 0.5, "clutch_off": 0.7}, "teach_gestures.yaml")
