"""Hardware-layer benchmarks: simulator real-time factor, commander.srv round trip with the
persistent client (baseline: a fresh connection per call), and streaming SetJoints at
500 Hz through motion_controller_server to a driver: the pybullet simulation (default), or
the simple_message driver on its byte-level simulated controller (TX90), or the UR driver
on its fake controller.

Run: bench/run hw_bench [--driver pybullet|simple_message_fake|ur_rtde_fake] [--stream-seconds 10] [--calls 2000]
Writes bench/results/hw_bench.json (pybullet) or hw_bench_<driver>.json.
"""

import argparse
import os
import subprocess
import sys
import time

import numpy as np
import yaml

from bench_common import write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
PORT = 11477  # a master of its own, so a running session is never disturbed
LAUNCH = os.path.join(ROOT, "src", "motion_bringup", "launch")
# Driver -> (launch file and arguments, the robot that launch file drives by default).
DRIVERS = {
    "pybullet": (["hw_sim.launch"], "ur5e"),
    "simple_message_fake": (["hw_industrial.launch", "fake_controller:=true"], "tx90"),
    "ur_rtde_fake": (["hw_ur.launch", "fake_controller:=true"], "ur5e"),
}


def start_pose(robot):
    """The robot's shipped start pose (motion_common/config/robots/<robot>.yaml), rad."""
    with open(os.path.join(ROOT, "src", "motion_common", "config", "robots", f"{robot}.yaml"), encoding="utf-8") as fh:
        return np.array(yaml.safe_load(fh)["initial_joints"], dtype=float)


HOME = start_pose("ur5e")


def percentiles(samples_s):
    """p50/p99/max in microseconds."""
    us = np.asarray(samples_s) * 1e6
    return {
        "p50_us": round(float(np.percentile(us, 50)), 1),
        "p99_us": round(float(np.percentile(us, 99)), 1),
        "max_us": round(float(us.max()), 1),
        "n": int(len(us)),
    }


def sim_real_time_factor(seconds):
    """Real-time factor of the pybullet driver in its real-time and free-running modes."""
    sys.path.insert(0, os.path.join(ROOT, "src", "hw_interface"))
    from hw_interface.sim_driver import PybulletSimDriver

    urdf = os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf")
    figures = {}
    for real_time in (True, False):
        sim = PybulletSimDriver(urdf, initial_joints=HOME, real_time=real_time)
        sim.login()
        start_wall, start_sim = time.perf_counter(), sim.sim_time
        while time.perf_counter() - start_wall < seconds:
            sim.set_joints(HOME + 0.1 * np.sin(time.perf_counter() - start_wall))
            time.sleep(0.002)
        factor = (sim.sim_time - start_sim) / (time.perf_counter() - start_wall)
        figures["real_time" if real_time else "free_running"] = {
            "factor": round(factor, 3),
            "overruns": sim.overruns,
            "steps": sim.steps,
        }
        sim.disconnect()
    return figures


def service_benchmarks(calls, stream_seconds, driver="pybullet"):
    """Round trip and 500 Hz streaming through the driver's launch file, started here."""
    (launch_file, *launch_args), robot = DRIVERS[driver]
    home = start_pose(robot)
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT}")
    os.environ["ROS_MASTER_URI"] = env["ROS_MASTER_URI"]
    launch = subprocess.Popen(
        ["roslaunch", "-p", str(PORT), os.path.join(LAUNCH, launch_file), *launch_args],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        import rospy

        from hw_interface.controller_client import MotionControllerClient
        from motion_commander.srv import commander, commanderRequest

        rospy.init_node("hw_bench", disable_signals=True)
        client = MotionControllerClient(timeout=60.0)
        client.move_j(home)
        for _ in range(50):  # warm up
            client.get_joints()
        persistent = []
        for _ in range(calls):
            t = time.perf_counter()
            client.call(3)
            persistent.append(time.perf_counter() - t)
        fresh = []
        for _ in range(max(100, calls // 10)):
            proxy = rospy.ServiceProxy("/motion_controller", commander)
            t = time.perf_counter()
            proxy(commanderRequest(command_index=3))
            fresh.append(time.perf_counter() - t)
        period = 0.002
        total = int(stream_seconds / period)
        print(f"streaming SET_JOINTS at 500 Hz for {stream_seconds:.0f} s ({total} periods)...", flush=True)
        missed, stream_rtt = 0, []
        start = time.perf_counter()
        for k in range(total):
            due = start + k * period
            while time.perf_counter() < due:
                pass
            q = home + 0.2 * np.sin(2 * np.pi * 0.5 * k * period)
            t = time.perf_counter()
            client.set_joints(q)
            done = time.perf_counter()
            stream_rtt.append(done - t)
            if done > due + period:  # this command overran its 2 ms slot
                missed += 1
            if k % 500 == 0 and k:
                print(f"  {k}/{total} periods, missed so far {missed}", flush=True)
        elapsed = time.perf_counter() - start
        return {
            "round_trip_persistent": percentiles(persistent),
            "round_trip_fresh_connection_baseline": percentiles(fresh),
            "persistent_speedup_p50": round(float(np.median(fresh) / np.median(persistent)), 2),
            "stream_500hz": {
                "periods": total,
                "missed": missed,
                "missed_pct": round(100.0 * missed / total, 3),
                "achieved_rate_hz": round(total / elapsed, 1),
                **percentiles(stream_rtt),
            },
        }
    finally:
        launch.terminate()
        launch.wait(timeout=20)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--calls", type=int, default=2000, help="round trips to time (default 2000)")
    parser.add_argument("--stream-seconds", type=float, default=10.0, help="500 Hz streaming duration (s)")
    parser.add_argument("--sim-seconds", type=float, default=5.0, help="real-time factor run length (s)")
    parser.add_argument("--driver", choices=sorted(DRIVERS), default="pybullet", help="the driver to measure")
    args = parser.parse_args()
    results = {"driver": args.driver}
    if args.driver == "pybullet":
        print("simulator real-time factor...", flush=True)
        results["simulator"] = sim_real_time_factor(args.sim_seconds)
    results.update(service_benchmarks(args.calls, args.stream_seconds, args.driver))
    results["machine"] = {"cores": os.cpu_count()}
    write_results("hw_bench" if args.driver == "pybullet" else f"hw_bench_{args.driver}", results)


if __name__ == "__main__":
    main()
