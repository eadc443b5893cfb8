"""Every session launch offers the dashboard: a dashboard argument, and dashboard.launch
included only with dashboard:=true (directly, or through the session launch it wraps), with
every argument passed through, so that dashboard.launch alone declares the dashboard's own
(dashboard_port, dashboard_host, dashboard_token, dashboard_token_file)."""

import os
import xml.etree.ElementTree as ET

import pytest

from ..conftest import ROOT

SESSIONS = ["teleop_sim.launch", "teleop_ur.launch", "teach_sim.launch", "kitting_sim.launch", "kitting_ur.launch"]
OWN = ("dashboard_port", "dashboard_host", "dashboard_token", "dashboard_token_file")


def parse(name):
    return ET.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", name)).getroot()


@pytest.mark.parametrize("name", SESSIONS)
def test_session_launch_has_the_dashboard_switch_and_declares_nothing_else_of_it(name):
    declared = {arg.get("name"): arg.get("default") for arg in parse(name).findall("arg")}
    assert declared.get("dashboard") == "false"
    assert not [key for key in OWN if key in declared], f"{name} repeats dashboard.launch's arguments"


@pytest.mark.parametrize("name", SESSIONS)
def test_dashboard_is_included_only_when_asked_with_every_argument_passed(name):
    root = parse(name)
    direct = [inc for inc in root.findall("include") if inc.get("file", "").endswith("/dashboard.launch")]
    if direct:
        assert [inc.get("if") for inc in direct] == ["$(arg dashboard)"]
        assert direct[0].get("pass_all_args") == "true"
    else:  # through the session launch it wraps, with every argument passed on
        wrapped = [inc for inc in root.findall("include") if inc.get("file", "").endswith("_sim.launch")]
        assert wrapped and wrapped[0].get("pass_all_args") == "true", f"{name} does not pass the dashboard on"


def test_dashboard_launch_declares_its_arguments_binds_locally_without_a_token_by_default():
    declared = {arg.get("name"): arg.get("default") for arg in parse("dashboard.launch").findall("arg")}
    assert all(key in declared for key in OWN)
    assert declared["dashboard_host"] == "127.0.0.1" and declared["dashboard_token"] == ""


APPLICATION_OF = {
    "teleop_sim.launch": "teleop",
    "teach_sim.launch": "teach",
    "kitting_sim.launch": "kitting",
    "kitting_ur.launch": "kitting",
}


def test_dashboard_launch_takes_application_device_and_urdf_from_the_session():
    root = parse("dashboard.launch")
    declared = {arg.get("name"): arg.get("default") for arg in root.findall("arg")}
    assert declared["application"] == "auto" and declared["device"] == "" and declared["urdf"] == ""
    params = {param.get("name"): param.get("value") for param in root.find("node").findall("param")}
    assert params["application"] == "$(arg application)"
    assert params["device"] == "$(arg device)"
    assert params["urdf"] == "$(arg urdf)"


@pytest.mark.parametrize("name", sorted(APPLICATION_OF))
def test_each_session_tells_the_dashboard_its_application(name):
    direct = [inc for inc in parse(name).findall("include") if inc.get("file", "").endswith("/dashboard.launch")]
    given = {arg.get("name"): arg.get("value") for arg in direct[0].findall("arg")}
    assert given == {"application": APPLICATION_OF[name]}
