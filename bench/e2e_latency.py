"""End-to-end latency of the teleop session against the transport floor, in the same run.

The session: launch/teleop_sim.launch replaying the ~110 fps Leap recordings, sensor stamp
to the driver accepting the command (the server's CommandTrace), per stage (sensor ->
sequencer -> core -> driver). The replay stamps each frame as it publishes it, so every
millisecond measured is added by the framework. Each recording is replayed in as many
passes (hand-absent pause between them) as give >= --min-commands commands.

The floor (bench/transport_floor.py): a bare rospy chain with the session's three hops and
message types doing no work, >= 1000 commands, in two forms: 'floor', the issue's (queued
publishers), and 'sync' (synchronous publishers, the session's own setting). This machine's
speed drifts by tens of percent within minutes (a shared host), so the floor is measured
right before AND right after every session and the session is compared with the mean of
the two: ratios, not absolute figures, are what compare.

--breakdown adds where the time goes: the floor variants that each add one ingredient of
the session (queueing, the 500 Hz simulator thread, the core's per-frame work, topic
instead of service), serialisation of each message type, and the cost of the core's
per-frame work right after ~9 ms idle (as in a 110 Hz stream) against a hot loop.

With --netns (needs root and `ip netns`), each recording is also played across two network
namespaces joined by a veth pair (scripts/two_machines.py: sensor side = device +
sequencer, robot side = master + core + driver, own ROS_IP each) and compared with its
same-machine figure of this run.

Run: bench/run e2e_latency [--recordings NAME ...] [--min-commands 1000] [--floor-count 1100]
                           [--breakdown] [--netns]
Writes bench/results/e2e_latency.json and bench/results/e2e_latency.png.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from bench_common import RESULTS, teleop_session, write_results
from transport_floor import VARIANTS, run_floor

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
DEFAULT = ["Waiting-110fps", "test-paddle-rightwards", "rollAndPitchCropped"]
PORT = 11478
# Frames of a pass that never become commands: the sequencer's entry trim (10) and the
# clutch's steady frames (10), with a margin.
UNSENT_PER_PASS = 25
GOAL = {"p50": 2.0, "p99": 3.0}


def recording_path(name):
    return os.path.join(ROOT, "tests", "data", name + ".jsonl.gz")


def passes_for(name, min_commands):
    """Passes over ``name`` that give at least ``min_commands`` commands."""
    from motion_sensor.devices.replay import load_samples

    samples, _ = load_samples(recording_path(name))
    per_pass = max(1, sum(1 for _, s in samples if s.hands_num) - UNSENT_PER_PASS)
    return max(1, math.ceil(min_commands / per_pass))


def run_session(recording, repeat=1):
    """Run one teleop session on ``recording`` (``repeat`` passes); return its summary dict."""
    args = [f"recording:={recording_path(recording)}", f"repeat:={repeat}"]
    return teleop_session(PORT, tempfile.mkdtemp(prefix="e2e-"), args, what=f"the session on {recording}")


class FloorMaster:
    """A roscore of its own (port PORT + 1) for the floor runs."""

    def __enter__(self):
        self.env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT + 1}")
        self.core = subprocess.Popen(
            ["roscore", "-p", str(PORT + 1)], env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        import rosgraph

        master = rosgraph.Master("/e2e_bench", master_uri=self.env["ROS_MASTER_URI"])
        for _ in range(300):
            try:
                master.getPid()
                break
            except Exception:  # not up yet
                time.sleep(0.1)
        return self

    def floor(self, count, variant="floor"):
        return run_floor(count, 110.0, self.env, variant)

    def __exit__(self, *exc):
        self.core.terminate()
        self.core.wait(timeout=30)


def measure_floors(master, count):
    """Both floors (the issue's queued one and the synchronous one), sensor->server figures."""
    figures = {}
    for variant in ("floor", "sync"):
        figures[variant] = master.floor(count, variant)["sensor->server"]
    print(
        f"    floor: p50={figures['floor']['p50']} ms p99={figures['floor']['p99']} ms; "
        f"sync floor: p50={figures['sync']['p50']} ms p99={figures['sync']['p99']} ms "
        f"(n={figures['floor']['n']} each)",
        flush=True,
    )
    return figures


def bracket(before, after, variant):
    """Mean of the floor figures measured before and after a session."""
    return {q: round((before[variant][q] + after[variant][q]) / 2.0, 3) for q in ("p50", "p99")}


def measure_netns(name, same_machine, repeat):
    """``name`` across two network namespaces; its figures and ratios to ``same_machine``."""
    import two_machines

    reason = two_machines.netns_unavailable()
    if reason:
        print(f"two machines (netns): skipped, {reason}", flush=True)
        return {"skipped": reason}
    print(f"two machines (netns) on {name}...", flush=True)
    summary = two_machines.run_monitored_session(
        recording_path(name), tempfile.mkdtemp(prefix="e2e-netns-"), repeat=repeat
    )
    row = {
        key: summary[key]
        for key in ("latency_p50_ms", "latency_p99_ms", "latency_samples", "frames_dropped", "stage_latency_ms")
    }
    row.update(
        recording=name,
        vs_same_machine_p50=round(summary["latency_p50_ms"] / same_machine["latency_p50_ms"], 2),
        vs_same_machine_p99=round(summary["latency_p99_ms"] / same_machine["latency_p99_ms"], 2),
    )
    print(
        f"    sensor->driver p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms, "
        f"stages {row['stage_latency_ms']}",
        flush=True,
    )
    print(
        f"    vs same machine: p50 x{row['vs_same_machine_p50']}, p99 x{row['vs_same_machine_p99']} "
        f"({row['latency_samples']} commands; frames dropped {row['frames_dropped']})",
        flush=True,
    )
    return row


def serialisation_costs(rounds=2000):
    """Serialise + deserialise each message of the chain: us per message, hot."""
    from io import BytesIO

    from geometry_msgs.msg import PoseStamped

    from motion_commander.msg import CommandTrace
    from motion_commander.srv import commanderRequest, commanderResponse
    from motion_sensor.msg import hand

    messages = {
        "hand": hand(hands_num=1, hand_type=["right"]),
        "PoseStamped": PoseStamped(),
        "commander request": commanderRequest(command_index=5, joints=[0.1] * 6),
        "commander response": commanderResponse(joints=[0.1] * 6, position=[0.1] * 3, orientation=[0.0] * 4),
        "CommandTrace": CommandTrace(),
    }
    costs = {}
    for name, msg in messages.items():
        buffer = BytesIO()
        start = time.perf_counter()
        for _ in range(rounds):
            buffer.seek(0)
            buffer.truncate()
            msg.serialize(buffer)
            type(msg)().deserialize(buffer.getvalue())
        costs[name] = round((time.perf_counter() - start) / rounds * 1e6, 1)
    return costs


def idle_wake_penalty(gap=0.009, lead=0.0015):
    """The core's per-frame cost (TeleopCore on a real recording): in a hot loop, and with
    ``gap`` s of idle before each frame as in a 110 Hz stream, its between-frames work
    (prepare_next) done either right after the command or ``lead`` s before the next frame
    (the node's default, teleop.yaml prepare_lead_s). The three run interleaved, frame by
    frame, so the machine's drift touches them alike: p50/p99 in us."""
    from transport_floor import _core, recorded_hands

    path = recorded_hands()
    variants = {
        "hot loop": None,
        f"after {gap * 1000:.0f} ms idle, prepared right after the command": 0.0,
        f"after {gap * 1000:.0f} ms idle, prepared {lead * 1000:g} ms before the frame": lead,
    }
    cores = {label: _core() for label in variants}
    costs = {label: [] for label in variants}
    stamp = 1000.0
    for position, orientation in path:
        stamp += 1.0 / 110.0
        for label, prepare_lead in variants.items():
            core = cores[label]
            if prepare_lead is None:
                core.prepare_next()
            elif prepare_lead:
                time.sleep(gap - prepare_lead)
                core.prepare_next()
                time.sleep(prepare_lead)
            else:
                time.sleep(gap)
            start = time.perf_counter()
            command = core.on_hand_pose(stamp, position, orientation)
            if command is not None:
                costs[label].append(time.perf_counter() - start)
                core.on_joint_state(command.joints)
                if prepare_lead == 0.0:
                    core.prepare_next()
    figures = {}
    for label, values in costs.items():
        us = np.asarray(values) * 1e6
        figures[label] = {
            "p50_us": round(float(np.percentile(us, 50)), 1),
            "p99_us": round(float(np.percentile(us, 99)), 1),
            "n": len(values),
        }
    return figures


GC_PROBE = """
import gc, json, time
import rospy
from motion_common.kinematics import RobotKinematics
from motion_commander.teleop_core import TeleopCore
from motion_commander.srv import commander
from motion_sensor.msg import hand
from hw_interface.controller_client import MotionControllerClient
from motion_common.startup_heap import freeze_startup_heap
RobotKinematics(URDF)

def full_collection_ms():
    samples = []
    for _ in range(5):
        start = time.perf_counter()
        gc.collect()
        samples.append(time.perf_counter() - start)
    return round(sorted(samples)[2] * 1000, 3)

before = full_collection_ms()
freeze_startup_heap()
print(json.dumps({"start-up objects": gc.get_freeze_count(), "full collection before": before,
                  "after freeze_startup_heap": full_collection_ms()}))
"""


def garbage_collector_pauses():
    """A full garbage collection's pause (ms, median of 5) in a fresh interpreter with the
    core node's imports and robot model, before and after freeze_startup_heap(). A long
    session runs into such collections as long-lived objects accumulate."""
    urdf = os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf")
    output = subprocess.run(
        [sys.executable, "-c", f"URDF = {urdf!r}\n" + GC_PROBE], check=True, capture_output=True, text=True
    ).stdout
    return json.loads(output.strip().splitlines()[-1])


def breakdown(master, count):
    """Floor variants (one ingredient each), serialisation and the idle-wake penalty."""
    rows = {}
    for variant in VARIANTS:
        print(f"breakdown: {variant} ({VARIANTS[variant]})...", flush=True)
        rows[variant] = master.floor(count, variant)
    sync = rows["sync"]["sensor->server"]
    table = {}
    for variant, hops in rows.items():
        server = hops["sensor->server"]
        base = rows["floor"]["sensor->server"] if variant == "sync" else sync
        table[variant] = {
            "what": VARIANTS[variant],
            "p50": server["p50"],
            "p99": server["p99"],
            "added_p50": None if variant in ("floor",) else round(server["p50"] - base["p50"], 3),
            "added_p99": None if variant in ("floor",) else round(server["p99"] - base["p99"], 3),
            "hops": hops,
        }
    return {
        "variants": table,
        "serialisation_us": serialisation_costs(),
        "core_idle_wake": idle_wake_penalty(),
        "gc_pause_ms": garbage_collector_pauses(),
    }


def print_breakdown(result):
    print("where the time goes (sensor->server, ms; 'added' is against the line it builds on):")
    for variant, row in result["variants"].items():
        added = "" if row["added_p50"] is None else f"  added p50 {row['added_p50']:+.3f}, p99 {row['added_p99']:+.3f}"
        print(f"  {variant:15s} p50 {row['p50']:.3f}  p99 {row['p99']:.3f}{added}   ({row['what']})")
    print(f"  serialise + deserialise, us per message (hot): {result['serialisation_us']}")
    idle = result["core_idle_wake"]
    print(f"  core per frame (TeleopCore), us: {idle}")
    print(f"  full garbage collection in the core's process, ms: {result['gc_pause_ms']}")


def plot(results, path):
    """Per recording: session p50/p99 against the bracketing floors; the breakdown bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n in results["sessions"]]
    panels = 2 if "breakdown" in results else 1
    fig, axes = plt.subplots(1, panels, figsize=(6.5 * panels, 4.5), squeeze=False)
    ax = axes[0][0]
    x = np.arange(len(names))
    for offset, (label, key, _floor_key) in enumerate(
        (("session", None, None), ("floor (queued)", "floor", None), ("floor (sync)", "sync_floor", None))
    ):
        p50 = [
            results["sessions"][n]["latency_p50_ms"] if key is None else results["sessions"][n][key]["p50"]
            for n in names
        ]
        p99 = [
            results["sessions"][n]["latency_p99_ms"] if key is None else results["sessions"][n][key]["p99"]
            for n in names
        ]
        bars = ax.bar(x + (offset - 1) * 0.27, p50, 0.25, label=f"{label} p50")
        ax.scatter(
            x + (offset - 1) * 0.27, p99, marker="_", s=300, color=bars.patches[0].get_facecolor(), label=f"{label} p99"
        )
    ax.set_xticks(x, [n.replace("-", "-\n", 1) for n in names], fontsize=8)
    ax.set_ylabel("sensor -> driver latency [ms]")
    ax.set_title("Teleop session against its transport floor (same run)")
    ax.legend(fontsize=7)
    if panels == 2:
        ax = axes[0][1]
        rows = results["breakdown"]["variants"]
        labels = list(rows)
        ax.barh(labels, [rows[v]["p50"] for v in labels], label="p50")
        ax.scatter([rows[v]["p99"] for v in labels], labels, marker="|", s=300, color="k", label="p99")
        ax.set_xlabel("sensor -> server [ms]")
        ax.set_title("Floor variants: one session ingredient each")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--recordings", nargs="+", default=DEFAULT, help="names in tests/data (without .jsonl.gz)")
    parser.add_argument(
        "--min-commands",
        type=int,
        default=1000,
        help="commands per session figure: the recording is replayed in passes until reached (default 1000)",
    )
    parser.add_argument("--floor-count", type=int, default=1100, help="commands through each floor run")
    parser.add_argument("--breakdown", action="store_true", help="also measure where the time goes (~1.5 min)")
    parser.add_argument(
        "--netns", action="store_true", help="also play each recording across two network namespaces (root)"
    )
    args = parser.parse_args()
    results = {"sessions": {}, "goal_vs_floor": GOAL}
    total = len(args.recordings)
    with FloorMaster() as master:
        print(f"floors ({args.floor_count} commands each at 110 Hz), before session 1...", flush=True)
        before = measure_floors(master, args.floor_count)
        results["floors"] = [before]
        for index, name in enumerate(args.recordings, start=1):
            repeat = passes_for(name, args.min_commands)
            print(f"[{index}/{total}] session on {name} ({repeat} passes)...", flush=True)
            summary = run_session(name, repeat)
            print(f"    floors after session {index}...", flush=True)
            after = measure_floors(master, args.floor_count)
            results["floors"].append(after)
            row = {
                key: summary[key]
                for key in (
                    "frames_in",
                    "frames_out",
                    "commands_sent",
                    "latency_p50_ms",
                    "latency_p99_ms",
                    "stage_latency_ms",
                    "tracking_error_rms_mm",
                    "frames_dropped",
                    "latency_samples",
                )
            }
            row["passes"] = repeat
            row["floor"], row["sync_floor"] = bracket(before, after, "floor"), bracket(before, after, "sync")
            for key, floor in (("vs_floor", row["floor"]), ("vs_sync_floor", row["sync_floor"])):
                row[key] = {q: round(summary[f"latency_{q}_ms"] / floor[q], 2) for q in ("p50", "p99")}
            results["sessions"][name] = row
            before = after
            print(
                f"    sensor->driver p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms, "
                f"stages {row['stage_latency_ms']}",
                flush=True,
            )
            print(
                f"    vs floor (mean of before/after): p50 x{row['vs_floor']['p50']}, p99 x{row['vs_floor']['p99']}; "
                f"vs sync floor: p50 x{row['vs_sync_floor']['p50']}, p99 x{row['vs_sync_floor']['p99']} "
                f"({row['latency_samples']} commands in {repeat} passes; frames dropped {row['frames_dropped']}, "
                f"{row['frames_dropped'] / repeat:.0f} per pass)",
                flush=True,
            )
            if row["latency_samples"] < args.min_commands:
                print(f"    note: only {row['latency_samples']} commands (< {args.min_commands})", flush=True)
        if args.breakdown:
            results["breakdown"] = breakdown(master, args.floor_count)
    if args.netns:
        results["netns"] = {
            name: measure_netns(name, results["sessions"][name], results["sessions"][name]["passes"])
            for name in args.recordings
        }
    sessions = results["sessions"].values()
    results["worst_vs_floor"] = {q: max(r["vs_floor"][q] for r in sessions) for q in ("p50", "p99")}
    results["worst_vs_sync_floor"] = {q: max(r["vs_sync_floor"][q] for r in sessions) for q in ("p50", "p99")}
    write_results("e2e_latency", results, show=False)
    png = os.path.join(RESULTS, "e2e_latency.png")
    plot(results, png)
    print()
    print("=== end-to-end latency summary ===")
    for name, row in results["sessions"].items():
        print(
            f"{name}: sensor->driver p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms "
            f"({row['latency_samples']} commands); floor: p50={row['floor']['p50']} p99={row['floor']['p99']}; "
            f"x{row['vs_floor']['p50']} / x{row['vs_floor']['p99']} (sync floor "
            f"x{row['vs_sync_floor']['p50']} / x{row['vs_sync_floor']['p99']})"
        )
    worst, worst_sync = results["worst_vs_floor"], results["worst_vs_sync_floor"]
    print(
        f"worst session vs floor: p50 x{worst['p50']}, p99 x{worst['p99']} (goal x{GOAL['p50']:g} / x{GOAL['p99']:g}); "
        f"vs sync floor: p50 x{worst_sync['p50']}, p99 x{worst_sync['p99']}"
    )
    if args.breakdown:
        print_breakdown(results["breakdown"])
    for name, row in results.get("netns", {}).items():
        if "skipped" not in row:
            print(
                f"two machines (netns), {name}: sensor->driver p50 {row['latency_p50_ms']} ms, "
                f"p99 {row['latency_p99_ms']} ms; vs same machine p50 x{row['vs_same_machine_p50']}, "
                f"p99 x{row['vs_same_machine_p99']}"
            )
    print(f"plot: {png}")


if __name__ == "__main__":
    main()
