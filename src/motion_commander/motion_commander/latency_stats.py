"""LatencyStats: exact-to-10-microseconds percentiles of a day-long stream of latencies in
fixed memory.

A session that runs all day makes millions of commands; keeping every latency would grow
without bound. A histogram of 10 us bins up to 1 s (400 kB) keeps the count, the mean,
the maximum and every percentile to within half a bin; slower values (a stall) are counted
and their maximum kept. Plain numpy, no ROS.
"""

import numpy as np

__all__ = ["LatencyStats"]


class LatencyStats:
    """Streaming latencies (seconds): ``append`` each, ask ``percentile`` at any time."""

    def __init__(self, values=(), bin_s: float = 1e-5, span_s: float = 1.0):
        self.bin_s = float(bin_s)
        self._bins = np.zeros(int(round(span_s / bin_s)), dtype=np.int64)
        self.count = 0
        self.total = 0.0
        self.maximum = float("-inf")
        self.over_span = 0
        for value in values:
            self.append(value)

    def append(self, seconds: float) -> None:
        """Count one latency (negative ones, from clock skew, count as zero)."""
        value = max(float(seconds), 0.0)
        index = int(value / self.bin_s)
        if index < len(self._bins):
            self._bins[index] += 1
        else:
            self.over_span += 1
        self.count += 1
        self.total += value
        self.maximum = max(self.maximum, value)

    def __len__(self) -> int:
        return self.count

    @property
    def mean(self) -> float | None:
        return self.total / self.count if self.count else None

    def percentile(self, q: float) -> float | None:
        """The q-th percentile (s), as numpy's linear one would give on the values, within
        half a bin; None without values. Values past the span read as the maximum."""
        if not self.count:
            return None
        rank = q / 100.0 * (self.count - 1)
        low, high = int(np.floor(rank)), int(np.ceil(rank))
        return self._value_at(low) + (rank - low) * (self._value_at(high) - self._value_at(low))

    def _value_at(self, rank: int) -> float:
        cumulative = np.cumsum(self._bins)
        index = int(np.searchsorted(cumulative, rank + 1))
        if index >= len(self._bins):
            return self.maximum
        return min((index + 0.5) * self.bin_s, self.maximum)
