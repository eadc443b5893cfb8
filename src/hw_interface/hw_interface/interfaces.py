"""The one declaration of the hardware interface's node (see ``motion_common.interface``):
``motion_controller_server``'s parameters, topics and services, with relative names. The
chosen driver's own parameters (``driver_params``) are declared by the driver class
(``PARAMETERS``) and listed with it. No ROS import.
"""

from motion_common.interface import NodeInterface, Service, Topic
from motion_common.params import Param, ParamSchema

from .server_params import SERVER_PARAMETERS

__all__ = ["MOTION_CONTROLLER_SERVER", "SCENE_CAMERA", "all_interfaces"]

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
        Topic(
            "frames/state",
            "motion_commander/FrameSample",
            "the measured joints, their rate and the tool at each recorded frame's instant",
        ),
    ),
    subscribes=(
        Topic(
            "frames/clock",
            "std_msgs/Float64",
            "a dataset recorder's frame period (s): starts the frames/ taps",
            optional=True,
        ),
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


SCENE_CAMERA = NodeInterface(
    "hw_interface",
    "scene_camera",
    "A camera looking at the simulated cell, rendered in its own process from a mirror of the robot's joints "
    "and the server's scene bodies (hw_interface.scene_camera).",
    ParamSchema(
        [
            Param("urdf", "", doc="robot URDF (required)"),
            Param("scene", "", doc="scene YAML of the simulated cell (its 'scene' list; empty: the robot alone)"),
            Param("rate", 15.0, "Hz", "images per second (at most what the renderer manages)", low=0.1, high=60.0),
            Param("width", 320, "px", "image width", low=16, high=1920),
            Param("height", 240, "px", "image height", low=16, high=1080),
            Param("eye", [0.15, -0.75, 0.65], "m", "camera position, base frame"),
            Param("target", [-0.45, -0.05, 0.2], "m", "point the camera looks at, base frame"),
            Param("fov_deg", 55.0, "deg", "vertical field of view", low=1.0, high=170.0),
            Param("frame_id", "scene_camera", doc="header.frame_id of the images"),
        ]
    ),
    publishes=(Topic("camera/image_raw", "sensor_msgs/Image", "the rendered images (rgb8)"),),
    subscribes=(
        Topic("joint_states", "sensor_msgs/JointState", "the measured joints"),
        Topic("tf", "tf2_msgs/TFMessage", "the server's scene bodies (frames scene/<name>)"),
    ),
)


def all_interfaces():
    """Every node of this package."""
    return [MOTION_CONTROLLER_SERVER, SCENE_CAMERA]
