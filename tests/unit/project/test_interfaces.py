"""Every node is declared once (its package's interfaces.py), and everything else agrees
with that declaration: docs/interfaces.md, the names the node scripts use, the shipped
YAML files, and the typed configs the Python API builds."""

import ast
import glob
import os
import re
import sys

import pytest
import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
while not os.path.isdir(os.path.join(ROOT, "src")):  # tests/unit/<package>/ or tests/unit/
    ROOT = os.path.dirname(ROOT)

sys.path.insert(0, os.path.join(ROOT, "scripts"))
import gen_interfaces  # noqa: E402
from motion_common.interface import NodeInterface, Topic  # noqa: E402

NODES = {node.node: node for node in gen_interfaces.all_interfaces()}

# Executables under src/*/nodes that are command-line tools, not ROS nodes of a session
# (no rospy.init_node, or an anonymous one-shot client): declared nowhere on purpose.
TOOLS = {
    "motion_controller_client",
    "calibrate_camera",
    "register_device",
    "webcam_hand_calibrate",
    "leap_replay_server",
    "gesture_eval",
    "train_skeleton_gestures",
    "record_gesture",
    "hands_to_csv",
}


def node_scripts():
    return sorted(glob.glob(os.path.join(ROOT, "src", "*", "nodes", "*")))


def test_docs_interfaces_is_up_to_date():
    with open(gen_interfaces.DOC, encoding="utf-8") as stream:
        assert stream.read() == gen_interfaces.render(), "docs/interfaces.md is stale: run scripts/gen_interfaces"


def test_every_node_is_declared_once():
    keys = [node.key for node in gen_interfaces.all_interfaces()]
    assert len(keys) == len(set(keys))
    for path in node_scripts():
        name = os.path.basename(path)
        if name in TOOLS:
            continue
        assert name in NODES, f"{path}: node without a declaration in its package's interfaces.py"


def test_declarations_refuse_absolute_names():
    with pytest.raises(ValueError, match="relative"):
        Topic("/joint_states", "sensor_msgs/JointState")
    with pytest.raises(ValueError, match="twice"):
        NodeInterface("p", "n", "", publishes=(Topic("a", "std_msgs/Bool"), Topic("a", "std_msgs/Bool")))


def test_lookup_of_an_undeclared_name_fails_with_the_declared_ones():
    with pytest.raises(KeyError, match="motion_states_stamped"):
        NODES["sequencer"].published("motion_state_stamped")


_CALLS = {"Publisher": "publishes", "Subscriber": "subscribes", "Service": "serves", "ServiceProxy": "calls"}


def literal_names(path):
    """(kind, name) of every rospy.Publisher/Subscriber/Service/ServiceProxy call with a
    literal name, and of every declared-name lookup (publisher(NODE, "name", ...))."""
    with open(path, encoding="utf-8") as stream:
        tree = ast.parse(stream.read(), path)
    found = []
    helpers = {"publisher": "publishes", "subscriber": "subscribes", "service": "serves", "service_proxy": "calls"}
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call):
            continue
        func = call.func
        if isinstance(func, ast.Attribute) and func.attr in _CALLS and call.args:
            arg = call.args[0]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                found.append((_CALLS[func.attr], arg.value))
        if isinstance(func, ast.Name) and func.id in helpers and len(call.args) >= 2:
            arg = call.args[1]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                found.append((helpers[func.id], arg.value))
    return found


@pytest.mark.parametrize(
    "path",
    [p for p in node_scripts() if os.path.basename(p) in NODES]
    + [os.path.join(ROOT, "src", "dashboard", "dashboard", "dashboard_node.py")],
    ids=os.path.basename,
)
def test_node_scripts_use_only_declared_relative_names(path):
    name = os.path.basename(path)
    node = NODES["dashboard" if name == "dashboard_node.py" else name]
    for kind, topic in literal_names(path):
        assert not topic.startswith("/"), f"{path}: absolute name {topic!r}; use a relative one"
        declared = [entry.name for entry in getattr(node, kind)]
        if kind == "subscribes" and topic not in declared and name == "dashboard_node.py":
            continue
        assert topic in declared, f"{path}: {kind} {topic!r} is not in {node.key}'s declaration {declared}"


def test_no_absolute_names_in_the_source():
    """Names go through launch files: no rospy call in src/ names an absolute topic."""
    pattern = re.compile(
        r"rospy\.(Publisher|Subscriber|Service|ServiceProxy|wait_for_service|wait_for_message)"
        r"\(\s*[\"']/"
    )
    offenders = []
    for path in glob.glob(os.path.join(ROOT, "src", "**", "*"), recursive=True):
        if os.path.isfile(path) and (path.endswith(".py") or "/nodes/" in path):
            with open(path, encoding="utf-8", errors="replace") as stream:
                if pattern.search(stream.read()):
                    offenders.append(path)
    assert not offenders


def _config(package, name):
    return os.path.join(ROOT, "src", package, "config", name)


def _device_params(module, cls):
    from motion_sensor.devices.device_interface import node_schema

    mod = __import__(f"motion_sensor.devices.{module}", fromlist=[cls])
    return node_schema(getattr(mod, cls))


def yaml_schema_pairs():
    from dashboard.config import DASHBOARD_PARAMETERS
    from motion_commander.config import TELEOP_PARAMETERS
    from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS

    return [
        (_config("motion_commander", "teleop.yaml"), TELEOP_PARAMETERS),
        (_config("motion_sensor", "sequencer.yaml"), SEQUENCER_PARAMS),
        (_config("motion_sensor", "replay.yaml"), _device_params("replay", "ReplayDevice")),
        (_config("motion_sensor", "leap.yaml"), _device_params("leap_client", "LeapDevice")),
        (_config("motion_sensor", "spacemouse.yaml"), _device_params("spacemouse", "SpaceMouseDevice")),
        (_config("dashboard", "dashboard.yaml"), DASHBOARD_PARAMETERS),
    ]


def _filled(param, value):
    """A nested mapping with every declared default filled in, so {} and a mapping that
    spells the defaults out compare equal."""
    if param.schema is None or not isinstance(value, dict):
        return value
    values = param.schema.validate(value, "test")
    return {name: _filled(param.schema.params[name], values[name]) for name in values}


def test_shipped_yaml_holds_exactly_the_declared_defaults():
    """The shipped YAML files are templates of the declaration: every key they set has its
    declared default, so a node launched with them and the Python API built without them
    run with the same values (docs/parameters.md says why)."""
    problems = []
    for path, schema in yaml_schema_pairs():
        with open(path, encoding="utf-8") as stream:
            values = yaml.safe_load(stream) or {}
        checked = schema.validate(values, path)
        defaults = schema.validate({}, path)
        for key in values:
            if _filled(schema.params[key], checked[key]) != _filled(schema.params[key], defaults[key]):
                problems.append(
                    f"{os.path.relpath(path, ROOT)}: {key} = {checked[key]!r}, declared default {defaults[key]!r}"
                )
    assert not problems, "\n".join(problems)


def test_python_api_gets_the_declared_defaults():
    """A core, a sequencer and a driver built from Python without any YAML get exactly what
    the launched nodes get from their declarations."""
    from motion_commander.config import TELEOP_PARAMETERS, TeleopConfig, load_teleop_config
    from motion_commander.teleop_core import SafetyConfig
    from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS, SequencerConfig, sequencer_setup

    assert TeleopConfig() == load_teleop_config({})
    safety = SafetyConfig()
    for key in ("joint_acceleration", "joint_speed_scale", "workspace_lower", "workspace_upper", "floor_z"):
        assert getattr(safety, key) == TELEOP_PARAMETERS.params[key].default
    assert safety.joint_acceleration == 200.0  # never "unlimited" by omission
    config, _ = sequencer_setup(SEQUENCER_PARAMS.validate({}, "test"), "test")
    built = SequencerConfig()
    for key in ("max_age_s", "entry_trim_frames", "jump_distance_m", "device_timeout_s", "filter_name"):
        assert getattr(built, key) == getattr(config, key)


def test_typed_configs_check_their_values_against_the_declaration():
    from motion_commander.teleop_core import SafetyConfig
    from motion_common.errors import ParameterError

    with pytest.raises(ParameterError, match="joint_speed_scale"):
        SafetyConfig(joint_speed_scale=2.0)
    with pytest.raises(ParameterError, match="singularity_slowdown"):
        SafetyConfig(singularity_slowdown=90.0)
