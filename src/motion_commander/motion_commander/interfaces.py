"""The one declaration of every node of the core (see ``motion_common.interface``):
parameters with default, unit and range, and the topics and services each node uses, all
with relative names. No ROS import.
"""

from motion_common.interface import NodeInterface, Service, Topic
from motion_common.params import Param, ParamSchema

from .config import TELEOP_PARAMETERS

__all__ = ["MOTION_COMMANDER", "SESSION_MONITOR", "all_interfaces"]

_POSE = "geometry_msgs/PoseStamped"
_COMMANDER = "motion_commander/commander"

MOTION_COMMANDER = NodeInterface(
    "motion_commander",
    "motion_commander",
    "The core: maps the filtered hand onto the tool (clutch, speed ratio), solves IK, applies the safety rules "
    "and streams joint targets to the server (`motion_controller`); also serves the paper's manipulation API.",
    TELEOP_PARAMETERS,
    publishes=(
        Topic("motion_commander/status", "std_msgs/UInt8", "TeleopStatus code", latched=True),
        Topic("motion_commander/target", _POSE, "the mapped tool target"),
        Topic(
            "motion_commander/latency",
            "motion_commander/StageLatency",
            "sensor -> sequencer -> core -> driver, per command",
        ),
        Topic("robot_pose", _POSE, "tool pose by forward kinematics of joint_states (while subscribed)"),
        Topic("motion_commander/command", "sensor_msgs/JointState", "the joint targets sent, sensor stamp"),
        Topic(
            "motion_commander/ready",
            "std_msgs/Bool",
            "True once the core has the robot state and its pose input is connected",
            latched=True,
        ),
        Topic("motion_commander/speed_ratio", "std_msgs/Float64", "the speed ratio in force", latched=True),
        Topic(
            "frames/command",
            "motion_commander/FrameSample",
            "the joint targets and the tool target at each recorded frame's instant",
        ),
    ),
    subscribes=(
        Topic(
            "frames/clock",
            "std_msgs/Float64",
            "a dataset recorder's frame period (s): starts the frames/ taps",
            optional=True,
        ),
        Topic("joint_states", "sensor_msgs/JointState", "the measured joints"),
        Topic("motion_states_stamped", _POSE, "the hand pose with its sensor stamp (input: stamped)", optional=True),
        Topic(
            "motion_states", "geometry_msgs/Pose", "any pose source, stamped on arrival (input: pose)", optional=True
        ),
        Topic("motion_sensor/hand", "motion_sensor/hand", "hands in view (engage: gesture)", optional=True),
        Topic("motion_commander/engage", "std_msgs/Bool", "clutch button (engage: button)"),
        Topic("motion_commander/estop", "std_msgs/Bool", "True latches the server's stop and disengages"),
        Topic("motion_commander/set_speed_ratio", "std_msgs/Float64", "live speed ratio (re-anchored)"),
        Topic("motion_controller/stop_latched", "std_msgs/Bool", "the server's latched stop"),
    ),
    serves=(
        Service("motion_commander/set_pose", _COMMANDER, "motion_setPose: MoveL to a pose"),
        Service("motion_commander/get_pose", _COMMANDER, "motion_getPose: the tool pose"),
        Service("motion_commander/get_joints", _COMMANDER, "motion_getJoints: the joints"),
    ),
    calls=(Service("motion_controller", _COMMANDER, "the hardware interface's one service"),),
)

SESSION_MONITOR = NodeInterface(
    "motion_commander",
    "session_monitor",
    "Observes a session and, when the recording has played, prints the summary and writes "
    "session_summary.json and session_paths.png.",
    ParamSchema(
        [
            Param("output_dir", "output", doc="folder for session_summary.json and session_paths.png"),
            Param("title", "teleop session", doc="plot title"),
            Param(
                "window_samples",
                20_000,
                "samples",
                "of each path kept for the tracking figures and the plot (about 3 min at 110 Hz); counts and latency "
                "figures cover the whole session",
                low=100,
                high=10_000_000,
            ),
            Param("settle", 1.5, "s", "wait after the end for the arm to settle before reporting", low=0.0, high=60.0),
            Param(
                "end_session",
                False,
                doc="when done, stop the roslaunch that started this node as Ctrl-C does "
                "(a hand-started session ends without the REQUIRED banner)",
            ),
            Param(
                "max_refused_fraction",
                0.1,
                "",
                "the session failed (exit code 3) when more of its commands than this were refused",
                low=0.0,
                high=1.0,
            ),
        ]
    ),
    subscribes=(
        Topic("motion_sensor/raw_hand", "motion_sensor/hand", "device frames (counted, the raw path)"),
        Topic("motion_sensor/hand", "motion_sensor/hand", "the filtered hand"),
        Topic("motion_commander/target", _POSE, "the tool targets"),
        Topic("motion_controller/tool_pose", _POSE, "the measured tool"),
        Topic("motion_controller/trace", "motion_commander/CommandTrace", "sensor-to-driver latency"),
        Topic("diagnostics", "diagnostic_msgs/DiagnosticArray", "the sequencer's counters"),
        Topic("motion_commander/latency", "motion_commander/StageLatency", "per-stage latency"),
        Topic(
            "hand_replay/finished",
            "std_msgs/Bool",
            "True when the recording has played (remap for another finite device)",
        ),
    ),
)


def all_interfaces():
    """Every node of this package."""
    return [MOTION_COMMANDER, SESSION_MONITOR]
