"""Teaching on hand-skeleton gestures: a stream of real SHREC'17 sequences
(tests/data/shrec17_slice.npz: tap, grab, expand, swipe left, shake of subject 2, with
idle gaps) through the skeleton spotter and the shipped model, each gesture mapped by
config/skeleton_gesture_commands.yaml to a teach command of a TeachSession."""

import os

import numpy as np

from motion_apps.teach import TeachSession, load_gesture_config
from motion_sensor.gestures.skeleton_classifier import SkeletonClassifier
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, load_skeleton_dataset
from motion_sensor.gestures.skeleton_spotter import SkeletonSpotter
from motion_sensor.gestures.skeleton_stream import build_stream

from ..conftest import DATA, ROOT

COMMANDS = os.path.join(ROOT, "src", "motion_apps", "config", "skeleton_gesture_commands.yaml")
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
