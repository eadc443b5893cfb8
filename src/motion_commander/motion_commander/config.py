"""Teleop parameters: defaults, units and start-up checks (as moveit_servo does).

Every parameter lives in config/teleop.yaml with its unit; ``TELEOP_PARAMETERS`` declares
them for the framework's one validator (motion_common.params), and ``load_teleop_config``
checks them once at start-up, naming the file and key of anything wrong.
"""

from dataclasses import dataclass, field, fields

from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema

from .teleop_core import SAFETY_PARAMS, SafetyConfig

_MAPPING = [
    Param("tool_frame", "tool0", doc="URDF frame that follows the hand"),
    Param(
        "input",
        "stamped",
        choices=("stamped", "pose"),
        doc="stamped: /motion_states_stamped (sensor stamp kept); pose: /motion_states from any source",
    ),
    Param("speed_ratio", 1.0, "m/m", "tool motion per hand motion", low=0.0, high=10.0, low_open=True),
    Param("follow_orientation", True, doc="rotate the tool with the hand"),
    Param(
        "hand_to_robot_rpy",
        [0.0, 0.0, 0.0],
        "rad",
        "device frame orientation in the base frame",
        length=3,
        low=-6.3,
        high=6.3,
    ),
    Param("registration_file", "", doc="register_device YAML; its rotation replaces hand_to_robot_rpy"),
    Param("engage", "auto", choices=("auto", "gesture", "button"), doc="clutch mode"),
    Param("steady_frames", 10, "frames", "steady tracking before engage", low=1, high=1000),
    Param("lost_after", 0.2, "s", "without a frame before disengage", low=0.0, high=10.0, low_open=True),
]
_NODE = [
    Param("urdf", "", doc="robot URDF path (set by the launch file)"),
    Param(
        "server_timeout_s",
        0.5,
        "s",
        "joint_states silence after which the robot server counts as lost (it publishes at 100 Hz): "
        "SERVER_LOST, nothing streams until it is back and the operator engages afresh",
        low=0.05,
        high=10.0,
    ),
    Param(
        "ready_timeout_s",
        60.0,
        "s",
        "how long to wait for the robot server before giving up",
        low=0.0,
        high=3600.0,
        low_open=True,
    ),
    Param(
        "prepare_lead_s",
        0.0015,
        "s",
        "before the next frame is due, the core prepares its pose-independent work (0: right after each command)",
        low=0.0,
        high=0.05,
    ),
]
_MAPPING_PARAMS = ParamSchema(_MAPPING)


@dataclass
class TeleopConfig:
    """Mapping and clutch parameters (defaults, units and ranges: ``_MAPPING``, i.e. the
    node's declaration); ``safety`` holds the safety rules' parameters."""

    tool_frame: str = _MAPPING_PARAMS.field("tool_frame")
    input: str = _MAPPING_PARAMS.field("input")
    speed_ratio: float = _MAPPING_PARAMS.field("speed_ratio")
    follow_orientation: bool = _MAPPING_PARAMS.field("follow_orientation")
    hand_to_robot_rpy: list = _MAPPING_PARAMS.field("hand_to_robot_rpy")
    registration_file: str = _MAPPING_PARAMS.field("registration_file")
    engage: str = _MAPPING_PARAMS.field("engage")
    steady_frames: int = _MAPPING_PARAMS.field("steady_frames")
    lost_after: float = _MAPPING_PARAMS.field("lost_after")
    safety: SafetyConfig = field(default_factory=SafetyConfig)

    def __post_init__(self):
        _MAPPING_PARAMS.check_fields(self, "TeleopConfig")


#: Every parameter of the motion_commander node, with units and ranges.
TELEOP_PARAMETERS = ParamSchema(_MAPPING + list(SAFETY_PARAMS.params.values()) + _NODE, ignore=("config_file",))
_SAFETY_NAMES = set(SAFETY_PARAMS.params)


def load_teleop_config(params: dict, source: str = "teleop.yaml") -> TeleopConfig:
    """Validate a parameter dict (the node's private params) into a TeleopConfig.

    Unknown keys are refused too: a typo must not silently leave a safety default in force.
    Raises ParameterError naming ``source`` and the key.
    """
    values = TELEOP_PARAMETERS.validate(params, source)
    config = TeleopConfig(**{f.name: values[f.name] for f in fields(TeleopConfig) if f.name != "safety"})
    try:
        config.safety = SafetyConfig(**{name: values[name] for name in _SAFETY_NAMES})
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None
    return config
