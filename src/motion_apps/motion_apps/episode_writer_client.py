"""The recorder's side of the LeRobot writer process (``lerobot_writer``, in
``.venv-lerobot``): starts it, sends it commands and frames, and collects its replies.

Frames go through a bounded queue drained by one sender thread, so a slow disk or a video
encode never blocks the caller: when the queue is full the frame is dropped and counted
(``dropped``), and the count goes into the episode's record. Commands wait for their reply
(``timeout_s``); a writer that died or answered ``error`` raises ``WriterError`` with its
reason.
"""

import json
import os
import queue
import subprocess
import threading

from .episode_wire import encode

__all__ = ["WriterError", "EpisodeWriterClient", "LEROBOT_PYTHON", "WRITER_SCRIPT"]

_PROJECT = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", ".."))
LEROBOT_PYTHON = os.path.join(_PROJECT, ".venv-lerobot", "bin", "python")
WRITER_SCRIPT = os.path.join(os.path.dirname(os.path.realpath(__file__)), "lerobot_writer.py")
WRITER_NICENESS = 10


class WriterError(RuntimeError):
    """The writer process failed a command, or is gone (the reason in the text)."""


class EpisodeWriterClient:
    """One writer process for one dataset."""

    def __init__(self, python: str = LEROBOT_PYTHON, queue_frames: int = 120, timeout_s: float = 120.0, env=None):
        if not os.path.exists(python):
            raise WriterError(
                f"{python} is missing: LeRobot is installed by `scripts/setup --datasets` (or --test) "
                "into its own venv, .venv-lerobot"
            )
        child_env = dict(os.environ if env is None else env)
        # Offline and quiet: the dataset is local, and a hub lookup can only fail here.
        child_env.update(
            HF_HUB_OFFLINE="1", HF_DATASETS_OFFLINE="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", PYTHONUNBUFFERED="1"
        )
        child_env.pop("PYTHONPATH", None)  # the framework's (Debian's rospy) must not leak into LeRobot's venv
        self.process = subprocess.Popen(
            [python, WRITER_SCRIPT],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=child_env,
            text=False,
            # Encoding and disk writes yield the CPU to the control path (a 2-core robot PC).
            preexec_fn=lambda: os.nice(WRITER_NICENESS),
        )
        self.timeout_s = timeout_s
        self.dropped = 0
        self._frames = queue.Queue(maxsize=queue_frames)
        self._replies = queue.Queue()
        self._write_lock = threading.Lock()
        self._stderr_tail = []
        threading.Thread(target=self._read_replies, daemon=True).start()
        threading.Thread(target=self._read_stderr, daemon=True).start()
        threading.Thread(target=self._send_frames, daemon=True).start()

    # -- threads ------------------------------------------------------------------------
    def _read_replies(self):
        for line in self.process.stdout:
            try:
                self._replies.put(json.loads(line))
            except ValueError:
                continue  # a library printed to stdout: not a reply
        self._replies.put({"event": "exit"})

    def _read_stderr(self):
        for line in self.process.stderr:
            self._stderr_tail = (self._stderr_tail + [line.decode("utf-8", "replace").rstrip()])[-20:]

    def _send_frames(self):
        while True:
            item = self._frames.get()
            if item is None:
                return
            if isinstance(item, threading.Event):
                item.set()  # every frame queued before the marker is written
                continue
            self._write(item)

    def _write(self, blob: bytes) -> None:
        with self._write_lock:
            try:
                self.process.stdin.write(blob)
                self.process.stdin.flush()
            except (BrokenPipeError, ValueError, OSError):
                pass  # the process is gone; the next command says so

    # -- API ----------------------------------------------------------------------------
    def command(self, cmd: str, **fields) -> dict:
        """Send a command after every frame queued so far; wait for its reply."""
        self.flush()
        self._write(encode({"cmd": cmd, **fields}))
        try:
            reply = self._replies.get(timeout=self.timeout_s)
        except queue.Empty:
            raise WriterError(f"writer: no answer to {cmd} within {self.timeout_s:.0f} s") from None
        if reply.get("event") == "exit":
            self._replies.put(reply)
            tail = "\n".join(self._stderr_tail[-8:])
            raise WriterError(f"writer process ended (exit {self.process.wait()}) during {cmd}:\n{tail}")
        if reply.get("event") == "error":
            raise WriterError(f"writer: {reply.get('command')}: {reply.get('reason')}")
        return reply

    def frame(self, arrays: dict) -> bool:
        """Queue one frame (never blocks); False when it was dropped."""
        try:
            self._frames.put_nowait(encode({"cmd": "frame"}, arrays))
            return True
        except queue.Full:
            self.dropped += 1
            return False

    def flush(self, timeout_s: float = 60.0) -> None:
        """Wait until every queued frame is written to the pipe."""
        marker = threading.Event()  # queued behind the frames: the sender sets it after them
        try:
            self._frames.put(marker, timeout=timeout_s)
        except queue.Full:
            raise WriterError(f"writer: frames not taken within {timeout_s:.0f} s") from None
        while not marker.wait(0.05):
            if self.process.poll() is not None:
                return

    def close(self, timeout_s: float = 30.0) -> int:
        """End the writer (an episode in progress is discarded); its exit code."""
        self.flush()
        self._frames.put(None)
        try:
            self.process.stdin.close()
        except OSError:
            pass
        try:
            return self.process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.process.wait()
