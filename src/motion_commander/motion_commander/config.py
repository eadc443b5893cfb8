"""Teleop parameters: defaults, units and start-up checks (as moveit_servo does).

Every parameter lives in config/teleop.yaml with its unit; ``load_teleop_config`` checks
them once at start-up and names the file and key of anything wrong.
"""
from dataclasses import dataclass, field, fields

import numpy as np

from .errors import MotionCommanderError
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


_POSITIVE = {"speed_ratio", "lost_after", "stale_timeout_s", "joint_speed_scale", "singularity_slowdown",
             "singularity_halt"}
_NON_NEGATIVE = {"joint_limit_margin", "engage_ramp_s"}


def _convert(name, default, value, source):
    where = f"{source}: parameter '{name}'"
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise MotionCommanderError(f"{where} must be true or false, got {value!r}")
        return value
    if isinstance(default, int) and not isinstance(default, bool):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise MotionCommanderError(f"{where} must be an integer >= 1, got {value!r}")
        return value
    if isinstance(default, float) or (default is None and name == "joint_acceleration"):
        if value is None and default is None:
            return None
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not np.isfinite(value):
            raise MotionCommanderError(f"{where} must be a finite number, got {value!r}")
        if name in _POSITIVE and value <= 0 or name in _NON_NEGATIVE and value < 0:
            raise MotionCommanderError(f"{where} must be {'> 0' if name in _POSITIVE else '>= 0'}, got {value!r}")
        if name == "joint_speed_scale" and value > 1:
            raise MotionCommanderError(f"{where} is a fraction of the rated joint speed: (0, 1], got {value!r}")
        return float(value)
    if isinstance(default, list):
        if not isinstance(value, list) or len(value) != len(default) or \
                not all(isinstance(v, (int, float)) and np.isfinite(v) for v in value):
            raise MotionCommanderError(f"{where} must be a list of {len(default)} finite numbers, got {value!r}")
        return [float(v) for v in value]
    if isinstance(default, str):
        if not isinstance(value, str):
            raise MotionCommanderError(f"{where} must be a string, got {value!r}")
        return value
    return value


def load_teleop_config(params: dict, source: str = "teleop.yaml") -> TeleopConfig:
    """Validate a parameter dict (the node's private params) into a TeleopConfig.

    Unknown keys are refused too: a typo must not silently leave a safety default in force.
    """
    config = TeleopConfig()
    safety = SafetyConfig()
    top = {f.name for f in fields(TeleopConfig)} - {"safety"}
    safety_names = {f.name for f in fields(SafetyConfig)}
    ignored = {"urdf", "config_file"}
    for name, value in params.items():
        if name in top:
            setattr(config, name, _convert(name, getattr(TeleopConfig(), name), value, source))
        elif name in safety_names:
            setattr(safety, name, _convert(name, getattr(SafetyConfig(), name), value, source))
        elif name not in ignored:
            known = sorted(top | safety_names)
            raise MotionCommanderError(f"{source}: unknown parameter '{name}'; known parameters: {known}")
    if config.input not in ("stamped", "pose"):
        raise MotionCommanderError(f"{source}: parameter 'input' must be stamped or pose, got {config.input!r}")
    if config.engage not in ("auto", "gesture", "button"):
        raise MotionCommanderError(f"{source}: parameter 'engage' must be auto, gesture or button, "
                                   f"got {config.engage!r}")
    if safety.singularity_slowdown >= safety.singularity_halt:
        raise MotionCommanderError(f"{source}: singularity_slowdown ({safety.singularity_slowdown}) must be "
                                   f"below singularity_halt ({safety.singularity_halt})")
    if np.any(np.asarray(safety.workspace_lower) >= np.asarray(safety.workspace_upper)):
        raise MotionCommanderError(f"{source}: workspace_lower must be below workspace_upper on every axis")
    config.safety = safety
    return config
