"""What recording demonstrations costs the teleop session, recording on against off in the
same run.

Sessions of launch/teleop_sim.launch on one ~110 fps Leap recording alternate off, on, off,
on, ... (``--rounds`` pairs; alternating, because this shared machine's speed drifts by tens
of percent within minutes). "On" records every session as one LeRobot episode
(dataset:=<temp>, dataset_start:=true; with ``--camera`` also the simulated scene camera,
whose rendering is the simulation's, not the recording's). Per session:

- sensor -> driver latency p50 / p99 (the session's own summary, the server's traces);
- CPU seconds of the whole session: getrusage of every process it ran (the LeRobot writer
  and its torch import included), and by process from /proc every 0.2 s;
- steady CPU (cores) over a fixed window of the session (``--steady-from`` s after its
  start, ``--steady-s`` long: every start-up over, the recording still playing), by process.

"Extra CPU" is CPU seconds of the whole graph with recording over without, minus one, from
the medians of the rounds: for the whole session (the recorder's and the writer's one-off
start-up, torch imported once, and the episode's save included), and in the steady window
(what recording costs for every further second). The one-off part is also given in CPU
seconds, with the session length at which the whole session's extra CPU reaches the 5 %
goal. The default session is ~65 s (12 passes); a lab's recording session is longer.

Run: bench/run recording_cost [--rounds 2] [--recording test-paddle-rightwards] [--repeat 12] [--camera] [--fps 10]
Writes bench/results/recording_cost.json and bench/results/recording_cost.png (at another
``--fps``, recording_cost_fps<N>.json and .png).
"""

import argparse
import json
import os
import resource
import shutil
import tempfile
import threading
import time
from collections import deque

import numpy as np

from bench_common import RESULTS, teleop_session, write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
PORT = 11491
GOAL_CPU_PERCENT = 5.0


class ProcessSampler:
    """CPU seconds (user + sys, /proc/PID/stat) of every process under a session's roslaunch,
    by node: sampled every ``period`` s in a thread, each process's last sample kept, so a
    process that ends between two samples loses at most ``period`` s of its time (the
    session's total comes from getrusage, exact; this is its breakdown)."""

    def __init__(self, period: float = 0.2):
        self.period = period
        self.cpu = {}  # pid -> (label, cpu seconds)
        self.timeline = deque(maxlen=100_000)  # (monotonic s, {label: cpu s}) per sample
        self._stop = threading.Event()
        self._thread = None
        self._tick = os.sysconf("SC_CLK_TCK")

    def __call__(self, root_pid: int) -> None:
        self._thread = threading.Thread(target=self._run, args=(root_pid,), daemon=True)
        self._thread.start()

    def stop(self) -> dict:
        """CPU seconds by label (summed over the processes that bear it)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        out = {}
        for label, cpu in self.cpu.values():
            out[label] = round(out.get(label, 0.0) + cpu, 2)
        return dict(sorted(out.items(), key=lambda item: -item[1]))

    def _run(self, root_pid: int) -> None:
        while not self._stop.is_set():
            self._sample(root_pid)
            self._stop.wait(self.period)

    def _sample(self, root_pid: int) -> None:
        parents = {}
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                stat = self._stat(int(entry))
                if stat is not None:
                    parents[int(entry)] = stat
        tree = {root_pid}
        grew = True
        while grew:
            grew = False
            for pid, (ppid, _cpu) in parents.items():
                if pid not in tree and ppid in tree:
                    tree.add(pid)
                    grew = True
        for pid in tree:
            if pid in parents:
                label = self.cpu.get(pid, (None,))[0]
                if label is None or (label in ("roslaunch", "python3", "nice", "?") and pid != root_pid):
                    # A node seen between roslaunch's fork and its exec (or through `nice`)
                    # bears its parent's name: asked again until it bears its own.
                    label = self._label(pid)
                self.cpu[pid] = (label, parents[pid][1])
        totals = {}
        for label, cpu in self.cpu.values():
            totals[label] = totals.get(label, 0.0) + cpu
        self.timeline.append((time.monotonic(), totals))

    def steady(self, from_s: float, length_s: float) -> dict:
        """CPU cores by label from ``from_s`` after the first sample, over ``length_s``
        (empty when the session was shorter)."""
        if not self.timeline:
            return {}
        t0 = self.timeline[0][0] + from_s
        inside = [sample for sample in self.timeline if t0 <= sample[0] <= t0 + length_s]
        if len(inside) < 2 or inside[-1][0] - inside[0][0] < 0.8 * length_s:
            return {}
        (ta, a), (tb, b) = inside[0], inside[-1]
        rates = {label: round((cpu - a.get(label, 0.0)) / (tb - ta), 4) for label, cpu in b.items()}
        return dict(sorted(rates.items(), key=lambda item: -item[1]))

    def _stat(self, pid: int):
        try:
            with open(f"/proc/{pid}/stat", encoding="ascii") as stream:
                fields = stream.read().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            return None
        # after the command: state ppid ... utime (12th) stime (13th)
        return int(fields[1]), (int(fields[11]) + int(fields[12])) / self._tick

    @staticmethod
    def _label(pid: int) -> str:
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as stream:
                argv = stream.read().decode("utf-8", "replace").split("\0")
        except OSError:
            return "?"
        for arg in argv:
            if arg.startswith("__name:="):
                return arg.split(":=", 1)[1]
        for arg in argv:
            base = os.path.basename(arg)
            if base in ("rosmaster", "roslaunch", "lerobot_writer.py", "rosout"):
                return base
        return os.path.basename(argv[0]) if argv and argv[0] else "?"


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_session(recording: str, repeat: int, record: bool, camera: bool, window: tuple, fps: float = 10.0) -> dict:
    """One teleop session; its summary plus cpu_s and wall_s (and the episode, if recorded)."""
    out = tempfile.mkdtemp(prefix="rec-cost-")
    args = [f"recording:={os.path.join(ROOT, 'tests', 'data', recording + '.jsonl.gz')}", f"repeat:={repeat}"]
    dataset = os.path.join(out, "dataset")
    if record:
        args += [f"dataset:={dataset}", "dataset_start:=true", f"dataset_fps:={fps:g}"]
        if camera:
            args += ["dataset_camera:=scene"]
    sampler = ProcessSampler()
    cpu0, wall0 = _children_cpu(), time.monotonic()
    summary = teleop_session(
        PORT, out, args, timeout=900, what=f"the session (recording {'on' if record else 'off'})", watch=sampler
    )
    cpu, wall = _children_cpu() - cpu0, time.monotonic() - wall0
    by_process = sampler.stop()
    row = {
        "latency_p50_ms": summary["latency_p50_ms"],
        "latency_p99_ms": summary["latency_p99_ms"],
        "latency_samples": summary["latency_samples"],
        "cpu_s": round(cpu, 2),
        "wall_s": round(wall, 2),
        "cores": round(cpu / wall, 3),
        "cpu_s_by_process": by_process,
        "steady_cores_by_process": sampler.steady(*window),
    }
    row["steady_cores"] = round(sum(row["steady_cores_by_process"].values()), 4)
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
    for key, ax, label in (
        ("latency_p50_ms", axes[0], "sensor->driver p50 (ms)"),
        ("steady_cores", axes[1], "steady CPU (cores)"),
    ):
        x = np.arange(len(rounds))
        ax.bar(x - 0.2, [r["off"][key] for r in rounds], 0.4, label="recording off")
        ax.bar(x + 0.2, [r["on"][key] for r in rounds], 0.4, label="recording on")
        ax.set_xticks(x, [f"round {i + 1}" for i in x])
        ax.set_ylabel(label)
        ax.legend()
    fig.suptitle(
        f"recording cost ({results['recording']}, {results['repeat']} passes): p50 x{results['p50_ratio']}, "
        f"CPU +{results['extra_cpu_percent_steady']} % steady, +{results['extra_cpu_percent']} % whole session"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _median(rounds: list, side: str, key: str) -> float:
    return float(np.median([r[side][key] for r in rounds]))


def _median_by_process(rounds: list, side: str, key: str) -> dict:
    labels = sorted({label for r in rounds for label in r[side][key]})
    return {label: round(float(np.median([r[side][key].get(label, 0.0) for r in rounds])), 4) for label in labels}


def summarise(args, rounds: list, startup: float) -> dict:
    """The figures from the rounds' medians (see the module's docstring)."""
    median = {
        side: {
            k: _median(rounds, side, k) for k in ("latency_p50_ms", "latency_p99_ms", "cpu_s", "wall_s", "steady_cores")
        }
        for side in ("off", "on")
    }
    off, on = median["off"], median["on"]
    steady = {side: _median_by_process(rounds, side, "steady_cores_by_process") for side in ("off", "on")}
    total = {side: _median_by_process(rounds, side, "cpu_s_by_process") for side in ("off", "on")}
    extra_steady = 100 * (on["steady_cores"] / off["steady_cores"] - 1) if off["steady_cores"] else None
    extra_total = 100 * (on["cpu_s"] / off["cpu_s"] - 1)
    # The one-off part: what the whole session's extra is beyond the steady rate over its time.
    one_off = on["cpu_s"] - off["cpu_s"] * (1 + (extra_steady or 0) / 100)
    goal_s = None
    if extra_steady is not None and extra_steady < GOAL_CPU_PERCENT and off["steady_cores"]:
        goal_s = one_off / ((GOAL_CPU_PERCENT - extra_steady) / 100 * off["steady_cores"])
    return {
        "recording": args.recording,
        "repeat": args.repeat,
        "camera": args.camera,
        "steady_window_s": [args.steady_from, args.steady_from + args.steady_s],
        "rounds": rounds,
        "median": median,
        "steady_cores_by_process": steady,
        "cpu_s_by_process": total,
        "p50_ratio": round(on["latency_p50_ms"] / off["latency_p50_ms"], 3),
        "p99_ratio": round(on["latency_p99_ms"] / off["latency_p99_ms"], 3),
        "extra_cpu_percent": round(extra_total, 1),
        "extra_cpu_percent_steady": None if extra_steady is None else round(extra_steady, 1),
        "one_off_cpu_s": round(one_off, 2),
        "writer_startup_cpu_s": round(startup, 2),
        "session_s_for_goal": None if goal_s is None else round(goal_s, 0),
        "p50_spread_off_ms": [
            min(r["off"]["latency_p50_ms"] for r in rounds),
            max(r["off"]["latency_p50_ms"] for r in rounds),
        ],
        "goal_extra_cpu_percent": GOAL_CPU_PERCENT,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=2, help="off/on pairs (default 2)")
    parser.add_argument("--recording", default="test-paddle-rightwards", help="name in tests/data")
    parser.add_argument("--repeat", type=int, default=12, help="passes over the recording per session (~5.4 s each)")
    parser.add_argument("--camera", action="store_true", help="record the simulated scene camera too")
    parser.add_argument("--steady-from", type=float, default=20.0, help="steady window's start in a session (s)")
    parser.add_argument("--steady-s", type=float, default=30.0, help="steady window's length (s)")
    parser.add_argument("--fps", type=float, default=10.0, help="the episodes' frame rate (default 10)")
    args = parser.parse_args()
    name = "recording_cost" if args.fps == 10.0 else f"recording_cost_fps{args.fps:g}"
    window = (args.steady_from, args.steady_s)
    rounds = []
    for index in range(args.rounds):
        pair = {}
        for record in (False, True):
            label = "on" if record else "off"
            print(f"[round {index + 1}/{args.rounds}] recording {label}...", flush=True)
            pair[label] = run_session(args.recording, args.repeat, record, args.camera, window, args.fps)
            row = pair[label]
            print(
                f"    p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms, CPU {row['cpu_s']} s "
                f"over {row['wall_s']} s ({row['cores']} cores), steady {row['steady_cores']} cores"
                + (f", episode {row['episode_frames']} frames" if record else ""),
                flush=True,
            )
            if not row["steady_cores"]:
                raise SystemExit(f"sessions shorter than the steady window {window}: raise --repeat")
        rounds.append(pair)
    startup = writer_startup_cpu_s()
    print(f"LeRobot writer start-up alone: {startup:.1f} CPU s", flush=True)
    results = summarise(args, rounds, startup)
    results["fps"] = args.fps
    write_results(name, results, show=False)
    png = os.path.join(RESULTS, f"{name}.png")
    plot(results, png)
    median, steady = results["median"], results["steady_cores_by_process"]
    spread = results["p50_spread_off_ms"]
    print()
    print("=== recording cost summary ===")
    print(
        f"sensor->driver p50: off {median['off']['latency_p50_ms']:.3f} ms, on {median['on']['latency_p50_ms']:.3f} ms "
        f"(x{results['p50_ratio']}; off ranged {spread[0]}-{spread[1]} ms); "
        f"p99: off {median['off']['latency_p99_ms']:.3f} ms, on {median['on']['latency_p99_ms']:.3f} ms"
    )
    print(
        f"steady CPU ({args.steady_s:g} s from {args.steady_from:g} s): off {median['off']['steady_cores']:.3f} cores, "
        f"on {median['on']['steady_cores']:.3f}: +{results['extra_cpu_percent_steady']} % "
        f"(goal <= {GOAL_CPU_PERCENT:g} %)"
    )
    print(
        "  by process (on - off, cores): "
        + ", ".join(
            f"{label} {steady['on'].get(label, 0) - steady['off'].get(label, 0):+.4f}"
            for label in sorted(
                set(steady["on"]) | set(steady["off"]),
                key=lambda k: -abs(steady["on"].get(k, 0) - steady["off"].get(k, 0)),
            )[:8]
        )
    )
    print(
        f"whole session ({median['off']['wall_s']:.0f} s): off {median['off']['cpu_s']:.1f} CPU s, "
        f"on {median['on']['cpu_s']:.1f}: +{results['extra_cpu_percent']} %, of which one-off "
        f"{results['one_off_cpu_s']:.1f} CPU s a session (the writer's start-up alone {startup:.1f} s: torch and "
        f"LeRobot imported once)"
        + (
            f"; the whole session is within {GOAL_CPU_PERCENT:g} % from ~{results['session_s_for_goal']:.0f} s on"
            if results["session_s_for_goal"]
            else ""
        )
    )
    print(f"plot: {png}")


if __name__ == "__main__":
    main()
