"""Framework core: from a filtered hand pose to a safe joint command, the paper's
manipulation API, and the taught-program file format.

Its modules, by role (the robot model itself is ``motion_common.kinematics``):

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- teleoperation: ``teleop`` (hand motion since the clutch engaged, scaled, becomes a tool
  target; the clutches), ``safety`` (joint speed and acceleration limits, joint limit
  margin, singularity guard, workspace fence, engage ramp, stale-command watchdog, after
  moveit_servo's set), ``teleop_core`` (``TeleopCore``: one hand pose in, one checked
  joint command out), ``prepare_timing`` (when the between-frames work runs), ``config``
  (the teleop parameters, their units and start-up checks);
- ``manipulation``: the paper's manipulation API, pick-and-place and the MoveJ/MoveL
  vocabulary, over any object with the motion controller client's methods;
- ``program``: the program file of a gesture-taught task (read and written by both
  applications);
- ``session_report``: a teleop session's figures and plot, in bounded memory
  (``latency_stats``: streaming latency percentiles in a fixed histogram; ``lag_estimate``:
  how far one path trails another, the hand-to-tool delay);
- ``server_watch``: whether the robot server is alive (failed calls, stale joint_states),
  probed with backoff while it is lost;
- ``errors``: ``MotionCommanderError``.

No module here imports rospy: the nodes (``nodes/``) are the ROS edges. The names in
``__all__`` are imported from their module on first use, so ``import motion_commander``
does not load pinocchio.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "TeleopMapper": "teleop",
    "make_clutch": "teleop",
    "CLUTCHES": "teleop",
    "AutoClutch": "teleop",
    "GestureClutch": "teleop",
    "ButtonClutch": "teleop",
    "JointStepLimiter": "safety",
    "JointLimitMargin": "safety",
    "SingularityGuard": "safety",
    "WorkspaceFence": "safety",
    "EngageRamp": "safety",
    "StaleCommandWatchdog": "safety",
    "condition_number": "safety",
    "TeleopCore": "teleop_core",
    "TeleopStatus": "teleop_core",
    "TeleopCommand": "teleop_core",
    "Action": "teleop_core",
    "SafetyConfig": "teleop_core",
    "STREAMING_STATUSES": "teleop_core",
    "PrepareTiming": "prepare_timing",
    "TeleopConfig": "config",
    "load_teleop_config": "config",
    "TELEOP_PARAMETERS": "config",
    "ManipulationAPI": "manipulation",
    "Program": "program",
    "Waypoint": "program",
    "ProgramError": "program",
    "parse_program": "program",
    "load_program": "program",
    "save_program": "program",
    "SessionData": "session_report",
    "summarize": "session_report",
    "format_summary": "session_report",
    "plot_session": "session_report",
    "write_summary_json": "session_report",
    "MotionCommanderError": "errors",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
