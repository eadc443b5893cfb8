"""Leap driver latency: from the WebSocket frame leaving a local Leap v6 service to the
filtered /motion_sensor/hand reaching a subscriber (driver + sequencer + two ROS hops),
replaying the 110 fps recordings at recorded timing through launch/sensing.launch.
Also reported: to /motion_sensor/raw_hand (driver only).

Run: bench/run leap_latency
Writes bench/results/leap_latency.json.
"""

import os
import subprocess
import sys
import threading
import time

import numpy as np

from bench_common import write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
PORT, MASTER = 6466, 11479
RECORDINGS = ["Waiting-110fps", "rollAndPitchCropped"]


def main():
    os.environ["ROS_MASTER_URI"] = f"http://localhost:{MASTER}"
    import rospy

    from motion_sensor.devices.leap_server import LeapReplayServer
    from motion_sensor.devices.leap_v6 import parse_message, select_primary
    from motion_sensor.msg import hand

    master = subprocess.Popen(["roscore", "-p", str(MASTER)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(2.0)
    rospy.init_node("leap_latency_bench", disable_signals=True)
    results = {}
    try:
        for name in RECORDINGS:
            server = LeapReplayServer(
                os.path.join(ROOT, "tests", "data", f"{name}.jsonl.gz"), port=PORT, start_delay=2.0
            )
            # Positions identify frames exactly: the driver converts them deterministically.
            keys = {}
            for index, text in enumerate(server.frames):
                frame = parse_message(text)
                if frame.hands:
                    keys[tuple(np.round(select_primary(frame).position, 9))] = index
            raw_times, stamp_to_index, out_times, lock = {}, {}, {}, threading.Lock()

            # The callbacks bind this recording's tables: a late message of the previous
            # recording's subscribers must not land in the next one's.
            def on_raw(msg, *, keys=keys, lock=lock, raw_times=raw_times, stamp_to_index=stamp_to_index):
                now = time.time()
                index = keys.get(tuple(np.round([msg.position.x, msg.position.y, msg.position.z], 9)))
                if index is not None:
                    with lock:
                        raw_times.setdefault(index, now)
                        stamp_to_index[msg.header.stamp.to_nsec()] = index

            def on_filtered(msg, *, lock=lock, stamp_to_index=stamp_to_index, out_times=out_times):
                now = time.time()
                with lock:
                    index = stamp_to_index.get(msg.header.stamp.to_nsec())
                    if index is not None:
                        out_times.setdefault(index, now)

            subs = [
                rospy.Subscriber("/motion_sensor/raw_hand", hand, on_raw, queue_size=1000, tcp_nodelay=True),
                rospy.Subscriber("/motion_sensor/hand", hand, on_filtered, queue_size=1000, tcp_nodelay=True),
            ]
            server.start()
            launch = subprocess.Popen(
                [
                    "roslaunch",
                    os.path.join(ROOT, "src", "motion_bringup", "launch", "sensing.launch"),
                    f"leap_port:={PORT}",
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            print(f"replaying {name} ({len(server.frames)} frames)...", flush=True)
            server.done.wait(60)
            time.sleep(0.5)
            launch.terminate()
            launch.wait(20)
            server.shutdown()
            for sub in subs:
                sub.unregister()
            raw = [raw_times[i] - server.send_times[i] for i in raw_times if i in server.send_times]
            out = [out_times[i] - server.send_times[i] for i in out_times if i in server.send_times]
            results[name] = {
                "frames_sent": len(server.send_times),
                "to_raw_hand_ms": {
                    "p50": round(float(np.percentile(raw, 50)) * 1000, 3),
                    "p99": round(float(np.percentile(raw, 99)) * 1000, 3),
                    "n": len(raw),
                },
                "to_filtered_hand_ms": {
                    "p50": round(float(np.percentile(out, 50)) * 1000, 3),
                    "p99": round(float(np.percentile(out, 99)) * 1000, 3),
                    "n": len(out),
                },
            }
            print(f"  {results[name]}", flush=True)
    finally:
        master.terminate()
        master.wait(10)
    write_results("leap_latency", results, show=False)


if __name__ == "__main__":
    sys.exit(main())
