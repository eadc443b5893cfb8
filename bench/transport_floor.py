"""The transport floor of a teleop session: a bare rospy chain with the session's three
hops and message types, doing no work, as four separate processes:

  source (motion_sensor/hand, stamped as published, 110 Hz) -> relay (PoseStamped, stamp
  kept) -> caller (commander.srv SET_JOINTS over a persistent proxy) -> server (answers
  SUCCESS at once).

Each hop records (now - sensor stamp) per message; the server's figure is the floor of
sensor->driver. Used by bench/e2e_latency.py (same run as the sessions); runnable alone:

  bench/run transport_floor [--count 1100] [--rate 110]

Needs a ROS master at ROS_MASTER_URI (e2e_latency starts its own).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROLES = ("server", "caller", "relay", "source")


def _dump(path, rows):
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(rows, fh)


def role_server(out, count):
    """Serve /floor/controller: SUCCESS at once, record now - request stamp."""
    import rospy
    from motion_commander.srv import commander, commanderResponse
    rows = []

    def handle(request):
        rows.append(rospy.get_time() - request.header.stamp.to_sec())
        return commanderResponse(result=0)
    rospy.Service("/floor/controller", commander, handle)
    _spin_until(lambda: len(rows) >= count, 180.0)
    _dump(out, rows)


def role_caller(out, count):
    """PoseStamped in, one persistent service call out per message."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from motion_commander.srv import commander, commanderRequest
    rospy.wait_for_service("/floor/controller", timeout=60.0)
    proxy = rospy.ServiceProxy("/floor/controller", commander, persistent=True)
    rows = []

    def on_pose(msg):
        rows.append(rospy.get_time() - msg.header.stamp.to_sec())
        request = commanderRequest(command_index=5, joints=[0.0] * 6)
        request.header.stamp = msg.header.stamp
        proxy(request)
    rospy.Subscriber("/floor/pose", PoseStamped, on_pose, queue_size=10, tcp_nodelay=True)
    _spin_until(lambda: len(rows) >= count, 180.0)
    _dump(out, rows)


def role_relay(out, count):
    """motion_sensor/hand in, PoseStamped out with the sensor stamp."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from motion_sensor.msg import hand
    pub = rospy.Publisher("/floor/pose", PoseStamped, queue_size=10, tcp_nodelay=True)
    rows = []

    def on_hand(msg):
        rows.append(rospy.get_time() - msg.header.stamp.to_sec())
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position = msg.position
        pose.pose.orientation = msg.orientation
        pub.publish(pose)
    rospy.Subscriber("/floor/hand", hand, on_hand, queue_size=10, tcp_nodelay=True)
    _spin_until(lambda: len(rows) >= count, 180.0)
    _dump(out, rows)


def role_source(_out, count, rate):
    """Publish ``count`` hands at ``rate`` Hz once the chain is connected."""
    import rospy
    from motion_sensor.msg import hand
    pub = rospy.Publisher("/floor/hand", hand, queue_size=10, tcp_nodelay=True)
    deadline = time.monotonic() + 60.0
    while pub.get_num_connections() < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)  # let the relay's and caller's own connections settle
    period = 1.0 / rate
    start = time.monotonic()
    for k in range(count + 20):  # a few extra: nothing downstream waits on a lost tail
        msg = hand(hands_num=1, hand_type=["right"])
        msg.orientation.w = 1.0
        msg.header.stamp = rospy.Time.now()
        pub.publish(msg)
        delay = start + (k + 1) * period - time.monotonic()
        if delay > 0:
            time.sleep(delay)


def _spin_until(condition, timeout):
    import rospy
    deadline = time.monotonic() + timeout
    while not rospy.is_shutdown() and not condition() and time.monotonic() < deadline:
        time.sleep(0.05)


def stats(seconds):
    """p50/p99 in ms of a list of seconds."""
    ms = np.asarray(seconds, dtype=float) * 1000.0
    return {"p50": round(float(np.percentile(ms, 50)), 3), "p99": round(float(np.percentile(ms, 99)), 3),
            "n": int(len(ms))}


def run_floor(count=1100, rate=110.0, env=None):
    """Run the four processes against the master in ``env``; return per-hop figures."""
    folder = tempfile.mkdtemp(prefix="floor-")
    procs = []
    for role in ROLES:
        cmd = [sys.executable, os.path.abspath(__file__), "--role", role, "--count", str(count), "--rate", str(rate),
               "--out", os.path.join(folder, f"{role}.json")]
        procs.append(subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        time.sleep(0.3)
    for proc in procs:
        proc.wait(timeout=240)
    hops = {}
    for role, hop in (("relay", "sensor->relay"), ("caller", "sensor->caller"), ("server", "sensor->server")):
        path = os.path.join(folder, f"{role}.json")
        with open(path, encoding="utf-8") as fh:
            hops[hop] = stats(json.load(fh)[:count])
    return hops


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--role", choices=ROLES, help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    parser.add_argument("--count", type=int, default=1100, help="commands measured (default 1100)")
    parser.add_argument("--rate", type=float, default=110.0, help="source rate in Hz (default 110, the Leap's)")
    args = parser.parse_args()
    if args.role is None:
        hops = run_floor(args.count, args.rate)
        print(f"floor: p50={hops['sensor->server']['p50']} ms p99={hops['sensor->server']['p99']} ms "
              f"(n={hops['sensor->server']['n']}); hops {hops}")
        return
    import rospy
    rospy.init_node(f"floor_{args.role}", disable_signals=True)
    if args.role == "source":
        role_source(args.out, args.count, args.rate)
    else:
        {"server": role_server, "caller": role_caller, "relay": role_relay}[args.role](args.out, args.count)


if __name__ == "__main__":
    main()
