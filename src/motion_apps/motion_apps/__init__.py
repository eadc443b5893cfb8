"""Application layer: gesture-taught programs.

Its modules, by role (the program file format itself is ``motion_commander.program``,
shared with the kitting application):

- ``interfaces``: the one declaration of each of this package's nodes (parameters, topics,
  services; see ``motion_common.interface``), from which docs/interfaces.md is generated;
- ``teach``: the teach-mode state machine, fed with gesture events and tool poses, and
  its gesture configuration;
- ``program_check``: reachability, workspace fence and collision check of every waypoint
  and segment before the arm moves (in a pybullet scene);
- ``program_runner``: replays a program through the manipulation API;
- ``teach_report``: the teach demo's placement error, summary and taught-path plot.

Plain Python: no rospy outside ``nodes/``. The names in ``__all__`` are imported from
their module on first use, so ``import motion_apps`` loads neither pybullet nor
pinocchio.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "TeachSession": "teach",
    "Feedback": "teach",
    "load_gesture_config": "teach",
    "check_gesture_config": "teach",
    "ProgramChecker": "program_check",
    "CheckReport": "program_check",
    "Issue": "program_check",
    "load_check_params": "program_check",
    "load_scene_file": "program_check",
    "ProgramRunner": "program_runner",
    "RunOutcome": "program_runner",
    "EXIT_OK": "program_runner",
    "EXIT_STOPPED": "program_runner",
    "EXIT_REFUSED": "program_runner",
    "taught_place": "teach_report",
    "placement_error": "teach_report",
    "write_summary": "teach_report",
    "format_summary": "teach_report",
    "plot_taught_path": "teach_report",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
