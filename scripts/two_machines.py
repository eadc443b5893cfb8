#!/usr/bin/env python3
"""A sensor PC and a robot PC on one machine: two network namespaces joined by a veth pair.

The robot side (10.231.0.1) runs the master, the core and the simulated driver
(launch/robot_pc.launch); the sensor side (10.231.0.2) runs the device and the sequencer
(launch/sensing.launch device:=replay). Each process has its own ROS_IP and
ROS_MASTER_URI=http://10.231.0.1:PORT, exactly as on two PCs, so every topic and service
between the layers crosses the link. Both namespaces share the machine's clock (no
chrony needed here; two real PCs need it, see the README).

Used by tests/system/test_two_machines.py and bench/e2e_latency.py --netns. Run alone
(as root) it plays one recording across the link with session_monitor on the robot side
and prints the session summary:

  sudo scripts/two_machines.py [--recording FILE] [--port 11497] [--logs DIR]

Namespace and interface names are unique per run; everything started in them is stopped
and the namespaces deleted on exit, whatever happens.
"""

import argparse
import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SETUP = os.path.join(ROOT, "catkin_ws", "devel", "setup.bash")
PYTHON = os.path.join(ROOT, ".venv", "bin", "python")
ROBOT_IP, SENSOR_IP = "10.231.0.1", "10.231.0.2"
PORT = 11497  # not 11311: other ROS sessions on the machine keep theirs
RECORDING = os.path.join(ROOT, "tests", "data", "test-paddle-rightwards.jsonl.gz")

# Runs argv inside a namespace with the workspace sourced and this side's ROS addresses.
# setup.bash reads the caller's arguments, so they are hidden while it runs.
_WRAPPER = (
    'm="$1"; i="$2"; shift 2; a=("$@"); set --; source "' + SETUP + '"; '
    'export ROS_MASTER_URI="$m" ROS_IP="$i"; unset ROS_HOSTNAME; exec "${a[@]}"'
)


def netns_unavailable():
    """Why two namespaces cannot be made here (None when they can): needs root and `ip`."""
    if os.geteuid() != 0:
        return "needs root (ip netns add)"
    if shutil.which("ip") is None:
        return "the `ip` command (iproute2) is not installed"
    probe = f"mc-probe-{secrets.token_hex(3)}"
    made = subprocess.run(["ip", "netns", "add", probe], capture_output=True, text=True, check=False)
    if made.returncode != 0:
        return f"ip netns add failed: {made.stderr.strip()}"
    subprocess.run(["ip", "netns", "del", probe], capture_output=True, check=False)
    return None


def _ip(*args):
    subprocess.run(["ip", *args], check=True, capture_output=True, text=True)


class TwoMachines:
    """Context manager: the two namespaces, the link, and the processes started in them."""

    def __init__(self, log_dir, port=PORT):
        tag = secrets.token_hex(3)
        self.ns = {"robot": f"mc-robot-{tag}", "sensor": f"mc-sensor-{tag}"}
        self.ips = {"robot": ROBOT_IP, "sensor": SENSOR_IP}
        self.veth = {"robot": f"mcr{tag}", "sensor": f"mcs{tag}"}  # <= 15 characters
        self.master_uri = f"http://{ROBOT_IP}:{port}"
        self.port = port
        self.log_dir = log_dir
        self.procs = []  # (side, name, Popen), in start order
        self.made = []

    def __enter__(self):
        try:
            for _side, ns in self.ns.items():
                _ip("netns", "add", ns)
                self.made.append(ns)
            _ip("link", "add", self.veth["robot"], "type", "veth", "peer", "name", self.veth["sensor"])
            for side, ns in self.ns.items():
                _ip("link", "set", self.veth[side], "netns", ns)
                _ip("-n", ns, "addr", "add", f"{self.ips[side]}/24", "dev", self.veth[side])
                _ip("-n", ns, "link", "set", self.veth[side], "up")
                _ip("-n", ns, "link", "set", "lo", "up")
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def spawn(self, side, name, argv):
        """Start argv in ``side``'s namespace (own process group); output to LOG_DIR/name.log."""
        env = dict(os.environ, ROS_HOME=os.path.join(self.log_dir, "ros-" + side))
        log = open(os.path.join(self.log_dir, name + ".log"), "w", encoding="utf-8")
        cmd = [
            "ip",
            "netns",
            "exec",
            self.ns[side],
            "bash",
            "-c",
            _WRAPPER,
            "bash",
            self.master_uri,
            self.ips[side],
            *argv,
        ]
        proc = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        log.close()
        self.procs.append((side, name, proc))
        return proc

    def wait_for_master(self, timeout=60.0):
        """Block until the sensor side reaches the master over the link; False on timeout."""
        probe = (
            "import sys, time, rosgraph\n"
            "deadline = time.time() + float(sys.argv[1])\n"
            "while time.time() < deadline:\n"
            "    try:\n"
            "        rosgraph.Master('/netns_probe').getPid(); sys.exit(0)\n"
            "    except Exception:\n"
            "        time.sleep(0.2)\n"
            "sys.exit(1)\n"
        )
        proc = self.spawn("sensor", "master_probe", [PYTHON, "-c", probe, str(timeout)])
        return proc.wait(timeout=timeout + 30) == 0

    def log_tail(self, name, lines=30):
        """The last lines of a process's log (for failure messages)."""
        try:
            with open(os.path.join(self.log_dir, name + ".log"), encoding="utf-8", errors="replace") as fh:
                return "".join(fh.readlines()[-lines:])
        except OSError:
            return ""

    def close(self):
        """Stop every process (SIGINT, roslaunch's shutdown, then SIGKILL), delete the namespaces."""
        for _, _, proc in reversed(self.procs):  # sensor side and checkers first, the master last
            _signal_group(proc, signal.SIGINT)
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                _signal_group(proc, signal.SIGKILL)
                proc.wait(timeout=5)
        for ns in self.made:
            # roslaunch starts each node in its own session: whatever is left in our namespace
            # (only processes this run started) is killed by pid before the namespace goes.
            pids = subprocess.run(["ip", "netns", "pids", ns], capture_output=True, text=True, check=False)
            for pid in pids.stdout.split():
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except (ProcessLookupError, ValueError):
                    pass
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, check=False)
        self.made = []


def _signal_group(proc, sig):
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            pass


def start_session(pair, recording, watchers=(), robot_args=(), sensor_args=()):
    """robot_pc.launch (with its master) on the robot side; once the master answers across
    the link, the ``watchers`` ((name, argv) pairs) on the robot side, then sensing.launch
    device:=replay on the sensor side. Returns the watchers' processes; raises if the master
    never answers."""
    pair.spawn(
        "robot",
        "robot_pc",
        [
            "roslaunch",
            "-p",
            str(pair.port),
            os.path.join(ROOT, "src", "motion_bringup", "launch", "robot_pc.launch"),
            *robot_args,
        ],
    )
    if not pair.wait_for_master(90.0):
        raise RuntimeError("the master on the robot side never answered over the link:\n" + pair.log_tail("robot_pc"))
    procs = [pair.spawn("robot", name, argv) for name, argv in watchers]
    pair.spawn(
        "sensor",
        "sensing",
        [
            "roslaunch",
            os.path.join(ROOT, "src", "motion_bringup", "launch", "sensing.launch"),
            "device:=replay",
            f"recording:={recording}",
            *sensor_args,
        ],
    )
    return procs


def run_monitored_session(recording, log_dir, port=PORT, timeout=180.0, repeat=1):
    """One recording (``repeat`` passes) across the link with session_monitor on the robot
    side; its summary dict."""
    out = os.path.join(log_dir, "output")
    os.makedirs(out, exist_ok=True)
    with TwoMachines(log_dir, port) as pair:
        (monitor,) = start_session(
            pair,
            recording,
            watchers=[
                (
                    # nice 19, as in teleop_sim.launch: the observer never takes a core from the chain.
                    "session_monitor",
                    [
                        "nice",
                        "-n",
                        "19",
                        "rosrun",
                        "motion_commander",
                        "session_monitor",
                        f"_output_dir:={out}",
                        "_title:=two machines, " + os.path.basename(recording),
                    ],
                )
            ],
            sensor_args=[f"repeat:={repeat}"],
        )
        try:
            code = monitor.wait(timeout=timeout * repeat)
        except subprocess.TimeoutExpired:
            raise RuntimeError(
                f"session_monitor did not report within {timeout:.0f} s:\n"
                + pair.log_tail("session_monitor")
                + pair.log_tail("sensing")
            ) from None
        if code != 0:
            raise RuntimeError(f"session_monitor exited with {code}:\n" + pair.log_tail("session_monitor"))
    with open(os.path.join(out, "session_summary.json"), encoding="utf-8") as fh:
        return json.load(fh)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--recording", default=RECORDING, help="hand recording the sensor side replays")
    parser.add_argument("--port", type=int, default=PORT, help="master port on the robot side")
    parser.add_argument("--logs", default=None, help="folder for the process logs (default: a new temp folder)")
    args = parser.parse_args()
    reason = netns_unavailable()
    if reason:
        sys.exit(f"two_machines: cannot run: {reason}")
    logs = args.logs or tempfile.mkdtemp(prefix="two-machines-")
    os.makedirs(logs, exist_ok=True)
    start = time.time()
    summary = run_monitored_session(args.recording, logs, args.port)
    print(f"two machines ({ROBOT_IP} robot, {SENSOR_IP} sensor), {time.time() - start:.0f} s; logs in {logs}")
    print(
        f"sensor->driver p50 {summary['latency_p50_ms']} ms, p99 {summary['latency_p99_ms']} ms "
        f"({summary['latency_samples']} commands, frames in {summary['frames_in']}, "
        f"out {summary['frames_out']}, dropped {summary['frames_dropped']})"
    )


if __name__ == "__main__":
    main()
