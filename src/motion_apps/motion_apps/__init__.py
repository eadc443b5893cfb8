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
- ``teach_report``: the teach demo's placement error, summary and taught-path plot;
- demonstrations recorded as LeRobot datasets: ``episode_frames`` (what a frame holds, made
  at a fixed rate from the newest value of each stream), ``frame_pacer`` (the frame clock,
  which makes up the ticks a held-up recorder missed), ``stamped_history`` (a stream's last messages by
  stamp: the tapped values kept for their instants, the replay's tool poses),
  ``skeleton_raw`` (a hand skeleton read from its bytes), ``episode_recorder`` (start, stop,
  discard, mark success, the start/stop gesture, the episode list), ``episode_writer_client``
  (the writer process, fed without blocking), ``episode_wire`` (the messages to it),
  ``lerobot_writer`` (that process: LeRobot's own writer, run in ``.venv-lerobot``),
  ``dataset_store`` (one atomically committed version of the dataset per episode; the
  folder check), ``lerobot_reader`` and ``lerobot_readback`` (a dataset read back by
  LeRobot's own loader, as NumPy arrays), ``episode_replay`` (an episode's actions sent
  again, the tool's error against the recording), ``stream_lag`` (how long the replaying
  arm trails the stream, measured from its stamped joints) and ``episode_report`` (the dataset's
  summary and one episode's picture).

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
    "EpisodeFrames": "episode_frames",
    "EpisodeRecorder": "episode_recorder",
    "EpisodeWriterClient": "episode_writer_client",
    "DatasetStore": "dataset_store",
    "check_dataset_folder": "dataset_store",
    "read_dataset": "lerobot_readback",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
