"""Teaching on hand-skeleton gestures: a stream of real SHREC'17 sequences
(tests/data/shrec17_slice.npz: tap, grab, expand, swipe left, shake of subject 2, with
idle gaps) through the skeleton spotter and the shipped model, each gesture mapped by
config/skeleton_gesture_commands.yaml to a teach command of a TeachSession; and the
operator stream of the skeleton teach demo (data/skeleton_teach_demo.npz, what
teach_sim.launch gestures:=skeleton plays), checked without ROS."""

import os
import sys

import numpy as np
import yaml

from motion_apps.teach import TeachSession, load_gesture_config
from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, load_skeleton_dataset
from motion_sensor.gestures.skeleton_spotter import SkeletonSpotter
from motion_sensor.gestures.skeleton_stream import build_stream

from ..conftest import DATA, ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import make_skeleton_teach_stream  # noqa: E402

COMMANDS = os.path.join(ROOT, "src", "motion_apps", "config", "skeleton_gesture_commands.yaml")
TEACH_SPOTTER = os.path.join(ROOT, "src", "motion_apps", "config", "skeleton_teach_spotter.yaml")
DEMO = os.path.join(ROOT, "src", "motion_apps", "data", "skeleton_teach_demo.npz")
ORDER = ("tap", "grab", "expand", "swipe_left", "shake")


def test_skeleton_commands_file_maps_the_operator_gestures():
    config = load_gesture_config(COMMANDS)
    assert config["commands"] == {
        "grab": "grip",
        "expand": "release",
        "tap": "mark_waypoint",
        "swipe_left": "undo",
        "shake": "stop",
    }
    assert set(config["commands"]) <= set(CLASSES_14)


def test_teach_session_runs_on_skeleton_gestures(tmp_path):
    data = load_skeleton_dataset(os.path.join(DATA, "shrec17_slice.npz"))
    picked = []
    for name in ORDER:
        picked.append(next(i for i in range(len(data)) if data.subject[i] == 2 and CLASSES_14[data.label14[i]] == name))
    stamps, joints, truth = build_stream(
        [data.sequences[i] for i in picked], list(ORDER), np.random.default_rng(5), order=range(len(picked))
    )
    config = load_gesture_config(COMMANDS)
    spotter = SkeletonSpotter(SkeletonClassifier(), {"labels": sorted(config["commands"])})
    now = {"t": 0.0}

    def robot_state():  # the tool moves on while the operator teaches
        return [0.4 + 0.01 * now["t"], 0.0, 0.3], [0.0, 0.0, 0.0, 1.0], [0.0] * 6

    session = TeachSession("ur5e", robot_state, programs_dir=str(tmp_path), program_name="skel", config=config)
    feedback = []
    for stamp, frame in zip(stamps, joints, strict=True):
        now["t"] = stamp
        for event in spotter.update(stamp, frame):
            feedback.append((event.name, session.on_gesture(event.name, event.stamp)))
    for event in spotter.finish():
        feedback.append((event.name, session.on_gesture(event.name, event.stamp)))
    names = [name for name, _ in feedback]
    assert names == list(ORDER), feedback
    assert all(answer.understood for _, answer in feedback), feedback
    # tap -> waypoint, grab -> grip, expand -> release, swipe left -> undo (the release), shake -> stop (saved)
    assert [w.action for w in session.program().waypoints] == ["none", "grip"]
    assert session.stopped and session.saved_path and os.path.isfile(session.saved_path)


def test_shipped_skeleton_teach_stream_is_what_the_generator_writes(tmp_path):
    out = str(tmp_path / "demo.npz")
    make_skeleton_teach_stream.main(["--output", out])
    written, shipped = np.load(out), np.load(DEMO)
    assert sorted(written.files) == sorted(shipped.files)
    for name in shipped.files:
        np.testing.assert_array_equal(written[name], shipped[name], err_msg=name)


def test_skeleton_teach_stream_teaches_at_the_designed_places():
    """As shrec_stream_driver plays it (file order, 1.2 s rests) and the teach session's
    spotter settings take it: every gesture is spotted with its label, and the palm, moved
    as the tool follows it, is where the command must be taken (within 1 cm): the grip at
    the part, the release at the place."""
    data = load_skeleton_dataset(DEMO)
    script = make_skeleton_teach_stream.SCRIPT
    assert [CLASSES_14[k] for k in data.label14] == [label for _, label, _ in script]
    stamps, joints, _ = build_stream(
        data.sequences,
        [CLASSES_14[k] for k in data.label14],
        np.random.default_rng(0),
        hold_s=(1.2, 1.2),
        order=range(len(data)),
    )
    config = load_gesture_config(COMMANDS)
    with open(TEACH_SPOTTER, encoding="utf-8") as handle:
        settings = yaml.safe_load(handle)
    assert sorted(settings["labels"]) == sorted(config["commands"])
    spotter = SkeletonSpotter(SkeletonClassifier(), settings)
    found = []
    for stamp, frame in zip(stamps, joints, strict=True):
        found += [(e.name, frame[1] - joints[0, 1]) for e in spotter.update(stamp, frame)]
    assert [name for name, _ in found] == [label for _, label, _ in script]
    for (_, palm), (_, _, tool) in zip(found, script, strict=True):
        if tool is not None:
            np.testing.assert_allclose(make_skeleton_teach_stream.START + palm, tool, atol=0.01)
