"""A fast stamped stream thinned to what a recorder sampling it at a frame rate needs (plain
Python: publishing and the subscriber count are injected, so it is tested without ROS).

A dataset recorder makes a frame every ``period`` s of the wall clock, each standing for the
instant ``k * period`` and blended between the two messages stamped around it. Subscribing
to the 100-110 Hz streams themselves costs their publishers a serialisation and a write per
message for each extra subscriber (most of recording's CPU), for ~2 messages a frame that
are used. So the producer offers a tap: of the messages it publishes anyway, the tap
forwards only the two around each multiple of the period (the last stamped at or before
it and the first after it), ~2 per frame instead of ~10, and nothing while no one listens
or the period is unknown. A stream the recorder takes as it is, not blended
(``pairs=False``: the hand), needs only the first message after each multiple. A producer
that can blend its own samples (``at_instant``: the server's joints and tool, the core's
command and target, ``motion_common.frame_blend``) sends one message a frame instead: its
value at the instant, stamped with it, made from the two samples around it. The recorder
announces the period (``FrameTap.period``).
"""

import math
import threading

__all__ = ["FrameTap", "MAX_INSTANTS"]

# The most instants one sample sends after a gap (a recorder makes up at most 10 missed
# frames: motion_apps' frame pacer).
MAX_INSTANTS = 12


class FrameTap:
    """Forwards (``publish``) the messages of a stamped stream around each multiple of
    ``period`` s, while ``connected()``."""

    def __init__(self, publish, connected, period: float | None = None, pairs: bool = True, at_instant=None):
        self._publish = publish
        self._connected = connected
        self.period = period
        self.pairs = pairs
        # at_instant(stamp before, sample before, stamp after, sample after, instant) -> the
        # one message sent for the instant (None: the samples themselves are sent)
        self.at_instant = at_instant
        self._last = None  # [bucket, message, forwarded, stamp] of the previous message
        self._lock = threading.Lock()  # a stream may be fed from two threads

    def add(self, stamp: float, message) -> int:
        """Offer the stream's next message; how many messages were forwarded (0-2; with
        ``at_instant``, one for each multiple since the last message)."""
        with self._lock:
            return self._add(stamp, message)

    def _add(self, stamp: float, message) -> int:
        period = self.period
        if not period or period <= 0 or not self._connected():
            self._last = None
            return 0
        bucket = math.floor(stamp / period)
        last, sent = self._last, 0
        if last is not None and bucket > last[0]:  # a multiple of the period lies in (last, stamp]
            if self.at_instant is not None:
                # Every multiple in (last, stamp]: after a gap (a producer held up, a stalled
                # simulation) each instant gets its value between the two samples, as a blend
                # of the whole stream would; the last MAX_INSTANTS of a long gap only.
                first = max(last[0] + 1, bucket - MAX_INSTANTS + 1)
                for k in range(first, bucket + 1):
                    self._publish(self.at_instant(last[3], last[1], stamp, message, k * period))
                self._last = [bucket, message, True, stamp]
                return bucket + 1 - first
            if self.pairs and not last[2]:
                self._publish(last[1])
                sent += 1
            self._publish(message)
            sent += 1
        self._last = [bucket, message, sent > 0, stamp]
        return sent
