"""Every motion_sensor node's parameters through motion_common.params: the shipped YAMLs
validate, a misspelt key is refused naming the file, the key and the valid keys, and every
parameter the launch files and rostests set is declared."""

import inspect
import os
import re
import shutil

import pytest
import yaml

from motion_common.errors import ParameterError
from motion_sensor.devices.leap_client import LeapDevice
from motion_sensor.devices.replay import ReplayDevice
from motion_sensor.devices.spacemouse import SpaceMouseDevice
from motion_sensor.sequencing.filters import FILTER_PARAMS, FILTERS
from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS, Sequencer, sequencer_setup

from ..conftest import ROOT

CONFIG = os.path.join(ROOT, "src", "motion_sensor", "config")


def node_schema(device_cls):
    """The device node's schema, from its ROS-free declaration."""
    from motion_sensor.devices.device_interface import node_schema as schema

    return schema(device_cls)


SCHEMAS = {
    "sequencer.yaml": lambda: SEQUENCER_PARAMS,
    "spacemouse.yaml": lambda: node_schema(SpaceMouseDevice),
    "leap.yaml": lambda: node_schema(LeapDevice),
    "replay.yaml": lambda: node_schema(ReplayDevice),
}


def load(name):
    with open(os.path.join(CONFIG, name), encoding="utf-8") as fh:
        return yaml.safe_load(fh)


@pytest.mark.parametrize("name", sorted(SCHEMAS))
def test_shipped_yaml_validates(name):
    SCHEMAS[name]().validate(load(name), name)


def test_shipped_sequencer_yaml_builds_every_filter():
    params = SEQUENCER_PARAMS.validate(load("sequencer.yaml"), "sequencer.yaml")
    for name in ("mean", "one_euro", "kalman"):
        config, inputs = sequencer_setup({**params, "filter": name}, "sequencer.yaml")
        Sequencer(config)
        assert inputs == [{"topic": "~input", "device": "default", "priority": 0}]
    config, _ = sequencer_setup({**params, "filter": "mean", "queue_size": 4}, "x")
    assert config.filter_params == {"queue_size": 4}


@pytest.mark.parametrize(
    "name,misspelt",
    [
        ("sequencer.yaml", "max_age"),
        ("spacemouse.yaml", "deadzon"),
        ("leap.yaml", "hots"),
        ("replay.yaml", "start_ofset"),
    ],
)
def test_misspelt_key_in_a_copy_is_refused_with_file_key_and_valid_keys(tmp_path, name, misspelt):
    copy = tmp_path / name
    shutil.copy(os.path.join(CONFIG, name), copy)
    text = copy.read_text()
    right = {"max_age": "max_age_s", "deadzon": "deadzone", "hots": "host", "start_ofset": "start_offset"}[misspelt]
    copy.write_text(re.sub(rf"^{right}:", f"{misspelt}:", text, flags=re.M))
    with pytest.raises(ParameterError) as error:
        SCHEMAS[name]().validate(yaml.safe_load(copy.read_text()), str(copy))
    message = str(error.value)
    assert str(copy) in message and f"'{misspelt}'" in message and "valid keys" in message and right in message


def test_unknown_filter_param_stops_the_sequencer(tmp_path):
    values = load("sequencer.yaml")
    values["filter_params"]["one_euro"]["betta"] = 1.0
    with pytest.raises(ParameterError, match=r"'filter_params'.*'one_euro'.*unknown parameter 'betta'.*beta_rot"):
        SEQUENCER_PARAMS.validate(values, "sequencer.yaml")
    values = load("sequencer.yaml")
    values["filter_params"]["kalman"]["switch_probability"] = 0.7
    with pytest.raises(ParameterError, match="switch_probability"):
        SEQUENCER_PARAMS.validate(values, "sequencer.yaml")
    with pytest.raises(ParameterError, match="inputs"):
        sequencer_setup(SEQUENCER_PARAMS.validate({"inputs": [{"topic": "/a", "prio": 1}]}, "x"), "x")


def test_filter_schema_defaults_are_the_constructors():
    for name, cls in FILTERS.items():
        signature = inspect.signature(cls.__init__)
        declared = FILTER_PARAMS.params[name].schema.defaults()
        assert declared == {k: p.default for k, p in signature.parameters.items() if k != "self"}, name


LAUNCH_NODES = {
    "sequencer": lambda: SEQUENCER_PARAMS,
    "spacemouse_driver": lambda: node_schema(SpaceMouseDevice),
    "leap_driver": lambda: node_schema(LeapDevice),
    "hand_replay": lambda: node_schema(ReplayDevice),
}


def test_every_param_launch_files_and_rostests_set_is_declared():
    from xml.etree import ElementTree

    files = [
        os.path.join(ROOT, "src", "motion_bringup", "launch", f)
        for f in os.listdir(os.path.join(ROOT, "src", "motion_bringup", "launch"))
        if f.endswith(".launch")
    ]
    files += [os.path.join(ROOT, "tests", "rostest", f) for f in os.listdir(os.path.join(ROOT, "tests", "rostest"))]
    seen = 0
    for path in files:
        root = ElementTree.parse(path).getroot()
        for node in root.iter("node"):
            if node.get("pkg") == "motion_sensor" and node.get("type") in LAUNCH_NODES:
                schema = LAUNCH_NODES[node.get("type")]()
                for param in node.findall("param"):
                    seen += 1
                    assert param.get("name") in schema.params or param.get("name") == "config_file", (
                        path,
                        param.attrib,
                    )
        for param in root.findall("param"):  # e.g. <param name="hand_replay/topic" .../>
            node, _, key = param.get("name").rpartition("/")
            if node in LAUNCH_NODES:
                seen += 1
                assert key in LAUNCH_NODES[node]().params, (path, param.attrib)
    assert seen > 10
