"""motion_controller_server's parameters: the shipped YAMLs pass their schemas (server and
driver), an unknown or out-of-range key is refused naming the file and the valid keys."""

import os

import pytest
import yaml

from hw_interface.server_params import SERVER_PARAMETERS, check_server_params
from motion_common.errors import ParameterError

from ..conftest import ROOT, UR5E

CONFIG = os.path.join(ROOT, "src", "hw_interface", "config")


def load(name, **extra):
    values = yaml.safe_load(open(os.path.join(CONFIG, name), encoding="utf-8"))
    values.update(urdf=UR5E, **extra)
    return values


@pytest.mark.parametrize(
    "name, driver", [("sim_driver.yaml", None), ("ur_driver.yaml", None), ("ur_driver.yaml", "ur_rtde_fake")]
)
def test_shipped_configs_pass(name, driver):
    values = load(name)
    if driver:
        values["driver"] = driver
        values["driver_params"]["initial_joints"] = [0.0] * 6
    params = check_server_params(values, name)
    assert params["move_timeout"] == 60.0 and params["driver_params"]
    assert SERVER_PARAMETERS.params["move_timeout"].unit == "s"


def test_unknown_server_key_names_file_and_valid_keys():
    with pytest.raises(ParameterError, match=r"sim_driver.yaml.*unknown parameter 'move_timout'.*valid keys"):
        check_server_params(load("sim_driver.yaml", move_timout=3.0), "sim_driver.yaml")


def test_unknown_or_bad_driver_key_is_refused():
    values = load("ur_driver.yaml")
    values["driver_params"]["fake_controller"] = True
    with pytest.raises(
        ParameterError,
        match=r"ur_driver.yaml: driver_params of driver 'ur_rtde'.*"
        r"unknown parameter 'fake_controller'.*valid keys",
    ):
        check_server_params(values, "ur_driver.yaml")
    values = load("ur_driver.yaml")
    values["driver_params"]["lookahead_time"] = 0.5
    with pytest.raises(ParameterError, match=r"lookahead_time' \(s\) must be in \[0.03, 0.2\]"):
        check_server_params(values, "ur_driver.yaml")
    values = load("sim_driver.yaml")
    values["driver_params"]["goal_tolerance"] = 0.0
    with pytest.raises(ParameterError, match="goal_tolerance"):
        check_server_params(values, "sim_driver.yaml")


def test_unknown_driver_is_named():
    with pytest.raises(ParameterError, match="kuka_magic.*available"):
        check_server_params(load("sim_driver.yaml", driver="kuka_magic"), "sim_driver.yaml")
