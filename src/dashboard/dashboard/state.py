"""The dashboard's state: ROS callbacks write it from their threads, the page reads
snapshots from the web server's thread. One lock; a snapshot is a plain dict copy.

Everything that grows is bounded: paths, latency window, time series and event log are
deques with a maxlen, and the camera keeps only its latest frame."""

import copy
import threading
import time
from collections.abc import Callable

from .event_log import EventLog
from .path_buffer import PathBuffer
from .readings import LatencyWindow
from .series import Telemetry
from .status_style import log_text

__all__ = ["DashboardState"]


class DashboardState:
    """Thread-safe store of everything the page shows.

    ``set(key, value)`` records a value and when it arrived (``clock``, injectable for
    tests); ``snapshot()`` returns every value, its age in seconds, the latency
    percentiles and the plot's path series.
    """

    def __init__(
        self,
        clock: Callable[[], float] = time.monotonic,
        path_points: int = 400,
        path_interval_s: float = 0.05,
        latency_window: int = 500,
        series_points: int = 600,
        series_interval_s: float = 0.1,
        events: int = 200,
        wall_clock: Callable[[], float] = time.time,
    ):
        self._clock = clock
        self._lock = threading.Lock()
        self._values = {}
        self._stamps = {}
        self._paths = PathBuffer(path_points, path_interval_s)
        self._latency = LatencyWindow(latency_window)
        self._telemetry = Telemetry(series_points, series_interval_s)
        self._events = EventLog(events, clock=wall_clock)
        self._camera = None  # (format, bytes) of the latest annotated frame
        self._camera_frames = 0
        self._joint_version = 0

    def set(self, key: str, value) -> None:
        """Record ``value`` under ``key`` now."""
        with self._lock:
            self._values[key] = value
            self._stamps[key] = self._clock()

    def update(self, **values) -> None:
        """Record several values at once."""
        with self._lock:
            now = self._clock()
            for key, value in values.items():
                self._values[key] = value
                self._stamps[key] = now

    def get(self, key: str, default=None):
        """One value (a copy-free read: callers must not mutate it)."""
        with self._lock:
            return self._values.get(key, default)

    def age(self, key: str) -> float | None:
        """Seconds since ``key`` was last set, or None if never."""
        with self._lock:
            stamp = self._stamps.get(key)
            return None if stamp is None else self._clock() - stamp

    def add_path_point(self, name: str, t: float, position) -> None:
        """A point of the hand ('hand') or tool ('tool') path."""
        with self._lock:
            self._paths.add(name, t, position)

    def robot_pose(self) -> dict:
        """What the 3-D view draws, copied: joints (names, radians), the hand target and the
        tool path in 3-D (m). Lighter than snapshot(): the view refreshes at 10 Hz."""
        with self._lock:
            return {
                "joint_state": self._values.get("joint_state"),
                "joint_version": self._joint_version,
                "target": self._values.get("target"),
                "tool_path": self._paths.points("tool"),
            }

    def set_joints(self, names, positions) -> None:
        """A joint_states message: names and positions (rad)."""
        with self._lock:
            now = self._clock()
            self._values["joint_state"] = (tuple(names), tuple(float(p) for p in positions))
            self._stamps["joint_state"] = now
            self._joint_version += 1

    def clear_paths(self) -> None:
        """Empty the plot."""
        with self._lock:
            self._paths.clear()

    def add_latency(self, seconds: float) -> None:
        """One command's sensor-to-driver latency (the p50/p99 window and the chart)."""
        with self._lock:
            self._latency.add(seconds)
            self._telemetry.add_latency(self._clock(), seconds)

    def set_status(self, code: int) -> None:
        """The teleop status: its value, a chart sample, and a log line when it changes
        (status_style.log_text: the streaming states count as one)."""
        code = int(code)
        with self._lock:
            now = self._clock()
            self._values["status"], self._stamps["status"] = code, now
            self._telemetry.add_status(now, code)
            text = log_text(code)
            if self._events.changed("status", text):
                self._events.add("status", text)

    def set_watched(self, key: str, value, kind: str, text: str) -> None:
        """Record ``value`` under ``key`` and log ``text`` when the value changed."""
        with self._lock:
            self._values[key], self._stamps[key] = value, self._clock()
            if self._events.changed(key, value):
                self._events.add(kind, text)

    def add_target(self, t: float, position) -> None:
        """The hand target (m): the path plot, and the reference of the tracking error."""
        with self._lock:
            self._paths.add("hand", t, position)
            self._telemetry.add_target(self._clock(), position)
            self._values["target"], self._stamps["target"] = tuple(float(v) for v in position), self._clock()

    def add_tool(self, t: float, position) -> None:
        """The measured tool position (m): the path plot and a tracking-error sample."""
        with self._lock:
            self._paths.add("tool", t, position)
            self._telemetry.add_tool(self._clock(), position)

    def log(self, kind: str, text: str) -> None:
        """One event for the page's log."""
        with self._lock:
            self._events.add(kind, text)

    def set_camera(self, image_format: str, data: bytes) -> None:
        """The latest annotated camera frame (only the latest is kept)."""
        with self._lock:
            self._camera = (str(image_format), bytes(data))
            self._camera_frames += 1
            self._stamps["camera"] = self._clock()

    def camera(self):
        """(frame number, format, bytes) of the latest camera frame, or None."""
        with self._lock:
            return None if self._camera is None else (self._camera_frames, *self._camera)

    def snapshot(self) -> dict:
        """Everything, copied: {'values', 'ages', 'latency_ms', 'paths', 'series',
        'events' (lines, newest first), 'events_version', 'camera_frames'}."""
        with self._lock:
            now = self._clock()
            return {
                "values": copy.deepcopy(self._values),
                "ages": {key: now - stamp for key, stamp in self._stamps.items()},
                "latency_ms": self._latency.percentiles_ms(),
                "paths": self._paths.series(),
                "series": self._telemetry.relative(now),
                "events": [event.line() for event in self._events.newest_first()],
                "events_version": self._events.version,
                "camera_frames": self._camera_frames,
            }
