"""The LeRobot writer process: writes the episodes the recorder streams to it with LeRobot's
own ``LeRobotDataset`` (create/add_frame/save_episode/finalize), one committed version of the
dataset per episode (``dataset_store``).

It runs in ``.venv-lerobot`` (LeRobot's pins, torch among them, never touch the framework's
venv), started by ``episode_writer_client`` as ``python lerobot_writer.py`` with messages
(``episode_wire``) on stdin and one JSON reply a line on stdout:

- ``open``: dataset ``root``, ``repo_id``, ``fps``, LeRobot ``features``, ``robot_type``,
  ``vcodec`` -> ``opened`` (episodes already there);
- ``start``: ``task`` -> ``started`` (``episode_index``): a staging copy is opened;
- ``frame`` (no reply): the arrays of one frame;
- ``save``: ``success`` and ``info`` (the recorder's counts) -> ``saved``: LeRobot writes the
  episode into the staging copy, the framework's record goes into
  ``meta/teleop_episodes.json``, and the copy becomes the dataset (atomic);
- ``discard`` -> ``discarded``; ``mark``: ``episode_index``, ``success`` (and ``root``
  when nothing was opened) -> ``marked``;
- end of stdin: an episode in progress is discarded, and the process ends.

A bad message or a LeRobot error is answered with ``error`` (its reason) and the episode in
progress is dropped; the process keeps serving. Being a separate process, its encoding and
disk writes never run in the recorder's (nor the control path's) interpreter.
"""

import json
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
from dataset_store import DatasetStore, read_sidecar, write_sidecar  # noqa: E402
from episode_wire import WireError, read_message  # noqa: E402

__all__ = ["Writer", "main"]


def _reply(out, event: str, **fields) -> None:
    out.write(json.dumps({"event": event, **fields}) + "\n")
    out.flush()


class Writer:
    """The state of one writer process: the dataset and the episode in progress."""

    def __init__(self):
        self.store = None
        self.config = None
        self.dataset = None
        self.staging = None
        self.task = ""
        self.frames = 0
        self.failure = None  # why the episode in progress was dropped (a bad frame), told at save

    def _lerobot(self):
        from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: PLC0415 - heavy (torch)

        return LeRobotDataset

    def open(self, header: dict) -> dict:
        self.store = DatasetStore(header["root"])
        self.config = dict(header)
        # JSON has no tuples; LeRobot compares shapes as tuples.
        self.config["features"] = {
            key: dict(spec, shape=tuple(spec["shape"])) for key, spec in header["features"].items()
        }
        current = self.store.current()
        episodes = len(read_sidecar(current)) if current else 0
        if current:
            self._check_features(current)
        return {"episodes": episodes, "root": self.store.path}

    def _check_features(self, root: str) -> None:
        """An existing dataset must hold the same features (joints, camera size)."""
        with open(os.path.join(root, "meta", "info.json"), encoding="utf-8") as stream:
            existing = json.load(stream)["features"]
        for key, spec in self.config["features"].items():
            old = existing.get(key)
            if old is None:
                raise RuntimeError(f"{self.store.path} has no feature {key!r}: record into a new dataset")
            if list(old["shape"]) != list(spec["shape"]) or old.get("names") != spec.get("names"):
                raise RuntimeError(
                    f"{self.store.path}: feature {key!r} is {old['shape']} {old.get('names')}, this session's is "
                    f"{list(spec['shape'])} {spec.get('names')}: record into a new dataset"
                )

    def start(self, header: dict) -> dict:
        if self.store is None:
            raise RuntimeError("start before open")
        if self.dataset is not None:
            self.discard()
        dataset_class = self._lerobot()
        self.staging = self.store.stage()
        cfg = self.config
        if self.store.current() is None:
            self.dataset = dataset_class.create(
                repo_id=cfg["repo_id"],
                fps=int(cfg["fps"]),
                features=cfg["features"],
                root=self.staging,
                robot_type=cfg.get("robot_type") or None,
                use_videos=True,
                vcodec=cfg.get("vcodec", "h264"),
                image_writer_threads=int(cfg.get("image_writer_threads", 1)),
            )
        else:
            self.dataset = dataset_class(
                cfg["repo_id"], root=self.staging, vcodec=cfg.get("vcodec", "h264"), video_backend="pyav"
            )
            if int(cfg.get("image_writer_threads", 1)):
                self.dataset.start_image_writer(num_threads=int(cfg.get("image_writer_threads", 1)))
        self.task = str(header.get("task", ""))
        self.frames = 0
        self.failure = None
        return {"episode_index": int(self.dataset.meta.total_episodes), "task": self.task}

    def frame(self, arrays: dict) -> None:
        if self.dataset is None:
            return  # frames after a stop or an error: nothing to add them to
        frame = {key: np.asarray(value) for key, value in arrays.items()}
        frame["task"] = self.task
        self.dataset.add_frame(frame)
        self.frames += 1

    def save(self, header: dict) -> dict:
        if self.failure:
            failure, self.failure = self.failure, None
            raise RuntimeError(f"episode dropped: {failure}")
        if self.dataset is None:
            raise RuntimeError("save without an episode in progress")
        if self.frames == 0:
            self.discard()
            raise RuntimeError("episode has no frames: discarded")
        index = int(self.dataset.meta.total_episodes)
        self.dataset.save_episode(parallel_encoding=False)
        self.dataset.finalize()
        self.dataset.stop_image_writer()
        record = dict(header.get("info", {}))
        record.update(episode_index=index, task=self.task, frames=self.frames, success=bool(header.get("success")))
        episodes = read_sidecar(self.staging)
        episodes.append(record)
        write_sidecar(self.staging, episodes)
        self.dataset = None
        root = self.store.commit(self.staging)
        self.staging = None
        return {"episode_index": index, "frames": record["frames"], "success": record["success"], "version": root}

    def discard(self) -> dict:
        if self.dataset is not None:
            try:
                self.dataset.stop_image_writer()
            except Exception:  # noqa: BLE001 - a broken episode is being thrown away anyway
                pass
        self.dataset = None
        if self.staging:
            self.store.discard(self.staging)
        self.staging = None
        return {}

    def mark(self, header: dict) -> dict:
        if self.store is None and header.get("root"):
            self.store = DatasetStore(header["root"])  # marking needs no features: no open
        if self.store is None:
            raise RuntimeError("mark before open")
        record = self.store.mark(int(header["episode_index"]), bool(header.get("success")))
        return {"episode_index": record["episode_index"], "success": record["success"]}


def main(stdin=None, stdout=None) -> int:
    # Ctrl-C (roslaunch's SIGINT to the recorder's process group) reaches this process too:
    # the recorder saves the episode in progress at its shutdown and then ends this process
    # by closing its stdin, so SIGINT must not kill it first.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    stdin = stdin or sys.stdin.buffer
    stdout = stdout or sys.stdout
    writer = Writer()
    writer._lerobot()  # LeRobot and torch load while the recorder waits for its first episode
    handlers = {
        "open": writer.open,
        "start": writer.start,
        "save": writer.save,
        "discard": lambda _h: writer.discard(),
        "mark": writer.mark,
    }
    replies = {"open": "opened", "start": "started", "save": "saved", "discard": "discarded", "mark": "marked"}
    while True:
        try:
            message = read_message(stdin)
        except EOFError:
            message = None
        except WireError as exc:
            writer.discard()
            _reply(stdout, "error", command="?", reason=f"malformed message: {exc}")
            return 2  # the stream is out of step: nothing after this can be trusted
        if message is None:
            writer.discard()
            return 0
        header, arrays = message
        command = header.get("cmd")
        try:
            if command == "frame":
                try:
                    writer.frame(arrays)
                except Exception as exc:  # noqa: BLE001 - told at the episode's save
                    writer.discard()
                    writer.failure = writer.failure or f"{type(exc).__name__}: {exc}"
                continue
            if command not in handlers:
                raise RuntimeError(f"unknown command {command!r}")
            _reply(stdout, replies[command], **handlers[command](header))
        except Exception as exc:  # noqa: BLE001 - reported to the recorder; the process keeps serving
            if command in ("start", "save"):
                writer.discard()
            _reply(stdout, "error", command=str(command), reason=f"{type(exc).__name__}: {exc}")


if __name__ == "__main__":
    sys.exit(main())
