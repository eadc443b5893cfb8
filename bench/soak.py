"""Soak: every node of a looping teleop session keeps flat memory.

Runs teleop_sim.launch (a real Leap recording in a loop, the session monitor on) under a
master of its own for --minutes, samples each node's resident memory (VmRSS, through the
master's node list and each node's getPid) every --period seconds, and fits a straight line
to each node's RSS after a warm-up (--warmup minutes: imports, caches, the first pybullet
frames). A node passes when its slope is within --max-slope MB per hour: the per-frame
pinocchio.Quaternion(matrix) leak grew the core by ~55 MB/h, the monitor's unbounded sample
lists by ~360 MB/h.

Run: bench/run soak [--minutes 10] [--period 5] [--warmup 2] [--max-slope 5]
Writes bench/results/soak.json and bench/results/soak.png.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

import numpy as np

from bench_common import RESULTS, ROOT, write_results

PORT = 11471


def rss_mb(pid: int) -> float | None:
    """Resident memory of a process (MB), None when it is gone."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def node_pids(master) -> dict:
    """{node name: pid} of every node the master knows, this script's own excepted."""
    pids = {}
    publishers, subscribers, services = master.getSystemState()
    names = {n for _, nodes in publishers + subscribers + services for n in nodes}
    for name in sorted(names - {"/soak_bench", "/rosout"}):
        try:
            api = master.lookupNode(name)
            pids[name] = int(xmlrpc.client.ServerProxy(api).getPid("/soak_bench")[2])
        except Exception:  # noqa: BLE001 - a node that just left
            continue
    return pids


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="length of the soak (default 10)")
    parser.add_argument("--period", type=float, default=5.0, help="s between RSS samples (default 5)")
    parser.add_argument("--warmup", type=float, default=2.0, help="minutes left out of the fit (default 2)")
    parser.add_argument("--max-slope", type=float, default=5.0, help="MB per hour allowed per node (default 5)")
    args = parser.parse_args(argv)
    if not args.minutes > args.warmup >= 0 or not args.period > 0:
        parser.error("need --minutes > --warmup >= 0 and --period > 0")
    import rosgraph

    out = tempfile.mkdtemp(prefix="soak-")
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT}")
    launch = subprocess.Popen(
        [
            "roslaunch",
            "-p",
            str(PORT),
            os.path.join(ROOT, "src", "motion_bringup", "launch", "teleop_sim.launch"),
            "loop:=true",
            "exit_when_done:=false",
            f"output_dir:={out}",
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    master = rosgraph.Master("/soak_bench", master_uri=env["ROS_MASTER_URI"])
    samples = {}  # node -> [(minutes, MB)]
    start = time.monotonic()
    try:
        while (elapsed := time.monotonic() - start) < args.minutes * 60:
            try:
                pids = node_pids(master)
            except Exception:  # noqa: BLE001 - the master is not up yet
                pids = {}
            for name, pid in pids.items():
                value = rss_mb(pid)
                if value is not None:
                    samples.setdefault(name, []).append((elapsed / 60.0, value))
            done = elapsed / 60.0
            print(f"\r{done:5.1f} / {args.minutes:g} min, {len(pids)} nodes", end="", flush=True)
            time.sleep(args.period)
    finally:
        launch.terminate()
        try:
            launch.wait(30)
        except subprocess.TimeoutExpired:
            launch.kill()
    print()
    results = {"minutes": args.minutes, "warmup_minutes": args.warmup, "max_slope_mb_per_hour": args.max_slope}
    nodes = {}
    for name, rows in sorted(samples.items()):
        data = np.array([r for r in rows if r[0] >= args.warmup])
        if len(data) < 3:
            continue
        slope = float(np.polyfit(data[:, 0], data[:, 1], 1)[0]) * 60.0  # MB per hour
        nodes[name] = {
            "rss_start_mb": round(float(data[0, 1]), 1),
            "rss_end_mb": round(float(data[-1, 1]), 1),
            "slope_mb_per_hour": round(slope, 2),
            "flat": slope <= args.max_slope,
        }
    results["nodes"] = nodes
    results["all_flat"] = bool(nodes) and all(n["flat"] for n in nodes.values())
    write_results("soak", results, show=False)
    for name, figures in nodes.items():
        print(
            f"{name:28s} RSS {figures['rss_start_mb']:7.1f} -> {figures['rss_end_mb']:7.1f} MB, "
            f"slope {figures['slope_mb_per_hour']:+7.2f} MB/h {'ok' if figures['flat'] else 'GROWS'}"
        )
    plot(samples, args.warmup, os.path.join(RESULTS, "soak.png"))
    print(f"all nodes flat within {args.max_slope:g} MB/h: {results['all_flat']}")
    return 0 if results["all_flat"] else 1


def plot(samples, warmup, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    for name, rows in sorted(samples.items()):
        data = np.array(rows)
        ax.plot(data[:, 0], data[:, 1] - data[0, 1], label=name)
    ax.axvline(warmup, color="grey", linestyle=":", label="end of warm-up")
    ax.set_xlabel("minutes")
    ax.set_ylabel("RSS change since start (MB)")
    ax.set_title("Soak: resident memory of every node, looping teleop session")
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"plot: {path}")


if __name__ == "__main__":
    sys.exit(main())
