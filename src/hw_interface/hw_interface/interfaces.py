"""The one declaration of the hardware interface's node (see ``motion_common.interface``):
``motion_controller_server``'s parameters, topics and services, with relative names. The
chosen driver's own parameters (``driver_params``) are declared by the driver class
(``PARAMETERS``) and listed with it. No ROS import.
"""

from motion_common.interface import NodeInterface, Service, Topic

from .server_params import SERVER_PARAMETERS

__all__ = ["MOTION_CONTROLLER_SERVER", "all_interfaces"]

_BOOL = "std_msgs/Bool"

MOTION_CONTROLLER_SERVER = NodeInterface(
    "hw_interface",
    "motion_controller_server",
    "Serves the paper's commander.srv on `motion_controller` through the chosen driver (registry name "
    "`driver`: pybullet, ur_rtde, ur_rtde_fake or a plugin), publishes the robot state, and holds the latched "
    "stop that halts every client.",
    SERVER_PARAMETERS,
    publishes=(
        Topic("joint_states", "sensor_msgs/JointState", "measured joints at publish_rate"),
        Topic("motion_controller/tool_pose", "geometry_msgs/PoseStamped", "measured tool pose at publish_rate"),
        Topic("motion_controller/trace", "motion_commander/CommandTrace", "sensor-to-driver latency of every command"),
        Topic(
            "motion_controller/status",
            "diagnostic_msgs/DiagnosticStatus",
            "driver connection, fault, protective stop, gripper, latched stop",
            latched=True,
        ),
        Topic("motion_controller/stop_latched", _BOOL, "the latched stop", latched=True),
        Topic("motion_controller/gripper", _BOOL, "gripper state after each accepted SET_GRIPPER", latched=True),
    ),
    subscribes=(
        Topic("motion_commander/estop", _BOOL, "True latches the stop, False releases it"),
        Topic(
            "stop_all",
            _BOOL,
            "the same, shared by every arm of a multi-arm session (the launch file "
            "remaps it to one topic): one STOP halts them all",
        ),
    ),
    serves=(
        Service("motion_controller", "motion_commander/commander", "the paper's commander.srv (Table 2)"),
        Service("motion_controller/latch_stop", "std_srvs/SetBool", "latch (True) or release (False) the stop"),
        Service(
            "motion_controller/reset_scene",
            "std_srvs/Trigger",
            "simulation only: back to the scene's start",
            optional=True,
        ),
    ),
)


def all_interfaces():
    """Every node of this package."""
    return [MOTION_CONTROLLER_SERVER]
