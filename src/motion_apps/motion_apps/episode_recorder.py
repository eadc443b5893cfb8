"""Episode recording as a state machine, fed by the recorder node (plain Python, tested
without ROS): start, the fixed-rate ticks, stop (save), discard, mark success, a gesture
that starts and stops, and the list of saved episodes.

Frames go to a writer (``EpisodeWriterClient``, injected) that never blocks a tick; saving,
discarding and starting wait for the writer's answer. An episode longer than
``max_episode_s`` is saved and a new one is not started: memory stays bounded however long
a session runs. Every refusal is returned as a reason, never raised, so the node keeps
running.
"""

import os
import time

from .dataset_store import DatasetStore, DatasetStoreError, read_sidecar
from .episode_frames import EpisodeFrames

__all__ = ["EpisodeRecorder", "read_episode_list"]


def read_episode_list(dataset: str) -> list:
    """The framework's record of each saved episode of ``dataset`` (empty before the first)."""
    return read_sidecar(dataset) if os.path.isdir(dataset) else []


class EpisodeRecorder:
    """One dataset, one episode at a time."""

    def __init__(
        self,
        frames: EpisodeFrames,
        writer_factory,
        dataset: str,
        repo_id: str,
        fps: float,
        task: str,
        robot_type: str = "",
        max_episode_s: float = 600.0,
        toggle_gesture: str = "",
        vcodec: str = "h264",
        clock=time.monotonic,
        wall_clock=time.time,
    ):
        self.frames = frames
        self.writer_factory = writer_factory
        self.writer = None
        self.opened = False
        self.dataset = os.path.abspath(dataset)
        self.repo_id = repo_id
        self.fps = fps
        self.task = task
        self.robot_type = robot_type
        self.max_episode_s = max_episode_s
        self.toggle_gesture = toggle_gesture
        self.vcodec = vcodec
        self.clock = clock
        self.wall_clock = wall_clock
        self.recording = False
        self.episode_index = None
        self.success = False
        self.started = None
        self.started_wall = None
        self.dropped_at_start = 0
        self.last_result = ""

    # -- writer -------------------------------------------------------------------------
    def prepare(self) -> None:
        """Start the writer process early (LeRobot's import takes seconds)."""
        if self.writer is None:
            self.writer = self.writer_factory()

    def _open(self) -> None:
        self.prepare()
        if not self.opened:
            self.writer.command(
                "open",
                root=self.dataset,
                repo_id=self.repo_id,
                fps=int(round(self.fps)),
                features=self.frames.features(),
                robot_type=self.robot_type,
                vcodec=self.vcodec,
            )
            self.opened = True

    # -- commands -----------------------------------------------------------------------
    def start(self, task: str | None = None) -> tuple[bool, str]:
        if self.recording:
            return False, f"episode {self.episode_index} is already being recorded"
        missing = self.frames.missing()
        if missing:
            return False, f"cannot start: no {', '.join(missing)} yet"
        try:
            self._open()
            reply = self.writer.command("start", task=task if task else self.task)
        except Exception as exc:  # noqa: BLE001 - the writer's reason goes to the caller
            return False, f"cannot start: {exc}"
        self.recording = True
        self.episode_index = reply["episode_index"]
        self.success = False
        self.started = self.clock()
        self.started_wall = self.wall_clock()
        self.dropped_at_start = self.writer.dropped
        self.frames.reset_counts()
        return True, f"recording episode {self.episode_index} ({reply['task']!r})"

    def tick(self, late_s: float = 0.0) -> None:
        """One frame at the recorder's rate (call it every 1/fps s, with how late this call
        is, ``late_s``, against its tick). An episode's first frame is not made late by more
        than a frame: starting waits for the writer (seconds the first time, LeRobot's
        import), and a tick held up by it would make a first frame of values that old, while
        the arm moved on (a demo episode's first frame lay 17 cm off its second, and its
        replay jumped there). The next tick makes it."""
        if not self.recording:
            return
        if self.frames.counts.frames == 0 and late_s > 1.0 / self.fps:
            return
        frame = self.frames.sample()
        if frame is not None:
            self.writer.frame(frame)
        if self.clock() - self.started >= self.max_episode_s:
            self.last_result = self.stop()[1] + f" (max_episode_s {self.max_episode_s:g} s reached)"

    def stop(self, success: bool | None = None) -> tuple[bool, str]:
        """Save the episode in progress (with ``success`` if given, else the mark)."""
        if not self.recording:
            return False, "no episode is being recorded"
        self.recording = False
        if success is not None:
            self.success = bool(success)
        counts = self.frames.counts
        duration = counts.frames / self.fps if self.fps else 0.0
        info = counts.as_dict()
        info.update(
            fps=self.fps,
            duration_s=round(duration, 3),
            started_unix_s=round(self.started_wall, 3),
            dropped_frames=self.writer.dropped - self.dropped_at_start,
        )
        if self.frames.camera:
            sampled = max(counts.frames, 1)
            info["camera"] = self.frames.camera
            info["camera_loss_fraction"] = round((counts.camera_repeated + counts.camera_missing) / sampled, 4)
        try:
            reply = self.writer.command("save", success=self.success, info=info)
        except Exception as exc:  # noqa: BLE001
            return False, f"episode {self.episode_index} not saved: {exc}"
        return True, f"saved episode {reply['episode_index']}: {reply['frames']} frames, success={reply['success']}"

    def discard(self) -> tuple[bool, str]:
        if not self.recording:
            return False, "no episode is being recorded"
        self.recording = False
        try:
            self.writer.command("discard")
        except Exception as exc:  # noqa: BLE001
            return False, f"discard: {exc}"
        return True, f"discarded episode {self.episode_index}"

    def mark_success(self, success: bool) -> tuple[bool, str]:
        """Mark the episode in progress; with none, the last saved one."""
        if self.recording:
            self.success = bool(success)
            return True, f"episode {self.episode_index} will be saved with success={self.success}"
        episodes = self.episodes()
        if not episodes:
            return False, "no episode to mark"
        last = episodes[-1]["episode_index"]
        try:
            DatasetStore(self.dataset).mark(last, success)  # the writer is idle between episodes
        except (DatasetStoreError, OSError) as exc:
            return False, f"mark: {exc}"
        return True, f"episode {last} marked success={bool(success)}"

    def on_gesture(self, name: str) -> tuple[bool, str] | None:
        """The start/stop gesture toggles recording; other gestures are not ours (None)."""
        if not self.toggle_gesture or name != self.toggle_gesture:
            return None
        return self.stop() if self.recording else self.start()

    # -- reading ------------------------------------------------------------------------
    def episodes(self) -> list:
        try:
            return read_episode_list(self.dataset)
        except DatasetStoreError:
            return []

    def status(self) -> dict:
        return {
            "dataset": self.dataset,
            "recording": self.recording,
            "episode_index": self.episode_index if self.recording else None,
            "frames": self.frames.counts.frames if self.recording else 0,
            "success": self.success if self.recording else None,
            "last_result": self.last_result,
        }

    def close(self) -> None:
        """End the writer; an episode in progress is discarded."""
        if self.writer is not None:
            self.writer.close()
            self.writer = None
