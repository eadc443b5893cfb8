"""Sequencer cost per frame at 1 kHz input, per filter: a real recording's palm path
resampled to 1 kHz with irregular gaps, through Sequencer.process (validation, binding,
timing, trims, jump gate, filter, continuity). Baseline: the filter's update alone.

Run: bench/run sequencer_bench
Writes bench/results/sequencer_bench.json.
"""

import os
import sys
import time

import numpy as np

from bench_common import write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_sensor"))

from motion_sensor.devices.leap_v6 import read_recording, select_primary  # noqa: E402
from motion_sensor.hand_sample import HandSample  # noqa: E402
from motion_sensor.sequencing.filters import make_filter  # noqa: E402
from motion_sensor.sequencing.sequencer import Sequencer, SequencerConfig  # noqa: E402


def stream_1khz(seconds=5.0):
    """(stamps, positions, quaternions) at ~1 kHz from the paddle recording."""
    recording = read_recording(os.path.join(ROOT, "tests", "data", "test-paddle-rightwards.jsonl.gz"))
    t = np.array([f.timestamp for f in recording.frames])
    p = np.array([select_primary(f).position for f in recording.frames])
    q = np.array([select_primary(f).orientation for f in recording.frames])
    rng = np.random.default_rng(3)
    stamps = 100.0 + np.cumsum(rng.uniform(0.0008, 0.0012, int(seconds * 1000)))
    u = t[0] + (stamps - stamps[0]) % (t[-1] - t[0])
    positions = np.column_stack([np.interp(u, t, p[:, i]) for i in range(3)])
    index = np.searchsorted(t, u).clip(0, len(t) - 1)
    return stamps, positions, q[index]


def percentiles(samples):
    us = np.asarray(samples) * 1e6
    return {"p50_us": round(float(np.percentile(us, 50)), 2), "p99_us": round(float(np.percentile(us, 99)), 2)}


def main():
    stamps, positions, quats = stream_1khz()
    samples = [HandSample(stamp=s, position=p, orientation=q) for s, p, q in zip(stamps, positions, quats)]
    results = {"frames": len(samples), "input_rate_hz": round(float(1 / np.median(np.diff(stamps))), 1)}
    for name in ("mean", "one_euro", "kalman"):
        sequencer = Sequencer(SequencerConfig(filter_name=name))
        costs = []
        for sample in samples:
            start = time.perf_counter()
            sequencer.process(sample, now=sample.stamp + 0.0005)
            costs.append(time.perf_counter() - start)
        bare = make_filter(name)
        filter_costs = []
        for sample in samples:
            start = time.perf_counter()
            bare.update(sample.stamp, sample.position, sample.orientation)
            filter_costs.append(time.perf_counter() - start)
        results[name] = {
            "sequencer": percentiles(costs),
            "filter_only_baseline": percentiles(filter_costs),
            "frames_out": sequencer.counters["frames_out"],
            "dropped": sequencer.dropped,
            "budget_used_at_1khz_p99": round(float(np.percentile(costs, 99)) / 0.001, 3),
        }
        print(
            f"{name:9s} sequencer p50 {results[name]['sequencer']['p50_us']} us, "
            f"p99 {results[name]['sequencer']['p99_us']} us (filter alone p50 "
            f"{results[name]['filter_only_baseline']['p50_us']} us)",
            flush=True,
        )
    write_results("sequencer_bench", results, show=False)


if __name__ == "__main__":
    main()
