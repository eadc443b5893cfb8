"""The one declaration of every node of the teach application (see
``motion_common.interface``): parameters with default, unit and range, and the topics and
services each node uses, all with relative names. No ROS import.
"""

import os

from motion_common.interface import NodeInterface, Service, Topic
from motion_common.params import Param, ParamSchema

from .teach import DEFAULT_PROGRAMS_DIR

__all__ = [
    "TEACH_MODE",
    "TEACH_DEMO",
    "RUN_PROGRAM",
    "EPISODE_RECORDER",
    "REPLAY_EPISODE",
    "PROJECT_PROGRAMS_DIR",
    "PROJECT_DATASETS_DIR",
    "all_interfaces",
]

# The project's output/programs wherever roslaunch runs the node from (its cwd is ROS_HOME):
# this file is <project>/src/motion_apps/motion_apps/interfaces.py.
PROJECT_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", ".."))
PROJECT_PROGRAMS_DIR = os.path.join(PROJECT_ROOT, DEFAULT_PROGRAMS_DIR)
PROJECT_DATASETS_DIR = os.path.join(PROJECT_ROOT, "output", "datasets")

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


EPISODE_RECORDER = NodeInterface(
    "motion_apps",
    "episode_recorder",
    "Records demonstrations as episodes of a LeRobot dataset (observations at a fixed rate, camera as video, "
    "the core's commands as actions, task text, success), written by LeRobot's own writer in a process of its "
    "own; started and stopped by service, topic, the dashboard or a gesture.",
    ParamSchema(
        [
            Param(
                "dataset",
                os.path.join(PROJECT_DATASETS_DIR, "teleop"),
                doc="dataset folder (a LeRobot root; a relative path is taken from the project root)",
            ),
            Param("repo_id", "local/teleop", doc="LeRobot repo_id written into the dataset (never pushed)"),
            Param("task", "teleoperation", doc="task text of the episodes (episodes/task changes it)"),
            Param("fps", 15.0, "Hz", "frame rate of the episodes", low=1.0, high=60.0),
            Param("camera", "", doc="camera name (observation.images.<camera>) of camera/image_raw; empty: no camera"),
            Param("image_width", 320, "px", "camera frames are resized to this width (0: as received)", low=0),
            Param("image_height", 240, "px", "camera frames are resized to this height (0: as received)", low=0),
            Param(
                "max_episode_s",
                600.0,
                "s",
                "an episode this long is saved and recording stops (bounds memory)",
                low=1.0,
            ),
            Param("min_free_mb", 500.0, "MB", "free disk the dataset folder needs at start-up", low=0.0),
            Param("toggle_gesture", "", doc="gesture that starts and stops an episode (empty: none)"),
            Param("robot_type", "", doc="robot_type written into the dataset (empty: the joint_states' arm)"),
            Param(
                "vcodec",
                "h264",
                doc="video codec of the camera stream (LeRobot's: h264, hevc, libsvtav1)",
                choices=("h264", "hevc", "libsvtav1"),
            ),
            Param("start_recording", False, doc="start an episode as soon as the robot state is there"),
        ]
    ),
    publishes=(
        Topic(
            "episodes/status", "std_msgs/String", "recording state as JSON (episode, frames, last result)", latched=True
        ),
        Topic(
            "frames/clock",
            "std_msgs/Float64",
            "the frame period (s): the producers' frames/ taps send their streams at its multiples",
            latched=True,
        ),
        Topic(
            "episodes/list",
            "std_msgs/String",
            "the saved episodes as JSON (index, task, frames, success)",
            latched=True,
        ),
    ),
    subscribes=(
        Topic(
            "frames/state",
            "motion_commander/FrameSample",
            "the measured joints, their rate and the tool at each frame's instant (the server's tap)",
        ),
        Topic("motion_controller/gripper", "std_msgs/Bool", "the gripper state"),
        Topic("frames/hand", "motion_sensor/hand", "the operator's hand around each frame's instant"),
        Topic(
            "frames/hand_skeleton",
            "motion_sensor/HandSkeleton",
            "the operator's hand skeleton around each frame's instant (devices that see fingers)",
            optional=True,
        ),
        Topic(
            "frames/command",
            "motion_commander/FrameSample",
            "the joint targets sent (the action) and the core's tool target at each frame's instant",
        ),
        Topic("camera/image_raw", "sensor_msgs/Image", "the camera (with ~camera)", optional=True),
        Topic("episodes/task", "std_msgs/String", "task text of the next episodes"),
        Topic("episodes/command", "std_msgs/String", "start, stop, discard, success, failure (for scripts)"),
        Topic(
            "motion_sensor/gesture",
            "motion_sensor/Gesture",
            "the start/stop gesture (with ~toggle_gesture)",
            optional=True,
        ),
    ),
    serves=(
        Service("episodes/start", "std_srvs/Trigger", "start an episode"),
        Service("episodes/stop", "std_srvs/Trigger", "save the episode"),
        Service("episodes/discard", "std_srvs/Trigger", "drop the episode"),
        Service("episodes/mark_success", "std_srvs/SetBool", "success of the episode (the last saved one when none)"),
    ),
)

REPLAY_EPISODE = NodeInterface(
    "motion_apps",
    "replay_episode",
    "Command-line replay of a recorded episode through the server's safety checks (by default its recorded joint "
    "path, ahead by the recorded arm's lag; or its actions), reporting the tracking error against the recorded "
    "states (anonymous node; arguments on the command line, see --help).",
    subscribes=(
        Topic(
            "motion_controller/tool_pose",
            _POSE,
            "the measured tool, stamped: the tool at the moment each frame's targets are sent",
        ),
        Topic(
            "joint_states",
            "sensor_msgs/JointState",
            "the measured joints, stamped: how long the arm trails the stream (--lag live)",
        ),
    ),
    calls=(_SERVER,),
)


def all_interfaces():
    """Every node of this package."""
    return [TEACH_MODE, TEACH_DEMO, RUN_PROGRAM, EPISODE_RECORDER, REPLAY_EPISODE]
