"""The program file of a gesture-taught task: a YAML list of waypoints, loaded with full
validation and saved atomically.

Format (``format_version: 1``)::

    format_version: 1
    robot: ur5e                 # the robot it was taught on (GET_ROBOTS name)
    tool_frame: tool0           # the URDF frame the poses are of
    waypoints:
      - name: pick_above
        pose:
          position: [-0.45, -0.2, 0.2]          # m, robot base frame
          orientation: [1.0, 0.0, 0.0, 0.0]     # quaternion x, y, z, w
        joints: [0.1, -1.4, 1.6, -1.8, -1.57, 0.1]   # rad, the arm when it was taught
        action: none            # none | grip | release, done once the pose is reached
        speed: 0.5              # fraction (0, 1] of the robot's configured speed

Every error names the file, and the waypoint (index and name) when it is in one. Saving
writes a temporary file in the same folder, flushes and fsyncs it, renames it over the
target with ``os.replace`` (atomic on POSIX) and fsyncs the folder: a crash at any moment
leaves either the old or the new program, never a truncated or mixed one.
"""

import os
from dataclasses import dataclass, field

import yaml

from motion_common.atomic_file import write_atomic
from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema
from motion_common.rotations import is_unit_quaternion, quaternion_norm

FORMAT_VERSION = 1
ACTIONS = ("none", "grip", "release")


class ProgramError(Exception):
    """A program file that cannot be read, is invalid, or cannot be written."""


POSE_SCHEMA = ParamSchema(
    [
        Param("position", [0.0, 0.0, 0.0], "m", "tool position in the robot base frame", length=3),
        Param("orientation", [0.0, 0.0, 0.0, 1.0], "1", "tool orientation, quaternion x, y, z, w", length=4),
    ]
)

WAYPOINT_SCHEMA = ParamSchema(
    [
        Param("name", "", doc="waypoint name, unique in the program"),
        Param("pose", {}, doc="position (m) and orientation (quaternion x, y, z, w)", schema=POSE_SCHEMA),
        Param("joints", [], "rad", "the arm's joints when the waypoint was taught (IK seed)"),
        Param("action", "none", doc="gripper action once the pose is reached", choices=ACTIONS),
        Param("speed", 1.0, "1", "fraction of the robot's configured speed", low=0.0, high=1.0, low_open=True),
    ]
)

PROGRAM_SCHEMA = ParamSchema(
    [
        Param("format_version", FORMAT_VERSION, doc="program file format", low=1),
        Param("robot", "", doc="name of the robot the program was taught on"),
        Param("tool_frame", "tool0", doc="URDF frame the poses are of"),
        Param("waypoints", [], doc="the waypoints, in order", item_kind=dict),
    ]
)

_REQUIRED_TOP = ("format_version", "robot", "waypoints")
# libyaml's parser and emitter when present (several times faster), else pure Python.
_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_Dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
_REQUIRED_WAYPOINT = ("name", "pose", "joints")


@dataclass
class Waypoint:
    """One taught pose: where the tool goes, the joints it had, and what to do there."""

    name: str
    position: list[float]
    orientation: list[float]
    joints: list[float]
    action: str = "none"
    speed: float = 1.0

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "pose": {
                "position": [float(v) for v in self.position],
                "orientation": [float(v) for v in self.orientation],
            },
            "joints": [float(v) for v in self.joints],
            "action": self.action,
            "speed": float(self.speed),
        }


@dataclass
class Program:
    """A taught program: the robot it belongs to, its tool frame and its waypoints."""

    robot: str
    tool_frame: str = "tool0"
    waypoints: list[Waypoint] = field(default_factory=list)
    format_version: int = FORMAT_VERSION

    def to_dict(self) -> dict:
        return {
            "format_version": int(self.format_version),
            "robot": self.robot,
            "tool_frame": self.tool_frame,
            "waypoints": [w.to_dict() for w in self.waypoints],
        }

    def to_yaml(self) -> str:
        return (
            "# Gesture-taught program (motion_commander.program, format_version 1): positions in m "
            "(robot base frame),\n# orientations quaternion x, y, z, w, joints in rad, speed a "
            "fraction (0, 1], action none|grip|release.\n"
            + yaml.dump(self.to_dict(), Dumper=_Dumper, sort_keys=False, default_flow_style=None, width=200)
        )


def parse_program(data, source: str) -> Program:
    """A Program from parsed YAML ``data``; ``source`` (the file) is named in every error."""
    if not isinstance(data, dict):
        raise ProgramError(
            f"{source}: a program file holds a mapping with {list(_REQUIRED_TOP)}, got {type(data).__name__}"
        )
    missing = [key for key in _REQUIRED_TOP if key not in data]
    if missing:
        raise ProgramError(f"{source}: missing {missing} (a program needs {list(_REQUIRED_TOP)})")
    try:
        top = PROGRAM_SCHEMA.validate(data, source)
    except ParameterError as exc:
        raise ProgramError(str(exc)) from None
    if top["format_version"] != FORMAT_VERSION:
        raise ProgramError(
            f"{source}: format_version {top['format_version']} is not supported (this version reads {FORMAT_VERSION})"
        )
    if not top["robot"].strip():
        raise ProgramError(f"{source}: 'robot' must name the robot the program was taught on")
    if not top["waypoints"]:
        raise ProgramError(f"{source}: the program has no waypoints")
    waypoints, names = [], {}
    for index, entry in enumerate(data["waypoints"]):
        where = f"{source}: waypoint {index}" + (
            f" ({entry.get('name')!r})" if isinstance(entry, dict) and entry.get("name") else ""
        )
        waypoint = _parse_waypoint(entry, where)
        if waypoint.name in names:
            raise ProgramError(f"{where}: name {waypoint.name!r} already used by waypoint {names[waypoint.name]}")
        names[waypoint.name] = index
        if waypoints and len(waypoint.joints) != len(waypoints[0].joints):
            raise ProgramError(f"{where}: {len(waypoint.joints)} joints, waypoint 0 has {len(waypoints[0].joints)}")
        waypoints.append(waypoint)
    return Program(
        robot=top["robot"], tool_frame=top["tool_frame"], waypoints=waypoints, format_version=top["format_version"]
    )


def _parse_waypoint(entry, where: str) -> Waypoint:
    if not isinstance(entry, dict):
        raise ProgramError(f"{where}: a waypoint is a mapping with {list(_REQUIRED_WAYPOINT)}, got {entry!r}")
    missing = [key for key in _REQUIRED_WAYPOINT if key not in entry]
    if isinstance(entry.get("pose"), dict):
        missing += [f"pose.{key}" for key in ("position", "orientation") if key not in entry["pose"]]
    if missing:
        raise ProgramError(f"{where}: missing {missing}")
    try:
        values = WAYPOINT_SCHEMA.validate(entry, where)
    except ParameterError as exc:
        raise ProgramError(str(exc)) from None
    if not values["name"].strip():
        raise ProgramError(f"{where}: 'name' must not be empty")
    if not values["joints"]:
        raise ProgramError(f"{where}: 'joints' (rad) must hold the arm's joints")
    quat = values["pose"]["orientation"]
    norm = quaternion_norm(quat)
    if not is_unit_quaternion(quat):
        raise ProgramError(
            f"{where}: pose.orientation {quat} is not a unit quaternion (norm {norm:.4f}); give x, y, z, w"
        )
    return Waypoint(
        name=values["name"],
        position=values["pose"]["position"],
        orientation=[v / norm for v in quat],
        joints=values["joints"],
        action=values["action"],
        speed=values["speed"],
    )


def load_program(path: str) -> Program:
    """Read and validate a program file; raise ProgramError naming the file (and waypoint)."""
    try:
        with open(path, encoding="utf-8") as stream:
            data = yaml.load(stream, Loader=_Loader)
    except OSError as exc:
        raise ProgramError(f"{path}: cannot read the program: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise ProgramError(f"{path}: not valid YAML: {exc}") from None
    return parse_program(data, path)


def program_path(folder: str, name: str) -> str:
    """The file of program ``name`` in ``folder``: ValueError for anything but a plain name
    (no folder part, no leading dot, no NUL), so a name from a page or a parameter can
    never reach outside ``folder``."""
    if not name or name != os.path.basename(name) or name.startswith(".") or "\0" in name or name in ("..",):
        raise ValueError(f"not a program name: {name!r} (a plain file name without a folder, e.g. pick_a)")
    return os.path.join(folder, name + ".yaml")


def save_program(program: Program, path: str) -> str:
    """Write ``program`` to ``path`` atomically; return the absolute path.

    The text is written to a temporary file in the same folder (same file system), flushed
    and fsynced, then renamed over ``path`` with os.replace, and the folder is fsynced so
    the rename itself survives a power cut. The program is validated first: an invalid
    program is never written.
    """
    text = program.to_yaml()
    path = os.path.abspath(path)
    parse_program(yaml.load(text, Loader=_Loader), path)  # never write what load_program would refuse
    return write_atomic(path, text)
