"""Every session launch offers the dashboard: dashboard, dashboard_port, dashboard_host and
dashboard_token arguments, and launch/dashboard.launch included only with dashboard:=true
(directly, or through the session launch it includes)."""

import os
import xml.etree.ElementTree as ET

import pytest

from ..conftest import ROOT

SESSIONS = ["teleop_sim.launch", "teleop_ur.launch", "teach_sim.launch", "kitting_sim.launch", "kitting_ur.launch"]
ARGS = {"dashboard": "false", "dashboard_port": "8080", "dashboard_host": "127.0.0.1", "dashboard_token": ""}


def parse(name):
    return ET.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", name)).getroot()


@pytest.mark.parametrize("name", SESSIONS)
def test_session_launch_has_the_dashboard_arguments(name):
    declared = {arg.get("name"): arg.get("default") for arg in parse(name).findall("arg")}
    assert {key: declared.get(key) for key in ARGS} == ARGS


@pytest.mark.parametrize("name", SESSIONS)
def test_dashboard_is_included_only_when_asked(name):
    root = parse(name)
    direct = [inc for inc in root.findall("include") if inc.get("file", "").endswith("/dashboard.launch")]
    if direct:
        assert [inc.get("if") for inc in direct] == ["$(arg dashboard)"]
        passed = {arg.get("name"): arg.get("value") for arg in direct[0].findall("arg")}
    else:  # through the session launch it wraps, with dashboard passed on
        wrapped = [
            inc for inc in root.findall("include") if any(arg.get("name") == "dashboard" for arg in inc.findall("arg"))
        ]
        assert wrapped, f"{name} neither includes dashboard.launch nor passes dashboard on"
        passed = {arg.get("name"): arg.get("value") for arg in wrapped[0].findall("arg")}
    for key in ("dashboard_port", "dashboard_host", "dashboard_token"):
        assert passed.get(key) == f"$(arg {key})", f"{name} does not pass {key}"


def test_dashboard_launch_binds_locally_without_a_token_by_default():
    declared = {arg.get("name"): arg.get("default") for arg in parse("dashboard.launch").findall("arg")}
    assert declared["dashboard_host"] == "127.0.0.1" and declared["dashboard_token"] == ""
