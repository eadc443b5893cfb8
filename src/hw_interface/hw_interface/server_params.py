"""motion_controller_server's parameters as a ParamSchema (units and ranges), and the check
of its ``driver_params`` against the chosen driver's own schema (``PARAMETERS``).

Pure Python: the node reads its private parameters with motion_common.ros_params and calls
``check_server_params``; an unknown or bad key (server or driver) stops the node with a
message naming the file and the valid keys.
"""

from motion_common.errors import ParameterError
from motion_common.params import Param, ParamSchema

from .registry import driver_parameters

SERVER_PARAMETERS = ParamSchema(
    [
        Param(
            "driver",
            "pybullet",
            doc="registry name of the driver: pybullet, ur_rtde, ur_rtde_fake, simple_message, simple_message_fake "
            "or a plugin",
        ),
        Param("driver_params", {}, doc="the driver's parameters, checked against its PARAMETERS schema"),
        Param("urdf", "", doc="robot URDF path (required)"),
        Param("tool_frame", "tool0", doc="tool link of the URDF"),
        Param("robot_name", None, kind=str, nullable=True, doc="name reported by GET_ROBOTS (default: the URDF's)"),
        Param("login_url", "", doc="controller to log in to at start-up; empty: wait for LOGIN"),
        Param("user", "", doc="controller user for LOGIN"),
        Param("password", "", doc="controller password for LOGIN"),
        Param("publish_rate", 100.0, "Hz", "joint_states and motion_controller/tool_pose rate", low=1.0, high=1000.0),
        Param(
            "max_stream_step",
            0.2,
            "rad",
            "largest joint change one SET_JOINTS may ask for",
            low=0.0,
            high=3.2,
            low_open=True,
        ),
        Param(
            "max_stream_lag",
            0.6,
            "rad",
            "largest distance a SET_JOINTS target may run ahead of the measured joints (a servo follows with a delay)",
            low=0.0,
            high=6.3,
            low_open=True,
        ),
        Param(
            "stream_start_tolerance",
            0.05,
            "rad",
            "the first SET_JOINTS of a stream (after a start, STOP, move or pause) must lie this close to the measured "
            "joints: a stale stream from before a restart is refused; so must a FOLLOW_PATH's first sample",
            low=0.0,
            high=3.2,
            low_open=True,
        ),
        Param(
            "move_timeout",
            60.0,
            "s",
            "longest a MOVE_J/MOVE_L may run before the robot is stopped and TIMEOUT answered (a FOLLOW_PATH: "
            "beyond its duration; a path that ends away from its goal is answered by the driver first)",
            low=0.0,
            high=3600.0,
            low_open=True,
        ),
        Param("workspace_min", [-2.0, -2.0, 0.0], "m", "tool position box, lower corner (base frame)", length=3),
        Param("workspace_max", [2.0, 2.0, 2.0], "m", "tool position box, upper corner (base frame)", length=3),
    ],
    ignore=("config_file",),
)


def check_server_params(values: dict, source: str) -> dict:
    """The server's checked parameters, with ``driver_params`` checked by the driver's
    schema (when it declares one); raise ParameterError naming ``source`` and the key."""
    params = SERVER_PARAMETERS.validate(values, source)
    if not params["urdf"]:
        raise ParameterError(f"{source}: parameter 'urdf' (robot URDF path) is required")
    if any(lo >= hi for lo, hi in zip(params["workspace_min"], params["workspace_max"])):
        raise ParameterError(
            f"{source}: workspace_min {params['workspace_min']} must be below workspace_max "
            f"{params['workspace_max']} on every axis"
        )
    try:
        schema = driver_parameters(params["driver"])
    except Exception as exc:  # unknown driver: say which exist
        raise ParameterError(f"{source}: parameter 'driver': {exc}") from None
    if schema is not None:
        params["driver_params"] = schema.validate(
            params["driver_params"], f"{source}: driver_params of driver '{params['driver']}'"
        )
    return params
