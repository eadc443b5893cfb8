"""The operator's dashboard: a web page for operation and settings (the paper's
/dashboard_gui).

Its modules, by role:

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- state and readings (plain Python, unit-tested): ``state`` (``DashboardState``: ROS
  callbacks write it, the page reads snapshots), ``path_buffer`` (the hand and tool
  paths), ``series`` (the bounded time series: status, latency, tracking error),
  ``event_log`` (the bounded log, newest first), ``robot_view`` (the arm's links and
  joint readings from the URDF's forward kinematics), ``readings`` (message contents as
  the page shows them), ``status_style`` (the teleop status's name and colour),
  ``episodes`` (the episode recorder's messages as the episode panel shows them), ``tray``
  (the kitting tray's filled slots as the kitting panel shows them);
- rules and actions (plain Python): ``controls`` (which controls can act now, and why
  not; the check of a typed speed ratio), ``application`` (which panels each
  application shows), ``jobs`` (program runs and kitting campaigns as child processes), ``programs``
  (the taught programs on disk), ``access`` (who may open the page), ``config`` (the
  node's parameters);
- ``page``: the NiceGUI page;
- ``dashboard_node``: the ROS edge (rospy): subscribers feed the state, actions call the
  core's and the server's services, and the NiceGUI server runs in its process.

The names in ``__all__`` are imported from their module on first use, so ``import
dashboard`` loads neither NiceGUI nor rospy.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "DashboardState": "state",
    "PathBuffer": "path_buffer",
    "SeriesWindow": "series",
    "Telemetry": "series",
    "EventLog": "event_log",
    "RobotView": "robot_view",
    "segment_pose": "robot_view",
    "joint_readings": "robot_view",
    "detect_application": "application",
    "panels_for": "application",
    "device_label": "readings",
    "image_data_url": "readings",
    "parse_tray": "tray",
    "tray_text": "tray",
    "check_speed_ratio": "controls",
    "RatioDecision": "controls",
    "LatencyWindow": "readings",
    "sequencer_counters": "readings",
    "driver_status": "readings",
    "tool_reading": "readings",
    "status_view": "status_style",
    "is_engaged": "status_style",
    "STATUS_COLOURS": "status_style",
    "ControlState": "controls",
    "control_states": "controls",
    "Job": "jobs",
    "run_program_command": "jobs",
    "campaign_command": "jobs",
    "ProgramInfo": "programs",
    "list_programs": "programs",
    "program_path": "programs",
    "delete_program": "programs",
    "check_access_config": "access",
    "token_accepted": "access",
    "DASHBOARD_PARAMETERS": "config",
    "DashboardPage": "page",
    "serve": "page",
    "DashboardNode": "dashboard_node",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
