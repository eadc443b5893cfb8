"""How far the tool trails the hand: the lag, end to end and per stage, of a teleop session.

For each recording and filter, one session of launch/teleop_sim.launch (pybullet arm, UR5e)
is recorded by a listener node, and the lag L of each stage is the one that best explains
the stage's output as an affine map of its input delayed by L (least squares over the
engaged span, L searched from 0 to 300 ms in 2 ms steps):

    raw hand (motion_sensor/raw_hand, sensor stamps)
      -> filtered hand (motion_sensor/hand, sensor stamps: the filter's lag)
      -> core target (motion_commander/target: mapping, speed and step limits)
      -> commanded joints (motion_commander/command, as tool positions by forward kinematics)
      -> measured tool (motion_controller/tool_pose, stamped when measured)

and hand -> tool end to end. An affine map absorbs the speed ratio and the frame change, so
only the delay is left. Stages are not additive exactly (each fit is its own), but close.

"none" is the mean filter over one frame (no smoothing); "mean" the paper's mean over 10
frames. The default session is teleop_sim.launch's default filter (one_euro). Recordings
come from ../shared/data/leap_v6 (real Leap streams), falling back to tests/data.

The UR path: the same sessions with the UR driver on its simulated controller
(real_robot:=true fake_controller:=true), whose servoJ follows each target first-order with
the lookahead time as time constant (a delay and smoothing of that length), for each
lookahead in --lookaheads, with the default filter.

Run: bench/run hand_to_tool [--recordings NAME ...] [--filters none mean one_euro kalman]
     [--lookaheads 0.03 0.05 0.1]
Writes bench/results/hand_to_tool.json (top level hand_to_tool_ms_p50: over the recordings,
default session) and bench/results/hand_to_tool.png (hand and tool against time, one
recording).
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

from bench_common import RESULTS, write_results

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src", "motion_commander"))
from motion_commander.lag_estimate import MIN_SPAN_M, trailing_lag  # noqa: E402
from motion_commander.session_report import overshoot  # noqa: E402
from motion_common.launch_args import declared_args  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "data", "leap_v6"))
# Slow and fast hands, one and two hands in view, several frame rates.
DEFAULT = ["brian", "test-paddle-rightwards", "Waiting-110fps", "wave", "flapping", "rollAndPitchCropped"]
FILTERS = {
    "none": ["filter:=mean", "queue_size:=1"],
    "mean": ["filter:=mean", "queue_size:=10"],
    "one_euro": ["filter:=one_euro"],
    "kalman": ["filter:=kalman"],
}
# The filter of a session started without filter:= (teleop_sim.launch's default, the
# sequencer's declared default: a unit test keeps them equal).
DEFAULT_FILTER = declared_args(os.path.join(ROOT, "src", "motion_bringup", "launch", "teleop_sim.launch"))[
    "filter"
].default
PORT = 11481
STAGES = [("raw", "filtered"), ("filtered", "target"), ("target", "commanded"), ("commanded", "tool"), ("raw", "tool")]
STAGE_NAMES = [f"{a}->{b}" for a, b in STAGES]
UR_LOOKAHEADS = [0.03, 0.05, 0.1]  # s, servoJ lookahead times run on the UR path


def recording_path(name):
    for folder in (SHARED, os.path.join(ROOT, "tests", "data")):
        path = os.path.join(folder, name + ".jsonl.gz")
        if os.path.exists(path):
            return path
    raise SystemExit(f"hand_to_tool: no recording {name!r} in {SHARED} or tests/data")


def engaged_span(streams):
    """The part of every stream inside the span of the core's targets (engaged)."""
    target = streams["target"]
    start, end = target[0, 0], target[-1, 0]
    return {name: rows[(rows[:, 0] >= start) & (rows[:, 0] <= end)] for name, rows in streams.items()}


def stage_lags(streams, min_span=MIN_SPAN_M):
    """Lag (ms) of each stage and end to end (lag_estimate.trailing_lag: None where it
    cannot be told), and how far the measured tool went past the core target's turning
    points (``overshoot_mm``, as the session summary gives it)."""
    streams = engaged_span(streams)
    lags = {
        f"{source}->{follower}": trailing_lag(streams[source], streams[follower], min_span)
        for source, follower in STAGES
    }
    lags["overshoot_mm"] = round(overshoot(streams["target"], streams["tool"]) * 1000.0, 2)
    return lags


def record(out_path):
    """The listener: a node that records the five streams until the replay has finished."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Bool

    from motion_common.kinematics import RobotKinematics
    from motion_sensor.msg import hand

    rows = {name: [] for name in ("raw", "filtered", "target", "commanded", "tool")}
    done = []

    def on_hand(name):
        def callback(msg):
            if msg.hands_num:
                p = msg.position
                rows[name].append((msg.header.stamp.to_sec(), p.x, p.y, p.z))

        return callback

    def on_pose(name):
        def callback(msg):
            p = msg.pose.position
            rows[name].append((msg.header.stamp.to_sec(), p.x, p.y, p.z))

        return callback

    def on_command(msg):  # joints now; tool positions once recorded, off the callbacks
        rows["commanded"].append((msg.header.stamp.to_sec(), *msg.position))

    rospy.init_node("hand_to_tool_recorder", disable_signals=True)
    rospy.Subscriber("/motion_sensor/raw_hand", hand, on_hand("raw"), queue_size=1000)
    rospy.Subscriber("/motion_sensor/hand", hand, on_hand("filtered"), queue_size=1000)
    rospy.Subscriber("/motion_commander/target", PoseStamped, on_pose("target"), queue_size=1000)
    rospy.Subscriber("/motion_commander/command", JointState, on_command, queue_size=1000)
    rospy.Subscriber("/motion_controller/tool_pose", PoseStamped, on_pose("tool"), queue_size=1000)
    rospy.Subscriber("/hand_replay/finished", Bool, lambda m: m.data and done.append(time.monotonic()), queue_size=1)
    deadline = time.monotonic() + 300.0
    while not (done and time.monotonic() > done[0] + 1.0) and time.monotonic() < deadline:
        time.sleep(0.05)
    robot = RobotKinematics(os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf"))
    rows["commanded"] = [(row[0], *robot.forward(list(row[1:])).translation) for row in list(rows["commanded"])]
    np.savez(out_path, **{name: np.array(values, dtype=float).reshape(-1, 4) for name, values in rows.items()})


def ur_args(lookahead, workdir):
    """Session arguments of the UR path: the UR driver on its simulated controller, whose
    servoJ follows with the lookahead's delay and smoothing, with this lookahead."""
    params = os.path.join(workdir, "ur_params.yaml")
    with open(params, "w", encoding="utf-8") as stream:
        stream.write(f"lookahead_time: {lookahead}\n")
    return ["real_robot:=true", "fake_controller:=true", f"driver_params:={params}"]


def wait_for_master(uri, launch, timeout=60.0):
    """Until the session's roscore answers, so that the recorder registers at once (rospy
    prints a warning per retry otherwise)."""
    import rosgraph

    deadline = time.monotonic() + timeout
    while not rosgraph.is_master_online(uri):
        if launch.poll() is not None or time.monotonic() > deadline:
            raise SystemExit(f"hand_to_tool: no roscore at {uri} (roslaunch exit code {launch.poll()})")
        time.sleep(0.1)


def run_session(recording, filter_args, workdir):
    """One session recorded; the five streams as arrays of rows (t, x, y, z)."""
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{PORT}", ROS_HOME=workdir)
    out = os.path.join(workdir, "streams.npz")
    launch = subprocess.Popen(
        [
            "roslaunch",
            "-p",
            str(PORT),
            os.path.join(ROOT, "src", "motion_bringup", "launch", "teleop_sim.launch"),
            f"recording:={recording}",
            f"output_dir:={workdir}",
            "exit_when_done:=false",
            "monitor:=false",
            *filter_args,
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        wait_for_master(env["ROS_MASTER_URI"], launch)
        subprocess.run([sys.executable, os.path.abspath(__file__), "--record", out], env=env, timeout=360, check=True)
    finally:
        launch.send_signal(signal.SIGINT)
        launch.wait(timeout=60)
    data = np.load(out)
    return {name: data[name] for name in data.files}


def plot(streams, title, path):
    import matplotlib.pyplot as plt

    from motion_common.atomic_file import write_atomic

    streams = engaged_span(streams)
    figure, axis = plt.subplots(figsize=(9, 4))
    t0 = streams["raw"][0, 0]
    for name, colour in (("raw", "tab:blue"), ("target", "tab:orange"), ("tool", "tab:green")):
        rows = streams[name]
        axis.plot(rows[:, 0] - t0, 1000.0 * (rows[:, 1] - rows[0, 1]), colour, label=name, linewidth=1)
    axis.set_xlabel("time (s)")
    axis.set_ylabel("x from its start (mm; raw hand unscaled)")
    axis.set_title(title)
    axis.legend()
    figure.tight_layout()
    temporary = path + ".tmp.png"
    figure.savefig(temporary, dpi=100)
    plt.close(figure)
    with open(temporary, "rb") as stream:
        write_atomic(path, stream.read())
    os.remove(temporary)


def p50(values):
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--recordings", nargs="+", default=DEFAULT, help="recording names (default: %(default)s)")
    parser.add_argument("--filters", nargs="+", default=list(FILTERS), choices=list(FILTERS), help="filters to run")
    parser.add_argument(
        "--lookaheads",
        nargs="*",
        type=float,
        default=UR_LOOKAHEADS,
        help="UR path: servoJ lookahead times (s) to run with the default filter (none: skip the UR path)",
    )
    parser.add_argument("--record", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.record:
        record(args.record)
        return
    results = {
        "method": "affine fit of each stage's output to its input delayed by L; L in 0-300 ms, 2 ms steps",
        "default_filter": DEFAULT_FILTER,
    }
    runs = [(name, filter_name, None) for name in args.recordings for filter_name in args.filters]
    runs += [(name, DEFAULT_FILTER, lookahead) for lookahead in args.lookaheads for name in args.recordings]
    per, ur = {}, {}
    for done, (name, filter_name, lookahead) in enumerate(runs, start=1):
        with tempfile.TemporaryDirectory(prefix="hand-to-tool-") as workdir:
            extra = [] if lookahead is None else ur_args(lookahead, workdir)
            streams = run_session(recording_path(name), FILTERS[filter_name] + extra, workdir)
        if len(streams["target"]) < 20:
            lags = {"error": "the clutch never engaged"}
        else:
            lags = stage_lags(streams)
            if lookahead is None and name == args.recordings[0] and filter_name == DEFAULT_FILTER:
                title = f"{name}: hand, core target and tool (x), default session ({filter_name})"
                plot(streams, title, os.path.join(RESULTS, "hand_to_tool.png"))
        if lookahead is None:
            per.setdefault(name, {})[filter_name] = lags
            label = f"{filter_name:9s}"
        else:
            ur.setdefault(f"{lookahead:g}", {})[name] = lags
            label = f"UR lookahead {lookahead:g} s"
        print(f"[{done}/{len(runs)}] {name:26s} {label} {lags}", flush=True)
    results["recordings"] = per
    for filter_name in args.filters:
        results[f"{filter_name}_hand_to_tool_ms_p50"] = p50(per[n][filter_name].get("raw->tool") for n in per)
        for stage in STAGE_NAMES:
            results.setdefault("stage_ms_p50", {}).setdefault(filter_name, {})[stage] = p50(
                per[n][filter_name].get(stage) for n in per
            )
    for filter_name in args.filters:
        values = [per[n][filter_name].get("overshoot_mm") for n in per]
        results[f"{filter_name}_overshoot_mm_max"] = max((v for v in values if v is not None), default=None)
    results["hand_to_tool_ms_p50"] = results.get(f"{DEFAULT_FILTER}_hand_to_tool_ms_p50")
    results["overshoot_mm_max"] = results.get(f"{DEFAULT_FILTER}_overshoot_mm_max")
    if ur:
        results["ur_path"] = {
            "filter": DEFAULT_FILTER,
            "driver": "ur_rtde_fake: servoJ followed first-order with the lookahead as time constant",
            "recordings": ur,
            "hand_to_tool_ms_p50": {k: p50(v[n].get("raw->tool") for n in v) for k, v in ur.items()},
            "commanded_to_tool_ms_p50": {k: p50(v[n].get("commanded->tool") for n in v) for k, v in ur.items()},
            "overshoot_mm_max": {k: max(v[n].get("overshoot_mm", 0.0) for n in v) for k, v in ur.items()},
        }
    write_results("hand_to_tool", results, show=False)
    print(json.dumps({k: v for k, v in results.items() if k.endswith(("p50", "_max"))}, indent=2))
    if ur:
        print("UR path, hand -> tool p50 by lookahead (s):", results["ur_path"]["hand_to_tool_ms_p50"])


if __name__ == "__main__":
    main()
