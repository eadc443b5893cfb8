"""The depth devices' parameters: the shipped YAMLs validate (with the node wrapper's
parameters), a misspelt key is refused naming it, and every parameter the launch files set
on depth_hand_driver / kinect_driver is declared."""

import os
from xml.etree import ElementTree

import pytest
import yaml

from motion_common.errors import ParameterError
from motion_sensor.devices.depth_device import DepthTopicDevice
from motion_sensor.devices.kinect import KinectDevice

from ..conftest import ROOT
from .test_sensor_params import node_schema

CONFIG = os.path.join(ROOT, "src", "motion_sensor", "config")


def load(name):
    with open(os.path.join(CONFIG, name), encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def test_shipped_yamls_validate():
    depth = node_schema(DepthTopicDevice).validate(load("depth_hand.yaml"), "depth_hand.yaml")
    assert "image_topic" not in depth and depth["min_depth_m"] <= 0.4
    assert depth["max_depth_m"] >= 1.2  # the working volume reaches 0.4-1.2 m at least
    kinect = node_schema(KinectDevice).validate({**load("depth_hand.yaml"), **load("kinect.yaml")}, "kinect.yaml")
    assert kinect["depth_format"] == "mm" and len(kinect["intrinsics_px"]) == 4


@pytest.mark.parametrize("device,key", [(DepthTopicDevice, "max_dept_m"), (KinectDevice, "device_idx")])
def test_misspelt_key_is_refused(device, key):
    with pytest.raises(ParameterError, match=key):
        node_schema(device).validate({key: 1}, "x.yaml")


def test_launch_params_are_declared():
    schemas = {"depth_hand_driver": node_schema(DepthTopicDevice), "kinect_driver": node_schema(KinectDevice)}
    seen = set()
    # The device blocks live in sensing.launch only; the sessions include it.
    for name in ("sensing.launch", "teleop_sim.launch"):
        root = ElementTree.parse(os.path.join(ROOT, "src", "motion_bringup", "launch", name)).getroot()
        for node in root.iter("node"):
            if node.get("type") in schemas:
                seen.add((name, node.get("type")))
                for param in node.findall("param"):
                    assert param.get("name") in schemas[node.get("type")].params or param.get("name") == "config_file"
    assert seen == {("sensing.launch", "depth_hand_driver"), ("sensing.launch", "kinect_driver")}
