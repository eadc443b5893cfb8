"""What recording demonstrations costs the teleop session, recording on against off in the
same run.

Sessions of launch/teleop_sim.launch on one ~110 fps Leap recording alternate off, on, off,
on, ... (``--rounds`` pairs; alternating, because this shared machine's speed drifts by tens
of percent within minutes). "On" records every session as one LeRobot episode
(dataset:=<temp>, dataset_start:=true; with ``--camera`` also the simulated scene camera,
whose rendering is the simulation's, not the recording's). Per session:

- sensor -> driver latency p50 / p99 (the session's own summary, the server's traces);
- CPU seconds of the whole session (getrusage of every process it ran, the LeRobot writer
  and its torch import included) over its wall time.

Printed and written: the p50 ratio on/off, and the extra CPU of recording as a percentage
of the session's CPU (goal <= 5 %), both from the medians of the rounds.

Run: bench/run recording_cost [--rounds 3] [--recording test-paddle-rightwards] [--repeat 2] [--camera]
Writes bench/results/recording_cost.json and bench/results/recording_cost.png.
"""

import argparse
import json
import os
import resource
import shutil
import tempfile
import time

import numpy as np

from bench_common import RESULTS, teleop_session, write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
PORT = 11491
GOAL_CPU_PERCENT = 5.0


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_session(recording: str, repeat: int, record: bool, camera: bool) -> dict:
    """One teleop session; its summary plus cpu_s and wall_s (and the episode, if recorded)."""
    out = tempfile.mkdtemp(prefix="rec-cost-")
    args = [f"recording:={os.path.join(ROOT, 'tests', 'data', recording + '.jsonl.gz')}", f"repeat:={repeat}"]
    dataset = os.path.join(out, "dataset")
    if record:
        args += [f"dataset:={dataset}", "dataset_start:=true"]
        if camera:
            args += ["dataset_camera:=scene"]
    cpu0, wall0 = _children_cpu(), time.monotonic()
    summary = teleop_session(PORT, out, args, timeout=900, what=f"the session (recording {'on' if record else 'off'})")
    cpu, wall = _children_cpu() - cpu0, time.monotonic() - wall0
    row = {
        "latency_p50_ms": summary["latency_p50_ms"],
        "latency_p99_ms": summary["latency_p99_ms"],
        "latency_samples": summary["latency_samples"],
        "cpu_s": round(cpu, 2),
        "wall_s": round(wall, 2),
        "cores": round(cpu / wall, 3),
    }
    if record:
        episodes_file = os.path.join(dataset, "meta", "teleop_episodes.json")
        if os.path.exists(episodes_file):
            with open(episodes_file, encoding="utf-8") as stream:
                episode = json.load(stream)[-1]
            row["episode_frames"] = episode["frames"]
            row["dropped_frames"] = episode["dropped_frames"]
        else:
            row["episode_frames"] = 0  # the session ended before the episode was saved
    shutil.rmtree(out, ignore_errors=True)
    return row


def writer_startup_cpu_s() -> float:
    """CPU seconds of the LeRobot writer process's start-up alone (its torch and LeRobot
    import), paid once per session whatever its length: started and ended with no episode."""
    import sys  # noqa: PLC0415

    sys.path.insert(0, os.path.join(ROOT, "src", "motion_apps"))
    from motion_apps.episode_writer_client import EpisodeWriterClient  # noqa: PLC0415

    cpu0 = _children_cpu()
    client = EpisodeWriterClient()
    client.close(timeout_s=120)
    return _children_cpu() - cpu0


def plot(results: dict, path: str) -> None:
    import matplotlib.pyplot as plt  # noqa: PLC0415

    rounds = results["rounds"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for key, ax, label in (("latency_p50_ms", axes[0], "sensor->driver p50 (ms)"), ("cores", axes[1], "CPU (cores)")):
        x = np.arange(len(rounds))
        ax.bar(x - 0.2, [r["off"][key] for r in rounds], 0.4, label="recording off")
        ax.bar(x + 0.2, [r["on"][key] for r in rounds], 0.4, label="recording on")
        ax.set_xticks(x, [f"round {i + 1}" for i in x])
        ax.set_ylabel(label)
        ax.legend()
    fig.suptitle(
        f"recording cost ({results['recording']}, {results['repeat']} passes): p50 x{results['p50_ratio']}, "
        f"CPU +{results['extra_cpu_percent']} %"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3, help="off/on pairs (default 3)")
    parser.add_argument("--recording", default="test-paddle-rightwards", help="name in tests/data")
    parser.add_argument("--repeat", type=int, default=2, help="passes over the recording per session")
    parser.add_argument("--camera", action="store_true", help="record the simulated scene camera too")
    args = parser.parse_args()
    rounds = []
    for index in range(args.rounds):
        pair = {}
        for record in (False, True):
            label = "on" if record else "off"
            print(f"[round {index + 1}/{args.rounds}] recording {label}...", flush=True)
            pair[label] = run_session(args.recording, args.repeat, record, args.camera)
            row = pair[label]
            print(
                f"    p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms, CPU {row['cpu_s']} s "
                f"over {row['wall_s']} s ({row['cores']} cores)"
                + (f", episode {row['episode_frames']} frames" if record else ""),
                flush=True,
            )
        rounds.append(pair)
    startup = writer_startup_cpu_s()
    print(f"LeRobot writer start-up alone: {startup:.1f} CPU s", flush=True)
    median = {
        side: {k: float(np.median([r[side][k] for r in rounds])) for k in ("latency_p50_ms", "latency_p99_ms", "cpu_s")}
        for side in ("off", "on")
    }
    results = {
        "recording": args.recording,
        "repeat": args.repeat,
        "camera": args.camera,
        "rounds": rounds,
        "median": median,
        "p50_ratio": round(median["on"]["latency_p50_ms"] / median["off"]["latency_p50_ms"], 3),
        "p99_ratio": round(median["on"]["latency_p99_ms"] / median["off"]["latency_p99_ms"], 3),
        "extra_cpu_percent": round(100 * (median["on"]["cpu_s"] / median["off"]["cpu_s"] - 1), 1),
        "writer_startup_cpu_s": round(startup, 2),
        "extra_cpu_percent_after_startup": round(
            100 * (median["on"]["cpu_s"] - startup - median["off"]["cpu_s"]) / median["off"]["cpu_s"], 1
        ),
        "p50_spread_off_ms": [
            min(r["off"]["latency_p50_ms"] for r in rounds),
            max(r["off"]["latency_p50_ms"] for r in rounds),
        ],
        "goal_extra_cpu_percent": GOAL_CPU_PERCENT,
    }
    write_results("recording_cost", results, show=False)
    png = os.path.join(RESULTS, "recording_cost.png")
    plot(results, png)
    print()
    print("=== recording cost summary ===")
    print(
        f"sensor->driver p50: off {median['off']['latency_p50_ms']:.3f} ms, on {median['on']['latency_p50_ms']:.3f} ms "
        f"(x{results['p50_ratio']}; off ranged {results['p50_spread_off_ms'][0]}-{results['p50_spread_off_ms'][1]} ms)"
    )
    print(
        f"CPU per session: off {median['off']['cpu_s']:.1f} s, on {median['on']['cpu_s']:.1f} s: "
        f"+{results['extra_cpu_percent']} % (goal <= {GOAL_CPU_PERCENT:g} %); without the writer's one-off "
        f"start-up ({startup:.1f} s, torch and LeRobot imported once per session): "
        f"+{results['extra_cpu_percent_after_startup']} %"
    )
    print(f"plot: {png}")


if __name__ == "__main__":
    main()
