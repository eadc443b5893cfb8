"""Checks a session's launch arguments and every node's parameters before the graph starts.

A mistake found once the ROS graph is up costs the user ~10 s and a log to read; here it
costs well under a second and names the fix. ``check_session`` returns one message per
problem (an empty list: go):
- every ``name:=value`` against the arguments the launch file declares ("did you mean");
- true/false arguments;
- the launch file resolved by roslaunch's own loader (a missing file, a bad substitution);
- each node's private parameters against its declaration (``interfaces.py``), naming where a
  bad value came from: the command line, or the YAML file the launch file loaded;
- files the nodes will open: the recording, the SpaceMouse log, the video, the Kinect dump;
  the folders they write: a recorded dataset's (writable, enough free disk);
- the robot: the URDF loads, the start pose has one value per joint inside the limits and
  puts the tool inside the workspace box; the driver and its parameters;
- tools and display: rviz installed, a display for gui:=true or rviz:=true.

Used by scripts/run_session (and its --check); plain Python apart from roslaunch's loader.
"""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from gen_interfaces import all_interfaces  # noqa: E402
from motion_common.errors import ParameterError  # noqa: E402
from motion_common.launch_args import declared_args, parse_assignments, unknown_args  # noqa: E402
from motion_common.ros_params import LAUNCH_KEYS  # noqa: E402
from motion_common.tools_check import missing_tool_message  # noqa: E402

__all__ = ["check_session", "main"]

_BOOLEAN = ("true", "false")


def _nested(params: dict, prefix: str) -> dict:
    """The parameters under ``prefix`` (a node's private namespace) as nested mappings."""
    tree: dict = {}
    for key, param in params.items():
        if not key.startswith(prefix):
            continue
        parts = key[len(prefix) :].split("/")
        node = tree
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = param.value
    return tree


def _interface_index():
    index = {}
    for node in all_interfaces():
        index[(node.package, node.node)] = node
    return index


class _Session:
    """The session being checked: the command line and roslaunch's resolved config."""

    def __init__(self, launch_file: str, values: dict):
        self.launch_file = launch_file
        self.values = values

    def origin(self, value, config_file: str) -> str:
        """Where ``value`` came from: a command-line argument holding it, else the YAML
        the node loaded, else the launch file."""
        text = str(value).strip().lower()
        for name, given in self.values.items():
            if given.strip().lower() == text and given != "":
                return f"command line {name}:={given}"
        if config_file:
            return f"file {config_file}"
        return f"launch file {self.launch_file}"


def _check_node_params(session: _Session, node, interface, values: dict) -> list[str]:
    """Each private parameter against the declaration, key by key, so every bad one is
    reported with its own origin."""
    errors = []
    schema = interface.params
    config_file = values.get("config_file", "")
    for key, value in sorted(values.items()):
        if key in LAUNCH_KEYS or key in schema.ignore:
            continue
        origin = session.origin(value, config_file)
        if key not in schema.params:
            errors.append(f"{origin}: node {node.name} has no parameter {key!r}; valid keys: {sorted(schema.params)}")
            continue
        try:
            schema.params[key].check(value, f"{origin}: node {node.name}")
        except ParameterError as exc:
            errors.append(str(exc))
    return errors


def _exists(path: str, what: str, origin: str) -> list[str]:
    if path and not os.path.exists(os.path.expanduser(path)):
        return [f"{origin}: {what} {path} does not exist"]
    return []


def _check_files(session: _Session, node, values: dict) -> list[str]:
    """The files a node opens at start-up exist and, where cheap, parse."""
    config_file = values.get("config_file", "")
    errors = []
    if node.type == "hand_replay" and values.get("recording"):
        path = values["recording"]
        origin = session.origin(path, config_file)
        errors += _exists(path, "recording", origin)
        if not errors:
            from motion_sensor.devices.replay import load_samples
            from motion_sensor.errors import MotionSensorError

            try:
                samples, _ = load_samples(os.path.expanduser(path))
                if not samples:
                    errors.append(f"{origin}: recording {path} holds no frames")
            except (MotionSensorError, OSError, ValueError) as exc:
                errors.append(f"{origin}: recording {path} cannot be used: {exc}")
    if node.type == "spacemouse_driver":
        path = values.get("report_log", "")
        errors += _exists(path, "SpaceMouse report log", session.origin(path, config_file))
    if node.type == "webcam_hand_driver":
        path = values.get("video", "")
        errors += _exists(path, "video", session.origin(path, config_file))
    if node.type == "kinect_driver":
        path = values.get("fakenect_dump", "")
        errors += _exists(path, "Kinect dump directory", session.origin(path, config_file))
    if node.type == "episode_recorder":
        # An unwritable dataset folder or a full disk is said before the session starts,
        # not after the operator has teleoperated a whole episode.
        from motion_apps.dataset_store import check_dataset_folder
        from motion_apps.interfaces import EPISODE_RECORDER, PROJECT_ROOT

        path = values.get("dataset") or EPISODE_RECORDER.params.defaults()["dataset"]
        free = values.get("min_free_mb", EPISODE_RECORDER.params.defaults()["min_free_mb"])
        problem = check_dataset_folder(os.path.join(PROJECT_ROOT, os.path.expanduser(path)), float(free))
        if problem:
            errors.append(f"{session.origin(path, config_file)}: {problem}")
    if node.type == "kitting_trials" and values.get("kit_order"):
        path = values["kit_order"]
        origin = session.origin(path, config_file)
        errors += _exists(path, "kit order", origin)
        if not errors:
            from kitting.cell import DEFAULT_CELL, load_cell
            from kitting.kits import KitOrderError, load_kit_order

            try:
                load_kit_order(os.path.expanduser(path), load_cell(values.get("cell") or DEFAULT_CELL))
            except (KitOrderError, ValueError, OSError) as exc:
                errors.append(f"{origin}: {exc}")
    return errors


def _check_robot(session: _Session, node, values: dict) -> list[str]:
    """The server's parameters, its driver's, and the robot: URDF, start pose, workspace."""
    from hw_interface.server_params import check_server_params

    config_file = values.get("config_file", "")
    source = f"node {node.name} ({config_file or session.launch_file})"
    try:
        params = check_server_params({k: v for k, v in values.items() if k not in LAUNCH_KEYS}, source)
    except ParameterError as exc:
        return [str(exc)]
    urdf = params["urdf"]
    origin = session.origin(urdf, "")
    if not os.path.exists(urdf):
        return [f"{origin}: URDF {urdf} does not exist"]
    from motion_common.kinematics import RobotKinematics

    try:
        robot = RobotKinematics(urdf, params["tool_frame"])
    except Exception as exc:  # pinocchio raises ValueError/RuntimeError on a bad URDF
        return [f"{origin}: URDF {urdf} cannot be loaded with tool frame {params['tool_frame']!r}: {exc}"]
    start = params["driver_params"].get("initial_joints")
    if start is None:
        return []
    where = session.origin(start, "") if isinstance(start, str) else "the start pose (robot_config)"
    if len(start) != robot.dof:
        return [
            f"{where}: initial_joints has {len(start)} values but {os.path.basename(urdf)} has {robot.dof} "
            f"joints: give robot_config:=FILE with this robot's start pose"
        ]
    if not robot.within_limits(start):
        return [
            f"{where}: initial_joints {list(start)} lie outside the joint limits of {os.path.basename(urdf)}: "
            "give robot_config:=FILE with this robot's start pose"
        ]
    position = robot.forward(start).translation
    low, high = params["workspace_min"], params["workspace_max"]
    if any(p < lo or p > hi for p, lo, hi in zip(position, low, high)):
        return [
            f"{where}: the start pose puts the tool at {[round(float(p), 3) for p in position]} m, outside "
            f"the workspace box {low}..{high} m of {source}"
        ]
    return []


def _check_tools(config) -> list[str]:
    errors = []
    display = os.environ.get("DISPLAY", "")
    for node in config.nodes:
        if node.package == "rviz":
            missing = missing_tool_message("rviz")
            if missing:
                errors.append(f"rviz:=true: {missing}")
            elif not display:
                errors.append("rviz:=true needs a display and DISPLAY is not set (run under xvfb-run, or omit rviz)")
    for key, param in config.params.items():
        if key.endswith("/driver_params/gui") and param.value is True and not display:
            errors.append("gui:=true needs a display and DISPLAY is not set (run under xvfb-run, or omit gui)")
    return errors


def _device_names(launch_dir: str) -> list[str]:
    """The device names sensing.launch knows (its ``device == 'NAME'`` conditions)."""
    import re

    with open(os.path.join(launch_dir, "sensing.launch"), encoding="utf-8") as stream:
        return sorted(set(re.findall(r"device == '(\w+)'", stream.read())) | {"none"})


def _check_choices(launch_file: str, values: dict, declared: dict) -> list[str]:
    """Arguments whose meaning the nodes cannot check: the device, and a URDF without its
    start pose."""
    errors = []
    device = values.get("device")
    if device is not None and "device" in declared:
        from motion_common.launch_args import suggestion

        if ":" in device:
            from motion_sensor.devices.device_loader import device_class
            from motion_sensor.errors import MotionSensorError

            module_name, _, attribute = device.partition(":")
            try:
                device_class(device)  # what device_node will load
            except MotionSensorError as exc:
                errors.append(f"command line device:={device}: cannot load {attribute!r} from {module_name!r}: {exc}")
        else:
            names = _device_names(os.path.dirname(os.path.abspath(launch_file)))
            if device not in names:
                errors.append(
                    f"command line device:={device}: unknown device{suggestion(device, names)}; "
                    f"one of {names}, or module:Class of your own"
                )
    if device == "spacemouse" and values.get("engage") == "gesture":
        errors.append(
            "command line engage:=gesture: the SpaceMouse shows no second hand; use engage:=button (its left "
            "button is the clutch; the default with device:=spacemouse)"
        )
    if values.get("ur_fake") == "true" and "ur_fake" in declared:
        ignored = [name for name in ("driver", "driver_params", "driver_config") if name in values]
        if ignored:
            errors.append(
                f"command line ur_fake:=true with {', '.join(n + ':=' for n in ignored)}: the UR path drives the UR "
                "driver on its simulated controller with hw_interface/config/ur_driver.yaml; leave them out"
            )
    if "urdf" in values and "robot_config" in declared and "robot_config" not in values:
        robot = values.get("robot", declared["robot"].default if "robot" in declared else "")
        shipped = os.path.join(ROOT, "src", "motion_common", "urdf", f"{robot}.urdf")
        if os.path.realpath(os.path.expanduser(values["urdf"])) != os.path.realpath(shipped):
            errors.append(
                f"command line urdf:={values['urdf']} without robot_config:=FILE: the start pose would be "
                f"the {robot}'s; give robot_config:= a YAML with this robot's initial_joints (rad)"
            )
    return errors


def _load_config(launch_file: str, argv):
    import roslaunch.config
    from roslaunch.core import RLException

    try:
        return roslaunch.config.load_config_default([(launch_file, list(argv))], None, verbose=False), None
    except RLException as exc:
        return None, str(exc).strip()


def check_session(launch_file: str, argv) -> list[str]:
    """Every problem found in ``name:=value`` arguments for ``launch_file``, as messages."""
    try:
        values = parse_assignments(argv)
        declared = declared_args(launch_file)
    except ParameterError as exc:
        return [str(exc)]
    name = os.path.basename(launch_file)
    errors = [f"{message}; {name} declares: see --help" for message in unknown_args(values, declared)]
    for key, value in values.items():
        arg = declared.get(key)
        if arg is not None and arg.default in _BOOLEAN and value.lower() not in _BOOLEAN:
            errors.append(f"command line {key}:={value}: must be true or false")
    errors += _check_choices(launch_file, values, declared)
    if errors:
        return errors
    config, failure = _load_config(launch_file, argv)
    if config is None:
        return [f"{name}: {failure}"]
    session = _Session(name, values)
    index = _interface_index()
    for node in config.nodes:
        interface = index.get((node.package, node.name)) or index.get((node.package, node.type))
        if interface is None:
            continue
        prefix = (node.namespace or "/") + node.name + "/"
        params = _nested(config.params, prefix)
        errors += _check_node_params(session, node, interface, params)
        errors += _check_files(session, node, params)
        if node.type == "motion_controller_server":
            errors += _check_robot(session, node, params)
    errors += _check_tools(config)
    return errors


def main(argv) -> int:
    """``preflight.py LAUNCH_FILE [name:=value ...]``: print the problems; exit 2 if any."""
    if len(argv) < 2:
        print(__doc__)
        return 2
    errors = check_session(argv[1], argv[2:])
    for message in errors:
        print(f"error: {message}", file=sys.stderr)
    return 2 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
