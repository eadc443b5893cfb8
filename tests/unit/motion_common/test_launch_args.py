"""Launch arguments: what a launch file accepts (with pass_all_args includes), name:=value
parsing, and unknown names refused with the closest declared ones."""

import pytest

from motion_common.errors import ParameterError
from motion_common.launch_args import declared_args, parse_assignments, suggestion, unknown_args

from ..conftest import ROOT

LAUNCH = f"{ROOT}/src/motion_bringup/launch"


def write(path, text):
    path.write_text(f'<?xml version="1.0"?>\n<launch>\n{text}\n</launch>\n')
    return str(path)


def test_declared_args_follow_pass_all_args_includes_only(tmp_path):
    write(tmp_path / "child.launch", '<arg name="port" default="8080" doc="the port"/>')
    write(tmp_path / "other.launch", '<arg name="hidden" default="x"/>')
    top = write(
        tmp_path / "top.launch",
        '<arg name="robot" default="ur5e" doc="model"/><arg name="fixed" value="1"/>'
        '<arg name="needed"/>'
        '<include file="$(dirname)/child.launch" pass_all_args="true"/>'
        '<include file="$(dirname)/other.launch"><arg name="hidden" value="y"/></include>',
    )
    args = declared_args(top)
    assert sorted(args) == ["needed", "port", "robot"]  # a fixed value is not settable
    assert args["robot"].default == "ur5e" and args["robot"].doc == "model"
    assert args["needed"].default is None and args["port"].file.endswith("child.launch")


def test_session_launch_files_accept_their_dashboard_arguments():
    args = declared_args(f"{LAUNCH}/teleop_sim.launch")
    for name in ("speed_ratio", "robot_config", "driver", "driver_params", "dashboard_port", "device"):
        assert name in args, name


def test_missing_and_broken_launch_files_are_named(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        declared_args(str(tmp_path / "none.launch"))
    (tmp_path / "bad.launch").write_text("<launch><arg name=")
    with pytest.raises(ParameterError, match="not valid XML"):
        declared_args(str(tmp_path / "bad.launch"))


def test_assignments_are_parsed_and_malformed_words_explained():
    assert parse_assignments(["a:=1", "b_c:=x:=y", "e:="]) == {"a": "1", "b_c": "x:=y", "e": ""}
    with pytest.raises(ParameterError, match=r"name:=value \(write name:=value\)"):
        parse_assignments(["speed_ratio=0.5"])
    with pytest.raises(ParameterError, match="not of the form"):
        parse_assignments(["--gui"])
    with pytest.raises(ParameterError, match="given twice"):
        parse_assignments(["a:=1", "a:=2"])


def test_unknown_names_get_the_closest_declared_ones():
    declared = {"speed_ratio": None, "robot": None, "recording": None}
    assert unknown_args({"speed_ration": "0.5", "robot": "x"}, declared) == [
        "unknown argument 'speed_ration' (did you mean 'speed_ratio'?)"
    ]
    assert suggestion("zzz", declared) == ""
