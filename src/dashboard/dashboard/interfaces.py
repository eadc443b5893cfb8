"""The one declaration of the dashboard node (see ``motion_common.interface``): its
parameters (config.DASHBOARD_PARAMETERS) and the topics and services it uses, all with
relative names. No ROS import.
"""

from motion_common.interface import NodeInterface, Service, Topic

from .config import DASHBOARD_PARAMETERS

__all__ = ["DASHBOARD", "all_interfaces"]


def _in(name, type_name, doc):
    return Topic(name, type_name, doc)


DASHBOARD = NodeInterface(
    "dashboard",
    "dashboard",
    "The operator's web console (NiceGUI): a 3-D view of the arm, the hand and tool paths, time series, an "
    "event log, the kitting camera and the session's controls (engage, e-stop and release, speed ratio, "
    "filter, programs, kitting campaigns, recorded episodes).",
    DASHBOARD_PARAMETERS,
    publishes=(
        Topic("motion_commander/engage", "std_msgs/Bool", "the clutch button"),
        Topic("motion_commander/estop", "std_msgs/Bool", "e-stop (fallback when the latch service is down)"),
        Topic("motion_commander/set_speed_ratio", "std_msgs/Float64", "a new speed ratio"),
        Topic("motion_sensor/set_filter", "std_msgs/String", "a new filter"),
        Topic("kitting_trials/stop", "std_msgs/Bool", "stop a running campaign"),
        Topic("kitting/tray_swapped", "std_msgs/Empty", "the finished kit's tray was taken away (Tray swapped)"),
        Topic("episodes/command", "std_msgs/String", "start, stop, discard, success, failure (episode panel)"),
    ),
    subscribes=(
        _in("motion_commander/status", "std_msgs/UInt8", "teleop status"),
        _in("motion_controller/stop_latched", "std_msgs/Bool", "the latched stop"),
        _in("motion_commander/speed_ratio", "std_msgs/Float64", "the speed ratio in force"),
        _in("motion_sensor/filter", "std_msgs/String", "the active filter"),
        _in("motion_sensor/active_device", "std_msgs/String", "the device that drives"),
        _in("motion_sensor/raw_hand", "motion_sensor/hand", "hands in view"),
        _in("motion_sensor/gesture", "motion_sensor/Gesture", "the last gesture"),
        _in("teach/feedback", "std_msgs/String", "teach mode's feedback"),
        _in("motion_commander/latency", "motion_commander/StageLatency", "latency p50/p99"),
        _in("joint_states", "sensor_msgs/JointState", "the joints"),
        _in("motion_controller/tool_pose", "geometry_msgs/PoseStamped", "the tool path"),
        _in("motion_commander/target", "geometry_msgs/PoseStamped", "the hand path"),
        _in("diagnostics", "diagnostic_msgs/DiagnosticArray", "the sequencer's counters"),
        _in("motion_controller/status", "diagnostic_msgs/DiagnosticStatus", "the driver's state"),
        _in("episodes/status", "std_msgs/String", "the episode recorder's state (episode panel)"),
        _in("episodes/list", "std_msgs/String", "the recorded episodes (episode panel)"),
        _in("kitting_trials/progress", "std_msgs/String", "campaign progress"),
        _in("kitting_trials/result", "std_msgs/String", "campaign result"),
        _in("kitting/tray", "std_msgs/String", "the kitting tray's filled slots (kitting panel)"),
        _in("kitting/events", "kitting/KittingEvent", "the kitting cell's picks, places and misses (event log)"),
        _in(
            "kitting/vision/annotated",
            "sensor_msgs/CompressedImage",
            "the kitting camera with its detections drawn (camera panel)",
        ),
    ),
    calls=(
        Service("motion_controller/latch_stop", "std_srvs/SetBool", "latch or release the stop"),
        Service("motion_controller", "motion_commander/commander", "program replay and dry runs"),
        Service("kitting_cell_sim/spawn", "kitting/SpawnPart", "campaigns", optional=True),
    ),
)


def all_interfaces():
    """Every node of this package."""
    return [DASHBOARD]
