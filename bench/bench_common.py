"""Shared by the benchmark scripts: where results go and how they are written, and one
teleop session run for its summary."""

import json
import os
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
RESULTS = os.path.join(ROOT, "bench", "results")
sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))

from motion_common.atomic_file import write_atomic  # noqa: E402


def write_results(name: str, results: dict, show: bool = True) -> str:
    """Write ``results`` to bench/results/NAME.json, print them, and return the path."""
    # Atomically: an interrupted run leaves the last good results as they were.
    path = write_atomic(os.path.join(RESULTS, f"{name}.json"), json.dumps(results, indent=2) + "\n")
    if show:
        print(json.dumps(results, indent=2))
    print(f"written to {path}")
    return path


def teleop_session(port: int, out: str, args, timeout: float = 600.0, what: str = "the session", watch=None) -> dict:
    """Run launch/teleop_sim.launch on its own master (``port``) with ``args`` (name:=value,
    output_dir:=``out`` added) until it ends; return its session_summary.json. ``watch``,
    if given, is called with roslaunch's pid once it runs (e.g. to sample its processes)."""
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{port}")
    launch = os.path.join(ROOT, "src", "motion_bringup", "launch", "teleop_sim.launch")
    cmd = ["roslaunch", "-p", str(port), launch, f"output_dir:={out}", *args]
    with subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) as proc:
        if watch is not None:
            watch(proc.pid)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    path = os.path.join(out, "session_summary.json")
    if not os.path.exists(path):
        raise RuntimeError(f"{what} wrote no summary; run scripts/teleop_sim {' '.join(args)} to see why")
    with open(path, encoding="utf-8") as stream:
        return json.load(stream)
