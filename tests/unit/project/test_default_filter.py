"""A session started without filter:= runs the sequencer's declared default filter: every
launch file that sets the sequencer's filter defaults to it, and so does sequencer.yaml."""

import os

import pytest
import yaml

from motion_common.launch_args import declared_args
from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS

from ..conftest import ROOT

LAUNCH = os.path.join(ROOT, "src", "motion_bringup", "launch")


@pytest.mark.parametrize("name", ["teleop_sim.launch", "sensing.launch", "bimanual_sim.launch"])
def test_launch_files_default_to_the_declared_filter(name):
    assert declared_args(os.path.join(LAUNCH, name))["filter"].default == SEQUENCER_PARAMS.defaults()["filter"]


def test_sequencer_yaml_names_the_declared_filter():
    with open(os.path.join(ROOT, "src", "motion_sensor", "config", "sequencer.yaml"), encoding="utf-8") as stream:
        assert yaml.safe_load(stream)["filter"] == SEQUENCER_PARAMS.defaults()["filter"]
