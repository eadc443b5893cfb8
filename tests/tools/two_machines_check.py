"""Checker of the two-machine session (tests/system/test_two_machines.py), run on the robot
side by scripts/two_machines.py: the core gets ready, /motion_states_stamped arrives from
the sensor side's sequencer (its node advertises the sensor address), the clutch engages,
the driver accepts N commands and the tool moves. Waits on events with generous bounds,
never sleeps and hopes. Writes what it saw to --out (JSON) and exits 0 when all held.

usage: two_machines_check.py --out FILE --sensor-ip IP [--commands 100] [--timeout 60]
"""

import argparse
import json
import sys
import threading
from urllib.parse import urlparse

import numpy as np
import rosgraph
import rospy
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Bool, UInt8

from motion_commander.msg import CommandTrace

ENGAGED = {2, 3, 12}  # TeleopStatus ENGAGED, JOINT_SPEED_LIMITED, RAMPING


class Watch:
    """What the robot side sees, filled by subscriber callbacks under one lock."""

    def __init__(self, commands):
        self.lock = threading.Lock()
        self.ready = threading.Event()
        self.enough = threading.Event()
        self.commands = commands
        self.latencies, self.refused, self.statuses, self.tools = [], [], [], []
        rospy.Subscriber("/motion_commander/ready", Bool, self.on_ready, queue_size=1)
        rospy.Subscriber("/motion_controller/trace", CommandTrace, self.on_trace, queue_size=1000)
        rospy.Subscriber("/motion_commander/status", UInt8, self.on_status, queue_size=100)
        rospy.Subscriber("/motion_controller/tool_pose", PoseStamped, self.on_tool, queue_size=1000)

    def on_ready(self, msg):
        if msg.data:
            self.ready.set()

    def on_trace(self, msg):
        with self.lock:
            if msg.result == 0:
                self.latencies.append(msg.driver_latency)
            else:
                self.refused.append(msg.result)
            if len(self.latencies) >= self.commands:
                self.enough.set()

    def on_status(self, msg):
        with self.lock:
            self.statuses.append(msg.data)

    def on_tool(self, msg):
        p = msg.pose.position
        with self.lock:
            self.tools.append((p.x, p.y, p.z))


def node_host(master, topic, kind):
    """{node: host it advertises} of the publishers ("pub") or services ("srv") named ``topic``."""
    publishers, _, services = master.getSystemState()
    table = publishers if kind == "pub" else services
    nodes = [n for name, ns in table if name == topic for n in ns]
    return {n: urlparse(master.lookupNode(n)).hostname for n in nodes}


def check(args):
    """Run the checks; a dict of what was seen and an ``ok`` flag."""
    rospy.init_node("two_machines_check")
    watch = Watch(args.commands)
    seen = {"ready": watch.ready.wait(args.timeout)}
    try:
        rospy.wait_for_message("/motion_states_stamped", PoseStamped, timeout=args.timeout)
        seen["motion_states_arrived"] = True
    except rospy.ROSException:
        seen["motion_states_arrived"] = False
    master = rosgraph.Master("/two_machines_check")
    seen["motion_states_publishers"] = node_host(master, "/motion_states_stamped", "pub")
    seen["driver_hosts"] = node_host(master, "/motion_controller", "srv")
    seen["enough_commands"] = watch.enough.wait(args.timeout)
    with watch.lock:
        tools = np.array(watch.tools) if watch.tools else np.zeros((0, 3))
        seen.update(
            accepted=len(watch.latencies),
            refused=sorted(set(watch.refused)),
            engaged=bool(ENGAGED & set(watch.statuses)),
            latency_p50_ms=round(float(np.median(watch.latencies)) * 1000, 3) if watch.latencies else None,
            tool_travel_mm=round(float(np.ptp(tools, axis=0).max()) * 1000, 1) if len(tools) else 0.0,
        )
    seen["ok"] = bool(
        seen["ready"]
        and seen["motion_states_arrived"]
        and seen["enough_commands"]
        and seen["engaged"]
        and not seen["refused"]
        and seen["tool_travel_mm"] > args.min_travel_mm
        and seen["motion_states_publishers"]
        and set(seen["motion_states_publishers"].values()) == {args.sensor_ip}
    )
    return seen


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True, help="JSON file for what the checker saw")
    parser.add_argument("--sensor-ip", required=True, help="address the sensor side's nodes advertise")
    parser.add_argument("--commands", type=int, default=100, help="accepted commands to wait for")
    parser.add_argument("--min-travel-mm", type=float, default=20.0, help="the tool must move at least this far")
    parser.add_argument("--timeout", type=float, default=60.0, help="bound of each wait, s")
    args = parser.parse_args(rospy.myargv()[1:])
    seen = check(args)
    with open(args.out, "w", encoding="utf-8") as fh:
        json.dump(seen, fh, indent=1)
    print(json.dumps(seen), flush=True)
    sys.exit(0 if seen["ok"] else 1)


if __name__ == "__main__":
    main()
