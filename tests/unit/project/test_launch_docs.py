"""Project rule: every <arg> of every launch file says what it is for (a non-empty doc=,
which `roslaunch --ros-args FILE` prints). Also: the real kitting cell's launch switches the
electromagnet on the output the cell YAML names."""

import glob
import os
import xml.etree.ElementTree as ET

import pytest
import yaml

from ..conftest import ROOT

LAUNCH_FILES = sorted(glob.glob(os.path.join(ROOT, "src", "motion_bringup", "launch", "*.launch")))


def test_there_are_launch_files():
    assert LAUNCH_FILES, f"no launch files found in {ROOT}/src/motion_bringup/launch"


@pytest.mark.parametrize("path", LAUNCH_FILES, ids=os.path.basename)
def test_every_arg_has_a_doc(path):
    root = ET.parse(path).getroot()
    # An <arg> inside <include> passes a value to the included file (documented there);
    # every other <arg> declares one of this file's arguments.
    passed = {id(arg) for include in root.iter("include") for arg in include.findall("arg")}
    undocumented = [
        arg.get("name") for arg in root.iter("arg") if id(arg) not in passed and not (arg.get("doc") or "").strip()
    ]
    assert not undocumented, f"{os.path.basename(path)}: <arg> without a doc=: {undocumented}"


def _launch_args(name):
    root = ET.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", name)).getroot()
    return {arg.get("name"): arg.get("default") for arg in root.findall("arg")}


def test_kitting_ur_gripper_output_is_the_cells_magnet():
    with open(os.path.join(ROOT, "src", "kitting", "config", "cell.yaml"), encoding="utf-8") as stream:
        cell = yaml.safe_load(stream)
    args = _launch_args("kitting_ur.launch")
    assert int(args["gripper_output"]) == cell["gripper"]["output"]
    root = ET.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", "kitting_ur.launch")).getroot()
    params = {p.get("name"): p.get("value") for p in root.findall("param")}
    assert params["motion_controller_server/driver_params/gripper_output"] == "$(arg gripper_output)"
