"""Checker of the link cut between the sensor PC and the robot PC
(tests/system/test_two_machines.py), run on the robot side: it records the core's status
and the driver's accepted commands against the machine's monotonic clock (shared by both
namespaces), tells the test when teleop streams (--streaming FILE), waits for the test to
cut and restore the link (--restored FILE holds the cut and restore times), then for teleop
to stream again, and writes what it saw to --out (JSON).

usage: link_cut_check.py --out FILE --streaming FILE --restored FILE [--timeout 60]
"""

import argparse
import json
import os
import sys
import threading
import time

import rospy
from std_msgs.msg import UInt8

from motion_commander.msg import CommandTrace

STREAMING = {2, 3, 12}  # TeleopStatus ENGAGED, JOINT_SPEED_LIMITED, RAMPING
RAMPING = 12


class Record:
    def __init__(self):
        self.lock = threading.Lock()
        self.statuses = []  # (monotonic, code)
        self.accepted = []  # monotonic arrival of accepted commands
        rospy.Subscriber("/motion_commander/status", UInt8, self.on_status, queue_size=200)
        rospy.Subscriber("/motion_controller/trace", CommandTrace, self.on_trace, queue_size=2000)

    def on_status(self, msg):
        with self.lock:
            self.statuses.append((time.monotonic(), int(msg.data)))

    def on_trace(self, msg):
        if msg.result == 0:
            with self.lock:
                self.accepted.append(time.monotonic())


def wait(condition, timeout):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not rospy.is_shutdown():
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True)
    parser.add_argument("--streaming", required=True, help="file written once teleop streams")
    parser.add_argument("--restored", required=True, help="file the test writes after restoring the link")
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args(rospy.myargv()[1:])
    rospy.init_node("link_cut_check")
    record = Record()
    seen = {"streaming": bool(wait(lambda: len(record.accepted) > 50, args.timeout))}
    with open(args.streaming, "w", encoding="utf-8") as fh:
        fh.write(str(time.monotonic()))
    times = wait(
        lambda: os.path.exists(args.restored) and open(args.restored, encoding="utf-8").read(), 2 * args.timeout
    )
    if times:
        cut, restored = (float(v) for v in times.split())
        seen.update(cut=cut, restored=restored)
        back = wait(
            lambda: next((t for t, c in list(record.statuses) if t > restored and c in STREAMING), None), args.timeout
        )
        seen["streaming_again"] = back is not None
        if back is not None:
            wait(lambda: time.monotonic() > back + 1.0, 5.0)
        with record.lock:
            statuses = [(t - cut, c) for t, c in record.statuses if t >= cut - 0.5]
            accepted = [t - cut for t in record.accepted if t >= cut - 0.5]
        seen["statuses"] = statuses
        # The first moment nothing streams after the cut (halt or disengage), and the first
        # accepted command after it.
        seen["halted_after_s"] = next((t for t, c in statuses if t >= 0 and c not in STREAMING), None)
        stopped = seen["halted_after_s"]
        seen["first_command_after_halt_s"] = next((t for t in accepted if stopped is not None and t > stopped), None)
        seen["ramp_after_s"] = next(
            (t for t, c in statuses if stopped is not None and t > stopped and c == RAMPING), None
        )
    with open(args.out, "w", encoding="utf-8") as fh:
        json.dump(seen, fh, indent=1)
    sys.exit(0)


if __name__ == "__main__":
    main()
