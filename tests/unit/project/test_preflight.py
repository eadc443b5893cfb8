"""The session pre-flight check (scripts/preflight.py): every mistake of a first hour is
refused before any ROS process starts, with where the value came from and the fix."""

import os
import sys

import pytest

from ..conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from preflight import check_session  # noqa: E402

LAUNCH = os.path.join(ROOT, "src", "motion_bringup", "launch")
TELEOP = os.path.join(LAUNCH, "teleop_sim.launch")
URDF = os.path.join(ROOT, "src", "motion_common", "urdf")
ROBOTS = os.path.join(ROOT, "src", "motion_common", "config", "robots")
EXAMPLES = os.path.join(ROOT, "examples")


@pytest.fixture(autouse=True)
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.syspath_prepend(EXAMPLES)


@pytest.mark.parametrize(
    "launch", ["teleop_sim", "teach_sim", "kitting_sim", "bimanual_sim", "teleop_ur", "kitting_ur", "sensing"]
)
def test_every_session_passes_with_its_defaults(launch):
    assert check_session(os.path.join(LAUNCH, f"{launch}.launch"), []) == []


@pytest.mark.parametrize(
    "args, expected",
    [
        (["speed_ration:=0.5"], r"unknown argument 'speed_ration' \(did you mean 'speed_ratio'\?\)"),
        (["speed_ratio=0.5"], r"not of the form name:=value \(write name:=value\)"),
        (["record:=yes"], r"command line record:=yes: must be true or false"),
        (
            ["filter:=butterworth"],
            r"command line filter:=butterworth: node sequencer: parameter 'filter' must be one of",
        ),
        (["speed_ratio:=abc"], r"command line speed_ratio:=abc: node motion_commander: parameter 'speed_ratio'"),
        (["speed_ratio:=70"], r"command line speed_ratio:=70: .* must be in \(0, 10\]"),
        (["queue_size:=0"], r"command line queue_size:=0: .*'queue_size' \(frames\) must be in \[1, 10000\]"),
        (["recording:=/nowhere/hand.jsonl.gz"], r"command line recording:=/nowhere/hand.jsonl.gz: .* does not exist"),
        (["device:=leapp"], r"unknown device \(did you mean 'leap'\?\)"),
        (["device:=nomodule:Glove"], r"cannot load 'Glove' from 'nomodule'"),
        (["driver:=kuka_magic"], r"no robot driver named 'kuka_magic'"),
        (["driver:=kinematic_driver:Nope"], r"module 'kinematic_driver' has no 'Nope'"),
        ([f"urdf:={URDF}/tx90.urdf"], r"without robot_config:=FILE: the start pose would be the ur5e's"),
        (["robot:=tx90", f"robot_config:={ROBOTS}/ur5e.yaml", "rviz:=true"], r"rviz"),
        (["gui:=true"], r"gui:=true needs a display and DISPLAY is not set"),
        (["device:=spacemouse", "engage:=gesture"], r"the SpaceMouse shows no second hand; use engage:=button"),
    ],
)
def test_mistakes_are_refused_with_their_origin_and_fix(args, expected):
    errors = check_session(TELEOP, args)
    assert errors, f"{args} was accepted"
    assert any(__import__("re").search(expected, e) for e in errors), errors


def test_a_start_pose_for_another_robot_is_refused(tmp_path):
    pose = tmp_path / "pose.yaml"
    pose.write_text("initial_joints: [0.0, 0.0, 0.0]\n")
    errors = check_session(TELEOP, [f"robot_config:={pose}"])
    assert any("initial_joints has 3 values but ur5e.urdf has 6 joints" in e for e in errors), errors
    pose.write_text("initial_joints: [0.0, 0.0, 9.0, 0.0, 0.0, 0.0]\n")
    errors = check_session(TELEOP, [f"robot_config:={pose}"])
    assert any("outside the joint limits" in e for e in errors), errors


def test_a_bad_driver_parameter_names_its_file(tmp_path):
    params = tmp_path / "driver.yaml"
    params.write_text("joint_speed: -1.0\n")
    errors = check_session(TELEOP, ["driver:=kinematic_driver:KinematicDriver", f"driver_params:={params}"])
    assert any("joint_speed" in e for e in errors), errors


def test_your_own_robot_driver_and_device_pass():
    args = [
        f"urdf:={URDF}/tx90.urdf",
        f"robot_config:={ROBOTS}/tx90.yaml",
        "driver:=kinematic_driver:KinematicDriver",
        "device:=circle_device:CircleDevice",
    ]
    assert check_session(TELEOP, args) == []


def test_a_dataset_folder_that_cannot_be_written_is_refused_before_the_start(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    errors = check_session(TELEOP, [f"dataset:={blocker}/set", "dataset_start:=true"])
    assert len(errors) == 1 and errors[0].startswith(f"command line dataset:={blocker}/set: dataset folder")
    assert "is not a folder" in errors[0]
    import shutil

    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(10**9, 10**9 - 10**7, 10**7))
    errors = check_session(TELEOP, [f"dataset:={tmp_path}/set"])
    assert len(errors) == 1 and "only 10 MB free" in errors[0]
