"""Teleop parameters: defaults, units and start-up checks (as moveit_servo does).

Every parameter lives in config/teleop.yaml with its unit; ``TELEOP_PARAMETERS`` declares
them for the framework's one validator (motion_common.params), and ``load_teleop_config``
checks them once at start-up, naming the file and key of anything wrong.
"""
from dataclasses import dataclass, field, fields

from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema

from .teleop_core import SafetyConfig


@dataclass
class TeleopConfig:
    """Mapping and clutch parameters; ``safety`` holds the safety rules' parameters."""

    tool_frame: str = "tool0"
    input: str = "stamped"                   # stamped | pose
    speed_ratio: float = 1.0                 # m of tool motion per m of hand motion
    follow_orientation: bool = True
    hand_to_robot_rpy: list = field(default_factory=lambda: [0.0, 0.0, 0.0])  # rad
    registration_file: str = ""              # register_device YAML; its rotation overrides the rpy
    engage: str = "auto"                     # auto | gesture | button
    steady_frames: int = 10                  # frames of steady tracking before engage
    lost_after: float = 0.2                  # s without a frame before disengage
    safety: SafetyConfig = field(default_factory=SafetyConfig)


_MAPPING = [
    Param("tool_frame", "tool0", doc="URDF frame that follows the hand"),
    Param("input", "stamped", choices=("stamped", "pose"),
          doc="stamped: /motion_states_stamped (sensor stamp kept); pose: /motion_states from any source"),
    Param("speed_ratio", 1.0, "m/m", "tool motion per hand motion", low=0.0, high=10.0, low_open=True),
    Param("follow_orientation", True, doc="rotate the tool with the hand"),
    Param("hand_to_robot_rpy", [0.0, 0.0, 0.0], "rad", "device frame orientation in the base frame",
          length=3, low=-6.3, high=6.3),
    Param("registration_file", "", doc="register_device YAML; its rotation replaces hand_to_robot_rpy"),
    Param("engage", "auto", choices=("auto", "gesture", "button"), doc="clutch mode"),
    Param("steady_frames", 10, "frames", "steady tracking before engage", low=1, high=1000),
    Param("lost_after", 0.2, "s", "without a frame before disengage", low=0.0, high=10.0, low_open=True),
]
_SAFETY = [
    Param("joint_speed_scale", 0.5, "fraction", "of the URDF joint velocity limits", low=0.0, high=1.0,
          low_open=True),
    Param("joint_acceleration", None, "rad/s^2", "change of commanded joint velocity (empty: unlimited)",
          kind=float, low=0.0, high=1000.0, low_open=True, nullable=True),
    Param("joint_limit_margin", 0.05, "rad", "kept clear of every joint limit", low=0.0, high=0.5),
    Param("singularity_slowdown", 40.0, "condition number", "motion toward a singularity slows here",
          low=1.0, high=1e6),
    Param("singularity_halt", 80.0, "condition number", "motion toward a singularity stops here",
          low=1.0, high=1e6),
    Param("workspace_lower", [-1.5, -1.5, 0.0], "m", "tool target box, base frame", length=3, low=-10, high=10),
    Param("workspace_upper", [1.5, 1.5, 1.5], "m", "tool target box, base frame", length=3, low=-10, high=10),
    Param("floor_z", 0.0, "m", "the tool target never goes below this height", low=-10.0, high=10.0),
    Param("engage_ramp_s", 0.3, "s", "speed ramps from 0 after engage or resume", low=0.0, high=10.0),
    Param("stale_timeout_s", 0.1, "s", "without a fresh command before the robot is halted", low=0.0, high=5.0,
          low_open=True),
]
_NODE = [
    Param("urdf", "", doc="robot URDF path (set by the launch file)"),
    Param("ready_timeout_s", 60.0, "s", "how long to wait for the robot server before giving up", low=0.0,
          high=3600.0, low_open=True),
    Param("prepare_lead_s", 0.0015, "s", "before the next frame is due, the core prepares its pose-independent "
          "work (0: right after each command)", low=0.0, high=0.05),
]
#: Every parameter of the motion_commander node, with units and ranges.
TELEOP_PARAMETERS = ParamSchema(_MAPPING + _SAFETY + _NODE, ignore=("config_file",))
_SAFETY_NAMES = {param.name for param in _SAFETY}


def load_teleop_config(params: dict, source: str = "teleop.yaml") -> TeleopConfig:
    """Validate a parameter dict (the node's private params) into a TeleopConfig.

    Unknown keys are refused too: a typo must not silently leave a safety default in force.
    Raises ParameterError naming ``source`` and the key.
    """
    values = TELEOP_PARAMETERS.validate(params, source)
    config = TeleopConfig(**{f.name: values[f.name] for f in fields(TeleopConfig) if f.name != "safety"})
    config.safety = SafetyConfig(**{name: values[name] for name in _SAFETY_NAMES})
    safety = config.safety
    if safety.singularity_slowdown >= safety.singularity_halt:
        raise ParameterError(f"{source}: singularity_slowdown ({safety.singularity_slowdown}) must be "
                             f"below singularity_halt ({safety.singularity_halt})")
    if any(low >= high for low, high in zip(safety.workspace_lower, safety.workspace_upper)):
        raise ParameterError(f"{source}: workspace_lower must be below workspace_upper on every axis")
    return config
