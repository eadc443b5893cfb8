"""Core benchmarks: IK per teleop step (warm start against a cold-start baseline) on
reachable continuous paths for every shipped robot, and the core's cost per frame
(TeleopCore.on_hand_pose with teleop.yaml: mapping, IK, all safety rules) on real Leap recordings, against
IK alone as baseline. Pure Python, no ROS.

Run: bench/run core_bench [--paths 20]
Writes bench/results/core_bench.json and bench/results/core_bench.png.
"""

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
for package in ("motion_sensor", "motion_commander"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))

from bench_common import RESULTS, write_results  # noqa: E402
from motion_commander.config import load_teleop_config  # noqa: E402
from motion_commander.teleop import TeleopMapper, make_clutch  # noqa: E402
from motion_commander.teleop_core import TeleopCore  # noqa: E402
from motion_common.kinematics import RobotKinematics  # noqa: E402
from motion_sensor.devices.leap_v6 import frame_to_sample, read_recording  # noqa: E402
from motion_sensor.sequencing.sequencer import Sequencer  # noqa: E402

HOMES = {
    "ur5e": [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
    "ur10e": [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
    "tx90": [0.0, 0.4, 1.6, 0.0, 1.14, 0.0],
}
RECORDINGS = ["Waiting-110fps", "test-paddle-rightwards", "rollAndPitchCropped", "flapping", "wave"]


def stats(samples):
    """p50/p99 in microseconds."""
    us = np.asarray(samples) * 1e6
    return {
        "p50_us": round(float(np.percentile(us, 50)), 1),
        "p99_us": round(float(np.percentile(us, 99)), 1),
        "n": int(len(us)),
    }


def ik_benchmark(robot, paths, rng):
    """Warm-started IK along smooth joint-space paths (reachable by construction)."""
    kin = RobotKinematics(os.path.join(ROOT, "src", "motion_common", "urdf", f"{robot}.urdf"))
    home = np.array(HOMES[robot])
    warm, cold, successes, steps = [], [], 0, 0
    for _ in range(paths):
        # 2 s at 110 Hz of a smooth random joint motion of up to +-0.4 rad.
        t = np.linspace(0, 2, 220)[:, None]
        amplitude, frequency, phase = rng.uniform(-0.4, 0.4, 6), rng.uniform(0.2, 1.0, 6), rng.uniform(0, 6.3, 6)
        path = home + amplitude * np.sin(2 * np.pi * frequency * t + phase) - amplitude * np.sin(phase)
        targets = [kin.forward(q) for q in path]
        q = path[0].copy()
        for target in targets:
            start = time.perf_counter()
            result = kin.solve_ik(target, q)
            warm.append(time.perf_counter() - start)
            successes += result.success
            steps += 1
            q = result.joints
        for target in targets[::10]:
            start = time.perf_counter()
            kin.solve_ik(target, home)
            cold.append(time.perf_counter() - start)
    return {
        "warm": stats(warm),
        "cold_baseline": stats(cold),
        "success_rate": successes / steps,
        "steps": steps,
        "cold_over_warm_p50": round(float(np.median(cold) / np.median(warm)), 2),
    }, warm


def core_benchmark():
    """TeleopCore.on_hand_pose per frame on the sequenced real recordings (UR5e)."""
    kin = RobotKinematics(os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf"))
    import yaml

    with open(os.path.join(ROOT, "src", "motion_commander", "config", "teleop.yaml"), encoding="utf-8") as fh:
        config = load_teleop_config(yaml.safe_load(fh))
    per_frame, ik_only = [], []
    for name in RECORDINGS:
        recording = read_recording(os.path.join(ROOT, "tests", "data", f"{name}.jsonl.gz"))
        # The session's own configuration (teleop.yaml: speed ratio, limits, acceleration).
        core = TeleopCore(
            kin,
            TeleopMapper(config.speed_ratio),
            make_clutch(config.engage, config.steady_frames, config.lost_after),
            config.safety,
        )
        core.on_joint_state(HOMES["ur5e"])
        sequencer = Sequencer()
        for frame in recording.frames:
            sample = frame_to_sample(frame, frame.timestamp)
            pose = sequencer.process(sample, now=frame.timestamp)
            if pose is None:
                continue
            start = time.perf_counter()
            command = core.on_hand_pose(pose.stamp, pose.position, pose.orientation)
            elapsed = time.perf_counter() - start
            if command is not None:
                core.prepare_next()  # as the node does, once the command is out (not timed)
                per_frame.append(elapsed)
                start = time.perf_counter()
                kin.solve_ik(kin.forward(command.joints), command.joints)
                ik_only.append(time.perf_counter() - start)
    return {
        "per_frame": stats(per_frame),
        "ik_only_baseline": stats(ik_only),
        "per_frame_over_ik_p50": round(float(np.median(per_frame) / np.median(ik_only)), 2),
        "recordings": RECORDINGS,
    }, per_frame


def plot(ik_samples, core_samples, path):
    """Histogram of per-step costs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    bins = np.logspace(np.log10(5), np.log10(2000), 60)
    for label, samples in list(ik_samples.items()) + [("TeleopCore per frame (ur5e)", core_samples)]:
        ax.hist(np.asarray(samples) * 1e6, bins=bins, histtype="step", lw=1.5, label=label)
    ax.axvline(50, color="k", ls="--", lw=1, label="IK goal: median 50 us")
    ax.set_xscale("log")
    ax.set_xlabel("time per step [us]")
    ax.set_ylabel("steps")
    ax.set_title("Core cost per step (warm-started IK, full core)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--paths", type=int, default=20, help="random continuous paths per robot (default 20)")
    args = parser.parse_args()
    rng = np.random.default_rng(7)
    results, ik_samples = {"ik": {}}, {}
    for robot in HOMES:
        print(f"IK on {args.paths} continuous paths: {robot}...", flush=True)
        results["ik"][robot], ik_samples[f"IK warm ({robot})"] = ik_benchmark(robot, args.paths, rng)
    print("core cost per frame on real recordings...", flush=True)
    results["core"], core_samples = core_benchmark()
    write_results("core_bench", results)
    plot(ik_samples, core_samples, os.path.join(RESULTS, "core_bench.png"))
    print(f"plot: {os.path.join(RESULTS, 'core_bench.png')}")


if __name__ == "__main__":
    main()
