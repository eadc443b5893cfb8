"""Commands the dashboard runs for the operator (a program replay or dry run, a kitting
campaign) as child processes: their output is kept for the page, and they are ended with
SIGINT like roslaunch ends a node."""

import json
import os
import signal
import subprocess
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence


class Job:
    """One child process; ``lines`` holds the last ``keep_lines`` lines of its output."""

    def __init__(
        self, name: str, command: Sequence[str], keep_lines: int = 200, on_exit: Callable[["Job"], None] | None = None
    ):
        self.name = name
        self.command = list(command)
        self._lines = deque(maxlen=keep_lines)
        self._lock = threading.Lock()
        self._on_exit = on_exit
        self.started = time.time()  # wall clock: what the job writes is newer than this
        # Its own process group, so an end reaches what it started too (rosrun's child).
        self.process = subprocess.Popen(
            self.command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1, start_new_session=True
        )
        self._reader = threading.Thread(target=self._read, name=f"job-{name}", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.process.stdout:
            with self._lock:
                self._lines.append(line.rstrip("\n"))
        self.process.wait()
        if self._on_exit is not None:
            self._on_exit(self)

    @property
    def running(self) -> bool:
        """True until the process has exited."""
        return self.process.poll() is None

    @property
    def exit_code(self) -> int | None:
        """The exit code, or None while it runs."""
        return self.process.poll()

    def lines(self) -> list[str]:
        """The output kept so far."""
        with self._lock:
            return list(self._lines)

    def stop(self, timeout: float = 10.0) -> int | None:
        """SIGINT the process group, then SIGKILL if it has not exited within ``timeout``."""
        if self.running:
            try:
                os.killpg(self.process.pid, signal.SIGINT)
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait()
            except ProcessLookupError:
                pass
        self._reader.join(timeout)
        return self.process.poll()

    def wait(self, timeout: float | None = None) -> int | None:
        """Wait for the exit and for its output to be read; the exit code."""
        self.process.wait(timeout)
        self._reader.join(timeout)
        return self.process.poll()


def run_program_command(path: str, dry_run: bool, scene: str = "") -> list[str]:
    """motion_apps' run_program on a program file (checked first; --dry-run moves nothing)."""
    command = ["rosrun", "motion_apps", "run_program", path]
    if dry_run:
        command.append("--dry-run")
    if scene:
        command += ["--scene", scene]
    return command


def campaign_command(trials: int, seed: int, perturb: bool, output_dir: str) -> list[str]:
    """kitting's kitting_trials feeding the simulated cell (it reports when done or ended)."""
    if trials < 1:
        raise ValueError(f"a campaign needs at least 1 trial, got {trials}")
    return [
        "rosrun",
        "kitting",
        "kitting_trials",
        "__name:=dashboard_campaign",
        f"_trials:={int(trials)}",
        f"_seed:={int(seed)}",
        f"_perturb:={'true' if perturb else 'false'}",
        f"_output_dir:={output_dir}",
    ]


def campaign_summary(path: str, since: float, exit_code) -> dict:
    """The summary a campaign started at ``since`` (wall clock) wrote to ``path``, or an
    error: a file older than the campaign is an earlier run's, never this one's."""
    try:
        if os.path.getmtime(path) < since:
            return {"error": f"campaign exited ({exit_code}) before writing a summary of this run"}
        with open(path, encoding="utf-8") as stream:
            return json.load(stream)
    except (OSError, ValueError) as exc:
        return {"error": f"campaign exited ({exit_code}), no summary: {exc}"}
