"""The webcam hand driver's parameters: the shipped config/webcam.yaml validates with its
units, a misspelt key is refused naming it, and every parameter the launch files set on
webcam_hand_driver is declared."""

import os
from xml.etree import ElementTree

import pytest
import yaml

from motion_common.errors import ParameterError
from motion_sensor.devices.webcam_device import WebcamHandDevice

from ..conftest import ROOT
from .test_sensor_params import node_schema

CONFIG = os.path.join(ROOT, "src", "motion_sensor", "config", "webcam.yaml")


def test_shipped_webcam_yaml_validates_and_documents_units():
    with open(CONFIG, encoding="utf-8") as fh:
        values = yaml.safe_load(fh)
    config = node_schema(WebcamHandDevice).validate(values, CONFIG)
    assert config["camera"] == 0 and config["video"] == "" and config["min_subscribers"] == 1
    text = open(CONFIG, encoding="utf-8").read()
    for key, param in WebcamHandDevice.params.params.items():
        if param.unit:  # the YAML states the unit next to the value
            line = next(line for line in text.splitlines() if line.startswith(key + ":"))
            assert param.unit.split("/")[0] in line or "deg" in line, (key, line)


def test_misspelt_key_is_refused():
    with pytest.raises(ParameterError, match="hfov_dg"):
        node_schema(WebcamHandDevice).validate({"hfov_dg": 70.0}, CONFIG)


def test_launch_files_set_only_declared_parameters():
    schema = node_schema(WebcamHandDevice)
    seen = 0
    for name in ("sensing.launch",):  # the sessions include it: no second copy of the block
        root = ElementTree.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", name)).getroot()
        nodes = [n for n in root.iter("node") if n.get("type") == "webcam_hand_driver"]
        assert nodes, name
        for param in nodes[0].findall("param"):
            seen += 1
            assert param.get("name") in schema.params or param.get("name") == "config_file", (name, param.attrib)
    assert seen >= 4
