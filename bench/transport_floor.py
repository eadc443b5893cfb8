"""The transport floor of a teleop session: a bare rospy chain with the session's three
hops and message types, as four separate processes:

  source (motion_sensor/hand, a recorded Leap path, stamped as published, 110 Hz) -> relay
  (PoseStamped, stamp kept) -> caller (commander.srv SET_JOINTS over a persistent proxy)
  -> server (answers SUCCESS).

Each hop records (now - sensor stamp) per message; the server's figure is the floor of
sensor->driver. Variants add ONE ingredient of the real session each, so the difference to
their base is what that ingredient costs (bench/e2e_latency.py --breakdown):

  floor           the issue's floor: publishers queued (queue_size 10), doing no work
  sync            publishers synchronous (queue_size None), as the session's device and
                  sequencer publish: the difference to 'floor' is rospy's queue hand-off
  sim_thread      sync + the server process runs the pybullet UR5e at 500 Hz and hands each
                  target to it: interpreter-lock and driver-lock contention with the simulator
  core_work       sync + the caller runs the core (TeleopCore with teleop.yaml: mapping, IK,
                  safety) on each pose before calling: the core's own per-frame cost
  topic_last_hop  sync, but the last hop is a topic (JointState) instead of the service

Runnable alone (needs a ROS master at ROS_MASTER_URI; e2e_latency starts its own):

  bench/run transport_floor [--variant floor] [--count 1100] [--rate 110]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
ROLES = ("server", "caller", "relay", "source")
VARIANTS = {
    "floor": "the issue's floor: queued publishers, no work",
    "sync": "synchronous publishers (the session's setting), no work",
    "sim_thread": "sync + pybullet UR5e stepping at 500 Hz in the server process",
    "core_work": "sync + the core's per-frame work (TeleopCore) in the caller",
    "topic_last_hop": "sync, last hop a JointState topic instead of the service",
}
RECORDING = os.path.join(ROOT, "tests", "data", "Waiting-110fps.jsonl.gz")
URDF = os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf")
HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]


def extra_frames(variant):
    """Frames the source sends beyond ``count`` (and the relay forwards): nothing downstream
    waits on a lost tail, and the core's clutch takes 10 frames to engage."""
    return 20 + (30 if variant == "core_work" else 0)


def _queue(variant):
    """Publisher queue_size of a variant: None is rospy's synchronous publish."""
    return 10 if variant == "floor" else None


def _dump(path, rows):
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(rows, fh)


def role_server(out, count, variant):
    """Serve /floor/controller (or subscribe /floor/joints): record now - request stamp."""
    import rospy
    from sensor_msgs.msg import JointState

    from motion_commander.srv import commander, commanderResponse

    rows = []
    driver = None
    if variant == "sim_thread":
        from hw_interface.sim_driver import PybulletSimDriver

        driver = PybulletSimDriver(URDF, initial_joints=HOME)
        driver.login()

    def accept(joints):
        if driver is not None:
            driver.set_joints(joints)

    def handle(request):
        accept(request.joints)
        rows.append(rospy.get_time() - request.header.stamp.to_sec())
        return commanderResponse(result=0)

    def on_joints(msg):
        accept(msg.position)
        rows.append(rospy.get_time() - msg.header.stamp.to_sec())

    if variant == "topic_last_hop":
        rospy.Subscriber("/floor/joints", JointState, on_joints, queue_size=10, tcp_nodelay=True)
    else:
        rospy.Service("/floor/controller", commander, handle)
    _spin_until(lambda: len(rows) >= count, 180.0)
    if driver is not None:
        driver.disconnect()
    _dump(out, rows)


def _core():
    """A TeleopCore configured as the session's (teleop.yaml, UR5e, auto clutch)."""
    import yaml

    from motion_commander.config import load_teleop_config
    from motion_commander.teleop import TeleopMapper, make_clutch
    from motion_commander.teleop_core import TeleopCore
    from motion_common.kinematics import RobotKinematics

    with open(os.path.join(ROOT, "src", "motion_commander", "config", "teleop.yaml"), encoding="utf-8") as fh:
        config = load_teleop_config(yaml.safe_load(fh))
    core = TeleopCore(
        RobotKinematics(URDF, config.tool_frame),
        TeleopMapper(config.speed_ratio, np.eye(3)),
        make_clutch(config.engage, config.steady_frames, config.lost_after),
        config.safety,
    )
    core.on_joint_state(HOME)
    return core


def role_caller(out, count, variant):
    """PoseStamped in, one persistent service call (or JointState) out per message."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Bool

    from motion_commander.srv import commander, commanderRequest

    core = _core() if variant == "core_work" else None
    if variant == "topic_last_hop":
        pub = rospy.Publisher("/floor/joints", JointState, queue_size=None, tcp_nodelay=True)
        while pub.get_num_connections() < 1 and not rospy.is_shutdown():
            time.sleep(0.05)

        def send(stamp, joints):
            msg = JointState(position=joints)
            msg.header.stamp = stamp
            pub.publish(msg)
    else:
        rospy.wait_for_service("/floor/controller", timeout=60.0)
        proxy = rospy.ServiceProxy("/floor/controller", commander, persistent=True)

        def send(stamp, joints):
            request = commanderRequest(command_index=5, joints=joints)
            request.header.stamp = stamp
            proxy(request)

    rows, sent = [], []

    def on_pose(msg):
        rows.append(rospy.get_time() - msg.header.stamp.to_sec())
        joints = HOME
        if core is not None:
            p, o = msg.pose.position, msg.pose.orientation
            command = core.on_hand_pose(
                msg.header.stamp.to_sec(), [p.x, p.y, p.z], [o.x, o.y, o.z, o.w], now=rospy.get_time()
            )
            if command is None:
                return  # engaging (the clutch's steady frames): nothing to send yet
            joints = command.joints.tolist()
            core.on_joint_state(joints)
        send(msg.header.stamp, joints)
        sent.append(1)
        if core is not None:
            core.prepare_next()  # the between-frames work, after the command (the node times it later)

    subscriber = rospy.Subscriber("/floor/pose", PoseStamped, on_pose, queue_size=10, tcp_nodelay=True)
    # The source starts only once this end of the chain is connected: a caller slow to
    # start (the core's imports) must not miss the first poses.
    _spin_until(lambda: subscriber.get_num_connections() >= 1, 60.0)
    ready = rospy.Publisher("/floor/ready", Bool, queue_size=1, latch=True)
    ready.publish(Bool(True))
    _spin_until(lambda: len(sent) >= count, 180.0)
    _dump(out, rows)


def role_relay(out, count, variant):
    """motion_sensor/hand in, PoseStamped out with the sensor stamp."""
    import rospy
    from geometry_msgs.msg import PoseStamped

    from motion_sensor.msg import hand

    pub = rospy.Publisher("/floor/pose", PoseStamped, queue_size=_queue(variant), tcp_nodelay=True)
    rows = []

    def on_hand(msg):
        rows.append(rospy.get_time() - msg.header.stamp.to_sec())
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position = msg.position
        pose.pose.orientation = msg.orientation
        pub.publish(pose)

    rospy.Subscriber("/floor/hand", hand, on_hand, queue_size=10, tcp_nodelay=True)
    _spin_until(lambda: len(rows) >= count + extra_frames(variant), 180.0)
    _dump(out, rows)


def recorded_hands():
    """The right hand's (position, orientation) of a real Leap recording, looped by the source."""
    from motion_sensor.devices.replay import load_samples

    samples, _ = load_samples(RECORDING)
    return [(s.position.tolist(), s.orientation.tolist()) for _, s in samples if s.hands_num]


def role_source(_out, count, rate, variant):
    """Publish ``count`` recorded hands at ``rate`` Hz once the chain is connected."""
    import rospy
    from std_msgs.msg import Bool

    from motion_sensor.msg import hand

    pub = rospy.Publisher("/floor/hand", hand, queue_size=_queue(variant), tcp_nodelay=True)
    path = recorded_hands()
    ready = []
    rospy.Subscriber("/floor/ready", Bool, lambda msg: ready.append(msg.data), queue_size=1)
    # Start once the relay listens and the caller says the rest of the chain is connected.
    _spin_until(lambda: pub.get_num_connections() >= 1 and ready, 60.0)
    period = 1.0 / rate
    start = time.monotonic()
    for k in range(count + extra_frames(variant)):
        position, orientation = path[k % len(path)]
        msg = hand(hands_num=1, hand_type=["right"])
        msg.position.x, msg.position.y, msg.position.z = position
        msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = orientation
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
    return {
        "p50": round(float(np.percentile(ms, 50)), 3),
        "p99": round(float(np.percentile(ms, 99)), 3),
        "n": int(len(ms)),
    }


def run_floor(count=1100, rate=110.0, env=None, variant="floor"):
    """Run the four processes of ``variant`` against the master in ``env``; per-hop figures."""
    folder = tempfile.mkdtemp(prefix="floor-")
    procs = []
    for role in ROLES:
        cmd = [
            sys.executable,
            os.path.abspath(__file__),
            "--role",
            role,
            "--count",
            str(count),
            "--rate",
            str(rate),
            "--variant",
            variant,
            "--out",
            os.path.join(folder, f"{role}.json"),
        ]
        procs.append(subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        time.sleep(0.3)
    for proc in procs:
        proc.wait(timeout=240)
    hops = {}
    for role, hop in (("relay", "sensor->relay"), ("caller", "sensor->caller"), ("server", "sensor->server")):
        path = os.path.join(folder, f"{role}.json")
        if not os.path.exists(path):
            raise RuntimeError(
                f"transport floor ({variant}): the {role} wrote no figures; run it alone with "
                f"bench/run transport_floor --variant {variant} to see its error"
            )
        with open(path, encoding="utf-8") as fh:
            hops[hop] = stats(json.load(fh)[:count])
    return hops


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--role", choices=ROLES, help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    parser.add_argument("--variant", choices=sorted(VARIANTS), default="floor", help="see above (default floor)")
    parser.add_argument("--count", type=int, default=1100, help="commands measured (default 1100)")
    parser.add_argument("--rate", type=float, default=110.0, help="source rate in Hz (default 110, the Leap's)")
    args = parser.parse_args()
    if args.role is None:
        hops = run_floor(args.count, args.rate, variant=args.variant)
        print(
            f"floor ({args.variant}): p50={hops['sensor->server']['p50']} ms p99={hops['sensor->server']['p99']} ms "
            f"(n={hops['sensor->server']['n']}); hops {hops}"
        )
        return
    import rospy

    rospy.init_node(f"floor_{args.role}", disable_signals=True)
    if args.role == "source":
        role_source(args.out, args.count, args.rate, args.variant)
    else:
        {"server": role_server, "caller": role_caller, "relay": role_relay}[args.role](
            args.out, args.count, args.variant
        )


if __name__ == "__main__":
    main()
