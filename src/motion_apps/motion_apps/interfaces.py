"""The one declaration of every node of the teach application (see
``motion_common.interface``): parameters with default, unit and range, and the topics and
services each node uses, all with relative names. No ROS import.
"""

import os

from motion_common.interface import NodeInterface, Service, Topic
from motion_common.params import Param, ParamSchema

from .teach import DEFAULT_PROGRAMS_DIR

__all__ = ["TEACH_MODE", "TEACH_DEMO", "RUN_PROGRAM", "PROJECT_PROGRAMS_DIR", "all_interfaces"]

# The project's output/programs wherever roslaunch runs the node from (its cwd is ROS_HOME):
# this file is <project>/src/motion_apps/motion_apps/interfaces.py.
PROJECT_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", ".."))
PROJECT_PROGRAMS_DIR = os.path.join(PROJECT_ROOT, DEFAULT_PROGRAMS_DIR)

_POSE = "geometry_msgs/PoseStamped"
_GESTURE = Topic("motion_sensor/gesture", "motion_sensor/Gesture", "recognised gestures")
_JOINTS = Topic("joint_states", "sensor_msgs/JointState", "the measured joints")
_ROBOT_POSE = Topic("robot_pose", _POSE, "the tool pose (the core's forward kinematics)")
_SERVER = Service("motion_controller", "motion_commander/commander", "the hardware interface")

TEACH_MODE = NodeInterface(
    "motion_apps",
    "teach_mode",
    "Turns gestures into a taught program (waypoints, grip, release, undo, save) and saves it as YAML.",
    ParamSchema(
        [
            Param(
                "gesture_config", "", doc="gesture -> command YAML (default: motion_apps/config/gesture_commands.yaml)"
            ),
            Param(
                "programs_dir",
                PROJECT_PROGRAMS_DIR,
                doc="folder the programs are saved in (default: the project's "
                "output/programs; a relative path is taken from the project root)",
            ),
            Param("program_name", "", doc="file name without .yaml (empty: teach_<date>_<time>)"),
            Param("robot", "", doc="robot name written into the program (empty: the server's GET_ROBOTS name)"),
            Param("tool_frame", "tool0", doc="tool frame of the taught poses"),
            Param("actuate_gripper", True, doc="carry out grip/release while teaching"),
        ]
    ),
    publishes=(
        Topic("teach/feedback", "std_msgs/String", "what each gesture did, for the operator"),
        Topic("teach/saved", "std_msgs/String", "path of the saved program", latched=True),
        Topic(
            "teach/ready", "std_msgs/Bool", "True once teaching can start (the teach stream waits for it)", latched=True
        ),
    ),
    subscribes=(_ROBOT_POSE, _JOINTS, Topic("motion_commander/ready", "std_msgs/Bool", "the core is ready"), _GESTURE),
    serves=(Service("teach/save", "std_srvs/Trigger", "save the program now"),),
    calls=(_SERVER,),
)

TEACH_DEMO = NodeInterface(
    "motion_apps",
    "teach_demo",
    "The teach demo's referee: collects the teaching session, replays the saved program on a reset scene and "
    "reports the placement error (teach_summary.json, teach_path.png).",
    ParamSchema(
        [
            Param("output_dir", "output", doc="folder for teach_summary.json and teach_path.png"),
            Param("scene", "", doc="scene YAML the program is checked against (its static bodies)"),
            Param("urdf", "", doc="robot URDF (for the program check)"),
            Param("part", "part", doc="scene body that is picked and placed"),
            Param(
                "end_session",
                False,
                doc="when done, stop the roslaunch that started this node as Ctrl-C does "
                "(a hand-started session ends without the REQUIRED banner)",
            ),
            Param("tolerance_mm", 10.0, "mm", "largest placement error that counts as success", low=0.0, low_open=True),
            Param(
                "save_timeout_s",
                30.0,
                "s",
                "how long after the stream ends a save may still come",
                low=0.0,
                low_open=True,
            ),
        ]
    ),
    publishes=(Topic("~result", "std_msgs/String", "the summary as JSON", latched=True),),
    subscribes=(
        _ROBOT_POSE,
        _GESTURE,
        Topic("teach/feedback", "std_msgs/String", "teach_mode's feedback"),
        Topic("teach/saved", "std_msgs/String", "the saved program"),
        _JOINTS,
        Topic("hand_replay/finished", "std_msgs/Bool", "True when the teaching stream has ended"),
    ),
    calls=(Service("motion_controller/reset_scene", "std_srvs/Trigger", "back to the scene's start"), _SERVER),
)

RUN_PROGRAM = NodeInterface(
    "motion_apps",
    "run_program",
    "Command-line replay of a taught program (anonymous node; arguments on the command line, see --help).",
    calls=(_SERVER,),
)


def all_interfaces():
    """Every node of this package."""
    return [TEACH_MODE, TEACH_DEMO, RUN_PROGRAM]
