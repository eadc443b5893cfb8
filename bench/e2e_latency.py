"""End-to-end latency of the teleop session: sensor stamp to the driver accepting the
command, per stage (sensor -> sequencer -> core -> driver), while replaying the ~110 fps
Leap recordings through launch/teleop_sim.launch. The replay stamps each frame as it
publishes it, so every millisecond measured is added by the framework.

Baseline in the same run: the transport floor (bench/transport_floor.py), a bare rospy
chain with the session's three hops and message types doing no work, >= 1000 commands.
Absolute figures move with the machine; the ratios to the floor are what compare.

With --netns (needs root and `ip netns`), each recording is also played across two
network namespaces joined by a veth pair (scripts/two_machines.py: sensor side = device +
sequencer, robot side = master + core + driver, own ROS_IP each) and compared with its
same-machine figure of this run.

Run: bench/run e2e_latency [--recordings NAME ...] [--floor-count 1100] [--netns]
Writes bench/results/e2e_latency.json.
"""
import argparse
import json
import os
import subprocess
import tempfile
import sys
import time

from bench_common import write_results
from transport_floor import run_floor

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
DEFAULT = ["Waiting-110fps", "test-paddle-rightwards", "rollAndPitchCropped"]
PORT = 11478


def run_session(recording):
    """Run one teleop session on ``recording``; return its summary dict."""
    out = tempfile.mkdtemp(prefix="e2e-")
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT}")
    cmd = ["roslaunch", "-p", str(PORT), os.path.join(ROOT, "launch", "teleop_sim.launch"),
           f"recording:={os.path.join(ROOT, 'tests', 'data', recording + '.jsonl.gz')}", f"output_dir:={out}"]
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=180, check=False)
    with open(os.path.join(out, "session_summary.json"), encoding="utf-8") as fh:
        return json.load(fh)


def measure_floor(count):
    """The transport floor on its own master (port PORT + 1); per-hop figures."""
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT + 1}")
    core = subprocess.Popen(["roscore", "-p", str(PORT + 1)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        import rosgraph
        master = rosgraph.Master("/e2e_bench", master_uri=env["ROS_MASTER_URI"])
        for _ in range(200):
            try:
                master.getPid()
                break
            except Exception:  # not up yet
                time.sleep(0.1)
        return run_floor(count, 110.0, env)
    finally:
        core.terminate()
        core.wait(timeout=30)


def measure_netns(name, same_machine):
    """``name`` across two network namespaces; its figures and ratios to ``same_machine``."""
    import two_machines
    reason = two_machines.netns_unavailable()
    if reason:
        print(f"two machines (netns): skipped, {reason}", flush=True)
        return {"skipped": reason}
    print(f"two machines (netns) on {name}...", flush=True)
    summary = two_machines.run_monitored_session(os.path.join(ROOT, "tests", "data", name + ".jsonl.gz"),
                                                 tempfile.mkdtemp(prefix="e2e-netns-"))
    row = {key: summary[key] for key in ("latency_p50_ms", "latency_p99_ms", "latency_samples", "frames_dropped",
                                         "stage_latency_ms")}
    row.update(recording=name, vs_same_machine_p50=round(summary["latency_p50_ms"] / same_machine["latency_p50_ms"], 2),
               vs_same_machine_p99=round(summary["latency_p99_ms"] / same_machine["latency_p99_ms"], 2))
    print(f"    sensor->driver p50 {row['latency_p50_ms']} ms, p99 {row['latency_p99_ms']} ms, "
          f"stages {row['stage_latency_ms']}", flush=True)
    print(f"    vs same machine: p50 x{row['vs_same_machine_p50']}, p99 x{row['vs_same_machine_p99']} "
          f"({row['latency_samples']} commands; frames dropped {row['frames_dropped']})", flush=True)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--recordings", nargs="+", default=DEFAULT, help="names in tests/data (without .jsonl.gz)")
    parser.add_argument("--floor-count", type=int, default=1100, help="commands through the transport floor")
    parser.add_argument("--netns", action="store_true",
                        help="also play each recording across two network namespaces (root)")
    args = parser.parse_args()
    print(f"transport floor ({args.floor_count} commands at 110 Hz)...", flush=True)
    floor_hops = measure_floor(args.floor_count)
    floor = floor_hops["sensor->server"]
    print(f"    floor: p50={floor['p50']} ms p99={floor['p99']} ms (n={floor['n']})", flush=True)
    print(f"    floor hops: {floor_hops}", flush=True)
    results = {}
    for index, name in enumerate(args.recordings, start=1):
        print(f"[{index}/{len(args.recordings)}] session on {name}...", flush=True)
        summary = run_session(name)
        results[name] = {key: summary[key] for key in ("frames_in", "frames_out", "commands_sent", "latency_p50_ms",
                                                        "latency_p99_ms", "stage_latency_ms",
                                                        "tracking_error_rms_mm", "frames_dropped", "latency_samples")}
        ratio_p50 = round(summary["latency_p50_ms"] / floor["p50"], 2)
        ratio_p99 = round(summary["latency_p99_ms"] / floor["p99"], 2)
        results[name].update(vs_floor_p50=ratio_p50, vs_floor_p99=ratio_p99)
        print(f"    sensor->driver p50 {summary['latency_p50_ms']} ms, p99 {summary['latency_p99_ms']} ms, "
              f"stages {summary['stage_latency_ms']}", flush=True)
        print(f"    vs floor: p50 x{ratio_p50}, p99 x{ratio_p99} ({summary['latency_samples']} commands; "
              f"frames dropped {summary['frames_dropped']})", flush=True)
    if args.netns:
        results["netns"] = {name: measure_netns(name, results[name]) for name in args.recordings}
    sessions = [r for name, r in results.items() if name != "netns"]
    worst_p50 = max(r["vs_floor_p50"] for r in sessions)
    worst_p99 = max(r["vs_floor_p99"] for r in sessions)
    results["floor"] = floor_hops
    results["worst_vs_floor"] = {"p50": worst_p50, "p99": worst_p99, "goal_p50": 2.0, "goal_p99": 3.0}
    write_results("e2e_latency", results, show=False)
    print(f"floor: p50={floor['p50']} ms p99={floor['p99']} ms; worst session vs floor: p50 x{worst_p50}, "
          f"p99 x{worst_p99} (goal x2 / x3)")
    for name, row in results.get("netns", {}).items():
        if "skipped" not in row:
            print(f"two machines (netns), {name}: sensor->driver p50 {row['latency_p50_ms']} ms, "
                  f"p99 {row['latency_p99_ms']} ms; vs same machine p50 x{row['vs_same_machine_p50']}, "
                  f"p99 x{row['vs_same_machine_p99']}")


if __name__ == "__main__":
    main()
