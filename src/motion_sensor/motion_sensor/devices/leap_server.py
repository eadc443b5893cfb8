"""A local Leap v6 WebSocket service that replays a recording at its recorded timing.

It sends exactly what a Leap service sends ({"version":6}, then frame texts), so the Leap
driver can be run and tested without a device. Faults can be injected to exercise the
driver and the sequencer: malformed, truncated, oversized and NaN frames, dropouts (frames
lost), and hand exit and entry (frames without hands). Used by the rostests and the
``leap_replay_server`` tool.
"""

import gzip
import json
import threading
import time
from dataclasses import dataclass, field

from websockets.exceptions import ConnectionClosed
from websockets.sync.server import serve

from motion_sensor.errors import MotionSensorError


@dataclass
class Faults:
    """Which faults to inject, by frame index of the recording."""

    malformed: list[int] = field(default_factory=list)  # replaced by broken JSON
    truncated: list[int] = field(default_factory=list)  # cut in half
    oversized: list[int] = field(default_factory=list)  # padded past 256 kB
    nan: list[int] = field(default_factory=list)  # palmPosition becomes NaN
    dropout_at: int | None = None  # frames from this one ...
    dropout_s: float = 0.0  # ... for this long are lost (not sent)
    exit_at: int | None = None  # from here, frames carry no hand ...
    exit_frames: int = 0  # ... for this many frames (then re-entry)


def load_lines(path: str) -> list[str]:
    """The messages of a .jsonl/.jsonl.gz recording, version line first."""
    opener = gzip.open if path.endswith(".gz") else open
    try:
        with opener(path, "rt", encoding="utf-8") as fh:
            lines = [line.rstrip("\n") for line in fh if line.strip()]
    except OSError as exc:
        raise MotionSensorError(f"cannot read recording {path}: {exc}") from None
    if not lines or '"version"' not in lines[0]:
        raise MotionSensorError(f'{path} does not start with the Leap {{"version":6}} line')
    return lines


def _inject(index: int, text: str, faults: Faults) -> str:
    if index in faults.malformed:
        return '{"id": 1, "timestamp": oops}'
    if index in faults.truncated:
        return text[: len(text) // 2]
    if index in faults.oversized:
        return text[:-1] + ', "padding": "' + "x" * 300_000 + '"}'
    if index in faults.nan:
        frame = json.loads(text)
        for hand in frame.get("hands", []):
            hand["palmPosition"] = [float("nan")] * 3
        return json.dumps(frame)
    if faults.exit_at is not None and faults.exit_at <= index < faults.exit_at + faults.exit_frames:
        frame = json.loads(text)
        frame["hands"], frame["pointables"] = [], []
        return json.dumps(frame)
    return text


class LeapReplayServer:
    """Serves a recording on ws://host:port/v6.json, one client at a time.

    ``received`` lists the control messages clients sent (the test checks the driver sent
    the exact {"focused":true}); ``done`` is set when a full pass has been sent.
    """

    def __init__(
        self,
        path: str,
        host: str = "127.0.0.1",
        port: int = 6437,
        rate: float = 1.0,
        loop: bool = False,
        faults: Faults | None = None,
        start_delay: float = 0.0,
    ):
        self.lines = load_lines(path)
        self.frames = self.lines[1:]
        self.stamps = [json.loads(line).get("timestamp", 0) * 1e-6 for line in self.frames]
        self.host, self.port, self.rate, self.loop = host, port, rate, loop
        self.faults = faults or Faults()
        self.start_delay = start_delay
        self.received: list[str] = []
        self.sent = 0
        self.send_times = {}  # frame index -> time.time() when sent (latency benchmarks)
        self.done = threading.Event()
        self._server = None

    def _handler(self, socket) -> None:
        socket.send(self.lines[0])
        reader = threading.Thread(target=self._read_controls, args=(socket,), daemon=True)
        reader.start()
        time.sleep(self.start_delay)
        try:
            while True:
                start, origin = time.monotonic(), self.stamps[0]
                for index, text in enumerate(self.frames):
                    if self._lost(index):
                        continue
                    if self.rate > 0:
                        delay = start + (self.stamps[index] - origin) / self.rate - time.monotonic()
                        if delay > 0:
                            time.sleep(delay)
                    socket.send(_inject(index, text, self.faults))
                    self.send_times.setdefault(index, time.time())
                    self.sent += 1
                self.done.set()
                if not self.loop:
                    break
            socket.close()
        except ConnectionClosed:
            pass

    def _lost(self, index: int) -> bool:
        """True for frames inside the injected dropout (lost as on a real link)."""
        at = self.faults.dropout_at
        if at is None or index < at:
            return False
        return self.stamps[index] - self.stamps[at] < self.faults.dropout_s

    def _read_controls(self, socket) -> None:
        try:
            for message in socket:
                self.received.append(message)
        except ConnectionClosed:
            pass

    def serve_forever(self) -> None:
        """Serve until shutdown()."""
        with serve(
            self._handler, self.host, self.port, compression=None, max_size=4 * 1024 * 1024, close_timeout=0.5
        ) as server:
            self._server = server
            server.serve_forever()

    def start(self) -> "LeapReplayServer":
        """Serve in a background thread; returns self."""
        threading.Thread(target=self.serve_forever, daemon=True).start()
        deadline = time.monotonic() + 5.0
        while self._server is None and time.monotonic() < deadline:
            time.sleep(0.01)
        return self

    def shutdown(self) -> None:
        """Stop serving."""
        if self._server is not None:
            self._server.shutdown()
